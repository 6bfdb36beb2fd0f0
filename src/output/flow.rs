//! Flow pictures: the particles of one snapshot coloured by a field, with a colour bar,
//! axes in metres and every wall and body drawn at its pose (`mpsfsi plot`, the
//! service's `snapshot.svg`). Plotters' SVG backend, like the load plots.
//!
//! What a test can read back: each particle is one filled `<rect>` of the particle
//! spacing; the colour bar is [`BAR_STEPS`] `<rect>`s right of the plot; walls are
//! `<polyline>`s in [`WALL_COLOUR`] and bodies in [`BODY_COLOUR`], of stroke width 2 and
//! 3, one per surface segment (the walls file's cells are pieces of them); [`Frame`] maps
//! metres to the picture's pixels.

use super::plot::{drawing, PlotError};
use super::snapshots::{PVD_NAME, SNAPSHOT_DIR};
use super::vtk::{parse_pvd, parse_vtu, VtuData, PARTICLES_PART, WALLS_PART};
use crate::math::Real;
use plotters::prelude::*;
use std::path::Path;

/// The field a picture is coloured by.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FlowField {
    /// Pressure; as Cp = p / (½ ρ V²) when a body moves (V its speed at that time).
    Pressure,
    Speed,
    VelocityX,
    VelocityY,
}

impl FlowField {
    pub const NAMES: [&'static str; 4] = ["pressure", "speed", "velocity_x", "velocity_y"];

    /// The field named `name`, or the message naming the valid ones.
    pub fn parse(name: &str) -> Result<Self, String> {
        Ok(match name {
            "pressure" => Self::Pressure,
            "speed" => Self::Speed,
            "velocity_x" => Self::VelocityX,
            "velocity_y" => Self::VelocityY,
            _ => {
                return Err(format!(
                    "{name:?}: expected one of {}",
                    Self::NAMES.join(", ")
                ))
            }
        })
    }
}

/// One snapshot read back: the particles and, when the run wrote them, the walls.
#[derive(Debug, Clone)]
pub struct Snapshot {
    pub time: Real,
    pub particles: VtuData,
    pub walls: Option<VtuData>,
}

#[derive(Debug, thiserror::Error)]
pub enum SnapshotError {
    #[error("the run directory has no snapshots (output.snapshot_interval was \"none\", or no step has been written yet)")]
    None,
    #[error("cannot read the snapshots: {0}")]
    Io(#[from] std::io::Error),
}

/// Times of the snapshots written so far (none: an empty list).
pub fn snapshot_times(run_dir: &Path) -> Result<Vec<Real>, SnapshotError> {
    let pvd = run_dir.join(SNAPSHOT_DIR).join(PVD_NAME);
    let text = match std::fs::read_to_string(&pvd) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(e.into()),
    };
    Ok(parse_pvd(&text)?
        .into_iter()
        .filter(|e| e.part == PARTICLES_PART)
        .map(|e| e.time)
        .collect())
}

/// The snapshot nearest `time` (the last one when `time` is None).
pub fn read_snapshot(run_dir: &Path, time: Option<Real>) -> Result<Snapshot, SnapshotError> {
    let dir = run_dir.join(SNAPSHOT_DIR);
    let text = match std::fs::read_to_string(dir.join(PVD_NAME)) {
        Ok(text) => text,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Err(SnapshotError::None),
        Err(e) => return Err(e.into()),
    };
    let entries = parse_pvd(&text)?;
    let nearest = entries
        .iter()
        .filter(|e| e.part == PARTICLES_PART)
        .min_by(|a, b| {
            let d = |t: Real| time.map_or(-t, |want| (t - want).abs());
            d(a.time).total_cmp(&d(b.time))
        })
        .ok_or(SnapshotError::None)?;
    let particles = parse_vtu(&std::fs::read_to_string(dir.join(&nearest.file))?)?;
    let walls = match entries
        .iter()
        .find(|e| e.part == WALLS_PART && e.time == nearest.time)
    {
        Some(e) => Some(parse_vtu(&std::fs::read_to_string(dir.join(&e.file))?)?),
        None => None,
    };
    Ok(Snapshot {
        time: nearest.time,
        particles,
        walls,
    })
}

/// Where the plot sits in the picture: `x`, `y` the window in metres, `pixels` the
/// plotting area (left, top, right, bottom) they map to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    pub x: (Real, Real),
    pub y: (Real, Real),
    pub pixels: (i32, i32, i32, i32),
}

