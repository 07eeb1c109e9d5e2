//! The fused symplectic-Euler step of grid lattices: spring forces, velocity and position
//! update in one streaming pass, with the topology implicit in the grid.
//!
//! On a grid lattice (node `a = i · n_v + j`, [`SpringLattice::grid`]) every spring joins a
//! node `(i, j)` to `(i + di, j + dj)` for a few offsets ("directions"): `(0, 1)` and `(1, 0)`
//! for structural springs, `(1, 1)` and `(1, −1)` for shear, `(0, 2)` and `(2, 0)` for
//! bending. Per direction the step stores one rest length per spring, indexed by its lower
//! node, and one stiffness for the whole direction when its springs share it (per spring
//! otherwise); no node indices at all. Per node it stores nothing when the mass, damping and
//! external force are the same on every free node (a lattice built from a surface), one value
//! per node otherwise.
//!
//! The pass runs over the rows `i` in increasing order. Row `i` evaluates each spring whose
//! lower node lies in it once, `t = s d` (`d = x_a − x_b`, `s = k (1 − l/|d|)`, paper eq. (5)
//! with the sign of a stiffness), into a ring of the last `depth + 1` rows of spring forces
//! per direction, `depth` being the largest row offset. Every spring at a node of row `i` is
//! then known, so the node's force is summed from the ring (per direction `t` of its spring as
//! lower node minus `t` of its spring as upper node) and its velocity and position are updated
//! in place (`v += Δt M⁻¹ (f_ext − f_int − D v)`, `q += Δt v`) while rows `i + 1 …` still hold
//! the old positions that the next springs need. The position and force rows are
//! structure-of-arrays copies (fixed nodes filled in), so the loops are plain vector loops.
//!
//! In parallel the rows are cut into bands. The old positions of the `depth` rows on each side
//! of every cut are copied first ("halos"); a band then evaluates the springs that reach into
//! it from the rows above its first row and reads the rows below its last one from the halo.
//! Every node receives its contributions in the same order whatever the cut, so the result
//! does not depend on the number of bands or threads, bit for bit. Against the generic path (forces per node, then the update) only the order of the
//! force sums differs: the two agree to round-off.

use nurbspring_sim::FusedStep;

use crate::SpringLattice;

/// Rows per band (one parallel task), at least.
const BAND_ROWS: usize = 32;
/// The most bands a step is cut into.
const MAX_BANDS: usize = 256;
/// Below this many springs the bands run one after another on the calling thread (rayon
/// would cost more than it saves).
const SERIAL_SPRINGS: usize = 16_384;
/// Shortest row (`n_v`) for which the grid step is used; shorter rows take the generic path.
pub(crate) const MIN_ROW: usize = 4;
/// Largest row offset `di` and column offset `|dj|` of a spring on the grid step.
const MAX_DI: usize = 2;
const MAX_DJ: usize = 2;

/// A value per free node, stored once when every free node has the same.
#[derive(Clone, Debug)]
enum PerNode<T> {
    Uniform(T),
    Varying(Vec<T>),
}

impl<T: Copy + PartialEq> PerNode<T> {
    fn new(values: Vec<T>) -> Self {
        match values.first() {
            Some(&first) if values.iter().all(|&v| v == first) => PerNode::Uniform(first),
            _ => PerNode::Varying(values),
        }
    }

    #[inline(always)]
    fn get(&self, k: usize) -> T {
        match self {
            PerNode::Uniform(v) => *v,
            PerNode::Varying(v) => v[k],
        }
    }

    fn bytes(&self) -> usize {
        match self {
            PerNode::Uniform(_) => 0,
            PerNode::Varying(v) => std::mem::size_of_val(v.as_slice()),
        }
    }
}

/// The stiffness of the springs of one direction.
#[derive(Clone, Debug)]
enum Stiffness {
    Uniform(f64),
    /// Per spring, indexed like the rest lengths.
    PerSpring(Vec<f64>),
}

