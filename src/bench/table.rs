//! Cell formatting shared by the CSV and Markdown tables of every study.

use crate::math::Real;

/// A CSV field, quoted (with doubled quotes) when it holds a comma, quote or newline.
pub fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// A number in a CSV cell with `decimals` decimals; `NaN` when not finite.
pub fn csv_num(x: f64, decimals: usize) -> String {
    if x.is_finite() {
        format!("{x:.decimals$}")
    } else {
        "NaN".into()
    }
}

/// A number in a Markdown cell with `decimals` decimals; a dash when not finite.
pub fn md_num(x: f64, decimals: usize) -> String {
    if x.is_finite() {
        format!("{x:.decimals$}")
    } else {
        "—".into()
    }
}

/// A relative error in a Markdown cell as a percentage with two decimals; a dash when
/// not finite.
pub fn md_percent(e: Real) -> String {
    if e.is_finite() {
        format!("{:.2}%", 100.0 * e)
    } else {
        "—".into()
    }
}

/// Text in a Markdown cell: a `|` would end the cell, so it becomes `/`.
pub fn md_text(s: &str) -> String {
    s.replace('|', "/")
}
