//! The load vector f(t) of the weak form: ⟨f(t), φ⟩ = ∫_Ω f0·φ dx + ∫_Γ2 f2·φ da (P.2, P.4).
//! Parts that do not depend on t are integrated once and cached.

use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::model::expr::VecExpr;

use super::Dofs;

/// Quadrature point with the DOF weights ω_q φ_a(x_q) of the nodes it touches.
#[derive(Debug, Clone)]
struct QPoint {
    x: [f64; 2],
    /// (node, weight × basis value)
    nodes: Vec<(usize, f64)>,
}

#[derive(Debug, Clone)]
struct Term {
    field: VecExpr,
    points: Vec<QPoint>,
    /// the key path of the expression, for messages
    path: String,
}

/// f(t) on the free DOFs.
#[derive(Debug, Clone)]
pub struct LoadVector {
    dofs: Dofs,
    /// time-dependent terms, integrated at each call
    varying: Vec<Term>,
    /// the sum of the time-independent terms
    fixed: Vec<f64>,
    all: Vec<Term>,
}

impl LoadVector {
    /// `body` is f0; `surface` lists (edges, f2, key path) for each loaded side.
    pub fn new(mesh: &Mesh, dofs: &Dofs, body: &VecExpr, surface: &[(Vec<[usize; 2]>, VecExpr, String)]) -> LoadVector {
        let mut terms = Vec::new();
        if !body.is_zero() {
            terms.push(Term { field: body.clone(), points: body_points(mesh), path: "loads.body".into() });
        }
        for (edges, f2, path) in surface {
            if !f2.is_zero() {
                terms.push(Term { field: f2.clone(), points: edge_points(mesh, edges), path: path.clone() });
            }
        }
        let mut fixed = vec![0.0; dofs.n_free];
        let mut varying = Vec::new();
        for t in &terms {
            if t.field.depends_on_t() {
                varying.push(t.clone());
            } else {
                integrate(t, 0.0, dofs, &mut fixed);
            }
        }
        LoadVector { dofs: dofs.clone(), varying, fixed, all: terms }
    }

    /// (P.4) f(t): body force f0 by the edge-midpoint rule (exact for quadratics) and tractions
    /// f2 on Γ2 by two-point Gauss per edge (exact for cubics along the edge).
    pub fn at(&self, t: f64) -> Vec<f64> {
        let mut f = self.fixed.clone();
        for term in &self.varying {
            integrate(term, t, &self.dofs, &mut f);
        }
        f
    }

    /// True when f does not depend on t.
    pub fn is_constant(&self) -> bool {
        self.varying.is_empty()
    }

    /// Every load expression is finite at every quadrature point at time t.
    pub fn check_finite(&self, t: f64) -> Result<()> {
        for term in &self.all {
            for q in &term.points {
                let v = term.field.eval(q.x[0], q.x[1], t);
                if !(v[0].is_finite() && v[1].is_finite()) {
                    return Err(Error::Expression {
                        path: term.path.clone(),
                        message: format!(
                            "evaluates to ({}, {}) at x = {}, y = {}, t = {t}; loads must be finite on the whole mesh and time interval",
                            v[0], v[1], q.x[0], q.x[1]
                        ),
                    });
                }
            }
        }
        Ok(())
    }
}

fn integrate(term: &Term, t: f64, dofs: &Dofs, f: &mut [f64]) {
    for q in &term.points {
        let v = term.field.eval(q.x[0], q.x[1], t);
        for &(node, w) in &q.nodes {
            for c in 0..2 {
                if let Some(i) = dofs.map[2 * node + c] {
                    f[i] += w * v[c];
                }
            }
        }
    }
}

/// Edge-midpoint rule on each triangle: weights |T|/3, φ = ½ on the edge's two nodes.
fn body_points(mesh: &Mesh) -> Vec<QPoint> {
    let mut pts = Vec::with_capacity(3 * mesh.triangles.len());
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let w = mesh.signed_area(t) / 3.0;
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            let (p, q) = (mesh.nodes[a], mesh.nodes[b]);
            pts.push(QPoint { x: [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])], nodes: vec![(a, 0.5 * w), (b, 0.5 * w)] });
        }
    }
    pts
}

/// Two-point Gauss rule on each edge: ξ = ½ ∓ 1/(2√3), weights |e|/2, φ_a = 1 − ξ, φ_b = ξ.
fn edge_points(mesh: &Mesh, edges: &[[usize; 2]]) -> Vec<QPoint> {
    let g = 0.5 / 3f64.sqrt();
    let mut pts = Vec::with_capacity(2 * edges.len());
    for &[a, b] in edges {
        let (p, q) = (mesh.nodes[a], mesh.nodes[b]);
        let len = ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt();
        for xi in [0.5 - g, 0.5 + g] {
            let x = [p[0] + xi * (q[0] - p[0]), p[1] + xi * (q[1] - p[1])];
            pts.push(QPoint { x, nodes: vec![(a, 0.5 * len * (1.0 - xi)), (b, 0.5 * len * xi)] });
        }
    }
    pts
}
