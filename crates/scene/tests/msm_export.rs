//! The SOFA bending export (`msm_export::sofa_bending`, `sofa_bending_stiffness`): the
//! components hold every hinge once, each component's topology makes bending springs on exactly
//! its hinges (SOFA's `FastTriangularBendingSprings` puts one on every edge two of its
//! triangles share), and the converted stiffness gives SOFA's energy our `½ k w θ²` to second
//! order; the difference at larger angles and under in-plane motion is measured here, with
//! SOFA's energy written out from its source (`EdgeSpring::setEdgeSpring` and `addForce`).

use std::collections::{BTreeMap, BTreeSet};

use nurbspring_geom::{KnotVector, NurbsSurface};
use nurbspring_msm::{
    Class, Constants, HingeKind, LatticeOptions, ParameterGrid, SpringKind, SpringLattice,
};
use nurbspring_scene::msm_export::{sofa_bending, sofa_bending_stiffness};

fn sheet(n_u: usize, n_v: usize, lift: f64) -> SpringLattice {
    let k = KnotVector::try_new(vec![0., 0., 1., 1.], 1).unwrap();
    let pts = vec![
        [0., 0., 0.],
        [0., 0.8, lift],
        [1.2, 0., lift],
        [1.2, 0.8, 0.],
    ];
    let surface = NurbsSurface::try_new(k.clone(), k, pts, vec![1.0; 4]).unwrap();
    let options = LatticeOptions {
        grid: ParameterGrid::Uniform {
            nodes_u: n_u,
            nodes_v: n_v,
        },
        constants: Constants::from_pairs([
            (Class::Spring(SpringKind::Structural), 10.0),
            (Class::Spring(SpringKind::Shear), 4.0),
            (Class::Hinge(HingeKind::Grid), 0.02),
            (Class::Hinge(HingeKind::Diagonal), 0.01),
        ]),
        ..Default::default()
    };
    SpringLattice::triangulated(&surface, &options, &[]).unwrap()
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// SOFA's `FastTriangularBendingSprings` energy of one edge spring, as its source has it: wings
/// A, B, edge C–D, `alpha` and `lambda` from the rest positions `p`, energy `½ λ |R|²` with
/// `R = Σ alpha_i x_i` at the current positions `x`.
fn sofa_energy(p: &[[f64; 3]; 4], x: &[[f64; 3]; 4], bending_stiffness: f64) -> f64 {
    // Our hinge [x0, x1, x2, x3] (edge x0–x1, wings x2, x3) in SOFA's order A, B, C, D.
    let [c, d, a, b] = [0, 1, 2, 3];
    let na = norm(cross(sub(p[a], p[c]), sub(p[a], p[d])));
    let nb = norm(cross(sub(p[b], p[d]), sub(p[b], p[c])));
    let nc = norm(cross(sub(p[c], p[b]), sub(p[c], p[a])));
    let nd = norm(cross(sub(p[d], p[a]), sub(p[d], p[b])));
    let alpha = [
        nb / (na + nb),
        na / (na + nb),
        -nd / (nc + nd),
        -nc / (nc + nd),
    ];
    let l = norm(sub(p[c], p[d]));
    let dir = sub(p[c], p[d]).map(|v| v / l);
    let height = |v: [f64; 3]| {
        let s = v[0] * dir[0] + v[1] * dir[1] + v[2] * dir[2];
        norm([v[0] - s * dir[0], v[1] - s * dir[1], v[2] - s * dir[2]])
    };
    let (ha, hb) = (height(sub(p[c], p[a])), height(sub(p[c], p[b])));
    let lambda = 2.0 / 3.0 * (ha + hb) / (ha * ha * hb * hb) * l * bending_stiffness;
    let mut r = [0.0; 3];
    for (i, &node) in [a, b, c, d].iter().enumerate() {
        for k in 0..3 {
            r[k] += alpha[i] * x[node][k];
        }
    }
    0.5 * lambda * (r[0] * r[0] + r[1] * r[1] + r[2] * r[2])
}

/// Folds the hinge `p` (flat) by the angle `theta` about its edge: wing x3 rotates.
fn folded(p: &[[f64; 3]; 4], theta: f64) -> [[f64; 3]; 4] {
    let e = sub(p[1], p[0]);
    let l = norm(e);
    let u = e.map(|v| v / l);
    let w = sub(p[3], p[0]);
    let (c, s) = (theta.cos(), theta.sin());
    let uxw = cross(u, w);
    let udw = u[0] * w[0] + u[1] * w[1] + u[2] * w[2];
    let rotated: [f64; 3] =
        std::array::from_fn(|k| p[0][k] + w[k] * c + uxw[k] * s + u[k] * udw * (1.0 - c));
    [p[0], p[1], p[2], rotated]
}

#[test]
fn sofa_components_hold_every_hinge_once_and_nothing_else() {
    let mut lattice = sheet(6, 5, 0.0);
    // Three weights among the grid hinges: several stiffnesses, so several components.
    let n_grid = lattice.count(Class::Hinge(HingeKind::Grid));
    let weights: Vec<f64> = (0..n_grid).map(|i| 1.0 + 0.5 * (i % 3) as f64).collect();
    lattice
        .set_weights(Class::Hinge(HingeKind::Grid), &weights)
        .unwrap();
    let components = sofa_bending(&lattice).unwrap();
    assert!(components.len() >= 3, "{} components", components.len());
    let mut seen = vec![0usize; lattice.hinges.len()];
    for c in &components {
        let mut count: BTreeMap<(usize, usize), usize> = BTreeMap::new();
        for t in &c.triangles {
            for k in 0..3 {
                let (p, q) = (t[k], t[(k + 1) % 3]);
                *count.entry((p.min(q), p.max(q))).or_default() += 1;
            }
        }
        assert!(count.values().all(|&n| n <= 2));
        let shared: BTreeSet<(usize, usize)> = count
            .iter()
            .filter(|(_, n)| **n == 2)
            .map(|(e, _)| *e)
            .collect();
        let own: BTreeSet<(usize, usize)> = c
            .hinges
            .iter()
            .map(|&h| {
                let [a, b, ..] = lattice.hinges[h].nodes;
                (a.min(b), a.max(b))
            })
            .collect();
        assert_eq!(shared, own, "a component's bending springs are its hinges");
        for &h in &c.hinges {
            seen[h] += 1;
            let hinge = &lattice.hinges[h];
            let b = sofa_bending_stiffness(
                &hinge.nodes.map(|a| lattice.positions[a]),
                hinge.stiffness(),
            );
            assert!((b - c.stiffness).abs() <= 1e-12 * b);
        }
    }
    assert!(seen.iter().all(|&n| n == 1), "every hinge exactly once");
}

#[test]
fn sofa_refuses_a_curved_rest_shape() {
    let lattice = sheet(4, 4, 0.2);
    let message = sofa_bending(&lattice).unwrap_err();
    assert!(message.contains("rest angle"), "{message}");
    assert!(
        message.contains("FastTriangularBendingSprings"),
        "{message}"
    );
}

/// SOFA's energy with the converted stiffness against ours, `½ k w θ²`, on every hinge of a
/// flat sheet folded by θ: equal to second order (the ratio → 1 as θ → 0), and the measured
/// difference at larger angles (docs/export.md quotes these bounds).
#[test]
fn sofa_bending_energy_matches_ours_to_second_order() {
    let lattice = sheet(5, 4, 0.0);
    let mut worst = [0.0_f64; 4];
    let angles = [1e-3, 0.1, 0.5, 1.0];
    for h in &lattice.hinges {
        let p = h.nodes.map(|a| lattice.positions[a]);
        let kw = h.stiffness();
        let b = sofa_bending_stiffness(&p, kw);
        assert!(
            sofa_energy(&p, &p, b) <= 1e-28 * b,
            "flat rest state is stress-free"
        );
        for (w, &theta) in worst.iter_mut().zip(&angles) {
            let ours = 0.5 * kw * theta * theta;
            let sofa = sofa_energy(&p, &folded(&p, theta), b);
            *w = w.max((sofa / ours - 1.0).abs());
        }
    }
    eprintln!("|E_sofa / E_ours - 1| at theta = {angles:?}: {worst:?}");
    // SOFA's |R| is the chord the folded wing moves, not its arc: |R| = 2 sin(θ/2) h_A h_B /
    // (h_A + h_B), so E_sofa / E_ours = (2 sin(θ/2) / θ)² on every hinge.
    for (w, &theta) in worst.iter().zip(&angles) {
        let expected = 1.0 - (2.0 * (0.5 * theta).sin() / theta).powi(2);
        assert!((w - expected).abs() <= 1e-9, "{w} vs {expected} at {theta}");
    }
    assert!(worst[0] < 1e-6);
}

/// What SOFA's bending adds that ours has not: an in-plane shear of the flat pair (no change
/// of the dihedral angle, so no energy of ours) has an energy in SOFA's (its `alpha` are fixed
/// at rest), of order `D / h²` times the squared in-plane displacement.
#[test]
fn sofa_bending_stiffens_in_plane_motion() {
    let lattice = sheet(3, 3, 0.0);
    let h = &lattice.hinges[0];
    let p = h.nodes.map(|a| lattice.positions[a]);
    let b = sofa_bending_stiffness(&p, h.stiffness());
    let mut x = p;
    let shift = 1e-3;
    x[2][0] += shift;
    let mut all: Vec<f64> = lattice.positions.concat();
    for k in 0..3 {
        all[3 * h.nodes[2] + k] = x[2][k];
    }
    assert!(h.energy(&all) <= 1e-30, "ours: {}", h.energy(&all));
    let sofa = sofa_energy(&p, &x, b);
    assert!(sofa > 0.0, "SOFA's energy of an in-plane shift is {sofa}");
    eprintln!(
        "in-plane shift {shift}: SOFA energy {sofa:.3e}, ours 0; per unit k w and shift²: {:.3}",
        sofa / (h.stiffness() * shift * shift)
    );
}
