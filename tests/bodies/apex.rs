//! Body walls in the particle number density near a wedge apex, where a flat-wall
//! table (Harada et al. 2008) is wrong: a fluid particle there must get, from its
//! fluid lattice neighbours plus the wall terms, the number density n0 of a particle
//! in the full lattice. The tolerance is the free-surface margin 1 - beta = 3 %: a
//! larger deficit would flag an interior particle as free surface.
//!
//! Printed for diagnosis: the same sum with the full lattice outside the wedge (no
//! l0/2 clearance) and with a flat-wall table instead of the clipped wall lattice.

use crate::common::*;
use mpsfsi::engine::kernel::{Kernel, Koshizuka};
use mpsfsi::engine::math::{Real, Vec2};
use mpsfsi::engine::walls::geometry::inside;
use mpsfsi::engine::walls::{wall_terms, PlacedWall, WallKernels, WallWeights};
use mpsfsi::engine::Simulation;

struct Weights {
    re: Real,
    re_lap: Real,
}

impl WallWeights for Weights {
    fn w(&self, r: Real) -> Real {
        Koshizuka::w(r, self.re)
    }
    fn dw(&self, r: Real) -> Real {
        Koshizuka::dw(r, self.re)
    }
    fn lap(&self, r: Real) -> Real {
        Koshizuka::hl(r, self.re_lap)
    }
}

/// Flat-wall table: the kernel summed over a half-plane lattice whose first row is
/// l0/2 behind the wall, seen from distance d.
fn flat_wall_z(d: Real, l0: Real, re: Real) -> Real {
    let m = (re / l0).ceil() as i32 + 1;
    let mut z = 0.0;
    for a in -m..=m {
        for row in 0..=m {
            let dy = d + (row as Real + 0.5) * l0;
            z += Koshizuka::w(((a as Real * l0).powi(2) + dy * dy).sqrt(), re);
        }
    }
    z
}

#[test]
#[ignore = "fails: n/n0 - 1 down to -0.11 at 0.5 l0 from the apex (wall terms vs the full lattice) and -0.19 with the scene's particles, which drops lattice sites within l0/2 of an inclined face; closing note of issue 3"]
fn particle_near_wedge_apex_gets_full_lattice_number_density() {
    let l0 = 0.01;
    let mut worst: Real = 0.0;
    let mut worst_flat: Real = 0.0;
    let mut worst_scene: Real = 0.0;
    let mut checked = 0;
    for (ox, oy) in [
        (0.0, 0.0),
        (0.3, 0.0),
        (0.0, 0.37),
        (0.21, 0.44),
        (0.5, 0.5),
    ] {
        let case = shipped(
            "wedge_free_fall.json",
            &[
                format!("particle_spacing={l0}"),
                format!("bodies.0.position=[{}, {}]", ox * l0, -0.35 + oy * l0),
                r#"bodies.0.motion={"type": "prescribed", "velocity": [0.0, 0.0]}"#.into(),
            ],
        );
        let sim = Simulation::new(&case);
        let prm = &sim.params;
        let k = sim.walls.iter().position(|w| w.body.is_some()).unwrap();
        let placed = PlacedWall::new(&sim.walls[k], sim.walls[k].state);
        let kernels = WallKernels {
            l0,
            re: prm.re,
            re_lap: prm.re_lap,
        };
        let weights = Weights {
            re: prm.re,
            re_lap: prm.re_lap,
        };
        let apex = sim.walls[k].state.position;
        let x = &sim.particles.position;
        // the full lattice of the scene (anchored half a spacing inside the fluid
        // block's lower-left corner at (-1, -1)), split into fluid and solid points
        let lattice = |p: Vec2| {
            Vec2::new(
                -1.0 + ((p.x + 1.0) / l0).floor() * l0 + 0.5 * l0,
                -1.0 + ((p.y + 1.0) / l0).floor() * l0 + 0.5 * l0,
            )
        };
        let edges = &placed.loop_edges;
        for i in 0..x.len() {
            if (x[i] - apex).norm() > 1.6 * l0 || x[i].y > apex.y + 0.5 * l0 {
                continue;
            }
            let base = lattice(x[i]);
            assert!((base - x[i]).norm() < 1e-9, "particle off the lattice");
            let m = (prm.re / l0).ceil() as i32 + 1;
            let (mut fluid_full, mut solid_lattice) = (0.0, 0.0);
            for a in -m..=m {
                for b in -m..=m {
                    if (a, b) == (0, 0) {
                        continue;
                    }
                    let p = base + Vec2::new(a as Real * l0, b as Real * l0);
                    let w = Koshizuka::w((p - x[i]).norm(), prm.re);
                    if inside(p, edges) {
                        solid_lattice += w;
                    } else {
                        fluid_full += w;
                    }
                }
            }
            // the scene's own particles (the lattice minus those within l0/2 of the surface)
            let fluid_scene: Real = (0..x.len())
                .filter(|&j| j != i)
                .map(|j| Koshizuka::w((x[j] - x[i]).norm(), prm.re))
                .sum();
            let (xw, d) = placed
                .nearest(x[i], prm.re.max(prm.re_lap))
                .expect("particle near the apex sees the wedge");
            let (terms, _, penetrated) = wall_terms(x[i], xw, &placed, &kernels, &weights);
            assert!(!penetrated);
            let err = (fluid_full + terms.number_density) / prm.n0 - 1.0;
            let flat = (fluid_full + flat_wall_z(d, l0, prm.re)) / prm.n0 - 1.0;
            let scene = (fluid_scene + terms.number_density) / prm.n0 - 1.0;
            println!(
                "offset ({ox}, {oy}) l0, particle at {:?} l0 from apex (d = {:.2} l0): n/n0 - 1 = {:+.4} (flat-wall table {:+.4}; with the scene's particles {:+.4}); wall terms / solid lattice sum = {:.4}",
                ((x[i] - apex) / l0).map(|v| (v * 100.0).round() / 100.0).as_slice(),
                d / l0,
                err,
                flat,
                scene,
                terms.number_density / solid_lattice
            );
            worst = worst.max(err.abs());
            worst_flat = worst_flat.max(flat.abs());
            worst_scene = worst_scene.max(scene.abs());
            checked += 1;
        }
    }
    println!("apex: {checked} particles, worst |n/n0 - 1| = {worst:.4} (flat-wall table {worst_flat:.4}; scene particles instead of the full lattice {worst_scene:.4})");
    assert!(checked >= 5, "too few particles near the apex: {checked}");
    // what the engine computes at t = 0: the scene's particles plus the wall terms
    assert!(
        worst_scene < 0.03,
        "number density near the apex off by {:.2} % (full lattice outside the wedge: {:.2} %)",
        100.0 * worst_scene,
        100.0 * worst
    );
}

