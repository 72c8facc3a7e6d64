//! W⁻¹ for the Newton directions in velocity form: the operator (W⁻¹)_FF + Ĝ_F on the free
//! components and its preconditioners — the sparse Cholesky factor of its near field, or node
//! blocks where that factor cannot be had.

use faer::dyn_stack::{MemStack, StackReq};
use faer::linalg::solvers::{DenseSolveCore, Solve};
use faer::matrix_free::{LinOp, Precond};
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use faer::{Mat, MatMut, MatRef, Par, Side};

use super::Delassus;
use super::cg::conjugate_gradients_tracked;
use super::hmatrix::HMatrix;

/// Which products with W⁻¹ a Newton direction in velocity form takes.
/// - `Exact`: the dense W⁻¹, or its hierarchical form to HMATRIX_TOLERANCE (1e-12 of max|W⁻¹|):
///   on a fixed active set the direction lands on the linearized system's solution to round-off
///   (complementarity exact, so the constraint dissipation never decreases).
/// - `Loose`: the certified loose form where one is kept (else the exact one): an inexact Newton
///   direction (forcing ≤ HMATRIX_CERTIFICATE), for the iterations whose active sets still move
///   and for the fixed point's inexact convex solves. On a residual r it leaves ≲ 1e-3 r, so
///   from Newton's tolerance one more lands below NEWTON_LANDING too.
///
/// Newton stops after an exact direction or once the residual is below NEWTON_LANDING of the
/// velocity scale (landed to round-off, whichever direction got it there).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DirectionForm {
    Exact,
    Loose,
}

/// W⁻¹ of a dense Delassus operator, for Newton directions in velocity form (see
/// `newton::velocity_direction`): with the prescribed components' velocities known, the
/// linearized step is the symmetric system [(W⁻¹)_FF + ω Ĝ_F] Δy_F = b on the free components F,
/// positive definite whenever the step problem is convex (the frozen bound of F.1 always; the
/// unfrozen one of N.4 under (C.k)), solved by conjugate gradients preconditioned with its node
/// blocks — matrix–vector products only, no factorization per Newton iteration, and no slip
/// frames (a slipping node's 2 × 2 block is just added). Kept when W is dense, has at least
/// [`GEMV_FROM`](crate::defaults::GEMV_FROM) components, has a Cholesky factor (to invert it)
/// and is well conditioned for conjugate gradients: a trial solve at setup reaches 1e-10 within
/// [`VELOCITY_FORM_TRIAL`](crate::defaults::VELOCITY_FORM_TRIAL) iterations.
pub struct InverseDelassus {
    /// W⁻¹ (dense, m × m)
    pub winv: Mat<f64>,
    /// components per node
    pub dim: usize,
    /// iterations of the trial solve at setup
    pub trial_iterations: usize,
    /// the near field of W⁻¹ (its pattern, analysed once for Cholesky), or None when it could
    /// not be built (the solves then use node blocks)
    near: Option<NearField>,
    /// W⁻¹ compressed as a hierarchical matrix (`compressed`): when present, every product
    /// with W⁻¹ goes through it (the entries of the preconditioners still come from `winv`)
    h: Option<HMatrix>,
    /// W⁻¹ compressed at a certified loose ε (`compressed`): the loose directions' products
    h_loose: Option<HMatrix>,
    /// W compressed likewise, for the momentum residual (N.1) of the velocity form
    w_h: Option<HMatrix>,
    /// ‖W‖_∞ (the largest row sum of |W|): bounds how far a residual of the directions' systems,
    /// in force units, moves the momentum residual (N.1), in velocity units
    w_norm_inf: f64,
}

