//! VTK XML writers: `.vtu` unstructured grids (lattices, control nets, point clouds), `.vts`
//! structured grids (a tessellated surface) and `.pvd` collections (time series for ParaView).
//!
//! Binary data is written inline in VTK's `format="binary"` encoding: for each array the
//! little-endian bytes are prefixed with their byte count (a `UInt64` or `UInt32` header, as
//! declared by the file's `header_type` attribute) and the whole is base64-encoded as one block,
//! uncompressed. Coordinates and data arrays are `Float64`, connectivity and offsets `Int64`,
//! cell types `UInt8`. An ASCII encoding is available for debugging.
//!
//! Unstructured grids also carry string arrays ([`StringArray`], `type="String"`, VTK's
//! `vtkStringArray`), e.g. the name of each cell's category: in binary the UTF-8 bytes of the
//! strings, each followed by a NUL byte, behind the same byte-count header; in ASCII the same
//! bytes as decimal numbers separated by spaces (each string ending in `0`), as VTK's
//! `vtkXMLWriter` writes them. `NumberOfTuples` gives the number of strings.
//!
//! ```
//! use nurbspring_io::vtk::{Cell, DataArray, VtkUnstructured};
//! # let dir = tempfile::tempdir().unwrap();
//! let mut grid = VtkUnstructured::new(vec![[0.0, 0.0, 2.0], [1.0, 0.0, 2.0], [1.0, 1.0, 2.0]]);
//! grid.cells = vec![Cell::Line([0, 1]), Cell::Line([1, 2]), Cell::Triangle([0, 1, 2])];
//! grid.point_data.push(DataArray::vectors("velocity", &[[0.0, 0.0, -0.2]; 3]));
//! grid.cell_data.push(DataArray::scalars("k", vec![2.7225, 2.7225, 0.0]));
//! grid.write(dir.path().join("lattice.vtu")).unwrap();
//! ```

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use base64::Engine as _;
use base64::engine::general_purpose::STANDARD as BASE64;

use crate::OutputError;
use crate::atomic::write_atomic;
use crate::output::format_f64;

/// Integer type of the byte-count header in front of each binary array.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum HeaderType {
    /// 32-bit header (VTK's default for files without a `header_type` attribute); arrays are
    /// limited to 4 GiB.
    UInt32,
    /// 64-bit header (what current VTK writes).
    #[default]
    UInt64,
}

impl HeaderType {
    fn name(self) -> &'static str {
        match self {
            HeaderType::UInt32 => "UInt32",
            HeaderType::UInt64 => "UInt64",
        }
    }
}

/// How array values are stored in the file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum VtkEncoding {
    /// Inline base64 (`format="binary"`): compact and exact.
    #[default]
    Binary,
    /// Inline text (`format="ascii"`), shortest round-trip decimals: readable, larger.
    Ascii,
}

/// Encoding options of a VTK XML file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct VtkFormat {
    /// Binary (default) or ASCII.
    pub encoding: VtkEncoding,
    /// Header integer for binary arrays (default `UInt64`).
    pub header: HeaderType,
}

/// A cell of an unstructured grid, by 0-based point indices.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Cell {
    /// One point (`VTK_VERTEX` = 1).
    Vertex(usize),
    /// A set of points (`VTK_POLY_VERTEX` = 2).
    PolyVertex(Vec<usize>),
    /// A segment, e.g. a spring (`VTK_LINE` = 3).
    Line([usize; 2]),
    /// A polyline, e.g. a trajectory (`VTK_POLY_LINE` = 4).
    PolyLine(Vec<usize>),
    /// A triangle (`VTK_TRIANGLE` = 5).
    Triangle([usize; 3]),
    /// A quadrilateral, corners in order around it (`VTK_QUAD` = 9).
    Quad([usize; 4]),
}

impl Cell {
    /// The VTK cell type number.
    pub fn vtk_type(&self) -> u8 {
        match self {
            Cell::Vertex(_) => 1,
            Cell::PolyVertex(_) => 2,
            Cell::Line(_) => 3,
            Cell::PolyLine(_) => 4,
            Cell::Triangle(_) => 5,
            Cell::Quad(_) => 9,
        }
    }

    /// The point indices of this cell.
    pub fn points(&self) -> &[usize] {
        match self {
            Cell::Vertex(a) => std::slice::from_ref(a),
            Cell::PolyVertex(v) | Cell::PolyLine(v) => v,
            Cell::Line(v) => v,
            Cell::Triangle(v) => v,
            Cell::Quad(v) => v,
        }
    }
}

