//! The sparse form of W by probing (the module doc of `delassus`): the decay radius measured at
//! one node, the colouring that lets far-apart nodes share a probe, and the kept entries.

use std::collections::HashMap;

use faer::Side;
use faer::sparse::linalg::cholesky::{SymmetricOrdering, factorize_symbolic_cholesky};
use faer::sparse::{SparseColMat, Triplet};

use super::{responses, unit};
use crate::linalg::Cholesky;
use crate::model::contact::ContactModel;

/// The probed, truncated Delassus operator and what it cost.
pub struct SparseDelassus {
    /// the kept entries of W (symmetric, whole node blocks)
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

/// The decay of W measured at one node: the radius R beyond which every entry of its columns is
/// below `truncation` × its diagonal, and the share of contact nodes within R.
pub struct Probe {
    /// the fraction of the diagonal below which an entry counts as decayed
    pub truncation: f64,
    /// R (mesh units)
    pub radius: f64,
    /// the share of contact nodes within R of the probed node (the estimate of W's density)
    pub density: f64,
}

impl Probe {
    /// Probe the d columns of the contact node nearest the centroid of the contact nodes
    /// (`positions`; d solves).
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

/// out += a W[:, l] for a sparse W.
pub(super) fn column_add(w: &SparseColMat<usize, f64>, l: usize, a: f64, out: &mut [f64]) {
    for (&i, v) in w.symbolic().row_idx_of_col_raw(l).iter().zip(w.val_of_col(l)) {
        out[i] += v * a;
    }
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
