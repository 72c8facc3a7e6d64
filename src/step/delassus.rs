//! The Delassus operator W = H A_k⁻¹ Hᵀ (the fast path of the README's design notes): the response of
//! the contact velocities to unit contact forces, computed once per run. Two forms:
//!
//! * **dense** (d n_c solves, an m × m matrix, m = d n_c): exact; cost and memory grow like m²
//!   per apply and m³ per factorization — the small scenes' form;
//! * **sparse** (probing): W's entries decay with the distance between contact nodes (the step
//!   operator A_k = M + (k/2) C + (k²/4) K is mass-dominated over a step, and the elastic response
//!   of a strip decays over its height). One probe column at the middle of Γ3 measures the radius
//!   R beyond which every entry is below `truncation` × the diagonal; contact nodes more than 2R
//!   apart are then probed together (a greedy distance colouring), so W costs d × (colours) solves
//!   and keeps only the entries within R. The error of the kept operator is measured on a random
//!   vector against an exact solve and reported (`SparseStats`).
//!
//! The choice between them is automatic from the sizes (`[solver] contact_solve = "auto"`), or set.

use std::cell::RefCell;
use std::collections::HashMap;

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::solvers::{DenseSolveCore, Llt, Solve};
use faer::matrix_free::conjugate_gradient::{CgParams, conjugate_gradient, conjugate_gradient_scratch};
use faer::matrix_free::{InitialGuessStatus, LinOp, Precond};
use faer::sparse::linalg::cholesky::{LltRef, SymbolicCholesky, SymmetricOrdering, factorize_symbolic_cholesky};
use faer::sparse::{SparseColMat, Triplet};
use faer::{Conj, Mat, MatMut, MatRef, Par, Side};

use crate::linalg::Cholesky;
use crate::model::contact::ContactModel;
use crate::model::kinds::ContactSolve;

/// The Delassus operator in one of its two forms.
pub enum Delassus {
    Dense(Mat<f64>),
    Sparse(SparseDelassus),
}

/// The probed, truncated Delassus operator and what it cost.
pub struct SparseDelassus {
    pub w: SparseColMat<usize, f64>,
    /// each component's position in a fill-reducing order of W (AMD, computed once); the
    /// Newton matrices W_UU + D are factored in the order it induces on U
    pub rank: Vec<usize>,
    pub stats: SparseStats,
}

/// Facts of the sparse form (summary.json `contact_solve`).
#[derive(Debug, Clone, Copy, Default, serde::Serialize, serde::Deserialize)]
pub struct SparseStats {
    /// entries below this fraction of the diagonal were dropped
    pub truncation: f64,
    /// the probing radius R (mesh units)
    pub radius: f64,
    /// colours (probes per component)
    pub colours: usize,
    /// A_k solves spent on W
    pub solves: usize,
    /// stored entries / m²
    pub density: f64,
    /// ‖W_sparse x − H A_k⁻¹ Hᵀ x‖_∞ / ‖H A_k⁻¹ Hᵀ x‖_∞ for a pseudo-random x
    pub apply_error: f64,
}

static ZERO: f64 = 0.0;

impl std::ops::Index<(usize, usize)> for Delassus {
    type Output = f64;
    /// W_ij (0 for an entry the sparse form does not keep).
    fn index(&self, (i, j): (usize, usize)) -> &f64 {
        match self {
            Delassus::Dense(w) => &w[(i, j)],
            Delassus::Sparse(s) => {
                let rows = s.w.symbolic().row_idx_of_col_raw(j);
                match rows.binary_search(&i) {
                    Ok(p) => &s.w.val_of_col(j)[p],
                    Err(_) => &ZERO,
                }
            }
        }
    }
}

impl std::fmt::Debug for Delassus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Delassus({}, {} × {})", self.form(), self.dim(), self.dim())
    }
}

impl Delassus {
    /// m = d n_c.
    pub fn dim(&self) -> usize {
        match self {
            Delassus::Dense(w) => w.nrows(),
            Delassus::Sparse(s) => s.w.nrows(),
        }
    }
    /// "dense" or "sparse".
    pub fn form(&self) -> &'static str {
        match self {
            Delassus::Dense(_) => "dense",
            Delassus::Sparse(_) => "sparse",
        }
    }
    pub fn sparse_stats(&self) -> Option<SparseStats> {
        match self {
            Delassus::Dense(_) => None,
            Delassus::Sparse(s) => Some(s.stats),
        }
    }
    /// out += alpha W r, by columns, skipping zero forces (separated nodes); a dense W from
    /// [`GEMV_FROM`](crate::defaults::GEMV_FROM) components on goes through faer's
    /// matrix–vector product (SIMD of the machine, chosen at run time) over all columns.
    pub fn add_times(&self, r: &[f64], alpha: f64, out: &mut [f64]) {
        if let Delassus::Dense(w) = self
            && w.nrows() >= crate::defaults::GEMV_FROM
        {
            let rhs = faer::MatRef::from_column_major_slice(r, r.len(), 1);
            let dst = faer::MatMut::from_column_major_slice_mut(out, w.nrows(), 1);
            faer::linalg::matmul::matmul(dst, faer::Accum::Add, w.as_ref(), rhs, alpha, Par::Seq);
            return;
        }
        for (l, &rl) in r.iter().enumerate() {
            if rl == 0.0 {
                continue;
            }
            let a = alpha * rl;
            match self {
                Delassus::Dense(w) => {
                    for (o, w) in out.iter_mut().zip(w.col_as_slice(l)) {
                        *o += w * a;
                    }
                }
                Delassus::Sparse(s) => column_add(&s.w, l, a, out),
            }
        }
    }
    /// (W r)_j alone, summed over l in the order of [`add_times`](Self::add_times) (so the same
    /// bits): W is symmetric, so row j is read as column j.
    pub fn row_times(&self, j: usize, r: &[f64]) -> f64 {
        let mut out = 0.0;
        match self {
            Delassus::Dense(w) => {
                for (&rl, &wl) in r.iter().zip(w.col_as_slice(j)) {
                    if rl != 0.0 {
                        out += wl * rl;
                    }
                }
            }
            Delassus::Sparse(s) => {
                for (&l, &wl) in s.w.symbolic().row_idx_of_col_raw(j).iter().zip(s.w.val_of_col(j)) {
                    if r[l] != 0.0 {
                        out += wl * r[l];
                    }
                }
            }
        }
        out
    }
    /// The dense matrix (a copy for the sparse form: the unsymmetric Newton systems and the
    /// conic twin work on it).
    pub fn to_dense(&self) -> Mat<f64> {
        match self {
            Delassus::Dense(w) => w.clone(),
            Delassus::Sparse(s) => s.w.to_dense(),
        }
    }
}

