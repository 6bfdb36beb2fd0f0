//! `mpsfsi plot RUN_DIR [--time T] [--field F] [--window X0,X1,Y0,Y1] --out FILE.svg`

use super::{EXIT_ERROR, EXIT_REJECTED};
use mpsfsi::output::flow::{flow_svg, parse_window, read_snapshot, title, FlowField};
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
    let svg = match flow_svg(&snapshot, field, window, &title(&name, &snapshot)) {
        Ok((svg, _)) => svg,
        Err(e) => {
            eprintln!("error: {e}");
            return EXIT_ERROR;
        }
    };
    if let Err(e) = std::fs::write(out, svg) {
        eprintln!("error: cannot write {}: {e}", out.display());
        return EXIT_ERROR;
    }
    println!(
        "t = {:.6} s ({} particles) -> {}",
        snapshot.time,
        snapshot.particles.points.len(),
        out.display()
    );
    0
}
