//! VTK XML files, ASCII: one UnstructuredGrid (`.vtu`) per snapshot with the particles
//! as vertex cells, and a ParaView collection (`.pvd`) indexing them by time.
//!
//! The writer takes plain slices, so tests and tools can write grids without a
//! simulation; the reader understands what the writer writes (and any ASCII `.vtu`
//! whose `DataArray`s are inline ASCII), which is what the benchmark uses to measure
//! the dam-break surge front from the snapshots.

use crate::math::{Real, Vec2};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::io;

/// The particle fields of one snapshot.
pub struct VtuFields<'a> {
    pub position: &'a [Vec2],
    pub velocity: &'a [Vec2],
    pub pressure: &'a [Real],
    pub number_density: &'a [Real],
    /// n0, to write n/n0 next to n; None leaves it out.
    pub n0: Option<Real>,
    pub free_surface: &'a [bool],
}

fn push_scalars(out: &mut String, name: &str, kind: &str, values: impl Iterator<Item = String>) {
    let _ = writeln!(
        out,
        "        <DataArray type=\"{kind}\" Name=\"{name}\" format=\"ascii\">"
    );
    push_wrapped(out, values);
    out.push_str("        </DataArray>\n");
}

fn push_wrapped(out: &mut String, values: impl Iterator<Item = String>) {
    let mut on_line = 0;
    for v in values {
        if on_line == 0 {
            out.push_str("          ");
        } else {
            out.push(' ');
        }
        out.push_str(&v);
        on_line += 1;
        if on_line == 8 {
            out.push('\n');
            on_line = 0;
        }
    }
    if on_line > 0 {
        out.push('\n');
    }
}

/// The text of a `.vtu` file with the particles as vertices (z = 0) and the fields as
/// point data (`velocity` as a 3-vector with vz = 0).
pub fn vtu_string(fields: &VtuFields<'_>, time: Real) -> String {
    let n = fields.position.len();
    assert!(
        fields.velocity.len() == n
            && fields.pressure.len() == n
            && fields.number_density.len() == n
            && fields.free_surface.len() == n,
        "all particle fields have one value per particle"
    );
    let mut out = String::with_capacity(200 + n * 160);
    out.push_str("<?xml version=\"1.0\"?>\n");
    out.push_str("<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n");
    out.push_str("  <UnstructuredGrid>\n");
    // TimeValue as field data lets ParaView show the time of a lone file.
    out.push_str("    <FieldData>\n");
    let _ = writeln!(
        out,
        "      <DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">{time:.12e}</DataArray>"
    );
    out.push_str("    </FieldData>\n");
    let _ = writeln!(
        out,
        "    <Piece NumberOfPoints=\"{n}\" NumberOfCells=\"{n}\">"
    );
    out.push_str("      <PointData Scalars=\"pressure\" Vectors=\"velocity\">\n");
    let _ = writeln!(out, "        <DataArray type=\"Float64\" Name=\"velocity\" NumberOfComponents=\"3\" format=\"ascii\">");
    push_wrapped(
        &mut out,
        fields.velocity.iter().flat_map(|v| {
            [
                format!("{:.9e}", v.x),
                format!("{:.9e}", v.y),
                "0".to_string(),
            ]
        }),
    );
    out.push_str("        </DataArray>\n");
    push_scalars(
        &mut out,
        "pressure",
        "Float64",
        fields.pressure.iter().map(|p| format!("{p:.9e}")),
    );
    push_scalars(
        &mut out,
        "number_density",
        "Float64",
        fields.number_density.iter().map(|v| format!("{v:.9e}")),
    );
    if let Some(n0) = fields.n0.filter(|n0| *n0 > 0.0) {
        push_scalars(
            &mut out,
            "number_density_ratio",
            "Float64",
            fields
                .number_density
                .iter()
                .map(|v| format!("{:.9e}", v / n0)),
        );
    }
    push_scalars(
        &mut out,
        "free_surface",
        "UInt8",
        fields.free_surface.iter().map(|f| u8::from(*f).to_string()),
    );
    out.push_str("      </PointData>\n");
    out.push_str("      <Points>\n");
    out.push_str("        <DataArray type=\"Float64\" Name=\"position\" NumberOfComponents=\"3\" format=\"ascii\">\n");
    push_wrapped(
        &mut out,
        fields.position.iter().flat_map(|p| {
            [
                format!("{:.9e}", p.x),
                format!("{:.9e}", p.y),
                "0".to_string(),
            ]
        }),
    );
    out.push_str("        </DataArray>\n");
    out.push_str("      </Points>\n");
    out.push_str("      <Cells>\n");
    out.push_str("        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n");
    push_wrapped(&mut out, (0..n).map(|i| i.to_string()));
    out.push_str("        </DataArray>\n");
    out.push_str("        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n");
    push_wrapped(&mut out, (1..=n).map(|i| i.to_string()));
    out.push_str("        </DataArray>\n");
    // VTK_VERTEX = 1
    out.push_str("        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n");
    push_wrapped(&mut out, (0..n).map(|_| "1".to_string()));
    out.push_str("        </DataArray>\n");
    out.push_str("      </Cells>\n");
    out.push_str("    </Piece>\n");
    out.push_str("  </UnstructuredGrid>\n");
    out.push_str("</VTKFile>\n");
    out
}