/// The springs `(i, j) – (i + di, j + dj)` of one direction.
#[derive(Clone, Debug)]
struct Direction {
    di: usize,
    dj: isize,
    /// Columns `j_lo .. j_hi` of the lower nodes that have a spring in this direction.
    j_lo: usize,
    j_hi: usize,
    k: Stiffness,
    /// Rest length of the spring at lower node `(i, j)`, at `i · n_v + j` (entries of columns
    /// outside `j_lo .. j_hi` and of the last `di` rows are unused).
    rest: Vec<f64>,
}

/// The fused symplectic-Euler step of a grid lattice (see the module docs).
#[derive(Clone, Debug)]
pub(crate) struct GridStep {
    n_u: usize,
    n_v: usize,
    /// Largest `di` of the directions (≥ 1 unless every spring lies within a row).
    depth: usize,
    dirs: Vec<Direction>,
    /// Free-node index of the first free node of each row (`n_u + 1` entries).
    row_free: Vec<usize>,
    /// CSR by row of the fixed nodes: offsets (`n_u + 1`), columns, positions.
    fixed_off: Vec<usize>,
    fixed_col: Vec<usize>,
    fixed_x: Vec<[f64; 3]>,
    /// `f_ext`, `1/m` and `γ` of the free nodes.
    external: PerNode<[f64; 3]>,
    inv_mass: PerNode<f64>,
    damping: PerNode<f64>,
    /// Row ranges of the bands.
    bands: Vec<(usize, usize)>,
    n_springs: usize,
}