impl InverseDelassus {
    /// W⁻¹ of a dense W when the velocity form suits it (see the type's doc), else None:
    /// `winv` when the setup already has it (the Schur complement), else W's Cholesky inverse.
    pub fn new(w: &Delassus, dim: usize, winv: Option<Mat<f64>>) -> Option<InverseDelassus> {
        let Delassus::Dense(w) = w else { return None };
        let m = w.nrows();
        if m < crate::defaults::GEMV_FROM {
            return None;
        }
        let winv = match winv {
            Some(winv) => winv,
            None => w.llt(Side::Lower).ok()?.inverse(),
        };
        let near = (m >= crate::defaults::NEAR_FIELD_FROM)
            .then(|| NearField::new(&winv, dim, crate::defaults::NEAR_FIELD_TOLERANCE))
            .flatten();
        let w_norm_inf = norm_inf(w.as_ref());
        let mut inv =
            InverseDelassus { winv, dim, trial_iterations: 0, near, h: None, h_loose: None, w_h: None, w_norm_inf };
        // the trial: every component free, no stiffness, a pseudo-random right-hand side
        let b: Vec<f64> = (0..m).map(|l| ((l * 7919 + 13) % 101) as f64 / 101.0 - 0.5).collect();
        let free: Vec<usize> = (0..m).collect();
        let blocks = vec![None; m / dim];
        let (mut x, mut winv_x) = (vec![0.0; m], vec![0.0; m]);
        inv.trial_iterations = inv.solve(
            &mut None,
            &free,
            &vec![0.0; m],
            &blocks,
            &b,
            1e-10,
            crate::defaults::VELOCITY_FORM_TRIAL,
            DirectionForm::Exact,
            (&mut x, &mut winv_x),
        )?;
        Some(inv)
    }

    /// The products with W⁻¹ and with W through their hierarchical forms (`HMatrix`; `positions`
    /// are the contact nodes'): m log m memory reads per product instead of m².
    /// - W⁻¹ to every entry within HMATRIX_TOLERANCE · max|W⁻¹| for the exact directions: the
    ///   step's solution is the same to round-off of the linearized system Newton lands on;
    /// - W⁻¹ at the loosest ε of HMATRIX_LOOSE_TOLERANCES whose error is certified, for the loose
    ///   directions: ‖H − W⁻¹‖_F ≤ HMATRIX_CERTIFICATE / ‖W‖_∞ ≤ HMATRIX_CERTIFICATE · λ_min(W⁻¹),
    ///   so H stays positive definite and a loose direction is that of a system within 10% of the
    ///   exact one (an inexact Newton direction). Without a dense W to bound λ_min, or when no ε is
    ///   certified, no loose form (every direction exact);
    /// - W (a dense `w` only), for the momentum residual (N.1), to every entry within
    ///   HMATRIX_TOLERANCE_W · max|W|: the residual moves by at most that times ‖r‖₁, far below
    ///   the Newton tolerance.
    pub fn compressed(mut self, w: &Delassus, positions: &[[f64; 3]]) -> InverseDelassus {
        self.h = Some(HMatrix::new(self.winv.as_ref(), self.dim, positions, crate::defaults::HMATRIX_TOLERANCE));
        // λ_min(W⁻¹) = 1 / λ_max(W) ≥ 1 / ‖W‖_∞ (summed in `new` from the same W)
        let lambda_min = (matches!(w, Delassus::Dense(_)) && self.w_norm_inf > 0.0).then(|| 1.0 / self.w_norm_inf);
        self.h_loose = lambda_min.and_then(|l| {
            crate::defaults::HMATRIX_LOOSE_TOLERANCES
                .iter()
                .map(|&tol| HMatrix::new(self.winv.as_ref(), self.dim, positions, tol))
                .find(|h| h.error_frobenius() <= crate::defaults::HMATRIX_CERTIFICATE * l)
        });
        if let Delassus::Dense(w) = w {
            self.w_h = Some(HMatrix::new(w.as_ref(), self.dim, positions, crate::defaults::HMATRIX_TOLERANCE_W));
        }
        self
    }

    /// The same W⁻¹ with its products dense, and W's (the comparisons of the tests and the
    /// bench).
    pub fn without_compression(mut self) -> InverseDelassus {
        self.h = None;
        self.h_loose = None;
        self.w_h = None;
        self
    }

    /// The same W⁻¹ with every direction exact (no loose form: the comparisons of the tests and
    /// the bench).
    pub fn without_loose_form(mut self) -> InverseDelassus {
        self.h_loose = None;
        self
    }

    /// ‖W‖_∞ of the W this inverse was formed from.
    pub fn w_norm_inf(&self) -> f64 {
        self.w_norm_inf
    }

    /// W's hierarchical form, when the momentum residual's products go through it.
    pub fn hierarchical_w(&self) -> Option<&HMatrix> {
        self.w_h.as_ref()
    }

    /// The hierarchical form, when the exact directions' products go through it.
    pub fn hierarchical(&self) -> Option<&HMatrix> {
        self.h.as_ref()
    }

