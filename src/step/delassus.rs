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

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::solvers::{Llt, Solve};
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, LltRef, SymbolicCholesky, SymmetricOrdering};
use faer::sparse::{SparseColMat, Triplet};
use faer::{Conj, Mat, Par, Side};

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
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
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
    /// out += alpha W r, by columns, skipping zero forces (separated nodes).
    pub fn add_times(&self, r: &[f64], alpha: f64, out: &mut [f64]) {
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
pub fn build_with_responses(a: &Cholesky, contact: &ContactModel, positions: &[[f64; 3]], choice: ContactSolve) -> (Delassus, Option<Mat<f64>>) {
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
        let i0 = (0..nc).min_by(|&a, &b| distance(&positions[a], &centroid).total_cmp(&distance(&positions[b], &centroid))).unwrap_or(0);
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
    let sym: Vec<Triplet<usize, usize, f64>> =
        triplets.iter().flat_map(|t| [Triplet::new(t.row, t.col, 0.5 * t.val), Triplet::new(t.col, t.row, 0.5 * t.val)]).collect();
    let w = SparseColMat::<usize, f64>::try_new_from_triplets(m, m, &sym).ok()?;
    // 3. the kept operator against an exact solve on a pseudo-random force
    let x: Vec<f64> = (0..m).map(|l| ((l * 7919 + 13) % 101) as f64 / 101.0 - 0.5).collect();
    let exact = &responses(a, contact, std::slice::from_ref(&x))[0];
    let mut kept = vec![0.0; m];
    for (l, &xl) in x.iter().enumerate() {
        column_add(&w, l, xl, &mut kept);
    }
    let apply_error = kept.iter().zip(exact).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max) / crate::linalg::norm_inf(exact).max(f64::MIN_POSITIVE);
    let density = w.compute_nnz() as f64 / (m * m) as f64;
    let rank = factorize_symbolic_cholesky(w.symbolic(), Side::Lower, SymmetricOrdering::Amd, Default::default())
        .ok()
        .and_then(|sym| sym.perm().map(|p| p.arrays().1.to_vec()))
        .unwrap_or_else(|| (0..m).collect());
    Some(SparseDelassus { w, rank, stats: SparseStats { truncation, radius, colours, solves: d * (colours + 1) + 1, density, apply_error } })
}

/// Cholesky factorizations of W_UU + D (a principal submatrix of the Delassus operator plus a
/// nonnegative diagonal), the Newton matrix of the frozen step problem (see
/// `newton::reduced_direction`). The last one is kept with its key (U, D): Newton, the F.1
/// iterations and the next steps reuse it while their active and stick sets, and so the matrix,
/// are unchanged. A reuse is bit-identical to refactoring: the cache changes the cost, never the
/// answer.
#[derive(Default)]
pub struct DelassusFactors {
    last: RefCell<Option<Factor>>,
    /// factorizations computed and reused (for the benchmark's accounting)
    counts: RefCell<(usize, usize)>,
}

struct Factor {
    unknown: Vec<usize>,
    diag: Vec<f64>,
    llt: FactorKind,
}

enum FactorKind {
    Dense(Llt<f64>),
    Sparse(SparseFactor),
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
    /// Solve (W_UU + D) x = b in place, U = `unknown` (indices into W), D = `diag`. None when
    /// the matrix is not numerically positive definite.
    pub fn solve(&self, w: &Delassus, unknown: &[usize], diag: &[f64], b: &mut [f64]) -> Option<()> {
        let mut last = self.last.borrow_mut();
        let hit = last.as_ref().is_some_and(|f| f.unknown == unknown && f.diag == diag);
        if hit {
            self.counts.borrow_mut().1 += 1;
        } else {
            *last = Some(Factor { unknown: unknown.to_vec(), diag: diag.to_vec(), llt: factor(w, unknown, diag)? });
            self.counts.borrow_mut().0 += 1;
        }
        let f = last.as_ref()?;
        match &f.llt {
            FactorKind::Dense(llt) => llt.solve_in_place(faer::MatMut::from_column_major_slice_mut(b, unknown.len(), 1)),
            FactorKind::Sparse(llt) => llt.solve_in_place(b),
        }
        b.iter().all(|v| v.is_finite()).then_some(())
    }

    /// (factorizations computed, factorizations reused) so far.
    pub fn counts(&self) -> (usize, usize) {
        *self.counts.borrow()
    }
}

/// The Cholesky factor of W_UU + D in W's own form (dense LLᵀ, or sparse with AMD ordering).
fn factor(w: &Delassus, unknown: &[usize], diag: &[f64]) -> Option<FactorKind> {
    let k = unknown.len();
    match w {
        Delassus::Dense(w) => {
            let a = Mat::<f64>::from_fn(k, k, |i, j| w[(unknown[i], unknown[j])] + if i == j { diag[i] } else { 0.0 });
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
                for (&i, &v) in s.w.symbolic().row_idx_of_col_raw(j).iter().zip(s.w.val_of_col(j)) {
                    // the upper triangle, with Side::Upper: faer 0.24's low-level analysis in a
                    // given order reads the upper triangle (the lower one with Side::Lower gave a
                    // wrong factor: measured residual 5e-2)
                    if position[i] != usize::MAX && position[i] <= p {
                        trip.push(Triplet::new(position[i], p, v));
                    }
                }
            }
            let a = SparseColMat::<usize, f64>::try_new_from_triplets(k, k, &trip).ok()?;
            let symbolic = factorize_symbolic_cholesky(a.symbolic(), Side::Upper, SymmetricOrdering::Identity, Default::default()).ok()?;
            let mut values = vec![0.0; symbolic.len_val()];
            let mut mem = MemBuffer::new(symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()));
            symbolic
                .factorize_numeric_llt(&mut values, a.as_ref(), Side::Upper, Default::default(), Par::Seq, MemStack::new(&mut mem), Default::default())
                .ok()?;
            Some(FactorKind::Sparse(SparseFactor { order, symbolic, values }))
        }
    }
}
