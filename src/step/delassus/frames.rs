//! The slip frames the Newton matrices read W in (3-D), and W read in them: W' = Qᵀ W Q.

use super::Delassus;

/// The tangent frames the Newton matrices read each slipping node in (3-D): node i's tangential
/// pair (τ_1, τ_2) is taken in the basis (ẑ_i, ẑ_i^⊥), ẑ_i the direction of t_i + ρ v̄_i on the
/// disk's slip branch and ẑ^⊥ = (−ẑ_2, ẑ_1), where the friction force is known along ẑ and
/// follows the slip rate across it (see `newton::direction`). W' = Qᵀ W Q with Q the block
/// rotation; nodes without a frame (all of them in 2-D) keep their own components.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SlipFrames {
    pub(super) dim: usize,
    /// per contact node: ẑ in the node's (τ_1, τ_2) components, or None
    pub(super) zhat: Vec<Option<[f64; 2]>>,
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
