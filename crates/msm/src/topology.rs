//! Node-to-spring and node-to-hinge incidences (CSR) and the parallel force kernels.
//!
//! The moving ("active") nodes are renumbered `0 … n_active − 1` in increasing original order.
//! For each active node the incidence lists the springs at it in two parts:
//! - springs to other active nodes: the other node's active index and `(k, l)`;
//! - springs to inactive (fixed) nodes: the fixed node's constant position and `(k, l)`.
//!
//! Each node then sums its own force (paper eq. (5)) without locks: the work is split into
//! chunks of nodes with rayon, each chunk writing only its own output rows. Every spring is
//! evaluated once from each end; since `d` only changes sign, the two forces are exact
//! negatives, so the total force is zero up to the rounding of the per-node sums. Springs
//! between two fixed nodes never move: their energy is a constant, computed once.
//!
//! Hinges (docs/math.md §5.2) couple four nodes: each chunk of nodes evaluates the hinges with
//! a node in the chunk (a hinge across two chunks twice, about one in eight on a 256-wide
//! grid) and adds their forces to its own nodes only, in the chunk's hinge order; no buffer,
//! no locks, and the chunks are the same serially and in parallel, so the result does not
//! depend on the number of threads. A hinge node that is fixed is read from its stored
//! position.

use rayon::prelude::*;

use crate::hinge::{angle, angle_difference, angle_terms, edge_gradients};
use crate::spring::{energy, internal_coefficient, sub};
use crate::{Class, SpringLattice};

/// Nodes per rayon task.
const CHUNK_NODES: usize = 2048;
/// Springs per vectorized group in the force kernel.
const GROUP: usize = 4;
/// Below this many incidences the kernels run serially (rayon would cost more than it saves).
const SERIAL_INCIDENCES: usize = 32_768;

/// The incidence of a lattice restricted to its active nodes.
#[derive(Clone, Debug)]
pub(crate) struct Topology {
    /// Active index → original node index.
    pub active_nodes: Vec<usize>,
    /// CSR offsets of the active–active incidences (length `n_active + 1`).
    pub off: Vec<usize>,
    /// Active index of the other node.
    pub other: Vec<u32>,
    /// `(k, l)` of the spring.
    pub kl: Vec<[f64; 2]>,
    /// Spring index.
    pub spring: Vec<u32>,
    /// CSR offsets of the active–fixed incidences.
    pub off_fixed: Vec<usize>,
    /// Position of the fixed node.
    pub pos_fixed: Vec<[f64; 3]>,
    /// `(k, l)` of the spring.
    pub kl_fixed: Vec<[f64; 2]>,
    /// Spring index.
    pub spring_fixed: Vec<u32>,
    /// Energy of the springs and hinges whose nodes are all fixed (constant).
    pub fixed_energy: f64,
    /// Class and weight of every spring of the lattice.
    pub spring_class: Vec<(Class, f64)>,
    /// Axial damping `c` per active–active incidence (empty when no spring is damped).
    pub damping: Vec<f64>,
    /// Axial damping `c` per active–fixed incidence (empty when no spring is damped).
    pub damping_fixed: Vec<f64>,
    /// The hinges touching an active node.
    pub hinges: HingeTopology,
}

/// The hinges of a [`Topology`] that touch at least one active node.
#[derive(Clone, Debug, Default)]
pub(crate) struct HingeTopology {
    /// The four nodes of each hinge: an active index, or `FIXED | slot` for a fixed node
    /// whose position is `fixed_x[slot]`.
    pub nodes: Vec<[u32; 4]>,
    /// Positions of the fixed hinge nodes.
    pub fixed_x: Vec<[f64; 3]>,
    /// `k w` of each hinge.
    pub kw: Vec<f64>,
    /// Rest angle of each hinge.
    pub rest: Vec<f64>,
    /// Class and weight of each hinge.
    pub class: Vec<(Class, f64)>,
    /// CSR by active node of its `(hinge, slot)` incidences (offsets: `n_active + 1`).
    pub off: Vec<usize>,
    pub incidence: Vec<(u32, u8)>,
    /// CSR by chunk of [`CHUNK_NODES`] active nodes of the hinges with a node in the chunk,
    /// in increasing order (a hinge across two chunks is listed in both).
    pub chunk_off: Vec<usize>,
    pub chunk_hinges: Vec<u32>,
}

