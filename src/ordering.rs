//! Fill-reducing orders for the sparse Cholesky factors of A_k: faer's approximate minimum
//! degree (AMD), or a nested dissection from where the unknowns sit, whichever factor holds
//! fewer entries by a margin.
//!
//! AMD is local: on a 3-D mesh as thick as it is wide its factor grows faster than the
//! n^{4/3} of nested dissection (George; Lipton–Rose–Tarjan). Measured on academic3d's boxes:
//! the factor of A_k holds 62.4 M entries under AMD and 42.4 M under the dissection below at
//! 48×24×16 (61,200 unknowns), 323.5 M and 167.2 M at 64×32×24 (158,400), and with the contact
//! unknowns ordered last (the Schur complement's factor) 103.7 M and 68.3 M at 48×24×16.
//! On thin, slender or 2-D meshes AMD's factor is the smaller one (a column of 1,212 unknowns:
//! 16,878 entries against ~33,000), and small problems keep it: the dissection is taken only when
//! its factor holds at most
//! [`NESTED_DISSECTION_ADVANTAGE`](crate::defaults::NESTED_DISSECTION_ADVANTAGE) of AMD's.
//!
//! The dissection is geometric: bisect the unknowns at the median of their positions along one
//! side of their bounding box — of the three, the one whose separator is the smallest; the
//! unknowns of the lower half that couple (in A's pattern) with the upper half form the
//! separator, ordered after both halves, which are dissected in turn down to [`LEAF`] unknowns.
//! Removing the separator leaves no coupling between the halves whatever the mesh (a P1 mesh of
//! a box cut along a layer of nodes: that layer). A node's unknowns share its position, so they
//! stay together.
//!
//! Written by hand (README, design notes): faer orders by AMD or COLAMD only; METIS (the
//! `metis` crate) builds a C library, and a geometric bisection of a mesh whose positions are
//! known needs none of its graph partitioning.

use faer::perm::PermRef;
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, SymbolicCholesky, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::{FaerError, SymbolicSparseColMatRef};
use faer::{Side as Triangle, dyn_stack::MemBuffer, dyn_stack::MemStack};

/// Most unknowns of a part the dissection does not cut again (four 3-D nodes: measured on
/// academic3d 48×24×16 with each part cut across its longest side, leaves of 12, 48 and 192
/// unknowns gave factors of 45.0 M, 45.4 M and 47.1 M entries, hertz3d 12.2 M, 12.4 M and
/// 13.1 M).
pub const LEAF: usize = 12;

/// How a factor's unknowns are ordered.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FillOrder {
    /// faer's approximate minimum degree
    MinimumDegree,
    /// the geometric nested dissection of [`nested_dissection`]
    NestedDissection,
}

impl FillOrder {
    /// Its name in reports.
    pub fn name(self) -> &'static str {
        match self {
            FillOrder::MinimumDegree => "minimum degree",
            FillOrder::NestedDissection => "nested dissection",
        }
    }
}

