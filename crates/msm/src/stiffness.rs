//! Tangent stiffness `K_T = −∂f/∂x` and unit-stiffness matrices `G_c` (paper eqs. (9)–(10),
//! docs/math.md §5), on a block pattern computed once.
//!
//! The pattern has a dense 3 × 3 block for every active node (diagonal) and for every pair of
//! active nodes joined by at least one spring or sharing a hinge. In compressed-column storage
//! the three columns of node `a` are contiguous and each holds the same rows (the blocks of
//! `a`'s neighbours and of `a`, ascending), so node `a` owns the value range
//! `col_ptr[3a] .. col_ptr[3a + 3]` and fills it alone: entry `(3b + r, 3a + c)` sits at offset
//! `c · 3 s_a + 3 pos_a(b) + r`, with `s_a` the number of blocks in the column and `pos_a(b)`
//! the rank of `b` among them. Values are filled in parallel, without locks; a hinge's
//! 12 × 12 block is computed by each of its active nodes for its own three columns.

use nurbspring_linalg::SparseMatrix;
use rayon::prelude::*;

use crate::Class;
use crate::hinge::hinge_blocks;
use crate::spring::{stiffness_block_with, sub};
use crate::topology::{FIXED, Topology};

/// Nodes per rayon task when filling values.
const CHUNK_NODES: usize = 1024;

/// Which constant multiplies each element's block.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Coefficient {
    /// The element's own `k w`: the tangent stiffness `K_T`.
    Stiffness,
    /// The element's own `k w` with the geometric term of compressed springs dropped and the
    /// hinges' Gauss–Newton part `k w ∇θ ∇θᵀ` only: a positive semi-definite part of `K_T`
    /// (see `stiffness_block_with` and `Hinge::stiffness_blocks`).
    ProjectedStiffness,
    /// The weight `w` for the elements of this class, `0` otherwise: the unit matrix `G_c`.
    Unit(Class),
    /// The spring's own `k w` times the identity block, `k w I ⪰ B` at any length (B's
    /// eigenvalues are `k w` along the spring and `k w (1 − l/r) < k w` across it): the
    /// stiffness bound `K̄ ⪰ K_T(q)` of [`crate::MsmModel`]'s `stiffness_bound` (springs only;
    /// hinges have no such bound).
    Bound,
    /// The axial damping `c n nᵀ` of each spring (docs/math.md §5.1): the damping matrix
    /// `C(x)`.
    AxialDamping,
}

/// The block pattern of a [`Topology`] and a template matrix with that pattern.
#[derive(Clone, Debug)]
pub(crate) struct TangentPattern {
    /// A matrix with the pattern, all values zero (clone and fill).
    pub template: SparseMatrix,
    /// Start of each active node's value range (`col_ptr[3a]`), length `n_active + 1`.
    start: Vec<usize>,
    /// Number of blocks `s_a` in each node's columns.
    blocks: Vec<u32>,
    /// Rank of the node's own (diagonal) block.
    diag: Vec<u32>,
    /// Rank of the other node's block, per active–active incidence.
    slot: Vec<u32>,
    /// Ranks of the four hinge nodes in the column of the node, per hinge incidence
    /// (`u32::MAX` for a fixed node).
    hinge_slots: Vec<[u32; 4]>,
}

