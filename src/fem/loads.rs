//! The load vector f(t) of the weak form: ⟨f(t), φ⟩ = ∫_Ω f0·φ dx + ∫_Γ2 f2·φ da (P.2, P.4).
//! Parts that do not depend on t are integrated once and cached.

use crate::error::{Error, Result};
use crate::mesh::PlaneMesh;
use crate::mesh::solid::SolidMesh;
use crate::model::expr::VecExpr;

use super::Dofs;

/// Quadrature point with the DOF weights ω_q φ_a(x_q) of the nodes it touches.
#[derive(Debug, Clone)]
struct QPoint {
    /// the point (z = 0 in 2-D)
    x: [f64; 3],
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
    pub fn new(
        mesh: &PlaneMesh,
        dofs: &Dofs,
        body: &VecExpr,
        surface: &[(Vec<[usize; 2]>, VecExpr, String)],
    ) -> LoadVector {
        let mut terms = Vec::new();
        if !body.is_zero() {
            terms.push(Term { field: body.clone(), points: body_points(mesh), path: "loads.body".into() });
        }
        for (edges, f2, path) in surface {
            if !f2.is_zero() {
                terms.push(Term { field: f2.clone(), points: edge_points(mesh, edges), path: path.clone() });
            }
        }
        LoadVector::from_terms(dofs, terms)
    }

    /// The same on a tetrahedral mesh: `surface` lists (faces, f2, key path) per loaded side.
    pub fn solid(
        mesh: &SolidMesh,
        dofs: &Dofs,
        body: &VecExpr,
        surface: &[(Vec<[usize; 3]>, VecExpr, String)],
    ) -> LoadVector {
        let mut terms = Vec::new();
        if !body.is_zero() {
            terms.push(Term { field: body.clone(), points: tet_points(mesh), path: "loads.body".into() });
        }
        for (faces, f2, path) in surface {
            if !f2.is_zero() {
                terms.push(Term { field: f2.clone(), points: face_points(mesh, faces), path: path.clone() });
            }
        }
        LoadVector::from_terms(dofs, terms)
    }

    fn from_terms(dofs: &Dofs, terms: Vec<Term>) -> LoadVector {
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
    /// f2 on Γ2 by two-point Gauss per edge (exact for cubics along the edge); in 3-D the
    /// four-point rule on tetrahedra and the edge-midpoint rule on faces (both exact for
    /// quadratics).
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
        check_terms_finite(&self.all, t)
    }

    /// The evaluations of a scan of the time-dependent loads at `times` times: one per
    /// quadrature point of each varying term per time.
    pub fn scan_cost(&self, times: usize) -> usize {
        self.varying.iter().map(|t| t.points.len()).sum::<usize>().saturating_mul(times)
    }

    /// Every time-dependent load expression is finite at every quadrature point at each of the
    /// times (the loads that do not depend on t are checked once, by [`LoadVector::check_finite`]).
    pub fn check_finite_at(&self, times: impl IntoIterator<Item = f64>) -> Result<()> {
        if self.varying.is_empty() {
            return Ok(());
        }
        times.into_iter().try_for_each(|t| check_terms_finite(&self.varying, t))
    }
}

/// Each term's expression is finite at each of its quadrature points at time t; else an
/// expression error naming the term's key, the value, the point and t.
fn check_terms_finite(terms: &[Term], t: f64) -> Result<()> {
    for term in terms {
        for q in &term.points {
            let v = term.field.eval3(q.x, t);
            if !v.iter().all(|c| c.is_finite()) {
                let d = term.field.dim();
                let (vals, at) = if d == 3 {
                    (
                        format!("({}, {}, {})", v[0], v[1], v[2]),
                        format!("x = {}, y = {}, z = {}", q.x[0], q.x[1], q.x[2]),
                    )
                } else {
                    (format!("({}, {})", v[0], v[1]), format!("x = {}, y = {}", q.x[0], q.x[1]))
                };
                return Err(Error::Expression {
                    path: term.path.clone(),
                    message: format!(
                        "evaluates to {vals} at {at}, t = {t}; loads must be finite on the whole mesh and time interval"
                    ),
                });
            }
        }
    }
    Ok(())
}