/// A named data array attached to points or cells: `values.len() = components × count`,
/// interleaved (`[x0, y0, z0, x1, …]` for vectors).
#[derive(Clone, Debug, PartialEq)]
pub struct DataArray {
    /// Name shown in ParaView (must be non-empty and unique within its point or cell data).
    pub name: String,
    /// Components per tuple (1 scalar, 3 vector, 9 tensor, …); at least 1.
    pub components: usize,
    /// The values, tuple after tuple.
    pub values: Vec<f64>,
}

impl DataArray {
    /// An array with `components` values per point or cell.
    pub fn new(name: impl Into<String>, components: usize, values: Vec<f64>) -> Self {
        Self {
            name: name.into(),
            components,
            values,
        }
    }

    /// One value per point or cell.
    pub fn scalars(name: impl Into<String>, values: Vec<f64>) -> Self {
        Self::new(name, 1, values)
    }

    /// One 3-vector per point or cell.
    pub fn vectors(name: impl Into<String>, values: &[[f64; 3]]) -> Self {
        Self::new(name, 3, values.iter().flatten().copied().collect())
    }
}

/// A named array of strings attached to points or cells, one string per point or cell
/// (VTK's `vtkStringArray`, `type="String"`): e.g. the name of a category next to its integer
/// code. Strings must not contain NUL bytes (they terminate each string in the file).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct StringArray {
    /// Name shown in ParaView (non-empty, unique among all arrays of its point or cell data).
    pub name: String,
    /// One string per point or cell.
    pub values: Vec<String>,
}

impl StringArray {
    /// An array of one string per point or cell.
    pub fn new(name: impl Into<String>, values: Vec<String>) -> Self {
        Self {
            name: name.into(),
            values,
        }
    }
}

impl<S: Into<String>> From<(S, usize, Vec<f64>)> for DataArray {
    fn from((name, components, values): (S, usize, Vec<f64>)) -> Self {
        Self::new(name, components, values)
    }
}

/// An unstructured grid (`.vtu`): points, cells of mixed kinds, point and cell data.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VtkUnstructured {
    /// Point coordinates.
    pub points: Vec<[f64; 3]>,
    /// Cells.
    pub cells: Vec<Cell>,
    /// Arrays with one tuple per point.
    pub point_data: Vec<DataArray>,
    /// Arrays with one tuple per cell.
    pub cell_data: Vec<DataArray>,
    /// String arrays with one string per point (written after `point_data`).
    pub point_strings: Vec<StringArray>,
    /// String arrays with one string per cell (written after `cell_data`).
    pub cell_strings: Vec<StringArray>,
}

impl VtkUnstructured {
    /// A grid of `points` with no cells and no data.
    pub fn new(points: Vec<[f64; 3]>) -> Self {
        Self {
            points,
            ..Self::default()
        }
    }

    /// A point cloud: one `Vertex` cell per point (ParaView then shows the points).
    pub fn point_cloud(points: Vec<[f64; 3]>) -> Self {
        let cells = (0..points.len()).map(Cell::Vertex).collect();
        Self {
            points,
            cells,
            ..Self::default()
        }
    }

    /// Checks indices and array lengths; the message names the offending cell or array.
    pub fn validate(&self) -> Result<(), String> {
        let n = self.points.len();
        for (c, cell) in self.cells.iter().enumerate() {
            if cell.points().is_empty() {
                return Err(format!("cell {c} has no points"));
            }
            if let Some(&k) = cell.points().iter().find(|&&k| k >= n) {
                return Err(format!(
                    "cell {c} refers to point {k}, but there are {n} points"
                ));
            }
        }
        check_arrays("point", &self.point_data, n)?;
        check_arrays("cell", &self.cell_data, self.cells.len())?;
        check_strings("point", &self.point_strings, &self.point_data, n)?;
        check_strings(
            "cell",
            &self.cell_strings,
            &self.cell_data,
            self.cells.len(),
        )
    }