impl GridStep {
    /// The grid step of `lattice` (free nodes as in [`crate::topology::Topology`]: in
    /// increasing order, `external` their `f_ext` per coordinate), or `None` when the lattice
    /// is not a grid lattice the step can run: no grid, rows shorter than [`MIN_ROW`], linear
    /// elements, a spring that is not `(i, j) – (i + di, j + dj)` with `di ≤ 2`, `|dj| ≤ 2`,
    /// two springs between the same nodes, or a direction that misses a spring somewhere (the
    /// generic path runs these).
    pub fn new(lattice: &SpringLattice, external: &[f64]) -> Option<Self> {
        let (n_u, n_v) = lattice.grid?;
        if n_v < MIN_ROW
            || n_u == 0
            || !lattice.elements.is_empty()
            || !lattice.hinges.is_empty()
            || lattice.springs.is_empty()
            || lattice.springs.iter().any(|s| s.damping != 0.0)
        {
            return None;
        }
        let n = n_u * n_v;
        if lattice.n_nodes() != n {
            return None;
        }
        let mut dirs: Vec<Direction> = Vec::new();
        let mut filled: Vec<Vec<bool>> = Vec::new();
        let mut k_per_spring: Vec<Vec<f64>> = Vec::new();
        for s in &lattice.springs {
            let (mut ia, mut ja, mut ib, mut jb) = (s.a / n_v, s.a % n_v, s.b / n_v, s.b % n_v);
            if ib < ia || (ib == ia && jb < ja) {
                (ia, ja, ib, jb) = (ib, jb, ia, ja);
            }
            let (di, dj) = (ib - ia, jb as isize - ja as isize);
            if di > MAX_DI || dj.unsigned_abs() > MAX_DJ || (di == 0 && dj == 0) {
                return None;
            }
            let d = match dirs.iter().position(|d| (d.di, d.dj) == (di, dj)) {
                Some(d) => d,
                None => {
                    dirs.push(Direction {
                        di,
                        dj,
                        j_lo: (-dj).max(0) as usize,
                        j_hi: (n_v as isize - dj.max(0)) as usize,
                        k: Stiffness::Uniform(s.stiffness()),
                        rest: vec![0.0; n],
                    });
                    filled.push(vec![false; n]);
                    k_per_spring.push(vec![0.0; n]);
                    dirs.len() - 1
                }
            };
            let slot = ia * n_v + ja;
            if std::mem::replace(&mut filled[d][slot], true) {
                return None;
            }
            dirs[d].rest[slot] = s.rest_length;
            k_per_spring[d][slot] = s.stiffness();
        }
        // Every direction complete: one spring at each lower node that has an upper one.
        for (d, dir) in dirs.iter_mut().enumerate() {
            let count = (n_u.saturating_sub(dir.di)) * (dir.j_hi.saturating_sub(dir.j_lo));
            if filled[d].iter().filter(|&&f| f).count() != count {
                return None;
            }
            let k = std::mem::take(&mut k_per_spring[d]);
            let k0 = k[dir.j_lo];
            let uniform = (0..n_u - dir.di)
                .all(|i| (dir.j_lo..dir.j_hi).all(|j| k[i * n_v + j].to_bits() == k0.to_bits()));
            dir.k = if uniform {
                Stiffness::Uniform(k0)
            } else {
                Stiffness::PerSpring(k)
            };
        }
        // Rows in order, directions by (di, dj) so that the sums run in a fixed order.
        dirs.sort_by_key(|d| (d.di, d.dj));
        let depth = dirs.iter().map(|d| d.di).max().unwrap_or(0);

        let mut row_free = Vec::with_capacity(n_u + 1);
        let mut fixed_off = Vec::with_capacity(n_u + 1);
        let (mut fixed_col, mut fixed_x) = (Vec::new(), Vec::new());
        let mut free = 0;
        for i in 0..n_u {
            row_free.push(free);
            fixed_off.push(fixed_col.len());
            for j in 0..n_v {
                let a = i * n_v + j;
                if lattice.fixed[a] {
                    fixed_col.push(j);
                    fixed_x.push(lattice.positions[a]);
                } else {
                    free += 1;
                }
            }
        }
        row_free.push(free);
        fixed_off.push(fixed_col.len());
        if external.len() != 3 * free {
            return None;
        }
        let free_nodes = (0..n).filter(|&a| !lattice.fixed[a]);
        let inv_mass = PerNode::new(
            free_nodes
                .clone()
                .map(|a| 1.0 / lattice.masses[a])
                .collect(),
        );
        let damping = PerNode::new(free_nodes.map(|a| lattice.damping[a]).collect());
        let external = PerNode::new(
            external
                .chunks_exact(3)
                .map(|f| [f[0], f[1], f[2]])
                .collect(),
        );
        let n_bands = (n_u / BAND_ROWS).clamp(1, MAX_BANDS);
        let bands = (0..n_bands)
            .map(|b| (b * n_u / n_bands, (b + 1) * n_u / n_bands))
            .collect();
        Some(Self {
            n_u,
            n_v,
            depth,
            dirs,
            row_free,
            fixed_off,
            fixed_col,
            fixed_x,
            external,
            inv_mass,
            damping,
            bands,
            n_springs: lattice.springs.len(),
        })
    }

    /// Length of one SoA row buffer (`x`, `y`, `z` of `n_v` nodes).
    fn row_len(&self) -> usize {
        3 * self.n_v
    }

    /// Scratch of one band: `depth + 1` position rows, `depth + 1` rows of spring forces per
    /// direction, one row of node forces.
    fn band_len(&self) -> usize {
        (self.depth + 2) * self.row_len() + self.dirs.len() * (self.depth + 1) * self.t_row_len()
    }

    /// Halo of one cut: the `depth` rows above it and the `depth` rows below it.
    fn halo_len(&self) -> usize {
        2 * self.depth * self.row_len()
    }

    /// Length of the `f64` workspace [`GridStep::symplectic_euler`] needs.
    pub fn workspace_len(&self) -> usize {
        self.bands.len() * self.band_len() + (self.bands.len() - 1) * self.halo_len()
    }