/// W in the form `choice` asks for. `auto` takes the dense form below
/// [`SPARSE_FROM`](crate::defaults::SPARSE_FROM) contact unknowns; from there it probes the
/// decay of W (d solves) and takes the sparse form when the probed radius keeps at most
/// [`SPARSE_DENSITY`](crate::defaults::SPARSE_DENSITY) of the entries (measured crossover: README,
/// "Speed").
pub fn build(a: &Cholesky, contact: &ContactModel, positions: &[[f64; 3]], choice: ContactSolve) -> Delassus {
    build_with_responses(a, contact, positions, choice).0
}

/// [`build`], and for the dense form the responses G = A_k⁻¹ Hᵀ when they fit in
/// [`RESPONSES_BYTES`](crate::defaults::RESPONSES_BYTES).
pub fn build_with_responses(
    a: &Cholesky,
    contact: &ContactModel,
    positions: &[[f64; 3]],
    choice: ContactSolve,
) -> (Delassus, Option<Mat<f64>>) {
    let m = contact.dim * contact.n();
    let truncation = crate::defaults::DELASSUS_TRUNCATION;
    let probe = match choice {
        ContactSolve::Dense => None,
        ContactSolve::Sparse => Some(Probe::new(a, contact, positions, truncation)),
        ContactSolve::Auto if m < crate::defaults::SPARSE_FROM => None,
        ContactSolve::Auto => {
            let p = Probe::new(a, contact, positions, truncation);
            (p.density <= crate::defaults::SPARSE_DENSITY).then_some(p)
        }
    };
    // the sparse form falls back to the dense one if faer refuses to build it (it cannot for
    // indices below m, but a failed allocation should not end the run)
    match probe.and_then(|p| sparse(a, contact, positions, &p)) {
        Some(s) => (Delassus::Sparse(s), None),
        None => {
            let keep = 8.0 * a.dim() as f64 * m as f64 <= crate::defaults::RESPONSES_BYTES;
            let (w, g) = dense_with_responses(a, contact, keep);
            (Delassus::Dense(w), g)
        }
    }
}

/// The decay of W measured at one node: the radius R beyond which every entry of its columns is
/// below `truncation` × its diagonal, and the share of contact nodes within R.
pub struct Probe {
    pub truncation: f64,
    pub radius: f64,
    pub density: f64,
}

impl Probe {
    /// Probe the d columns of the contact node nearest the centroid of Γ3 (d solves).
    pub fn new(a: &Cholesky, contact: &ContactModel, positions: &[[f64; 3]], truncation: f64) -> Probe {
        let (d, nc) = (contact.dim, contact.n());
        let m = d * nc;
        let centroid: Vec<f64> = (0..3).map(|k| positions.iter().map(|p| p[k]).sum::<f64>() / nc as f64).collect();
        let i0 = (0..nc)
            .min_by(|&a, &b| distance(&positions[a], &centroid).total_cmp(&distance(&positions[b], &centroid)))
            .unwrap_or(0);
        let columns = responses(a, contact, &(0..d).map(|c| unit(m, d * i0 + c)).collect::<Vec<_>>());
        let mut radius = 0.0f64;
        for (c, col) in columns.iter().enumerate() {
            let diag = col[d * i0 + c].abs();
            for j in 0..nc {
                if (0..d).any(|r| col[d * j + r].abs() > truncation * diag) {
                    radius = radius.max(distance(&positions[i0], &positions[j]));
                }
            }
        }
        let within = (0..nc).filter(|&j| distance(&positions[i0], &positions[j]) <= radius).count();
        Probe { truncation, radius, density: within as f64 / nc as f64 }
    }
}

fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>().sqrt()
}

/// The dense W (d n_c × d n_c, symmetric positive definite), components (ν_1, τ_1, …, ν_2, τ_2, …):
/// d n_c solves in blocks of 64 right-hand sides.
pub fn dense(a: &Cholesky, contact: &ContactModel) -> Mat<f64> {
    dense_with_responses(a, contact, false).0
}

/// The dense W and, if `keep`, the responses G = A_k⁻¹ Hᵀ (n × d n_c) from the same solves
/// (W = H G, symmetrized).
pub fn dense_with_responses(a: &Cholesky, contact: &ContactModel, keep: bool) -> (Mat<f64>, Option<Mat<f64>>) {
    let m = contact.dim * contact.n();
    let mut w = Mat::<f64>::zeros(m, m);
    let mut g = keep.then(|| Mat::<f64>::zeros(a.dim(), m));
    const BLOCK: usize = 64;
    for start in (0..m).step_by(BLOCK) {
        let units: Vec<Vec<f64>> = (start..(start + BLOCK).min(m)).map(|l| unit(m, l)).collect();
        let x = solve_forces(a, contact, &units);
        for c in 0..units.len() {
            let col: Vec<f64> = (0..a.dim()).map(|i| x[(i, c)]).collect();
            for (j, v) in contact.restrict(&col).iter().enumerate() {
                w[(j, start + c)] = *v;
            }
            if let Some(g) = &mut g {
                g.col_as_slice_mut(start + c).copy_from_slice(&col);
            }
        }
    }
    // symmetrize the round-off
    for i in 0..m {
        for j in 0..i {
            let s = 0.5 * (w[(i, j)] + w[(j, i)]);
            w[(i, j)] = s;
            w[(j, i)] = s;
        }
    }
    (w, g)
}

