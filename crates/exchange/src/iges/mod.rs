//! IGES 5.3 (ANSI US PRO/IPO-100) fixed-format ASCII files: rational B-spline curves
//! (entity 126) and surfaces (entity 128).
//!
//! # The file
//!
//! Every record is 80 columns: data in 1–72, the section letter in 73 (`S` Start, `G` Global,
//! `D` Directory Entry, `P` Parameter Data, `T` Terminate), a sequence number in 74–80 counting
//! from 1 in each section. The Global section is free format: its first two parameters name the
//! parameter delimiter (default `,`) and the record delimiter (default `;`) as Hollerith
//! strings (`1H,`), and every later string is Hollerith too (`5HHello`). Each entity has two
//! Directory Entry lines of ten 8-column fields and a Parameter Data record in columns 1–64 of
//! one or more `P` lines whose columns 66–72 point back to the entity's first D line.
//!
//! # What is read
//!
//! - **126** `K, M, PROP1–4, T(−M..N+M), W(0..K), (X, Y, Z)(0..K), V(0), V(1), normal`:
//!   a [`NurbsCurve`](nurbspring_geom::NurbsCurve) of degree `M` with `K + 1` control points.
//! - **128** `K1, K2, M1, M2, PROP1–5, S(..), T(..), W(i, j), (X, Y, Z)(i, j), U(0), U(1), V(0),
//!   V(1)`: weights and points are listed with the first (u) index fastest,
//!   `W(0,0), W(1,0), …, W(K1,0), W(0,1), …`; file position `m = j (K1 + 1) + i` becomes
//!   nurbspring's `k = i n_v + j`.
//! - **124** transformation matrices that a 126/128 points to (Directory Entry field 7), chained
//!   through their own field 7, are applied to the control points (`x' = R x + T`; an affine map
//!   of a NURBS is the NURBS of the mapped control points).
//! - **143** bounded surface, **144** trimmed surface and **510** face: their underlying surface is
//!   imported untrimmed when it is a 128 (a note says so); when it is another surface type it is
//!   reported as unsupported, with its type number.
//! - Everything else is skipped and listed in [`ReadReport::skipped`] with the reason: colors
//!   (314), properties (406), associativities (402), views, annotation, B-rep topology (186, 502,
//!   504, 508, 514), and unsupported geometry (lines, arcs, analytic surfaces, …).
//!
//! A file without any 126 or 128 is an error. The Global section's model-space scale and units are
//! reported in [`Global`] and not applied: coordinates are returned as written.
//!
//! # What is written
//!
//! Independent 126/128 entities (status `00000000`, form 0) in an IGES 5.3 file with units of
//! millimetres by default, which Open CASCADE's `IGESControl_Reader` reads as edges and faces.
//! Reals are written with Rust's shortest round-trip digits (`0.7071067811865476`, `1.0E-7`), so
//! nothing is lost.

mod read;
mod records;
mod write;

use std::path::Path;

pub use read::read;
pub use write::{WriteOptions, write, write_with};

use crate::{ExchangeError, Shape, fsio};

/// What [`read()`] found in an IGES file.
#[derive(Clone, Debug, PartialEq)]
pub struct ReadReport {
    /// Every entity 126 and 128, in Directory Entry order.
    pub shapes: Vec<Shape>,
    /// For each shape (same index), where it came from and its IGES flags.
    pub entities: Vec<EntityInfo>,
    /// Every other entity, with the reason it was not imported.
    pub skipped: Vec<Skipped>,
    /// Remarks for people: wrappers whose surface was imported untrimmed, parameter ranges
    /// narrower than the knot domain, transformations applied, …
    pub notes: Vec<String>,
    /// The Global section.
    pub global: Global,
    /// The Start section's text (lines joined with `\n`, trailing blanks removed).
    pub start: String,
}

