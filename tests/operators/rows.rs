//! Properties of the row form that the pressure assembly relies on, and of the
//! divergence and fallback paths: symmetric rows where the variant is symmetric (so CG
//! applies), non-symmetric ones where `LaplacianKind::is_symmetric` says so, linear exactness of the
//! consistent operators on a disordered cloud, the GC fallback, thread-count
//! independence, and variant names from a case file.

use mpsfsi::case::{parse_case_str, GradientKind, LaplacianKind};
use mpsfsi::engine::kernel::WendlandC2;
use mpsfsi::engine::neighbors::NeighborList;
use mpsfsi::engine::operators::{
    divergence, gradient, gradient_row, laplacian, laplacian_row, Cloud, LatticeConstants,
    Normalisation,
};
use mpsfsi::math::{Real, Vec2};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const L0: Real = 0.1;

fn jittered_cloud(amplitude: Real, seed: u64) -> Vec<Vec2> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut v = Vec::new();
    for b in 0..20 {
        for a in 0..20 {
            let j = Vec2::new(
                rng.random_range(-amplitude..=amplitude),
                rng.random_range(-amplitude..=amplitude),
            );
            v.push((Vec2::new(a as Real, b as Real) + j) * L0);
        }
    }
    v
}

/// Interior particles (full support at r_e = 3.1 l0).
fn interior(pos: &[Vec2]) -> Vec<usize> {
    (0..pos.len())
        .filter(|&i| {
            pos[i].x > 4.0 * L0
                && pos[i].x < 15.0 * L0
                && pos[i].y > 4.0 * L0
                && pos[i].y < 15.0 * L0
        })
        .collect()
}

fn coefficient(row: &[(usize, Real)], j: usize) -> Real {
    row.iter().filter(|e| e.0 == j).map(|e| e.1).sum()
}

#[test]
fn classic_hl_and_second_order_rows_are_symmetric_chl_anisotropic_least_squares_are_not() {
    let pos = jittered_cloud(0.2 * L0, 1);
    let re = 3.1 * L0;
    let nb = NeighborList::build(&pos, re);
    let cloud = Cloud::new(&pos, &nb, re);
    let norm = Normalisation::Reference(LatticeConstants::compute::<WendlandC2>(L0, re, 2));
    for kind in [
        LaplacianKind::Classic,
        LaplacianKind::HigherOrder,
        LaplacianKind::SecondOrder,
        LaplacianKind::CorrectedHigherOrder,
        LaplacianKind::Anisotropic,
        LaplacianKind::LeastSquares,
    ] {
        let rows: Vec<_> = (0..pos.len())
            .map(|i| laplacian_row::<WendlandC2>(kind, &cloud, norm, i).off_diagonal)
            .collect();
        let mut asym: Real = 0.0;
        let mut scale: Real = 0.0;
        for i in 0..pos.len() {
            for &(j, c) in &rows[i] {
                asym = asym.max((c - coefficient(&rows[j], i)).abs());
                scale = scale.max(c.abs());
            }
        }
        assert_eq!(
            kind.is_symmetric(),
            asym <= 1e-12 * scale,
            "{kind:?}: max |c_ij - c_ji| = {asym:.3e} (scale {scale:.3e})"
        );
    }
}

#[test]
fn consistent_operators_are_exact_for_linear_and_quadratic_fields_on_a_disordered_cloud() {
    let pos = jittered_cloud(0.3 * L0, 2);
    let re = 3.1 * L0;
    let nb = NeighborList::build(&pos, re);
    let cloud = Cloud::new(&pos, &nb, re);
    let norm = Normalisation::Local;
    let linear: Vec<Real> = pos.iter().map(|p| 3.0 * p.x - 2.0 * p.y + 1.0).collect();
    let quadratic: Vec<Real> = pos
        .iter()
        .map(|p| p.x * p.x + 3.0 * p.x * p.y - 2.0 * p.y * p.y + p.x)
        .collect(); // ∇² = 2 - 4
    let velocity: Vec<Vec2> = pos
        .iter()
        .map(|p| Vec2::new(2.0 * p.x + p.y, -p.x + 0.5 * p.y))
        .collect(); // ∇·u = 2.5
    for kind in [GradientKind::Corrected, GradientKind::LeastSquares] {
        let g = gradient::<WendlandC2>(kind, &cloud, norm, &linear);
        let d = divergence::<WendlandC2>(kind, &cloud, norm, &velocity);
        for &i in &interior(&pos) {
            assert!(
                (g[i] - Vec2::new(3.0, -2.0)).norm() < 1e-9,
                "{kind:?} gradient {:?}",
                g[i]
            );
            assert!((d[i] - 2.5).abs() < 1e-9, "{kind:?} divergence {}", d[i]);
        }
    }
    let lap = laplacian::<WendlandC2>(LaplacianKind::LeastSquares, &cloud, norm, &quadratic);
    for &i in &interior(&pos) {
        assert!(
            (lap[i] + 2.0).abs() < 1e-8,
            "least-squares Laplacian {}",
            lap[i]
        );
    }
    // the classic gradient is not exact there (Imoto 2022 Fig. 3b): the test can tell
    let classic = gradient::<WendlandC2>(GradientKind::Cmps, &cloud, norm, &linear);
    let worst = interior(&pos)
        .iter()
        .map(|&i| (classic[i] - Vec2::new(3.0, -2.0)).norm())
        .fold(0.0, Real::max);
    assert!(
        worst > 1e-3,
        "classic gradient unexpectedly exact: {worst:.3e}"
    );
}

