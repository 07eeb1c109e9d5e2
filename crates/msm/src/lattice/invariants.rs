//! The invariants of a lattice ([`SpringLattice::validate`]).

use super::*;

impl SpringLattice {
    /// Checks the invariants every computation relies on: at least one and at most
    /// [`MAX_NODES`] nodes, per-node arrays of one length, finite positions and gravity,
    /// masses `> 0`, damping `≥ 0`, springs naming existing nodes, `k ≥ 0`, weight `> 0`,
    /// axial damping `≥ 0`, rest length `≥ 0`, every value finite, and no spring of zero length
    /// at the initial positions; hinges on four distinct existing nodes, `k ≥ 0`, weight `> 0`,
    /// rest angle in `[−π, π]`, both triangles of positive area at the initial positions;
    /// triangles on three distinct existing nodes. Also `params` and `grid`, when present,
    /// must match the number of nodes.
    pub fn validate(&self) -> Result<(), MsmError> {
        let n = self.positions.len();
        if n > MAX_NODES {
            return Err(MsmError::TooLarge { nodes: n });
        }
        if n == 0 {
            return Err(MsmError::InvalidParameter {
                name: "number of nodes".into(),
                value: 0.0,
            });
        }
        for (what, len) in [
            ("masses", self.masses.len()),
            ("damping", self.damping.len()),
            ("fixed", self.fixed.len()),
        ] {
            if len != n {
                return Err(MsmError::LengthMismatch {
                    what,
                    expected: n,
                    found: len,
                });
            }
        }
        if let Some(p) = &self.params
            && p.len() != n
        {
            return Err(MsmError::LengthMismatch {
                what: "params",
                expected: n,
                found: p.len(),
            });
        }
        if let Some((n_u, n_v)) = self.grid
            && n_u.checked_mul(n_v) != Some(n)
        {
            return Err(MsmError::LengthMismatch {
                what: "grid n_u × n_v",
                expected: n,
                found: n_u.saturating_mul(n_v),
            });
        }
        for (a, x) in self.positions.iter().enumerate() {
            if let Some(&v) = x.iter().find(|v| !representable(**v)) {
                return Err(MsmError::NonFinite {
                    what: "position of node",
                    index: a,
                    value: v,
                });
            }
        }
        for (a, &m) in self.masses.iter().enumerate() {
            if !representable(m) {
                return Err(MsmError::NonFinite {
                    what: "mass of node",
                    index: a,
                    value: m,
                });
            }
            if m <= 0.0 {
                return Err(MsmError::NonPositiveMass { node: a, mass: m });
            }
        }
        for (a, &g) in self.damping.iter().enumerate() {
            if !representable(g) {
                return Err(MsmError::NonFinite {
                    what: "damping of node",
                    index: a,
                    value: g,
                });
            }
            if g < 0.0 {
                return Err(MsmError::InvalidParameter {
                    name: format!("damping of node {a} (must be ≥ 0)"),
                    value: g,
                });
            }
        }
        if let Some(&g) = self.gravity.iter().find(|g| !representable(**g)) {
            return Err(MsmError::NonFinite {
                what: "gravity component",
                index: 0,
                value: g,
            });
        }
        for (s, spring) in self.springs.iter().enumerate() {
            for node in [spring.a, spring.b] {
                if node >= n {
                    return Err(MsmError::MissingNode {
                        of: "spring",
                        index: s,
                        node,
                        n_nodes: n,
                    });
                }
            }
            if !representable(spring.k) {
                return Err(MsmError::NonFinite {
                    what: "stiffness of spring",
                    index: s,
                    value: spring.k,
                });
            }
            if spring.k < 0.0 {
                return Err(MsmError::NegativeStiffness {
                    spring: s,
                    k: spring.k,
                });
            }
            if !representable(spring.rest_length) {
                return Err(MsmError::NonFinite {
                    what: "rest length of spring",
                    index: s,
                    value: spring.rest_length,
                });
            }
            if spring.rest_length < 0.0 {
                return Err(MsmError::InvalidParameter {
                    name: format!("rest length of spring {s} (must be ≥ 0)"),
                    value: spring.rest_length,
                });
            }
            if !(representable(spring.weight) && spring.weight > 0.0) {
                return Err(MsmError::InvalidParameter {
                    name: format!("weight of spring {s} (must be in (0, 1e30])"),
                    value: spring.weight,
                });
            }
            if !(representable(spring.damping) && spring.damping >= 0.0) {
                return Err(MsmError::InvalidParameter {
                    name: format!("axial damping of spring {s} (must be in [0, 1e30])"),
                    value: spring.damping,
                });
            }
            let d = sub(self.positions[spring.a], self.positions[spring.b]);
            if d == [0.0; 3] {
                return Err(MsmError::ZeroLengthSpring {
                    spring: s,
                    a: spring.a,
                    b: spring.b,
                });
            }
        }
        for (e, el) in self.elements.iter().enumerate() {
            let bad = |what: String, value: f64| MsmError::InvalidElement {
                element: e,
                what,
                value,
            };
            if !(2..=4).contains(&el.nodes.len()) || el.coefficients.len() != el.nodes.len() {
                return Err(bad(
                    format!(
                        "{} nodes and {} coefficients (2 to 4 nodes, one coefficient each)",
                        el.nodes.len(),
                        el.coefficients.len()
                    ),
                    el.nodes.len() as f64,
                ));
            }
            for (i, &a) in el.nodes.iter().enumerate() {
                if a >= n {
                    return Err(MsmError::MissingNode {
                        of: "linear element",
                        index: e,
                        node: a,
                        n_nodes: n,
                    });
                }
                if el.nodes[..i].contains(&a) {
                    return Err(bad(format!("node {a} listed twice"), a as f64));
                }
            }
            if let Some(&c) = el.coefficients.iter().find(|c| !representable(**c)) {
                return Err(bad("coefficient (must be finite, |c| ≤ 1e30)".into(), c));
            }
            if !(representable(el.weight) && el.weight > 0.0) {
                return Err(bad("weight (must be in (0, 1e30])".into(), el.weight));
            }
            if !(representable(el.k) && el.k >= 0.0) {
                return Err(bad("constant k (must be in [0, 1e30])".into(), el.k));
            }
        }
        for (i, h) in self.hinges.iter().enumerate() {
            let bad = |what: String, value: f64| MsmError::InvalidHinge {
                hinge: i,
                what,
                value,
            };
            for (slot, &a) in h.nodes.iter().enumerate() {
                if a >= n {
                    return Err(MsmError::MissingNode {
                        of: "hinge",
                        index: i,
                        node: a,
                        n_nodes: n,
                    });
                }
                if h.nodes[..slot].contains(&a) {
                    return Err(bad(format!("nodes (node {a} listed twice)"), a as f64));
                }
            }
            if !(representable(h.k) && h.k >= 0.0) {
                return Err(bad("constant k (must be in [0, 1e30])".into(), h.k));
            }
            if !(representable(h.weight) && h.weight > 0.0) {
                return Err(bad("weight (must be in (0, 1e30])".into(), h.weight));
            }
            if h.rest_angle.is_nan() || h.rest_angle.abs() > std::f64::consts::PI {
                return Err(bad(
                    "rest_angle (radians, must be in [-pi, pi])".into(),
                    h.rest_angle,
                ));
            }
            let x = h.nodes.map(|a| self.positions[a]);
            if !angle(&x).is_finite() || degenerate(&x) {
                return Err(bad(
                    "triangles (one of its two triangles has zero area at the initial positions)"
                        .into(),
                    f64::NAN,
                ));
            }
        }
        for (i, t) in self.triangles.iter().enumerate() {
            for (slot, &a) in t.iter().enumerate() {
                if a >= n {
                    return Err(MsmError::MissingNode {
                        of: "triangle",
                        index: i,
                        node: a,
                        n_nodes: n,
                    });
                }
                if t[..slot].contains(&a) {
                    return Err(MsmError::InvalidParameter {
                        name: format!("triangle {i}: node {a} listed twice"),
                        value: a as f64,
                    });
                }
            }
        }
        if !self.forces.is_empty() && self.forces.len() != n {
            return Err(MsmError::LengthMismatch {
                what: "node forces",
                expected: n,
                found: self.forces.len(),
            });
        }
        if let Some((a, &v)) = self
            .forces
            .iter()
            .enumerate()
            .find_map(|(a, f)| f.iter().find(|x| !representable(**x)).map(|v| (a, v)))
        {
            return Err(MsmError::NonFinite {
                what: "force on node",
                index: a,
                value: v,
            });
        }
        Ok(())
    }
}