    /// Renders the XML text of the `.vtu` file.
    pub fn to_xml(&self, format: VtkFormat) -> Result<String, String> {
        self.validate()?;
        let mut x = XmlWriter::new(format, "UnstructuredGrid");
        x.open("UnstructuredGrid", "");
        x.open(
            "Piece",
            &format!(
                " NumberOfPoints=\"{}\" NumberOfCells=\"{}\"",
                self.points.len(),
                self.cells.len()
            ),
        );
        x.data_section("PointData", &self.point_data, &self.point_strings)?;
        x.data_section("CellData", &self.cell_data, &self.cell_strings)?;
        x.points(&self.points)?;
        x.open("Cells", "");
        let connectivity: Vec<i64> = self
            .cells
            .iter()
            .flat_map(|c| c.points().iter().map(|&k| k as i64))
            .collect();
        let offsets: Vec<i64> = self
            .cells
            .iter()
            .scan(0i64, |end, c| {
                *end += c.points().len() as i64;
                Some(*end)
            })
            .collect();
        let types: Vec<u8> = self.cells.iter().map(Cell::vtk_type).collect();
        x.array(Some("connectivity"), 1, Payload::I64(&connectivity))?;
        x.array(Some("offsets"), 1, Payload::I64(&offsets))?;
        x.array(Some("types"), 1, Payload::U8(&types))?;
        x.close("Cells");
        x.close("Piece");
        x.close("UnstructuredGrid");
        Ok(x.finish())
    }

    /// Writes the grid as a binary `.vtu` file (UInt64 headers), atomically.
    pub fn write(&self, path: impl AsRef<Path>) -> Result<(), OutputError> {
        self.write_with(path, VtkFormat::default())
    }

    /// Writes the grid with the given encoding options.
    pub fn write_with(&self, path: impl AsRef<Path>, format: VtkFormat) -> Result<(), OutputError> {
        let path = path.as_ref();
        check_finite(path, &self.points, &self.point_data, &self.cell_data)?;
        let xml = self
            .to_xml(format)
            .map_err(|m| OutputError::invalid(path, m))?;
        write_atomic(path, |w| w.write_all(xml.as_bytes()))
    }
}

/// A structured grid (`.vts`) of `n_u × n_v` points, e.g. a surface tessellated on a parameter
/// grid. Points are in nurbspring's order `k = i · n_v + j` (`i` along u); in the file the first
/// VTK index runs along u (the writer transposes), so ParaView's `i` is u and `j` is v. Cell
/// data has `(n_u − 1)(n_v − 1)` tuples in the order `c = i · (n_v − 1) + j`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VtkStructured {
    /// Number of samples along u (≥ 2).
    pub n_u: usize,
    /// Number of samples along v (≥ 2).
    pub n_v: usize,
    /// `n_u · n_v` points, `points[i * n_v + j]`.
    pub points: Vec<[f64; 3]>,
    /// Arrays with one tuple per point (same order as `points`).
    pub point_data: Vec<DataArray>,
    /// Arrays with one tuple per cell.
    pub cell_data: Vec<DataArray>,
}

impl VtkStructured {
    /// A grid with no data arrays.
    pub fn new(n_u: usize, n_v: usize, points: Vec<[f64; 3]>) -> Self {
        Self {
            n_u,
            n_v,
            points,
            ..Self::default()
        }
    }

    /// Checks the sizes; the message names the offending array.
    pub fn validate(&self) -> Result<(), String> {
        if self.n_u < 2 || self.n_v < 2 {
            return Err(format!(
                "a structured surface grid needs at least 2 x 2 points, got {} x {}",
                self.n_u, self.n_v
            ));
        }
        let n = self
            .n_u
            .checked_mul(self.n_v)
            .ok_or_else(|| format!("{} x {} points overflow", self.n_u, self.n_v))?;
        if self.points.len() != n {
            return Err(format!(
                "{} x {} grid needs {n} points, got {}",
                self.n_u,
                self.n_v,
                self.points.len()
            ));
        }
        check_arrays("point", &self.point_data, n)?;
        check_arrays("cell", &self.cell_data, (self.n_u - 1) * (self.n_v - 1))
    }

