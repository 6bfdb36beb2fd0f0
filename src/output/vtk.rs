//! VTK XML files with inline binary (base64) arrays: per snapshot one UnstructuredGrid (`.vtu`) with the particles
//! as vertex cells and one with the walls and bodies as line cells at their pose, each
//! cell carrying the surface pressure on it, and a ParaView collection (`.pvd`) indexing
//! both by time (parts 0 and 1).
//!
//! The writer takes plain slices, so tests and tools can write grids without a
//! simulation; the reader understands what the writer writes (and any `.vtu` whose
//! `DataArray`s are inline, ASCII or binary with a UInt64 header, uncompressed), which
//! is what the flow and surface pictures and the benchmark's dam-break surge front read.

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
    /// Fluid density (kg/m³) and particle spacing (m), written as field data so that a
    /// snapshot alone can be drawn (marker size, pressure coefficient).
    pub density: Option<Real>,
    pub spacing: Option<Real>,
    /// Each particle's spacing (m) of a multi-resolution layout, written as the point
    /// array `spacing`; None for one spacing (the field data's `particle_spacing`).
    pub particle_spacing: Option<Vec<Real>>,
}

/// The surface of one wall or body at its pose, for the walls grid: its surface
/// segments cut into line cells, in the order of the segments and along each.
pub struct Outline {
    /// Line cells facing the fluid, world frame.
    pub cells: Vec<[Vec2; 2]>,
    /// Velocity of each cell's end points (rigid motion), one pair per cell.
    pub velocities: Vec<[Vec2; 2]>,
    /// Index of each cell's surface segment in the object (segments in the order of the
    /// body polygon's or wall polyline's vertices).
    pub segment: Vec<u32>,
    /// Pressure on each cell (Pa).
    pub pressure: Vec<Real>,
    /// A body (moving or free) rather than a fixed wall.
    pub moving: bool,
    /// Speed of the object's centre of mass (m/s).
    pub speed: Real,
}

/// A value type of a `DataArray`: its VTK name and its little-endian bytes.
trait VtkValue: Copy {
    const TYPE: &'static str;
    fn put(self, bytes: &mut Vec<u8>);
}

macro_rules! vtk_value {
    ($t:ty, $name:literal) => {
        impl VtkValue for $t {
            const TYPE: &'static str = $name;
            fn put(self, bytes: &mut Vec<u8>) {
                bytes.extend_from_slice(&self.to_le_bytes());
            }
        }
    };
}
vtk_value!(f64, "Float64");
vtk_value!(i64, "Int64");
vtk_value!(i32, "Int32");
vtk_value!(u8, "UInt8");

fn push_scalars<T: VtkValue>(out: &mut String, name: &str, values: impl Iterator<Item = T>) {
    push_array(out, name, 1, values);
}

/// One `DataArray` in VTK's inline binary form: base64 of a UInt64 byte count followed
/// by the raw values. Printing 200 000 particles' values as text cost the 30° wedge's
/// default job 12 % of its run time for ten snapshots; this costs a copy.
fn push_array<T: VtkValue>(
    out: &mut String,
    name: &str,
    components: usize,
    values: impl Iterator<Item = T>,
) {
    use base64::Engine as _;
    let _ = write!(
        out,
        "        <DataArray type=\"{}\" Name=\"{name}\" NumberOfComponents=\"{components}\" format=\"binary\">\n          ",
        T::TYPE
    );
    let mut bytes = vec![0u8; 8];
    for v in values {
        v.put(&mut bytes);
    }
    let count = (bytes.len() - 8) as u64;
    bytes[..8].copy_from_slice(&count.to_le_bytes());
    base64::engine::general_purpose::STANDARD.encode_string(&bytes, out);
    out.push_str("\n        </DataArray>\n");
}

/// The start of a `.vtu` file up to its `<Piece>`: time and `extra` as field data.
fn push_header(out: &mut String, time: Real, extra: &[(&str, Real)], points: usize, cells: usize) {
    out.push_str("<?xml version=\"1.0\"?>\n");
    out.push_str("<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n");
    out.push_str("  <UnstructuredGrid>\n");
    // TimeValue as field data lets ParaView show the time of a lone file.
    out.push_str("    <FieldData>\n");
    for (name, value) in std::iter::once(&("TimeValue", time)).chain(extra) {
        let _ = writeln!(
            out,
            "      <DataArray type=\"Float64\" Name=\"{name}\" NumberOfTuples=\"1\" format=\"ascii\">{value:.12e}</DataArray>"
        );
    }
    out.push_str("    </FieldData>\n");
    let _ = writeln!(
        out,
        "    <Piece NumberOfPoints=\"{points}\" NumberOfCells=\"{cells}\">"
    );
}

