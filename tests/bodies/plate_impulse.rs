//! The wall model's kinematic condition on a moving body, in isolation: a flat plate of
//! half-breadth c lying on still water is started impulsively downwards at V. Potential
//! flow gives the impulse on the plate, its added mass times V, with Wagner's added mass
//! of a plate on a free surface rho pi c² / 2 (per unit length), and the water under the
//! plate leaves with the plate's velocity. This is the quantity a slamming load is made
//! of (Wagner's force is d(m_a V)/dt), measured without the jet and the moving wetted
//! breadth of a wedge.
//!
//! The plate lies in the shipped wedge tank (4 m x 1.2 m of water), large enough for
//! c = 0.1 m: a 2 m x 1 m tank reads 0.4 % above its double at 1 cm. Steps of 5 µs
//! (V dt = l0 / 2000 at 1 cm) keep the start impulsive; the impulse is complete within
//! four steps.

use crate::common::*;
use mpsfsi::coupling::CouplingOptions;
use std::f64::consts::PI;

const C: f64 = 0.1;
const V: f64 = 1.0;
const STEPS: usize = 6;
const DT: f64 = 5e-6;

struct Start {
    /// Impulse on the plate over the first steps / (rho pi c² V / 2).
    impulse: f64,
    /// Mean downward velocity of the row under the middle half of the plate / V.
    first_row: f64,
}

impl Start {
    /// Both against potential flow: the added mass within `impulse` (a fraction) and the
    /// water under the plate at the plate's velocity within `row`.
    fn check(&self, l0: f64, impulse: f64, row: f64) {
        assert!(
            (self.impulse - 1.0).abs() < impulse,
            "l0 = {l0}: added mass {:.4} of rho pi c² / 2 ({impulse} allowed)",
            self.impulse
        );
        assert!(
            (self.first_row - 1.0).abs() < row,
            "l0 = {l0}: the water under the plate leaves at {:.4} V ({row} allowed)",
            self.first_row
        );
    }
}

fn impulsive_start(l0: f64, kinematics: &str) -> Start {
    plate_start(l0, kinematics, C, &[])
}

/// The plate of half-breadth `c` in the shipped wedge tank changed by `extra` overrides.
fn plate_start(l0: f64, kinematics: &str, c: f64, extra: &[String]) -> Start {
    let mut overrides = vec![
        format!("particle_spacing={l0}"),
        format!(
            "bodies.0.polygon=[[{m}, 0.0], [{c}, 0.0], [{c}, 0.02], [{m}, 0.02]]",
            m = -c
        ),
        // centred on the tank's axis, with r_e = 2.1 l0, as the added masses of
        // docs/validation.md were measured (2.5 carries 1.104 / 1.111 at 10 / 5 mm with
        // the default projection)
        "bodies.0.position=[0.0, 0.0]".into(),
        "scheme.radius=2.1".into(),
        format!("bodies.0.motion.velocity=[0.0, {}]", -V),
        format!("time.max_dt={DT}"),
        format!("scheme.wall_kinematics=\"{kinematics}\""),
    ];
    overrides.extend_from_slice(extra);
    let case = shipped("wedge_30deg_constant_velocity.json", &overrides);
    let mut first_row = 0.0;
    let trace = run(
        &case,
        CouplingOptions::default(),
        Some(STEPS as f64 * DT),
        |sim| {
            let p = &sim.particles;
            let row: Vec<f64> = (0..p.len())
                .filter(|&i| p.position[i].x.abs() < 0.5 * c && p.position[i].y > -l0)
                .map(|i| -p.velocity[i].y)
                .collect();
            first_row = row.iter().sum::<f64>() / row.len() as f64 / V;
        },
    );
    assert!(trace.error.is_none(), "{:?}", trace.error);
    assert_eq!(trace.steps.len(), STEPS, "steps of {DT} s");
    let k = trace.wall("wedge");
    let impulse: f64 = trace.steps.iter().map(|s| s.force[k].y * s.dt).sum();
    let start = Start {
        impulse: impulse / (RHO * PI * c * c / 2.0 * V),
        first_row,
    };
    println!(
        "plate c = {c} m, l0 = {l0} m, {kinematics} kinematics: impulse / (rho pi c² V / 2) = {:.4}, first row at {:.4} V",
        start.impulse, start.first_row
    );
    start
}

/// `wall_kinematics = "neumann"`: the approach velocity enters the Neumann gradient of
/// the virtual pressures, the projection's own boundary condition: 1.034 / 1.019 at
/// 10 / 5 mm, the row under the plate at 1.0003 / 1.0010 V, first order in l0 (1.013 at
/// 2.5 mm in a 2 m x 1 m tank).
#[test]
fn impulsively_started_plate_carries_wagner_added_mass() {
    let spacings = [0.01, 0.005];
    let starts: Vec<Start> = spacings
        .iter()
        .map(|&l0| impulsive_start(l0, "neumann"))
        .collect();
    for ((s, l0), bound) in starts.iter().zip(spacings).zip([0.05, 0.03]) {
        s.check(l0, bound, 0.01);
    }
    assert!(
        (starts[1].impulse - 1.0).abs() < (starts[0].impulse - 1.0).abs(),
        "the added mass does not converge: {:.4} at 1 cm, {:.4} at 5 mm",
        starts[0].impulse,
        starts[1].impulse
    );
}

