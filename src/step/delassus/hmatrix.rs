//! W⁻¹ (and W, for the momentum residual) as a hierarchical matrix: its products in about
//! m log m memory reads instead of m².
//!
//! W⁻¹ is the Schur complement of A_k on the contact unknowns (a discrete Dirichlet-to-Neumann
//! map): the coupling of two groups of contact nodes far apart compared with their size is
//! smooth, so that block of W⁻¹ is close to a matrix of low rank. The contact nodes are
//! clustered by recursive bisection of their positions (a binary tree whose leaves hold at most
//! [`LEAF`] nodes); a pair of clusters (a, b) is *admissible* when
//! max(diam a, diam b) ≤ η dist(a, b) (bounding boxes, η = [`ETA`]) and its block is stored as
//! U Vᵀ; the other pairs of leaves are stored dense. W⁻¹ is symmetric, so only the blocks on and
//! above the diagonal are kept and each off-diagonal block is applied twice (B and Bᵀ).
//!
//! Compression: cross approximation with full pivoting on the dense block (the block is in
//! memory: W⁻¹ comes whole from the Schur complement) — repeatedly subtract the rank-one cross
//! through the residual's largest entry until that entry is at most ε max|W⁻¹|. So every stored
//! entry is within ε max|W⁻¹| of W⁻¹'s, and for any x, ‖(H − W⁻¹) x‖_∞ ≤ ε max|W⁻¹| ‖x‖₁: the
//! bound `tests` check. A block whose factors would not be smaller than it stays dense.
//!
//! Written by hand (README, design notes): scirs2-linalg's H-matrix module works on ndarray and
//! brings SciRS2's dependency tree; the C++ and Julia libraries (H2Lib, HLIBpro, HMatrices.jl)
//! are the references this follows.

use faer::{Accum, Mat, MatRef, Par};

/// Most contact nodes in a leaf cluster.
pub const LEAF: usize = 32;
/// The admissibility parameter η: a pair of clusters is compressed when
/// max(diam a, diam b) ≤ η dist(a, b).
pub const ETA: f64 = 2.0;

/// A cluster: the contact nodes at positions `start..end` of the tree's order, their bounding
/// box, and its two children (None for a leaf).
#[derive(Debug, Clone)]
struct Cluster {
    start: usize,
    end: usize,
    lo: [f64; 3],
    hi: [f64; 3],
    children: Option<[usize; 2]>,
}

impl Cluster {
    fn diam(&self) -> f64 {
        (0..3).map(|k| (self.hi[k] - self.lo[k]).powi(2)).sum::<f64>().sqrt()
    }
    fn dist(&self, other: &Cluster) -> f64 {
        (0..3).map(|k| (self.lo[k] - other.hi[k]).max(other.lo[k] - self.hi[k]).max(0.0).powi(2)).sum::<f64>().sqrt()
    }
}

/// One stored block: rows and columns are ranges of the tree's component order.
#[derive(Debug)]
enum Block {
    Dense { rows: std::ops::Range<usize>, cols: std::ops::Range<usize>, b: Mat<f64> },
    LowRank { rows: std::ops::Range<usize>, cols: std::ops::Range<usize>, u: Mat<f64>, v: Mat<f64> },
}

/// A symmetric matrix as blocks on and above the diagonal of its cluster tree.
#[derive(Debug)]
pub struct HMatrix {
    m: usize,
    /// position p of the tree's component order holds component `order[p]`
    order: Vec<usize>,
    blocks: Vec<Block>,
    /// ε: every stored entry within ε max|A| of A's
    tolerance: f64,
    /// ‖H − A‖_F, summed exactly over the compressed blocks (each off-diagonal one twice)
    error_frobenius: f64,
}

