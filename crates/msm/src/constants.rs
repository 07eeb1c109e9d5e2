//! Element classes and the constants that go with them: `K_S = Σ_c k_c G_c` (paper eq. (10),
//! docs/math.md §5), one constant per class.
//!
//! [`Class`] names every class of elements a lattice can hold; [`Constants`] maps classes to
//! their constants and is the one form of "spring constants" used by lattice options, fits,
//! command-line overrides and reports. A new class is a new [`Class`] variant with its names.

use std::collections::BTreeMap;

use serde::ser::{Serialize, SerializeMap, Serializer};

use crate::{HingeKind, LinearKind, Region, SpringKind};

/// A class of elements sharing one constant.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Class {
    /// The springs (paper eq. (5)) of one kind.
    Spring(SpringKind),
    /// The linear isotropic elements of one kind in one region.
    Linear(LinearKind, Region),
    /// The hinges (dihedral-angle bending, docs/math.md §5.2) of one kind.
    Hinge(HingeKind),
}

impl Class {
    /// Every spring class, in report order.
    pub const SPRINGS: [Class; 3] = [
        Class::Spring(SpringKind::Structural),
        Class::Spring(SpringKind::Shear),
        Class::Spring(SpringKind::Bend),
    ];

    /// Every hinge class, in report order.
    pub const HINGES: [Class; 2] = [
        Class::Hinge(HingeKind::Grid),
        Class::Hinge(HingeKind::Diagonal),
    ];

    /// Every linear class of `kinds`, interior then boundary for each kind.
    pub fn linear(kinds: &[LinearKind]) -> Vec<Class> {
        kinds
            .iter()
            .flat_map(|&k| Region::ALL.map(|r| Class::Linear(k, r)))
            .collect()
    }

    /// The name of the class in files and messages: `"structural"`, `"shear"`, `"bend"` for
    /// springs, `"kind@region"` for linear elements (`"bend_u@boundary"`), `"hinge"` and
    /// `"hinge_diagonal"` for hinges.
    pub fn name(self) -> String {
        match self {
            Class::Spring(kind) => kind.name().to_string(),
            Class::Linear(kind, region) => format!("{}@{}", kind.name(), region.name()),
            Class::Hinge(kind) => kind.name().to_string(),
        }
    }

    /// Parses a [`Class::name`].
    ///
    /// ```
    /// use nurbspring_msm::{Class, HingeKind};
    /// assert_eq!(Class::parse("hinge_diagonal"), Some(Class::Hinge(HingeKind::Diagonal)));
    /// ```
    pub fn parse(s: &str) -> Option<Class> {
        if let Some((kind, region)) = s.split_once('@') {
            let region = Region::ALL.into_iter().find(|r| r.name() == region)?;
            return Some(Class::Linear(LinearKind::parse(kind)?, region));
        }
        if s.starts_with("hinge") {
            return HingeKind::parse(s).map(Class::Hinge);
        }
        SpringKind::parse(s).map(Class::Spring)
    }

    /// True for a class of springs or hinges (elements with a rest state, rotation invariant),
    /// false for linear elements.
    pub fn is_nonlinear(self) -> bool {
        !matches!(self, Class::Linear(..))
    }

    /// The symbol of its constant: as the paper writes it for springs (`k_edge`, `k_diag`,
    /// `k_bend`), `k_hinge` and `k_hinge_diag` for hinges, the class name for linear elements.
    ///
    /// ```
    /// use nurbspring_msm::{Class, LinearKind, Region, SpringKind};
    /// assert_eq!(Class::Spring(SpringKind::Shear).symbol(), "k_diag");
    /// assert_eq!(Class::Linear(LinearKind::BendU, Region::Boundary).symbol(), "bend_u@boundary");
    /// ```
    pub fn symbol(self) -> String {
        match self {
            Class::Spring(SpringKind::Structural) => "k_edge".to_string(),
            Class::Spring(SpringKind::Shear) => "k_diag".to_string(),
            Class::Spring(SpringKind::Bend) => "k_bend".to_string(),
            Class::Hinge(kind) => kind.symbol().to_string(),
            Class::Linear(..) => self.name(),
        }
    }
}

impl Serialize for Class {
    /// As its [`Class::name`].
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.name())
    }
}

impl std::fmt::Display for Class {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.name())
    }
}

/// Constants by class; a class that is absent has no elements (or none that matter).
///
/// Serialized as a map from [`Class::symbol`] to the value, so `{"k_edge": 2.7, "k_diag": 0.9}`.
///
/// ```
/// use nurbspring_msm::{Class, Constants, SpringKind};
/// let k = Constants::from_pairs([(Class::Spring(SpringKind::Structural), 2.0)]);
/// assert_eq!(k.get(Class::Spring(SpringKind::Structural)), Some(2.0));
/// assert_eq!(k.value(Class::Spring(SpringKind::Shear)), 0.0);
/// assert_eq!(serde_json::to_string(&k).unwrap(), r#"{"k_edge":2.0}"#);
/// ```
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Constants(BTreeMap<Class, f64>);

impl Constants {
    /// No classes.
    pub fn new() -> Self {
        Self::default()
    }

    /// From `(class, constant)` pairs (a later pair of the same class wins).
    pub fn from_pairs(pairs: impl IntoIterator<Item = (Class, f64)>) -> Self {
        Self(pairs.into_iter().collect())
    }

    /// The classes with their constants, `classes[i]` with `values[i]`.
    pub fn from_values(classes: &[Class], values: &[f64]) -> Self {
        Self::from_pairs(classes.iter().copied().zip(values.iter().copied()))
    }

    /// The constant of `class`, if the class is present.
    pub fn get(&self, class: Class) -> Option<f64> {
        self.0.get(&class).copied()
    }

    /// The constant of `class`, 0 when it is absent.
    pub fn value(&self, class: Class) -> f64 {
        self.get(class).unwrap_or(0.0)
    }

    /// Sets (or adds) the constant of `class`.
    pub fn set(&mut self, class: Class, k: f64) {
        self.0.insert(class, k);
    }

    /// Removes a class.
    pub fn remove(&mut self, class: Class) {
        self.0.remove(&class);
    }

    /// True when `class` is present.
    pub fn contains(&self, class: Class) -> bool {
        self.0.contains_key(&class)
    }

    /// The classes present, ascending.
    pub fn classes(&self) -> Vec<Class> {
        self.0.keys().copied().collect()
    }

    /// The constants of `classes`, in that order (0 for an absent class).
    pub fn values_of(&self, classes: &[Class]) -> Vec<f64> {
        classes.iter().map(|&c| self.value(c)).collect()
    }

    /// `(class, constant)` pairs, ascending by class.
    pub fn iter(&self) -> impl Iterator<Item = (Class, f64)> + '_ {
        self.0.iter().map(|(&c, &k)| (c, k))
    }

    /// Number of classes.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// True when there is no class.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
}

impl Serialize for Constants {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(self.0.len()))?;
        for (class, k) in &self.0 {
            map.serialize_entry(&class.symbol(), k)?;
        }
        map.end()
    }
}
