//! Tangent stiffness `K_T = −∂f/∂x` and unit-stiffness matrices `G_c` (paper eqs. (9)–(10),
//! docs/math.md §5), on a block pattern computed once.
//!
//! The pattern has a dense 3 × 3 block for every active node (diagonal) and for every pair of
//! active nodes joined by at least one spring. In compressed-column storage the three columns
//! of node `a` are contiguous and each holds the same rows (the blocks of `a`'s neighbours and
//! of `a`, ascending), so node `a` owns the value range `col_ptr[3a] .. col_ptr[3a + 3]` and
//! fills it alone: entry `(3b + r, 3a + c)` sits at offset `c · 3 s_a + 3 pos_a(b) + r`, with
//! `s_a` the number of blocks in the column and `pos_a(b)` the rank of `b` among them. Values
//! are filled in parallel, without locks.

use nurbspring_linalg::SparseMatrix;
use rayon::prelude::*;

use crate::SpringKind;
use crate::spring::{stiffness_block_with, sub};
use crate::topology::Topology;

/// Nodes per rayon task when filling values.
const CHUNK_NODES: usize = 1024;

/// Which spring constant multiplies each block.
pub(crate) enum Coefficient {
    /// The spring's own `k`: the tangent stiffness `K_T`.
    Stiffness,
    /// The spring's own `k` with the geometric term of compressed springs dropped: the
    /// positive semi-definite part of `K_T` (see `stiffness_block_with`).
    ProjectedStiffness,
    /// `1` for springs of this kind, `0` otherwise: the unit matrix `G_c`.
    Unit(SpringKind),
    /// The spring's own `k` times the identity block, `k I ⪰ B` at any length (B's
    /// eigenvalues are `k` along the spring and `k (1 − l/r) < k` across it): the stiffness
    /// bound `K̄ ⪰ K_T(q)` of [`crate::MsmModel`]'s `stiffness_bound`.
    Bound,
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
}

impl Topology {
    /// The block pattern of `K_T` on the active nodes (computed once per topology).
    pub fn pattern(&self) -> TangentPattern {
        let n = self.n_active();
        let mut start = Vec::with_capacity(n + 1);
        let mut blocks = Vec::with_capacity(n);
        let mut diag = Vec::with_capacity(n);
        let mut slot = vec![0u32; self.other.len()];
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
            col_nodes.sort_unstable();
            col_nodes.dedup();
            for e in lo..hi {
                slot[e] = col_nodes
                    .binary_search(&self.other[e])
                    .expect("neighbour in its column") as u32;
            }
            diag.push(
                col_nodes
                    .binary_search(&(a as u32))
                    .expect("diagonal block") as u32,
            );
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
        }
    }

    /// Fills `values` (of a matrix with `pattern`) with `Σ_springs coef · B` blocks at the active
    /// positions `x` (interleaved): `+B` on the diagonal blocks, `−B` off the diagonal, where
    /// `B = k [ (l/|d|) n nᵀ + (1 − l/|d|) I ]` (paper eq. (9)). Springs to fixed nodes
    /// contribute to the diagonal block only.
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
        let bound = matches!(coef, Coefficient::Bound);
        let block_of = |k: f64, l: f64, d: [f64; 3]| {
            if bound {
                [[k, 0.0, 0.0], [0.0, k, 0.0], [0.0, 0.0, k]]
            } else {
                stiffness_block_with(k, l, d, project)
            }
        };
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
                for e in self.off[a]..self.off[a + 1] {
                    let [k, l] = self.kl[e];
                    let Some(k) = coef.value(k, self.spring[e], &self.kinds) else {
                        continue;
                    };
                    let block = block_of(k, l, sub(xa, x[self.other[e] as usize]));
                    let off = 3 * pattern.slot[e] as usize;
                    add_block(v, stride, diag, &block, 1.0);
                    add_block(v, stride, off, &block, -1.0);
                }
                for e in self.off_fixed[a]..self.off_fixed[a + 1] {
                    let [k, l] = self.kl_fixed[e];
                    let Some(k) = coef.value(k, self.spring_fixed[e], &self.kinds) else {
                        continue;
                    };
                    let block = block_of(k, l, sub(xa, self.pos_fixed[e]));
                    add_block(v, stride, diag, &block, 1.0);
                }
            }
        });
    }
}

impl Coefficient {
    /// The constant multiplying spring `spring` (of stiffness `k`, kind `kinds[spring]`), or
    /// `None` when the spring does not enter.
    #[inline]
    fn value(&self, k: f64, spring: u32, kinds: &[SpringKind]) -> Option<f64> {
        match self {
            Coefficient::Stiffness | Coefficient::ProjectedStiffness | Coefficient::Bound => {
                Some(k)
            }
            Coefficient::Unit(kind) => (kinds[spring as usize] == *kind).then_some(1.0),
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
