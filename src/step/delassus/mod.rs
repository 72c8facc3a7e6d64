//! The Delassus operator W = H A_k⁻¹ Hᵀ (the fast path of the README's design notes): the response of
//! the contact velocities to unit contact forces, computed once per run. Two forms:
//!
//! * **dense** (d n_c solves, an m × m matrix, m = d n_c): exact; cost and memory grow like m²
//!   per apply and m³ per factorization — the small scenes' form;
//! * **sparse** (probing): W's entries decay with the distance between contact nodes (the step
//!   matrix A_k = M/k + C/2 + kK/4 of (S.2) is mass-dominated over a step, and the elastic
//!   response of a strip decays over its height). The d columns of the contact node nearest the
//!   centroid of the contact nodes (d solves) measure the radius R beyond which every entry is
//!   below `truncation` × the diagonal; contact nodes more than 2R apart are then probed together
//!   (a greedy distance colouring), so W costs d × (colours) solves and keeps only the entries
//!   within R. The error of the kept operator is measured on a pseudo-random vector against an
//!   exact solve (one more solve) and reported (`SparseStats`).
//!
//! The choice between them is automatic from the sizes (`[solver] contact_solve = "auto"`), or set.
//!
//! The files: this one holds the operator and its dense form; `sparse` the probed form;
//! `frames` the slip frames the Newton matrices read it in; `factors` the kept factorization of
//! those matrices (with conjugate gradients and their preconditioner); `inverse` W⁻¹ for the
//! velocity form; `cg` the conjugate-gradient driver both use; `convexity` the sharp form of
//! (C.k) that W allows (Ck.1).

mod cg;
mod convexity;
mod factors;
mod frames;
mod hmatrix;
mod inverse;
mod schur;
mod sparse;

pub use convexity::{SHARP_CONVEXITY_MARGIN, sharp_convex};
pub use factors::{DelassusFactors, FactorCounts, FactorKey};
pub use frames::SlipFrames;
pub use hmatrix::HMatrix;
pub use inverse::{DirectionForm, InverseDelassus};
pub use schur::{contact_block_of_factor, delassus_pair};
pub use sparse::{Probe, SparseDelassus, SparseStats, sparse};

use faer::{Mat, Par};

use sparse::column_add;

use crate::linalg::Cholesky;
use crate::model::contact::ContactModel;
use crate::model::kinds::ContactSolve;

/// The Delassus operator in one of its two forms.
pub enum Delassus {
    /// the exact m × m matrix
    Dense(Mat<f64>),
    /// the probed, truncated matrix
    Sparse(SparseDelassus),
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
    /// The sparse form's facts (None for the dense form).
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
    build_with_responses(a, None, contact, positions, choice).w
}

/// What the setup of the contact solve computes once.
pub struct Built {
    /// W, in the form chosen
    pub w: Delassus,
    /// the responses G = A_k⁻¹ Hᵀ (dense form, when they fit in
    /// [`RESPONSES_BYTES`](crate::defaults::RESPONSES_BYTES))
    pub responses: Option<Mat<f64>>,
    /// W⁻¹, when W came from the Schur complement of A_k (which gives it first)
    pub winv: Option<Mat<f64>>,
    /// how the dense W was computed: "solves" (d n_c solve pairs with the factor of A_k),
    /// "schur" (the Schur complement, [`delassus_pair`]), or "probed" for the sparse form
    pub route: &'static str,
}

/// [`build`], and for the dense form the responses G = A_k⁻¹ Hᵀ when they fit in
/// [`RESPONSES_BYTES`](crate::defaults::RESPONSES_BYTES). With A_k itself (`matrix`, with its
/// unknowns' positions for the nested dissection of the second factor), a dense W
/// of at least [`SCHUR_FROM`](crate::defaults::SCHUR_FROM) components whose responses are not
/// kept comes from the Schur complement of A_k on the contact unknowns (one more sparse
/// factorization instead of d n_c solve pairs; W and W⁻¹ agree with the solves' to round-off),
/// falling back to the solves if that factorization fails or its second factor would not fit
/// in 90% of the memory available.
pub fn build_with_responses(
    a: &Cholesky,
    matrix: Option<(&crate::linalg::SpMat, Option<&[[f64; 3]]>)>,
    contact: &ContactModel,
    positions: &[[f64; 3]],
    choice: ContactSolve,
) -> Built {
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
    if let Some(s) = probe.and_then(|p| sparse(a, contact, positions, &p)) {
        return Built { w: Delassus::Sparse(s), responses: None, winv: None, route: "probed" };
    }
    let keep = 8.0 * a.dim() as f64 * m as f64 <= crate::defaults::RESPONSES_BYTES;
    if !keep
        && m >= crate::defaults::SCHUR_FROM
        && let Some((w, winv)) =
            matrix.and_then(|(k, dof_positions)| delassus_pair(k, dof_positions, contact, schur_budget()))
    {
        return Built { w: Delassus::Dense(w), responses: None, winv: Some(winv), route: "schur" };
    }
    let (w, g) = dense_with_responses(a, contact, keep);
    Built { w: Delassus::Dense(w), responses: g, winv: None, route: "solves" }
}

/// The memory the Schur route may take: 90% of what the system has available now (beside the
/// factor of A_k already held), or no limit where the system does not say.
fn schur_budget() -> Option<f64> {
    crate::resources::available_memory().map(|b| 0.9 * b)
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
