//! Errors of the exchange formats.

use std::fmt;
use std::path::PathBuf;

use nurbspring_geom::GeomError;

/// The five sections of an IGES file (fixed ASCII form), by their letter in column 73.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Section {
    /// `S`: free text for people.
    Start,
    /// `G`: the Global section (delimiters, units, …).
    Global,
    /// `D`: the Directory Entry section, two lines per entity.
    Directory,
    /// `P`: the Parameter Data section.
    Parameter,
    /// `T`: the Terminate line with the section line counts.
    Terminate,
}

impl Section {
    /// The letter in column 73.
    pub fn letter(self) -> char {
        match self {
            Section::Start => 'S',
            Section::Global => 'G',
            Section::Directory => 'D',
            Section::Parameter => 'P',
            Section::Terminate => 'T',
        }
    }

    /// The section of a column-73 letter.
    pub fn from_letter(c: char) -> Option<Self> {
        Some(match c {
            'S' => Section::Start,
            'G' => Section::Global,
            'D' => Section::Directory,
            'P' => Section::Parameter,
            'T' => Section::Terminate,
            _ => return None,
        })
    }

    /// The section's name in the IGES specification.
    pub fn name(self) -> &'static str {
        match self {
            Section::Start => "Start",
            Section::Global => "Global",
            Section::Directory => "Directory Entry",
            Section::Parameter => "Parameter Data",
            Section::Terminate => "Terminate",
        }
    }
}

impl fmt::Display for Section {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} ({})", self.name(), self.letter())
    }
}

/// Where in the input something is wrong.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Location {
    /// An IGES line: 1-based line number in the file and its section.
    Iges {
        /// 1-based line number in the file.
        line: usize,
        /// The section the line belongs to (`None` when column 73 is unreadable).
        section: Option<Section>,
    },
    /// A 1-based line (and column, where known; 0 when not) of a text file (OBJ, JSON syntax).
    Line {
        /// 1-based line number.
        line: usize,
        /// 1-based column, 0 when unknown.
        column: usize,
    },
    /// A value inside a JSON document, as a path like `shape.data[0].knotvector[3]`.
    Json {
        /// The path from the document root.
        path: String,
    },
    /// The input as a whole.
    Whole,
}

impl Location {
    /// An IGES line of a known section.
    pub fn iges(line: usize, section: Section) -> Self {
        Location::Iges {
            line,
            section: Some(section),
        }
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::Iges {
                line,
                section: Some(s),
            } => write!(f, "line {line} ({s} section)"),
            Location::Iges {
                line,
                section: None,
            } => write!(f, "line {line}"),
            Location::Line { line, column: 0 } => write!(f, "line {line}"),
            Location::Line { line, column } => write!(f, "line {line}, column {column}"),
            Location::Json { path } => write!(f, "at {path}"),
            Location::Whole => write!(f, "in the input"),
        }
    }
}