impl Topology {
    /// The block pattern of `K_T` on the active nodes (computed once per topology).
    pub fn pattern(&self) -> TangentPattern {
        let n = self.n_active();
        let hinges = &self.hinges;
        let mut start = Vec::with_capacity(n + 1);
        let mut blocks = Vec::with_capacity(n);
        let mut diag = Vec::with_capacity(n);
        let mut slot = vec![0u32; self.other.len()];
        let mut hinge_slots = vec![[u32::MAX; 4]; hinges.incidence.len()];
        let mut col_nodes: Vec<u32> = Vec::new();
        let mut col_ptr = Vec::with_capacity(3 * n + 1);
        let mut row_idx: Vec<usize> = Vec::new();
        col_ptr.push(0);
        let mut acc = 0usize;
        for a in 0..n {
            let (lo, hi) = (self.off[a], self.off[a + 1]);
            col_nodes.clear();
            col_nodes.extend_from_slice(&self.other[lo..hi]);
            col_nodes.push(a as u32);
            let (hlo, hhi) = (hinges.off[a], hinges.off[a + 1]);
            for &(h, _) in &hinges.incidence[hlo..hhi] {
                col_nodes.extend(hinges.nodes[h as usize].iter().filter(|&&i| i & FIXED == 0));
            }
            col_nodes.sort_unstable();
            col_nodes.dedup();
            let rank = |b: u32| {
                col_nodes
                    .binary_search(&b)
                    .expect("neighbour in its column") as u32
            };
            for e in lo..hi {
                slot[e] = rank(self.other[e]);
            }
            for (e, &(h, _)) in (hlo..hhi).zip(&hinges.incidence[hlo..hhi]) {
                hinge_slots[e] = hinges.nodes[h as usize]
                    .map(|i| if i & FIXED != 0 { u32::MAX } else { rank(i) });
            }
            diag.push(rank(a as u32));
            blocks.push(col_nodes.len() as u32);
            start.push(acc);
            for _ in 0..3 {
                for &b in &col_nodes {
                    row_idx.extend((0..3).map(|r| 3 * b as usize + r));
                }
                acc += 3 * col_nodes.len();
                col_ptr.push(acc);
            }
        }
        start.push(acc);
        let values = vec![0.0; acc];
        let template = SparseMatrix::try_from_csc(3 * n, 3 * n, col_ptr, row_idx, values)
            .expect("the block pattern is a valid CSC matrix");
        TangentPattern {
            template,
            start,
            blocks,
            diag,
            slot,
            hinge_slots,
        }
    }