/// The symbolic Cholesky factorization of the symmetric `pattern` (its lower triangle read)
/// with the unknowns `last` moved to the end in that order (the Schur complement's route to W;
/// empty: no constraint), the others in the order of AMD or, when `positions` (one per unknown)
/// are given and its factor holds at most NESTED_DISSECTION_ADVANTAGE of AMD's entries, of the
/// nested dissection. Without `last`, AMD is faer's own ordering of the pattern (the factor
/// `linalg::Cholesky` had before this choice existed). The entries compared are the stored
/// values of each factor as faer lays it out (what a solve reads). Should the dissection's own
/// analysis fail (memory), AMD's stands.
///
/// # Panics
/// When `last` holds an unknown twice or one ≥ n (its callers pass distinct contact unknowns:
/// `schur::contact_block_of_factor` checks them first).
pub fn analyse(
    pattern: SymbolicSparseColMatRef<'_, usize>,
    positions: Option<&[[f64; 3]]>,
    last: &[usize],
    params: CholeskySymbolicParams<'_>,
) -> Result<(SymbolicCholesky<usize>, FillOrder), FaerError> {
    let n = pattern.nrows();
    let mut is_last = vec![false; n];
    for &l in last {
        is_last[l] = true;
    }
    // the order with `last` moved to the end, as faer's custom permutation
    let constrained = |order: &[usize]| -> Result<SymbolicCholesky<usize>, FaerError> {
        let fwd: Vec<usize> = order.iter().copied().filter(|&i| !is_last[i]).chain(last.iter().copied()).collect();
        let mut inv = vec![0usize; n];
        for (k, &i) in fwd.iter().enumerate() {
            inv[i] = k;
        }
        factorize_symbolic_cholesky(
            pattern,
            Triangle::Lower,
            SymmetricOrdering::Custom(PermRef::new_checked(&fwd, &inv, n)),
            params,
        )
    };
    let by_degree = if last.is_empty() {
        factorize_symbolic_cholesky(pattern, Triangle::Lower, SymmetricOrdering::Amd, params)?
    } else {
        let (mut order, mut order_inv) = (vec![0usize; n], vec![0usize; n]);
        let mut mem = MemBuffer::try_new(amd::order_scratch::<usize>(n, pattern.compute_nnz()))?;
        amd::order(&mut order, &mut order_inv, pattern, amd::Control::default(), MemStack::new(&mut mem))?;
        constrained(&order)?
    };
    let dissected = positions
        .filter(|_| n > LEAF)
        .and_then(|positions| constrained(&nested_dissection(pattern, positions)).ok())
        .filter(|d| d.len_val() as f64 <= crate::defaults::NESTED_DISSECTION_ADVANTAGE * by_degree.len_val() as f64);
    Ok(match dissected {
        Some(d) => (d, FillOrder::NestedDissection),
        None => (by_degree, FillOrder::MinimumDegree),
    })
}

/// The order `order[k]` = the unknown eliminated k-th, of the symmetric pattern `pattern`
/// (either triangle or both; the diagonal is ignored) whose unknown i sits at `positions[i]`:
/// nested dissection (see the module's doc). A permutation of 0..n.
pub fn nested_dissection(pattern: SymbolicSparseColMatRef<'_, usize>, positions: &[[f64; 3]]) -> Vec<usize> {
    let n = pattern.nrows();
    assert_eq!(positions.len(), n, "one position per unknown");
    let adjacency = symmetric_adjacency(pattern);
    let mut side = vec![Side::Unset; n];
    let mut order = Vec::with_capacity(n);
    dissect((0..n).collect(), positions, &adjacency, &mut side, &mut order);
    order
}

/// Which half of the current bisection an unknown fell in (scratch of `dissect`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Side {
    Unset,
    Upper,
}

/// The pattern's couplings as adjacency lists of both directions, without the diagonal.
fn symmetric_adjacency(pattern: SymbolicSparseColMatRef<'_, usize>) -> Vec<Vec<usize>> {
    let n = pattern.nrows();
    let mut adjacency = vec![Vec::new(); n];
    for j in 0..n {
        for i in pattern.row_idx_of_col(j) {
            if i != j {
                adjacency[i].push(j);
                adjacency[j].push(i);
            }
        }
    }
    for a in &mut adjacency {
        a.sort_unstable();
        a.dedup();
    }
    adjacency
}

/// What `dissect` still has to do, kept on an explicit stack (no recursion, whatever the mesh):
/// dissect a part, or append a separator once both halves before it are ordered.
enum Task {
    Dissect(Vec<usize>),
    Append(Vec<usize>),
}

