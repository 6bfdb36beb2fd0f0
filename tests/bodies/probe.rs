//! A diagnostic run driven by the environment (not a check): MPSFSI_CASE names a
//! shipped case, MPSFSI_SET holds `;`-separated overrides, MPSFSI_END the end time.
//! Prints the loads and body states every MPSFSI_EVERY steps.

use crate::common::*;
use mpsfsi::coupling::{AddedMass, CouplingOptions};

#[test]
#[ignore = "diagnostic run driven by MPSFSI_CASE / MPSFSI_SET, not a check"]
fn probe_case() {
    let name = std::env::var("MPSFSI_CASE")
        .unwrap_or_else(|_| "wedge_30deg_constant_velocity.json".into());
    let overrides: Vec<String> = std::env::var("MPSFSI_SET")
        .map(|s| {
            s.split(';')
                .filter(|x| !x.is_empty())
                .map(String::from)
                .collect()
        })
        .unwrap_or_default();
    let end = std::env::var("MPSFSI_END")
        .ok()
        .map(|s| s.parse::<f64>().unwrap());
    let every: usize = std::env::var("MPSFSI_EVERY")
        .ok()
        .map(|s| s.parse().unwrap())
        .unwrap_or(10);
    let added_mass = if std::env::var("MPSFSI_PLAIN").is_ok() {
        AddedMass::Off
    } else {
        AddedMass::default()
    };
    let case = shipped(&name, &overrides);
    let mut n = 0usize;
    let trace = run(&case, CouplingOptions { added_mass }, end, |sim| {
        n += 1;
        if n % every == 0 {
            let f: Vec<String> = sim
                .loads
                .iter()
                .map(|l| format!("({:.1}, {:.1})", l.force.x, l.force.y))
                .collect();
            let b: Vec<String> = sim
                .walls
                .iter()
                .filter(|w| w.body.is_some())
                .map(|w| {
                    format!(
                        "com ({:.5}, {:.5}) v ({:.4}, {:.4})",
                        w.state.center_of_mass.x,
                        w.state.center_of_mass.y,
                        w.state.velocity.x,
                        w.state.velocity.y
                    )
                })
                .collect();
            println!(
                "step {n} t {:.6} max|u| {:.3} loads {} {}",
                sim.time,
                sim.max_particle_speed(),
                f.join(" "),
                b.join(" ")
            );
        }
    });
    println!(
        "{} particles, {} steps, {:.1} s (coupling {:.3} s), error {:?}",
        trace.particles,
        trace.steps.len(),
        trace.wall_seconds,
        trace.coupling_seconds,
        trace.error
    );
}