/// The unit force on contact component l (of m).
fn unit(m: usize, l: usize) -> Vec<f64> {
    let mut e = vec![0.0; m];
    e[l] = 1.0;
    e
}

/// out += a W[:, l] for a sparse W.
fn column_add(w: &SparseColMat<usize, f64>, l: usize, a: f64, out: &mut [f64]) {
    for (&i, v) in w.symbolic().row_idx_of_col_raw(l).iter().zip(w.val_of_col(l)) {
        out[i] += v * a;
    }
}

/// Solve A_k X = Hᵀ F for a block of contact force vectors F (columns of `forces`, each of
/// length m): X, n × (columns).
fn solve_forces(a: &Cholesky, contact: &ContactModel, forces: &[Vec<f64>]) -> Mat<f64> {
    let n = a.dim();
    let mut rhs = Mat::<f64>::zeros(n, forces.len());
    for (c, f) in forces.iter().enumerate() {
        contact.scatter_add(f, rhs.col_as_slice_mut(c));
    }
    a.solve_mat_in_place(&mut rhs);
    rhs
}

/// H A_k⁻¹ Hᵀ F per column of `forces`.
fn responses(a: &Cholesky, contact: &ContactModel, forces: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let x = solve_forces(a, contact, forces);
    (0..forces.len()).map(|c| contact.restrict(&(0..a.dim()).map(|i| x[(i, c)]).collect::<Vec<f64>>())).collect()
}

/// The sparse W by probing (module doc): `positions` are the contact nodes' coordinates, `probe`
/// the measured decay radius. None if faer cannot build the matrix.
pub fn sparse(a: &Cholesky, contact: &ContactModel, positions: &[[f64; 3]], probe: &Probe) -> Option<SparseDelassus> {
    let (d, nc) = (contact.dim, contact.n());
    let m = d * nc;
    let (radius, truncation) = (probe.radius, probe.truncation);
    let dist = |i: usize, j: usize| distance(&positions[i], &positions[j]);
    // 1. greedy colouring: nodes of one colour are more than 2R apart (a grid of cells 2R wide)
    let cell = (2.0 * radius).max(f64::MIN_POSITIVE);
    let key = |i: usize| -> [i64; 3] { [0, 1, 2].map(|k| (positions[i][k] / cell).floor() as i64) };
    let mut grid: HashMap<[i64; 3], Vec<usize>> = HashMap::new();
    let mut colour = vec![usize::MAX; nc];
    let mut colours = 0;
    let near = |grid: &HashMap<[i64; 3], Vec<usize>>, i: usize, within: f64| -> Vec<usize> {
        let k = key(i);
        let mut out = Vec::new();
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(v) = grid.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) {
                        out.extend(v.iter().copied().filter(|&j| dist(i, j) <= within));
                    }
                }
            }
        }
        out
    };
    for i in 0..nc {
        let taken: Vec<usize> = near(&grid, i, 2.0 * radius).iter().map(|&j| colour[j]).collect();
        let c = (0..).find(|c| !taken.contains(c)).unwrap_or(0);
        colour[i] = c;
        colours = colours.max(c + 1);
        grid.entry(key(i)).or_default().push(i);
    }
    // 2. probe each colour and component; keep the entries within R of the probed node
    let mut triplets = Vec::new();
    let probes: Vec<(usize, usize)> = (0..colours).flat_map(|c| (0..d).map(move |r| (c, r))).collect();
    for block in probes.chunks(64) {
        let forces: Vec<Vec<f64>> = block
            .iter()
            .map(|&(c, r)| {
                let mut f = vec![0.0; m];
                for j in (0..nc).filter(|&j| colour[j] == c) {
                    f[d * j + r] = 1.0;
                }
                f
            })
            .collect();
        for (&(c, r), y) in block.iter().zip(responses(a, contact, &forces)) {
            for j in (0..nc).filter(|&j| colour[j] == c) {
                for i in near(&grid, j, radius) {
                    for s in 0..d {
                        triplets.push(Triplet::new(d * i + s, d * j + r, y[d * i + s]));
                    }
                }
            }
        }
    }
    // symmetrize: average W_ij and W_ji (both are kept: the neighbour relation is symmetric)
    let sym: Vec<Triplet<usize, usize, f64>> = triplets
        .iter()
        .flat_map(|t| [Triplet::new(t.row, t.col, 0.5 * t.val), Triplet::new(t.col, t.row, 0.5 * t.val)])
        .collect();
    let w = SparseColMat::<usize, f64>::try_new_from_triplets(m, m, &sym).ok()?;
    // 3. the kept operator against an exact solve on a pseudo-random force
    let x: Vec<f64> = (0..m).map(|l| ((l * 7919 + 13) % 101) as f64 / 101.0 - 0.5).collect();
    let exact = &responses(a, contact, std::slice::from_ref(&x))[0];
    let mut kept = vec![0.0; m];
    for (l, &xl) in x.iter().enumerate() {
        column_add(&w, l, xl, &mut kept);
    }
    let apply_error = kept.iter().zip(exact).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max)
        / crate::linalg::norm_inf(exact).max(f64::MIN_POSITIVE);
    let density = w.compute_nnz() as f64 / (m * m) as f64;
    let rank = factorize_symbolic_cholesky(w.symbolic(), Side::Lower, SymmetricOrdering::Amd, Default::default())
        .ok()
        .and_then(|sym| sym.perm().map(|p| p.arrays().1.to_vec()))
        .unwrap_or_else(|| (0..m).collect());
    Some(SparseDelassus {
        w,
        rank,
        stats: SparseStats { truncation, radius, colours, solves: d * (colours + 1) + 1, density, apply_error },
    })
}

/// The tangent frames the Newton matrices read each slipping node in (3-D): node i's tangential
/// pair (τ_1, τ_2) is taken in the basis (ẑ_i, ẑ_i^⊥), ẑ_i the direction of t_i + ρ v̄_i on the
/// disk's slip branch and ẑ^⊥ = (−ẑ_2, ẑ_1), where the friction force is known along ẑ and
/// follows the slip rate across it (see `newton::direction`). W' = Qᵀ W Q with Q the block
/// rotation; nodes without a frame (all of them in 2-D) keep their own components.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SlipFrames {
    dim: usize,
    /// per contact node: ẑ in the node's (τ_1, τ_2) components, or None
    zhat: Vec<Option<[f64; 2]>>,
}