/// Points (z = 0), then the cells, then the end of the file.
fn push_geometry(
    out: &mut String,
    points: &[Vec2],
    connectivity: impl Iterator<Item = usize>,
    offsets: impl Iterator<Item = usize>,
    cell_type: u8,
    cells: usize,
) {
    out.push_str("      <Points>\n");
    push_array(
        out,
        "position",
        3,
        points.iter().flat_map(|p| [p.x, p.y, 0.0]),
    );
    out.push_str("      </Points>\n");
    out.push_str("      <Cells>\n");
    push_scalars(out, "connectivity", connectivity.map(|i| i as i64));
    push_scalars(out, "offsets", offsets.map(|i| i as i64));
    push_scalars(out, "types", std::iter::repeat_n(cell_type, cells));
    out.push_str("      </Cells>\n");
    out.push_str("    </Piece>\n");
    out.push_str("  </UnstructuredGrid>\n");
    out.push_str("</VTKFile>\n");
}

/// VTK cell types used here.
const VTK_VERTEX: u8 = 1;
const VTK_LINE: u8 = 3;

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
    let mut out = String::with_capacity(1000 + n * 130);
    let extra: Vec<(&str, Real)> = [
        ("density", fields.density),
        ("particle_spacing", fields.spacing),
    ]
    .into_iter()
    .filter_map(|(k, v)| v.map(|v| (k, v)))
    .collect();
    push_header(&mut out, time, &extra, n, n);
    out.push_str("      <PointData Scalars=\"pressure\" Vectors=\"velocity\">\n");
    push_array(
        &mut out,
        "velocity",
        3,
        fields.velocity.iter().flat_map(|v| [v.x, v.y, 0.0]),
    );
    push_scalars(&mut out, "pressure", fields.pressure.iter().copied());
    push_scalars(
        &mut out,
        "number_density",
        fields.number_density.iter().copied(),
    );
    if let Some(n0) = fields.n0.filter(|n0| *n0 > 0.0) {
        push_scalars(
            &mut out,
            "number_density_ratio",
            fields.number_density.iter().map(|v| v / n0),
        );
    }
    push_scalars(
        &mut out,
        "free_surface",
        fields.free_surface.iter().map(|f| u8::from(*f)),
    );
    if let Some(s) = &fields.particle_spacing {
        push_scalars(&mut out, "spacing", s.iter().copied());
    }
    out.push_str("      </PointData>\n");
    push_geometry(&mut out, fields.position, 0..n, 1..=n, VTK_VERTEX, n);
    out
}

/// The text of a `.vtu` file with every wall and body surface as line cells at its pose.
/// Cell data: `object` (the outline's index, the order of loads.csv's names), `segment`
/// (the surface segment the cell lies on, within its object), `moving` (1 for a body),
/// `speed` (its centre of mass's, m/s) and `pressure` (Pa, on the cell); point data:
/// `velocity` of the material point.
pub fn walls_vtu_string(outlines: &[Outline], time: Real) -> String {
    let mut points = Vec::new();
    let mut velocity: Vec<Vec2> = Vec::new();
    let (mut object, mut segment, mut moving, mut speed, mut pressure) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for (k, o) in outlines.iter().enumerate() {
        assert!(
            o.velocities.len() == o.cells.len()
                && o.segment.len() == o.cells.len()
                && o.pressure.len() == o.cells.len(),
            "every cell of an outline has its velocities, segment and pressure"
        );
        for c in 0..o.cells.len() {
            points.extend(o.cells[c]);
            velocity.extend(o.velocities[c]);
            object.push(k);
            segment.push(o.segment[c]);
            moving.push(u8::from(o.moving));
            speed.push(o.speed);
            pressure.push(o.pressure[c]);
        }
    }
    let cells = object.len();
    let mut out = String::with_capacity(1000 + cells * 200);
    push_header(&mut out, time, &[], points.len(), cells);
    out.push_str("      <PointData Vectors=\"velocity\">\n");
    push_array(
        &mut out,
        "velocity",
        3,
        velocity.iter().flat_map(|v| [v.x, v.y, 0.0]),
    );
    out.push_str("      </PointData>\n");
    out.push_str("      <CellData Scalars=\"object\">\n");
    push_scalars(&mut out, "object", object.into_iter().map(|k| k as i32));
    push_scalars(&mut out, "segment", segment.into_iter().map(|s| s as i32));
    push_scalars(&mut out, "moving", moving.into_iter());
    push_scalars(&mut out, "speed", speed.into_iter());
    push_scalars(&mut out, "pressure", pressure.into_iter());
    out.push_str("      </CellData>\n");
    push_geometry(
        &mut out,
        &points,
        0..points.len(),
        (1..=cells).map(|c| 2 * c),
        VTK_LINE,
        cells,
    );
    out
}