    /// Bytes a step must read and write at least: positions and velocities of the free nodes
    /// read and written once, the rest lengths (and per-spring stiffnesses, per-node values
    /// where they vary) read once.
    pub fn traffic_bytes(&self) -> usize {
        let free = self.row_free[self.n_u];
        let per_spring: usize = self
            .dirs
            .iter()
            .map(|d| {
                let count = (self.n_u - d.di) * (d.j_hi - d.j_lo);
                let k = match d.k {
                    Stiffness::Uniform(_) => 0,
                    Stiffness::PerSpring(_) => 8,
                };
                count * (8 + k)
            })
            .sum();
        4 * 3 * 8 * free
            + per_spring
            + self.external.bytes()
            + self.inv_mass.bytes()
            + self.damping.bytes()
    }

    /// One symplectic-Euler step in place: `v += Δt M⁻¹ (f_ext − f_int(q) − D v)`, then
    /// `q += Δt v`, on the free coordinates. `workspace` must have
    /// [`GridStep::workspace_len`] entries; its contents do not matter.
    pub fn symplectic_euler(&self, dt: f64, q: &mut [f64], v: &mut [f64], workspace: &mut [f64]) {
        // The bands' loops are compiled for the widest vector unit of the CPU (pulp's runtime
        // dispatch): the same IEEE operations in the same order at any width.
        self.step_with(dt, q, v, workspace, &|band| {
            pulp::Arch::new().dispatch(band)
        });
    }

