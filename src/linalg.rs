//! Thin wrappers over faer: sparse matrices from triplets, products, the sparse Cholesky
//! factor that the time loop reuses, and a dense LU for the unsymmetric contact systems.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::solvers::Solve;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::LltError;
use faer::sparse::linalg::cholesky::supernodal::SupernodalLltRef;
use faer::sparse::linalg::cholesky::{LltRef, SymbolicCholesky, SymbolicCholeskyRaw};
use faer::sparse::{FaerError, SparseColMat, Triplet};
use faer::{Conj, Mat, Side};

use crate::error::{Error, Result};
use crate::failure::LinearAlgebraFailure;
use crate::ordering::FillOrder;

/// Compressed sparse column matrix of f64.
pub type SpMat = SparseColMat<usize, f64>;

/// Build an n × m matrix from (row, col, value) triplets; duplicates are summed.
pub fn from_triplets(n: usize, m: usize, trip: &[(usize, usize, f64)]) -> Result<SpMat> {
    let t: Vec<Triplet<usize, usize, f64>> = trip.iter().map(|&(i, j, v)| Triplet::new(i, j, v)).collect();
    SparseColMat::try_new_from_triplets(n, m, &t).map_err(|e| Error::LinearAlgebra(LinearAlgebraFailure::Assembly(e)))
}

/// All stored entries (row, col, value).
pub fn triplets(a: &SpMat) -> Vec<(usize, usize, f64)> {
    let r = a.as_ref();
    let (cp, ri, v) = (r.symbolic().col_ptr(), r.symbolic().row_idx(), r.val());
    let mut out = Vec::with_capacity(v.len());
    for j in 0..a.ncols() {
        for p in cp[j]..cp[j + 1] {
            out.push((ri[p], j, v[p]));
        }
    }
    out
}

/// y += alpha A x.
pub fn mul_add(a: &SpMat, x: &[f64], alpha: f64, y: &mut [f64]) {
    let r = a.as_ref();
    let (cp, ri, v) = (r.symbolic().col_ptr(), r.symbolic().row_idx(), r.val());
    for j in 0..a.ncols() {
        let xj = alpha * x[j];
        if xj == 0.0 {
            continue;
        }
        let span = cp[j]..cp[j + 1];
        for (&i, &a) in ri[span.clone()].iter().zip(&v[span]) {
            y[i] += a * xj;
        }
    }
}

/// Whether A and B store the same sparsity pattern (one pass can then form products of both).
pub fn same_pattern(a: &SpMat, b: &SpMat) -> bool {
    let (sa, sb) = (a.as_ref().symbolic(), b.as_ref().symbolic());
    a.nrows() == b.nrows() && a.ncols() == b.ncols() && sa.col_ptr() == sb.col_ptr() && sa.row_idx() == sb.row_idx()
}

/// (A x, A y, B y) for symmetric A and B: column j gathers (A x)_j = Σ_p A_pj x_p, and when A
/// and B share a pattern the three sums read the indices of column j once. Equal to
/// [`mul`] up to the order of the sums.
pub fn sym_mul3(a: &SpMat, b: &SpMat, x: &[f64], y: &[f64]) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    if !same_pattern(a, b) {
        return (mul(a, x), mul(a, y), mul(b, y));
    }
    let n = a.ncols();
    let (mut ax, mut ay, mut by) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let (ra, rb) = (a.as_ref(), b.as_ref());
    let (cp, ri, va, vb) = (ra.symbolic().col_ptr(), ra.symbolic().row_idx(), ra.val(), rb.val());
    for j in 0..n {
        let span = cp[j]..cp[j + 1];
        let (mut s1, mut s2, mut s3) = (0.0, 0.0, 0.0);
        for ((&i, &a), &b) in ri[span.clone()].iter().zip(&va[span.clone()]).zip(&vb[span]) {
            s1 += a * x[i];
            s2 += a * y[i];
            s3 += b * y[i];
        }
        ax[j] = s1;
        ay[j] = s2;
        by[j] = s3;
    }
    (ax, ay, by)
}