/// The collection's part holding the particles.
pub const PARTICLES_PART: u32 = 0;
/// The collection's part holding the walls and bodies.
pub const WALLS_PART: u32 = 1;

/// One entry of a `.pvd` collection.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PvdEntry {
    pub time: Real,
    /// Path of the `.vtu`, relative to the `.pvd`.
    pub file: String,
    /// [`PARTICLES_PART`] or [`WALLS_PART`]: ParaView shows the parts of one time together.
    pub part: u32,
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
            "    <DataSet timestep=\"{:.12e}\" group=\"\" part=\"{}\" file=\"{}\"/>",
            e.time,
            e.part,
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
        let part = match tag.attributes.get("part") {
            None => PARTICLES_PART,
            Some(p) => p.parse().map_err(|e| bad(format!("part: {e}")))?,
        };
        entries.push(PvdEntry { time, file, part });
        at = tag.end;
    }
    Ok(entries)
}

/// A `.vtu` read back: points, cells and named data arrays.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct VtuData {
    pub time: Option<Real>,
    /// Field data other than the time (one value each).
    pub field_data: BTreeMap<String, Real>,
    pub points: Vec<[Real; 3]>,
    pub cells: usize,
    /// Point indices of the cells, in order; cell k ends at `offsets[k]`.
    pub connectivity: Vec<usize>,
    pub offsets: Vec<usize>,
    /// Name -> (components, values flattened).
    pub point_data: BTreeMap<String, (usize, Vec<Real>)>,
    pub cell_data: BTreeMap<String, (usize, Vec<Real>)>,
}

impl VtuData {
    /// A scalar point-data array by name.
    pub fn scalar(&self, name: &str) -> Option<&[Real]> {
        self.point_data
            .get(name)
            .filter(|(c, _)| *c == 1)
            .map(|(_, v)| v.as_slice())
    }

    /// A scalar cell-data array by name.
    pub fn cell_scalar(&self, name: &str) -> Option<&[Real]> {
        self.cell_data
            .get(name)
            .filter(|(c, _)| *c == 1)
            .map(|(_, v)| v.as_slice())
    }

    /// The point indices of cell `k`.
    pub fn cell(&self, k: usize) -> &[usize] {
        let start = if k == 0 { 0 } else { self.offsets[k - 1] };
        &self.connectivity[start..self.offsets[k]]
    }
}

/// The body of a `<DataArray ...>` whose start tag ends at `tag.end`, parsed as numbers.
fn data_array_values(text: &str, tag: &Tag) -> io::Result<Vec<Real>> {
    if tag.self_closing {
        return Ok(Vec::new());
    }
    let close = text[tag.end..]
        .find("</DataArray>")
        .ok_or_else(|| bad("unterminated DataArray"))?
        + tag.end;
    let body = &text[tag.end..close];
    match tag.attributes.get("format").map(String::as_str) {
        Some("ascii") => body
            .split_ascii_whitespace()
            .map(|s| {
                s.parse::<Real>()
                    .map_err(|e| bad(format!("DataArray value {s:?}: {e}")))
            })
            .collect(),
        Some("binary") => binary_values(body, tag),
        other => Err(bad(format!(
            "DataArray format {other:?}: only inline ascii and binary are read"
        ))),
    }
}