impl SlipFrames {
    /// No node rotated (`dim` components per node, `n` nodes).
    pub fn identity(dim: usize, n: usize) -> SlipFrames {
        SlipFrames { dim, zhat: vec![None; if dim == 3 { n } else { 0 }] }
    }
    /// Read node i's tangential pair along ẑ (unit) and ẑ^⊥.
    pub fn rotate(&mut self, i: usize, zhat: [f64; 2]) {
        self.zhat[i] = Some(zhat);
    }
    /// Whether any node is rotated.
    pub fn any(&self) -> bool {
        self.zhat.iter().any(Option::is_some)
    }
    /// The global components (index, coefficient) that make the local component l: one, or two
    /// for a rotated tangential component.
    fn basis(&self, l: usize) -> ([(usize, f64); 2], usize) {
        let (i, c) = (l / self.dim.max(1), l % self.dim.max(1));
        match self.zhat.get(i).copied().flatten() {
            Some(z) if c >= 1 => {
                let (t1, t2) = (self.dim * i + 1, self.dim * i + 2);
                // slot 1: ẑ = (z_1, z_2); slot 2: ẑ^⊥ = (−z_2, z_1)
                if c == 1 { ([(t1, z[0]), (t2, z[1])], 2) } else { ([(t1, -z[1]), (t2, z[0])], 2) }
            }
            _ => ([(l, 1.0), (l, 0.0)], 1),
        }
    }
    /// Global components → local ones (x ← Qᵀ x).
    pub fn to_local(&self, x: &mut [f64]) {
        for (i, z) in self.zhat.iter().enumerate() {
            if let Some(z) = z {
                let (a, b) = (x[self.dim * i + 1], x[self.dim * i + 2]);
                x[self.dim * i + 1] = z[0] * a + z[1] * b;
                x[self.dim * i + 2] = -z[1] * a + z[0] * b;
            }
        }
    }
    /// Local components → global ones (x ← Q x).
    pub fn to_global(&self, x: &mut [f64]) {
        for (i, z) in self.zhat.iter().enumerate() {
            if let Some(z) = z {
                let (a, b) = (x[self.dim * i + 1], x[self.dim * i + 2]);
                x[self.dim * i + 1] = z[0] * a - z[1] * b;
                x[self.dim * i + 2] = z[1] * a + z[0] * b;
            }
        }
    }
}

impl Delassus {
    /// W'_{l l'} = (Qᵀ W Q)_{l l'} in the local components of `frames`.
    pub fn entry_in(&self, frames: &SlipFrames, l: usize, lp: usize) -> f64 {
        if !frames.any() {
            return self[(l, lp)];
        }
        let ((a, na), (b, nb)) = (frames.basis(l), frames.basis(lp));
        let mut s = 0.0;
        for &(i, ci) in &a[..na] {
            for &(j, cj) in &b[..nb] {
                s += ci * cj * self[(i, j)];
            }
        }
        s
    }
    /// out += alpha W' x in the local components of `frames` (x local, out local).
    pub fn add_times_in(&self, frames: &SlipFrames, x: &[f64], alpha: f64, out: &mut [f64]) {
        if !frames.any() {
            return self.add_times(x, alpha, out);
        }
        let mut xg = x.to_vec();
        frames.to_global(&mut xg);
        let mut wx = vec![0.0; out.len()];
        self.add_times(&xg, alpha, &mut wx);
        frames.to_local(&mut wx);
        for (o, v) in out.iter_mut().zip(&wx) {
            *o += v;
        }
    }
}

/// The key of a kept factorization (checkpoints): U, and D and the frames as exact bit patterns.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FactorKey {
    pub unknown: Vec<usize>,
    diag: Vec<u64>,
    frames_dim: usize,
    frames: Vec<Option<[u64; 2]>>,
}

/// How the Newton matrices W'_UU + D were solved so far (summary.json, the benchmark).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct FactorCounts {
    /// Cholesky factorizations computed
    pub factorizations: usize,
    /// solves by a kept factorization of the same matrix (bit-identical to refactoring)
    pub reuses: usize,
    /// solves by conjugate gradients preconditioned with the kept factorization of a nearby matrix
    /// (same unknowns, other D or slip frames)
    pub pcg_solves: usize,
    /// conjugate-gradient iterations over those solves
    pub pcg_iterations: usize,
    /// Newton directions in velocity form (W⁻¹, conjugate gradients on the free components),
    /// and their iterations
    pub velocity_solves: usize,
    pub velocity_iterations: usize,
}

/// Cholesky factorizations of W'_UU + D (a principal submatrix of the Delassus operator, read
/// in the slipping nodes' frames, plus a nonnegative diagonal), the Newton matrix of the frozen
/// step problem (see `newton::reduced_direction`). The last one is kept with its key (U, D,
/// frames): Newton, the F.1 iterations and the next steps reuse it while their active and stick
/// sets, and so the matrix, are unchanged — a reuse is bit-identical to refactoring. When only D
/// or the slip frames moved (3-D slip: the friction force's stiffness across the slip and its
/// direction change every iteration), the system is solved by conjugate gradients preconditioned
/// with the kept factor, to [`PCG_TOLERANCE`](crate::defaults::PCG_TOLERANCE) of the right-hand
/// side, and the factor is only recomputed when that takes more than
/// [`PCG_MAX_ITERATIONS`](crate::defaults::PCG_MAX_ITERATIONS).
#[derive(Default)]
pub struct DelassusFactors {
    last: RefCell<Option<Factor>>,
    counts: RefCell<FactorCounts>,
}

struct Factor {
    unknown: Vec<usize>,
    diag: Vec<f64>,
    frames: SlipFrames,
    llt: FactorKind,
}

enum FactorKind {
    Dense(Llt<f64>),
    /// boxed: the sparse factor's symbolic and numeric parts are much larger than a dense Llt's handle
    Sparse(Box<SparseFactor>),
}

