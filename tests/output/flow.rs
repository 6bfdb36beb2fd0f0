//! Flow pictures and the walls in the snapshots: the body drawn and written at the pose
//! its prescribed motion gives (x(t) = x0 + V t), the default snapshot schedule, and a
//! third-party reader (meshio) opening the walls' files.

use crate::scratch_dir;
use mpsfsi::case::{load_case_file, parse_case_value, Limits, Motion, ValidCase};
use mpsfsi::output::flow::{
    flow_svg, read_snapshot, snapshot_times, FlowField, BAR_STEPS, BODY_COLOUR,
};
use mpsfsi::run::{run_case, Quiet, RunStatus};
use serde_json::{json, Value};
use std::path::Path;

/// Body vertices in its own frame, its start position and its velocity.
const BOX: [[f64; 2]; 4] = [[-0.05, 0.0], [0.05, 0.0], [0.05, 0.05], [-0.05, 0.05]];
const START: [f64; 2] = [0.2, 0.12];
const V: f64 = -1.0;
const END: f64 = 0.04;

/// A box pushed down into a small tank at 1 m/s; `output` as given.
fn box_entry(output: Value) -> Value {
    json!({
        "name": "box-entry",
        "fluid": { "density": 1000.0, "kinematic_viscosity": 1.0e-6, "gravity": [0.0, -9.81] },
        "particle_spacing": 0.01,
        "domain": { "min": [-0.05, -0.05], "max": [0.45, 0.3] },
        "fluid_blocks": [ { "polygon": [[0.0, 0.0], [0.4, 0.0], [0.4, 0.1], [0.0, 0.1]] } ],
        "walls": [ { "name": "tank", "polyline": [[0.0, 0.25], [0.0, 0.0], [0.4, 0.0], [0.4, 0.25]] } ],
        "bodies": [ {
            "name": "box", "polygon": BOX, "position": START, "angle": 0.0,
            "motion": { "type": "prescribed", "velocity": [0.0, V], "angular_velocity": 0.0 }
        } ],
        "time": { "end": END, "max_dt": 1.0e-3 },
        "output": output
    })
}

fn run(case: Value, dir: &Path) {
    let case = ValidCase::new(parse_case_value(case).unwrap(), &Limits::default()).unwrap();
    let summary = run_case(&case, dir, &mut Quiet).unwrap();
    assert_eq!(summary.status, RunStatus::Succeeded, "{:?}", summary.reason);
}

/// Where the box's vertex k is at time t.
fn vertex_at(k: usize, t: f64) -> [f64; 2] {
    [BOX[k][0] + START[0], BOX[k][1] + START[1] + V * t]
}

#[test]
fn snapshots_default_to_ten_over_the_run_and_none_turns_them_off() {
    let dir = scratch_dir("snapshots-default");
    run(box_entry(json!({ "load_interval": 0.001 })), &dir);
    let times = snapshot_times(&dir).unwrap();
    assert_eq!(times.len(), 11, "t = 0 and ten intervals: {times:?}");
    for (k, t) in times.iter().enumerate() {
        // a snapshot is written at the first step at or after its time
        let due = END * k as f64 / 10.0;
        assert!(
            *t >= due - 1e-12 && *t < due + 1.0e-3,
            "snapshot {k} at {t}"
        );
    }
    for off in [json!("none"), Value::Null] {
        let dir = scratch_dir("snapshots-off");
        run(
            box_entry(json!({ "load_interval": 0.001, "snapshot_interval": off })),
            &dir,
        );
        assert!(!dir.join("snapshots").exists(), "{off}: no snapshots");
        assert!(snapshot_times(&dir).unwrap().is_empty());
        assert!(read_snapshot(&dir, None).is_err());
    }
}