fn integrate(term: &Term, t: f64, dofs: &Dofs, f: &mut [f64]) {
    for q in &term.points {
        let v = term.field.eval3(q.x, t);
        for &(node, w) in &q.nodes {
            for c in 0..dofs.dim {
                if let Some(i) = dofs.map[dofs.dim * node + c] {
                    f[i] += w * v[c];
                }
            }
        }
    }
}

/// Edge-midpoint rule on each triangle: weights |T|/3, φ = ½ on the edge's two nodes.
fn body_points(mesh: &PlaneMesh) -> Vec<QPoint> {
    let mut pts = Vec::with_capacity(3 * mesh.cells.len());
    for (t, tri) in mesh.cells.iter().enumerate() {
        let w = mesh.signed_measure(t) / 3.0;
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            let (p, q) = (mesh.nodes[a], mesh.nodes[b]);
            pts.push(QPoint {
                x: [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1]), 0.0],
                nodes: vec![(a, 0.5 * w), (b, 0.5 * w)],
            });
        }
    }
    pts
}

/// Two-point Gauss rule on each edge: ξ = ½ ∓ 1/(2√3), weights |e|/2, φ_a = 1 − ξ, φ_b = ξ.
fn edge_points(mesh: &PlaneMesh, edges: &[[usize; 2]]) -> Vec<QPoint> {
    let g = 0.5 / 3f64.sqrt();
    let mut pts = Vec::with_capacity(2 * edges.len());
    for &[a, b] in edges {
        let (p, q) = (mesh.nodes[a], mesh.nodes[b]);
        let len = ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt();
        for xi in [0.5 - g, 0.5 + g] {
            let x = [p[0] + xi * (q[0] - p[0]), p[1] + xi * (q[1] - p[1]), 0.0];
            pts.push(QPoint { x, nodes: vec![(a, 0.5 * len * (1.0 - xi)), (b, 0.5 * len * xi)] });
        }
    }
    pts
}

/// The symmetric four-point rule on each tetrahedron (exact for quadratics): barycentric
/// points (a, b, b, b) and permutations, a = (5 + 3√5)/20, b = (5 − √5)/20, weights |T|/4.
fn tet_points(mesh: &SolidMesh) -> Vec<QPoint> {
    let a = (5.0 + 3.0 * 5f64.sqrt()) / 20.0;
    let b = (5.0 - 5f64.sqrt()) / 20.0;
    let mut pts = Vec::with_capacity(4 * mesh.cells.len());
    for (t, tet) in mesh.cells.iter().enumerate() {
        let w = mesh.signed_measure(t).abs() / 4.0;
        let x = tet.map(|v| mesh.nodes[v]);
        for k in 0..4 {
            let lam: [f64; 4] = std::array::from_fn(|j| if j == k { a } else { b });
            let p = std::array::from_fn(|c| (0..4).map(|j| lam[j] * x[j][c]).sum());
            pts.push(QPoint { x: p, nodes: (0..4).map(|j| (tet[j], w * lam[j])).collect() });
        }
    }
    pts
}

/// The edge-midpoint rule on each face (exact for quadratics on the triangle): weights |F|/3,
/// φ = ½ on the edge's two nodes.
fn face_points(mesh: &SolidMesh, faces: &[[usize; 3]]) -> Vec<QPoint> {
    let mut pts = Vec::with_capacity(3 * faces.len());
    for f in faces {
        let [p, q, r] = f.map(|v| mesh.nodes[v]);
        let (u, v) = ([q[0] - p[0], q[1] - p[1], q[2] - p[2]], [r[0] - p[0], r[1] - p[1], r[2] - p[2]]);
        let n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
        let w = 0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt() / 3.0;
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            let (xa, xb) = (mesh.nodes[a], mesh.nodes[b]);
            pts.push(QPoint {
                x: std::array::from_fn(|c| 0.5 * (xa[c] + xb[c])),
                nodes: vec![(a, 0.5 * w), (b, 0.5 * w)],
            });
        }
    }
    pts
}
