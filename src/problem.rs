//! Scene → discrete problem: the mesh with Γ1, Γ2, Γ3, the material, the loads, the initial
//! data (S.0) and the contact model. Everything the time loop needs, checked once.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::fem::{Dofs, LoadVector};
use crate::mesh::{self, Mesh};
use crate::model::contact::ContactModel;
use crate::model::expr::{Expr, VecExpr};
use crate::model::laws::{FrictionBoundLaw, FrictionCoefficient, NormalLaw};
use crate::model::material::Material;
use crate::scene::{Bound, DomainKind, Enforcement, FrictionBound, FrictionLaw, NumOrStr, Scene};

/// The discrete problem of one scene.
pub struct Problem {
    pub scene: Scene,
    pub mesh: Mesh,
    pub material: Material,
    pub dofs: Dofs,
    pub loads: LoadVector,
    /// u^0 and v^0 on the free DOFs (S.0)
    pub u0: Vec<f64>,
    pub v0: Vec<f64>,
    pub contact: Option<ContactModel>,
    /// k and N
    pub k: f64,
    pub steps: usize,
}

impl Problem {
    /// Build from a scene; `scene_dir` resolves a relative Gmsh path.
    pub fn new(scene: Scene, scene_dir: &Path) -> Result<Problem> {
        let mesh = build_mesh(&scene, scene_dir)?;
        let names = mesh.side_list();
        let side_err = |key: String, s: &str| Error::scene(key, format!("no side named {s:?}; the mesh has {names}"));
        for (i, s) in scene.boundary.dirichlet.iter().enumerate() {
            if mesh.side(s).is_none() {
                return Err(side_err(format!("boundary.dirichlet[{i}]"), s));
            }
        }
        for (i, s) in scene.boundary.contact.iter().enumerate() {
            if mesh.side(s).is_none() {
                return Err(side_err(format!("boundary.contact[{i}]"), s));
            }
        }
        for (i, tr) in scene.loads.traction.iter().enumerate() {
            if mesh.side(&tr.side).is_none() {
                return Err(side_err(format!("loads.traction[{i}].side"), &tr.side));
            }
        }
        let material = Material::from_scene(&scene.material, scene.domain.plane);
        let clamped = mesh.nodes_on(&scene.boundary.dirichlet)?;
        let dofs = Dofs::new(mesh.nodes.len(), &clamped);
        if dofs.n_free == 0 {
            return Err(Error::scene("boundary.dirichlet", "clamps every node: there is nothing to solve"));
        }

        // loads
        let body = VecExpr::parse(&scene.loads.body, &["x", "y", "t"], "loads.body")?;
        let mut surface = Vec::new();
        for (i, tr) in scene.loads.traction.iter().enumerate() {
            let path = format!("loads.traction[{i}].value");
            let f2 = VecExpr::parse(&tr.value, &["x", "y", "t"], &path)?;
            let edges = mesh.side(&tr.side).map(|s| s.edges.clone()).unwrap_or_default();
            surface.push((edges, f2, path));
        }
        // f3 on Γ3 (every contact side), for manufactured solutions with contact
        let f3 = VecExpr::parse(&scene.loads.contact_surface, &["x", "y", "t"], "loads.contact_surface")?;
        if !f3.is_zero() {
            for side in &scene.boundary.contact {
                let edges = mesh.side(side).map(|s| s.edges.clone()).unwrap_or_default();
                surface.push((edges, f3.clone(), "loads.contact_surface".into()));
            }
        }
        let loads = LoadVector::new(&mesh, &dofs, &body, &surface);
        loads.check_finite(0.0)?;
        loads.check_finite(scene.time.end)?;

        // initial data (S.0): nodal interpolation
        let (u0e, v0e) = initial_fields(&scene)?;
        let (u0, v0) = initial_data(&mesh, &dofs, &u0e, &v0e)?;

        let contact = if scene.has_contact() { Some(build_contact(&scene, &mesh, &dofs, &clamped)?) } else { None };
        if let Some(c) = &contact {
            if c.n() == 0 {
                return Err(Error::scene(
                    "boundary.contact",
                    "the contact sides have no node off the clamped sides (Γ̄3 \\ Γ̄1 is empty)",
                ));
            }
            // S.0: u^0 ∈ K^h
            if let Some(g) = c.constraint {
                let d0 = c.penetration(&u0);
                if let Some(i) = (0..c.n()).find(|&i| d0[i] > g * (1.0 + 1e-12) + 1e-300) {
                    let x = mesh.nodes[c.nodes[i]];
                    return Err(Error::scene(
                        "initial.displacement",
                        format!(
                            "the initial state penetrates beyond the bound: u_ν − gap = {:.6e} > g = {g} at node {} ({}, {}); \
                             u0 must satisfy the constraint (S.0)",
                            d0[i], c.nodes[i], x[0], x[1]
                        ),
                    ));
                }
            }
        }
        let steps = scene.steps();
        let k = scene.time.step;
        Ok(Problem { scene, mesh, material, dofs, loads, u0, v0, contact, k, steps })
    }

    /// The time of step n.
    pub fn time(&self, n: usize) -> f64 {
        n as f64 * self.k
    }
}

