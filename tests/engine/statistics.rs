//! The run's statistics: the particle updates it counts.

use mpsfsi::case::{parse_case_str, Limits, ValidCase};
use mpsfsi::engine::Simulation;

const TANK: &str = r#"{
  "name": "ordering-tank",
  "fluid": { "density": 1000.0, "kinematic_viscosity": 1.0e-6, "gravity": [0.0, -9.81] },
  "particle_spacing": 0.01,
  "domain": { "min": [-0.05, -0.05], "max": [1.05, 0.5] },
  "fluid_blocks": [ { "polygon": [[0.0, 0.0], [1.0, 0.0], [1.0, 0.2], [0.0, 0.2]] } ],
  "walls": [ { "name": "tank", "polyline": [[0.0, 0.45], [0.0, 0.0], [1.0, 0.0], [1.0, 0.45]] } ],
  "time": { "end": 0.01, "max_dt": 0.001 },
  "output": { "load_interval": 0.001 }
}"#;

fn tank() -> ValidCase {
    ValidCase::new(parse_case_str(TANK).unwrap(), &Limits::default()).unwrap()
}

#[test]
fn particle_steps_is_the_sum_of_the_particles_over_the_steps_taken() {
    let case = tank();
    let mut sim = Simulation::new(&case);
    let mut expected = 0u64;
    for _ in 0..5 {
        expected += sim.particle_count() as u64;
        let dt = sim.next_dt();
        sim.step(dt).unwrap();
    }
    assert_eq!(sim.steps, 5);
    assert_eq!(sim.stats.particle_steps, expected);
    assert_eq!(expected, 5 * 2000);
}

#[test]
fn particle_steps_counts_the_particles_left_after_each_removal() {
    // the block moves right at 2 m/s out of a domain that ends 2.5 spacings past it
    let text = TANK
        .replace(r#""max": [1.05, 0.5]"#, r#""max": [1.025, 0.5]"#)
        .replace(
            r#"[0.0, 0.2]] } ]"#,
            r#"[0.0, 0.2]], "velocity": [2.0, 0.0] } ]"#,
        )
        .replace(r#"[1.0, 0.0], [1.0, 0.45]"#, r#"[1.0, 0.0]"#);
    let case = ValidCase::new(parse_case_str(&text).unwrap(), &Limits::default()).unwrap();
    let mut sim = Simulation::new(&case);
    let mut expected = 0u64;
    for _ in 0..20 {
        expected += sim.particle_count() as u64;
        let dt = sim.next_dt();
        sim.step(dt).unwrap();
    }
    assert!(sim.stats.removed > 0, "particles left the domain");
    assert_eq!(sim.stats.particle_steps, expected);
}