impl HMatrix {
    /// Compress the symmetric m × m matrix `a` (m = dim · positions.len(), node i's components at
    /// dim·i..dim·i + dim) to every entry within `tolerance` · max|a|.
    pub fn new(a: MatRef<'_, f64>, dim: usize, positions: &[[f64; 3]], tolerance: f64) -> HMatrix {
        let n = positions.len();
        let m = a.nrows();
        assert_eq!(m, dim * n, "one position per node");
        let mut nodes: Vec<usize> = (0..n).collect();
        let mut tree = Vec::new();
        if n > 0 {
            cluster(&mut nodes, positions, 0, &mut tree);
        }
        let order: Vec<usize> = nodes.iter().flat_map(|&i| (0..dim).map(move |k| dim * i + k)).collect();
        let max_entry =
            (0..m).flat_map(|j| (0..m).map(move |i| (i, j))).fold(0.0f64, |s, (i, j)| s.max(a[(i, j)].abs()));
        let eps = tolerance * max_entry;
        // the pairs of clusters, on and above the diagonal
        let mut pairs = Vec::new();
        let mut stack = if n > 0 { vec![(0usize, 0usize)] } else { vec![] };
        while let Some((p, q)) = stack.pop() {
            let (cp, cq) = (&tree[p], &tree[q]);
            if p != q && cp.diam().max(cq.diam()) <= ETA * cp.dist(cq) {
                pairs.push((p, q, true));
                continue;
            }
            match (cp.children, cq.children) {
                (None, None) => pairs.push((p, q, false)),
                (Some([p1, p2]), _) if p == q => {
                    stack.extend([(p1, p1), (p1, p2), (p2, p2)]);
                }
                (Some(kp), Some(kq)) => {
                    for x in kp {
                        for y in kq {
                            stack.push((x, y));
                        }
                    }
                }
                (Some(kp), None) => stack.extend(kp.map(|x| (x, q))),
                (None, Some(kq)) => stack.extend(kq.map(|y| (p, y))),
            }
        }
        let mut error_squared = 0.0;
        let blocks = pairs
            .into_iter()
            .map(|(p, q, admissible)| {
                let rows = dim * tree[p].start..dim * tree[p].end;
                let cols = dim * tree[q].start..dim * tree[q].end;
                let b = Mat::from_fn(rows.len(), cols.len(), |i, j| a[(order[rows.start + i], order[cols.start + j])]);
                match admissible.then(|| cross_approximation(&b, eps)).flatten() {
                    Some((u, v, e2)) => {
                        // admissible pairs are off the diagonal: the block stands for B and Bᵀ
                        error_squared += 2.0 * e2;
                        Block::LowRank { rows, cols, u, v }
                    }
                    None => Block::Dense { rows, cols, b },
                }
            })
            .collect();
        HMatrix { m, order, blocks, tolerance, error_frobenius: error_squared.sqrt() }
    }

    /// ε: every stored entry is within ε max|A| of A's.
    pub fn tolerance(&self) -> f64 {
        self.tolerance
    }

    /// ‖H − A‖_F, computed from each compressed block's remainder: it bounds ‖H − A‖₂, so
    /// λ_min(H) ≥ λ_min(A) − ‖H − A‖_F (Weyl) — the definiteness certificate of
    /// `InverseDelassus::compressed`.
    pub fn error_frobenius(&self) -> f64 {
        self.error_frobenius
    }

    /// The stored values against m² (the dense matrix's).
    pub fn storage_share(&self) -> f64 {
        let stored: usize = self
            .blocks
            .iter()
            .map(|b| {
                let (len, twice) = match b {
                    Block::Dense { b, rows, cols } => (b.nrows() * b.ncols(), rows != cols),
                    Block::LowRank { u, v, .. } => (u.nrows() * u.ncols() + v.nrows() * v.ncols(), true),
                };
                if twice { 2 * len } else { len }
            })
            .sum();
        stored as f64 / (self.m as f64).powi(2)
    }