#[test]
fn the_walls_file_holds_each_surface_at_its_pose() {
    let dir = scratch_dir("walls-pose");
    run(box_entry(json!({ "load_interval": 0.001 })), &dir);
    for t in snapshot_times(&dir).unwrap() {
        let s = read_snapshot(&dir, Some(t)).unwrap();
        assert_eq!(s.time, t);
        let walls = s.walls.expect("a walls file beside every particle file");
        let moving = walls.cell_scalar("moving").unwrap();
        let object = walls.cell_scalar("object").unwrap();
        let segment = walls.cell_scalar("segment").unwrap();
        let speed = walls.cell_scalar("speed").unwrap();
        let pressure = walls.cell_scalar("pressure").unwrap();
        // the tank: 3 segments, fixed; the box: 4 segments, moving at |V|; each segment
        // cut into pieces of equal length, at most l0/2 (the load integral's), which
        // together make the segment
        let mut segments: std::collections::BTreeMap<_, Vec<([f64; 3], [f64; 3])>> =
            Default::default();
        for k in 0..walls.cells {
            let [a, b] = [0, 1].map(|e| walls.points[walls.cell(k)[e]]);
            let length = (b[0] - a[0]).hypot(b[1] - a[1]);
            assert!(length <= 0.005 * (1.0 + 1e-9), "cell {k}: {length} m");
            let pieces: &mut Vec<_> = segments
                .entry((object[k] as u32, segment[k] as u32))
                .or_default();
            if let Some(&(_, end)) = pieces.last() {
                assert!(
                    [0, 1].iter().all(|&c| (a[c] - end[c]).abs() < 1e-12),
                    "cell {k} starts where the one before it ends"
                );
            }
            pieces.push((a, b));
            assert!(pressure[k] >= 0.0 && pressure[k].is_finite());
        }
        let keys: Vec<_> = segments.keys().copied().collect();
        let expected: Vec<(u32, u32)> = (0..3)
            .map(|s| (0, s))
            .chain((0..4).map(|s| (1, s)))
            .collect();
        assert_eq!(keys, expected, "(object, segment) of the cells");
        for ((o, s), pieces) in &segments {
            let lengths: Vec<f64> = pieces
                .iter()
                .map(|(a, b)| (b[0] - a[0]).hypot(b[1] - a[1]))
                .collect();
            assert!(
                lengths.iter().all(|l| (l - lengths[0]).abs() < 1e-12),
                "object {o} segment {s}: equal pieces {lengths:?}"
            );
        }
        assert_eq!(
            moving.iter().filter(|m| **m == 1.0).count(),
            segments
                .iter()
                .filter(|((o, _), _)| *o == 1)
                .map(|(_, p)| p.len())
                .sum::<usize>()
        );
        let mut corners = Vec::new();
        for k in 0..walls.cells {
            assert_eq!(walls.cell(k).len(), 2, "a line cell");
            if moving[k] == 1.0 {
                assert_eq!(
                    object[k], 1.0,
                    "the box is the second object, as in loads.csv"
                );
                assert!((speed[k] - V.abs()).abs() < 1e-12);
                corners.extend(walls.cell(k).iter().map(|&i| walls.points[i]));
            }
        }
        for k in 0..4 {
            let [x, y] = vertex_at(k, t);
            assert!(
                corners
                    .iter()
                    .any(|p| (p[0] - x).abs() < 1e-9 && (p[1] - y).abs() < 1e-9),
                "vertex {k} at ({x}, {y}) at t = {t}: {corners:?}"
            );
        }
        let (c, v) = &walls.point_data["velocity"];
        assert_eq!(*c, 3);
        for (k, m) in moving.iter().enumerate() {
            for &i in walls.cell(k) {
                let want = if *m == 1.0 { V } else { 0.0 };
                assert!((v[3 * i + 1] - want).abs() < 1e-12 && v[3 * i].abs() < 1e-12);
            }
        }
    }
}

/// The `points` of every `<polyline>` drawn in `colour` with stroke width `width`.
fn polylines(svg: &str, colour: &str, width: u32) -> Vec<Vec<(f64, f64)>> {
    let mut out = Vec::new();
    for element in svg.split("<polyline").skip(1) {
        let element = &element[..element.find("/>").unwrap()];
        if !element.contains(&format!("stroke=\"{colour}\""))
            || !element.contains(&format!("stroke-width=\"{width}\""))
        {
            continue;
        }
        let points = element.split("points=\"").nth(1).unwrap();
        let points = &points[..points.find('"').unwrap()];
        out.push(
            points
                .split_whitespace()
                .map(|p| {
                    let (x, y) = p.split_once(',').unwrap();
                    (x.parse().unwrap(), y.parse().unwrap())
                })
                .collect(),
        );
    }
    out
}