impl Frame {
    /// Pixel of the point (x, y) in metres.
    pub fn to_pixel(&self, x: Real, y: Real) -> (Real, Real) {
        let (l, t, r, b) = self.pixels;
        (
            l as Real + (x - self.x.0) / (self.x.1 - self.x.0) * (r - l) as Real,
            b as Real - (y - self.y.0) / (self.y.1 - self.y.0) * (b - t) as Real,
        )
    }
}

pub const WALL_COLOUR: RGBColor = RGBColor(96, 96, 96);
pub const BODY_COLOUR: RGBColor = RGBColor(0, 0, 0);
pub const BAR_STEPS: usize = 64;

/// Width of the plotting area in pixels; the height follows the window's aspect.
const PLOT_WIDTH: u32 = 900;

/// Viridis at five stops, linearly interpolated.
fn colour_map(s: Real) -> RGBColor {
    const STOPS: [(f64, f64, f64); 5] = [
        (68.0, 1.0, 84.0),
        (59.0, 82.0, 139.0),
        (33.0, 145.0, 140.0),
        (94.0, 201.0, 98.0),
        (253.0, 231.0, 37.0),
    ];
    let s = if s.is_finite() {
        s.clamp(0.0, 1.0)
    } else {
        0.0
    } * 4.0;
    let k = (s.floor() as usize).min(3);
    let f = s - k as f64;
    let (a, b) = (STOPS[k], STOPS[k + 1]);
    let mix = |p: f64, q: f64| (p + (q - p) * f).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// The speed of the fastest moving body (m/s), from the walls' cell data.
fn body_speed(walls: Option<&VtuData>) -> Option<Real> {
    let w = walls?;
    let moving = w.cell_scalar("moving")?;
    let speed = w.cell_scalar("speed")?;
    moving
        .iter()
        .zip(speed)
        .filter(|(m, _)| **m > 0.5)
        .map(|(_, s)| *s)
        .fold(None, |acc: Option<Real>, s| {
            Some(acc.map_or(s, |a| a.max(s)))
        })
        .filter(|v| *v > 0.0)
}

/// The values to colour by, and the colour bar's label.
fn field_values(s: &Snapshot, field: FlowField) -> Result<(Vec<Real>, String), PlotError> {
    let p = &s.particles;
    let velocity = || {
        p.point_data
            .get("velocity")
            .filter(|(c, _)| *c == 3)
            .map(|(_, v)| v)
            .ok_or_else(|| PlotError::Data("the snapshot has no velocity".into()))
    };
    Ok(match field {
        FlowField::Pressure => {
            let pressure = p
                .scalar("pressure")
                .ok_or_else(|| PlotError::Data("the snapshot has no pressure".into()))?;
            let rho = p.field_data.get("density").copied();
            match (body_speed(s.walls.as_ref()), rho) {
                (Some(v), Some(rho)) => {
                    let q = 0.5 * rho * v * v;
                    (
                        pressure.iter().map(|x| x / q).collect(),
                        format!("Cp = p / (½ρV²), V = {v:.3} m/s, ½ρV² = {:.4} kPa", q / 1e3),
                    )
                }
                _ => (pressure.to_vec(), "pressure (Pa)".into()),
            }
        }
        FlowField::Speed => (
            velocity()?
                .chunks_exact(3)
                .map(|c| c[0].hypot(c[1]))
                .collect(),
            "speed (m/s)".into(),
        ),
        FlowField::VelocityX => (
            velocity()?.chunks_exact(3).map(|c| c[0]).collect(),
            "velocity x (m/s)".into(),
        ),
        FlowField::VelocityY => (
            velocity()?.chunks_exact(3).map(|c| c[1]).collect(),
            "velocity y (m/s)".into(),
        ),
    })
}

/// The colour range: the 0.1 and 99.9 percentiles of `values`, so that a few spikes do
/// not wash out the picture (values beyond take the end colours); the 99.5th clipped
/// the 30° wedge's jet-root Cp from 5 to 1.2.
fn colour_range(values: &[Real]) -> (Real, Real) {
    let mut v: Vec<Real> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return (0.0, 1.0);
    }
    v.sort_by(Real::total_cmp);
    let at = |q: Real| v[((v.len() - 1) as Real * q).round() as usize];
    let (lo, hi) = (at(0.001), at(0.999));
    if hi > lo {
        (lo, hi)
    } else {
        (lo - 0.5 * lo.abs().max(1.0), hi + 0.5 * hi.abs().max(1.0))
    }
}