    /// [`GridStep::symplectic_euler`] with each band run by `run` (a vector width chosen).
    fn step_with(
        &self,
        dt: f64,
        q: &mut [f64],
        v: &mut [f64],
        workspace: &mut [f64],
        run: &(dyn Fn(Band<'_>) + Sync),
    ) {
        let free = self.row_free[self.n_u];
        assert_eq!(q.len(), 3 * free, "positions of {free} free nodes expected");
        assert_eq!(
            v.len(),
            3 * free,
            "velocities of {free} free nodes expected"
        );
        assert!(
            workspace.len() >= self.workspace_len(),
            "grid step workspace: {} entries needed, {} given",
            self.workspace_len(),
            workspace.len()
        );
        let (halos, scratch) = workspace.split_at_mut((self.bands.len() - 1) * self.halo_len());
        // Old positions around every cut, before any band moves a node.
        for (b, halo) in halos.chunks_exact_mut(self.halo_len().max(1)).enumerate() {
            let cut = self.bands[b + 1].0;
            for (r, row) in halo.chunks_exact_mut(self.row_len()).enumerate() {
                let p = cut as isize - self.depth as isize + r as isize;
                if p >= 0 && (p as usize) < self.n_u {
                    self.load_row(p as usize, q, 0, row);
                }
            }
        }
        let parallel = self.n_springs >= SERIAL_SPRINGS;
        let scratch = &mut scratch[..self.bands.len() * self.band_len()];
        self.run_bands(0, self.bands.len(), dt, q, v, scratch, halos, parallel, run);
    }

    /// Bands `b0 .. b1`, which own `q` and `v` (their free coordinates) and `scratch`.
    fn run_bands(
        &self,
        b0: usize,
        b1: usize,
        dt: f64,
        q: &mut [f64],
        v: &mut [f64],
        scratch: &mut [f64],
        halos: &[f64],
        parallel: bool,
        run: &(dyn Fn(Band<'_>) + Sync),
    ) {
        if b1 - b0 == 1 {
            run(Band {
                step: self,
                b: b0,
                dt,
                q,
                v,
                scratch,
                halos,
            });
            return;
        }
        let mid = (b0 + b1) / 2;
        let first = self.row_free[self.bands[b0].0];
        let split = 3 * (self.row_free[self.bands[mid].0] - first);
        let (q_lo, q_hi) = q.split_at_mut(split);
        let (v_lo, v_hi) = v.split_at_mut(split);
        let (s_lo, s_hi) = scratch.split_at_mut((mid - b0) * self.band_len());
        if parallel {
            rayon::join(
                || self.run_bands(b0, mid, dt, q_lo, v_lo, s_lo, halos, parallel, run),
                || self.run_bands(mid, b1, dt, q_hi, v_hi, s_hi, halos, parallel, run),
            );
        } else {
            self.run_bands(b0, mid, dt, q_lo, v_lo, s_lo, halos, parallel, run);
            self.run_bands(mid, b1, dt, q_hi, v_hi, s_hi, halos, parallel, run);
        }
    }

    /// Copies the old positions of row `p` into the SoA buffer `out` from `q`, the free
    /// coordinates starting at free node `first` (fixed nodes from their positions).
    #[inline(always)]
    fn load_row(&self, p: usize, q: &[f64], first: usize, out: &mut [f64]) {
        let n_v = self.n_v;
        let (xs, rest) = out.split_at_mut(n_v);
        let (ys, zs) = rest.split_at_mut(n_v);
        let k0 = self.row_free[p] - first;
        let (f0, f1) = (self.fixed_off[p], self.fixed_off[p + 1]);
        if f0 == f1 {
            let src = &q[3 * k0..3 * (k0 + n_v)];
            for (((c, x), y), z) in src.chunks_exact(3).zip(xs).zip(ys).zip(zs) {
                (*x, *y, *z) = (c[0], c[1], c[2]);
            }
            return;
        }
        let (mut k, mut f) = (k0, f0);
        for j in 0..n_v {
            let x = if f < f1 && self.fixed_col[f] == j {
                f += 1;
                self.fixed_x[f - 1]
            } else {
                k += 1;
                [q[3 * k - 3], q[3 * k - 2], q[3 * k - 1]]
            };
            (xs[j], ys[j], zs[j]) = (x[0], x[1], x[2]);
        }
    }

    /// Band `b`: rows `r0 .. r1` of the grid, `q` and `v` its free coordinates.
    #[inline(always)]
    fn band(
        &self,
        b: usize,
        dt: f64,
        q: &mut [f64],
        v: &mut [f64],
        scratch: &mut [f64],
        halos: &[f64],
    ) {
        let (r0, r1) = self.bands[b];
        let depth = self.depth;
        let row = self.row_len();
        let ring = depth + 1;
        let (xring, rest) = scratch.split_at_mut(ring * row);
        let (tring, frow) = rest.split_at_mut(self.dirs.len() * ring * self.t_row_len());
        let frow = &mut frow[..row];
        let first = self.row_free[r0];
        // Halo rows: above the band from the cut at r0, below it from the cut at r1.
        let halo_row = |p: usize| -> &[f64] {
            if p < r0 {
                let h = (b - 1) * self.halo_len() + (p + depth - r0) * row;
                &halos[h..h + row]
            } else {
                let h = b * self.halo_len() + (depth + p - r1) * row;
                &halos[h..h + row]
            }
        };
        let p0 = r0.saturating_sub(depth);
        for p in p0..(p0 + ring).min(self.n_u) {
            let slot = &mut xring[(p % ring) * row..][..row];
            if p < r0 || p >= r1 {
                slot.copy_from_slice(halo_row(p));
            } else {
                self.load_row(p, q, first, slot);
            }
        }
        // Columns without a spring and the margins stay zero throughout.
        tring.fill(0.0);
        for p in p0..r1 {
            for (d, dir) in self.dirs.iter().enumerate() {
                let p_hi = p + dir.di;
                if p_hi < r0 {
                    // Springs of the band above only.
                    continue;
                }
                let t = self.t_row_mut(tring, d, p);
                if p_hi >= self.n_u {
                    t.fill(0.0);
                } else {
                    self.spring_row(p, dir, xring, t);
                }
            }
            if p >= r0 {
                self.row_forces(p, tring, frow);
                self.update_row(p, dt, first, q, v, frow);
            }
            // Row p leaves the position ring; row p + ring takes its slot.
            let next = p + ring;
            if next < self.n_u && next < r1 + depth {
                let xs = &mut xring[(p % ring) * row..][..row];
                if next >= r1 {
                    xs.copy_from_slice(halo_row(next));
                } else {
                    self.load_row(next, q, first, xs);
                }
            }
        }
    }

    /// Length of one row of spring forces: `x`, `y`, `z` of `n_v` springs, each with a margin
    /// of [`MAX_DJ`] zeros on both sides so that shifted reads stay in bounds.
    fn t_row_len(&self) -> usize {
        3 * (self.n_v + 2 * MAX_DJ)
    }

    /// The spring forces of direction `d` at lower row `p`, in the ring.
    fn t_row<'a>(&self, tring: &'a [f64], d: usize, p: usize) -> &'a [f64] {
        let len = self.t_row_len();
        let ring = self.depth + 1;
        &tring[(d * ring + p % ring) * len..][..len]
    }

    fn t_row_mut<'a>(&self, tring: &'a mut [f64], d: usize, p: usize) -> &'a mut [f64] {
        let len = self.t_row_len();
        let ring = self.depth + 1;
        &mut tring[(d * ring + p % ring) * len..][..len]
    }