/// The values of an inline binary `DataArray`: base64 of a UInt64 byte count and the
/// little-endian values.
fn binary_values(body: &str, tag: &Tag) -> io::Result<Vec<Real>> {
    use base64::Engine as _;
    let compact: String = body.split_ascii_whitespace().collect();
    let bytes = base64::engine::general_purpose::STANDARD
        .decode(compact)
        .map_err(|e| bad(format!("DataArray base64: {e}")))?;
    let (header, data) = bytes
        .split_at_checked(8)
        .ok_or_else(|| bad("binary DataArray shorter than its header"))?;
    let count = u64::from_le_bytes(header.try_into().expect("8 bytes")) as usize;
    let data = data
        .get(..count)
        .ok_or_else(|| bad("binary DataArray shorter than its byte count"))?;
    fn values<const N: usize>(data: &[u8], f: impl Fn([u8; N]) -> Real) -> Vec<Real> {
        data.chunks_exact(N)
            .map(|c| f(c.try_into().expect("N bytes")))
            .collect()
    }
    Ok(match tag.attributes.get("type").map(String::as_str) {
        Some("Float64") => values(data, f64::from_le_bytes),
        Some("Float32") => values(data, |b| f32::from_le_bytes(b) as Real),
        Some("Int64") => values(data, |b| i64::from_le_bytes(b) as Real),
        Some("UInt64") => values(data, |b| u64::from_le_bytes(b) as Real),
        Some("Int32") => values(data, |b| i32::from_le_bytes(b) as Real),
        Some("UInt32") => values(data, |b| u32::from_le_bytes(b) as Real),
        Some("UInt8") => values(data, |b: [u8; 1]| b[0] as Real),
        Some("Int8") => values(data, |b: [u8; 1]| b[0] as i8 as Real),
        other => return Err(bad(format!("binary DataArray of type {other:?}"))),
    })
}

/// Parse a `.vtu` with inline arrays (one piece) and check its counts are consistent.
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
        let value = data_array_values(text, &tag)?.first().copied();
        match (tag.attributes.get("Name").map(String::as_str), value) {
            (Some("TimeValue"), _) => data.time = value,
            (Some(name), Some(v)) => {
                data.field_data.insert(name.to_string(), v);
            }
            _ => {}
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
    for (name, count, map) in [
        ("PointData", n, &mut data.point_data),
        ("CellData", cells, &mut data.cell_data),
    ] {
        let Some((start, end)) = section(name)? else {
            continue;
        };
        let mut at = start;
        while let Some(tag) = next_tag(text, "DataArray", at)?.filter(|t| t.end <= end) {
            let array = tag
                .attributes
                .get("Name")
                .cloned()
                .ok_or_else(|| bad(format!("{name} DataArray without Name")))?;
            let components: usize = tag
                .attributes
                .get("NumberOfComponents")
                .map(|c| c.parse().map_err(|e| bad(format!("{e}"))))
                .transpose()?
                .unwrap_or(1);
            let values = data_array_values(text, &tag)?;
            if values.len() != components * count {
                return Err(bad(format!(
                    "{name} {array}: {} values for {count} x {components}",
                    values.len()
                )));
            }
            map.insert(array, (components, values));
            at = tag.end;
        }
    }
    if let Some((start, end)) = section("Cells")? {
        let mut at = start;
        while let Some(tag) = next_tag(text, "DataArray", at)?.filter(|t| t.end <= end) {
            let values = data_array_values(text, &tag)?;
            let len = values.len();
            let name = tag.attributes.get("Name").cloned().unwrap_or_default();
            if matches!(name.as_str(), "offsets" | "types") && len != cells {
                return Err(bad(format!(
                    "cell array {name}: {len} values for {cells} cells"
                )));
            }
            let indices = || values.iter().map(|v| *v as usize).collect::<Vec<_>>();
            match name.as_str() {
                "connectivity" => data.connectivity = indices(),
                "offsets" => data.offsets = indices(),
                _ => {}
            }
            at = tag.end;
        }
    }
    let consistent = data.offsets.windows(2).all(|w| w[0] <= w[1])
        && data.offsets.last().copied().unwrap_or(0) == data.connectivity.len()
        && data.connectivity.iter().all(|&i| i < n);
    if !consistent {
        return Err(bad("cell offsets or connectivity out of range"));
    }
    Ok(data)
}