/// Append `part`'s unknowns to `order`: its two halves dissected, then their separator. A part
/// is cut at the median position across the side (of the three) whose cut has the smallest
/// separator — the upper half above the median, or at and above it when nothing lies above —
/// and stays whole when all its positions coincide or it holds at most LEAF unknowns.
fn dissect(
    part: Vec<usize>,
    positions: &[[f64; 3]],
    adjacency: &[Vec<usize>],
    side: &mut [Side],
    order: &mut Vec<usize>,
) {
    let mut tasks = vec![Task::Dissect(part)];
    while let Some(task) = tasks.pop() {
        let part = match task {
            Task::Append(separator) => {
                order.extend(separator);
                continue;
            }
            Task::Dissect(part) if part.len() <= LEAF => {
                order.extend(part);
                continue;
            }
            Task::Dissect(part) => part,
        };
        // every side that can be cut, the smallest separator kept (the longest side on a tie):
        // a side of few node layers but great length (stretched cells) would cut across the
        // whole part
        let mut best: Option<(Vec<usize>, Vec<usize>, Vec<usize>)> = None;
        for (axis, median, strictly) in cuts(&part, positions) {
            let above = |x: f64| if strictly { x > median } else { x >= median };
            for &i in &part {
                if above(positions[i][axis]) {
                    side[i] = Side::Upper;
                }
            }
            let (mut lower, mut upper, mut separator) = (Vec::new(), Vec::new(), Vec::new());
            for &i in &part {
                if side[i] == Side::Upper {
                    upper.push(i);
                } else if adjacency[i].iter().any(|&j| side[j] == Side::Upper) {
                    separator.push(i);
                } else {
                    lower.push(i);
                }
            }
            for &i in &upper {
                side[i] = Side::Unset;
            }
            if best.as_ref().is_none_or(|b| separator.len() < b.2.len()) {
                best = Some((lower, upper, separator));
            }
        }
        let Some((lower, upper, separator)) = best else {
            order.extend(part);
            continue;
        };
        // last in, first out: the lower half, then the upper one, then the separator
        tasks.push(Task::Append(separator));
        tasks.push(Task::Dissect(upper));
        tasks.push(Task::Dissect(lower));
    }
}

