//! The three VTK XML file kinds ParaView needs, written by hand: `.vtu` (points as vertex
//! cells), `.vti` (a regular grid) and `.pvd` (a time collection of either).
//!
//! Arrays go to one appended block in raw binary (little-endian, a `UInt64` byte count before
//! each array), the most compact of VTK's XML encodings and the one ParaView reads fastest.
//! A hand-written writer rather than the `vtkio` crate: the files are a few fixed tags, and
//! `vtkio`'s last stable release (0.6) dates from 2021 and would bring a parser, a
//! compression stack and its own data model for what is here a hundred lines.

use std::fmt::Write as _;

use glam::DVec2;

/// One named array of a file's point data (or of its coordinates).
pub struct Array {
    pub name: String,
    /// VTK's type name: `Float64`, `Int32`, `Int64` or `UInt8`.
    kind: &'static str,
    components: usize,
    bytes: Vec<u8>,
}

impl Array {
    /// `components` values per point, flattened point by point.
    pub fn f64(name: &str, components: usize, values: impl IntoIterator<Item = f64>) -> Array {
        Array::from_bytes(name, "Float64", components, values, f64::to_le_bytes)
    }

    /// 2D vectors as VTK's three components (z = 0).
    pub fn vectors(name: &str, v: &[DVec2]) -> Array {
        Array::f64(name, 3, v.iter().flat_map(|v| [v.x, v.y, 0.0]))
    }

    pub fn i32(name: &str, values: impl IntoIterator<Item = i32>) -> Array {
        Array::from_bytes(name, "Int32", 1, values, i32::to_le_bytes)
    }

    pub fn i64(name: &str, values: impl IntoIterator<Item = i64>) -> Array {
        Array::from_bytes(name, "Int64", 1, values, i64::to_le_bytes)
    }

    pub fn u8(name: &str, values: impl IntoIterator<Item = u8>) -> Array {
        Array::from_bytes(name, "UInt8", 1, values, u8::to_le_bytes)
    }

    fn from_bytes<T, const N: usize>(
        name: &str,
        kind: &'static str,
        components: usize,
        values: impl IntoIterator<Item = T>,
        le: fn(T) -> [u8; N],
    ) -> Array {
        Array {
            name: name.to_string(),
            kind,
            components,
            bytes: values.into_iter().flat_map(le).collect(),
        }
    }
}

/// The appended block and the tags that point into it.
#[derive(Default)]
struct Appended {
    block: Vec<u8>,
}

impl Appended {
    /// The `DataArray` tag of `array`, its bytes added to the block.
    fn tag(&mut self, array: &Array) -> String {
        let offset = self.block.len();
        self.block
            .extend_from_slice(&(array.bytes.len() as u64).to_le_bytes());
        self.block.extend_from_slice(&array.bytes);
        format!(
            "<DataArray type=\"{}\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"appended\" offset=\"{offset}\"/>\n",
            array.kind,
            escape(&array.name),
            array.components
        )
    }

    fn tags(&mut self, arrays: &[Array]) -> String {
        arrays.iter().map(|a| self.tag(a)).collect()
    }

    /// The whole file: `body` (the data set's element) then the appended block.
    fn file(self, kind: &str, body: &str) -> Vec<u8> {
        let mut out = format!(
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"{kind}\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n{body}<AppendedData encoding=\"raw\">\n_"
        )
        .into_bytes();
        out.extend_from_slice(&self.block);
        out.extend_from_slice(b"\n</AppendedData>\n</VTKFile>\n");
        out
    }
}

/// Whole-data-set field data: the simulated time (so a file read on its own still says
/// when it is) and `fields`, each a name and its components.
fn field_data(time: f64, fields: &[(&str, &[f64])]) -> String {
    let mut s = format!(
        "<FieldData>\n<DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">{time:e}</DataArray>\n"
    );
    for (name, values) in fields {
        let text: Vec<String> = values.iter().map(|v| format!("{v:e}")).collect();
        let _ = writeln!(
            s,
            "<DataArray type=\"Float64\" Name=\"{}\" NumberOfTuples=\"1\" NumberOfComponents=\"{}\" format=\"ascii\">{}</DataArray>",
            escape(name),
            values.len(),
            text.join(" ")
        );
    }
    s.push_str("</FieldData>\n");
    s
}

/// A `.vtu` of `positions` (z = 0) as vertex cells, with `arrays` as point data.
pub fn unstructured_points(time: f64, positions: &[DVec2], arrays: &[Array]) -> Vec<u8> {
    let n = positions.len();
    let mut appended = Appended::default();
    let mut body = format!(
        "<UnstructuredGrid>\n{}<Piece NumberOfPoints=\"{n}\" NumberOfCells=\"{n}\">\n<PointData>\n",
        field_data(time, &[])
    );
    body.push_str(&appended.tags(arrays));
    body.push_str("</PointData>\n<Points>\n");
    let coords = Array::vectors("position", positions);
    body.push_str(&appended.tag(&coords));
    body.push_str("</Points>\n<Cells>\n");
    let cells = [
        Array::i64("connectivity", 0..n as i64),
        Array::i64("offsets", 1..=n as i64),
        // VTK_VERTEX
        Array::u8("types", std::iter::repeat_n(1, n)),
    ];
    body.push_str(&appended.tags(&cells));
    body.push_str("</Cells>\n</Piece>\n</UnstructuredGrid>\n");
    appended.file("UnstructuredGrid", &body)
}