impl std::fmt::Debug for FactorKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            FactorKind::Dense(_) => "FactorKind::Dense",
            FactorKind::Sparse(_) => "FactorKind::Sparse",
        })
    }
}

impl FactorKind {
    fn solve_in_place(&self, b: &mut [f64]) {
        match self {
            FactorKind::Dense(llt) => llt.solve_in_place(faer::MatMut::from_column_major_slice_mut(b, b.len(), 1)),
            FactorKind::Sparse(llt) => llt.solve_in_place(b),
        }
    }
}

/// A sparse LLᵀ of W_UU + D in the order W's AMD order induces on U: `order[p]` is the local
/// index (into U) of the factor's p-th unknown.
struct SparseFactor {
    order: Vec<usize>,
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
}

impl SparseFactor {
    fn solve_in_place(&self, b: &mut [f64]) {
        let mut x = Mat::<f64>::from_fn(b.len(), 1, |p, _| b[self.order[p]]);
        let llt = LltRef::new(&self.symbolic, &self.values);
        let mut mem = MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
        llt.solve_in_place_with_conj(Conj::No, x.as_mut(), Par::Seq, MemStack::new(&mut mem));
        for (p, &l) in self.order.iter().enumerate() {
            b[l] = x[(p, 0)];
        }
    }
}

impl DelassusFactors {
    /// Solve (W'_UU + D) x = b in place, U = `unknown` (indices of local components), D = `diag`,
    /// W' = W read in `frames`. None when the matrix is not numerically positive definite.
    pub fn solve(
        &self,
        w: &Delassus,
        frames: &SlipFrames,
        unknown: &[usize],
        diag: &[f64],
        b: &mut [f64],
    ) -> Option<()> {
        self.solve_to(w, frames, unknown, diag, crate::defaults::PCG_TOLERANCE, b)
    }

    /// [`solve`](Self::solve), where conjugate gradients may stop at the relative residual
    /// `forcing` (≥ [`PCG_TOLERANCE`](crate::defaults::PCG_TOLERANCE)): Newton's inexact
    /// directions far from its solution (Eisenstat–Walker forcing).
    pub fn solve_to(
        &self,
        w: &Delassus,
        frames: &SlipFrames,
        unknown: &[usize],
        diag: &[f64],
        forcing: f64,
        b: &mut [f64],
    ) -> Option<()> {
        let mut last = self.last.borrow_mut();
        let hit = last.as_ref().is_some_and(|f| f.unknown == unknown && f.diag == diag && f.frames == *frames);
        if hit {
            self.counts.borrow_mut().reuses += 1;
            last.as_ref()?.llt.solve_in_place(b);
            return b.iter().all(|v| v.is_finite()).then_some(());
        }
        // a nearby matrix: conjugate gradients preconditioned by the kept factor, on the
        // unknowns the two share (the others by their diagonal)
        let large = unknown.len() >= crate::defaults::PCG_FROM;
        if let Some(f) = last
            .as_ref()
            .filter(|f| f.unknown == unknown && (large || frames.any()) || large && Preconditioner::close(f, unknown))
        {
            let prec = Preconditioner::new(f, w, frames, unknown, diag);
            if let Some(iterations) =
                pcg(w, frames, unknown, diag, &prec, forcing.max(crate::defaults::PCG_TOLERANCE), b)
            {
                let mut c = self.counts.borrow_mut();
                c.pcg_solves += 1;
                c.pcg_iterations += iterations;
                return b.iter().all(|v| v.is_finite()).then_some(());
            }
        }
        *last = Some(Factor {
            unknown: unknown.to_vec(),
            diag: diag.to_vec(),
            frames: frames.clone(),
            llt: factor(w, frames, unknown, diag)?,
        });
        self.counts.borrow_mut().factorizations += 1;
        last.as_ref()?.llt.solve_in_place(b);
        b.iter().all(|v| v.is_finite()).then_some(())
    }

    /// What identifies the kept factorization (U, D, frames), for a checkpoint: the factor is a
    /// function of it and W, and the next Newton systems are preconditioned by it, so a resumed
    /// run rebuilds it to stay bit-identical with an uninterrupted one.
    pub fn key(&self) -> Option<FactorKey> {
        self.last.borrow().as_ref().map(|f| FactorKey {
            unknown: f.unknown.clone(),
            diag: f.diag.iter().map(|v| v.to_bits()).collect(),
            frames_dim: f.frames.dim,
            frames: f.frames.zhat.iter().map(|z| z.map(|z| z.map(f64::to_bits))).collect(),
        })
    }

    /// Rebuild the kept factorization of a checkpoint's key (None: a key that does not fit W
    /// or a matrix that is not positive definite).
    pub fn restore(&self, w: &Delassus, key: &FactorKey) -> Option<()> {
        let m = w.dim();
        if key.unknown.iter().any(|&l| l >= m) || key.diag.len() != key.unknown.len() {
            return None;
        }
        let frames = SlipFrames {
            dim: key.frames_dim,
            zhat: key.frames.iter().map(|z| z.map(|z| z.map(f64::from_bits))).collect(),
        };
        if frames.zhat.len() * frames.dim.max(1) > m {
            return None;
        }
        let diag: Vec<f64> = key.diag.iter().map(|b| f64::from_bits(*b)).collect();
        let llt = factor(w, &frames, &key.unknown, &diag)?;
        *self.last.borrow_mut() = Some(Factor { unknown: key.unknown.clone(), diag, frames, llt });
        Some(())
    }

    /// (factorizations computed, factorizations reused) so far.
    pub fn counts(&self) -> (usize, usize) {
        let c = *self.counts.borrow();
        (c.factorizations, c.reuses)
    }

    /// Count a Newton direction solved in velocity form (`InverseDelassus`).
    pub fn record_velocity_solve(&self, iterations: usize) {
        let mut c = self.counts.borrow_mut();
        c.velocity_solves += 1;
        c.velocity_iterations += iterations;
    }

    /// Every count so far.
    pub fn all_counts(&self) -> FactorCounts {
        *self.counts.borrow()
    }
}