#[test]
fn corrected_gradient_falls_back_to_the_classic_one_on_a_line_of_neighbours() {
    let pos: Vec<Vec2> = (0..7).map(|k| Vec2::new(k as Real * L0, 0.0)).collect();
    let re = 2.1 * L0;
    let nb = NeighborList::build(&pos, re);
    let cloud = Cloud::new(&pos, &nb, re);
    let norm = Normalisation::Reference(LatticeConstants::compute::<WendlandC2>(L0, re, 2));
    let gc = gradient_row::<WendlandC2>(GradientKind::Corrected, &cloud, norm, 3);
    let classic = gradient_row::<WendlandC2>(GradientKind::Cmps, &cloud, norm, 3);
    assert!(!gc.is_empty());
    assert_eq!(
        gc, classic,
        "a singular corrective matrix must fall back to the classic row"
    );
    assert!(gc.iter().all(|(_, g)| g.x.is_finite() && g.y.is_finite()));
}

#[test]
fn operators_do_not_depend_on_the_thread_count() {
    let pos = jittered_cloud(0.25 * L0, 3);
    let re = 3.1 * L0;
    let nb = NeighborList::build(&pos, re);
    let f: Vec<Real> = pos.iter().map(|p| (3.0 * p.x).sin() * p.y.exp()).collect();
    let compute = || {
        let cloud = Cloud::new(&pos, &nb, re);
        let l = laplacian::<WendlandC2>(
            LaplacianKind::CorrectedHigherOrder,
            &cloud,
            Normalisation::Local,
            &f,
        );
        let g =
            gradient::<WendlandC2>(GradientKind::LeastSquares, &cloud, Normalisation::Local, &f);
        (l, g)
    };
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(compute);
    let three = rayon::ThreadPoolBuilder::new()
        .num_threads(3)
        .build()
        .unwrap()
        .install(compute);
    assert!(one
        .0
        .iter()
        .zip(&three.0)
        .all(|(a, b)| a.to_bits() == b.to_bits()));
    assert!(one
        .1
        .iter()
        .zip(&three.1)
        .all(|(a, b)| a.x.to_bits() == b.x.to_bits() && a.y.to_bits() == b.y.to_bits()));
}

#[test]
fn every_variant_is_reachable_by_name_and_unknown_names_list_the_valid_ones() {
    let case = |scheme: &str| {
        format!(
            r#"{{ "name": "n", "particle_spacing": 0.01, "fluid": {{}}, "domain": {{ "min": [0, 0], "max": [1, 1] }},
                "fluid_blocks": [ {{ "polygon": [[0.1, 0.1], [0.5, 0.1], [0.5, 0.5], [0.1, 0.5]] }} ],
                "time": {{ "end": 0.1, "cfl": 0.2, "max_dt": 0.001 }}, "scheme": {scheme} }}"#
        )
    };
    for name in [
        "classic",
        "higher_order",
        "corrected_higher_order",
        "second_order",
        "anisotropic",
        "least_squares",
    ] {
        let c = parse_case_str(&case(&format!(r#"{{ "laplacian": "{name}" }}"#)))
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(serde_json::to_value(c.scheme.laplacian).unwrap(), name);
    }
    for name in [
        "minimum_pressure",
        "cmps",
        "corrected",
        "anisotropic",
        "least_squares",
    ] {
        let c = parse_case_str(&case(&format!(r#"{{ "gradient": "{name}" }}"#)))
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(serde_json::to_value(c.scheme.gradient).unwrap(), name);
    }
    let err = parse_case_str(&case(r#"{ "laplacian": "chl" }"#))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("corrected_higher_order") && err.contains("least_squares"),
        "error should list the variants: {err}"
    );
}