    /// The certified loose hierarchical form, when the loose directions' products go through it.
    pub fn hierarchical_loose(&self) -> Option<&HMatrix> {
        self.h_loose.as_ref()
    }

    /// Whether loose directions differ from exact ones (a certified loose form is kept).
    pub fn has_loose_form(&self) -> bool {
        self.h_loose.is_some()
    }

    /// The form whose products a direction of `form` takes: the loose one when asked for and kept.
    fn form(&self, form: DirectionForm) -> Option<&HMatrix> {
        match form {
            DirectionForm::Loose => self.h_loose.as_ref().or(self.h.as_ref()),
            DirectionForm::Exact => self.h.as_ref(),
        }
    }

    /// out = W⁻¹ x (all components), through `form`'s products.
    pub fn apply(&self, x: &[f64], form: DirectionForm) -> Vec<f64> {
        if let Some(h) = self.form(form) {
            return h.apply(x);
        }
        let mut out = vec![0.0; x.len()];
        let rhs = faer::MatRef::from_column_major_slice(x, x.len(), 1);
        let dst = faer::MatMut::from_column_major_slice_mut(&mut out, x.len(), 1);
        faer::linalg::matmul::matmul(dst, faer::Accum::Replace, self.winv.as_ref(), rhs, 1.0, Par::Seq);
        out
    }

    /// The same W⁻¹ with the near-field preconditioner whatever its size (the tests and the
    /// bench compare the two preconditioners below NEAR_FIELD_FROM too).
    pub fn with_near_field(mut self) -> InverseDelassus {
        if self.near.is_none() {
            self.near = NearField::new(&self.winv, self.dim, crate::defaults::NEAR_FIELD_TOLERANCE);
        }
        self
    }

    /// The same W⁻¹ with node blocks as the only preconditioner (the form before the near
    /// field; kept for the comparisons of the tests and the bench).
    pub fn without_near_field(mut self) -> InverseDelassus {
        self.near = None;
        self
    }

    /// Whether the solves are preconditioned by the near field (else by node blocks).
    pub fn has_near_field(&self) -> bool {
        self.near.is_some()
    }

    /// The share of W⁻¹'s entries its near field keeps (0 without one).
    pub fn near_field_density(&self) -> f64 {
        self.near
            .as_ref()
            .map_or(0.0, |n| (2 * n.entries.len() - self.winv.nrows()) as f64 / (self.winv.nrows() as f64).powi(2))
    }

    /// Solve [(W⁻¹)_FF + Ĝ_F] x_F = b_F (W⁻¹'s products through `form`) by conjugate gradients preconditioned with the
    /// Cholesky factor of the same matrix's near field (node blocks where that factor fails:
    /// the near field of a matrix that is not positive definite), to the relative residual
    /// `tolerance` within `max_iterations`. F: the free components (`free_list`; x and b are
    /// full-length, zero off F); Ĝ: `diag` per component plus, per node, an optional 2 × 2 block
    /// on its tangential pair (3-D slip; it replaces the diagonal there). `kept`: the near-field
    /// factor of an earlier solve, tried first as the preconditioner while its F is this one
    /// (Ĝ moves between Newton iterations and steps; a preconditioner need not follow it, and
    /// the answer is CG's to `tolerance` either way); a new factor takes its place when CG does
    /// not converge with it, and the next solve factors anew once it costs more than
    /// NEAR_FIELD_KEPT_SLOWDOWN times the iterations it took when new. The iterations, or None
    /// when the matrix showed a non-positive curvature (not positive definite: N.4 beyond
    /// (C.k)) or the tolerance was not reached.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn solve(
        &self,
        kept: &mut Option<KeptNear>,
        free_list: &[usize],
        diag: &[f64],
        blocks: &[Option<[[f64; 2]; 2]>],
        b: &[f64],
        tolerance: f64,
        max_iterations: usize,
        form: DirectionForm,
        (x, winv_x): (&mut [f64], &mut [f64]),
    ) -> Option<usize> {
        let m = b.len();
        let mut is_free = vec![false; m];
        for &l in free_list {
            is_free[l] = true;
        }
        let op = VelocityMatrix { inverse: self, form, is_free: &is_free, free_list, diag, blocks };
        let apply = |v: &[f64], out: &mut [f64], winv_v: &mut [f64]| op.apply(v, out, winv_v);
        if let Some(near) = &self.near {
            let slot = usize::from(form == DirectionForm::Loose);
            if let Some(k) = kept.as_mut().filter(|k| k.is_free == is_free)
                && let Some(iterations) =
                    conjugate_gradients_tracked(apply, &k.prec, b, (&mut *x, &mut *winv_x), tolerance, max_iterations)
            {
                // Ĝ has drifted far enough from the factor's to cost iterations: the next
                // solve factors anew (measured against the factor's first solve of the same
                // form: loose directions stop at the forcing, exact ones at round-off)
                let fresh = *k.fresh_iterations[slot].get_or_insert(iterations);
                if iterations > crate::defaults::NEAR_FIELD_KEPT_SLOWDOWN * fresh.max(1) {
                    *kept = None;
                }
                return Some(iterations);
            }
            if let Some(prec) = near.factor(self, &is_free, diag, blocks) {
                let solved =
                    conjugate_gradients_tracked(apply, &prec, b, (&mut *x, &mut *winv_x), tolerance, max_iterations);
                *kept = solved.map(|iterations| {
                    let mut fresh_iterations = [None; 2];
                    fresh_iterations[slot] = Some(iterations);
                    KeptNear { is_free, prec, fresh_iterations }
                });
                return solved;
            }
        }
        let prec = NodeBlocks::new(self, &is_free, diag, blocks)?;
        conjugate_gradients_tracked(apply, &prec, b, (x, winv_x), tolerance, max_iterations)
    }
}