/// The kept factor of a nearby Newton matrix as a preconditioner for W'_UU + D: the unknowns
/// both matrices have go through the factor (the kept matrix's other unknowns held at zero), the
/// new ones are scaled by their diagonal entry. Symmetric positive definite whatever the change,
/// so conjugate gradients converge; fast when little changed.
#[derive(Debug)]
struct Preconditioner<'f> {
    factor: &'f FactorKind,
    /// the kept factor's size and, per unknown of U, its position there (None: a new unknown)
    kept: usize,
    position: Vec<Option<usize>>,
    /// 1/(W'_UU + D)_pp for the new unknowns
    inv_diag: Vec<f64>,
}

impl<'f> Preconditioner<'f> {
    /// Whether the kept factor is worth trying for U: at most
    /// [`PCG_NEW_SHARE`](crate::defaults::PCG_NEW_SHARE) of U is new to it.
    fn close(f: &Factor, unknown: &[usize]) -> bool {
        let new = unknown.iter().filter(|l| f.unknown.binary_search(l).is_err()).count();
        !unknown.is_empty() && (new as f64) <= crate::defaults::PCG_NEW_SHARE * unknown.len() as f64
    }
    fn new(f: &'f Factor, w: &Delassus, frames: &SlipFrames, unknown: &[usize], diag: &[f64]) -> Preconditioner<'f> {
        let position: Vec<Option<usize>> = unknown.iter().map(|l| f.unknown.binary_search(l).ok()).collect();
        let inv_diag = unknown
            .iter()
            .zip(&position)
            .zip(diag)
            .map(|((&l, q), d)| if q.is_some() { 0.0 } else { 1.0 / (w.entry_in(frames, l, l) + d) })
            .collect();
        Preconditioner { factor: &f.llt, kept: f.unknown.len(), position, inv_diag }
    }
    /// z ← P⁻¹ z.
    fn apply_to(&self, z: &mut [f64]) {
        let mut x = vec![0.0; self.kept];
        for (p, q) in self.position.iter().enumerate() {
            if let Some(q) = q {
                x[*q] = z[p];
            }
        }
        self.factor.solve_in_place(&mut x);
        for (p, q) in self.position.iter().enumerate() {
            z[p] = match q {
                Some(q) => x[*q],
                None => z[p] * self.inv_diag[p],
            };
        }
    }
}

/// Conjugate gradients (faer's `matrix_free::conjugate_gradient`) on `op` x = b preconditioned
/// by `prec`, from the initial guess in `x`, to the relative residual `tolerance` within
/// `max_iterations`: the iterations, or None (x unspecified) when they did not get there or met
/// a non-positive curvature.
fn conjugate_gradients(
    op: &impl LinOp<f64>,
    prec: &impl Precond<f64>,
    b: &[f64],
    x: &mut [f64],
    tolerance: f64,
    max_iterations: usize,
) -> Option<usize> {
    let n = b.len();
    let params = CgParams {
        initial_guess: InitialGuessStatus::MaybeNonZero,
        abs_tolerance: 0.0,
        rel_tolerance: tolerance,
        max_iters: max_iterations,
        ..CgParams::default()
    };
    let mut mem = MemBuffer::new(conjugate_gradient_scratch(prec, op, 1, Par::Seq));
    let info = conjugate_gradient(
        faer::MatMut::from_column_major_slice_mut(x, n, 1),
        prec,
        op,
        faer::MatRef::from_column_major_slice(b, n, 1),
        params,
        |_| {},
        Par::Seq,
        MemStack::new(&mut mem),
    )
    .ok()?;
    x.iter().all(|v| v.is_finite()).then_some(info.iter_count)
}

/// W'_UU + D as an operator on the unknowns U (force form).
#[derive(Debug)]
struct ForceMatrix<'a> {
    w: &'a Delassus,
    frames: &'a SlipFrames,
    unknown: &'a [usize],
    diag: &'a [f64],
}

impl LinOp<f64> for ForceMatrix<'_> {
    fn apply_scratch(&self, _rhs_ncols: usize, _par: Par) -> StackReq {
        StackReq::EMPTY
    }
    fn nrows(&self) -> usize {
        self.unknown.len()
    }
    fn ncols(&self) -> usize {
        self.unknown.len()
    }
    fn apply(&self, mut out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, _par: Par, _stack: &mut MemStack) {
        let m = self.w.dim();
        for c in 0..rhs.ncols() {
            let mut full = vec![0.0; m];
            for (p, &l) in self.unknown.iter().enumerate() {
                full[l] = rhs[(p, c)];
            }
            let mut wx = vec![0.0; m];
            self.w.add_times_in(self.frames, &full, 1.0, &mut wx);
            for (p, &l) in self.unknown.iter().enumerate() {
                out[(p, c)] = wx[l] + self.diag[p] * rhs[(p, c)];
            }
        }
    }
    fn conj_apply(&self, out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, par: Par, stack: &mut MemStack) {
        self.apply(out, rhs, par, stack)
    }
}

impl LinOp<f64> for Preconditioner<'_> {
    fn apply_scratch(&self, _rhs_ncols: usize, _par: Par) -> StackReq {
        StackReq::EMPTY
    }
    fn nrows(&self) -> usize {
        self.position.len()
    }
    fn ncols(&self) -> usize {
        self.position.len()
    }
    fn apply(&self, mut out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, _par: Par, _stack: &mut MemStack) {
        for c in 0..rhs.ncols() {
            let mut z: Vec<f64> = (0..rhs.nrows()).map(|p| rhs[(p, c)]).collect();
            self.apply_to(&mut z);
            for (p, v) in z.into_iter().enumerate() {
                out[(p, c)] = v;
            }
        }
    }
    fn conj_apply(&self, out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, par: Par, stack: &mut MemStack) {
        self.apply(out, rhs, par, stack)
    }
}

impl Precond<f64> for Preconditioner<'_> {}

