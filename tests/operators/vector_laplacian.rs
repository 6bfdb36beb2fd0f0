//! The vector Laplacian's pair sums that the explicit stage (viscosity) and the spacing
//! stage (velocity filter) call, `operators::vector_laplacian_sums`, against analytic
//! values: the Laplacian form is exact for quadratics on the square lattice with the
//! lattice coefficient; the strain-rate form is ∇²u + 2∇(∇·u) for quadratics on the
//! triangular lattice (whose fourth moments are isotropic, as the form assumes) and
//! vanishes for a rigid rotation on any cloud; both exchange momentum pairwise, also
//! across a resolution jump; the filter leaves a uniform velocity unchanged. The walls'
//! share, `WallContacts::viscous_mirror`, mirrors the velocity (no slip) or its normal
//! part (free slip).

use mpsfsi::case::ViscosityKind;
use mpsfsi::engine::kernel::{Kernel, WendlandC2};
use mpsfsi::engine::neighbors::NeighborList;
use mpsfsi::engine::operators::{vector_laplacian_sums, Cloud, LatticeConstants};
use mpsfsi::engine::resolution::Scales;
use mpsfsi::engine::walls::{WallContact, WallContacts, WallTerms};
use mpsfsi::math::{Real, Vec2};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

type K = WendlandC2;
const L0: Real = 0.1;
const RE: Real = 3.1 * L0;

fn square_lattice(n: usize) -> Vec<Vec2> {
    super::square_lattice(n, L0)
}

/// Rows of spacing l0 shifted by half a spacing every other row: every point's
/// neighbourhood is six-fold symmetric.
fn triangular_lattice(n: usize) -> Vec<Vec2> {
    let h = (3.0 as Real).sqrt() / 2.0;
    (0..n * n)
        .map(|k| {
            let (a, b) = ((k % n) as Real, (k / n) as Real);
            Vec2::new(a + 0.5 * (k / n % 2) as Real, b * h) * L0
        })
        .collect()
}

fn jittered(n: usize, amplitude: Real, seed: u64) -> Vec<Vec2> {
    super::jittered_lattice(n, L0, amplitude, seed)
}

/// Points at least `margin` inside the bounding box of `pos` (a full neighbourhood).
fn interior(pos: &[Vec2], margin: Real) -> Vec<usize> {
    let (lo, hi) = pos.iter().fold(
        (Vec2::repeat(Real::MAX), Vec2::repeat(Real::MIN)),
        |(lo, hi), p| (lo.inf(p), hi.sup(p)),
    );
    (0..pos.len())
        .filter(|&i| {
            let p = pos[i];
            p.x > lo.x + margin && p.x < hi.x - margin && p.y > lo.y + margin && p.y < hi.y - margin
        })
        .collect()
}

fn relative_error(got: Vec2, want: Vec2) -> Real {
    (got - want).norm() / want.norm()
}

/// With the lattice coefficient a = 2d / Σ L r², a Σ_j L u_ij is ∇²u for any quadratic
/// u at a lattice point with a full neighbourhood, for the classic weight and for HL:
/// u = (x² + 3y² + x, xy - y) has ∇²u = (8, 0) + nothing from the linear part.
/// Measured error 1e-14; tolerance 1e-10.
#[test]
fn laplacian_form_is_exact_for_a_quadratic_on_the_square_lattice() {
    let pos = square_lattice(16);
    let nb = NeighborList::build(&pos, RE);
    let cloud = Cloud::new(&pos, &nb, RE);
    let lattice = LatticeConstants::compute::<K>(L0, RE, 2);
    let u: Vec<Vec2> = pos
        .iter()
        .map(|p| Vec2::new(p.x * p.x + 3.0 * p.y * p.y + p.x, p.x * p.y - p.y))
        .collect();
    for (classic, a) in [
        (true, lattice.classic_coefficient),
        (false, lattice.hl_coefficient),
    ] {
        let sums = vector_laplacian_sums::<K>(classic, ViscosityKind::Laplacian, &cloud, &u);
        let inner = interior(&pos, RE);
        assert!(inner.len() > 50);
        for &i in &inner {
            let lap = sums[i] * a;
            assert!(
                (lap - Vec2::new(8.0, 0.0)).norm() < 1e-10 * 8.0,
                "classic {classic}: ∇²u = {lap:?} at {:?}",
                pos[i]
            );
        }
    }
}

