//! The other pair sums the step calls, against analytic values on lattices:
//! - the gradient of n (particle shifting) and the first moment Σ r w / r² (the
//!   free-surface asymmetry) vanish in the bulk and, at a flat surface, point into the
//!   fluid with the half-lattice's value;
//! - the neighbour count (the free surface's cluster seeds) is the lattice's;
//! - the HS divergence in row form (the exact projection) gives ∇·x = d on the lattice
//!   and the divergence of `number_density_and_divergence` on a disordered cloud;
//! - the corrected gradient in row form (the exact projection) is exact for a linear
//!   field on a disordered cloud and, with virtual points standing in for the missing
//!   half, at a flat surface, and equals the correction's `pressure_gradient`;
//! - the collision pass gives an approaching pair the restitution e, keeps its momentum
//!   and leaves separating and distant pairs alone;
//! - the neighbourhood queries (an empty Laplacian row, a flagged neighbour within r_e).

use mpsfsi::case::GradientKind;
use mpsfsi::engine::kernel::{Kernel, WendlandC2};
use mpsfsi::engine::neighbors::NeighborList;
use mpsfsi::engine::operators::{
    collision_velocity_changes, corrected_gradient_row, first_moment, has_laplacian_neighbour,
    hs_divergence_row, neighbour_count, number_density_and_divergence_all, number_density_gradient,
    pressure_gradient, Cloud, LatticeConstants, PressureGradient, VirtualPoints,
};
use mpsfsi::engine::resolution::Scales;
use mpsfsi::math::{Mat2, Real, Vec2};

type K = WendlandC2;
const L0: Real = 0.1;
const RE: Real = 3.1 * L0;
const N: usize = 16;

/// N × N points of spacing l0 from the origin: the top row, y = (N - 1) l0, is a flat
/// free surface.
fn square_lattice() -> Vec<Vec2> {
    super::square_lattice(N, L0)
}

fn jittered(amplitude: Real, seed: u64) -> Vec<Vec2> {
    super::jittered_lattice(N, L0, amplitude, seed)
}

/// Whether p has a full neighbourhood (at least r_e from every edge).
fn in_bulk(p: Vec2) -> bool {
    let far = (N - 1) as Real * L0 - RE;
    p.x > RE && p.x < far && p.y > RE && p.y < far
}

/// The middle particles of the top row: lattice neighbours on every side but above.
fn surface_row(pos: &[Vec2]) -> Vec<usize> {
    let top = (N - 1) as Real * L0;
    let far = (N - 1) as Real * L0 - RE;
    (0..pos.len())
        .filter(|&i| pos[i].y > top - 0.5 * L0 && pos[i].x > RE && pos[i].x < far)
        .collect()
}

/// The lattice offsets r within r_e (the point itself excluded).
fn offsets() -> Vec<Vec2> {
    let m = (RE / L0).ceil() as i64;
    let mut out = Vec::new();
    for b in -m..=m {
        for a in -m..=m {
            let r = Vec2::new(a as Real, b as Real) * L0;
            if (a, b) != (0, 0) && r.norm() < RE {
                out.push(r);
            }
        }
    }
    out
}

/// ∇n = Σ w'(r) (x_i - x_j) / r: zero in the bulk (tolerance 1e-12 of |w'(l0)|); at the
/// flat surface it is the sum over the lattice offsets below, Σ_{r_y<0} -w'(r) r / r, which
/// points down into the fluid (tolerance 1e-12 relative).
#[test]
fn number_density_gradient_vanishes_in_the_bulk_and_points_into_the_fluid_at_the_surface() {
    let pos = square_lattice();
    let nb = NeighborList::build(&pos, RE);
    let cloud = Cloud::new(&pos, &nb, RE);
    let scale = K::dw(L0, RE).abs();
    for i in (0..pos.len()).filter(|&i| in_bulk(pos[i])) {
        let g = number_density_gradient::<K>(&cloud, i);
        assert!(g.norm() < 1e-12 * scale, "bulk ∇n {g:?} at {:?}", pos[i]);
    }
    let half: Vec2 = offsets()
        .into_iter()
        .filter(|r| r.y <= 0.0)
        .map(|r| -r * (K::dw(r.norm(), RE) / r.norm()))
        .sum();
    assert!(half.y < 0.0 && half.x.abs() < 1e-12 * half.norm());
    for i in surface_row(&pos) {
        let g = number_density_gradient::<K>(&cloud, i);
        assert!(
            (g - half).norm() < 1e-12 * half.norm(),
            "surface ∇n {g:?} against {half:?}"
        );
    }
}