/// Conjugate gradients on (W'_UU + D) x = b preconditioned by `prec`, started from the
/// preconditioned right-hand side; x in place of b. The number of iterations, or None (b
/// untouched) when the relative residual did not reach `tolerance` within
/// [`PCG_MAX_ITERATIONS`](crate::defaults::PCG_MAX_ITERATIONS).
fn pcg(
    w: &Delassus,
    frames: &SlipFrames,
    unknown: &[usize],
    diag: &[f64],
    prec: &Preconditioner,
    tolerance: f64,
    b: &mut [f64],
) -> Option<usize> {
    let mut x = b.to_vec();
    prec.apply_to(&mut x);
    let op = ForceMatrix { w, frames, unknown, diag };
    let iterations = conjugate_gradients(&op, prec, b, &mut x, tolerance, crate::defaults::PCG_MAX_ITERATIONS)?;
    b.copy_from_slice(&x);
    Some(iterations)
}

/// The Cholesky factor of W'_UU + D in W's own form (dense LLᵀ, or sparse with AMD ordering).
fn factor(w: &Delassus, frames: &SlipFrames, unknown: &[usize], diag: &[f64]) -> Option<FactorKind> {
    let k = unknown.len();
    match w {
        Delassus::Dense(_) => {
            let a = Mat::<f64>::from_fn(k, k, |i, j| {
                w.entry_in(frames, unknown[i], unknown[j]) + if i == j { diag[i] } else { 0.0 }
            });
            a.llt(Side::Lower).ok().map(FactorKind::Dense)
        }
        Delassus::Sparse(s) => {
            // the factor's order: U sorted by W's fill-reducing rank
            let mut order: Vec<usize> = (0..k).collect();
            order.sort_by_key(|&p| s.rank[unknown[p]]);
            let mut position = vec![usize::MAX; s.w.nrows()];
            for (p, &lp) in order.iter().enumerate() {
                position[unknown[lp]] = p;
            }
            let mut trip = Vec::new();
            for (p, &lp) in order.iter().enumerate() {
                trip.push(Triplet::new(p, p, diag[lp]));
                let j = unknown[lp];
                // W' shares W's pattern: a rotation mixes the two tangential components of one
                // node, and W keeps whole node blocks
                for (&i, &v) in s.w.symbolic().row_idx_of_col_raw(j).iter().zip(s.w.val_of_col(j)) {
                    // the upper triangle, with Side::Upper: faer 0.24's low-level analysis in a
                    // given order reads the upper triangle (the lower one with Side::Lower gave a
                    // wrong factor: measured residual 5e-2)
                    if position[i] != usize::MAX && position[i] <= p {
                        let v = if frames.any() { w.entry_in(frames, i, j) } else { v };
                        trip.push(Triplet::new(position[i], p, v));
                    }
                }
            }
            let a = SparseColMat::<usize, f64>::try_new_from_triplets(k, k, &trip).ok()?;
            let symbolic =
                factorize_symbolic_cholesky(a.symbolic(), Side::Upper, SymmetricOrdering::Identity, Default::default())
                    .ok()?;
            let mut values = vec![0.0; symbolic.len_val()];
            let mut mem = MemBuffer::new(symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()));
            symbolic
                .factorize_numeric_llt(
                    &mut values,
                    a.as_ref(),
                    Side::Upper,
                    Default::default(),
                    Par::Seq,
                    MemStack::new(&mut mem),
                    Default::default(),
                )
                .ok()?;
            Some(FactorKind::Sparse(Box::new(SparseFactor { order, symbolic, values })))
        }
    }
}

/// W⁻¹ of a dense Delassus operator, for Newton directions in velocity form (see
/// `newton::velocity_direction`): with the prescribed components' velocities known, the
/// linearized step is the symmetric system [(W⁻¹)_FF + ω Ĝ_F] Δy_F = b on the free components F,
/// positive definite whenever the step problem is convex (the frozen bound of F.1 always; the
/// unfrozen one of N.4 under (C.k)), solved by conjugate gradients preconditioned with its node
/// blocks — matrix–vector products only, no factorization per Newton iteration, and no slip
/// frames (a slipping node's 2 × 2 block is just added). Kept when W is dense, has at least
/// [`GEMV_FROM`](crate::defaults::GEMV_FROM) components and is well conditioned for that
/// iteration: a trial solve at setup reaches 1e-10 within
/// [`VELOCITY_FORM_TRIAL`](crate::defaults::VELOCITY_FORM_TRIAL) iterations.
pub struct InverseDelassus {
    pub winv: Mat<f64>,
    /// components per node
    pub dim: usize,
    /// iterations of the trial solve at setup
    pub trial_iterations: usize,
}

impl InverseDelassus {
    /// W⁻¹ of a dense W when the velocity form suits it (see the type's doc), else None.
    pub fn new(w: &Delassus, dim: usize) -> Option<InverseDelassus> {
        let Delassus::Dense(w) = w else { return None };
        let m = w.nrows();
        if m < crate::defaults::GEMV_FROM {
            return None;
        }
        let winv = w.llt(Side::Lower).ok()?.inverse();
        let mut inv = InverseDelassus { winv, dim, trial_iterations: 0 };
        // the trial: every component free, no stiffness, a pseudo-random right-hand side
        let b: Vec<f64> = (0..m).map(|l| ((l * 7919 + 13) % 101) as f64 / 101.0 - 0.5).collect();
        let free: Vec<usize> = (0..m).collect();
        let blocks = vec![None; m / dim];
        let mut x = vec![0.0; m];
        inv.trial_iterations =
            inv.solve(&free, &vec![0.0; m], &blocks, &b, 1e-10, crate::defaults::VELOCITY_FORM_TRIAL, &mut x)?;
        Some(inv)
    }