/// A x.
pub fn mul(a: &SpMat, x: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; a.nrows()];
    mul_add(a, x, 1.0, &mut y);
    y
}

/// xᵀ A y, column by column: Σ_j y_j (Σ_p A_pj x_p) — reads A once and writes nothing.
pub fn quad(a: &SpMat, x: &[f64], y: &[f64]) -> f64 {
    quad_by(a, |i| x[i], |j| y[j])
}

/// xᵀ A y with x and y given entry by entry (no temporary vectors: the (E.1) terms of a large
/// mesh form x and y from the states on the fly); the same sums as [`quad`].
pub fn quad_by(a: &SpMat, x: impl Fn(usize) -> f64, y: impl Fn(usize) -> f64) -> f64 {
    let r = a.as_ref();
    let (cp, ri, v) = (r.symbolic().col_ptr(), r.symbolic().row_idx(), r.val());
    let mut total = 0.0;
    for j in 0..a.ncols() {
        let yj = y(j);
        if yj == 0.0 {
            continue;
        }
        let span = cp[j]..cp[j + 1];
        let col: f64 = ri[span.clone()].iter().zip(&v[span]).map(|(&i, &a)| a * x(i)).sum();
        total += col * yj;
    }
    total
}

pub fn dot(x: &[f64], y: &[f64]) -> f64 {
    x.iter().zip(y).map(|(a, b)| a * b).sum()
}

pub fn norm_inf(x: &[f64]) -> f64 {
    x.iter().fold(0.0, |m, v| m.max(v.abs()))
}

/// Σ_k c_k A_k for matrices of equal shape.
pub fn combine(terms: &[(f64, &SpMat)]) -> Result<SpMat> {
    let (n, m) = (terms[0].1.nrows(), terms[0].1.ncols());
    let mut trip = Vec::new();
    for (c, a) in terms {
        if *c != 0.0 {
            trip.extend(triplets(a).into_iter().map(|(i, j, v)| (i, j, c * v)));
        }
    }
    from_triplets(n, m, &trip)
}

/// Sparse Cholesky factor L Lᵀ of a symmetric positive definite matrix, computed once, its
/// unknowns ordered by `ordering::analyse` (AMD, or nested dissection where the unknowns'
/// positions are given and its factor is the smaller by a margin).
pub struct Cholesky {
    symbolic: SymbolicCholesky<usize>,
    /// the factor's values, in `symbolic`'s layout
    values: Vec<f64>,
    order: FillOrder,
}

impl Cholesky {
    /// Factor `a` (only its lower triangle is read); `positions`: where each unknown sits (one
    /// per row), for the nested dissection.
    pub fn new(a: &SpMat, what: &str, positions: Option<&[[f64; 3]]>) -> Result<Cholesky> {
        let (symbolic, order) =
            crate::ordering::analyse(a.symbolic(), positions, &[], Default::default()).map_err(|cause| {
                Error::LinearAlgebra(LinearAlgebraFailure::SymbolicCholesky { matrix: what.to_string(), cause })
            })?;
        let numeric = |symbolic: &SymbolicCholesky<usize>| -> std::result::Result<Vec<f64>, LltError> {
            let mut values = Vec::new();
            values.try_reserve_exact(symbolic.len_val()).map_err(|_| FaerError::OutOfMemory)?;
            values.resize(symbolic.len_val(), 0.0);
            let par = faer::get_global_parallelism();
            let mut mem = MemBuffer::try_new(symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()))
                .map_err(|_| FaerError::OutOfMemory)?;
            symbolic.factorize_numeric_llt(
                &mut values,
                a.as_ref(),
                Side::Lower,
                Default::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )?;
            Ok(values)
        };
        let values = numeric(&symbolic).map_err(|cause| {
            Error::LinearAlgebra(LinearAlgebraFailure::Cholesky { matrix: what.to_string(), cause })
        })?;
        Ok(Cholesky { symbolic, values, order })
    }

    pub fn dim(&self) -> usize {
        self.symbolic.nrows()
    }

    /// Stored entries of the factor L.
    pub fn factor_len(&self) -> usize {
        self.symbolic.len_val()
    }

    /// How the factor's unknowns are ordered.
    pub fn fill_order(&self) -> FillOrder {
        self.order
    }

    /// B ← A⁻¹ B for a dense block of right-hand sides.
    pub fn solve_mat_in_place(&self, b: &mut Mat<f64>) {
        let par = faer::get_global_parallelism();
        let mut mem = MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(b.ncols(), par));
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            b.as_mut(),
            par,
            MemStack::new(&mut mem),
        );
    }

    /// b ← A⁻¹ b.
    pub fn solve_in_place(&self, b: &mut [f64]) {
        let par = faer::get_global_parallelism();
        let mut mem = MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(1, par));
        let col = faer::ColMut::from_slice_mut(b);
        LltRef::new(&self.symbolic, &self.values).solve_in_place_with_conj(
            Conj::No,
            col.as_mat_mut(),
            par,
            MemStack::new(&mut mem),
        );
    }
}