impl std::fmt::Debug for InverseDelassus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "InverseDelassus({} × {}, {} per node)", self.winv.nrows(), self.winv.ncols(), self.dim)
    }
}

/// The near field of W⁻¹: the node blocks (i, j) whose largest entry relative to the diagonal,
/// |W⁻¹_ab| / √(W⁻¹_aa W⁻¹_bb), is at least the tolerance — W⁻¹ is the Schur complement of A_k
/// on the contact unknowns (a discrete Dirichlet-to-Neumann map, local where W is not), so these
/// are a node's few neighbours. The lower triangle's pattern is analysed for Cholesky once; a
/// solve factors the values of (W⁻¹)_FF + Ĝ_F on it (identity rows for the prescribed
/// components), or reuses the factor kept from an earlier solve on the same F (`KeptNear`).
struct NearField {
    /// the lower triangle's (row, column) of each stored value, column by column
    entries: Vec<(usize, usize)>,
    /// W⁻¹'s value at each entry, read once here: the factor of every direction reads them
    /// contiguously instead of gathering them from the dense W⁻¹ (scattered reads of m² memory)
    values: Vec<f64>,
    pattern: SymbolicSparseColMat<usize>,
    symbolic: SymbolicLlt<usize>,
}

impl NearField {
    fn new(winv: &Mat<f64>, dim: usize, tolerance: f64) -> Option<NearField> {
        let (m, n) = (winv.nrows(), winv.nrows() / dim);
        let scale: Vec<f64> = (0..m).map(|l| winv[(l, l)].abs().sqrt()).collect();
        let near = |i: usize, j: usize| {
            (0..dim).any(|a| {
                (0..dim).any(|b| {
                    let (p, q) = (dim * i + a, dim * j + b);
                    winv[(p, q)].abs() >= tolerance * scale[p] * scale[q]
                })
            })
        };
        let mut col_ptr = vec![0usize];
        let mut row_idx = Vec::new();
        let mut entries = Vec::new();
        for j in 0..n {
            let rows: Vec<usize> = (j..n).filter(|&i| i == j || near(i, j)).collect();
            for b in 0..dim {
                let q = dim * j + b;
                for &i in &rows {
                    for a in 0..dim {
                        let p = dim * i + a;
                        if p >= q {
                            row_idx.push(p);
                            entries.push((p, q));
                        }
                    }
                }
                col_ptr.push(row_idx.len());
            }
        }
        let pattern = SymbolicSparseColMat::new_checked(m, m, col_ptr, None, row_idx);
        let symbolic = SymbolicLlt::try_new(pattern.as_ref(), Side::Lower).ok()?;
        let values = entries.iter().map(|&(p, q)| winv[(p, q)]).collect();
        Some(NearField { entries, values, pattern, symbolic })
    }

