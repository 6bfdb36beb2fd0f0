//! Reading `loads.csv` (header [`LOADS_HEADER`], rows written by [`super::RunWriter`]):
//! the one reader behind the filter, the plot, the service's `loads.svg` and the bench.
//! It is strict (a wrong header or a number that does not parse is an error); a file a
//! running job is still appending to is read up to its last newline by the caller.

use super::LOADS_HEADER;
use crate::math::Real;
use std::io;

/// One row of `loads.csv`.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadRow {
    pub time: Real,
    pub body: String,
    pub fx: Real,
    pub fy: Real,
    pub mz: Real,
}

fn invalid(message: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidData, message)
}

/// Parse the text of `loads.csv` (header `time,body,fx,fy,mz`).
pub fn parse_loads_csv(text: &str) -> io::Result<Vec<LoadRow>> {
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .from_reader(text.as_bytes());
    let headers = reader
        .headers()
        .map_err(|e| invalid(format!("loads.csv header: {e}")))?
        .clone();
    let expected: Vec<&str> = LOADS_HEADER.split(',').collect();
    if headers.iter().collect::<Vec<_>>() != expected {
        return Err(invalid(format!(
            "loads.csv header is {:?}, expected {}",
            headers, LOADS_HEADER
        )));
    }
    let mut rows = Vec::new();
    for (line, record) in reader.records().enumerate() {
        let record = record.map_err(|e| invalid(format!("loads.csv row {}: {e}", line + 2)))?;
        let num = |i: usize| -> io::Result<Real> {
            record[i].trim().parse().map_err(|e| {
                invalid(format!(
                    "loads.csv row {} column {}: {e}",
                    line + 2,
                    expected[i]
                ))
            })
        };
        rows.push(LoadRow {
            time: num(0)?,
            body: record[1].to_string(),
            fx: num(2)?,
            fy: num(3)?,
            mz: num(4)?,
        });
    }
    Ok(rows)
}