/// The strain-rate form (d + 2) a Σ_j (u_ij·r) r L / r² is ∇²u + 2∇(∇·u) wherever the
/// neighbourhood's fourth moments are isotropic, as on the triangular lattice: u = (x², 0)
/// gives (2, 0) + 2 (2, 0) = (6, 0), the divergence-free shear u = (y², x²) gives (2, 2).
/// a = 2d / Σ L r² of the triangular lattice. Measured error 1e-14; tolerance 1e-10.
#[test]
fn strain_rate_form_is_the_laplacian_plus_twice_the_gradient_of_the_divergence() {
    let pos = triangular_lattice(18);
    let nb = NeighborList::build(&pos, RE);
    let cloud = Cloud::new(&pos, &nb, RE);
    let inner = interior(&pos, RE + L0);
    assert!(inner.len() > 50);
    // the lattice coefficient, summed here over one point's lattice neighbours
    let i0 = inner[0];
    for (classic, weight) in [
        (true, K::w as fn(Real, Real) -> Real),
        (false, K::hl as fn(Real, Real) -> Real),
    ] {
        let lr2: Real = pos
            .iter()
            .map(|p| (p - pos[i0]).norm())
            .filter(|&d| d > 0.0 && d < RE)
            .map(|d| weight(d, RE) * d * d)
            .sum();
        let a = 4.0 / lr2;
        for (field, want) in [
            (
                (|p: &Vec2| Vec2::new(p.x * p.x, 0.0)) as fn(&Vec2) -> Vec2,
                Vec2::new(6.0, 0.0),
            ),
            (
                |p: &Vec2| Vec2::new(p.y * p.y, p.x * p.x),
                Vec2::new(2.0, 2.0),
            ),
        ] {
            let u: Vec<Vec2> = pos.iter().map(field).collect();
            let sums = vector_laplacian_sums::<K>(classic, ViscosityKind::StrainRate, &cloud, &u);
            for &i in &inner {
                let got = sums[i] * a;
                assert!(
                    relative_error(got, want) < 1e-10,
                    "classic {classic}: {got:?} against {want:?} at {:?}",
                    pos[i]
                );
            }
        }
    }
}

/// A rigid rotation has no strain: u_ij·r_ij = 0 for every pair, so the strain-rate form
/// vanishes on any cloud, where the Laplacian form of the same field does not (it is
/// not zero at the edge of the cloud). Tolerance 1e-12 of the Laplacian form's largest
/// magnitude.
#[test]
fn strain_rate_form_of_a_rigid_rotation_vanishes_on_a_disordered_cloud() {
    let pos = jittered(16, 0.3 * L0, 5);
    let nb = NeighborList::build(&pos, RE);
    let cloud = Cloud::new(&pos, &nb, RE);
    let (omega, centre, drift) = (3.0, Vec2::new(0.7, 0.4), Vec2::new(0.2, -0.1));
    let u: Vec<Vec2> = pos
        .iter()
        .map(|p| {
            let r = p - centre;
            drift + Vec2::new(-r.y, r.x) * omega
        })
        .collect();
    let strain = vector_laplacian_sums::<K>(false, ViscosityKind::StrainRate, &cloud, &u);
    let laplacian = vector_laplacian_sums::<K>(false, ViscosityKind::Laplacian, &cloud, &u);
    let scale = laplacian.iter().map(|s| s.norm()).fold(0.0, Real::max);
    assert!(scale > 0.0);
    let worst = strain.iter().map(|s| s.norm()).fold(0.0, Real::max);
    assert!(
        worst < 1e-12 * scale,
        "strain-rate form of a rotation: {worst:.3e} (scale {scale:.3e})"
    );
}

