//! The pressure along one body's (or wall's) surface at one snapshot (`mpsfsi plot
//! --surface`, the service's `surface.svg`), read from the walls file's line cells: each
//! cell is one piece of a surface segment carrying the pressure the load integral read
//! there ([`crate::engine::walls::pressure_load`]).
//!
//! The x axis is the arc length from the polygon's (or polyline's) first vertex, with
//! every vertex marked by a thin vertical line in [`VERTEX_COLOUR`] labelled with its
//! index; the y axis is Cp = p / (½ ρ V²) with V the object's speed at that time, as the
//! flow picture colours the particles, or p in kPa when it does not move. What a test can
//! read back: each segment's pressure is one `<polyline>` of stroke width 2 through the
//! centres of its cells, with a dot on each.

use super::flow::Snapshot;
use super::plot::{colour, drawing, padded_range, PlotError};
use super::series::complete_lines;
use super::vtk::VtuData;
use crate::case::{parse_case_str, Case};
use crate::math::Real;
use plotters::prelude::*;
use std::path::Path;

pub const VERTEX_COLOUR: RGBColor = RGBColor(160, 160, 160);

/// The wall objects of a run in the order of loads.csv's names (the case's walls, then
/// its bodies), each with whether it is a body.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Objects(pub Vec<(String, bool)>);

impl Objects {
    /// The objects of `case`, in the order the scene builds them.
    pub fn of_case(case: &Case) -> Self {
        let walls = case.walls.iter().map(|w| (w.name.clone(), false));
        let bodies = case.bodies.iter().map(|b| (b.name.clone(), true));
        Self(walls.chain(bodies).collect())
    }

    /// The objects of a run directory: the names of loads.csv's first sample (bodies:
    /// those bodies.csv names), or, before the first sample, of the `case.json` a job's
    /// directory keeps; none when neither exists yet.
    pub fn of_run(run_dir: &Path) -> std::io::Result<Self> {
        let first_names = |file: &str| -> std::io::Result<Vec<String>> {
            match std::fs::read(run_dir.join(file)) {
                Ok(bytes) => Ok(first_sample_names(&String::from_utf8_lossy(
                    complete_lines(&bytes),
                ))),
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(Vec::new()),
                Err(e) => Err(e),
            }
        };
        let names = first_names("loads.csv")?;
        if !names.is_empty() {
            let bodies = first_names("bodies.csv")?;
            return Ok(Self(
                names
                    .into_iter()
                    .map(|n| {
                        let body = bodies.contains(&n);
                        (n, body)
                    })
                    .collect(),
            ));
        }
        match std::fs::read_to_string(run_dir.join("case.json")) {
            Ok(text) => Ok(parse_case_str(&text)
                .map(|case| Self::of_case(&case))
                .unwrap_or_default()),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(Self::default()),
            Err(e) => Err(e),
        }
    }

    /// The index of the object named `name`, or a message listing the bodies and walls.
    pub fn find(&self, name: &str) -> Result<usize, String> {
        if let Some(k) = self.0.iter().position(|(n, _)| n == name) {
            return Ok(k);
        }
        if self.0.is_empty() {
            return Err(format!(
                "no body named {name:?}: the run names no bodies yet (loads.csv has no rows)"
            ));
        }
        let list = |body: bool| {
            let names: Vec<&str> = self
                .0
                .iter()
                .filter(|(_, b)| *b == body)
                .map(|(n, _)| n.as_str())
                .collect();
            if names.is_empty() {
                "none".to_string()
            } else {
                names.join(", ")
            }
        };
        Err(format!(
            "no body named {name:?} in this run (bodies: {}; walls: {})",
            list(true),
            list(false)
        ))
    }
}

/// The second column of the rows of a `time,name,...` CSV text that share the first
/// row's time, in order.
fn first_sample_names(text: &str) -> Vec<String> {
    let mut names = Vec::new();
    let mut first_time = None;
    for line in text.lines().skip(1) {
        let mut columns = line.split(',');
        let (Some(time), Some(name)) = (columns.next(), columns.next()) else {
            break;
        };
        if *first_time.get_or_insert(time) != time {
            break;
        }
        names.push(name.to_string());
    }
    names
}

/// One object's surface pressure at one snapshot.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SurfaceProfile {
    /// Arc length from the first vertex to each cell's centre (m), per surface segment;
    /// cells of zero length are left out.
    pub along: Vec<Vec<Real>>,
    /// Pressure on each of those cells (Pa).
    pub pressure: Vec<Vec<Real>>,
    /// Arc length of every vertex (m): each segment's start, then the last segment's end.
    pub vertices: Vec<Real>,
    /// A body rather than a fixed wall.
    pub moving: bool,
    /// Speed of its centre of mass (m/s).
    pub speed: Real,
}

