//! `loads.svg`: fx, fy and mz of every body and wall against time, three panels.

use plotters::prelude::*;

/// Render the load history (rows of `(name, time, [fx, fy, mz])`) as an SVG document.
pub fn loads_svg(title: &str, rows: &[(String, f64, [f64; 3])]) -> Result<String, String> {
    let mut names: Vec<&str> = Vec::new();
    for (name, ..) in rows {
        if !names.contains(&name.as_str()) {
            names.push(name);
        }
    }
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 960)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let root = root
            .titled(title, ("sans-serif", 22))
            .map_err(|e| e.to_string())?;
        if rows.is_empty() {
            root.draw(&Text::new(
                "no load samples yet",
                (350, 400),
                ("sans-serif", 18),
            ))
            .map_err(|e| e.to_string())?;
        } else {
            let (t0, t1) = range(rows.iter().map(|r| r.1));
            let panels = root.split_evenly((3, 1));
            let labels = ["fx (N/m)", "fy (N/m)", "mz (N·m/m)"];
            for (c, area) in panels.iter().enumerate() {
                let (y0, y1) = range(rows.iter().map(|r| r.2[c]));
                let mut chart = ChartBuilder::on(area)
                    .margin(12)
                    .x_label_area_size(36)
                    .y_label_area_size(80)
                    .build_cartesian_2d(t0..t1, y0..y1)
                    .map_err(|e| e.to_string())?;
                chart
                    .configure_mesh()
                    .x_desc("time (s)")
                    .y_desc(labels[c])
                    .draw()
                    .map_err(|e| e.to_string())?;
                for (k, name) in names.iter().enumerate() {
                    let color = Palette99::pick(k).to_rgba();
                    let points = rows.iter().filter(|r| r.0 == *name).map(|r| (r.1, r.2[c]));
                    chart
                        .draw_series(LineSeries::new(points, color.stroke_width(2)))
                        .map_err(|e| e.to_string())?
                        .label(name.to_string())
                        .legend(move |(x, y)| {
                            PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                        });
                }
                chart
                    .configure_series_labels()
                    .background_style(WHITE.mix(0.8))
                    .border_style(BLACK)
                    .draw()
                    .map_err(|e| e.to_string())?;
            }
        }
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(svg)
}

/// A non-empty finite range covering the values.
fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = ((hi - lo) * 0.05)
        .max(hi.abs().max(lo.abs()) * 1e-3)
        .max(1e-12);
    (lo - pad, hi + pad)
}