    /// out = H x.
    pub fn apply(&self, x: &[f64]) -> Vec<f64> {
        let xp = Mat::from_fn(self.m, 1, |p, _| x[self.order[p]]);
        let mut yp = Mat::<f64>::zeros(self.m, 1);
        // y_at += B x_from
        let add = |yp: &mut Mat<f64>, at: &std::ops::Range<usize>, b: MatRef<'_, f64>, x: MatRef<'_, f64>| {
            faer::linalg::matmul::matmul(yp.subrows_mut(at.start, at.len()), Accum::Add, b, x, 1.0, Par::Seq)
        };
        for block in &self.blocks {
            let (rows, cols) = match block {
                Block::Dense { rows, cols, .. } | Block::LowRank { rows, cols, .. } => (rows, cols),
            };
            let (x_cols, x_rows) = (xp.subrows(cols.start, cols.len()), xp.subrows(rows.start, rows.len()));
            match block {
                Block::Dense { b, .. } => {
                    add(&mut yp, rows, b.as_ref(), x_cols);
                    if rows != cols {
                        add(&mut yp, cols, b.transpose(), x_rows);
                    }
                }
                Block::LowRank { u, v, .. } => {
                    // y_rows += U (Vᵀ x_cols), y_cols += V (Uᵀ x_rows)
                    add(&mut yp, rows, u.as_ref(), (v.transpose() * x_cols).as_ref());
                    add(&mut yp, cols, v.as_ref(), (u.transpose() * x_rows).as_ref());
                }
            }
        }
        let mut out = vec![0.0; self.m];
        for (p, &l) in self.order.iter().enumerate() {
            out[l] = yp[(p, 0)];
        }
        out
    }
}

/// Bisect `nodes` (positions `start..`) along the longest side of their bounding box until a
/// cluster holds at most LEAF nodes; returns the cluster's index in `tree`.
fn cluster(nodes: &mut [usize], positions: &[[f64; 3]], start: usize, tree: &mut Vec<Cluster>) -> usize {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for &i in nodes.iter() {
        for k in 0..3 {
            lo[k] = lo[k].min(positions[i][k]);
            hi[k] = hi[k].max(positions[i][k]);
        }
    }
    let me = tree.len();
    tree.push(Cluster { start, end: start + nodes.len(), lo, hi, children: None });
    if nodes.len() > LEAF {
        let k = (0..3).max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b]))).unwrap_or(0);
        nodes.sort_by(|&a, &b| positions[a][k].total_cmp(&positions[b][k]).then(a.cmp(&b)));
        let half = nodes.len() / 2;
        let (left, right) = nodes.split_at_mut(half);
        let l = cluster(left, positions, start, tree);
        let r = cluster(right, positions, start + half, tree);
        tree[me].children = Some([l, r]);
    }
    me
}