    /// The forces `s d` (lower node minus upper node) of the springs of `dir` with their lower
    /// node in row `p`, into the columns `j_lo .. j_hi` of `t`.
    #[inline(always)]
    fn spring_row(&self, p: usize, dir: &Direction, xring: &[f64], t: &mut [f64]) {
        let n_v = self.n_v;
        let row = self.row_len();
        let ring = self.depth + 1;
        let (lo, hi) = (dir.j_lo, dir.j_hi);
        let len = hi - lo;
        let x_lo = &xring[(p % ring) * row..][..row];
        let x_hi = &xring[((p + dir.di) % ring) * row..][..row];
        let rest = &dir.rest[p * n_v + lo..p * n_v + hi];
        let w = n_v + 2 * MAX_DJ;
        let (tx, rest_t) = t.split_at_mut(w);
        let (ty, tz) = rest_t.split_at_mut(w);
        let at = MAX_DJ + lo;
        let (tx, ty, tz) = (
            &mut tx[at..at + len],
            &mut ty[at..at + len],
            &mut tz[at..at + len],
        );
        let (ax, ay, az) = (
            &x_lo[lo..hi],
            &x_lo[n_v + lo..n_v + hi],
            &x_lo[2 * n_v + lo..2 * n_v + hi],
        );
        let h0 = (lo as isize + dir.dj) as usize;
        let (bx, by, bz) = (
            &x_hi[h0..h0 + len],
            &x_hi[n_v + h0..n_v + h0 + len],
            &x_hi[2 * n_v + h0..2 * n_v + h0 + len],
        );
        match &dir.k {
            Stiffness::Uniform(k) => {
                let k = *k;
                for i in 0..len {
                    let d = [ax[i] - bx[i], ay[i] - by[i], az[i] - bz[i]];
                    let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                    let s = k * (1.0 - rest[i] / r);
                    (tx[i], ty[i], tz[i]) = (s * d[0], s * d[1], s * d[2]);
                }
            }
            Stiffness::PerSpring(ks) => {
                let ks = &ks[p * n_v + lo..p * n_v + hi];
                for i in 0..len {
                    let d = [ax[i] - bx[i], ay[i] - by[i], az[i] - bz[i]];
                    let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                    let s = ks[i] * (1.0 - rest[i] / r);
                    (tx[i], ty[i], tz[i]) = (s * d[0], s * d[1], s * d[2]);
                }
            }
        }
    }