/// Provenance and flags of an imported 126 or 128.
#[derive(Clone, Debug, PartialEq)]
pub struct EntityInfo {
    /// 126 or 128.
    pub entity_type: u32,
    /// Form number (Directory Entry field 15); 0 means "shape given by the parameters".
    pub form: i64,
    /// Sequence number of the entity's first Directory Entry line (the "DE pointer", odd).
    pub de_pointer: usize,
    /// 1-based line of that Directory Entry line in the file.
    pub de_line: usize,
    /// Entity label (Directory Entry field 18), trimmed.
    pub label: String,
    /// Entity subscript (field 19).
    pub subscript: i64,
    /// Status number (field 9).
    pub status: Status,
    /// PROP1–PROP4 (126) or PROP1–PROP5 (128) as written: planar, closed, polynomial, periodic
    /// (126); closed in u, closed in v, polynomial, periodic in u, periodic in v (128).
    pub properties: Vec<i64>,
    /// The entity's parameter range `V(0), V(1)` (126) or `U(0), U(1)` (128).
    pub u_range: (f64, f64),
    /// `V(0), V(1)` of a 128.
    pub v_range: Option<(f64, f64)>,
    /// The unit normal of a planar 126 (PROP1 = 1).
    pub normal: Option<[f64; 3]>,
    /// Lines of the 124 transformation matrices applied, innermost first.
    pub transforms: Vec<usize>,
    /// Entities that refer to this one (trimmed and bounded surfaces, faces, curves on surfaces,
    /// boundaries): `(entity type, line of its Directory Entry)`.
    pub used_by: Vec<(u32, usize)>,
}

/// The Directory Entry status number, four two-digit fields.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Status {
    /// Blank status: 0 visible, 1 blanked.
    pub blank: u8,
    /// Subordinate entity switch: 0 independent, 1 physically dependent, 2 logically dependent,
    /// 3 both.
    pub subordinate: u8,
    /// Entity use flag: 0 geometry, 1 annotation, 2 definition, 3 other, 4 logical/positional,
    /// 5 2-D parametric (a curve in a surface's parameter space), 6 construction geometry.
    pub use_flag: u8,
    /// Hierarchy: 0 global top down, 1 global defer, 2 use the hierarchy property.
    pub hierarchy: u8,
}

/// Why an entity was not imported.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SkipKind {
    /// Not geometry: color, property, associativity, view, annotation, topology, null entity.
    NotGeometry,
    /// A 124 transformation matrix (applied to the entities that point to it).
    Transformation,
    /// A wrapper (143, 144, 510) whose 128 surface was imported on its own.
    Wrapper,
    /// Geometry of a type this reader does not convert (lines, arcs, analytic surfaces, …).
    UnsupportedGeometry,
}

/// An entity that [`read()`] did not import.
#[derive(Clone, Debug, PartialEq)]
pub struct Skipped {
    /// The IGES entity type number.
    pub entity_type: u32,
    /// Its form number.
    pub form: i64,
    /// 1-based line of its first Directory Entry line.
    pub de_line: usize,
    /// The kind of reason.
    pub kind: SkipKind,
    /// The reason, for people.
    pub reason: String,
}

/// The Global section's parameters (IGES 5.3 §2.2.4.3), defaults where the file leaves them out.
#[derive(Clone, Debug, PartialEq)]
pub struct Global {
    /// 1: parameter delimiter.
    pub parameter_delimiter: char,
    /// 2: record delimiter.
    pub record_delimiter: char,
    /// 3: product identification from the sending system.
    pub product_id: String,
    /// 4: file name.
    pub file_name: String,
    /// 5: native system ID.
    pub native_system: String,
    /// 6: preprocessor version.
    pub preprocessor: String,
    /// 12: product identification for the receiving system.
    pub receiver_product_id: String,
    /// 13: model space scale (metadata only: coordinates are not scaled).
    pub model_scale: f64,
    /// 14: units flag (1 inch, 2 mm, 3 see `units_name`, 4 ft, 5 mi, 6 m, 7 km, 8 mil, 9 micron,
    /// 10 cm, 11 microinch).
    pub units_flag: i64,
    /// 15: units name.
    pub units_name: String,
    /// 18: date and time of file generation.
    pub date: String,
    /// 19: minimum user-intended resolution.
    pub resolution: f64,
    /// 20: approximate maximum coordinate value.
    pub max_coordinate: f64,
    /// 21: author.
    pub author: String,
    /// 22: author's organization.
    pub organization: String,
    /// 23: version flag (11 = IGES 5.3).
    pub version: i64,
}

impl Default for Global {
    fn default() -> Self {
        Global {
            parameter_delimiter: ',',
            record_delimiter: ';',
            product_id: String::new(),
            file_name: String::new(),
            native_system: String::new(),
            preprocessor: String::new(),
            receiver_product_id: String::new(),
            model_scale: 1.0,
            units_flag: 1,
            units_name: String::new(),
            date: String::new(),
            resolution: 0.0,
            max_coordinate: 0.0,
            author: String::new(),
            organization: String::new(),
            version: 0,
        }
    }
}