/// Where `part` can be cut, longest side first: per side of non-zero length, the axis, the
/// median position along it, and whether the upper half lies strictly above it (else at and
/// above it: more than half the positions share the largest coordinate). Both halves of such a
/// cut are non-empty, so every part the dissection makes is smaller than the one it cut; no cut
/// when all the positions coincide.
fn cuts(part: &[usize], positions: &[[f64; 3]]) -> Vec<(usize, f64, bool)> {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for &i in part {
        for k in 0..3 {
            lo[k] = lo[k].min(positions[i][k]);
            hi[k] = hi[k].max(positions[i][k]);
        }
    }
    let mut axes = [0, 1, 2];
    axes.sort_by(|&a, &b| (hi[b] - lo[b]).total_cmp(&(hi[a] - lo[a])));
    axes.into_iter()
        .filter(|&k| hi[k] > lo[k])
        .filter_map(|axis| {
            let mut along: Vec<f64> = part.iter().map(|&i| positions[i][axis]).collect();
            let half = along.len() / 2;
            let median = *along.select_nth_unstable_by(half, f64::total_cmp).1;
            if along.iter().any(|&x| x > median) {
                Some((axis, median, true))
            } else {
                // the median is the largest coordinate, and the smallest lies below it
                (lo[axis] < median).then_some((axis, median, false))
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::sparse::SymbolicSparseColMat;

    /// The full pattern of the 27-point stencil (every node coupled with the nodes of the cells
    /// around it, as P1 on a Kuhn box or Q1 couple them) on an nx × ny × nz grid of nodes, d
    /// unknowns per node, and their positions.
    fn grid(nx: usize, ny: usize, nz: usize, d: usize) -> (SymbolicSparseColMat<usize>, Vec<[f64; 3]>) {
        let n = nx * ny * nz;
        let at = |x: usize, y: usize, z: usize| x + nx * (y + ny * z);
        let mut col_ptr = vec![0];
        let mut row_idx = Vec::new();
        let mut positions = vec![[0.0; 3]; d * n];
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    let mut nodes = Vec::new();
                    for zz in z.saturating_sub(1)..(z + 2).min(nz) {
                        for yy in y.saturating_sub(1)..(y + 2).min(ny) {
                            for xx in x.saturating_sub(1)..(x + 2).min(nx) {
                                nodes.push(at(xx, yy, zz));
                            }
                        }
                    }
                    nodes.sort_unstable();
                    for c in 0..d {
                        positions[d * at(x, y, z) + c] = [x as f64, y as f64, z as f64];
                        row_idx.extend(nodes.iter().flat_map(|&q| (0..d).map(move |cc| d * q + cc)));
                        col_ptr.push(row_idx.len());
                    }
                }
            }
        }
        (SymbolicSparseColMat::new_checked(d * n, d * n, col_ptr, None, row_idx), positions)
    }

    /// The entries of the Cholesky factor of `pattern` under faer's `ordering`.
    fn entries(pattern: &SymbolicSparseColMat<usize>, ordering: SymmetricOrdering<'_, usize>) -> usize {
        factorize_symbolic_cholesky(pattern.as_ref(), faer::Side::Lower, ordering, Default::default())
            .expect("symbolic analysis of a test pattern")
            .len_val()
    }

    /// The entries of the Cholesky factor of `pattern` under the order `order` (order[k] = the
    /// unknown eliminated k-th).
    fn dissected_entries(pattern: &SymbolicSparseColMat<usize>, order: &[usize]) -> usize {
        let mut inverse = vec![0; order.len()];
        for (k, &i) in order.iter().enumerate() {
            inverse[i] = k;
        }
        entries(pattern, SymmetricOrdering::Custom(PermRef::new_checked(order, &inverse, order.len())))
    }

    /// (S.2) The order is a permutation of the unknowns, and on a cube of 16³ nodes with three
    /// unknowns each (where nested dissection is known to beat local orderings) its factor holds
    /// fewer entries than AMD's, which holds fewer than the natural order's (the band).
    #[test]
    fn the_order_is_a_permutation_that_reduces_fill() {
        let (pattern, positions) = grid(16, 16, 16, 3);
        let n = pattern.nrows();
        let order = nested_dissection(pattern.as_ref(), &positions);
        let mut seen = vec![false; n];
        for &i in &order {
            assert!(!std::mem::replace(&mut seen[i], true), "unknown {i} ordered twice");
        }
        assert!(seen.iter().all(|s| *s), "every unknown ordered");
        let (natural, dissection, amd) = (
            entries(&pattern, SymmetricOrdering::Identity),
            dissected_entries(&pattern, &order),
            entries(&pattern, SymmetricOrdering::Amd),
        );
        // measured: natural 10,836,477, dissection 5,376,060, AMD 8,119,431 entries — the cube
        // of a P1-like pattern is where the dissection wins (0.66 of AMD's; academic3d 64×32×24:
        // 0.54)
        assert!(dissection < amd && amd < natural, "natural {natural}, dissection {dissection}, AMD {amd}");
    }

    /// A stretched grid (two node layers along its longest side, 16 × 16 nodes across): a cut
    /// along that side would put a whole layer in the separator, so the dissection cuts across
    /// a shorter side and its factor holds fewer entries than the natural order's (a band of two
    /// layers' width).
    #[test]
    fn a_stretched_part_is_still_cut() {
        let (pattern, mut positions) = grid(2, 16, 16, 3);
        for p in &mut positions {
            p[0] *= 100.0; // the x side (two layers) is now the longest
        }
        let order = nested_dissection(pattern.as_ref(), &positions);
        let natural = entries(&pattern, SymmetricOrdering::Identity);
        let dissection = dissected_entries(&pattern, &order);
        // measured: natural 186,480, dissection 140,931 (a cut along the two layers: 796,284)
        assert!(dissection < natural, "natural {natural}, dissection {dissection}");
    }

    /// Coincident positions (nothing to bisect) and a part smaller than a leaf are kept whole.
    #[test]
    fn coincident_positions_are_ordered_as_they_come() {
        let (pattern, _) = grid(4, 4, 2, 1);
        let positions = vec![[1.0, 2.0, 3.0]; 32];
        assert_eq!(nested_dissection(pattern.as_ref(), &positions), (0..32).collect::<Vec<_>>());
    }
}
