//! # nurbspring-exchange
//!
//! NURBS curves and surfaces in and out of three exchange formats:
//!
//! - [`geomdl`]: the JSON of geomdl's `exchange.export_json` / `import_json` (NURBS-Python),
//! - [`iges`]: IGES 5.3 fixed-format ASCII files, entities 126 (rational B-spline curve) and
//!   128 (rational B-spline surface), as Open CASCADE and most CAD systems write and read them,
//! - [`obj`]: Wavefront OBJ free-form geometry (`cstype rat bspline`, `curv`, `surf`).
//!
//! Every reader takes the text and nothing else, never panics on malformed input, and names the
//! place of each problem ([`Location`]: for IGES the 1-based line in the file and its section).
//! Every writer prints numbers with Rust's shortest round-trip formatting, so write → read gives
//! back the same doubles bit for bit, and write → read → write the same text.
//!
//! ```
//! use nurbspring_exchange::{Shape, geomdl, iges, obj};
//! use nurbspring_geom::{KnotVector, NurbsCurve};
//!
//! // A rational quadratic quarter circle.
//! let knots = KnotVector::try_new(vec![0., 0., 0., 1., 1., 1.], 2).unwrap();
//! let w = std::f64::consts::FRAC_1_SQRT_2;
//! let arc = NurbsCurve::try_new(knots, vec![[1., 0., 0.], [1., 1., 0.], [0., 1., 0.]],
//!     vec![1.0, w, 1.0]).unwrap();
//! let shapes = vec![Shape::Curve(arc.clone())];
//!
//! // geomdl JSON: the same curve comes back, bit for bit.
//! let json = geomdl::write(&shapes).unwrap();
//! assert_eq!(geomdl::read(&json).unwrap(), shapes);
//!
//! // IGES: an entity 126 in 80-column records; the report says what was read and skipped.
//! let text = iges::write(&shapes);
//! assert!(text.lines().all(|l| l.chars().count() == 80));
//! let report = iges::read(&text).unwrap();
//! assert_eq!(report.shapes, shapes);
//! assert_eq!(report.entities[0].entity_type, 126);
//! assert!(report.skipped.is_empty());
//!
//! // OBJ free-form: `cstype rat bspline`, `curv`, `parm u`, `end`.
//! let text = obj::write(&shapes);
//! assert!(text.contains("cstype rat bspline"));
//! assert_eq!(obj::read(&text).unwrap(), shapes);
//!
//! // Errors say where: here a weight of zero in the Parameter Data section.
//! let broken = iges::write(&shapes).replacen("0.7071067811865476", "0.0               ", 1);
//! let err = iges::read(&broken).unwrap_err().to_string();
//! assert!(err.starts_with("line 7 (Parameter Data (P) section): weight 1 is 0"), "{err}");
//! ```

mod error;
mod fmt;
mod fsio;
pub mod geomdl;
pub mod iges;
pub mod obj;

pub use error::{ExchangeError, Location, Section};
pub use fsio::{BoundedReadError, MAX_FILE_BYTES, read_text_bounded};

use nurbspring_geom::{NurbsCurve, NurbsSurface};

/// A shape in an exchange file.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// A NURBS curve.
    Curve(NurbsCurve),
    /// A NURBS surface (control point `(i, j)`, i along u, at flat index `i · n_v + j`).
    Surface(NurbsSurface),
}

impl Shape {
    /// The curve, if this is one.
    pub fn as_curve(&self) -> Option<&NurbsCurve> {
        match self {
            Shape::Curve(c) => Some(c),
            Shape::Surface(_) => None,
        }
    }

    /// The surface, if this is one.
    pub fn as_surface(&self) -> Option<&NurbsSurface> {
        match self {
            Shape::Surface(s) => Some(s),
            Shape::Curve(_) => None,
        }
    }
}

impl From<NurbsCurve> for Shape {
    fn from(c: NurbsCurve) -> Self {
        Shape::Curve(c)
    }
}

impl From<NurbsSurface> for Shape {
    fn from(s: NurbsSurface) -> Self {
        Shape::Surface(s)
    }
}