fn build_mesh(scene: &Scene, scene_dir: &Path) -> Result<Mesh> {
    let d = &scene.domain;
    let mesh = match d.kind {
        DomainKind::Rectangle => {
            let (size, cells) = match (d.size, d.cells) {
                (Some(s), Some(c)) => (s, c),
                _ => return Err(Error::scene("domain", "a rectangle needs size and cells")),
            };
            Mesh::rectangle(size[0], size[1], cells[0] as usize, cells[1] as usize)
        }
        DomainKind::Gmsh => {
            let file = d.file.as_deref().unwrap_or("");
            let path: PathBuf = if Path::new(file).is_absolute() { file.into() } else { scene_dir.join(file) };
            if !path.exists() {
                return Err(Error::scene("domain.file", format!("mesh file {:?} does not exist", path.display().to_string())));
            }
            mesh::gmsh::read(&path)?
        }
    };
    mesh.check()?;
    Ok(mesh)
}

/// (P.7) The initial conditions u(0) = u0, u̇(0) = v0 of the scene, as fields in x, y.
pub fn initial_fields(scene: &Scene) -> Result<(VecExpr, VecExpr)> {
    Ok((
        VecExpr::parse(&scene.initial.displacement, &["x", "y"], "initial.displacement")?,
        VecExpr::parse(&scene.initial.velocity, &["x", "y"], "initial.velocity")?,
    ))
}

/// (S.0) Discrete initial data u^0 = I_h u0, v^0 = I_h v0 (nodal interpolation; zero on Γ̄1).
pub fn initial_data(mesh: &Mesh, dofs: &Dofs, u0: &VecExpr, v0: &VecExpr) -> Result<(Vec<f64>, Vec<f64>)> {
    let mut out = Vec::new();
    for (e, path) in [(u0, "initial.displacement"), (v0, "initial.velocity")] {
        for (k, p) in mesh.nodes.iter().enumerate() {
            let v = e.eval(p[0], p[1], 0.0);
            if !(v[0].is_finite() && v[1].is_finite()) {
                return Err(Error::Expression {
                    path: path.into(),
                    message: format!("evaluates to ({}, {}) at node {k} ({}, {}); initial data must be finite", v[0], v[1], p[0], p[1]),
                });
            }
        }
        out.push(dofs.gather(|k| e.eval(mesh.nodes[k][0], mesh.nodes[k][1], 0.0)));
    }
    let v = out.pop().unwrap_or_default();
    let u = out.pop().unwrap_or_default();
    Ok((u, v))
}

fn build_contact(scene: &Scene, mesh: &Mesh, dofs: &Dofs, clamped: &[bool]) -> Result<ContactModel> {
    let c = scene.contact.as_ref().ok_or_else(|| Error::scene("contact", "missing section"))?;
    let side = mesh.side_nodes(&scene.boundary.contact, clamped)?;
    let gap_expr = match &c.gap {
        None => Expr::constant(0.0),
        Some(NumOrStr::Num(v)) => Expr::constant(*v),
        Some(NumOrStr::Str(s)) => Expr::parse(s, &["x", "y"], "contact.gap")?,
    };
    let mut gap = Vec::with_capacity(side.nodes.len());
    for &v in &side.nodes {
        let p = mesh.nodes[v];
        let g = gap_expr.eval(p[0], p[1], 0.0);
        if !g.is_finite() {
            return Err(Error::scene("contact.gap", format!("evaluates to {g} at node {v} ({}, {})", p[0], p[1])));
        }
        gap.push(g);
    }
    let bound = scene.bound_of(c)?;
    let compliance = NormalLaw::compliance(c.compliance);
    let (normal, constraint) = match (c.enforcement, bound) {
        (Enforcement::Exact, Bound::Finite(g)) => (compliance.clone(), Some(g)),
        (Enforcement::Exact, Bound::Infinite) => (compliance.clone(), None),
        (Enforcement::Penalty, Bound::Finite(g)) => (NormalLaw::penalized(c.compliance, g, c.penalty.unwrap_or(1.0)), None),
        (Enforcement::Penalty, Bound::Infinite) => {
            return Err(Error::scene("contact.enforcement", "penalty needs a finite penetration_bound"));
        }
    };
    let f = &c.friction;
    let friction = match f.law {
        FrictionLaw::None => None,
        FrictionLaw::Constant => Some(FrictionCoefficient::Constant(f.coefficient.unwrap_or(0.0))),
        FrictionLaw::Exponential => Some(FrictionCoefficient::Exponential {
            a: f.static_.unwrap_or(0.0),
            b: f.kinetic.unwrap_or(0.0),
            alpha: f.decay.unwrap_or(0.0),
        }),
        FrictionLaw::Table => Some(FrictionCoefficient::Table(f.points.clone().unwrap_or_default())),
    };
    let cap = match (c.friction_bound, bound) {
        (FrictionBound::Capped, Bound::Finite(g)) => Some(g),
        _ => None,
    };
    let p_tau = FrictionBoundLaw { compliance: compliance.clone(), cap };
    // a friction law whose bound is identically zero (e.g. Signorini: p ≡ 0) does nothing
    let friction = friction.filter(|mu| !(p_tau.compliance.is_zero() || (mu.is_constant() && mu.mu(0.0) == 0.0)));
    Ok(ContactModel::new(side, gap, dofs, normal, compliance, constraint, bound, c.enforcement, friction, p_tau))
}