/// The lattice-compatible corner: a box corner (a convex 90° apex) with both faces on
/// lattice lines, so the scene's particles plus the lattice points inside the box are
/// exactly the full lattice and n0 is exact for every particle. Particles diagonal to
/// the corner see the vertex as their nearest point, where a flat-wall table counts a
/// half-plane of solid instead of a quadrant.
#[test]
fn particle_near_convex_box_corner_gets_full_lattice_number_density() {
    let l0 = 0.01;
    let case = shipped(
        "floating_box.json",
        &[
            "bodies.0.position=[0.0, -0.35]".into(),
            r#"bodies.0.motion={"type": "prescribed", "velocity": [0.0, 0.0]}"#.into(),
        ],
    );
    let sim = Simulation::new(&case);
    let prm = &sim.params;
    let k = sim.walls.iter().position(|w| w.body.is_some()).unwrap();
    let placed = PlacedWall::new(&sim.walls[k], sim.walls[k].state);
    let kernels = WallKernels {
        l0,
        re: prm.re,
        re_lap: prm.re_lap,
    };
    let weights = Weights {
        re: prm.re,
        re_lap: prm.re_lap,
    };
    let corner = Vec2::new(-0.2, -0.35);
    let x = &sim.particles.position;
    let (mut worst, mut worst_flat, mut checked) = (0.0_f64, 0.0_f64, 0);
    for i in 0..x.len() {
        let r = x[i] - corner;
        // the quadrant outside both faces, within two spacings of the vertex
        if !(r.x < 0.0 && r.y < 0.0 && r.norm() < 2.0 * l0) {
            continue;
        }
        let fluid: Real = (0..x.len())
            .filter(|&j| j != i)
            .map(|j| Koshizuka::w((x[j] - x[i]).norm(), prm.re))
            .sum();
        let (xw, d) = placed.nearest(x[i], prm.re.max(prm.re_lap)).unwrap();
        let (terms, _, _) = wall_terms(x[i], xw, &placed, &kernels, &weights);
        let err = (fluid + terms.number_density) / prm.n0 - 1.0;
        let flat = (fluid + flat_wall_z(d, l0, prm.re)) / prm.n0 - 1.0;
        println!(
            "box corner, particle at {:?} l0: n/n0 - 1 = {err:+.4} (flat-wall table {flat:+.4})",
            (r / l0).as_slice()
        );
        worst = worst.max(err.abs());
        worst_flat = worst_flat.max(flat.abs());
        checked += 1;
    }
    println!("box corner: {checked} particles, worst |n/n0 - 1| = {worst:.4} (flat-wall table {worst_flat:.4})");
    assert!(checked >= 3);
    assert!(
        worst < 0.03,
        "number density at a convex corner off by {:.2} %",
        100.0 * worst
    );
}