/// Cross approximation with full pivoting: B ≈ U Vᵀ with every entry of B − U Vᵀ at most `eps`
/// in magnitude, and ‖B − U Vᵀ‖²_F (of the remainder it stops at); None when the factors would
/// hold as many values as B. (A truncated SVD of the factors, HLIBpro's recompression, was
/// measured on academic3d's W⁻¹ at 1,632 and 3,600 components: cross approximation to eps/2 and
/// an SVD dropping eps/2 stored 2–4% more than this, so the cross approximation's ranks stay.)
fn cross_approximation(b: &Mat<f64>, eps: f64) -> Option<(Mat<f64>, Mat<f64>, f64)> {
    let (r, c) = (b.nrows(), b.ncols());
    let mut res = b.clone();
    let (mut us, mut vs): (Vec<Vec<f64>>, Vec<Vec<f64>>) = (Vec::new(), Vec::new());
    loop {
        let (mut piv, mut big) = ((0, 0), 0.0f64);
        for j in 0..c {
            for i in 0..r {
                let e = res[(i, j)].abs();
                if e > big {
                    (piv, big) = ((i, j), e);
                }
            }
        }
        if big <= eps {
            break;
        }
        if (us.len() + 1) * (r + c) >= r * c {
            return None;
        }
        let (i0, j0) = piv;
        let pivot = res[(i0, j0)];
        let u: Vec<f64> = (0..r).map(|i| res[(i, j0)]).collect();
        let v: Vec<f64> = (0..c).map(|j| res[(i0, j)] / pivot).collect();
        for (j, &vj) in v.iter().enumerate() {
            if vj != 0.0 {
                for (i, &ui) in u.iter().enumerate() {
                    res[(i, j)] -= ui * vj;
                }
            }
        }
        us.push(u);
        vs.push(v);
    }
    let k = us.len();
    Some((Mat::from_fn(r, k, |i, q| us[q][i]), Mat::from_fn(c, k, |j, q| vs[q][j]), res.squared_norm_l2()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A symmetric smooth kernel on a plane grid of nodes with 3 components each: the far field
    /// of a 1/r kernel (what W is like) plus a dominant diagonal.
    fn kernel(nx: usize, ny: usize) -> (Mat<f64>, Vec<[f64; 3]>) {
        let positions: Vec<[f64; 3]> = (0..nx * ny).map(|i| [(i % nx) as f64, (i / nx) as f64, 0.0]).collect();
        let m = 3 * positions.len();
        let a = Mat::from_fn(m, m, |p, q| {
            let (i, j) = (p / 3, q / 3);
            let r = (0..3).map(|k| (positions[i][k] - positions[j][k]).powi(2)).sum::<f64>().sqrt();
            let coupling = if p % 3 == q % 3 { 1.0 } else { 0.1 };
            coupling / (1.0 + r) + if p == q { 10.0 } else { 0.0 }
        });
        (a, positions)
    }

    /// (S.6) every product is within ε max|A| ‖x‖₁ of the dense one (the entrywise bound of the
    /// compression; the slack 1e-13 covers the round-off of two products of ~2,300 terms), and
    /// the far field is compressed (it stores less than the dense matrix).
    #[test]
    fn products_stay_within_the_compression_bound() {
        let (a, positions) = kernel(32, 24);
        let m = a.nrows();
        let max_entry = a.norm_max();
        for tolerance in [1e-4, 1e-8, 1e-12] {
            let h = HMatrix::new(a.as_ref(), 3, &positions, tolerance);
            // measured 0.43, 0.71, 0.92 of the dense values (ranks 9, 42, 78): the far field
            // compresses, the more the looser ε
            assert!(h.storage_share() < 1.0, "storage {} at ε {tolerance:e}", h.storage_share());
            for seed in 0..3 {
                let x: Vec<f64> = (0..m).map(|l| (((l + seed) * 7919 + 13) % 101) as f64 / 101.0 - 0.5).collect();
                let y = h.apply(&x);
                let exact = &a * faer::ColRef::from_slice(&x);
                let bound = tolerance * max_entry * x.iter().map(|v| v.abs()).sum::<f64>() + 1e-13 * exact.norm_max();
                let err = (0..m).map(|l| (y[l] - exact[l]).abs()).fold(0.0, f64::max);
                assert!(err <= bound, "ε {tolerance:e}: error {err:e} above the bound {bound:e}");
            }
        }
    }

    /// (S.6) the reported ‖H − A‖_F (the definiteness certificate's input) is H's distance to A:
    /// H's dense form from its products with the identity's columns, at ε = 1e-4 and 1e-8 —
    /// to 1e-6 of itself (the remainders carry round-off ~1e-16 max|A| per entry, the norms are
    /// ≥ 1e-8 max|A|), and not zero (the far field was compressed).
    #[test]
    fn the_reported_frobenius_error_is_the_distance_to_the_matrix() {
        let (a, positions) = kernel(16, 12);
        let m = a.nrows();
        for tolerance in [1e-4, 1e-8] {
            let h = HMatrix::new(a.as_ref(), 3, &positions, tolerance);
            let mut dense = Mat::<f64>::zeros(m, m);
            for j in 0..m {
                let e: Vec<f64> = (0..m).map(|l| if l == j { 1.0 } else { 0.0 }).collect();
                for (i, v) in h.apply(&e).into_iter().enumerate() {
                    dense[(i, j)] = v;
                }
            }
            let error = (&dense - &a).norm_l2();
            assert!(
                error > 0.0 && (error - h.error_frobenius()).abs() <= 1e-6 * error,
                "ε {tolerance:e}: {error:e} against {:e}",
                h.error_frobenius()
            );
        }
    }

    /// (S.6) a matrix too small to have an admissible pair is stored exactly (one dense block).
    #[test]
    fn a_single_leaf_is_the_matrix_itself() {
        let (a, positions) = kernel(4, 4);
        let h = HMatrix::new(a.as_ref(), 3, &positions, 1e-12);
        assert_eq!(h.storage_share(), 1.0);
        let x: Vec<f64> = (0..a.nrows()).map(|l| l as f64).collect();
        let exact = &a * faer::ColRef::from_slice(&x);
        // one dense product in another order: round-off of 48 terms
        assert!((0..a.nrows()).all(|l| (h.apply(&x)[l] - exact[l]).abs() <= 1e-12 * exact.norm_max()));
    }
}
