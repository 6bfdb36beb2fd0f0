//! The CSV files a job serves as time series (loads, bodies, probes): which file, its
//! JSON group key and header. Reading them into columns is [`crate::output::series`].

/// The CSV files served per job: route name, file name, JSON group key, header.
#[derive(Debug, Clone, Copy)]
pub struct SeriesFile {
    pub file: &'static str,
    pub group: &'static str,
    pub header: &'static str,
}

pub const LOADS: SeriesFile = SeriesFile {
    file: "loads.csv",
    group: "bodies",
    header: crate::output::LOADS_HEADER,
};
pub const BODIES: SeriesFile = SeriesFile {
    file: "bodies.csv",
    group: "bodies",
    header: crate::output::BODIES_HEADER,
};
pub const PROBES: SeriesFile = SeriesFile {
    file: "probes.csv",
    group: "probes",
    header: crate::output::PROBES_HEADER,
};
/// The zero-phase filtered loads, written when the run ends.
pub const LOADS_FILTERED: SeriesFile = SeriesFile {
    file: "loads_filtered.csv",
    group: "bodies",
    header: crate::output::LOADS_HEADER,
};
/// The fluid's energy (`output.energy`): kept with the job, not served as a route.
pub const ENERGY: SeriesFile = SeriesFile {
    file: "energy.csv",
    group: "energy",
    header: crate::output::ENERGY_HEADER,
};
/// Written when the ladder ends (`?uncertainty=true`); until then the header alone.
pub const LOADS_UNCERTAINTY: SeriesFile = SeriesFile {
    file: "loads_uncertainty.csv",
    group: "bodies",
    header: "time,body,fx,fy,mz,u_fx,u_fy,u_mz",
};
