//! The surface pressure in the walls files and its picture: a box held still in a tank
//! of still water reads ρ g (depth) along its faces (hydrostatics), the pieces integrate
//! to the load loads.csv holds for that step (F = -∫ p n ds, the integral's invariant),
//! and `surface_svg` draws one line per face with the vertices marked.

use crate::scratch_dir;
use mpsfsi::case::{parse_case_value, Limits, ValidCase};
use mpsfsi::output::flow::read_snapshot;
use mpsfsi::output::surface::{surface_svg, Objects, VERTEX_COLOUR};
use mpsfsi::run::{run_case, Quiet, RunStatus};
use serde_json::{json, Value};
use std::path::Path;

const RHO: f64 = 1000.0;
const G: f64 = 9.81;
/// The still water's free surface (the top of the fluid block).
const SURFACE: f64 = 0.3;

/// A 0.6 m x 0.3 m tank of still water with a 0.2 m x 0.1 m box (counter-clockwise)
/// held 0.1 m below the surface, moving at `velocity`; no viscosity, so the load is the
/// pressure integral alone; a load row every step and a snapshot every 0.05 s.
fn still_box(velocity: [f64; 2]) -> Value {
    json!({
        "name": "still-box",
        "fluid": { "density": RHO, "kinematic_viscosity": 0.0, "gravity": [0.0, -G] },
        "particle_spacing": 0.01,
        "domain": { "min": [-0.05, -0.05], "max": [0.65, 0.5] },
        "fluid_blocks": [ { "polygon": [[0.0, 0.0], [0.6, 0.0], [0.6, SURFACE], [0.0, SURFACE]] } ],
        "walls": [ { "name": "tank", "polyline": [[0.0, 0.45], [0.0, 0.0], [0.6, 0.0], [0.6, 0.45]] } ],
        "bodies": [ {
            "name": "box",
            "polygon": [[-0.1, 0.0], [0.1, 0.0], [0.1, 0.1], [-0.1, 0.1]],
            "position": [0.3, 0.1],
            "motion": { "type": "prescribed", "velocity": velocity }
        } ],
        "time": { "end": 0.1, "max_dt": 0.001 },
        "output": { "load_interval": null, "snapshot_interval": 0.05 },
        "scheme": { "wall_load": "pressure_integral" }
    })
}

fn run(case: Value, dir: &Path) {
    let case = ValidCase::new(parse_case_value(case).unwrap(), &Limits::default()).unwrap();
    let summary = run_case(&case, dir, &mut Quiet).unwrap();
    assert_eq!(summary.status, RunStatus::Succeeded, "{:?}", summary.reason);
}

/// The row of `file` (a `time,name,...` CSV of the run) for `name` at `time`, as numbers
/// after the name.
fn row_at(dir: &Path, file: &str, name: &str, time: f64) -> Vec<f64> {
    let text = std::fs::read_to_string(dir.join(file)).unwrap();
    text.lines()
        .skip(1)
        .map(|l| l.split(',').collect::<Vec<_>>())
        .find(|r| r[1] == name && (r[0].parse::<f64>().unwrap() - time).abs() < 1e-9)
        .unwrap_or_else(|| panic!("no {file} row of {name} at {time}"))[2..]
        .iter()
        .map(|v| v.parse().unwrap())
        .collect()
}