/// Solve the dense system J x = r by LU with partial pivoting; None if J is singular or the
/// result is not finite.
pub fn dense_solve(j: &Mat<f64>, r: &[f64]) -> Option<Vec<f64>> {
    let n = r.len();
    let lu = j.partial_piv_lu();
    let rhs = Mat::<f64>::from_fn(n, 1, |i, _| r[i]);
    let x = lu.solve(&rhs);
    let out: Vec<f64> = (0..n).map(|i| x[(i, 0)]).collect();
    out.iter().all(|v| v.is_finite()).then_some(out)
}

/// The supernodes of a supernodal factor L (of P A Pᵀ) that a set of unknowns reaches: those
/// holding the unknowns and all their ancestors in the elimination tree, ascending (the order a
/// forward pass visits them). Every nonzero L_ij has i an ancestor of j, so
/// - a forward solve L z = P c with c nonzero only on the unknowns changes only these
///   supernodes' rows, and reads only their columns;
/// - the unknowns' values of a backward solve Lᵀ x = z depend only on these supernodes' rows,
///   and the other supernodes' rows can be finished afterwards from them.
///
/// The contact unknowns of a thick body reach ~0.68–0.77 of A_k's factor under its nested
/// dissection (academic3d, 64×32×24 → 24×12×8): the free solve and the recovery (S.2) each read
/// that share instead of the whole factor once (`Simulation::step`).
#[derive(Debug, Clone)]
pub struct Reach {
    /// the reached supernodes, ascending
    supernodes: Vec<usize>,
    /// the other supernodes, ascending
    rest: Vec<usize>,
    /// the unknowns, in the factor's order (P's)
    rows: Vec<usize>,
    /// per column of L (the factor's order): whether a reached supernode holds it
    covered: Vec<bool>,
    /// entries of L in the reached supernodes
    entries: usize,
}

impl Reach {
    /// Stored entries of L that a pass over the reach reads.
    pub fn entries(&self) -> usize {
        self.entries
    }
}