/// M1 = Σ r w / r²: zero in the bulk, and at the flat surface the sum over the offsets
/// below, Σ_{r_y<0} r w / r², pointing into the fluid. Tolerance 1e-12 of the surface
/// value.
#[test]
fn first_moment_vanishes_in_the_bulk_and_points_into_the_fluid_at_the_surface() {
    let pos = square_lattice();
    let nb = NeighborList::build(&pos, RE);
    let cloud = Cloud::new(&pos, &nb, RE);
    let half: Vec2 = offsets()
        .into_iter()
        .filter(|r| r.y < 0.0)
        .map(|r| r * (K::w(r.norm(), RE) / r.norm_squared()))
        .sum();
    assert!(half.y < 0.0);
    for i in (0..pos.len()).filter(|&i| in_bulk(pos[i])) {
        let m = first_moment::<K>(&cloud, i);
        assert!(m.norm() < 1e-12 * half.norm(), "bulk M1 {m:?}");
    }
    for i in surface_row(&pos) {
        let m = first_moment::<K>(&cloud, i);
        assert!(
            (m - half).norm() < 1e-12 * half.norm(),
            "surface M1 {m:?} against {half:?}"
        );
    }
}

/// The count of neighbours within r_e: the lattice's in the bulk, the offsets with
/// r_y <= 0 (less the point itself) in the surface row; exact.
#[test]
fn neighbour_count_is_the_lattice_count() {
    let pos = square_lattice();
    let nb = NeighborList::build(&pos, RE);
    let cloud = Cloud::new(&pos, &nb, RE);
    let lattice = LatticeConstants::compute::<K>(L0, RE, 2);
    assert_eq!(lattice.neighbours, offsets().len());
    for i in (0..pos.len()).filter(|&i| in_bulk(pos[i])) {
        assert_eq!(neighbour_count(&cloud, i), lattice.neighbours);
    }
    let below = offsets().iter().filter(|r| r.y <= 0.0).count();
    for i in surface_row(&pos) {
        assert_eq!(neighbour_count(&cloud, i), below);
    }
}

/// The HS divergence rows Σ_j e_ij·u_ij: with the lattice coefficient c = d / |Σ w' r|
/// the divergence of u = x is d in the bulk of the lattice (tolerance 1e-12), and on a
/// disordered cloud the rows give the divergence that the number-density pass computes,
/// to round-off (tolerance 1e-12 of the largest).
#[test]
fn hs_divergence_rows_give_the_divergence_of_the_density_pass() {
    let c = LatticeConstants::compute::<K>(L0, RE, 2).hs_divergence_coefficient;
    let apply = |cloud: &Cloud, u: &[Vec2], i: usize| -> Real {
        hs_divergence_row::<K>(cloud, c, i)
            .iter()
            .map(|&(j, e)| e.dot(&(u[j] - u[i])))
            .sum()
    };
    let pos = square_lattice();
    let nb = NeighborList::build(&pos, RE);
    let cloud = Cloud::new(&pos, &nb, RE);
    for i in (0..pos.len()).filter(|&i| in_bulk(pos[i])) {
        let div = apply(&cloud, &pos, i);
        assert!((div - 2.0).abs() < 1e-12 * 2.0, "∇·x = {div}");
    }
    let pos = jittered(0.3 * L0, 11);
    let nb = NeighborList::build(&pos, RE);
    let cloud = Cloud::new(&pos, &nb, RE);
    let u: Vec<Vec2> = pos
        .iter()
        .map(|p| Vec2::new((2.0 * p.y).sin() + p.x * p.x, p.x * p.y - (3.0 * p.x).cos()))
        .collect();
    let (_, pass) = number_density_and_divergence_all::<K>(&cloud, &u, c);
    let scale = pass.iter().map(|d| d.abs()).fold(0.0, Real::max);
    for (i, want) in pass.iter().enumerate() {
        let div = apply(&cloud, &u, i);
        assert!(
            (div - want).abs() < 1e-12 * scale,
            "row {div} against pass {want} (scale {scale:.3e})"
        );
    }
}

