//! The pressure-integral wall load (`scheme.wall_load = "pressure_integral"`) against
//! hydrostatics: a tank of still water carries the water's weight and the moment of its
//! pressure, a submerged box carries rho g A, and both hold when the particles sit off
//! the lattice (the hydrostatic field sampled at disordered points), which is where the
//! reaction of the wall terms reads 12-20% low (the perturbed-lattice stress scene).
//! The Neumann extrapolation makes the reading exact for a linear pressure field (to
//! round-off: asserted to 1e-9), whatever the arrangement.

use mpsfsi::engine::kernel::{Kernel, Koshizuka};
use mpsfsi::engine::neighbors::CellGrid;
use mpsfsi::engine::resolution::Scales;
use mpsfsi::engine::walls::pressure_load::{pressure_loads, surface_pressures};
use mpsfsi::engine::walls::{PlacedWall, WallObject, WallState};
use mpsfsi::geometry::WallShape;
use mpsfsi::math::Vec2;

const RHO: f64 = 1000.0;
const G: f64 = 9.81;
const L0: f64 = 0.02;
const DEPTH: f64 = 0.5;

fn placed(shape: WallShape) -> PlacedWall {
    let object = WallObject {
        name: "w".into(),
        body: None,
        shape,
        state: WallState::default(),
        free_slip: false,
    };
    PlacedWall::new(&object, WallState::default())
}

/// Tank polyline (0,1) -> (0,0) -> (1,0) -> (1,1), solid on the right of the walk.
fn tank() -> PlacedWall {
    let pts = [
        Vec2::new(0.0, 1.0),
        Vec2::new(0.0, 0.0),
        Vec2::new(1.0, 0.0),
        Vec2::new(1.0, 1.0),
    ];
    placed(WallShape::from_polyline(&pts, false, false, 0.1))
}

/// The box [0.3, 0.5] x [0.2, 0.3], solid inside.
fn submerged_box() -> PlacedWall {
    let pts = [
        Vec2::new(0.3, 0.2),
        Vec2::new(0.5, 0.2),
        Vec2::new(0.5, 0.3),
        Vec2::new(0.3, 0.3),
    ];
    placed(WallShape::solid_polygon(&pts))
}

/// Lattice points (i + 1/2) l0 filling 1 m x DEPTH, outside the box if `with_box`,
/// each moved by up to ±`jitter` l0 per axis (seeded, reproducible).
fn fluid(with_box: bool, jitter: f64) -> Vec<Vec2> {
    let n = (1.0 / L0).round() as usize;
    let mut seed: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut uniform = move || {
        seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
        ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    };
    let mut out = Vec::new();
    for k in 0..n * (DEPTH / L0).round() as usize {
        let x = Vec2::new(((k % n) as f64 + 0.5) * L0, ((k / n) as f64 + 0.5) * L0);
        if with_box && x.x > 0.3 && x.x < 0.5 && x.y > 0.2 && x.y < 0.3 {
            continue;
        }
        out.push(x + Vec2::new(uniform(), uniform()) * (jitter * L0));
    }
    out
}

/// Loads of `walls` with the still-water pressure rho g (DEPTH - y) at every particle.
fn loads(x: &[Vec2], walls: &[PlacedWall]) -> Vec<(Vec2, f64)> {
    let re = 2.1 * L0;
    let p: Vec<f64> = x.iter().map(|q| RHO * G * (DEPTH - q.y)).collect();
    let grid = CellGrid::build(x, re);
    let w = |d: f64| Koshizuka::w(d, re);
    let surfaces = surface_pressures(
        x,
        &p,
        Scales::UNIFORM,
        &grid,
        walls,
        &w,
        RHO,
        Vec2::new(0.0, -G),
        L0,
        re,
    );
    pressure_loads(walls, &surfaces)
}

fn assert_close(what: &str, got: f64, expected: f64, tol: f64) {
    let err = (got / expected - 1.0).abs();
    assert!(
        err < tol,
        "{what}: {got} vs {expected} ({:.3}%)",
        100.0 * err
    );
}

fn check_tank(jitter: f64) {
    let x = fluid(false, jitter);
    let (f, m) = loads(&x, &[tank()])[0];
    let weight = RHO * G * DEPTH; // per metre of width: the tank is 1 m wide
    assert_close("vertical load", -f.y, weight, 1e-9);
    // the side walls' thrusts rho g H²/2 cancel
    assert!(f.x.abs() < 1e-9 * weight, "horizontal load {}", f.x);
    // about the origin: the bottom's -weight x 0.5 m; the side walls' moments cancel
    assert_close("moment", -m, 0.5 * weight, 1e-9);
}

#[test]
fn still_tank_carries_the_water_weight() {
    check_tank(0.0);
}

#[test]
fn still_tank_carries_the_water_weight_off_the_lattice() {
    check_tank(0.2);
}

#[test]
fn submerged_box_carries_its_buoyancy() {
    for jitter in [0.0, 0.2] {
        let x = fluid(true, jitter);
        let out = loads(&x, &[tank(), submerged_box()]);
        let buoyancy = RHO * G * 0.2 * 0.1;
        assert_close("buoyancy", out[1].0.y, buoyancy, 1e-9);
        assert!(
            out[1].0.x.abs() < 1e-9 * buoyancy,
            "sideways {}",
            out[1].0.x
        );
    }
}