    /// out = W⁻¹ x (all components).
    pub fn apply(&self, x: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; x.len()];
        let rhs = faer::MatRef::from_column_major_slice(x, x.len(), 1);
        let dst = faer::MatMut::from_column_major_slice_mut(&mut out, x.len(), 1);
        faer::linalg::matmul::matmul(dst, faer::Accum::Replace, self.winv.as_ref(), rhs, 1.0, Par::Seq);
        out
    }

    /// Solve [(W⁻¹)_FF + Ĝ_F] x_F = b_F by conjugate gradients preconditioned with the node
    /// blocks, to the relative residual `tolerance` within `max_iterations`. F: the free
    /// components (`free_list`; x and b are full-length, zero off F); Ĝ: `diag` per component
    /// plus, per node, an optional 2 × 2 block on its tangential pair (3-D slip; it replaces the
    /// diagonal there). The iterations, or None when the matrix showed a non-positive curvature
    /// (not positive definite: N.4 beyond (C.k)) or the tolerance was not reached.
    #[allow(clippy::too_many_arguments)]
    pub fn solve(
        &self,
        free_list: &[usize],
        diag: &[f64],
        blocks: &[Option<[[f64; 2]; 2]>],
        b: &[f64],
        tolerance: f64,
        max_iterations: usize,
        x: &mut [f64],
    ) -> Option<usize> {
        let m = b.len();
        let mut is_free = vec![false; m];
        for &l in free_list {
            is_free[l] = true;
        }
        let op = VelocityMatrix { inverse: self, is_free: &is_free, free_list, diag, blocks };
        let prec = NodeBlocks::new(self, &is_free, diag, blocks)?;
        x.iter_mut().for_each(|v| *v = 0.0);
        conjugate_gradients(&op, &prec, b, x, tolerance, max_iterations)
    }
}

impl std::fmt::Debug for InverseDelassus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "InverseDelassus({} × {}, {} per node)", self.winv.nrows(), self.winv.ncols(), self.dim)
    }
}

/// (W⁻¹)_FF + Ĝ_F as an operator on all m components (zero off F).
#[derive(Debug)]
struct VelocityMatrix<'a> {
    inverse: &'a InverseDelassus,
    is_free: &'a [bool],
    free_list: &'a [usize],
    diag: &'a [f64],
    blocks: &'a [Option<[[f64; 2]; 2]>],
}

impl LinOp<f64> for VelocityMatrix<'_> {
    fn apply_scratch(&self, _rhs_ncols: usize, _par: Par) -> StackReq {
        StackReq::EMPTY
    }
    fn nrows(&self) -> usize {
        self.is_free.len()
    }
    fn ncols(&self) -> usize {
        self.is_free.len()
    }
    fn apply(&self, mut out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, _par: Par, _stack: &mut MemStack) {
        let (m, d) = (self.is_free.len(), self.inverse.dim);
        for c in 0..rhs.ncols() {
            let v: Vec<f64> = (0..m).map(|l| if self.is_free[l] { rhs[(l, c)] } else { 0.0 }).collect();
            let mut o = self.inverse.apply(&v);
            for l in 0..m {
                if !self.is_free[l] {
                    o[l] = 0.0;
                }
            }
            for &l in self.free_list {
                o[l] += self.diag[l] * v[l];
            }
            for (i, blk) in self.blocks.iter().enumerate() {
                if let Some(g) = blk {
                    let (a, b) = (d * i + 1, d * i + 2);
                    if self.is_free[a] && self.is_free[b] {
                        o[a] += g[0][0] * v[a] + g[0][1] * v[b];
                        o[b] += g[1][0] * v[a] + g[1][1] * v[b];
                    }
                }
            }
            for (l, ol) in o.into_iter().enumerate() {
                out[(l, c)] = ol;
            }
        }
    }
    fn conj_apply(&self, out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, par: Par, stack: &mut MemStack) {
        self.apply(out, rhs, par, stack)
    }
}

/// The node-block preconditioner of the velocity form: per node, the inverse of its free
/// components' block of (W⁻¹)_FF + Ĝ_F (1 × 1 to 3 × 3).
#[derive(Debug)]
struct NodeBlocks {
    m: usize,
    blocks: Vec<(Vec<usize>, nalgebra::DMatrix<f64>)>,
}

impl NodeBlocks {
    /// None when a node's block is not positive definite.
    fn new(
        inverse: &InverseDelassus,
        is_free: &[bool],
        diag: &[f64],
        blocks: &[Option<[[f64; 2]; 2]>],
    ) -> Option<NodeBlocks> {
        let (m, d) = (is_free.len(), inverse.dim);
        let mut out = Vec::new();
        for i in 0..m / d {
            let comps: Vec<usize> = (d * i..d * i + d).filter(|&l| is_free[l]).collect();
            if comps.is_empty() {
                continue;
            }
            let mut blk = nalgebra::DMatrix::<f64>::from_fn(comps.len(), comps.len(), |p, q| {
                inverse.winv[(comps[p], comps[q])] + if p == q { diag[comps[p]] } else { 0.0 }
            });
            if let Some(g) = blocks[i] {
                for (p, &lp) in comps.iter().enumerate() {
                    for (q, &lq) in comps.iter().enumerate() {
                        if lp > d * i && lq > d * i {
                            // the block replaces the diagonal on the tangential pair
                            blk[(p, q)] += g[lp - d * i - 1][lq - d * i - 1] - if p == q { diag[lp] } else { 0.0 };
                        }
                    }
                }
            }
            out.push((comps, blk.cholesky()?.inverse()));
        }
        Some(NodeBlocks { m, blocks: out })
    }
}

impl LinOp<f64> for NodeBlocks {
    fn apply_scratch(&self, _rhs_ncols: usize, _par: Par) -> StackReq {
        StackReq::EMPTY
    }
    fn nrows(&self) -> usize {
        self.m
    }
    fn ncols(&self) -> usize {
        self.m
    }
    fn apply(&self, mut out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, _par: Par, _stack: &mut MemStack) {
        for c in 0..rhs.ncols() {
            for l in 0..self.m {
                out[(l, c)] = 0.0;
            }
            for (comps, inv) in &self.blocks {
                for (p, &lp) in comps.iter().enumerate() {
                    out[(lp, c)] = comps.iter().enumerate().map(|(q, &lq)| inv[(p, q)] * rhs[(lq, c)]).sum();
                }
            }
        }
    }
    fn conj_apply(&self, out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, par: Par, stack: &mut MemStack) {
        self.apply(out, rhs, par, stack)
    }
}

impl Precond<f64> for NodeBlocks {}