fn stationary_gradient(n0: Real) -> PressureGradient {
    PressureGradient {
        kind: GradientKind::Corrected,
        classic: 2.0 / n0,
        n0,
        dim: 2.0,
        stabilization: 0.0,
        close: 0.0,
    }
}

/// Σ_j g_ij (p_j - p_i) + b_i of one particle.
fn apply_row(cloud: &Cloud, n0: Real, p: &[Real], i: usize, walls: &[VirtualPoints]) -> Vec2 {
    let (row, b) = corrected_gradient_row::<K>(cloud, n0, 2.0 / n0, i, walls.iter().copied());
    row.iter().map(|&(j, g)| g * (p[j] - p[i])).sum::<Vec2>() + b
}

/// The corrected gradient's rows are exact for a linear field p = a + b·x on a disordered
/// cloud (tolerance 1e-9 of |b|) and equal the correction's `pressure_gradient` (GC, no
/// stabilisation) to round-off (tolerance 1e-12 of |b|).
#[test]
fn corrected_gradient_rows_are_exact_for_a_linear_field_on_a_disordered_cloud() {
    let n0 = LatticeConstants::compute::<K>(L0, RE, 2).n0;
    let pos = jittered(0.3 * L0, 12);
    let nb = NeighborList::build(&pos, RE);
    let cloud = Cloud::new(&pos, &nb, RE);
    let grad = Vec2::new(3.0e3, -9.81e3);
    let p: Vec<Real> = pos.iter().map(|x| 1.0e4 + grad.dot(x)).collect();
    let g = stationary_gradient(n0);
    for i in (0..pos.len()).filter(|&i| in_bulk(pos[i])) {
        let row = apply_row(&cloud, n0, &p, i, &[]);
        assert!((row - grad).norm() < 1e-9 * grad.norm(), "row {row:?}");
        let step = pressure_gradient::<K>(&g, &cloud, &p, None, i, std::iter::empty());
        assert!(
            (row - step).norm() < 1e-12 * grad.norm(),
            "row {row:?} step {step:?}"
        );
    }
}

/// At a flat surface whose missing upper half is supplied as virtual points (the moments
/// M1, M2 of the lattice offsets above, pressures extrapolated as p_i + c·r), the fluid
/// and wall moments make the full lattice's n0/d I, so the corrected gradient of a
/// linear field p = ∇p·x is ∇p + (d/n0) M2 (c - ∇p): ∇p itself when the extrapolation
/// gradient c is ∇p. Tolerance 1e-9 of |∇p|; and it equals `pressure_gradient` with the
/// same points (tolerance 1e-12).
#[test]
fn corrected_gradient_rows_take_the_walls_virtual_points() {
    let n0 = LatticeConstants::compute::<K>(L0, RE, 2).n0;
    let pos = square_lattice();
    let nb = NeighborList::build(&pos, RE);
    let cloud = Cloud::new(&pos, &nb, RE);
    let grad = Vec2::new(-2.0e3, -9.81e3);
    let p: Vec<Real> = pos.iter().map(|x| grad.dot(x)).collect();
    let (mut moment1, mut moment2) = (Vec2::zeros(), Mat2::zeros());
    for r in offsets().into_iter().filter(|r| r.y > 0.0) {
        let w = K::w(r.norm(), RE) / r.norm_squared();
        moment1 += r * w;
        moment2 += r * r.transpose() * w;
    }
    let g = stationary_gradient(n0);
    let rows = surface_row(&pos);
    assert!(!rows.is_empty());
    for c in [grad, grad + Vec2::new(300.0, 4.0e3)] {
        let wall = [VirtualPoints {
            linear: moment2 * c,
            moment1,
            moment2,
        }];
        let want = grad + moment2 * (c - grad) * (2.0 / n0);
        for &i in &rows {
            let row = apply_row(&cloud, n0, &p, i, &wall);
            assert!(
                (row - want).norm() < 1e-9 * grad.norm(),
                "row {row:?} against {want:?}"
            );
            let step = pressure_gradient::<K>(&g, &cloud, &p, None, i, wall.iter().copied());
            assert!(
                (row - step).norm() < 1e-12 * grad.norm(),
                "row {row:?} step {step:?}"
            );
        }
    }
}