/// Marks a fixed node in [`HingeTopology::nodes`].
pub(crate) const FIXED: u32 = 1 << 31;

/// Hinges per rayon task in the hinge kernels.
const CHUNK_HINGES: usize = 4096;
/// Below this many hinges the hinge kernels run serially.
const SERIAL_HINGES: usize = 8192;

impl HingeTopology {
    /// Number of hinges.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// The positions of hinge `h`'s nodes, the active ones from `x`.
    #[inline(always)]
    pub fn positions(&self, h: usize, x: &[[f64; 3]]) -> [[f64; 3]; 4] {
        let at = |i: u32| {
            if i & FIXED != 0 {
                self.fixed_x[(i & !FIXED) as usize]
            } else {
                x[i as usize]
            }
        };
        let [a, b, c, d] = self.nodes[h];
        [at(a), at(b), at(c), at(d)]
    }

    /// Adds the internal forces `k w (θ − θ0) ∂θ/∂x_i` of the hinges `list` to those of their
    /// nodes that are active nodes `first .. first + out.len()`, in the list's order.
    fn add_forces(&self, list: &[u32], first: usize, x: &[[f64; 3]], out: &mut [[f64; 3]]) {
        for &h in list {
            let h = h as usize;
            let (theta, g2, g3, t2, t3) = angle_terms(&self.positions(h, x));
            let s = self.kw[h] * angle_difference(theta, self.rest[h]);
            let [g0, g1] = edge_gradients(g2, g3, t2, t3);
            for (&i, g) in self.nodes[h].iter().zip([g0, g1, g2, g3]) {
                // A fixed node's index has the FIXED bit and is never in range.
                if let Some(f) = (i as usize).checked_sub(first).and_then(|r| out.get_mut(r)) {
                    f[0] += s * g[0];
                    f[1] += s * g[1];
                    f[2] += s * g[2];
                }
            }
        }
    }

    /// `Σ ½ k w (θ − θ0)²` over the hinges.
    fn energy(&self, x: &[[f64; 3]]) -> f64 {
        let range = |lo: usize, hi: usize| -> f64 {
            (lo..hi)
                .map(|h| {
                    let d = angle_difference(angle(&self.positions(h, x)), self.rest[h]);
                    0.5 * self.kw[h] * d * d
                })
                .sum()
        };
        let n = self.len();
        if n < SERIAL_HINGES {
            range(0, n)
        } else {
            let parts: Vec<f64> = (0..n.div_ceil(CHUNK_HINGES))
                .into_par_iter()
                .map(|c| range(c * CHUNK_HINGES, ((c + 1) * CHUNK_HINGES).min(n)))
                .collect();
            parts.iter().sum()
        }
    }
}

impl Topology {
    /// Incidence with every node active (the full lattice).
    pub fn all_nodes(lattice: &SpringLattice) -> Self {
        Self::new(lattice, &vec![true; lattice.n_nodes()])
    }