    /// Renders the XML text of the `.vts` file.
    pub fn to_xml(&self, format: VtkFormat) -> Result<String, String> {
        self.validate()?;
        let (nu, nv) = (self.n_u, self.n_v);
        // nurbspring index i * n_v + j → VTK index j * n_u + i (first index fastest).
        let transpose = |a: &DataArray, rows: usize, cols: usize| -> DataArray {
            let c = a.components;
            let mut values = Vec::with_capacity(a.values.len());
            for j in 0..cols {
                for i in 0..rows {
                    let k = i * cols + j;
                    values.extend_from_slice(&a.values[k * c..(k + 1) * c]);
                }
            }
            DataArray::new(a.name.clone(), c, values)
        };
        let points: Vec<[f64; 3]> = (0..nv)
            .flat_map(|j| (0..nu).map(move |i| (i, j)))
            .map(|(i, j)| self.points[i * nv + j])
            .collect();
        let pd: Vec<DataArray> = self
            .point_data
            .iter()
            .map(|a| transpose(a, nu, nv))
            .collect();
        let cd: Vec<DataArray> = self
            .cell_data
            .iter()
            .map(|a| transpose(a, nu - 1, nv - 1))
            .collect();
        let extent = format!("0 {} 0 {} 0 0", nu - 1, nv - 1);
        let mut x = XmlWriter::new(format, "StructuredGrid");
        x.open("StructuredGrid", &format!(" WholeExtent=\"{extent}\""));
        x.open("Piece", &format!(" Extent=\"{extent}\""));
        x.data_section("PointData", &pd, &[])?;
        x.data_section("CellData", &cd, &[])?;
        x.points(&points)?;
        x.close("Piece");
        x.close("StructuredGrid");
        Ok(x.finish())
    }

    /// Writes the grid as a binary `.vts` file (UInt64 headers), atomically.
    pub fn write(&self, path: impl AsRef<Path>) -> Result<(), OutputError> {
        self.write_with(path, VtkFormat::default())
    }

    /// Writes the grid with the given encoding options.
    pub fn write_with(&self, path: impl AsRef<Path>, format: VtkFormat) -> Result<(), OutputError> {
        let path = path.as_ref();
        check_finite(path, &self.points, &self.point_data, &self.cell_data)?;
        let xml = self
            .to_xml(format)
            .map_err(|m| OutputError::invalid(path, m))?;
        write_atomic(path, |w| w.write_all(xml.as_bytes()))
    }
}

/// Writes `grid` as a binary `.vtu` file (same as [`VtkUnstructured::write`]).
pub fn write_vtu(path: impl AsRef<Path>, grid: &VtkUnstructured) -> Result<(), OutputError> {
    grid.write(path)
}

/// Writes `grid` as a binary `.vts` file (same as [`VtkStructured::write`]).
pub fn write_vts(path: impl AsRef<Path>, grid: &VtkStructured) -> Result<(), OutputError> {
    grid.write(path)
}

/// A ParaView time series (`.pvd` collection): one `(time, file)` entry per frame. File names
/// are written as given; make them relative to the folder of the `.pvd` file so the series can
/// be moved.
///
/// ```
/// use nurbspring_io::vtk::PvdSeries;
/// # let dir = tempfile::tempdir().unwrap();
/// let mut series = PvdSeries::default();
/// series.push(0.0, "frames/msm_000000.vtu");
/// series.push(0.08, "frames/msm_000001.vtu");
/// series.write(dir.path().join("msm.pvd")).unwrap();
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PvdSeries {
    /// Frames in the order written.
    pub entries: Vec<(f64, PathBuf)>,
}

impl PvdSeries {
    /// Appends a frame.
    pub fn push(&mut self, time: f64, file: impl Into<PathBuf>) {
        self.entries.push((time, file.into()));
    }

    /// Renders the XML text of the collection. Non-finite times are refused.
    pub fn to_xml(&self) -> Result<String, String> {
        let mut s = String::from(
            "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n",
        );
        for (k, (t, file)) in self.entries.iter().enumerate() {
            if !t.is_finite() {
                return Err(format!("frame {k} has a non-finite time {t}"));
            }
            let name = file.to_string_lossy().replace('\\', "/");
            let _ = writeln!(
                s,
                "    <DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"{}\"/>",
                format_f64(*t),
                escape(&name)
            );
        }
        s.push_str("  </Collection>\n</VTKFile>\n");
        Ok(s)
    }

    /// Writes the `.pvd` file atomically (call it again after each new frame: readers always see
    /// a complete file).
    pub fn write(&self, path: impl AsRef<Path>) -> Result<(), OutputError> {
        let path = path.as_ref();
        let xml = self.to_xml().map_err(|m| OutputError::invalid(path, m))?;
        write_atomic(path, |w| w.write_all(xml.as_bytes()))
    }
}

/// Checks names, component counts and lengths of the arrays of one section.
fn check_arrays(kind: &str, arrays: &[DataArray], count: usize) -> Result<(), String> {
    for (k, a) in arrays.iter().enumerate() {
        if a.name.is_empty() {
            return Err(format!("{kind} data array {k} has an empty name"));
        }
        if arrays[..k].iter().any(|b| b.name == a.name) {
            return Err(format!("{kind} data array name `{}` is used twice", a.name));
        }
        if a.components == 0 {
            return Err(format!("{kind} data array `{}` has 0 components", a.name));
        }
        if Some(a.values.len()) != a.components.checked_mul(count) {
            return Err(format!(
                "{kind} data array `{}` has {} values, expected {} components x {count} {kind}s = {}",
                a.name,
                a.values.len(),
                a.components,
                a.components.saturating_mul(count)
            ));
        }
    }
    Ok(())
}

