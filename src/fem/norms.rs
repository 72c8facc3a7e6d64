//! Error norms of a P1 field against a smooth function, by a 7-point degree-5 quadrature
//! (Dunavant) on triangles and a degree-5 collapsed Gauss rule on tetrahedra, so the quadrature
//! error is far below the discretization error measured.

use super::element;
use crate::mesh::PlaneMesh;
use crate::mesh::solid::SolidMesh;
use crate::model::material::Material;

/// Barycentric points and weights (weights sum to 1) of the degree-5 rule.
const RULE: [([f64; 3], f64); 7] = {
    let a1 = 0.059_715_871_789_769_82;
    let b1 = 0.470_142_064_105_115_1;
    let a2 = 0.797_426_985_353_087_3;
    let b2 = 0.101_286_507_323_456_3;
    let w1 = 0.132_394_152_788_506_2;
    let w2 = 0.125_939_180_544_827_1;
    [
        ([1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0], 0.225),
        ([a1, b1, b1], w1),
        ([b1, a1, b1], w1),
        ([b1, b1, a1], w1),
        ([a2, b2, b2], w2),
        ([b2, a2, b2], w2),
        ([b2, b2, a2], w2),
    ]
};

/// (‖u_h − u‖_{L²}, a(u_h − u, u_h − u)^{1/2}) where a is the elastic energy of `mat` (the
/// energy norm). `u_h` is nodal; `u`, `grad_u` are the exact field and its gradient
/// [[∂x ux, ∂y ux], [∂x uy, ∂y uy]].
pub fn error_norms(
    mesh: &PlaneMesh,
    mat: &Material,
    u_h: &[[f64; 2]],
    u: impl Fn(f64, f64) -> [f64; 2],
    grad_u: impl Fn(f64, f64) -> [[f64; 2]; 2],
) -> (f64, f64) {
    let d = mat.elasticity();
    let (mut l2, mut en) = (0.0, 0.0);
    for tri in &mesh.cells {
        let x = [mesh.nodes[tri[0]], mesh.nodes[tri[1]], mesh.nodes[tri[2]]];
        let (grad, signed) = element::gradients(x);
        let area = signed.abs();
        // the constant FE gradient
        let mut gh = [[0.0; 2]; 2];
        for (k, g) in grad.iter().enumerate() {
            for c in 0..2 {
                gh[c][0] += u_h[tri[k]][c] * g[0];
                gh[c][1] += u_h[tri[k]][c] * g[1];
            }
        }
        for (bary, w) in RULE {
            let px = bary[0] * x[0][0] + bary[1] * x[1][0] + bary[2] * x[2][0];
            let py = bary[0] * x[0][1] + bary[1] * x[1][1] + bary[2] * x[2][1];
            let uh = [0, 1].map(|c| bary[0] * u_h[tri[0]][c] + bary[1] * u_h[tri[1]][c] + bary[2] * u_h[tri[2]][c]);
            let ue = u(px, py);
            l2 += w * area * ((uh[0] - ue[0]).powi(2) + (uh[1] - ue[1]).powi(2));
            let ge = grad_u(px, py);
            let e = [gh[0][0] - ge[0][0], gh[1][1] - ge[1][1], gh[0][1] - ge[0][1] + gh[1][0] - ge[1][0]];
            let ev = nalgebra::Vector3::from(e);
            en += w * area * ev.dot(&(d * ev));
        }
    }
    (l2.sqrt(), en.sqrt())
}

/// Barycentric points and weights (summing to 1) of a degree-5 rule on the tetrahedron: the
/// collapsed (Duffy) product of 4-point Gauss–Legendre rules, λ1 = a, λ2 = b (1 − a),
/// λ3 = c (1 − a)(1 − b) with the Jacobian (1 − a)²(1 − b) — 64 points, positive weights, exact
/// for polynomials of degree ≤ 5 (the transformed integrand has degree ≤ 7 per direction).
pub fn tet_rule() -> Vec<([f64; 4], f64)> {
    let g: [(f64, f64); 4] = [
        (0.5 - 0.5 * 0.861_136_311_594_052_6, 0.5 * 0.347_854_845_137_453_8),
        (0.5 - 0.5 * 0.339_981_043_584_856_3, 0.5 * 0.652_145_154_862_546_1),
        (0.5 + 0.5 * 0.339_981_043_584_856_3, 0.5 * 0.652_145_154_862_546_1),
        (0.5 + 0.5 * 0.861_136_311_594_052_6, 0.5 * 0.347_854_845_137_453_8),
    ];
    let mut rule = Vec::with_capacity(64);
    for &(a, wa) in &g {
        for &(b, wb) in &g {
            for &(c, wc) in &g {
                let l1 = a;
                let l2 = b * (1.0 - a);
                let l3 = c * (1.0 - a) * (1.0 - b);
                // the reference tetrahedron has volume 1/6: weights normalized to sum to 1
                let w = 6.0 * wa * wb * wc * (1.0 - a).powi(2) * (1.0 - b);
                rule.push(([1.0 - l1 - l2 - l3, l1, l2, l3], w));
            }
        }
    }
    rule
}

/// (‖u_h − u‖_{L²}, a(u_h − u, u_h − u)^{1/2}) on a tetrahedral mesh, a the elastic energy of
/// `mat` (the energy norm), by the degree-5 rule of [`tet_rule`]. `u_h` is nodal; `u`,
/// `grad_u` are the exact field and its gradient (∂_j u_i at [i][j]).
pub fn error_norms_3d(
    mesh: &SolidMesh,
    mat: &Material,
    u_h: &[[f64; 3]],
    u: impl Fn([f64; 3]) -> [f64; 3],
    grad_u: impl Fn([f64; 3]) -> [[f64; 3]; 3],
) -> (f64, f64) {
    let d = mat.elasticity_3d();
    let rule = tet_rule();
    let (mut l2, mut en) = (0.0, 0.0);
    for tet in &mesh.cells {
        let x = tet.map(|v| mesh.nodes[v]);
        let Some((grad, signed)) = super::tet::gradients(x) else { continue };
        let volume = signed.abs();
        let mut gh = [[0.0; 3]; 3];
        for (k, g) in grad.iter().enumerate() {
            for i in 0..3 {
                for j in 0..3 {
                    gh[i][j] += u_h[tet[k]][i] * g[j];
                }
            }
        }
        for (bary, w) in &rule {
            let p: [f64; 3] = std::array::from_fn(|c| (0..4).map(|k| bary[k] * x[k][c]).sum());
            let uh: [f64; 3] = std::array::from_fn(|c| (0..4).map(|k| bary[k] * u_h[tet[k]][c]).sum());
            let ue = u(p);
            l2 += w * volume * (0..3).map(|c| (uh[c] - ue[c]).powi(2)).sum::<f64>();
            let ge = grad_u(p);
            let e = |i: usize, j: usize| gh[i][j] - ge[i][j];
            // Voigt (ε_xx, ε_yy, ε_zz, γ_yz, γ_xz, γ_xy), the order of tet::strain_matrix
            let ev = nalgebra::Vector6::new(
                e(0, 0),
                e(1, 1),
                e(2, 2),
                e(1, 2) + e(2, 1),
                e(0, 2) + e(2, 0),
                e(0, 1) + e(1, 0),
            );
            en += w * volume * ev.dot(&(d * ev));
        }
    }
    (l2.sqrt(), en.sqrt())
}