/// (x, y, width, fill) of every `<rect>`.
fn rects(svg: &str) -> Vec<(f64, f64, f64, String)> {
    let attribute = |e: &str, name: &str| -> String {
        let from = e.find(&format!(" {name}=\"")).unwrap() + name.len() + 3;
        e[from..from + e[from..].find('"').unwrap()].to_string()
    };
    svg.split("<rect")
        .skip(1)
        .map(|e| {
            let e = &e[..e.find("/>").unwrap()];
            (
                attribute(e, "x").parse().unwrap(),
                attribute(e, "y").parse().unwrap(),
                attribute(e, "width").parse().unwrap(),
                attribute(e, "fill"),
            )
        })
        .collect()
}

/// The picture `flow_svg` draws of `snapshot` over `window` has: the body's edges within
/// 1.5 px of where `vertex(k)` puts its corners, one mark per particle in the window, one
/// spacing wide, coloured by the field, and the colour bar right of the plot.
fn check_picture(
    s: &mpsfsi::output::flow::Snapshot,
    window: [f64; 4],
    corners: &[[f64; 2]],
    spacing: f64,
) {
    let (svg, frame) = flow_svg(s, FlowField::Pressure, Some(window), "picture").unwrap();
    assert!(svg.contains("<svg"));
    // the pressure is shown as Cp because a body moves
    assert!(svg.contains("Cp = p"), "a Cp colour bar label");

    let colour = format!(
        "#{:02X}{:02X}{:02X}",
        BODY_COLOUR.0, BODY_COLOUR.1, BODY_COLOUR.2
    );
    let edges = polylines(&svg, &colour, 3);
    assert_eq!(edges.len(), corners.len(), "one polyline per body edge");
    for (k, [x, y]) in corners.iter().enumerate() {
        let (px, py) = frame.to_pixel(*x, *y);
        let near = edges
            .iter()
            .flatten()
            .any(|(qx, qy)| (qx - px).abs() <= 1.5 && (qy - py).abs() <= 1.5);
        assert!(near, "vertex {k} at pixel ({px:.1}, {py:.1}): {edges:?}");
    }

    let inside = s
        .particles
        .points
        .iter()
        .filter(|p| {
            p[0] >= window[0] && p[0] <= window[1] && p[1] >= window[2] && p[1] <= window[3]
        })
        .count();
    let marks = rects(&svg);
    let right = frame.pixels.2 as f64;
    let bar = marks.iter().filter(|r| r.0 > right + 1.0).count();
    let particles: Vec<_> = marks
        .iter()
        .filter(|r| r.0 <= right + 1.0 && r.3 != "#FFFFFF")
        .collect();
    assert_eq!(bar, BAR_STEPS, "the colour bar");
    assert_eq!(
        particles.len(),
        inside,
        "one mark per particle in the window"
    );
    let colours: std::collections::BTreeSet<&str> =
        particles.iter().map(|r| r.3.as_str()).collect();
    assert!(
        colours.len() > 20,
        "particles coloured by pressure: {} colours",
        colours.len()
    );
    // one spacing (plus the half-pixel overlap) wide; the median, as plotters clips the
    // marks at the window's edges
    let px_per_m = (frame.pixels.2 - frame.pixels.0) as f64 / (window[1] - window[0]);
    let mut widths: Vec<f64> = particles.iter().map(|r| r.2).collect();
    widths.sort_by(f64::total_cmp);
    let width = widths[widths.len() / 2];
    assert!(
        (width - spacing * px_per_m).abs() <= 2.0,
        "mark width {width} px"
    );
}