/// Two particles closer than the collision distance: approaching head-on with a
/// tangential drift, the normal relative velocity becomes -e times what it was, the
/// tangential one and the momentum are kept (tolerance 1e-14); separating, or beyond the
/// distance, nothing changes (exactly), nor sliding past each other. With spacing
/// multiples 2 the distance doubles.
#[test]
fn collisions_restitute_approaching_pairs_and_leave_separating_ones_alone() {
    let e = 0.2;
    let rc = 0.5 * L0;
    let normal = Vec2::new(0.6, 0.8);
    let tangent = Vec2::new(-0.8, 0.6);
    let pair = |distance: Real| vec![Vec2::zeros(), normal * distance];
    let approaching = vec![normal * 1.5 + tangent * 0.3, normal * -0.5 + tangent * 0.3];
    let changes = |pos: &[Vec2], u: &[Vec2], s: &[Real]| {
        let scales = Scales::new(s, s[0] != 1.0);
        let nb = NeighborList::build_scaled(pos, RE, scales);
        let cloud = Cloud::new(pos, &nb, rc).with_scales(scales);
        collision_velocity_changes(&cloud, u, e)
    };
    let close = pair(0.4 * L0);
    let du = changes(&close, &approaching, &[1.0, 1.0]);
    let after: Vec<Vec2> = (0..2).map(|k| approaching[k] + du[k]).collect();
    let before_n = (approaching[1] - approaching[0]).dot(&normal);
    let after_n = (after[1] - after[0]).dot(&normal);
    assert!(
        (after_n + e * before_n).abs() < 1e-14,
        "normal {before_n} -> {after_n}"
    );
    for k in 0..2 {
        assert!((after[k] - approaching[k]).dot(&tangent).abs() < 1e-14);
    }
    assert!(
        (du[0] + du[1]).norm() < 1e-14,
        "momentum change {:?}",
        du[0] + du[1]
    );
    let separating = vec![approaching[1], approaching[0]];
    for (pos, u) in [(&close, &separating), (&pair(0.6 * L0), &approaching)] {
        assert_eq!(changes(pos, u, &[1.0, 1.0]), vec![Vec2::zeros(); 2]);
    }
    // sliding past each other: u_ij·n̂ is zero up to the rounding of n̂
    let sliding = vec![tangent * 0.7, tangent * -0.4];
    let du = changes(&close, &sliding, &[1.0, 1.0]);
    assert!(du.iter().all(|d| d.norm() < 1e-15), "sliding {du:?}");
    // twice the spacing: 0.6 l0 is inside the pair's distance 2 r_c
    let du = changes(&pair(0.6 * L0), &approaching, &[2.0, 2.0]);
    assert!(du[0] != Vec2::zeros() && (du[0] + du[1]).norm() < 1e-14);
}

/// A particle whose listed neighbours all lie beyond the Laplacian's r_e has an empty
/// row (for either weight), one with a neighbour inside has not; a flagged neighbour is
/// found only inside r_e.
#[test]
fn neighbourhood_queries_see_only_neighbours_inside_the_radius() {
    let pos = vec![
        Vec2::zeros(),
        Vec2::new(1.05 * RE, 0.0),
        Vec2::new(0.0, 0.5 * RE),
    ];
    let nb = NeighborList::build(&pos, 2.5 * RE);
    let cloud = Cloud::new(&pos, &nb, RE);
    for classic in [true, false] {
        assert!(has_laplacian_neighbour::<K>(classic, &cloud, 0));
        assert!(has_laplacian_neighbour::<K>(classic, &cloud, 2));
        assert!(!has_laplacian_neighbour::<K>(classic, &cloud, 1));
    }
    assert!(cloud.any_within(0, |j| j == 2));
    assert!(!cloud.any_within(0, |j| j == 1));
    assert!(!cloud.any_within(1, |_| true));
}