    /// Incidence of the nodes with `active[a]`; the others are held at their lattice positions.
    /// The lattice must be valid (fewer than 2³² nodes and springs).
    pub fn new(lattice: &SpringLattice, active: &[bool]) -> Self {
        let n = lattice.n_nodes();
        let mut active_index = vec![u32::MAX; n];
        let mut active_nodes = Vec::new();
        for a in 0..n {
            if active[a] {
                active_index[a] = active_nodes.len() as u32;
                active_nodes.push(a);
            }
        }
        let n_active = active_nodes.len();
        let mut deg = vec![0usize; n_active + 1];
        let mut deg_fixed = vec![0usize; n_active + 1];
        let mut fixed_energy = 0.0;
        for s in &lattice.springs {
            let (ia, ib) = (active_index[s.a], active_index[s.b]);
            match (ia != u32::MAX, ib != u32::MAX) {
                (true, true) => {
                    deg[ia as usize] += 1;
                    deg[ib as usize] += 1;
                }
                (true, false) => deg_fixed[ia as usize] += 1,
                (false, true) => deg_fixed[ib as usize] += 1,
                (false, false) => {
                    fixed_energy += energy(
                        s.stiffness(),
                        s.rest_length,
                        sub(lattice.positions[s.a], lattice.positions[s.b]),
                    );
                }
            }
        }
        let off = exclusive_scan(&deg);
        let off_fixed = exclusive_scan(&deg_fixed);
        let (m, m_fixed) = (off[n_active], off_fixed[n_active]);
        let mut other = vec![0u32; m];
        let mut kl = vec![[0.0; 2]; m];
        let mut spring = vec![0u32; m];
        let mut pos_fixed = vec![[0.0; 3]; m_fixed];
        let mut kl_fixed = vec![[0.0; 2]; m_fixed];
        let mut spring_fixed = vec![0u32; m_fixed];
        let damped = lattice.springs.iter().any(|s| s.damping != 0.0);
        let mut damping = vec![0.0; if damped { m } else { 0 }];
        let mut damping_fixed = vec![0.0; if damped { m_fixed } else { 0 }];
        let mut next = off.clone();
        let mut next_fixed = off_fixed.clone();
        for (si, s) in lattice.springs.iter().enumerate() {
            let (ia, ib) = (active_index[s.a], active_index[s.b]);
            let params = [s.stiffness(), s.rest_length];
            for (me, you, you_node) in [(ia, ib, s.b), (ib, ia, s.a)] {
                if me == u32::MAX {
                    continue;
                }
                let me = me as usize;
                if you != u32::MAX {
                    let e = next[me];
                    next[me] += 1;
                    other[e] = you;
                    kl[e] = params;
                    spring[e] = si as u32;
                    if damped {
                        damping[e] = s.damping;
                    }
                } else {
                    let e = next_fixed[me];
                    next_fixed[me] += 1;
                    pos_fixed[e] = lattice.positions[you_node];
                    kl_fixed[e] = params;
                    spring_fixed[e] = si as u32;
                    if damped {
                        damping_fixed[e] = s.damping;
                    }
                }
            }
        }
        let (hinges, hinge_fixed_energy) = hinge_topology(lattice, &active_index);
        fixed_energy += hinge_fixed_energy;
        Self {
            active_nodes,
            off,
            other,
            kl,
            spring,
            off_fixed,
            pos_fixed,
            kl_fixed,
            spring_fixed,
            fixed_energy,
            spring_class: lattice
                .springs
                .iter()
                .map(|s| (Class::Spring(s.kind), s.weight))
                .collect(),
            damping,
            damping_fixed,
            hinges,
        }
    }

    /// Number of active nodes.
    pub fn n_active(&self) -> usize {
        self.active_nodes.len()
    }

    fn n_incidences(&self) -> usize {
        self.other.len() + self.pos_fixed.len()
    }

    /// True when some spring has axial damping.
    pub fn is_damped(&self) -> bool {
        !self.damping.is_empty()
    }

    /// Internal force `f_int = −f_elastic` (paper eq. (5) with the sign of a stiffness) on every
    /// active node: `out[a] = Σ_b k w (1 − l/|d|) d`, `d = x_a − x_b`, with `x` the active
    /// positions, plus `Σ_hinges k w (θ − θ0) ∂θ/∂x_a` (docs/math.md §5.2). Allocation-free;
    /// parallel over chunks of nodes (and hinges) for large lattices.
    pub fn internal_forces(&self, x: &[[f64; 3]], out: &mut [[f64; 3]]) {
        let n = self.n_active();
        assert_eq!(x.len(), n, "positions of {n} active nodes expected");
        assert_eq!(out.len(), n, "forces of {n} active nodes expected");
        let hinges = &self.hinges;
        let range = |first: usize, chunk: &mut [[f64; 3]]| {
            self.forces_range(first, x, chunk);
            let c = first / CHUNK_NODES;
            if hinges.len() > 0 {
                let list = &hinges.chunk_hinges[hinges.chunk_off[c]..hinges.chunk_off[c + 1]];
                hinges.add_forces(list, first, x, chunk);
            }
        };
        // The same chunks serially or in parallel, so the sums do not depend on the threads.
        if self.n_incidences() + 4 * self.hinges.len() < SERIAL_INCIDENCES {
            for (c, chunk) in out.chunks_mut(CHUNK_NODES).enumerate() {
                range(c * CHUNK_NODES, chunk);
            }
        } else {
            out.par_chunks_mut(CHUNK_NODES)
                .enumerate()
                .for_each(|(c, chunk)| range(c * CHUNK_NODES, chunk));
        }
    }