/// Checks the string arrays of one section: non-empty names unique among every array of the
/// section, one string per point or cell, no NUL byte.
fn check_strings(
    kind: &str,
    strings: &[StringArray],
    numeric: &[DataArray],
    count: usize,
) -> Result<(), String> {
    for (k, a) in strings.iter().enumerate() {
        if a.name.is_empty() {
            return Err(format!("{kind} string array {k} has an empty name"));
        }
        if strings[..k].iter().any(|b| b.name == a.name) || numeric.iter().any(|b| b.name == a.name)
        {
            return Err(format!("{kind} data array name `{}` is used twice", a.name));
        }
        if a.values.len() != count {
            return Err(format!(
                "{kind} string array `{}` has {} strings, expected one per {kind}: {count}",
                a.name,
                a.values.len()
            ));
        }
        if let Some(i) = a.values.iter().position(|v| v.contains('\0')) {
            return Err(format!(
                "{kind} string array `{}`, string {i} contains a NUL byte, which VTK reads as its end",
                a.name
            ));
        }
    }
    Ok(())
}

/// Escapes text for an XML attribute value.
fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            '\n' => out.push_str("&#10;"),
            _ => out.push(c),
        }
    }
    out
}

/// The values of one array, by VTK scalar type.
enum Payload<'a> {
    F64(&'a [f64]),
    I64(&'a [i64]),
    U8(&'a [u8]),
}

impl Payload<'_> {
    fn type_name(&self) -> &'static str {
        match self {
            Payload::F64(_) => "Float64",
            Payload::I64(_) => "Int64",
            Payload::U8(_) => "UInt8",
        }
    }

    fn le_bytes(&self) -> Vec<u8> {
        match self {
            Payload::F64(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            Payload::I64(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            Payload::U8(v) => v.to_vec(),
        }
    }

    fn ascii(&self, per_line: usize, indent: &str) -> String {
        let items: Vec<String> = match self {
            Payload::F64(v) => v.iter().map(|&x| format_f64(x)).collect(),
            Payload::I64(v) => v.iter().map(|x| x.to_string()).collect(),
            Payload::U8(v) => v.iter().map(|x| x.to_string()).collect(),
        };
        let mut s = String::new();
        for chunk in items.chunks(per_line.max(1)) {
            s.push_str(indent);
            s.push_str(&chunk.join(" "));
            s.push('\n');
        }
        s
    }
}

/// Builds an indented VTK XML document.
struct XmlWriter {
    format: VtkFormat,
    out: String,
    depth: usize,
}

impl XmlWriter {
    fn new(format: VtkFormat, kind: &str) -> Self {
        let mut out = String::from("<?xml version=\"1.0\"?>\n");
        let _ = writeln!(
            out,
            "<VTKFile type=\"{kind}\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"{}\">",
            format.header.name()
        );
        Self {
            format,
            out,
            depth: 1,
        }
    }

    fn indent(&self) -> String {
        "  ".repeat(self.depth)
    }

    fn open(&mut self, tag: &str, attributes: &str) {
        let _ = writeln!(self.out, "{}<{tag}{attributes}>", self.indent());
        self.depth += 1;
    }

    fn close(&mut self, tag: &str) {
        self.depth -= 1;
        let _ = writeln!(self.out, "{}</{tag}>", self.indent());
    }

    fn finish(mut self) -> String {
        self.out.push_str("</VTKFile>\n");
        self.out
    }

    fn data_section(
        &mut self,
        tag: &str,
        arrays: &[DataArray],
        strings: &[StringArray],
    ) -> Result<(), String> {
        self.open(tag, "");
        for a in arrays {
            self.array(Some(&a.name), a.components, Payload::F64(&a.values))?;
        }
        for a in strings {
            self.string_array(a)?;
        }
        self.close(tag);
        Ok(())
    }

    /// A `type="String"` array: the strings' bytes, each followed by a NUL byte, in binary
    /// behind the byte-count header; in ASCII as decimal byte values (VTK's convention).
    fn string_array(&mut self, a: &StringArray) -> Result<(), String> {
        let mut bytes = Vec::new();
        for v in &a.values {
            bytes.extend_from_slice(v.as_bytes());
            bytes.push(0);
        }
        let ind = self.indent();
        let encoding = match self.format.encoding {
            VtkEncoding::Binary => "binary",
            VtkEncoding::Ascii => "ascii",
        };
        let _ = writeln!(
            self.out,
            "{ind}<DataArray type=\"String\" Name=\"{}\" NumberOfComponents=\"1\" NumberOfTuples=\"{}\" format=\"{encoding}\">",
            escape(&a.name),
            a.values.len()
        );
        match self.format.encoding {
            VtkEncoding::Binary => {
                let block = self.binary_block(&format!(" `{}`", a.name), &bytes)?;
                let _ = writeln!(self.out, "{ind}  {}", BASE64.encode(&block));
            }
            VtkEncoding::Ascii => {
                // One string per line.
                for v in &a.values {
                    let codes: Vec<String> = v.bytes().map(|b| b.to_string()).collect();
                    let sep = if codes.is_empty() { "" } else { " " };
                    let _ = writeln!(self.out, "{ind}  {}{sep}0", codes.join(" "));
                }
            }
        }
        let _ = writeln!(self.out, "{ind}</DataArray>");
        Ok(())
    }

    /// The byte-count header followed by `data`, before base64 encoding.
    fn binary_block(&self, what: &str, data: &[u8]) -> Result<Vec<u8>, String> {
        let mut block = Vec::with_capacity(data.len() + 8);
        match self.format.header {
            HeaderType::UInt64 => block.extend((data.len() as u64).to_le_bytes()),
            HeaderType::UInt32 => {
                let n = u32::try_from(data.len()).map_err(|_| {
                    format!(
                        "array{what} has {} bytes, too many for a UInt32 header; use UInt64",
                        data.len()
                    )
                })?;
                block.extend(n.to_le_bytes());
            }
        }
        block.extend_from_slice(data);
        Ok(block)
    }

    fn points(&mut self, points: &[[f64; 3]]) -> Result<(), String> {
        let flat: Vec<f64> = points.iter().flatten().copied().collect();
        self.open("Points", "");
        self.array(None, 3, Payload::F64(&flat))?;
        self.close("Points");
        Ok(())
    }

    fn array(
        &mut self,
        name: Option<&str>,
        components: usize,
        payload: Payload<'_>,
    ) -> Result<(), String> {
        let name_attr = name
            .map(|n| format!(" Name=\"{}\"", escape(n)))
            .unwrap_or_default();
        let ind = self.indent();
        match self.format.encoding {
            VtkEncoding::Binary => {
                let block = self.binary_block(&name_attr, &payload.le_bytes())?;
                let _ = writeln!(
                    self.out,
                    "{ind}<DataArray type=\"{}\"{name_attr} NumberOfComponents=\"{components}\" format=\"binary\">",
                    payload.type_name()
                );
                let _ = writeln!(self.out, "{ind}  {}", BASE64.encode(&block));
                let _ = writeln!(self.out, "{ind}</DataArray>");
            }
            VtkEncoding::Ascii => {
                let _ = writeln!(
                    self.out,
                    "{ind}<DataArray type=\"{}\"{name_attr} NumberOfComponents=\"{components}\" format=\"ascii\">",
                    payload.type_name()
                );
                let per_line = if components > 1 { components * 3 } else { 9 };
                self.out
                    .push_str(&payload.ascii(per_line, &format!("{ind}  ")));
                let _ = writeln!(self.out, "{ind}</DataArray>");
            }
        }
        Ok(())
    }
}

/// Refuses (naming the array and index) a NaN or infinite point coordinate or data value:
/// never written to a file.
fn check_finite(
    path: &Path,
    points: &[[f64; 3]],
    point_data: &[DataArray],
    cell_data: &[DataArray],
) -> Result<(), OutputError> {
    if let Some(i) = points.iter().position(|p| p.iter().any(|x| !x.is_finite())) {
        return Err(OutputError::invalid(
            path,
            format!(
                "point {i} is {:?}: non-finite values are never written",
                points[i]
            ),
        ));
    }
    for (kind, arrays) in [("point", point_data), ("cell", cell_data)] {
        for a in arrays {
            if let Some(k) = a.values.iter().position(|x| !x.is_finite()) {
                return Err(OutputError::invalid(
                    path,
                    format!(
                        "{kind} data {:?}, value {k} is {}: non-finite values are never written",
                        a.name, a.values[k]
                    ),
                ));
            }
        }
    }
    Ok(())
}