/// One entry of a `.pvd` collection.
#[derive(Debug, Clone, PartialEq)]
pub struct PvdEntry {
    pub time: Real,
    /// Path of the `.vtu`, relative to the `.pvd`.
    pub file: String,
}

/// The text of a `.pvd` collection listing `entries` in order.
pub fn pvd_string(entries: &[PvdEntry]) -> String {
    let mut out = String::new();
    out.push_str("<?xml version=\"1.0\"?>\n");
    out.push_str("<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n");
    out.push_str("  <Collection>\n");
    for e in entries {
        let _ = writeln!(
            out,
            "    <DataSet timestep=\"{:.12e}\" group=\"\" part=\"0\" file=\"{}\"/>",
            e.time,
            xml_escape(&e.file)
        );
    }
    out.push_str("  </Collection>\n");
    out.push_str("</VTKFile>\n");
    out
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('"', "&quot;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

fn xml_unescape(s: &str) -> String {
    s.replace("&quot;", "\"")
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&amp;", "&")
}

fn bad(message: impl Into<String>) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidData, message.into())
}

/// An XML start tag: its name, attributes, and whether it closes itself (`<a/>`).
#[derive(Debug, Clone)]
struct Tag {
    attributes: BTreeMap<String, String>,
    self_closing: bool,
    /// Byte offset just after the tag's `>`.
    end: usize,
}

/// The next start tag named `name` at or after byte `from` (a minimal scanner for
/// the files written here: no CDATA, attributes in double quotes).
fn next_tag(text: &str, name: &str, from: usize) -> io::Result<Option<Tag>> {
    let mut at = from;
    let pattern = format!("<{name}");
    while let Some(rel) = text[at..].find(&pattern) {
        let start = at + rel;
        let after = start + pattern.len();
        let next = text[after..].chars().next();
        if !matches!(next, Some(c) if c.is_whitespace() || c == '>' || c == '/') {
            at = after;
            continue;
        }
        let close = text[after..]
            .find('>')
            .ok_or_else(|| bad(format!("unterminated <{name}> tag")))?
            + after;
        let inner = &text[after..close];
        let self_closing = inner.trim_end().ends_with('/');
        let inner = inner.trim_end().trim_end_matches('/');
        let mut attributes = BTreeMap::new();
        let mut rest = inner.trim_start();
        while !rest.is_empty() {
            let eq = rest
                .find('=')
                .ok_or_else(|| bad(format!("malformed attribute in <{name}>: {rest}")))?;
            let key = rest[..eq].trim().to_string();
            let after_eq = rest[eq + 1..].trim_start();
            let quoted = after_eq
                .strip_prefix('"')
                .ok_or_else(|| bad(format!("unquoted attribute {key} in <{name}>")))?;
            let end_q = quoted
                .find('"')
                .ok_or_else(|| bad(format!("unterminated attribute {key} in <{name}>")))?;
            attributes.insert(key, xml_unescape(&quoted[..end_q]));
            rest = quoted[end_q + 1..].trim_start();
        }
        return Ok(Some(Tag {
            attributes,
            self_closing,
            end: close + 1,
        }));
    }
    Ok(None)
}

/// The `.pvd` entries in file order.
pub fn parse_pvd(text: &str) -> io::Result<Vec<PvdEntry>> {
    if next_tag(text, "VTKFile", 0)?
        .and_then(|t| t.attributes.get("type").cloned())
        .as_deref()
        != Some("Collection")
    {
        return Err(bad("not a VTK Collection file"));
    }
    if !text.trim_end().ends_with("</VTKFile>") {
        return Err(bad("the collection is not closed by </VTKFile>"));
    }
    let mut entries = Vec::new();
    let mut at = 0;
    while let Some(tag) = next_tag(text, "DataSet", at)? {
        let time = tag
            .attributes
            .get("timestep")
            .ok_or_else(|| bad("DataSet without timestep"))?
            .parse::<Real>()
            .map_err(|e| bad(format!("timestep: {e}")))?;
        let file = tag
            .attributes
            .get("file")
            .ok_or_else(|| bad("DataSet without file"))?
            .clone();
        entries.push(PvdEntry { time, file });
        at = tag.end;
    }
    Ok(entries)
}

/// A `.vtu` read back: points and named point-data arrays.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct VtuData {
    pub time: Option<Real>,
    pub points: Vec<[Real; 3]>,
    pub cells: usize,
    /// Name -> (components, values flattened).
    pub point_data: BTreeMap<String, (usize, Vec<Real>)>,
}

