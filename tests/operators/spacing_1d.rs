//! Paper 001 §6.2 (Isshiki 2014): the MPS gradient (eq. 70a) and Laplacian (eq. 70b)
//! of φ = sin(2πx/L) on [0, L], L = 4, N = 40 intervals, weight w = h/|x| - 1 with
//! h_i = 2 dx_i (dx_i = x_{i+1} - x_i), the region extended by N_end_cor = 2 particles at
//! each end, n_i and λ_i per particle (eq. 71), on the meshes of its Table 2: regular,
//! algebraic, geometric, random (seeded) and sinusoidal.
//!
//! The paper's Tables 4-5 (MPS row): gradient good on regular, algebraic, random and
//! sinusoidal meshes, bad on the geometric one; Laplacian good on the regular and random
//! meshes, bad on the algebraic, geometric and sinusoidal ones.
//!
//! On the regular mesh both operators reduce to centred differences, whose error is
//! known exactly: relative (k dx)²/6 for the gradient and (k dx)²/12 for the Laplacian
//! (k dx = 2π/40): 4.1e-3 and 2.1e-3. The issue asked for regular-mesh errors below
//! 1e-3; at the paper's N = 40 that is below the truncation error of the centred
//! difference itself, so the test asserts the exact truncation error instead (within 5 %).

use mpsfsi::case::{GradientKind, LaplacianKind};
use mpsfsi::engine::kernel::Koshizuka;
use mpsfsi::engine::neighbors::NeighborList;
use mpsfsi::engine::operators::{gradient_row, laplacian_row, Cloud, Normalisation};
use mpsfsi::math::{Real, Vec2};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::PI;

const L: Real = 4.0;
const N: usize = 40;
const EXTENSION: usize = 2;

#[derive(Debug, Clone, Copy, PartialEq)]
enum Mesh {
    Regular,
    Algebraic,
    Geometric,
    Random,
    Sinusoidal,
}

/// dx_i of Table 2, normalised (α) so that Σ dx_i = L.
fn spacings(mesh: Mesh) -> Vec<Real> {
    let mut rng = ChaCha8Rng::seed_from_u64(2014);
    let raw: Vec<Real> = (0..N)
        .map(|i| {
            let i = i as Real;
            let base = L / N as Real;
            match mesh {
                Mesh::Regular => base,
                Mesh::Algebraic => base + i * L / 100.0,
                Mesh::Geometric => base * 1.05_f64.powf(i - 1.0),
                Mesh::Random => base * (1.0 + 0.0625 * rng.random::<Real>()),
                Mesh::Sinusoidal => base * (1.0 + 0.5 * (4.0 * PI * i / N as Real).sin()),
            }
        })
        .collect();
    let alpha = L / raw.iter().sum::<Real>();
    raw.iter().map(|d| d * alpha).collect()
}

/// Max relative errors (gradient, Laplacian) over the N + 1 mesh points.
fn errors(mesh: Mesh) -> (Real, Real) {
    let dx = spacings(mesh);
    // points: 2 extension points each side continuing the end spacings
    let mut xs = vec![0.0];
    for d in &dx {
        xs.push(xs.last().unwrap() + d);
    }
    let first = dx[0];
    let last = *dx.last().unwrap();
    let mut all: Vec<Real> = (1..=EXTENSION)
        .rev()
        .map(|k| -(k as Real) * first)
        .collect();
    all.extend(&xs);
    all.extend((1..=EXTENSION).map(|k| L + k as Real * last));
    let pos: Vec<Vec2> = all.iter().map(|&x| Vec2::new(x, 0.0)).collect();
    let spacing_at = |p: usize| -> Real {
        if p + 1 < all.len() {
            all[p + 1] - all[p]
        } else {
            all[p] - all[p - 1]
        }
    };
    let h_max = (0..all.len())
        .map(|p| 2.0 * spacing_at(p))
        .fold(0.0, Real::max);
    let nb = NeighborList::build(&pos, h_max);
    let k = 2.0 * PI / L;
    let f: Vec<Real> = all.iter().map(|&x| (k * x).sin()).collect();
    let (mut eg, mut el) = (0.0 as Real, 0.0 as Real);
    for p in EXTENSION..EXTENSION + N + 1 {
        let cloud = Cloud::one_dimensional(&pos, &nb, 2.0 * spacing_at(p));
        let g: Real =
            gradient_row::<Koshizuka>(GradientKind::Cmps, &cloud, Normalisation::Local, p)
                .iter()
                .map(|&(j, c)| c.x * (f[j] - f[p]))
                .sum();
        let lap =
            laplacian_row::<Koshizuka>(LaplacianKind::Classic, &cloud, Normalisation::Local, p)
                .apply(p, &f);
        let x = all[p];
        eg = eg.max((g - k * (k * x).cos()).abs() / k);
        el = el.max((lap + k * k * (k * x).sin()).abs() / (k * k));
    }
    (eg, el)
}

#[test]
fn mps_gradient_and_laplacian_on_the_meshes_of_table_2() {
    let meshes = [
        Mesh::Regular,
        Mesh::Algebraic,
        Mesh::Geometric,
        Mesh::Random,
        Mesh::Sinusoidal,
    ];
    let table: Vec<(Mesh, Real, Real)> = meshes
        .iter()
        .map(|&m| {
            let (g, l) = errors(m);
            (m, g, l)
        })
        .collect();
    println!("Isshiki 2014 §6.2, max relative error of the MPS operators, sin(2πx/L), N = 40:");
    println!("| mesh | dφ/dx | d²φ/dx² |");
    for (m, g, l) in &table {
        println!("| {m:?} | {g:.3e} | {l:.3e} |");
    }
    let kdx = 2.0 * PI / N as Real;
    let (_, g_reg, l_reg) = table[0];
    // regular mesh: exactly the centred-difference truncation error
    let g_exact = 1.0 - kdx.sin() / kdx;
    let l_exact = 1.0 - (2.0 * (kdx / 2.0).sin() / kdx).powi(2);
    assert!(
        (g_reg - g_exact).abs() < 0.05 * g_exact,
        "regular gradient error {g_reg:.4e}, centred difference {g_exact:.4e}"
    );
    assert!(
        (l_reg - l_exact).abs() < 0.05 * l_exact,
        "regular Laplacian error {l_reg:.4e}, centred difference {l_exact:.4e}"
    );
    assert!(g_reg < 5e-3 && l_reg < 5e-3);
    let get = |m: Mesh| table.iter().find(|t| t.0 == m).unwrap();
    // Table 5: the Laplacian is bad (×) on algebraic, geometric and sinusoidal meshes,
    // good on random ones
    for m in [Mesh::Algebraic, Mesh::Geometric, Mesh::Sinusoidal] {
        assert!(
            get(m).2 > 10.0 * l_reg,
            "{m:?}: Laplacian error {:.3e} should be far above the regular {l_reg:.3e}",
            get(m).2
        );
        assert!(
            get(m).2 > 5.0 * get(Mesh::Random).2,
            "{m:?}: Laplacian should be worse than on the random mesh"
        );
    }
    // Table 4: the gradient is bad only on the geometric mesh
    let g_geo = get(Mesh::Geometric).1;
    for m in [
        Mesh::Regular,
        Mesh::Algebraic,
        Mesh::Random,
        Mesh::Sinusoidal,
    ] {
        assert!(
            get(m).1 < g_geo,
            "{m:?}: gradient error {:.3e} should be below the geometric mesh's {g_geo:.3e}",
            get(m).1
        );
    }
}
