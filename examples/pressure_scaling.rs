//! Benchmark of the pressure solve: the hydrostatic tank from rest at a given spacing,
//! a fixed number of steps, with the time split into the solve and its preconditioner
//! setup. `cargo run --release --example pressure_scaling -- cases/hydrostatic.json STEPS [PATH=VALUE]...`
//! e.g. `... 30 particle_spacing=0.00357 scheme.solver=pcg_amg`; RAYON_NUM_THREADS sets threads.
use mpsfsi::case::load_case_file;
use mpsfsi::engine::pressure::preconditioner_setup_seconds;
use mpsfsi::engine::Simulation;
fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let steps: u64 = args[1].parse().expect("STEPS");
    let case = load_case_file(std::path::Path::new(&args[0]), &args[2..]).unwrap();
    let mut sim = Simulation::new(&case);
    let setup0 = preconditioner_setup_seconds();
    let t0 = std::time::Instant::now();
    let mut load = 0.0;
    for _ in 0..steps {
        let dt = sim.next_dt();
        sim.step(dt).expect("step");
        load = sim.loads.iter().map(|l| l.force.y).sum::<f64>();
    }
    let wall = t0.elapsed().as_secs_f64();
    let setup = preconditioner_setup_seconds() - setup0;
    let n = sim.particle_count();
    let s = steps as f64;
    let weight = n as f64 * case.fluid.density * case.particle_spacing.powi(2) * 9.81;
    println!(
        "{:?} threads {} particles {} ms/step {:.1} solve ms/step {:.1} ({:.0}%) setup ms/step {:.1} ({:.0}% of solve) iters/step {:.1} particle-steps/s {:.3e} load/weight {:.4} {:?}",
        sim.config.method.solver.kind,
        rayon::current_num_threads(),
        n,
        wall / s * 1e3,
        sim.stats.stage_times.solve / s * 1e3,
        100.0 * sim.stats.stage_times.solve / wall,
        setup / s * 1e3,
        100.0 * setup / sim.stats.stage_times.solve,
        sim.stats.total_solver_iterations as f64 / s,
        n as f64 * s / wall,
        -load / weight,
        sim.solver_reuse_counts(),
    );
}