    /// The internal force of every node of row `p` (SoA into `f`): per direction, the force
    /// of its spring as lower node minus that of its spring as upper node (zero where a node
    /// has none), directions in their fixed order.
    #[inline(always)]
    fn row_forces(&self, p: usize, tring: &[f64], f: &mut [f64]) {
        let n_v = self.n_v;
        let w = n_v + 2 * MAX_DJ;
        f.fill(0.0);
        for (d, dir) in self.dirs.iter().enumerate() {
            let lower = self.t_row(tring, d, p);
            // The spring at upper node (p, j) starts at (p − di, j − dj); none above row 0.
            let upper = (p >= dir.di).then(|| self.t_row(tring, d, p - dir.di));
            let shift = (MAX_DJ as isize - dir.dj) as usize;
            for c in 0..3 {
                let fc = &mut f[c * n_v..(c + 1) * n_v];
                let lo = &lower[c * w + MAX_DJ..c * w + MAX_DJ + n_v];
                match upper {
                    Some(upper) => {
                        let up = &upper[c * w + shift..c * w + shift + n_v];
                        for ((f, l), u) in fc.iter_mut().zip(lo).zip(up) {
                            *f += l - u;
                        }
                    }
                    None => {
                        for (f, l) in fc.iter_mut().zip(lo) {
                            *f += l;
                        }
                    }
                }
            }
        }
    }

    /// The update of the free nodes of row `p` from their internal forces `f` (SoA row):
    /// `v += Δt M⁻¹ (f_ext − f_int − D v)`, `q += Δt v`, written as the generic path writes it.
    #[inline(always)]
    fn update_row(&self, p: usize, dt: f64, first: usize, q: &mut [f64], v: &mut [f64], f: &[f64]) {
        let n_v = self.n_v;
        let (fx, rest) = f.split_at(n_v);
        let (fy, fz) = rest.split_at(n_v);
        let (f0, f1) = (self.fixed_off[p], self.fixed_off[p + 1]);
        if let (PerNode::Uniform(fext), PerNode::Uniform(inv_m), PerNode::Uniform(gamma), true) =
            (&self.external, &self.inv_mass, &self.damping, f0 == f1)
        {
            // No fixed node in the row and the same constants everywhere: one straight loop.
            let (inv_m, gamma) = (*inv_m, *gamma);
            let i0 = 3 * (self.row_free[p] - first);
            let qs = &mut q[i0..i0 + 3 * n_v];
            let vs = &mut v[i0..i0 + 3 * n_v];
            for (j, (qj, vj)) in qs
                .chunks_exact_mut(3)
                .zip(vs.chunks_exact_mut(3))
                .enumerate()
            {
                let fint = [fx[j], fy[j], fz[j]];
                for c in 0..3 {
                    let force = fext[c] - fint[c] - gamma * vj[c];
                    vj[c] += dt * inv_m * force;
                    qj[c] += dt * vj[c];
                }
            }
            return;
        }
        let mut k = self.row_free[p];
        let mut fixed = f0;
        for j in 0..n_v {
            if fixed < f1 && self.fixed_col[fixed] == j {
                fixed += 1;
                continue;
            }
            let (fext, inv_m, gamma) = (
                self.external.get(k),
                self.inv_mass.get(k),
                self.damping.get(k),
            );
            let fint = [fx[j], fy[j], fz[j]];
            let i = 3 * (k - first);
            for c in 0..3 {
                let force = fext[c] - fint[c] - gamma * v[i + c];
                v[i + c] += dt * inv_m * force;
                q[i + c] += dt * v[i + c];
            }
            k += 1;
        }
    }
}

/// One band of [`GridStep::symplectic_euler`], dispatched to the CPU's vector width.
struct Band<'a> {
    step: &'a GridStep,
    b: usize,
    dt: f64,
    q: &'a mut [f64],
    v: &'a mut [f64],
    scratch: &'a mut [f64],
    halos: &'a [f64],
}

impl pulp::WithSimd for Band<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) {
        let Band {
            step,
            b,
            dt,
            q,
            v,
            scratch,
            halos,
        } = self;
        step.band(b, dt, q, v, scratch, halos);
    }
}

impl FusedStep for GridStep {
    fn workspace_len(&self) -> usize {
        GridStep::workspace_len(self)
    }

    /// The external force of a lattice is constant: `t` does not enter.
    fn symplectic_euler(
        &self,
        _t: f64,
        dt: f64,
        q: &mut [f64],
        v: &mut [f64],
        workspace: &mut [f64],
    ) {
        GridStep::symplectic_euler(self, dt, q, v, workspace);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Class, Constants, LatticeOptions, ParameterGrid, SpringKind};
    use nurbspring_geom::{KnotVector, NurbsSurface};

