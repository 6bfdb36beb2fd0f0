//! Operators on the regular lattice: the classic gradient of a linear field is exact in
//! the interior, the classic Laplacian of |x|² equals 2d, n0 is the lattice sum.

use mpsfsi::case::{GradientKind, KernelKind, LaplacianKind, Scheme};
use mpsfsi::engine::kernel::Koshizuka;
use mpsfsi::engine::neighbors::NeighborList;
use mpsfsi::engine::operators::{gradient, laplacian, Cloud, LatticeConstants, Normalisation};
use mpsfsi::engine::params::MpsParameters;
use mpsfsi::math::Vec2;

fn lattice(n: usize, l0: f64) -> Vec<Vec2> {
    (0..n * n)
        .map(|k| Vec2::new((k % n) as f64 * l0, (k / n) as f64 * l0))
        .collect()
}

fn interior(p: &[Vec2], l0: f64, n: usize, margin: f64) -> Vec<usize> {
    let lo = margin * l0;
    let hi = (n - 1) as f64 * l0 - margin * l0;
    (0..p.len())
        .filter(|&i| p[i].x > lo && p[i].y > lo && p[i].x < hi && p[i].y < hi)
        .collect()
}

#[test]
fn classic_gradient_of_linear_field_is_exact_in_the_interior() {
    let (n, l0, re) = (24, 0.01, 2.1 * 0.01);
    let x = lattice(n, l0);
    let nb = NeighborList::build(&x, re);
    let cloud = Cloud::new(&x, &nb, re);
    let norm = Normalisation::Reference(LatticeConstants::compute::<Koshizuka>(l0, re, 2));
    let f: Vec<f64> = x.iter().map(|p| 3.0 * p.x - 2.0 * p.y + 1.0).collect();
    let g = gradient::<Koshizuka>(GradientKind::MinimumPressure, &cloud, norm, &f);
    for i in interior(&x, l0, n, 3.0) {
        assert!(
            (g[i] - Vec2::new(3.0, -2.0)).norm() < 1e-10,
            "particle {i}: {:?}",
            g[i]
        );
    }
}

#[test]
fn classic_laplacian_of_r_squared_is_2d() {
    let (n, l0) = (24, 0.01);
    let re = 3.1 * l0;
    let x = lattice(n, l0);
    let nb = NeighborList::build(&x, re);
    let cloud = Cloud::new(&x, &nb, re);
    let norm = Normalisation::Reference(LatticeConstants::compute::<Koshizuka>(l0, re, 2));
    let f: Vec<f64> = x.iter().map(|p| p.norm_squared()).collect();
    let lap = laplacian::<Koshizuka>(LaplacianKind::Classic, &cloud, norm, &f);
    for i in interior(&x, l0, n, 4.0) {
        assert!((lap[i] - 4.0).abs() < 1e-9, "particle {i}: {}", lap[i]);
    }
}

#[test]
fn reference_number_density_is_the_lattice_sum() {
    // Koshizuka kernel w = r_e/r - 1 at the default r_e = 2.5 l0: 4 neighbours at l0,
    // 4 at sqrt2 l0, 4 at 2 l0 and 8 at sqrt5 l0.
    let w = |r: f64| 2.5 / r - 1.0;
    let expected = 4.0 * w(1.0) + 4.0 * w(2f64.sqrt()) + 4.0 * w(2.0) + 8.0 * w(5f64.sqrt());
    let p = MpsParameters::from_scheme(0.01, &Scheme::default(), 1000.0, 1e-6, [0.0, -9.81]);
    assert!((p.n0 - expected).abs() < 1e-12, "n0 {} vs {expected}", p.n0);
    assert_eq!(Scheme::default().kernel, KernelKind::Koshizuka);
}