#[test]
fn the_flow_picture_shows_the_particles_a_colour_bar_and_the_body_at_its_pose() {
    let dir = scratch_dir("flow-picture");
    run(box_entry(json!({ "load_interval": 0.001 })), &dir);
    let s = read_snapshot(&dir, Some(0.03)).unwrap();
    let nearest = snapshot_times(&dir)
        .unwrap()
        .into_iter()
        .min_by(|a, b| (a - 0.03).abs().total_cmp(&(b - 0.03).abs()))
        .unwrap();
    assert_eq!(s.time, nearest, "the snapshot nearest 0.03 s");
    let corners: Vec<[f64; 2]> = (0..4).map(|k| vertex_at(k, s.time)).collect();
    check_picture(&s, [0.05, 0.35, -0.02, 0.2], &corners, 0.01);

    for field in [FlowField::Speed, FlowField::VelocityX, FlowField::VelocityY] {
        let (svg, _) = flow_svg(&s, field, None, "box").unwrap();
        assert!(svg.contains("(m/s)"));
    }
    assert!(flow_svg(&s, FlowField::Pressure, Some([1.0, 0.0, 0.0, 1.0]), "box").is_err());
}

/// The shipped 30° wedge (at 2 cm, to 6 ms): the wedge drawn where its prescribed
/// velocity has taken it.
#[test]
fn the_shipped_wedge_is_drawn_in_place() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("cases/wedge_30deg_constant_velocity.json");
    let overrides = [
        "particle_spacing=0.02".to_string(),
        "time.end=0.006".to_string(),
    ];
    let case = load_case_file(&path, &overrides).unwrap();
    let body = case.bodies[0].clone();
    let Motion::Prescribed { velocity, .. } = body.motion else {
        panic!("the shipped wedge has a prescribed motion")
    };
    let dir = scratch_dir("flow-wedge");
    let case = ValidCase::new(case, &Limits::default()).unwrap();
    let summary = run_case(&case, &dir, &mut Quiet).unwrap();
    assert_eq!(summary.status, RunStatus::Succeeded);
    let s = read_snapshot(&dir, None).unwrap();
    assert!(
        (s.time - 0.006).abs() < 1e-9,
        "the last snapshot is at the end"
    );
    // the polygon's body frame is placed at `position` with angle 0
    let corners: Vec<[f64; 2]> = body
        .polygon
        .iter()
        .map(|p| {
            [
                p[0] + body.position[0] + velocity[0] * s.time,
                p[1] + body.position[1] + velocity[1] * s.time,
            ]
        })
        .collect();
    check_picture(&s, [-0.6, 0.6, -0.5, 0.4], &corners, 0.02);

    // by default the picture is of the wedge and one breadth of water around it, not of
    // the 4 m tank: three breadths wide (B = 0.5 m) plus 2 % on each side
    let (_, frame) = flow_svg(&s, FlowField::Pressure, None, "wedge").unwrap();
    let pad = 0.02 * 1.5;
    assert!((frame.x.0 - (-0.75 - pad)).abs() < 1e-9 && (frame.x.1 - (0.75 + pad)).abs() < 1e-9);
    for [x, y] in &corners {
        assert!(frame.x.0 < *x && *x < frame.x.1 && frame.y.0 < *y && *y < frame.y.1);
    }
}

/// meshio (PyPI), a reader no one here wrote, opens a walls file and finds the box at its
/// pose. Skipped with a message when python3 or meshio is missing, unless CI is set.
#[test]
fn meshio_reads_the_bodies_at_their_pose() {
    let has_meshio = std::process::Command::new("python3")
        .args(["-c", "import meshio"])
        .status()
        .is_ok_and(|s| s.success());
    if !has_meshio {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI must run the meshio check (.ci/run installs meshio)"
        );
        eprintln!("skipped: python3 with meshio is not installed (pip install meshio)");
        return;
    }
    let dir = scratch_dir("walls-meshio");
    run(box_entry(json!({ "load_interval": 0.001 })), &dir);
    let s = read_snapshot(&dir, Some(0.03)).unwrap();
    let pvd = std::fs::read_to_string(dir.join("snapshots/run.pvd")).unwrap();
    let entry = mpsfsi::output::vtk::parse_pvd(&pvd)
        .unwrap()
        .into_iter()
        .find(|e| e.part == mpsfsi::output::vtk::WALLS_PART && e.time == s.time)
        .unwrap();
    let script = r#"
