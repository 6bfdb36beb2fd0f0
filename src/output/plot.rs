//! SVG plots (plotters' SVG backend into a String): the load history of a run (the
//! service's `/loads.svg`, `mpsfsi plot RUN --loads`), with its 95 % band when the run
//! has one, and the benchmark's error against wall time.
//!
//! Every data series is one `<polyline>` of stroke width 2 (grid and axis lines are
//! polylines of width 1; legend keys are rectangles), so the series can be counted.

use super::loads_csv::parse_loads_csv;
use plotters::prelude::*;
use std::collections::BTreeMap;

#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    #[error("cannot read the data: {0}")]
    Data(String),
    #[error("cannot draw the plot: {0}")]
    Drawing(String),
}

pub(super) fn drawing<E: std::fmt::Debug>(e: E) -> PlotError {
    PlotError::Drawing(format!("{e:?}"))
}

/// Colours of successive series.
const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

pub(super) fn colour(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

/// [lo, hi] of finite values, widened when empty or flat.
pub(super) fn padded_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let span = hi - lo;
    let pad = if span > 0.0 {
        0.05 * span
    } else {
        lo.abs().max(1.0) * 0.05
    };
    (lo - pad, hi + pad)
}

/// The load history of `loads.csv` (text with the header `time,body,fx,fy,mz`) as
/// an SVG document: three stacked panels, fx and fy in N/m and mz in N·m/m against
/// time in s, one line per body in each panel. The text of a file a running job is
/// still appending to is passed up to its last newline.
pub fn loads_svg(csv_text: &str, title: &str) -> Result<String, PlotError> {
    loads_svg_with_band(csv_text, None, title)
}

/// Per body, the rows of `loads_uncertainty.csv`: (time, [fx, fy, mz], [u_fx, u_fy, u_mz]).
type Band = BTreeMap<String, Vec<(f64, [f64; 3], [f64; 3])>>;

fn parse_band(text: &str) -> Result<Band, PlotError> {
    let bad = |e: String| PlotError::Data(format!("loads_uncertainty.csv: {e}"));
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .from_reader(super::series::complete_lines(text.as_bytes()));
    let header: Vec<String> = reader
        .headers()
        .map_err(|e| bad(e.to_string()))?
        .iter()
        .map(str::to_string)
        .collect();
    if header != ["time", "body", "fx", "fy", "mz", "u_fx", "u_fy", "u_mz"] {
        return Err(bad(format!("header {header:?}")));
    }
    let mut band = Band::new();
    for record in reader.records() {
        let record = record.map_err(|e| bad(e.to_string()))?;
        let v: Vec<f64> = [0, 2, 3, 4, 5, 6, 7]
            .iter()
            .map(|&i| {
                record[i]
                    .trim()
                    .parse::<f64>()
                    .map_err(|e| bad(e.to_string()))
            })
            .collect::<Result<_, _>>()?;
        band.entry(record[1].to_string()).or_default().push((
            v[0],
            [v[1], v[2], v[3]],
            [v[4], v[5], v[6]],
        ));
    }
    Ok(band)
}