/// Bounds of `points`, or None when there are none.
fn bounds<'a>(points: impl Iterator<Item = &'a [Real; 3]>) -> Option<[Real; 4]> {
    let mut b = [
        Real::INFINITY,
        Real::NEG_INFINITY,
        Real::INFINITY,
        Real::NEG_INFINITY,
    ];
    for p in points {
        b = [
            b[0].min(p[0]),
            b[1].max(p[0]),
            b[2].min(p[1]),
            b[3].max(p[1]),
        ];
    }
    b.iter().all(|v| v.is_finite()).then_some(b)
}

/// The default window: around the moving bodies, one body size beyond them on every
/// side (where the load is decided), within the bounds of everything; without a moving
/// body, everything. Padded by 2 %.
fn default_window(s: &Snapshot) -> [Real; 4] {
    let everything = std::iter::once(&s.particles).chain(s.walls.as_ref());
    let Some(all) = bounds(everything.flat_map(|g| g.points.iter())) else {
        return [0.0, 1.0, 0.0, 1.0];
    };
    let bodies = s.walls.as_ref().and_then(|w| {
        let moving = w.cell_scalar("moving")?;
        bounds(
            (0..w.cells)
                .filter(|&k| moving[k] > 0.5)
                .flat_map(|k| w.cell(k).iter().map(|&i| &w.points[i])),
        )
    });
    let [x0, x1, y0, y1] = match bodies {
        Some([bx0, bx1, by0, by1]) => {
            let size = (bx1 - bx0).max(by1 - by0);
            [
                (bx0 - size).max(all[0]),
                (bx1 + size).min(all[1]),
                (by0 - size).max(all[2]),
                (by1 + size).min(all[3]),
            ]
        }
        None => all,
    };
    let pad = 0.02 * (x1 - x0).max(y1 - y0).max(1e-9);
    [x0 - pad, x1 + pad, y0 - pad, y1 + pad]
}

/// The first and last cell of each surface segment of a walls file: the runs of
/// consecutive line cells with the same `object` and `segment` (the pieces the pressure
/// is written on), each drawn as one line. Without those arrays every cell is a run.
fn segment_runs(w: &VtuData) -> Vec<(usize, usize)> {
    let key = |k: usize| {
        w.cell_scalar("object")
            .zip(w.cell_scalar("segment"))
            .map(|(o, s)| (o[k], s[k]))
    };
    let mut runs: Vec<(usize, usize)> = Vec::new();
    for k in 0..w.cells {
        match runs.last_mut() {
            Some(run) if key(k).is_some() && key(k) == key(run.1) => run.1 = k,
            _ => runs.push((k, k)),
        }
    }
    runs
}

/// An axis label to 0.1 mm, without trailing zeros (plotters' own prints the zero tick
/// of a symmetric window as "-0.0").
fn tick(v: &Real) -> String {
    let text = format!("{v:.4}");
    let text = text.trim_end_matches('0').trim_end_matches('.');
    if text == "-0" {
        "0".into()
    } else {
        text.into()
    }
}