/// `projection = "exact"` with the default source kinematics: the rows away from the free
/// surface make the corrected velocity's HS divergence (the wall's virtual points moving
/// with the plate) the source's, instead of solving the HL Laplacian. Measured at 10 /
/// 5 mm (the default `laplacian_fill_floor` 0.5; without it 1.003 / 1.014 and 0.988 /
/// 0.995):
/// - blend 0.05 (nearly all exact): added mass 0.983 / 0.990, the row under the plate
///   at 0.991 / 0.997 V;
/// - the default blend 0.1: 0.993 / 1.007, the row at 1.012 / 1.057 V;
/// - the approximate projection: 1.075 / 1.096 / 1.116 and 1.24 / 1.26 / 1.27 V.
///
/// So the approximate projection's excess is the mismatch between its Laplacian and the
/// divergence of the corrected gradient.
#[test]
fn impulsively_started_plate_with_exact_projection() {
    for l0 in [0.01, 0.005] {
        let exact = [
            r#"scheme.projection="exact""#.to_string(),
            "scheme.exact_projection_blend=0.05".into(),
        ];
        plate_start(l0, "source", C, &exact).check(l0, 0.02, 0.03);
        let default_blend = plate_start(l0, "source", C, &exact[..1]);
        default_blend.check(l0, 0.02, 0.06);
    }
}

/// The default `wall_kinematics = "source"` (the wall's virtual points move with it in
/// the HS divergence) misses the condition on an impulsive start: the row under the
/// plate leaves at 1.24 / 1.26 / 1.27 V at 10 / 5 / 2.5 mm, separating from the plate,
/// and the added mass reads 1.073 / 1.095 at 10 / 5 mm in the shipped tank (about 1.13 at
/// 1.25 mm in a 2 m x 1 m tank), the error growing with refinement towards about +15 %,
/// the excess of the wedge's fitted slope.
/// Why: the pressure solves the HL Laplacian, which is not the HS divergence of the
/// corrected gradient that then moves the particles; `projection = "exact"` removes the
/// excess (`impulsively_started_plate_with_exact_projection`). Counting the wall's share
/// twice in the source also removes it (0.995 / 0.999 / 1.002, first row at
/// 1.03-1.04 V) but raises the wedge's C_F by 3 % (15.5 against 14.99 at 8 mm),
/// so it is not done. A flat-bottomed body dropped on water is where this matters.
#[test]
#[ignore = "fails by design: the default source kinematics carries 1.073 / 1.095 of the added mass at 10 / 5 mm (3 % allowed); `wall_kinematics = \"neumann\"` and `projection = \"exact\"` are the options that pass"]
fn impulsively_started_plate_with_default_kinematics() {
    for l0 in [0.01, 0.005] {
        impulsive_start(l0, "source").check(l0, 0.03, 0.05);
    }
}

/// The shipped wedge tank is large enough: doubling it changes the slamming force by
/// less than 1 %. Wagner's force on the wedge is V (dm_a/dc) dc/dt, so the tank's walls
/// act on it through the added mass's slope dm_a/dc over the wetted half-breadths of
/// the fitted window, 0.09-0.19 m; this measures that slope between c = 0.1 and 0.2 m
/// on impulsively started plates, which carry no per-step noise (the wedge's force
/// scatters by 50-90 % per step, and ensembles of four runs still differ by ±3-6 %).
/// Measured at 1 cm against an 8 m x 4 m tank: the earlier 2 m x 1 m tank +2.09 %,
/// 3 m x 1.2 m +0.94 %, the shipped 4 m x 1.2 m +0.68 % and its double +0.07 %.
#[test]
fn wedge_tank_is_large_enough() {
    let l0 = 0.01;
    let slope = |extra: &[String]| {
        let m = |c: f64| plate_start(l0, "source", c, extra).impulse * c * c;
        (m(0.2) - m(0.1)) / 0.1
    };
    let shipped = slope(&[]);
    let doubled = slope(&tank(4.0, 2.4, 0.3));
    let change = shipped / doubled - 1.0;
    println!(
        "added-mass slope dm_a/dc (units of rho pi V / 2): shipped tank {shipped:.5}, doubled {doubled:.5}: {:+.3} %",
        100.0 * change
    );
    assert!(
        change.abs() < 0.01,
        "the tank's walls change the slamming force by {:.2} % (1 % allowed)",
        100.0 * change
    );
}