/// The profile of object `object` (its index in loads.csv's names) from a walls file.
pub fn surface_profile(walls: &VtuData, object: usize) -> Result<SurfaceProfile, PlotError> {
    let array = |name: &str| {
        walls
            .cell_scalar(name)
            .ok_or_else(|| PlotError::Data(format!("the walls file has no cell data {name:?}")))
    };
    let (objects, pressure) = (array("object")?, array("pressure")?);
    let segments = walls.cell_scalar("segment");
    let (moving, speed) = (walls.cell_scalar("moving"), walls.cell_scalar("speed"));
    let mut profile = SurfaceProfile::default();
    let mut s = 0.0;
    let mut current = None;
    for k in (0..walls.cells).filter(|&k| objects[k] == object as Real) {
        let cell = walls.cell(k);
        let (Some(&a), Some(&b)) = (cell.first(), cell.last()) else {
            continue;
        };
        let (a, b) = (walls.points[a], walls.points[b]);
        let length = (b[0] - a[0]).hypot(b[1] - a[1]);
        // without a segment array every cell is a segment of its own
        let segment = segments.map_or(k as Real, |v| v[k]);
        if current != Some(segment) {
            current = Some(segment);
            profile.vertices.push(s);
            profile.along.push(Vec::new());
            profile.pressure.push(Vec::new());
        }
        if length > 0.0 {
            profile
                .along
                .last_mut()
                .expect("pushed")
                .push(s + 0.5 * length);
            profile
                .pressure
                .last_mut()
                .expect("pushed")
                .push(pressure[k]);
        }
        s += length;
        profile.moving = moving.is_some_and(|m| m[k] > 0.5);
        profile.speed = speed.map_or(0.0, |v| v[k]);
    }
    if profile.vertices.is_empty() {
        return Err(PlotError::Data(format!(
            "the walls file has no cells of object {object}"
        )));
    }
    profile.vertices.push(s);
    Ok(profile)
}

/// The title of a surface picture.
pub fn surface_title(name: &str, body: &str, snapshot: &Snapshot) -> String {
    format!(
        "{name}: pressure along {body}, t = {:.3} ms",
        snapshot.time * 1e3
    )
}

/// The pressure along object `object`'s surface at `snapshot` as an SVG picture: Cp
/// against the arc length when the object moves (ρ from the particles' field data, V its
/// speed), p in kPa otherwise.
pub fn surface_svg(snapshot: &Snapshot, object: usize, title: &str) -> Result<String, PlotError> {
    let walls = snapshot
        .walls
        .as_ref()
        .ok_or_else(|| PlotError::Data("the snapshot has no walls file".into()))?;
    let profile = surface_profile(walls, object)?;
    let rho = snapshot.particles.field_data.get("density").copied();
    let (scale, label) = match rho.filter(|_| profile.moving && profile.speed > 0.0) {
        Some(rho) => {
            let (v, q) = (profile.speed, 0.5 * rho * profile.speed.powi(2));
            (
                1.0 / q,
                format!("Cp = p / (½ρV²), V = {v:.3} m/s, ½ρV² = {:.4} kPa", q / 1e3),
            )
        }
        None => (1e-3, "p (kPa)".to_string()),
    };
    let values: Vec<Vec<Real>> = profile
        .pressure
        .iter()
        .map(|p| p.iter().map(|p| p * scale).collect())
        .collect();
    let (y0, y1) = padded_range(values.iter().flatten().copied().chain([0.0]));
    let total = profile.vertices.last().copied().unwrap_or(0.0);
    let (x0, x1) = if total > 0.0 {
        (0.0, total)
    } else {
        (0.0, 1.0)
    };
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (1000, 600)).into_drawing_area();
        root.fill(&WHITE).map_err(drawing)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 22))
            .margin(12)
            .margin_right(24)
            .x_label_area_size(50)
            .y_label_area_size(90)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(drawing)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .label_style(("sans-serif", 16))
            .x_desc("s, along the surface from vertex 0 (m)")
            .y_desc(label.as_str())
            .draw()
            .map_err(drawing)?;
        for (k, s) in profile.vertices.iter().enumerate() {
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(*s, y0), (*s, y1)],
                    VERTEX_COLOUR.stroke_width(1),
                )))
                .map_err(drawing)?;
            chart
                .draw_series(std::iter::once(Text::new(
                    k.to_string(),
                    (*s, y1),
                    ("sans-serif", 14).into_font(),
                )))
                .map_err(drawing)?;
        }
        let line = colour(0);
        for (along, values) in profile.along.iter().zip(&values) {
            let points: Vec<(Real, Real)> = along
                .iter()
                .copied()
                .zip(values.iter().copied())
                .filter(|(_, v)| v.is_finite())
                .collect();
            if points.is_empty() {
                continue;
            }
            chart
                .draw_series(points.iter().map(|p| Circle::new(*p, 2, line.filled())))
                .map_err(drawing)?;
            chart
                .draw_series(LineSeries::new(points, line.stroke_width(2)))
                .map_err(drawing)?;
        }
        root.present().map_err(drawing)?;
    }
    Ok(svg)
}
