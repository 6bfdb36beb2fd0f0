//! The polygon-wall lattice sums: a particle of the initial lattice next to a wall,
//! or in a concave tank corner, has the number density n0 of the full lattice
//! (fluid neighbours + virtual wall points), and the wall normal points into the fluid.

use mpsfsi::case::Scheme;
use mpsfsi::engine::kernel::{Kernel, Koshizuka};
use mpsfsi::engine::params::MpsParameters;
use mpsfsi::engine::walls::{
    wall_terms, PlacedWall, WallKernels, WallObject, WallState, WallWeights,
};
use mpsfsi::geometry::WallShape;
use mpsfsi::math::Vec2;

struct W(f64, f64);
impl WallWeights for W {
    fn w(&self, r: f64) -> f64 {
        Koshizuka::w(r, self.0)
    }
    fn dw(&self, r: f64) -> f64 {
        Koshizuka::dw(r, self.0)
    }
    fn lap(&self, r: f64) -> f64 {
        Koshizuka::hl(r, self.1)
    }
}

/// Tank polyline (0,1) -> (0,0) -> (1,0) -> (1,1), fluid inside; lattice at (i+1/2) l0.
fn tank(l0: f64) -> (PlacedWall, Vec<Vec2>, MpsParameters) {
    let params = MpsParameters::from_scheme(l0, &Scheme::default(), 1000.0, 0.0, [0.0, -9.81]);
    let pts = [
        Vec2::new(0.0, 1.0),
        Vec2::new(0.0, 0.0),
        Vec2::new(1.0, 0.0),
        Vec2::new(1.0, 1.0),
    ];
    // walking the polyline, the fluid (x in (0,1)) is on the left: solid on the right
    let shape = WallShape::from_polyline(&pts, false, false, 0.1);
    let object = WallObject {
        name: "tank".into(),
        body: None,
        shape,
        state: WallState::default(),
        free_slip: false,
    };
    let placed = PlacedWall::new(&object, WallState::default());
    let n = (1.0 / l0).round() as usize;
    let fluid = (0..n * n / 2)
        .map(|k| Vec2::new(((k % n) as f64 + 0.5) * l0, ((k / n) as f64 + 0.5) * l0))
        .collect();
    (placed, fluid, params)
}

fn number_density(
    x: Vec2,
    fluid: &[Vec2],
    wall: &PlacedWall,
    params: &MpsParameters,
) -> (f64, Vec2) {
    let re = params.re;
    let fluid_part: f64 = fluid
        .iter()
        .map(|p| (p - x).norm())
        .filter(|r| *r > 1e-9)
        .map(|r| Koshizuka::w(r, re))
        .sum();
    let k = WallKernels {
        l0: params.l0,
        re,
        re_lap: params.re_lap,
    };
    let (xw, _) = wall.nearest(x, re).expect("within reach of the wall");
    let (terms, normal, penetrated) = wall_terms(x, xw, wall, &k, &W(re, params.re_lap), 1.0);
    assert!(!penetrated);
    (fluid_part + terms.number_density, normal)
}

#[test]
fn particle_next_to_a_flat_wall_has_n0() {
    let l0 = 0.02;
    let (wall, fluid, params) = tank(l0);
    let x = Vec2::new(0.5 * l0 + 10.0 * l0, 0.5 * l0);
    let (n, normal) = number_density(x, &fluid, &wall, &params);
    assert!(
        (n / params.n0 - 1.0).abs() < 1e-9,
        "n/n0 = {}",
        n / params.n0
    );
    assert!(
        (normal - Vec2::new(0.0, 1.0)).norm() < 1e-12,
        "normal {normal:?}"
    );
}

#[test]
fn particle_in_a_concave_tank_corner_has_n0() {
    let l0 = 0.02;
    let (wall, fluid, params) = tank(l0);
    for (i, j) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
        let x = Vec2::new((i as f64 + 0.5) * l0, (j as f64 + 0.5) * l0);
        let (n, _) = number_density(x, &fluid, &wall, &params);
        assert!(
            (n / params.n0 - 1.0).abs() < 1e-9,
            "corner site ({i},{j}): n/n0 = {}",
            n / params.n0
        );
    }
}
