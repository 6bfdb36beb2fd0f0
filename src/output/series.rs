//! Time series of a run directory's CSV files as JSON columns:
//! `{ "<name>": { "time": [...], "<column>": [...] } }`, where the second CSV column
//! (`body` or `probe`) names the series. Only complete lines are read, so a file that a
//! running job is appending to gives what exists so far. The service serves these
//! columns and the benchmark scores them.

use serde_json::{Map, Value};

/// The complete lines of `text` (up to and including the last newline).
pub fn complete_lines(text: &[u8]) -> &[u8] {
    match text.iter().rposition(|b| *b == b'\n') {
        Some(end) => &text[..=end],
        None => &[],
    }
}

/// Parse CSV text (header first) into columns per series name, in order of appearance.
pub fn csv_to_columns(text: &[u8]) -> Result<Map<String, Value>, csv::Error> {
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .from_reader(complete_lines(text));
    let headers: Vec<String> = reader.headers()?.iter().map(str::to_string).collect();
    let mut out = Map::new();
    if headers.len() < 2 {
        return Ok(out);
    }
    for record in reader.records() {
        let record = record?;
        let name = record.get(1).unwrap_or("").to_string();
        let series = out.entry(name).or_insert_with(|| {
            let mut m = Map::new();
            for (k, h) in headers.iter().enumerate() {
                if k != 1 {
                    m.insert(h.clone(), Value::Array(Vec::new()));
                }
            }
            Value::Object(m)
        });
        let Value::Object(series) = series else {
            continue;
        };
        for (k, h) in headers.iter().enumerate() {
            if k == 1 {
                continue;
            }
            let v = record.get(k).and_then(|s| s.trim().parse::<f64>().ok());
            let v = v
                .and_then(serde_json::Number::from_f64)
                .map(Value::Number)
                .unwrap_or(Value::Null);
            if let Some(Value::Array(column)) = series.get_mut(h) {
                column.push(v);
            }
        }
    }
    Ok(out)
}