/// The part of the segment a-b inside `window` ([x0, x1, y0, y1]), Liang–Barsky.
fn clip_segment(
    a: (Real, Real),
    b: (Real, Real),
    [x0, x1, y0, y1]: [Real; 4],
) -> Option<((Real, Real), (Real, Real))> {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let (mut t0, mut t1) = (0.0 as Real, 1.0 as Real);
    for (p, q) in [
        (-dx, a.0 - x0),
        (dx, x1 - a.0),
        (-dy, a.1 - y0),
        (dy, y1 - a.1),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let t = q / p;
            if p < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    (t0 <= t1).then_some((
        (a.0 + t0 * dx, a.1 + t0 * dy),
        (a.0 + t1 * dx, a.1 + t1 * dy),
    ))
}

/// The picture of `snapshot` coloured by `field` over `window` ([x0, x1, y0, y1] in
/// metres; None: around the moving bodies, or everything without one), and where its
/// plot sits.
pub fn flow_svg(
    snapshot: &Snapshot,
    field: FlowField,
    window: Option<[Real; 4]>,
    title: &str,
) -> Result<(String, Frame), PlotError> {
    let [x0, x1, y0, y1] = window.unwrap_or_else(|| default_window(snapshot));
    if !(x1 > x0 && y1 > y0 && [x0, x1, y0, y1].iter().all(|v| v.is_finite())) {
        return Err(PlotError::Data(format!(
            "the window [{x0}, {x1}] x [{y0}, {y1}] is empty"
        )));
    }
    let (values, label) = field_values(snapshot, field)?;
    let (lo, hi) = colour_range(&values);
    // equal scales on both axes
    let plot_h = ((PLOT_WIDTH as Real) * (y1 - y0) / (x1 - x0)).clamp(120.0, 1400.0) as u32;
    let (left, bottom, top, bar) = (90u32, 60u32, 50u32, 170u32);
    let size = (PLOT_WIDTH + left + bar + 20, plot_h + top + bottom);
    let mut svg = String::new();
    let frame;
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        root.fill(&WHITE).map_err(drawing)?;
        let (main, side) = root.split_horizontally(PLOT_WIDTH + left + 20);
        let mut chart = ChartBuilder::on(&main)
            .caption(title, ("sans-serif", 26))
            .margin_right(20)
            .x_label_area_size(bottom)
            .y_label_area_size(left)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(drawing)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .label_style(("sans-serif", 18))
            .x_label_formatter(&tick)
            .y_label_formatter(&tick)
            .x_desc("x (m)")
            .y_desc("y (m)")
            .draw()
            .map_err(drawing)?;
        // half a spacing plus half a pixel: the marks are rounded to whole pixels, and
        // without the overlap the rounding leaves white seams between neighbours
        let pixel = (x1 - x0) / PLOT_WIDTH as Real;
        // each particle's own spacing in a multi-resolution snapshot
        let uniform = snapshot
            .particles
            .field_data
            .get("particle_spacing")
            .copied()
            .unwrap_or(0.0);
        let own = snapshot.particles.scalar("spacing");
        let half = |k: usize| 0.5 * (own.map_or(uniform, |s| s[k]) + pixel);
        let inside = |p: &[Real; 3]| p[0] >= x0 && p[0] <= x1 && p[1] >= y0 && p[1] <= y1;
        chart
            .draw_series(
                snapshot
                    .particles
                    .points
                    .iter()
                    .zip(&values)
                    .enumerate()
                    .filter(|(_, (p, _))| inside(p))
                    .map(|(k, (p, v))| {
                        let half = half(k);
                        Rectangle::new(
                            [(p[0] - half, p[1] - half), (p[0] + half, p[1] + half)],
                            colour_map((v - lo) / (hi - lo)).filled(),
                        )
                    }),
            )
            .map_err(drawing)?;
        if let Some(w) = &snapshot.walls {
            let moving = w.cell_scalar("moving");
            for (first, last) in segment_runs(w) {
                let body = moving.is_some_and(|m| m[first] > 0.5);
                let style = if body {
                    BODY_COLOUR.stroke_width(3)
                } else {
                    WALL_COLOUR.stroke_width(2)
                };
                let (Some(&a), Some(&b)) = (w.cell(first).first(), w.cell(last).last()) else {
                    continue;
                };
                let [a, b] = [a, b].map(|i| (w.points[i][0], w.points[i][1]));
                // plotters would pin a point outside the window to its edge
                if let Some((a, b)) = clip_segment(a, b, [x0, x1, y0, y1]) {
                    chart
                        .draw_series(std::iter::once(PathElement::new(vec![a, b], style)))
                        .map_err(drawing)?;
                }
            }
        }
        let (xs, ys) = chart.plotting_area().get_pixel_range();
        frame = Frame {
            x: (x0, x1),
            y: (y0, y1),
            pixels: (xs.start, ys.start, xs.end, ys.end),
        };
        // the colour bar
        let mut bar_chart = ChartBuilder::on(&side)
            .margin_top(top)
            .margin_bottom(bottom)
            .right_y_label_area_size(90)
            .build_cartesian_2d(0.0..1.0, lo..hi)
            .map_err(drawing)?;
        bar_chart
            .configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .label_style(("sans-serif", 16))
            .y_desc(label.as_str())
            .draw()
            .map_err(drawing)?;
        let step = (hi - lo) / BAR_STEPS as Real;
        bar_chart
            .draw_series((0..BAR_STEPS).map(|k| {
                let a = lo + step * k as Real;
                Rectangle::new(
                    [(0.0, a), (1.0, a + step)],
                    colour_map((k as Real + 0.5) / BAR_STEPS as Real).filled(),
                )
            }))
            .map_err(drawing)?;
        root.present().map_err(drawing)?;
    }
    Ok((svg, frame))
}

