use mpsfsi::output::plot::{loads_svg, loads_svg_with_band, log_log_svg, Series};

fn loads_text(bodies: &[&str], rows: usize) -> String {
    let mut s = String::from("time,body,fx,fy,mz\n");
    for k in 1..=rows {
        let t = k as f64 * 1e-3;
        for (b, name) in bodies.iter().enumerate() {
            let phase = b as f64;
            s.push_str(&format!(
                "{t:.9e},{name},{:.9e},{:.9e},{:.9e}\n",
                (40.0 * t + phase).sin(),
                100.0 * t,
                -(t + phase).cos()
            ));
        }
    }
    s
}

/// Points of every data-series `<polyline>` (stroke width 2; grid and axis lines are
/// polylines of width 1) in order.
fn polylines(svg: &str) -> Vec<usize> {
    svg.match_indices("<polyline")
        .filter_map(|(at, _)| {
            let rest = &svg[at..];
            let tag = &rest[..rest.find("/>").unwrap()];
            if !tag.contains("stroke-width=\"2\"") {
                return None;
            }
            let start = rest.find("points=\"").unwrap() + 8;
            let end = rest[start..].find('"').unwrap() + start;
            Some(rest[start..end].split_whitespace().count())
        })
        .collect()
}

fn assert_well_formed(svg: &str) {
    assert!(
        svg.trim_start().starts_with("<svg") || svg.trim_start().starts_with("<?xml"),
        "starts like an SVG document"
    );
    assert!(svg.trim_end().ends_with("</svg>"));
    assert_eq!(svg.matches("<svg").count(), 1);
    // every opened text element is closed
    assert_eq!(svg.matches("<text").count(), svg.matches("</text>").count());
}

#[test]
fn loads_svg_draws_one_polyline_per_body_and_component() {
    let svg = loads_svg(&loads_text(&["wedge", "tank"], 60), "wedge entry").unwrap();
    assert_well_formed(&svg);
    let lines = polylines(&svg);
    assert_eq!(lines.len(), 6, "3 components x 2 bodies");
    assert!(
        lines.iter().all(|&n| n == 60),
        "each line has one point per sample: {lines:?}"
    );
    for label in [
        "time (s)",
        "fx (N/m)",
        "fy (N/m)",
        "mz (N·m/m)",
        "wedge entry",
        "wedge",
        "tank",
    ] {
        assert!(svg.contains(label), "label {label:?} missing");
    }
}

#[test]
fn loads_svg_of_a_run_that_has_not_written_a_row_is_still_a_plot() {
    let svg = loads_svg("time,body,fx,fy,mz\n", "queued").unwrap();
    assert_well_formed(&svg);
    assert_eq!(polylines(&svg).len(), 0);
    assert!(svg.contains("no load samples yet"));
}

/// With loads_uncertainty.csv, each body's band is one filled polygon per panel, drawn
/// under the lines, and the axes reach the band's extremes (±5 kN/m here: far outside
/// the loads themselves, so a tick beyond 1000 appears).
#[test]
fn loads_svg_shades_the_band_of_each_body() {
    let loads = loads_text(&["wedge", "tank"], 60);
    let mut band = String::from("time,body,fx,fy,mz,u_fx,u_fy,u_mz\n");
    for line in loads.lines().skip(1) {
        band.push_str(&format!("{line},5000,5000,5000\n"));
    }
    let svg = loads_svg_with_band(&loads, Some(&band), "banded").unwrap();
    assert_well_formed(&svg);
    assert_eq!(
        svg.matches("<polygon").count(),
        6,
        "3 components x 2 bodies"
    );
    assert_eq!(polylines(&svg).len(), 6, "the lines are still there");
    assert!(svg.contains("4000"), "the axes hold the band");
    let plain = loads_svg_with_band(&loads, None, "plain").unwrap();
    assert_eq!(plain.matches("<polygon").count(), 0);
    let wrong = loads_svg_with_band(&loads, Some("time,body,fx\n"), "x").unwrap_err();
    assert!(
        wrong.to_string().contains("loads_uncertainty.csv"),
        "{wrong}"
    );
}

#[test]
fn loads_svg_rejects_text_that_is_not_loads_csv() {
    assert!(loads_svg("a,b\n1,2\n", "x").is_err());
    assert!(loads_svg("time,body,fx,fy,mz\n0.1,wedge,oops,1,2\n", "x").is_err());
}

#[test]
fn log_log_svg_draws_a_line_per_series_and_skips_non_positive_points() {
    let series = vec![
        Series {
            name: "classic".into(),
            points: vec![(0.5, 0.2), (2.0, 0.1), (8.0, 0.05)],
        },
        Series {
            name: "default".into(),
            points: vec![(0.7, 0.08), (3.0, 0.0), (9.0, f64::NAN), (10.0, 0.01)],
        },
    ];
    let svg = log_log_svg("dam break", "wall time (s)", "relative error", &series).unwrap();
    assert_well_formed(&svg);
    assert_eq!(polylines(&svg), vec![3, 2]);
}

/// Writes the load plot of a run's loads.csv for a look: `LOADS_CSV=path cargo test
/// --release --test output -- --ignored look_at`.
#[test]
#[ignore]
fn look_at_a_loads_plot() {
    let path = std::env::var("LOADS_CSV").expect("LOADS_CSV names a loads.csv");
    let svg = loads_svg(&std::fs::read_to_string(&path).unwrap(), "loads").unwrap();
    std::fs::write(std::path::Path::new(&path).with_extension("svg"), svg).unwrap();
}
