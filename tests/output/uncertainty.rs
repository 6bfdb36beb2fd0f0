//! The least-squares GCI (Eça & Hoekstra 2014) on manufactured ladders whose exact
//! limit is known, and the ladder's files from manufactured run directories.

use crate::scratch_dir;
use mpsfsi::analysis::uncertainty::{half_width, student_t95, Fit, SAFETY_OUTSIDE};
use mpsfsi::run::uncertainty::{combine, plan, Part};

const H: [f64; 4] = [1.0, 1.25, 1.5625, 1.953125];

fn ladder(limit: f64, a: f64, p: f64) -> Vec<f64> {
    H.iter().map(|h| limit + a * h.powf(p)).collect()
}

/// Data on phi_0 + alpha h^p with p inside [0.5, 2.1): the fit recovers p and phi_0,
/// and the half-width is 1.25 times the error estimate (no scatter, no misfit).
#[test]
fn an_exact_ladder_in_the_expected_range_gets_the_order_and_factor_1_25() {
    let phi = ladder(2.0, 0.3, 1.5);
    let e = half_width(&H, &phi, 0.0);
    assert_eq!(e.fit, Fit::ObservedOrder);
    assert!((e.order - 1.5).abs() < 1e-4, "order {}", e.order);
    assert!(
        (e.extrapolated - 2.0).abs() < 1e-6,
        "phi_0 {}",
        e.extrapolated
    );
    assert!(
        (e.half_width - 1.25 * 0.3).abs() < 1e-5,
        "U {}",
        e.half_width
    );
    assert!(e.well_behaved());
    // a random part adds in quadrature
    let r = half_width(&H, &phi, 0.4);
    assert!((r.half_width - (1.25f64 * 0.3).hypot(0.4)).abs() < 1e-5);
}

/// An order above 2.1 takes the safety factor 3 and a fixed-order fit; the band still
/// holds the exact limit.
#[test]
fn an_order_outside_the_range_takes_factor_3_and_still_holds_the_limit() {
    for p in [0.3, 3.0] {
        let phi = ladder(2.0, 0.3, p);
        let e = half_width(&H, &phi, 0.0);
        assert_ne!(e.fit, Fit::ObservedOrder, "p = {p}");
        assert_eq!(e.safety_factor, SAFETY_OUTSIDE, "p = {p}");
        assert!(!e.well_behaved());
        assert!(
            (e.value - 2.0).abs() <= e.half_width,
            "p = {p}: error {} outside ±{}",
            e.value - 2.0,
            e.half_width
        );
    }
}

/// Levels that differ only by scatter (no trend) take the scatter rule 3 U_s / Delta,
/// which is at least 3, and the band is at least the data range.
#[test]
fn scatter_without_a_trend_widens_the_band_beyond_the_range() {
    let phi = [2.0, 2.01, 1.99, 2.012];
    let e = half_width(&H, &phi, 0.0);
    assert!(
        e.safety_factor >= SAFETY_OUTSIDE,
        "factor {}",
        e.safety_factor
    );
    assert!(e.half_width >= 0.022, "U {}", e.half_width);
    // levels that agree exactly leave only the random part
    let flat = half_width(&H, &[2.0; 4], 0.05);
    assert_eq!(flat.fit, Fit::Constant);
    assert_eq!(flat.half_width, 0.05);
}

#[test]
fn student_t_quantiles_match_the_table() {
    assert_eq!(student_t95(3), 3.182);
    assert_eq!(student_t95(7), 2.365);
    assert_eq!(student_t95(1000), 1.96);
}