/// The title of a snapshot's picture.
pub fn title(name: &str, snapshot: &Snapshot) -> String {
    format!("{name}: t = {:.3} ms", snapshot.time * 1e3)
}

/// Pattern of a window (the `window` query parameter's in the contract): four numbers of
/// at most a million metres, comma separated.
pub const WINDOW_PATTERN: &str =
    r"^ *-?[0-9]{1,6}(\.[0-9]{1,9})? *(, *-?[0-9]{1,6}(\.[0-9]{1,9})? *){3}$";

/// A window `X0,X1,Y0,Y1` in metres (`--window`, the `window` query parameter): the
/// corners in either order; a side of zero width is widened to the other side's width
/// (1 m when both are zero), so any four numbers draw something.
pub fn parse_window(text: &str) -> Result<[f64; 4], String> {
    let values: Vec<f64> = text
        .split(',')
        .map(|v| v.trim().parse::<f64>().map_err(|e| format!("{v:?}: {e}")))
        .collect::<Result<_, _>>()?;
    let [a, b, c, d] = values[..] else {
        return Err(format!(
            "{text:?}: expected four numbers X0,X1,Y0,Y1 in metres"
        ));
    };
    if !values.iter().all(|v| v.is_finite()) {
        return Err(format!("{text:?}: the corners must be finite"));
    }
    let (mut x0, mut x1, mut y0, mut y1) = (a.min(b), a.max(b), c.min(d), c.max(d));
    let fallback = |other: f64| if other > 0.0 { other } else { 1.0 };
    if x1 == x0 {
        let w = 0.5 * fallback(y1 - y0);
        (x0, x1) = (x0 - w, x1 + w);
    }
    if y1 == y0 {
        let h = 0.5 * fallback(x1 - x0);
        (y0, y1) = (y0 - h, y1 + h);
    }
    Ok([x0, x1, y0, y1])
}