/// c_ij = c_ji and u_ij = -u_ji: with equal masses the fluid pairs exchange momentum
/// and create none, Σ_i s_i = 0, for either form and weight, and the strain-rate form's
/// central pair forces keep the angular momentum, Σ_i x_i × s_i = 0. With a resolution
/// jump the masses s_i² weight the sums and m_i v_ij stays symmetric
/// (`engine::resolution`), so Σ_i s_i² s_i = 0 as well. Random velocities on a
/// disordered cloud; tolerance 1e-12 of Σ_i |s_i|.
#[test]
fn the_pair_sums_conserve_momentum_and_the_strain_rate_form_angular_momentum() {
    let pos = jittered(16, 0.25 * L0, 7);
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    let u: Vec<Vec2> = pos
        .iter()
        .map(|_| Vec2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)))
        .collect();
    // the left half twice as coarse in spacing multiple (a jump in s, not in layout)
    let s: Vec<Real> = pos
        .iter()
        .map(|p| if p.x < 0.75 { 2.0 } else { 1.0 })
        .collect();
    for multi in [false, true] {
        let scales = Scales::new(&s, multi);
        let nb = NeighborList::build_scaled(&pos, RE, scales);
        let cloud = Cloud::new(&pos, &nb, RE).with_scales(scales);
        for classic in [true, false] {
            for form in [ViscosityKind::Laplacian, ViscosityKind::StrainRate] {
                let sums = vector_laplacian_sums::<K>(classic, form, &cloud, &u);
                let mass = |i: usize| scales.volume(i);
                let total: Vec2 = (0..pos.len()).map(|i| sums[i] * mass(i)).sum();
                let size: Real = (0..pos.len()).map(|i| sums[i].norm() * mass(i)).sum();
                assert!(size > 0.0);
                assert!(
                    total.norm() < 1e-12 * size,
                    "{form:?} classic {classic} multi {multi}: Σ m s = {total:?} of {size:.3e}"
                );
                if form == ViscosityKind::StrainRate {
                    let torque: Real = (0..pos.len())
                        .map(|i| {
                            let f = sums[i] * mass(i);
                            pos[i].x * f.y - pos[i].y * f.x
                        })
                        .sum();
                    assert!(
                        torque.abs() < 1e-12 * size,
                        "classic {classic} multi {multi}: Σ x × m s = {torque:.3e} of {size:.3e}"
                    );
                }
            }
        }
    }
}

/// The velocity filter, u_i += ε Σ_j w u_ij / n0 (the classic weight at r_e, the form
/// the spacing stage calls): a uniform velocity is left exactly as it is, and the
/// filter's momentum change Σ_i δu_i of a random field is zero to round-off (tolerance
/// 1e-12 of Σ_i |δu_i|).
#[test]
fn the_filter_leaves_a_uniform_velocity_unchanged_and_keeps_the_momentum() {
    let pos = jittered(14, 0.3 * L0, 9);
    let nb = NeighborList::build(&pos, RE);
    let cloud = Cloud::new(&pos, &nb, RE);
    let uniform = vec![Vec2::new(0.3, -1.7); pos.len()];
    let sums = vector_laplacian_sums::<K>(true, ViscosityKind::Laplacian, &cloud, &uniform);
    assert!(sums.iter().all(|s| *s == Vec2::zeros()));
    let mut rng = ChaCha8Rng::seed_from_u64(10);
    let u: Vec<Vec2> = pos
        .iter()
        .map(|_| Vec2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)))
        .collect();
    let sums = vector_laplacian_sums::<K>(true, ViscosityKind::Laplacian, &cloud, &u);
    let total: Vec2 = sums.iter().sum();
    let size: Real = sums.iter().map(|s| s.norm()).sum();
    assert!(size > 0.0);
    assert!(
        total.norm() < 1e-12 * size,
        "Σ δu = {total:?} of {size:.3e}"
    );
}

/// The mirror term Σ (u_m - u_i) Σ L of a particle with contacts on two wall objects,
/// one no-slip and one free-slip, both with normal +y and Σ L = 3: the no-slip wall
/// mirrors the whole relative velocity, 2 (u_w - u_i) Σ L, the free-slip one only its
/// normal part, and a particle moving with a no-slip wall feels nothing. Exact.
#[test]
fn the_wall_mirror_takes_the_relative_velocity_or_its_normal_part() {
    let contact = |object: u32, wall_velocity: Vec2| WallContact {
        object,
        point: Vec2::zeros(),
        normal: Vec2::new(0.0, 1.0),
        distance: 0.5 * L0,
        penetrated: false,
        wall_velocity,
        wall_acceleration: Vec2::zeros(),
        terms: WallTerms {
            laplacian_sum: 3.0,
            ..WallTerms::default()
        },
    };
    let u_w = Vec2::new(0.25, 0.0);
    let contacts = WallContacts {
        offsets: vec![0, 1, 2, 4],
        contacts: vec![
            contact(0, u_w),
            contact(1, u_w),
            contact(0, u_w),
            contact(1, u_w),
        ],
    };
    let free_slip = [false, true];
    let u = Vec2::new(1.0, -0.5);
    // relative velocity (-0.75, 0.5), times 2 Σ L = 6
    assert_eq!(
        contacts.viscous_mirror(0, u, &free_slip),
        Vec2::new(-4.5, 3.0)
    );
    assert_eq!(
        contacts.viscous_mirror(1, u, &free_slip),
        Vec2::new(0.0, 3.0)
    );
    assert_eq!(
        contacts.viscous_mirror(2, u, &free_slip),
        Vec2::new(-4.5, 6.0)
    );
    assert_eq!(contacts.viscous_mirror(0, u_w, &free_slip), Vec2::zeros());
}
