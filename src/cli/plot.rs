//! `mpsfsi plot RUN_DIR [--time T] [--field F] [--window X0,X1,Y0,Y1] --out FILE.svg`
//! and `mpsfsi plot RUN_DIR --surface BODY [--time T] --out FILE.svg`
//! and `mpsfsi plot RUN_DIR --loads --out FILE.svg`

use super::{EXIT_ERROR, EXIT_REJECTED};
use mpsfsi::output::flow::{flow_svg, parse_window, read_snapshot, title, FlowField};
use mpsfsi::output::surface::{surface_svg, surface_title, Objects};
use std::path::Path;

pub fn plot(
    run_dir: &Path,
    time: Option<f64>,
    field: &str,
    window: Option<&str>,
    out: &Path,
) -> i32 {
    let field = match FlowField::parse(field) {
        Ok(field) => field,
        Err(e) => {
            eprintln!("error: --field {e}");
            return EXIT_REJECTED;
        }
    };
    let window = match window.map(parse_window).transpose() {
        Ok(w) => w,
        Err(e) => {
            eprintln!("error: --window: {e}");
            return EXIT_REJECTED;
        }
    };
    let snapshot = match read_snapshot(run_dir, time) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {}: {e}", run_dir.display());
            return EXIT_ERROR;
        }
    };
    let name = run_dir
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let svg = flow_svg(&snapshot, field, window, &title(&name, &snapshot)).map(|(svg, _)| svg);
    let what = format!("{} particles", snapshot.particles.points.len());
    write_svg(svg, out, snapshot.time, &what)
}

/// Write a drawn picture to `out` and say what it shows; the exit code.
fn write_svg<E: std::fmt::Display>(
    svg: Result<String, E>,
    out: &Path,
    time: f64,
    what: &str,
) -> i32 {
    let svg = match svg {
        Ok(svg) => svg,
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_ERROR;
        }
    };
    if let Err(e) = std::fs::write(out, svg) {
        eprintln!("error: cannot write {}: {e}", out.display());
        return EXIT_ERROR;
    }
    println!("t = {time:.6} s ({what}) -> {}", out.display());
    0
}

/// The pressure along `body`'s surface at the snapshot nearest `time`.
pub fn plot_surface(run_dir: &Path, time: Option<f64>, body: &str, out: &Path) -> i32 {
    let objects = match Objects::of_run(run_dir) {
        Ok(objects) => objects,
        Err(e) => {
            eprintln!("error: {}: {e}", run_dir.display());
            return EXIT_ERROR;
        }
    };
    // an unknown name is told first, unless the run names nothing yet
    let found = objects.find(body);
    if let (Err(e), false) = (&found, objects.0.is_empty()) {
        eprintln!("error: --surface: {e}");
        return EXIT_REJECTED;
    }
    let snapshot = match read_snapshot(run_dir, time) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {}: {e}", run_dir.display());
            return EXIT_ERROR;
        }
    };
    let object = match found {
        Ok(k) => k,
        Err(e) => {
            eprintln!("error: --surface: {e}");
            return EXIT_REJECTED;
        }
    };
    // the case's name from the summary of a run that has ended, else the directory's
    let name = std::fs::read_to_string(run_dir.join("summary.json"))
        .ok()
        .and_then(|text| serde_json::from_str::<serde_json::Value>(&text).ok())
        .and_then(|summary| summary["case"].as_str().map(str::to_string))
        .or_else(|| {
            run_dir
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
        })
        .unwrap_or_default();
    let svg = surface_svg(&snapshot, object, &surface_title(&name, body, &snapshot));
    write_svg(svg, out, snapshot.time, &format!("the surface of {body}"))
}

/// The load history of `loads.csv`, with the band of `loads_uncertainty.csv` when the
/// run has one.
pub fn plot_loads(run_dir: &Path, out: &Path) -> i32 {
    let read = |name: &str| std::fs::read_to_string(run_dir.join(name));
    let loads = match read("loads.csv") {
        Ok(text) => text,
        Err(e) => {
            eprintln!("error: {}: loads.csv: {e}", run_dir.display());
            return EXIT_ERROR;
        }
    };
    let band = read("loads_uncertainty.csv").ok();
    let name = run_dir
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let title = format!(
        "{name}: loads{}",
        if band.is_some() { " (95 % band)" } else { "" }
    );
    let svg = mpsfsi::output::plot::loads_svg_with_band(&loads, band.as_deref(), &title);
    let rows = loads.lines().count().saturating_sub(1);
    let end = loads
        .lines()
        .last()
        .and_then(|l| l.split(',').next())
        .and_then(|t| t.parse().ok())
        .unwrap_or(0.0);
    write_svg(svg, out, end, &format!("{rows} rows"))
}
