//! P1 triangle kernels: basis gradients, the strain matrix and the element matrices of the
//! forms ∫ρ u·v, ∫ Bε(u):ε(v) and ∫ Aε(u):ε(v). DOFs are interleaved: (node k, comp c) → 2k + c.

use nalgebra::{Matrix3, SMatrix};

/// Gradients of the three P1 basis functions (constant on the triangle) and its signed area
/// (positive when counterclockwise; the gradients do not depend on the orientation).
/// grad φ_i = (b_i, c_i)/(2A) with b = (y2 − y3, y3 − y1, y1 − y2), c = (x3 − x2, x1 − x3, x2 − x1).
pub fn gradients(x: [[f64; 2]; 3]) -> ([[f64; 2]; 3], f64) {
    let [[x1, y1], [x2, y2], [x3, y3]] = x;
    let det = (x2 - x1) * (y3 - y1) - (x3 - x1) * (y2 - y1);
    let b = [y2 - y3, y3 - y1, y1 - y2];
    let c = [x3 - x2, x1 - x3, x2 - x1];
    ([[b[0] / det, c[0] / det], [b[1] / det, c[1] / det], [b[2] / det, c[2] / det]], 0.5 * det)
}

/// Strain matrix: (ε_xx, ε_yy, γ_xy) = S · (u_1x, u_1y, u_2x, u_2y, u_3x, u_3y).
pub fn strain_matrix(grad: &[[f64; 2]; 3]) -> SMatrix<f64, 3, 6> {
    let mut s = SMatrix::<f64, 3, 6>::zeros();
    for (i, g) in grad.iter().enumerate() {
        s[(0, 2 * i)] = g[0];
        s[(1, 2 * i + 1)] = g[1];
        s[(2, 2 * i)] = g[1];
        s[(2, 2 * i + 1)] = g[0];
    }
    s
}

/// (P.1) Element matrix ∫_T D ε(φ_j) : ε(φ_i) of the Kelvin–Voigt operators, D given as its
/// Voigt matrix: D = B gives the stiffness K, D = A the viscous matrix C.
pub fn operator_matrix(x: [[f64; 2]; 3], d: &Matrix3<f64>) -> SMatrix<f64, 6, 6> {
    let (grad, area) = gradients(x);
    let s = strain_matrix(&grad);
    s.transpose() * d * s * area.abs()
}

/// ∫_T ρ φ_j φ_i per component: ρA/12 (1 + δ_ij).
pub fn consistent_mass(area: f64, rho: f64) -> SMatrix<f64, 6, 6> {
    let mut m = SMatrix::<f64, 6, 6>::zeros();
    for i in 0..3 {
        for j in 0..3 {
            let v = rho * area / 12.0 * if i == j { 2.0 } else { 1.0 };
            m[(2 * i, 2 * j)] = v;
            m[(2 * i + 1, 2 * j + 1)] = v;
        }
    }
    m
}

/// The lumped (row-sum) mass a P1 triangle gives each of its vertices: ρ|T|/3.
pub fn vertex_mass(area: f64, rho: f64) -> f64 {
    rho * area / 3.0
}

/// Row-sum lumped mass: ρA/3 on each diagonal entry.
pub fn lumped_mass(area: f64, rho: f64) -> SMatrix<f64, 6, 6> {
    SMatrix::<f64, 6, 6>::from_diagonal_element(vertex_mass(area, rho))
}