/// Hydrostatics: at the last snapshot (t = 0.1 s) every piece of the box reads
/// ρ g (depth) at its centre within 1 %, and so does every piece of the tank deeper
/// than 2 l0; the tank's pieces 5 l0 above the water read 0 (measured: within 0.08 %).
/// The integral's invariant: the pieces of each object, p × length along the normal into
/// the fluid, sum to the force loads.csv holds for that step and their moment about the
/// box's centre of mass (bodies.csv) to its moment, within 1e-6 of |F| (and |F| × 0.2 m).
#[test]
fn the_pieces_read_hydrostatics_and_integrate_to_the_load() {
    let dir = scratch_dir("surface-still-box");
    run(still_box([0.0, 0.0]), &dir);
    let s = read_snapshot(&dir, None).unwrap();
    assert!(
        (s.time - 0.1).abs() < 1e-9,
        "the last snapshot, at {}",
        s.time
    );
    let walls = s.walls.as_ref().unwrap();
    let object = walls.cell_scalar("object").unwrap();
    let pressure = walls.cell_scalar("pressure").unwrap();
    let objects = Objects::of_run(&dir).unwrap();
    assert_eq!(
        objects.0,
        [("tank".to_string(), false), ("box".to_string(), true)]
    );
    let com = row_at(&dir, "bodies.csv", "box", s.time);
    let (cx, cy) = (com[0], com[1]);
    for (k, name) in ["tank", "box"].iter().enumerate() {
        let (mut f, mut mz, mut pieces) = ([0.0f64; 2], 0.0, 0);
        for c in (0..walls.cells).filter(|&c| object[c] == k as f64) {
            let [a, b] = [0, 1].map(|e| walls.points[walls.cell(c)[e]]);
            let mid = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let length = dx.hypot(dy);
            // into the fluid: out of the counter-clockwise box, into the tank
            let mut n = [dy / length, -dx / length];
            if *name == "tank" && n[0] * (0.3 - mid[0]) + n[1] * (SURFACE - mid[1]) < 0.0 {
                n = [-n[0], -n[1]];
            }
            let p = pressure[c];
            let depth = SURFACE - mid[1];
            let exact = RHO * G * depth;
            if *name == "box" || depth > 0.02 {
                assert!(
                    (p - exact).abs() <= 0.01 * exact,
                    "{name} piece at ({:.4}, {:.4}): {p:.1} Pa, ρ g d = {exact:.1} Pa",
                    mid[0],
                    mid[1]
                );
            } else if depth < -0.05 {
                assert_eq!(p, 0.0, "{name} above the water at y = {:.3}", mid[1]);
            }
            let df = [-p * length * n[0], -p * length * n[1]];
            f = [f[0] + df[0], f[1] + df[1]];
            mz += (mid[0] - cx) * df[1] - (mid[1] - cy) * df[0];
            pieces += 1;
        }
        assert!(pieces > 40, "{name}: {pieces} pieces");
        let load = row_at(&dir, "loads.csv", name, s.time);
        let size = load[0].hypot(load[1]);
        assert!(size > 100.0, "{name}: a load to compare with: {load:?}");
        for (axis, (sum, written)) in ["fx", "fy"].iter().zip(f.iter().zip(&load)) {
            assert!(
                (sum - written).abs() <= 1e-6 * size,
                "{name} {axis}: pieces {sum} N/m, loads.csv {written} N/m"
            );
        }
        if *name == "box" {
            assert!(
                (mz - load[2]).abs() <= 1e-6 * size * 0.2,
                "box mz: pieces {mz} N m/m, loads.csv {}",
                load[2]
            );
        }
    }
}

/// The `<polyline>`s of `svg` with stroke width `width` (and colour `colour`, if given).
fn polylines(svg: &str, width: u32, colour: Option<&str>) -> usize {
    svg.split("<polyline")
        .skip(1)
        .map(|e| &e[..e.find("/>").unwrap()])
        .filter(|e| e.contains(&format!("stroke-width=\"{width}\"")))
        .filter(|e| colour.is_none_or(|c| e.contains(&format!("stroke=\"{c}\""))))
        .count()
}

/// The picture of the box: one line per face, five vertex marks (0 to 4, the last
/// closing the polygon), p in kPa for the box held still and Cp for the box moving.
#[test]
fn the_surface_picture_draws_each_face_and_marks_the_vertices() {
    let vertex = format!(
        "#{:02X}{:02X}{:02X}",
        VERTEX_COLOUR.0, VERTEX_COLOUR.1, VERTEX_COLOUR.2
    );
    for (velocity, label) in [
        ([0.0, 0.0], "p (kPa)"),
        ([0.1, 0.0], "Cp = p / (½ρV²), V = 0.100 m/s"),
    ] {
        let dir = scratch_dir("surface-picture");
        run(still_box(velocity), &dir);
        let s = read_snapshot(&dir, None).unwrap();
        let svg = surface_svg(&s, 1, "still box").unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("still box"));
        assert!(svg.contains(label), "{label:?} missing");
        assert!(svg.contains("along the surface from vertex 0 (m)"));
        assert_eq!(polylines(&svg, 2, None), 4, "one line per face");
        assert_eq!(polylines(&svg, 1, Some(&vertex)), 5, "the vertex marks");
        // the tank (object 0) does not move: kPa
        let tank = surface_svg(&s, 0, "tank").unwrap();
        assert!(tank.contains("p (kPa)"));
        assert_eq!(polylines(&tank, 2, None), 3, "one line per wall");
        assert!(surface_svg(&s, 2, "nothing").is_err(), "no third object");
    }
}

#[test]
fn an_unknown_name_is_told_with_the_bodies_and_walls() {
    let objects = Objects(vec![
        ("tank".into(), false),
        ("wedge".into(), true),
        ("float".into(), true),
    ]);
    assert_eq!(objects.find("float"), Ok(2));
    let message = objects.find("hull").unwrap_err();
    assert!(
        message.contains("\"hull\"") && message.contains("bodies: wedge, float; walls: tank"),
        "{message}"
    );
    assert!(Objects::default().find("hull").is_err());
}