/// [`loads_svg`] with, when `band_text` (the text of `loads_uncertainty.csv`) is given,
/// each body's 95 % band drawn as a shaded area (filtered load ± half-width) under its
/// line. The band's extent is kept in the axes.
pub fn loads_svg_with_band(
    csv_text: &str,
    band_text: Option<&str>,
    title: &str,
) -> Result<String, PlotError> {
    let band = band_text.map(parse_band).transpose()?.unwrap_or_default();
    let rows = parse_loads_csv(csv_text).map_err(|e| PlotError::Data(e.to_string()))?;
    // body -> (t, [fx, fy, mz]) in file order; bodies in order of first appearance
    let mut order: Vec<String> = Vec::new();
    let mut series: BTreeMap<String, Vec<(f64, [f64; 3])>> = BTreeMap::new();
    for r in &rows {
        if !series.contains_key(&r.body) {
            order.push(r.body.clone());
        }
        series
            .entry(r.body.clone())
            .or_default()
            .push((r.time, [r.fx, r.fy, r.mz]));
    }
    let (t0, t1) = padded_range(rows.iter().map(|r| r.time));
    let panels = [
        ("fx (N/m)", "horizontal force fx"),
        ("fy (N/m)", "vertical force fy"),
        ("mz (N·m/m)", "moment mz"),
    ];

    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 960)).into_drawing_area();
        root.fill(&WHITE).map_err(drawing)?;
        let root = root.titled(title, ("sans-serif", 22)).map_err(drawing)?;
        if rows.is_empty() {
            // a queued job, or one that has not reached its first sample time
            root.draw(&Text::new(
                "no load samples yet",
                (350, 400),
                ("sans-serif", 18),
            ))
            .map_err(drawing)?;
        }
        let areas = root.split_evenly((3, 1));
        for (c, (area, (label, caption))) in areas.iter().zip(panels).enumerate() {
            let banded = band
                .values()
                .flatten()
                .flat_map(|(_, v, u)| [v[c] - u[c], v[c] + u[c]]);
            let (lo, hi) = padded_range(rows.iter().map(|r| [r.fx, r.fy, r.mz][c]).chain(banded));
            let mut chart = ChartBuilder::on(area)
                .caption(caption, ("sans-serif", 16))
                .margin(8)
                .x_label_area_size(40)
                .y_label_area_size(80)
                .build_cartesian_2d(t0..t1, lo..hi)
                .map_err(drawing)?;
            chart
                .configure_mesh()
                .x_desc("time (s)")
                .y_desc(label)
                .light_line_style(WHITE.mix(0.0))
                .draw()
                .map_err(drawing)?;
            for (b, name) in order.iter().enumerate() {
                let Some(rows) = band.get(name) else { continue };
                let outline: Vec<(f64, f64)> = rows
                    .iter()
                    .map(|(t, v, u)| (*t, v[c] + u[c]))
                    .chain(rows.iter().rev().map(|(t, v, u)| (*t, v[c] - u[c])))
                    .filter(|(t, y)| t.is_finite() && y.is_finite())
                    .collect();
                chart
                    .draw_series(std::iter::once(Polygon::new(
                        outline,
                        colour(b).mix(0.2).filled(),
                    )))
                    .map_err(drawing)?;
            }
            for (b, name) in order.iter().enumerate() {
                let points: Vec<(f64, f64)> = series[name]
                    .iter()
                    .filter(|(t, v)| t.is_finite() && v[c].is_finite())
                    .map(|(t, v)| (*t, v[c]))
                    .collect();
                let color = colour(b);
                chart
                    .draw_series(LineSeries::new(points, color.stroke_width(2)))
                    .map_err(drawing)?
                    .label(name.as_str())
                    .legend(move |(x, y)| {
                        Rectangle::new([(x, y - 4), (x + 16, y + 4)], color.filled())
                    });
            }
            if !order.is_empty() {
                chart
                    .configure_series_labels()
                    .background_style(WHITE.mix(0.85))
                    .border_style(BLACK)
                    .draw()
                    .map_err(drawing)?;
            }
        }
        root.present().map_err(drawing)?;
    }
    Ok(svg)
}

/// One line of a log-log plot.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    pub name: String,
    /// (x, y); points with a non-positive or non-finite coordinate are left out.
    pub points: Vec<(f64, f64)>,
}

fn log_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return (0.1, 10.0);
    }
    (lo / 1.5, hi * 1.5)
}

/// A log-log plot, one line (with point markers) per series, joining its points in
/// the order given: the benchmark's error against wall time.
pub fn log_log_svg(
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> Result<String, PlotError> {
    let keep = |(x, y): &(f64, f64)| x.is_finite() && y.is_finite() && *x > 0.0 && *y > 0.0;
    let (x0, x1) = log_range(
        series
            .iter()
            .flat_map(|s| s.points.iter().filter(|p| keep(p)).map(|p| p.0)),
    );
    let (y0, y1) = log_range(
        series
            .iter()
            .flat_map(|s| s.points.iter().filter(|p| keep(p)).map(|p| p.1)),
    );
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (800, 600)).into_drawing_area();
        root.fill(&WHITE).map_err(drawing)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
            .map_err(drawing)?;
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc(y_label)
            .draw()
            .map_err(drawing)?;
        let mut labelled = false;
        for (i, s) in series.iter().enumerate() {
            // in the given order (the benchmark gives coarse to fine spacing)
            let points: Vec<(f64, f64)> = s.points.iter().copied().filter(keep).collect();
            if points.is_empty() {
                continue;
            }
            let color = colour(i);
            chart
                .draw_series(LineSeries::new(points.clone(), color.stroke_width(2)))
                .map_err(drawing)?
                .label(s.name.as_str())
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 4), (x + 16, y + 4)], color.filled())
                });
            chart
                .draw_series(
                    points
                        .into_iter()
                        .map(|p| Circle::new(p, 4, color.filled())),
                )
                .map_err(drawing)?;
            labelled = true;
        }
        if labelled {
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .draw()
                .map_err(drawing)?;
        }
        root.present().map_err(drawing)?;
    }
    Ok(svg)
}
