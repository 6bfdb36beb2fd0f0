//! The hydrostatic tank solved with the AMG-preconditioned CG agrees with IC(0) and with
//! the water weight, and gives the same bytes on 1 and 2 threads.

use mpsfsi::case::{load_case_file, SolverKind};
use mpsfsi::engine::Simulation;

/// Mean vertical load on the tank over steps [skip, steps), the last loads, and the
/// water weight (particles * rho * l0^2 * g).
fn run(solver: &str, spacing: f64, steps: usize, skip: usize) -> (f64, Vec<f64>, f64) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/hydrostatic.json");
    let overrides = [
        format!("scheme.solver={solver}"),
        format!("particle_spacing={spacing}"),
    ];
    let case = load_case_file(&path, &overrides).unwrap();
    let mut sim = Simulation::new(&case);
    let mut sum = 0.0;
    let mut last = Vec::new();
    for s in 0..steps {
        let dt = sim.next_dt();
        sim.step(dt).unwrap();
        last = sim
            .loads
            .iter()
            .flat_map(|l| [l.force.x, l.force.y, l.moment])
            .collect();
        if s >= skip {
            sum += sim.loads.iter().map(|l| l.force.y).sum::<f64>();
        }
    }
    let weight =
        sim.particle_count() as f64 * case.fluid.density * case.particle_spacing.powi(2) * 9.81;
    (-sum / (steps - skip) as f64, last, weight)
}

#[test]
fn amg_hydrostatic_load_agrees_with_ic0_and_the_water_weight() {
    let case_solver = |s: &str| {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/hydrostatic.json");
        load_case_file(&path, &[format!("scheme.solver={s}")])
            .unwrap()
            .scheme
            .solver
    };
    assert_eq!(case_solver("pcg_amg"), SolverKind::PcgAmg);
    let (amg, _, weight) = run("pcg_amg", 0.01, 300, 100);
    let (ic0, _, _) = run("pcg_ic0", 0.01, 300, 100);
    let diff = (amg / ic0 - 1.0).abs();
    eprintln!(
        "mean tank load: AMG {amg:.3} N, IC(0) {ic0:.3} N, weight {weight:.3} N, AMG/IC0 - 1 = {diff:.2e}"
    );
    assert!(diff < 1e-3, "AMG {amg} vs IC(0) {ic0}");
    assert!(
        (amg / weight - 1.0).abs() < 0.01,
        "AMG {amg} vs weight {weight}"
    );
}

/// 40k particles, so that the finest level and the CG vectors take the parallel paths.
#[test]
fn amg_same_bytes_on_one_and_two_threads() {
    let on = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| run("pcg_amg", 0.0035, 6, 0).1)
    };
    let (one, two) = (on(1), on(2));
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&one), bits(&two));
}