impl Global {
    /// The length of one model unit in millimetres, from the units flag (and, for flag 3, the
    /// units name); `None` when unknown.
    pub fn unit_in_mm(&self) -> Option<f64> {
        let by_name = |n: &str| match n.trim().to_ascii_uppercase().as_str() {
            "IN" | "INCH" => Some(25.4),
            "MM" => Some(1.0),
            "FT" => Some(304.8),
            "MI" => Some(1_609_344.0),
            "M" => Some(1000.0),
            "KM" => Some(1_000_000.0),
            "MIL" => Some(0.0254),
            "UM" | "MICRON" => Some(0.001),
            "CM" => Some(10.0),
            "UIN" | "MICROINCH" => Some(0.0000254),
            _ => None,
        };
        match self.units_flag {
            1 => Some(25.4),
            2 => Some(1.0),
            3 => by_name(&self.units_name),
            4 => Some(304.8),
            5 => Some(1_609_344.0),
            6 => Some(1000.0),
            7 => Some(1_000_000.0),
            8 => Some(0.0254),
            9 => Some(0.001),
            10 => Some(10.0),
            11 => Some(0.0000254),
            _ => None,
        }
    }
}

/// Reads an IGES file (a regular file of at most [`crate::MAX_FILE_BYTES`]); see [`read()`].
pub fn read_file(path: impl AsRef<Path>) -> Result<ReadReport, ExchangeError> {
    read(&fsio::read_text(path.as_ref())?)
}

/// Writes shapes to an IGES file with default options; see [`write()`].
pub fn write_file(path: impl AsRef<Path>, shapes: &[Shape]) -> Result<(), ExchangeError> {
    fsio::write_text(path.as_ref(), &write(shapes))
}

/// The name of an IGES entity type in the specification (for messages).
pub fn entity_name(entity_type: u32) -> &'static str {
    match entity_type {
        0 => "null entity",
        100 => "circular arc",
        102 => "composite curve",
        104 => "conic arc",
        106 => "copious data",
        108 => "plane",
        110 => "line",
        112 => "parametric spline curve",
        114 => "parametric spline surface",
        116 => "point",
        118 => "ruled surface",
        120 => "surface of revolution",
        122 => "tabulated cylinder",
        123 => "direction",
        124 => "transformation matrix",
        125 => "flash",
        126 => "rational B-spline curve",
        128 => "rational B-spline surface",
        130 => "offset curve",
        132 => "connect point",
        134 => "node",
        136 => "finite element",
        138 => "nodal displacement and rotation",
        140 => "offset surface",
        141 => "boundary",
        142 => "curve on a parametric surface",
        143 => "bounded surface",
        144 => "trimmed (parametric) surface",
        146 => "nodal results",
        148 => "element results",
        150 => "block",
        152 => "right angular wedge",
        154 => "right circular cylinder",
        156 => "right circular cone frustum",
        158 => "sphere",
        160 => "torus",
        162 => "solid of revolution",
        164 => "solid of linear extrusion",
        168 => "ellipsoid",
        180 => "boolean tree",
        182 => "selected component",
        184 => "solid assembly",
        186 => "manifold solid B-rep object",
        190 => "plane surface",
        192 => "right circular cylindrical surface",
        194 => "right circular conical surface",
        196 => "spherical surface",
        198 => "toroidal surface",
        202 => "angular dimension",
        206 => "diameter dimension",
        208 => "flag note",
        210 => "general label",
        212 => "general note",
        213 => "new general note",
        214 => "leader (arrow)",
        216 => "linear dimension",
        218 => "ordinate dimension",
        220 => "point dimension",
        222 => "radius dimension",
        228 => "general symbol",
        230 => "sectioned area",
        302 => "associativity definition",
        304 => "line font definition",
        306 => "macro definition",
        308 => "subfigure definition",
        310 => "text font definition",
        312 => "text display template",
        314 => "color definition",
        316 => "units data",
        320 => "network subfigure definition",
        322 => "attribute table definition",
        402 => "associativity instance",
        404 => "drawing",
        406 => "property",
        408 => "singular subfigure instance",
        410 => "view",
        412 => "rectangular array subfigure instance",
        414 => "circular array subfigure instance",
        416 => "external reference",
        418 => "nodal load/constraint",
        420 => "network subfigure instance",
        422 => "attribute table instance",
        430 => "solid instance",
        502 => "vertex list",
        504 => "edge list",
        508 => "loop",
        510 => "face",
        514 => "shell",
        _ => "unknown entity type",
    }
}