    /// The Cholesky factor of the near field of (W⁻¹)_FF + Ĝ_F (Ĝ as in
    /// [`InverseDelassus::solve`]), identity on the prescribed components; None when that matrix
    /// is not positive definite.
    fn factor(
        &self,
        inverse: &InverseDelassus,
        is_free: &[bool],
        diag: &[f64],
        blocks: &[Option<[[f64; 2]; 2]>],
    ) -> Option<NearPreconditioner> {
        let d = inverse.dim;
        let values: Vec<f64> = self
            .entries
            .iter()
            .zip(&self.values)
            .map(|(&(p, q), &winv_pq)| {
                if !is_free[p] || !is_free[q] {
                    return if p == q { 1.0 } else { 0.0 };
                }
                let mut v = winv_pq + if p == q { diag[p] } else { 0.0 };
                let i = p / d;
                if let (true, Some(g)) = (q / d == i, blocks[i])
                    && p > d * i
                    && q > d * i
                {
                    // the block replaces the diagonal on the tangential pair
                    v += g[p - d * i - 1][q - d * i - 1] - if p == q { diag[p] } else { 0.0 };
                }
                v
            })
            .collect();
        let mat = SparseColMat::new(self.pattern.clone(), values);
        let llt = Llt::try_new_with_symbolic(self.symbolic.clone(), mat.as_ref(), Side::Lower).ok()?;
        Some(NearPreconditioner { llt, m: is_free.len() })
    }
}

/// A near-field factor kept between solves (`InverseDelassus::solve`): the free set it was
/// computed for, and CG's iterations in its first solve of each form (exact, loose).
pub(crate) struct KeptNear {
    is_free: Vec<bool>,
    prec: NearPreconditioner,
    fresh_iterations: [Option<usize>; 2],
}

/// The near field's factor as the preconditioner of [`VelocityMatrix`].
struct NearPreconditioner {
    llt: Llt<usize, f64>,
    m: usize,
}

impl std::fmt::Debug for NearPreconditioner {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "NearPreconditioner({} × {})", self.m, self.m)
    }
}

impl LinOp<f64> for NearPreconditioner {
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
        out.copy_from(rhs);
        self.llt.solve_in_place(out.as_mut());
    }
    fn conj_apply(&self, out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, par: Par, stack: &mut MemStack) {
        self.apply(out, rhs, par, stack)
    }
}

impl Precond<f64> for NearPreconditioner {}

/// (W⁻¹)_FF + Ĝ_F as an operator on all m components (zero off F).
#[derive(Debug)]
struct VelocityMatrix<'a> {
    inverse: &'a InverseDelassus,
    form: DirectionForm,
    is_free: &'a [bool],
    free_list: &'a [usize],
    diag: &'a [f64],
    blocks: &'a [Option<[[f64; 2]; 2]>],
}

impl VelocityMatrix<'_> {
    /// out = [(W⁻¹)_FF + Ĝ_F] v_F (zero off F) and winv_v = W⁻¹ v_F on every component (the
    /// prescribed rows' forces follow from it).
    fn apply(&self, v: &[f64], out: &mut [f64], winv_v: &mut [f64]) {
        let (m, d) = (self.is_free.len(), self.inverse.dim);
        let v: Vec<f64> = (0..m).map(|l| if self.is_free[l] { v[l] } else { 0.0 }).collect();
        winv_v.copy_from_slice(&self.inverse.apply(&v, self.form));
        for l in 0..m {
            out[l] = if self.is_free[l] { winv_v[l] } else { 0.0 };
        }
        for &l in self.free_list {
            out[l] += self.diag[l] * v[l];
        }
        for (i, blk) in self.blocks.iter().enumerate() {
            if let Some(g) = blk {
                let (a, b) = (d * i + 1, d * i + 2);
                if self.is_free[a] && self.is_free[b] {
                    out[a] += g[0][0] * v[a] + g[0][1] * v[b];
                    out[b] += g[1][0] * v[a] + g[1][1] * v[b];
                }
            }
        }
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

/// ‖A‖_∞ of a symmetric A: its largest column sum of |A| (the row sums, read down the columns
/// of the column-major storage).
fn norm_inf(a: MatRef<'_, f64>) -> f64 {
    (0..a.ncols()).map(|j| a.col(j).iter().map(|v| v.abs()).sum::<f64>()).fold(0.0, f64::max)
}