    /// Adds the axial damping forces `C(x) v` (docs/math.md §5.1) on every active node to `out`:
    /// `Σ_b c ((v_a − v_b)·n) n`, `n = d/|d|`, `d = x_a − x_b`, `v_b = 0` at a fixed node.
    pub fn add_damping_forces(&self, x: &[[f64; 3]], v: &[[f64; 3]], out: &mut [[f64; 3]]) {
        if !self.is_damped() {
            return;
        }
        let range = |first: usize, chunk: &mut [[f64; 3]]| {
            for (i, f) in chunk.iter_mut().enumerate() {
                let a = first + i;
                let (xa, va) = (x[a], v[a]);
                let mut add = |d: [f64; 3], dv: [f64; 3], c: f64| {
                    let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                    let s = c * (d[0] * dv[0] + d[1] * dv[1] + d[2] * dv[2]) / r2;
                    f[0] += s * d[0];
                    f[1] += s * d[1];
                    f[2] += s * d[2];
                };
                for e in self.off[a]..self.off[a + 1] {
                    let b = self.other[e] as usize;
                    add(sub(xa, x[b]), sub(va, v[b]), self.damping[e]);
                }
                for e in self.off_fixed[a]..self.off_fixed[a + 1] {
                    add(sub(xa, self.pos_fixed[e]), va, self.damping_fixed[e]);
                }
            }
        };
        if self.n_incidences() < SERIAL_INCIDENCES {
            range(0, out);
        } else {
            out.par_chunks_mut(CHUNK_NODES)
                .enumerate()
                .for_each(|(c, chunk)| range(c * CHUNK_NODES, chunk));
        }
    }

    /// Forces of the active nodes `first .. first + out.len()`.
    ///
    /// The springs of a node are taken [`GROUP`] at a time, with the differences, lengths and
    /// coefficients in small arrays, so that the compiler evaluates the square roots and
    /// divisions of a group with vector instructions; the sums are still formed in incidence
    /// order, so the result is the same as a one-by-one loop, bit for bit.
    #[inline]
    fn forces_range(&self, first: usize, x: &[[f64; 3]], out: &mut [[f64; 3]]) {
        let last = first + out.len();
        let offsets = self.off[first..=last].windows(2);
        let offsets_fixed = self.off_fixed[first..=last].windows(2);
        for (((fa, &xa), w), wf) in out
            .iter_mut()
            .zip(&x[first..last])
            .zip(offsets)
            .zip(offsets_fixed)
        {
            let mut f = [0.0; 3];
            let (others, others_rest) = self.other[w[0]..w[1]].as_chunks::<GROUP>();
            let (params, params_rest) = self.kl[w[0]..w[1]].as_chunks::<GROUP>();
            for (o, kl) in others.iter().zip(params) {
                let mut d = [[0.0; GROUP]; 3];
                for i in 0..GROUP {
                    let xb = x[o[i] as usize];
                    d[0][i] = xa[0] - xb[0];
                    d[1][i] = xa[1] - xb[1];
                    d[2][i] = xa[2] - xb[2];
                }
                let mut s = [0.0; GROUP];
                for i in 0..GROUP {
                    let r = (d[0][i] * d[0][i] + d[1][i] * d[1][i] + d[2][i] * d[2][i]).sqrt();
                    s[i] = kl[i][0] * (1.0 - kl[i][1] / r);
                }
                for i in 0..GROUP {
                    f[0] += s[i] * d[0][i];
                    f[1] += s[i] * d[1][i];
                    f[2] += s[i] * d[2][i];
                }
            }
            for (&o, &[k, l]) in others_rest.iter().zip(params_rest) {
                add_spring_force(&mut f, sub(xa, x[o as usize]), k, l);
            }
            let (lo, hi) = (wf[0], wf[1]);
            for (&xb, &[k, l]) in self.pos_fixed[lo..hi].iter().zip(&self.kl_fixed[lo..hi]) {
                add_spring_force(&mut f, sub(xa, xb), k, l);
            }
            *fa = f;
        }
    }