impl Cholesky {
    /// The supernodal factor, or None for a simplicial one (small or very sparse matrices,
    /// whose solves are cheap).
    fn supernodal(&self) -> Option<SupernodalLltRef<'_, usize, f64>> {
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(sym) => Some(SupernodalLltRef::new(sym, &self.values)),
            SymbolicCholeskyRaw::Simplicial(_) => None,
        }
    }

    /// The supernodal factor of the passes below, which only a factor with a [`Reach`] takes.
    /// Panics on a simplicial factor (whose `reach` is None): a caller's error, not an input's.
    fn passes(&self) -> SupernodalLltRef<'_, usize, f64> {
        self.supernodal().expect("the split passes need a supernodal factor (Cholesky::reach is Some only for one)")
    }

    /// The position of unknown i in the factor's order: (P x)_{pos(i)} = x_i.
    fn position(&self, i: usize) -> usize {
        self.symbolic.perm().map_or(i, |p| p.arrays().1[i])
    }

    /// The reach of the unknowns `rows` (see [`Reach`]); None for a simplicial factor, or when
    /// the reach is the whole factor (the split passes would gain nothing).
    pub fn reach(&self, rows: &[usize]) -> Option<Reach> {
        let l = self.supernodal()?;
        let sym = l.symbolic();
        let (begin, end) = (sym.supernode_begin(), sym.supernode_end());
        let mut of_col = vec![0usize; self.dim()];
        for s in 0..sym.n_supernodes() {
            of_col[begin[s]..end[s]].fill(s);
        }
        let mut hit = vec![false; sym.n_supernodes()];
        let rows: Vec<usize> = rows.iter().map(|&i| self.position(i)).collect();
        for &r in &rows {
            let mut s = of_col[r];
            // up the elimination tree: a supernode's parent holds the first (smallest) row of
            // its pattern (faer's patterns are ascending and exclude the supernode's own columns)
            while !std::mem::replace(&mut hit[s], true) {
                match sym.supernode(s).pattern().first() {
                    Some(&p) => s = of_col[p],
                    None => break,
                }
            }
        }
        let (supernodes, rest): (Vec<usize>, Vec<usize>) = (0..sym.n_supernodes()).partition(|&s| hit[s]);
        if rest.is_empty() {
            return None;
        }
        let covered = of_col.iter().map(|&s| hit[s]).collect();
        let entries = supernodes
            .iter()
            .map(|&s| (end[s] - begin[s]) * (end[s] - begin[s] + sym.supernode(s).pattern().len()))
            .sum();
        Some(Reach { supernodes, rest, rows, covered, entries })
    }

    /// z = L⁻¹ P b: the forward half of a solve, in the factor's order (faer's whole pass).
    /// Supernodal factors only (see `passes`).
    pub fn forward(&self, b: &[f64]) -> Vec<f64> {
        let l = self.passes();
        let mut z: Vec<f64> = match self.symbolic.perm() {
            Some(p) => p.arrays().0.iter().map(|&i| b[i]).collect(),
            None => b.to_vec(),
        };
        let par = faer::get_global_parallelism();
        let mut mem = MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(1, par));
        l.l_solve_with_conj(Conj::No, faer::ColMut::from_slice_mut(&mut z).as_mat_mut(), par, MemStack::new(&mut mem));
        z
    }

    /// x = Pᵀ L⁻ᵀ z: the backward half of a solve, from the factor's order (faer's whole pass).
    pub fn backward(&self, mut z: Vec<f64>) -> Vec<f64> {
        let l = self.passes();
        let par = faer::get_global_parallelism();
        let mut mem = MemBuffer::new(self.symbolic.solve_in_place_scratch::<f64>(1, par));
        l.l_transpose_solve_with_conj(
            Conj::No,
            faer::ColMut::from_slice_mut(&mut z).as_mat_mut(),
            par,
            MemStack::new(&mut mem),
        );
        self.unpermute(&z)
    }

    /// Pᵀ x: from the factor's order back to the unknowns'.
    fn unpermute(&self, x: &[f64]) -> Vec<f64> {
        match self.symbolic.perm() {
            Some(p) => p.arrays().1.iter().map(|&i| x[i]).collect(),
            None => x.to_vec(),
        }
    }

    /// z ← z − L⁻¹ P c for a c that is zero off the reach's unknowns: the forward pass over the
    /// reach's supernodes only (the others' rows of L⁻¹ P c are zero). Each visited supernode
    /// takes the kernels of faer's whole pass (`l_solve_with_conj`) with the same arguments, so
    /// L⁻¹ P c equals that pass's to the bit. A nonzero c_i off the reach is a caller's error
    /// (checked in debug builds).
    pub fn forward_sub(&self, reach: &Reach, c: &[f64], z: &mut [f64]) {
        let l = self.passes();
        let par = faer::get_global_parallelism();
        let mut x = vec![0.0; self.dim()];
        for (i, &ci) in c.iter().enumerate() {
            if ci != 0.0 {
                let j = self.position(i);
                debug_assert!(reach.covered[j], "c is nonzero at unknown {i}, off the reach");
                x[j] = ci;
            }
        }
        let mut tmp = Vec::new();
        for &s in &reach.supernodes {
            let node = l.supernode(s);
            let (ls, size) = (node.val(), node.val().ncols());
            let (ls_top, ls_bot) = ls.split_at_row(size);
            let mut x_top = faer::ColMut::from_slice_mut(&mut x[node.start()..node.start() + size]).as_mat_mut();
            faer::linalg::triangular_solve::solve_lower_triangular_in_place_with_conj(
                ls_top,
                Conj::No,
                x_top.rb_mut(),
                par,
            );
            tmp.clear();
            tmp.resize(node.pattern().len(), 0.0);
            faer::linalg::matmul::matmul_with_conj(
                faer::ColMut::from_slice_mut(&mut tmp).as_mat_mut(),
                faer::Accum::Replace,
                ls_bot,
                Conj::No,
                x_top.rb(),
                Conj::No,
                1.0,
                par,
            );
            for (t, &i) in tmp.iter().zip(node.pattern()) {
                x[i] -= t;
            }
        }
        for (zj, (xj, &covered)) in z.iter_mut().zip(x.iter().zip(&reach.covered)) {
            if covered {
                *zj -= xj;
            }
        }
    }

    /// The backward pass Lᵀ x = z over the reach's supernodes only: x (the factor's order) with
    /// the reach's rows final, and (Pᵀ x)_i at every unknown i the reach was built for (the other
    /// entries 0). Each visited supernode takes the kernels of faer's whole pass
    /// (`l_transpose_solve_with_conj`) with the same arguments, in the same order, on rows that
    /// only reached supernodes write: these entries equal the whole backward's to the bit.
    pub fn backward_over(&self, reach: &Reach, z: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let mut x = z.to_vec();
        self.backward_pass(reach.supernodes.iter().rev().copied(), &mut x);
        let mut out = vec![0.0; self.dim()];
        let fwd = self.symbolic.perm().map(|p| p.arrays().0);
        for &r in &reach.rows {
            out[fwd.map_or(r, |f| f[r])] = x[r];
        }
        (x, out)
    }

    /// Finish the backward pass that [`backward_over`](Self::backward_over) began, over the
    /// supernodes off the reach (descending: each reads only its ancestors' rows, final by
    /// then): Pᵀ L⁻ᵀ z, equal to [`backward`](Self::backward) of the same z to the bit.
    pub fn backward_rest(&self, reach: &Reach, mut x: Vec<f64>) -> Vec<f64> {
        self.backward_pass(reach.rest.iter().rev().copied(), &mut x);
        self.unpermute(&x)
    }

    /// The backward pass of faer's `l_transpose_solve_with_conj` over `supernodes` (descending).
    fn backward_pass(&self, supernodes: impl Iterator<Item = usize>, x: &mut [f64]) {
        let l = self.passes();
        let par = faer::get_global_parallelism();
        let mut tmp = Vec::new();
        for s in supernodes {
            let node = l.supernode(s);
            let (ls, size) = (node.val(), node.val().ncols());
            let (ls_top, ls_bot) = ls.split_at_row(size);
            tmp.clear();
            tmp.extend(node.pattern().iter().map(|&i| x[i]));
            let mut x_top = faer::ColMut::from_slice_mut(&mut x[node.start()..node.start() + size]).as_mat_mut();
            faer::linalg::matmul::matmul_with_conj(
                x_top.rb_mut(),
                faer::Accum::Add,
                ls_bot.transpose(),
                Conj::No,
                faer::ColRef::from_slice(&tmp).as_mat(),
                Conj::No,
                -1.0,
                par,
            );
            faer::linalg::triangular_solve::solve_upper_triangular_in_place_with_conj(
                ls_top.transpose(),
                Conj::No,
                x_top.rb_mut(),
                par,
            );
        }
    }
}