    /// A wavy sheet with every kind of spring and a few fixed nodes.
    fn lattice(n_u: usize, n_v: usize) -> SpringLattice {
        let k = KnotVector::try_new(vec![0., 0., 0., 1., 1., 1.], 2).unwrap();
        let pts: Vec<[f64; 3]> = (0..9)
            .map(|c| {
                [
                    (c / 3) as f64,
                    (c % 3) as f64,
                    if c == 4 { 0.5 } else { 0.0 },
                ]
            })
            .collect();
        let surface = NurbsSurface::try_new(k.clone(), k, pts, vec![1.0; 9]).unwrap();
        let options = LatticeOptions {
            grid: ParameterGrid::Uniform {
                nodes_u: n_u,
                nodes_v: n_v,
            },
            constants: Constants::from_pairs([
                (Class::Spring(SpringKind::Structural), 10.0),
                (Class::Spring(SpringKind::Shear), 4.0),
                (Class::Spring(SpringKind::Bend), 1.0),
            ]),
            pre_strain: 0.03,
            gravity: [0.0, 0.0, -1.0],
            ..Default::default()
        };
        let mut l = SpringLattice::from_surface(&surface, &options, &[]).unwrap();
        for a in [
            0,
            n_v + 1,
            31 * n_v,
            32 * n_v + 2,
            33 * n_v - 1,
            n_u * n_v - 1,
        ] {
            l.fixed[a] = true;
        }
        l
    }

    fn run(step: &GridStep, q: &[f64], v: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let (mut q, mut v) = (q.to_vec(), v.to_vec());
        let mut w = vec![f64::NAN; step.workspace_len()];
        for _ in 0..4 {
            step.symplectic_euler(1e-3, &mut q, &mut v, &mut w);
        }
        (q, v)
    }

    #[test]
    fn the_cut_into_bands_does_not_change_a_bit() {
        let l = lattice(70, 9);
        let free: Vec<usize> = (0..l.n_nodes()).filter(|&a| !l.fixed[a]).collect();
        let external: Vec<f64> = free
            .iter()
            .flat_map(|&a| l.gravity.map(|g| g * l.masses[a]))
            .collect();
        let step = GridStep::new(&l, &external).unwrap();
        assert_eq!(step.depth, 2);
        assert_eq!(step.bands, vec![(0, 35), (35, 70)]);
        let q: Vec<f64> = free
            .iter()
            .flat_map(|&a| l.positions[a])
            .enumerate()
            .map(|(i, x)| x + 1e-3 * (i as f64 * 0.37).sin())
            .collect();
        let v: Vec<f64> = (0..q.len()).map(|i| (i as f64 * 0.11).cos()).collect();
        let expected = run(&step, &q, &v);
        for bands in [
            vec![(0, 70)],
            vec![(0, 3), (3, 6), (6, 40), (40, 69), (69, 70)],
            vec![(0, 31), (31, 32), (32, 33), (33, 70)],
        ] {
            let cut = GridStep {
                bands: bands.clone(),
                ..step.clone()
            };
            assert_eq!(run(&cut, &q, &v), expected, "bands {bands:?}");
        }
        // The band compiled without the CPU's extensions (pulp's scalar fallback) gives the
        // same bits as the dispatched one (AVX2 where the CPU has it).
        use pulp::WithSimd;
        let widths: [(&str, &(dyn Fn(Band<'_>) + Sync)); 1] =
            [("baseline", &|band| band.with_simd(pulp::Scalar))];
        for (name, width) in widths {
            let (mut q, mut v) = (q.clone(), v.clone());
            let mut w = vec![f64::NAN; step.workspace_len()];
            for _ in 0..4 {
                step.step_with(1e-3, &mut q, &mut v, &mut w, width);
            }
            assert_eq!((q, v), expected, "{name}");
        }
    }
}