    /// Elastic energy `Σ k w (|d| − l)² / 2` of every spring (docs/math.md §5) and
    /// `Σ ½ k w (θ − θ0)²` of every hinge (§5.2) with the active nodes at `x`.
    pub fn energy(&self, x: &[[f64; 3]]) -> f64 {
        let n = self.n_active();
        assert_eq!(x.len(), n, "positions of {n} active nodes expected");
        let range = |first: usize, last: usize| -> f64 {
            let mut e_shared = 0.0;
            let mut e_fixed = 0.0;
            for a in first..last {
                let xa = x[a];
                for e in self.off[a]..self.off[a + 1] {
                    let [k, l] = self.kl[e];
                    e_shared += energy(k, l, sub(xa, x[self.other[e] as usize]));
                }
                for e in self.off_fixed[a]..self.off_fixed[a + 1] {
                    let [k, l] = self.kl_fixed[e];
                    e_fixed += energy(k, l, sub(xa, self.pos_fixed[e]));
                }
            }
            // Springs between two active nodes are visited from both ends.
            0.5 * e_shared + e_fixed
        };
        let moving = if self.n_incidences() < SERIAL_INCIDENCES {
            range(0, n)
        } else {
            // Per-chunk sums added in a fixed order: the result does not depend on scheduling.
            let parts: Vec<f64> = (0..n.div_ceil(CHUNK_NODES))
                .into_par_iter()
                .map(|c| range(c * CHUNK_NODES, ((c + 1) * CHUNK_NODES).min(n)))
                .collect();
            parts.iter().sum()
        };
        moving + self.hinges.energy(x) + self.fixed_energy
    }
}

/// The hinges of `lattice` with at least one active node (`active_index[a] = u32::MAX` for
/// an inactive node) and the energy of the others.
fn hinge_topology(lattice: &SpringLattice, active_index: &[u32]) -> (HingeTopology, f64) {
    let mut t = HingeTopology::default();
    let mut fixed_energy = 0.0;
    let n_active = active_index.iter().filter(|&&i| i != u32::MAX).count();
    let mut deg = vec![0usize; n_active + 1];
    for h in &lattice.hinges {
        if h.nodes.iter().all(|&a| active_index[a] == u32::MAX) {
            let x = h.nodes.map(|a| lattice.positions[a]);
            let d = angle_difference(angle(&x), h.rest_angle);
            fixed_energy += 0.5 * h.stiffness() * d * d;
            continue;
        }
        let nodes = h.nodes.map(|a| match active_index[a] {
            u32::MAX => {
                t.fixed_x.push(lattice.positions[a]);
                FIXED | (t.fixed_x.len() - 1) as u32
            }
            i => {
                deg[i as usize] += 1;
                i
            }
        });
        t.nodes.push(nodes);
        t.kw.push(h.stiffness());
        t.rest.push(h.rest_angle);
        t.class.push((Class::Hinge(h.kind), h.weight));
    }
    t.off = exclusive_scan(&deg);
    t.incidence = vec![(0, 0); t.off[n_active]];
    let mut next = t.off.clone();
    for (h, nodes) in t.nodes.iter().enumerate() {
        for (slot, &i) in nodes.iter().enumerate() {
            if i & FIXED == 0 {
                t.incidence[next[i as usize]] = (h as u32, slot as u8);
                next[i as usize] += 1;
            }
        }
    }
    let n_chunks = n_active.div_ceil(CHUNK_NODES);
    let chunks_of = |nodes: &[u32; 4]| {
        let mut c: Vec<usize> = nodes
            .iter()
            .filter(|&&i| i & FIXED == 0)
            .map(|&i| i as usize / CHUNK_NODES)
            .collect();
        c.sort_unstable();
        c.dedup();
        c
    };
    let mut count = vec![0usize; n_chunks + 1];
    for nodes in &t.nodes {
        for c in chunks_of(nodes) {
            count[c] += 1;
        }
    }
    t.chunk_off = exclusive_scan(&count);
    t.chunk_hinges = vec![0; t.chunk_off[n_chunks]];
    let mut next = t.chunk_off.clone();
    for (h, nodes) in t.nodes.iter().enumerate() {
        for c in chunks_of(nodes) {
            t.chunk_hinges[next[c]] = h as u32;
            next[c] += 1;
        }
    }
    (t, fixed_energy)
}

/// `f += k (1 − l/|d|) d`.
#[inline(always)]
fn add_spring_force(f: &mut [f64; 3], d: [f64; 3], k: f64, l: f64) {
    let s = internal_coefficient(k, l, d);
    f[0] += s * d[0];
    f[1] += s * d[1];
    f[2] += s * d[2];
}

fn exclusive_scan(counts: &[usize]) -> Vec<usize> {
    let mut off = Vec::with_capacity(counts.len());
    let mut acc = 0;
    for &c in counts {
        off.push(acc);
        acc += c;
    }
    off
}