/// A regular grid of `nodes[0] x nodes[1]` nodes, `spacing` apart from `origin`.
pub struct Lattice {
    pub origin: [f64; 2],
    pub spacing: f64,
    pub nodes: [usize; 2],
}

/// A `.vti` of `lattice` with `arrays` as point (node) data, node `(i, j)` at index
/// `j * nodes[0] + i`, and `fields` (name, values) as whole-data-set field data.
pub fn image_data(
    time: f64,
    lattice: &Lattice,
    arrays: &[Array],
    fields: &[(&str, &[f64])],
) -> Vec<u8> {
    let extent = format!(
        "0 {} 0 {} 0 0",
        lattice.nodes[0].saturating_sub(1),
        lattice.nodes[1].saturating_sub(1)
    );
    let [ox, oy] = lattice.origin;
    let h = lattice.spacing;
    let mut appended = Appended::default();
    let mut body = format!(
        "<ImageData WholeExtent=\"{extent}\" Origin=\"{ox:e} {oy:e} 0\" Spacing=\"{h:e} {h:e} {h:e}\">\n{}",
        field_data(time, fields)
    );
    let _ = write!(body, "<Piece Extent=\"{extent}\">\n<PointData>\n");
    body.push_str(&appended.tags(arrays));
    body.push_str("</PointData>\n</Piece>\n</ImageData>\n");
    appended.file("ImageData", &body)
}

/// One file of a time collection.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Entry {
    pub time: f64,
    /// Which data set of the frame (one per body).
    pub part: usize,
    /// Relative to the `.pvd`.
    pub file: String,
}

/// A `.pvd` listing `entries`: ParaView's time slider steps through their times.
pub fn collection(entries: &[Entry]) -> String {
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\">\n<Collection>\n",
    );
    for e in entries {
        let _ = writeln!(
            s,
            "<DataSet timestep=\"{:e}\" group=\"\" part=\"{}\" file=\"{}\"/>",
            e.time,
            e.part,
            escape(&e.file)
        );
    }
    s.push_str("</Collection>\n</VTKFile>\n");
    s
}

/// The entries of a `.pvd` this module wrote (for readers of a run's files).
pub fn read_collection(text: &str) -> Vec<Entry> {
    let attribute = |line: &str, name: &str| -> Option<String> {
        let start = line.find(&format!("{name}=\""))? + name.len() + 2;
        let len = line[start..].find('"')?;
        Some(unescape(&line[start..start + len]))
    };
    text.lines()
        .filter_map(|line| {
            Some(Entry {
                time: attribute(line, "timestep")?.parse().ok()?,
                part: attribute(line, "part")?.parse().ok()?,
                file: attribute(line, "file")?,
            })
        })
        .collect()
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('"', "&quot;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

fn unescape(s: &str) -> String {
    s.replace("&quot;", "\"")
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&amp;", "&")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_collection_reads_back_what_was_written() {
        let entries = vec![
            Entry {
                time: 0.0,
                part: 0,
                file: "bed_00000.vtu".into(),
            },
            Entry {
                time: 2.5e-3,
                part: 1,
                file: "a \"quoted\" & <odd> name.vtu".into(),
            },
        ];
        assert_eq!(read_collection(&collection(&entries)), entries);
    }

    #[test]
    fn appended_offsets_point_at_each_array_header() {
        let file = unstructured_points(
            0.5,
            &[DVec2::new(1.0, 2.0), DVec2::new(3.0, 4.0)],
            &[Array::f64("pressure", 1, [7.0, 8.0])],
        );
        let text = String::from_utf8_lossy(&file);
        let marker = b"<AppendedData encoding=\"raw\">\n_";
        let start = file
            .windows(marker.len())
            .position(|w| w == marker)
            .unwrap()
            + marker.len();
        // pressure first: 2 values of 8 bytes after an 8-byte count.
        assert!(text.contains(
            "Name=\"pressure\" NumberOfComponents=\"1\" format=\"appended\" offset=\"0\""
        ));
        assert_eq!(file[start..start + 8], 16u64.to_le_bytes());
        assert_eq!(file[start + 8..start + 16], 7.0f64.to_le_bytes());
        // the coordinates next, three per point.
        assert!(text.contains(
            "Name=\"position\" NumberOfComponents=\"3\" format=\"appended\" offset=\"24\""
        ));
        assert_eq!(file[start + 24..start + 32], 48u64.to_le_bytes());
        assert_eq!(file[start + 32 + 24..start + 32 + 32], 3.0f64.to_le_bytes());
    }
}
