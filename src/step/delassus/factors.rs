//! The kept factorization of the Newton matrices W'_UU + D (force form), conjugate gradients
//! preconditioned by it for nearby matrices, and the key a checkpoint carries to rebuild it.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::solvers::{Llt, Solve};
use faer::matrix_free::{LinOp, Precond};
use faer::sparse::linalg::cholesky::{LltRef, SymbolicCholesky, SymmetricOrdering, factorize_symbolic_cholesky};
use faer::sparse::{SparseColMat, Triplet};
use faer::{Conj, Mat, MatMut, MatRef, Par, Side};

use super::cg::conjugate_gradients;
use super::{Delassus, SlipFrames};

/// The key of a kept factorization (checkpoints): U, and D and the frames as exact bit patterns.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FactorKey {
    /// U, the local components of the factored matrix (ascending)
    pub unknown: Vec<usize>,
    diag: Vec<u64>,
    frames_dim: usize,
    frames: Vec<Option<[u64; 2]>>,
}

/// How the Newton matrices W'_UU + D were solved so far (summary.json, the benchmark).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
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
    /// of those directions, the loose ones (`DirectionForm::Loose` with a loose form kept)
    pub loose_velocity_solves: usize,
}

/// The factor cache of the Newton matrices W'_UU + D (a principal submatrix of the Delassus
/// operator, read in the slipping nodes' frames, plus a nonnegative diagonal), the matrices of the
/// frozen step problem's force form (see `newton::reduced_direction`). It keeps the last Cholesky
/// factor with its key (U, D, frames), so a solve depends on the solves before it: every method
/// that may reuse or replace the kept factor takes `&mut self`, and whoever holds the cache (the
/// run's `Simulation`, or a test's own) passes it down to the solvers.
///
/// A solve of (W'_UU + D) x = b takes the first of:
/// * **reuse**: the kept factor's key is (U, D, frames) exactly — bit-identical to refactoring
///   (Newton, the F.1 iterations and the next steps, while the active and stick sets hold);
/// * **conjugate gradients** preconditioned with the kept factor (see `Preconditioner`), to
///   [`PCG_TOLERANCE`](crate::defaults::PCG_TOLERANCE) of the right-hand side (or Newton's
///   looser forcing), when the kept U is the same and the system has at least
///   [`PCG_FROM`](crate::defaults::PCG_FROM) unknowns or some node is read in a slip frame (3-D
///   slip: the stiffness across the slip and its direction move every iteration), or when the
///   system has at least `PCG_FROM` unknowns and at most
///   [`PCG_NEW_SHARE`](crate::defaults::PCG_NEW_SHARE) of U is new to the kept factor — and they
///   converge within [`PCG_MAX_ITERATIONS`](crate::defaults::PCG_MAX_ITERATIONS);
/// * **a new factorization**, which replaces the kept one.
///
/// It also keeps the velocity form's last near-field factor (see `InverseDelassus::solve`).
#[derive(Default)]
pub struct DelassusFactors {
    last: Option<Factor>,
    counts: FactorCounts,
    /// the velocity form's near-field factor, kept as its CG preconditioner while the free
    /// set holds (`InverseDelassus::solve`)
    pub(crate) near: Option<super::inverse::KeptNear>,
    /// whether the last Newton solve's first direction was taken on sets that then moved: the
    /// next solve starts with a loose direction (`DirectionForm`) if so, else with an exact one
    /// (which lands at once when the sets were right, as on hertz3d's pressing steps)
    pub(crate) first_sets_moved: bool,
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
        &mut self,
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
        &mut self,
        w: &Delassus,
        frames: &SlipFrames,
        unknown: &[usize],
        diag: &[f64],
        forcing: f64,
        b: &mut [f64],
    ) -> Option<()> {
        let hit = self.last.as_ref().is_some_and(|f| f.unknown == unknown && f.diag == diag && f.frames == *frames);
        if hit {
            self.counts.reuses += 1;
            self.last.as_ref()?.llt.solve_in_place(b);
            return b.iter().all(|v| v.is_finite()).then_some(());
        }
        // a nearby matrix: conjugate gradients preconditioned by the kept factor, on the
        // unknowns the two share (the others by their diagonal)
        let large = unknown.len() >= crate::defaults::PCG_FROM;
        if let Some(f) = self
            .last
            .as_ref()
            .filter(|f| f.unknown == unknown && (large || frames.any()) || large && Preconditioner::close(f, unknown))
        {
            let prec = Preconditioner::new(f, w, frames, unknown, diag);
            if let Some(iterations) =
                pcg(w, frames, unknown, diag, &prec, forcing.max(crate::defaults::PCG_TOLERANCE), b)
            {
                self.counts.pcg_solves += 1;
                self.counts.pcg_iterations += iterations;
                return b.iter().all(|v| v.is_finite()).then_some(());
            }
        }
        self.last = Some(Factor {
            unknown: unknown.to_vec(),
            diag: diag.to_vec(),
            frames: frames.clone(),
            llt: factor(w, frames, unknown, diag)?,
        });
        self.counts.factorizations += 1;
        self.last.as_ref()?.llt.solve_in_place(b);
        b.iter().all(|v| v.is_finite()).then_some(())
    }

    /// What identifies the kept factorization (U, D, frames), for a checkpoint: the factor is a
    /// function of it and W, and the next Newton systems are preconditioned by it, so a resumed
    /// run rebuilds it to stay bit-identical with an uninterrupted one.
    pub fn key(&self) -> Option<FactorKey> {
        self.last.as_ref().map(|f| FactorKey {
            unknown: f.unknown.clone(),
            diag: f.diag.iter().map(|v| v.to_bits()).collect(),
            frames_dim: f.frames.dim,
            frames: f.frames.zhat.iter().map(|z| z.map(|z| z.map(f64::to_bits))).collect(),
        })
    }

    /// Rebuild the kept factorization of a checkpoint's key (None: a key that does not fit W
    /// or a matrix that is not positive definite).
    pub fn restore(&mut self, w: &Delassus, key: &FactorKey) -> Option<()> {
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
        self.last = Some(Factor { unknown: key.unknown.clone(), diag, frames, llt });
        Some(())
    }

    /// (factorizations computed, factorizations reused) so far.
    pub fn counts(&self) -> (usize, usize) {
        (self.counts.factorizations, self.counts.reuses)
    }

    /// Count a Newton direction solved in velocity form (`InverseDelassus`).
    pub fn record_velocity_solve(&mut self, iterations: usize, loose: bool) {
        self.counts.velocity_solves += 1;
        self.counts.velocity_iterations += iterations;
        self.counts.loose_velocity_solves += usize::from(loose);
    }

    /// Every count so far.
    pub fn all_counts(&self) -> FactorCounts {
        self.counts
    }

    /// Continue counting from `counts` (a resumed run's counts before its checkpoint).
    pub fn continue_counts(&mut self, counts: FactorCounts) {
        self.counts = counts;
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
