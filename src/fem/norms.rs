//! Error norms of a P1 field against a smooth function, by a 7-point degree-5 quadrature
//! (Dunavant), so the quadrature error is far below the discretization error measured.

use super::element;
use crate::mesh::Mesh;
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
    mesh: &Mesh,
    mat: &Material,
    u_h: &[[f64; 2]],
    u: impl Fn(f64, f64) -> [f64; 2],
    grad_u: impl Fn(f64, f64) -> [[f64; 2]; 2],
) -> (f64, f64) {
    let d = mat.elasticity();
    let (mut l2, mut en) = (0.0, 0.0);
    for tri in &mesh.triangles {
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