    /// Fills `values` (of a matrix with `pattern`) with the elements' blocks at the active
    /// positions `x` (interleaved), each scaled as `coef` says: for springs `+B` on the
    /// diagonal blocks and `−B` off the diagonal, where `B = k w [ (l/|d|) n nᵀ + (1 − l/|d|) I ]`
    /// (paper eq. (9)); springs to fixed nodes contribute to the diagonal block only. For
    /// hinges the 12 × 12 Hessian `k w (∇θ ∇θᵀ + (θ − θ0) ∇²θ)` (docs/math.md §5.2), the rows
    /// and columns of fixed nodes left out.
    pub fn fill(
        &self,
        pattern: &TangentPattern,
        x: &[f64],
        coef: &Coefficient,
        values: &mut [f64],
    ) {
        let n = self.n_active();
        assert_eq!(x.len(), 3 * n, "positions of {n} active nodes expected");
        assert_eq!(
            values.len(),
            pattern.start[n],
            "values of the block pattern expected"
        );
        let (x, _) = x.as_chunks::<3>();
        let project = matches!(coef, Coefficient::ProjectedStiffness);
        let block_of = |k: f64, l: f64, d: [f64; 3]| match coef {
            Coefficient::Bound => [[k, 0.0, 0.0], [0.0, k, 0.0], [0.0, 0.0, k]],
            Coefficient::AxialDamping => {
                let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                let mut b = [[0.0; 3]; 3];
                for i in 0..3 {
                    for j in 0..3 {
                        b[i][j] = k * d[i] * d[j] / r2;
                    }
                }
                b
            }
            _ => stiffness_block_with(k, l, d, project),
        };
        let damping = matches!(coef, Coefficient::AxialDamping);
        let hinges = &self.hinges;
        let with_hinges = hinges.len() > 0
            && !matches!(
                coef,
                Coefficient::Bound
                    | Coefficient::AxialDamping
                    | Coefficient::Unit(Class::Spring(_) | Class::Linear(..))
            );
        // Split the values into chunks of whole nodes.
        let mut chunks: Vec<(usize, &mut [f64])> = Vec::with_capacity(n.div_ceil(CHUNK_NODES));
        let mut rest = values;
        for first in (0..n).step_by(CHUNK_NODES) {
            let last = (first + CHUNK_NODES).min(n);
            let (head, tail) = rest.split_at_mut(pattern.start[last] - pattern.start[first]);
            chunks.push((first, head));
            rest = tail;
        }
        chunks.into_par_iter().for_each(|(first, vals)| {
            let last = (first + CHUNK_NODES).min(n);
            let base = pattern.start[first];
            for a in first..last {
                let v = &mut vals[pattern.start[a] - base..pattern.start[a + 1] - base];
                v.fill(0.0);
                let stride = 3 * pattern.blocks[a] as usize;
                let diag = 3 * pattern.diag[a] as usize;
                let xa = x[a];
                let spring_k = |kw: f64, s: u32, e: usize, fixed: bool| -> Option<f64> {
                    if damping {
                        let c = if fixed {
                            self.damping_fixed.get(e)
                        } else {
                            self.damping.get(e)
                        };
                        return c.copied().filter(|&c| c != 0.0);
                    }
                    coef.value(kw, self.spring_class[s as usize])
                };
                for e in self.off[a]..self.off[a + 1] {
                    let [k, l] = self.kl[e];
                    let Some(k) = spring_k(k, self.spring[e], e, false) else {
                        continue;
                    };
                    let block = block_of(k, l, sub(xa, x[self.other[e] as usize]));
                    let off = 3 * pattern.slot[e] as usize;
                    add_block(v, stride, diag, &block, 1.0);
                    add_block(v, stride, off, &block, -1.0);
                }
                for e in self.off_fixed[a]..self.off_fixed[a + 1] {
                    let [k, l] = self.kl_fixed[e];
                    let Some(k) = spring_k(k, self.spring_fixed[e], e, true) else {
                        continue;
                    };
                    let block = block_of(k, l, sub(xa, self.pos_fixed[e]));
                    add_block(v, stride, diag, &block, 1.0);
                }
                if !with_hinges {
                    continue;
                }
                for e in hinges.off[a]..hinges.off[a + 1] {
                    let (h, me) = hinges.incidence[e];
                    let h = h as usize;
                    let Some(kw) = coef.value(hinges.kw[h], hinges.class[h]) else {
                        continue;
                    };
                    let blocks = hinge_blocks(&hinges.positions(h, x), kw, hinges.rest[h], project);
                    for (b, &rank) in pattern.hinge_slots[e].iter().enumerate() {
                        if rank != u32::MAX {
                            // Rows of node b, the columns of this node.
                            add_block(v, stride, 3 * rank as usize, &blocks[b][me as usize], 1.0);
                        }
                    }
                }
            }
        });
    }
}

impl Coefficient {
    /// The constant multiplying an element of stiffness `k w` and `(class, weight)`, or `None`
    /// when the element does not enter.
    #[inline]
    fn value(&self, kw: f64, (class, weight): (Class, f64)) -> Option<f64> {
        match self {
            Coefficient::Stiffness | Coefficient::ProjectedStiffness | Coefficient::Bound => {
                Some(kw)
            }
            Coefficient::Unit(c) => (*c == class).then_some(weight),
            Coefficient::AxialDamping => None,
        }
    }
}

/// `v[c · stride + row0 + r] += sign · B[r][c]`.
#[inline(always)]
fn add_block(v: &mut [f64], stride: usize, row0: usize, block: &[[f64; 3]; 3], sign: f64) {
    for c in 0..3 {
        let col = &mut v[c * stride + row0..c * stride + row0 + 3];
        for r in 0..3 {
            col[r] += sign * block[r][c];
        }
    }
}