/// Manufactured run directories: every level's force is f(t) (1 + 0.2 (h/h_0)^1.5)
/// with f linear in t, the ensemble members alike. Away from the filter's ends each row
/// then reads the order 1.5 exactly and its half-width is 1.25 times 0.2 f(t);
/// loads_uncertainty.csv carries the user's rows with those widths.
#[test]
fn the_ladder_files_carry_the_finest_rows_and_their_half_widths() {
    let out = scratch_dir("uncertainty_combine");
    let h0 = 0.005;
    let parts: Vec<Part> = vec![(0, None), (1, None), (2, None)]
        .into_iter()
        .chain((0..4).map(|m| (3, Some((m as f64 + 0.5) / 4.0))))
        .map(|(level, phase)| Part {
            level,
            spacing: h0 * H[level],
            phase,
            name: format!("p{level}{phase:?}"),
        })
        .collect();
    let mut dirs = Vec::new();
    for (k, p) in parts.iter().enumerate() {
        let dir = if k == 0 {
            out.clone()
        } else {
            out.join(&p.name)
        };
        std::fs::create_dir_all(&dir).unwrap();
        let mut text = String::from("time,body,fx,fy,mz\n");
        for i in 1..=100 {
            let t = i as f64 * 1e-4;
            let fy = 1e6 * t * (1.0 + 0.2 * (p.spacing / h0).powf(1.5));
            text.push_str(&format!("{t},wedge,0,{fy},0\n"));
        }
        std::fs::write(dir.join("loads.csv"), text).unwrap();
        // a body whose fall speed reads 6 m/s (1 + 0.1 (h/h_0)^1.5) at every row
        let mut bodies = String::from("time,body,x,y,angle,vx,vy,omega\n");
        for i in 1..=100 {
            let vy = -6.0 * (1.0 + 0.1 * (p.spacing / h0).powf(1.5));
            bodies.push_str(&format!("{},wedge,0,0.1,0,0,{vy},0\n", i as f64 * 1e-4));
        }
        std::fs::write(dir.join("bodies.csv"), bodies).unwrap();
        dirs.push(dir);
    }
    let summary = combine(&out, &parts, &dirs, 5e-4).unwrap();
    let text = std::fs::read_to_string(out.join("loads_uncertainty.csv")).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("time,body,fx,fy,mz,u_fx,u_fy,u_mz"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| {
            l.split(',')
                .enumerate()
                .filter(|(i, _)| *i != 1)
                .map(|(_, v)| v.parse().unwrap())
                .collect()
        })
        .collect();
    assert_eq!(rows.len(), 100);
    for r in &rows[10..90] {
        let (t, fy, u) = (r[0], r[2], r[5]);
        let expected = 1e6 * t * 1.2;
        assert!((fy - expected).abs() < 1e-6 * expected, "t {t}: fy {fy}");
        assert!(
            (u - 1.25 * 0.2 * 1e6 * t).abs() < 1e-3 * u,
            "t {t}: u_fy {u} against {}",
            1.25 * 0.2 * 1e6 * t
        );
    }
    let fy = &summary.bodies[0].columns[1];
    assert_eq!(fy.column, "fy");
    assert!((fy.impulse.order - 1.5).abs() < 1e-3, "{:?}", fy.impulse);
    assert!(fy.rows_well_behaved > 0.8, "{}", fy.rows_well_behaved);
    // the motion's band, unfiltered: every row the exact 1.25 x 0.1 x 6 m/s
    let motion = std::fs::read_to_string(out.join("bodies_uncertainty.csv")).unwrap();
    let mut lines = motion.lines();
    assert_eq!(
        lines.next(),
        Some("time,body,x,y,angle,vx,vy,omega,u_x,u_y,u_angle,u_vx,u_vy,u_omega")
    );
    for l in lines {
        let f: Vec<f64> = l.split(',').skip(2).map(|v| v.parse().unwrap()).collect();
        assert!((f[4] + 6.6).abs() < 1e-9, "{l}");
        assert!((f[10] - 0.75).abs() < 1e-6, "{l}");
        assert_eq!(f[7], 0.0, "{l}");
    }
    // no probes.csv: no probes_uncertainty.csv
    assert!(!out.join("probes_uncertainty.csv").exists());
}

/// The shipped wedge's ladder: four levels about 1.25 apart, each a whole number of
/// rows of the 1.2 m of water, the coarsest four lattice offsets.
#[test]
fn the_ladder_keeps_the_water_depth_in_whole_rows() {
    let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("cases/wedge_30deg_constant_velocity.json");
    let case = mpsfsi::case::load_case_file(&path, &[]).unwrap();
    let parts = plan(&case, 1.25, 4, 4).unwrap();
    assert_eq!(parts.len(), 7);
    assert_eq!(parts[0].spacing, case.particle_spacing);
    for p in &parts {
        let rows = 1.2 / p.spacing;
        assert!((rows - rows.round()).abs() < 1e-9, "{p:?}: {rows} rows");
        let nominal = case.particle_spacing * 1.25f64.powi(p.level as i32);
        assert!((p.spacing / nominal - 1.0).abs() < 0.01, "{p:?}");
    }
    let phases: Vec<f64> = parts.iter().filter_map(|p| p.phase).collect();
    assert_eq!(phases, vec![0.125, 0.375, 0.625, 0.875]);
}