/// Everything that can go wrong reading or writing an exchange file. Messages name the place
/// ([`Location`]: for IGES the 1-based line in the file and its section) and the offending value.
#[derive(Debug, thiserror::Error)]
pub enum ExchangeError {
    /// The operating system refused to open, inspect or read a file.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// A file larger than the reading limit.
    #[error("{}: the file is larger than the limit of {limit} bytes", path.display())]
    FileTooLarge {
        /// The file.
        path: PathBuf,
        /// The limit in bytes.
        limit: u64,
    },
    /// A path that is a directory, FIFO, device, … rather than a regular file.
    #[error("{}: not a regular file", path.display())]
    NotRegularFile {
        /// The path.
        path: PathBuf,
    },
    /// A file that is not UTF-8 text.
    #[error("{}: not UTF-8 text (invalid byte sequence at byte offset {offset})", path.display())]
    NotText {
        /// The file.
        path: PathBuf,
        /// Offset of the first invalid byte.
        offset: usize,
    },
    /// A record, statement or document that does not follow the format's syntax.
    #[error("{at}: malformed record: {detail}")]
    Malformed {
        /// Where.
        at: Location,
        /// What is wrong, quoting the text.
        detail: String,
    },
    /// IGES fixed columns that are not where the format puts them (line length, column 73,
    /// sequence numbers, the blank column 65 of Parameter Data lines).
    #[error("{at}: wrong column layout: {detail}")]
    ColumnLayout {
        /// Where.
        at: Location,
        /// What is wrong.
        detail: String,
    },
    /// A pointer (IGES Directory Entry pointer, OBJ vertex index) to something that is not there,
    /// or a required key / parameter that is absent.
    #[error("{at}: missing entity: {detail}")]
    MissingEntity {
        /// Where the reference or the gap is.
        at: Location,
        /// What is missing.
        detail: String,
    },
    /// An IGES entity of a type this reader cannot turn into a NURBS shape where one was asked for.
    #[error("{at}: unsupported entity type {entity_type} ({name}): {detail}")]
    UnsupportedEntity {
        /// The entity's Directory Entry.
        at: Location,
        /// The IGES entity type number.
        entity_type: u32,
        /// Its name in the IGES specification.
        name: &'static str,
        /// Why it was wanted and what was done.
        detail: String,
    },
    /// An IGES file without a single rational B-spline curve (126) or surface (128).
    #[error(
        "no rational B-spline curve (entity 126) or surface (entity 128) in the file{}",
        if detail.is_empty() { String::new() } else { format!(": {detail}") }
    )]
    NoGeometry {
        /// What the file holds instead (unsupported geometric entities with their lines).
        detail: String,
    },
    /// A feature of a format that this crate does not read (binary IGES, geomdl volumes, OBJ
    /// trimming loops, …).
    #[error("{at}: unsupported: {detail}")]
    Unsupported {
        /// Where.
        at: Location,
        /// What is not supported.
        detail: String,
    },
    /// A weight that is zero, negative or not finite.
    #[error("{at}: weight {index} is {value}; weights must be positive and finite")]
    InvalidWeight {
        /// Where the weight is written.
        at: Location,
        /// Index of the weight in the file's order.
        index: usize,
        /// The value.
        value: f64,
    },
    /// Knot, degree and control point counts that do not fit together.
    #[error("{at}: inconsistent knot count: {detail}")]
    KnotCount {
        /// Where.
        at: Location,
        /// The counts.
        detail: String,
    },
    /// A number that is NaN, infinite or overflows a double.
    #[error("{at}: {what} is not a finite number ({text})")]
    NonFinite {
        /// Where.
        at: Location,
        /// Which value.
        what: String,
        /// As written.
        text: String,
    },
    /// Data that is readable but not a valid NURBS (decreasing knots, too high multiplicity, …).
    #[error("{at}: {source}")]
    Geometry {
        /// Where the shape is defined.
        at: Location,
        /// The geometry crate's verdict.
        #[source]
        source: GeomError,
    },
    /// Shapes that the requested format cannot hold together (geomdl JSON holds one kind).
    #[error("cannot write: {detail}")]
    Unwritable {
        /// Why.
        detail: String,
    },
}

impl ExchangeError {
    /// Shorthand for [`ExchangeError::Malformed`].
    pub(crate) fn malformed(at: Location, detail: impl Into<String>) -> Self {
        ExchangeError::Malformed {
            at,
            detail: detail.into(),
        }
    }

    /// The location the error names, if it names one.
    pub fn location(&self) -> Option<&Location> {
        match self {
            ExchangeError::Malformed { at, .. }
            | ExchangeError::ColumnLayout { at, .. }
            | ExchangeError::MissingEntity { at, .. }
            | ExchangeError::UnsupportedEntity { at, .. }
            | ExchangeError::Unsupported { at, .. }
            | ExchangeError::InvalidWeight { at, .. }
            | ExchangeError::KnotCount { at, .. }
            | ExchangeError::NonFinite { at, .. }
            | ExchangeError::Geometry { at, .. } => Some(at),
            _ => None,
        }
    }
}