impl VtuData {
    /// A scalar point-data array by name.
    pub fn scalar(&self, name: &str) -> Option<&[Real]> {
        self.point_data
            .get(name)
            .filter(|(c, _)| *c == 1)
            .map(|(_, v)| v.as_slice())
    }
}

/// The body of a `<DataArray ...>` whose start tag ends at `tag.end`, parsed as numbers.
fn data_array_values(text: &str, tag: &Tag) -> io::Result<Vec<Real>> {
    if tag.self_closing {
        return Ok(Vec::new());
    }
    if tag.attributes.get("format").map(String::as_str) != Some("ascii") {
        return Err(bad("only ASCII DataArrays are read"));
    }
    let close = text[tag.end..]
        .find("</DataArray>")
        .ok_or_else(|| bad("unterminated DataArray"))?
        + tag.end;
    text[tag.end..close]
        .split_ascii_whitespace()
        .map(|s| {
            s.parse::<Real>()
                .map_err(|e| bad(format!("DataArray value {s:?}: {e}")))
        })
        .collect()
}

/// Parse an ASCII `.vtu` (one piece) and check its counts are consistent.
pub fn parse_vtu(text: &str) -> io::Result<VtuData> {
    let root = next_tag(text, "VTKFile", 0)?.ok_or_else(|| bad("no <VTKFile>"))?;
    if root.attributes.get("type").map(String::as_str) != Some("UnstructuredGrid") {
        return Err(bad("not an UnstructuredGrid file"));
    }
    if !text.trim_end().ends_with("</VTKFile>") {
        return Err(bad("the file is not closed by </VTKFile>"));
    }
    let piece = next_tag(text, "Piece", root.end)?.ok_or_else(|| bad("no <Piece>"))?;
    let count = |key: &str| -> io::Result<usize> {
        piece
            .attributes
            .get(key)
            .ok_or_else(|| bad(format!("Piece without {key}")))?
            .parse()
            .map_err(|e| bad(format!("{key}: {e}")))
    };
    let n = count("NumberOfPoints")?;
    let cells = count("NumberOfCells")?;
    let mut data = VtuData {
        cells,
        ..Default::default()
    };
    // time from FieldData
    let mut at = root.end;
    while let Some(tag) = next_tag(text, "DataArray", at)? {
        if tag.end > piece.end {
            break;
        }
        if tag.attributes.get("Name").map(String::as_str) == Some("TimeValue") {
            data.time = data_array_values(text, &tag)?.first().copied();
        }
        at = tag.end;
    }
    let section = |name: &str| -> io::Result<Option<(usize, usize)>> {
        let Some(open) = next_tag(text, name, piece.end)? else {
            return Ok(None);
        };
        let close = text[open.end..]
            .find(&format!("</{name}>"))
            .ok_or_else(|| bad(format!("unterminated <{name}>")))?
            + open.end;
        Ok(Some((open.end, close)))
    };
    if let Some((start, end)) = section("Points")? {
        let tag = next_tag(text, "DataArray", start)?
            .filter(|t| t.end <= end)
            .ok_or_else(|| bad("Points without DataArray"))?;
        let values = data_array_values(text, &tag)?;
        if values.len() != 3 * n {
            return Err(bad(format!(
                "{} point coordinates for {n} points",
                values.len()
            )));
        }
        data.points = values.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    } else {
        return Err(bad("no <Points>"));
    }
    if let Some((start, end)) = section("PointData")? {
        let mut at = start;
        while let Some(tag) = next_tag(text, "DataArray", at)?.filter(|t| t.end <= end) {
            let name = tag
                .attributes
                .get("Name")
                .cloned()
                .ok_or_else(|| bad("point DataArray without Name"))?;
            let components: usize = tag
                .attributes
                .get("NumberOfComponents")
                .map(|c| c.parse().map_err(|e| bad(format!("{e}"))))
                .transpose()?
                .unwrap_or(1);
            let values = data_array_values(text, &tag)?;
            if values.len() != components * n {
                return Err(bad(format!(
                    "point data {name}: {} values for {n} points x {components}",
                    values.len()
                )));
            }
            data.point_data.insert(name, (components, values));
            at = tag.end;
        }
    }
    if let Some((start, end)) = section("Cells")? {
        let mut at = start;
        while let Some(tag) = next_tag(text, "DataArray", at)?.filter(|t| t.end <= end) {
            let len = data_array_values(text, &tag)?.len();
            let name = tag.attributes.get("Name").cloned().unwrap_or_default();
            if matches!(name.as_str(), "offsets" | "types") && len != cells {
                return Err(bad(format!(
                    "cell array {name}: {len} values for {cells} cells"
                )));
            }
            at = tag.end;
        }
    }
    Ok(data)
}
