//! scripts/check-layout, which CI runs, rejects what it exists to reject: here the
//! benchmark importing the service (two independent Cargo features), planted in a copy
//! of the source tree.

use std::path::{Path, PathBuf};
use std::process::Command;

fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let target = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            copy_tree(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), &target).unwrap();
        }
    }
}

/// Run check-layout on a copy of the tree it reads (sources, scripts, docs, schema, cases,
/// README) with `plant` appended to `file` (relative to src/); returns its exit code and
/// output.
fn check_planted(file: &str, plant: &str) -> (i32, String) {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let tag = file.replace('/', "-") + &plant.len().to_string();
    let copy = std::env::temp_dir().join(format!("mpsfsi-layout-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&copy);
    for dir in ["src", "scripts", "docs", "api", "cases"] {
        copy_tree(&root.join(dir), &copy.join(dir));
    }
    std::fs::copy(root.join("README.md"), copy.join("README.md")).unwrap();
    let planted = copy.join("src").join(file);
    let mut text = std::fs::read_to_string(&planted).unwrap();
    text.push_str(plant);
    std::fs::write(&planted, text).unwrap();
    let out = Command::new("python3")
        .arg(copy.join("scripts/check-layout"))
        .output()
        .expect("python3 runs scripts/check-layout");
    std::fs::remove_dir_all(&copy).unwrap();
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    (out.status.code().unwrap_or(-1), text)
}

#[test]
fn check_layout_rejects_a_bench_to_service_import() {
    let (code, out) = check_planted(
        "bench/table.rs",
        "\nuse crate::service::series::SeriesFile;\n",
    );
    assert_eq!(code, 1, "check-layout accepted the planted import:\n{out}");
    assert!(
        out.contains("forbidden: bench/table.rs (bench) imports service/series.rs (service)"),
        "{out}"
    );
}

#[test]
fn check_layout_accepts_the_tree_as_it_is() {
    let (code, out) = check_planted("bench/table.rs", "");
    assert_eq!(code, 0, "check-layout rejects the unplanted copy:\n{out}");
}
