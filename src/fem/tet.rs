//! P1 tetrahedron kernels (d = 3): basis gradients, the strain matrix and the element matrices
//! of the forms ∫ρ u·v, ∫ Bε(u):ε(v) and ∫ Aε(u):ε(v). DOFs are interleaved: (vertex k,
//! component c) → 3k + c. The 2-D triangle kernels are in [`super::element`].

use nalgebra::{Matrix3, Matrix6, SMatrix};

/// Gradients of the four P1 basis functions (constant on the tetrahedron) and its signed volume
/// (positive when (x1 − x0, x2 − x0, x3 − x0) is right-handed). With J = [x1 − x0, x2 − x0,
/// x3 − x0] (columns), grad φ_k = J⁻ᵀ e_k for k = 1, 2, 3 and grad φ_0 = −Σ grad φ_k.
/// None when the tetrahedron is degenerate (det J = 0 or not finite).
pub fn gradients(x: [[f64; 3]; 4]) -> Option<([[f64; 3]; 4], f64)> {
    let col = |k: usize| nalgebra::Vector3::new(x[k][0] - x[0][0], x[k][1] - x[0][1], x[k][2] - x[0][2]);
    let j = Matrix3::from_columns(&[col(1), col(2), col(3)]);
    let det = j.determinant();
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let jinv_t = j.try_inverse()?.transpose();
    let mut g = [[0.0; 3]; 4];
    for k in 1..4 {
        for c in 0..3 {
            g[k][c] = jinv_t[(c, k - 1)];
            g[0][c] -= g[k][c];
        }
    }
    Some((g, det / 6.0))
}

/// Strain matrix: (ε_xx, ε_yy, ε_zz, γ_yz, γ_xz, γ_xy) = S · (u_0x, u_0y, u_0z, …, u_3z).
pub fn strain_matrix(grad: &[[f64; 3]; 4]) -> SMatrix<f64, 6, 12> {
    let mut s = SMatrix::<f64, 6, 12>::zeros();
    for (k, g) in grad.iter().enumerate() {
        let (x, y, z) = (3 * k, 3 * k + 1, 3 * k + 2);
        s[(0, x)] = g[0];
        s[(1, y)] = g[1];
        s[(2, z)] = g[2];
        s[(3, y)] = g[2];
        s[(3, z)] = g[1];
        s[(4, x)] = g[2];
        s[(4, z)] = g[0];
        s[(5, x)] = g[1];
        s[(5, y)] = g[0];
    }
    s
}

/// (P.1) Element matrix ∫_T D ε(φ_j) : ε(φ_i) in three dimensions, D the 6×6 Voigt matrix of
/// B (stiffness K) or A (viscous matrix C). None for a degenerate tetrahedron.
pub fn operator_matrix(x: [[f64; 3]; 4], d: &Matrix6<f64>) -> Option<SMatrix<f64, 12, 12>> {
    let (grad, vol) = gradients(x)?;
    let s = strain_matrix(&grad);
    Some(s.transpose() * d * s * vol.abs())
}

/// ∫_T ρ φ_j φ_i per component: ρ|T|/20 (1 + δ_ij).
pub fn consistent_mass(volume: f64, rho: f64) -> SMatrix<f64, 12, 12> {
    let mut m = SMatrix::<f64, 12, 12>::zeros();
    for i in 0..4 {
        for j in 0..4 {
            let v = rho * volume / 20.0 * if i == j { 2.0 } else { 1.0 };
            for c in 0..3 {
                m[(3 * i + c, 3 * j + c)] = v;
            }
        }
    }
    m
}

/// The lumped (row-sum) mass a P1 tetrahedron gives each of its vertices: ρ|T|/4.
pub fn vertex_mass(volume: f64, rho: f64) -> f64 {
    rho * volume / 4.0
}