import json, sys, meshio
m = meshio.read(sys.argv[1])
lines = [c for c in m.cells if c.type == "line"]
moving = m.cell_data["moving"]
pressure = m.cell_data["pressure"]
out, p = [], []
for block, flags, values in zip(m.cells, moving, pressure):
    for cell, flag, value in zip(block.data, flags, values):
        if flag == 1:
            out.extend(m.points[i][:2].tolist() for i in cell)
            p.append(value.item())
print(json.dumps({"line_blocks": len(lines), "body_points": out, "body_pressure": p}))
"#;
    let output = std::process::Command::new("python3")
        .arg("-c")
        .arg(script)
        .arg(dir.join("snapshots").join(&entry.file))
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "meshio failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    let report: Value = serde_json::from_slice(&output.stdout).unwrap();
    assert!(report["line_blocks"].as_u64().unwrap() >= 1);
    let points = report["body_points"].as_array().unwrap();
    let pressure = report["body_pressure"].as_array().unwrap();
    assert_eq!(points.len(), 2 * pressure.len(), "line cells of two points");
    // the four edges, cut into pieces of at most l0/2: at least 2 * 0.3 m / 5 mm of them
    assert!(pressure.len() >= 60, "{} cells", pressure.len());
    // by 0.03 s the box is 1 cm into the water: its bottom is pressed
    assert!(pressure.iter().any(|p| p.as_f64().unwrap() > 0.0));
    for p in &points[..] {
        let (x, y) = (p[0].as_f64().unwrap(), p[1].as_f64().unwrap());
        let [x0, y0] = vertex_at(0, s.time);
        let [x1, y1] = vertex_at(2, s.time);
        let near = |a: f64, b: f64| (a - b).abs() < 1e-8;
        let within = |a: f64, lo: f64, hi: f64| a > lo - 1e-8 && a < hi + 1e-8;
        let side = (near(x, x0) || near(x, x1)) && within(y, y0, y1);
        let top_or_bottom = (near(y, y0) || near(y, y1)) && within(x, x0, x1);
        let on_edge = side || top_or_bottom;
        assert!(on_edge, "({x}, {y}) is on the box's outline");
    }
    for k in 0..4 {
        let [x, y] = vertex_at(k, s.time);
        assert!(
            points
                .iter()
                .any(|p| (p[0].as_f64().unwrap() - x).abs() < 1e-8
                    && (p[1].as_f64().unwrap() - y).abs() < 1e-8),
            "vertex {k} ({x}, {y}) in {points:?}"
        );
    }
}

#[test]
fn a_window_takes_its_corners_in_any_order_and_never_draws_nothing() {
    use mpsfsi::output::flow::{parse_window, WINDOW_PATTERN};
    assert_eq!(parse_window("1,0,0,2").unwrap(), [0.0, 1.0, 0.0, 2.0]);
    assert_eq!(
        parse_window(" -1, 1 ,3,-3").unwrap(),
        [-1.0, 1.0, -3.0, 3.0]
    );
    assert_eq!(parse_window("0,0,0,2").unwrap(), [-1.0, 1.0, 0.0, 2.0]);
    assert_eq!(parse_window("0,0,0,0").unwrap(), [-0.5, 0.5, -0.5, 0.5]);
    for bad in ["1,2,3", "a,b,c,d", "1,2,3,inf", ""] {
        assert!(parse_window(bad).is_err(), "{bad:?}");
    }
    // what the contract's pattern admits, parse_window accepts
    let re = regex::Regex::new(WINDOW_PATTERN).unwrap();
    for ok in ["0,0,0,0", "-999999.123456789,1,2,3", " 1 , -2,3 ,4 "] {
        assert!(re.is_match(ok) && parse_window(ok).is_ok(), "{ok:?}");
    }
}
