//! Model → discrete problem: the mesh with Γ1, Γ2, Γ3, the material, the loads, the initial
//! data (S.0) and the contact model. Everything the time loop needs, checked once.
//!
//! A `Problem` is built only from a validated [`Model`] (see `Scene::validate`); the
//! mesh-dependent checks (side names, the clamped set, u^0 ∈ K^h) are made here.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::fem::{Dofs, LoadVector};
use crate::mesh::{self, Mesh};
use crate::model::contact::ContactModel;
use crate::model::expr::VecExpr;
use crate::model::kinds::{Bound, FrictionBound};
use crate::model::laws::{FrictionBoundLaw, NormalLaw};
use crate::model::material::Material;
use crate::model::{ContactParams, Domain, Enforcement, Model};
use crate::scene::Scene;

/// The discrete problem of one scene.
pub struct Problem {
    /// the validated scene this problem was built from
    pub model: Model,
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
    /// Validate a scene and build its problem; `scene_dir` resolves a relative Gmsh path.
    pub fn from_scene(scene: &Scene, scene_dir: &Path) -> Result<Problem> {
        Problem::new(scene.validate()?, scene_dir)
    }

    /// Build from a validated model; `scene_dir` resolves a relative Gmsh path.
    pub fn new(model: Model, scene_dir: &Path) -> Result<Problem> {
        let mesh = build_mesh(&model.domain, scene_dir)?;
        check_sides(&model, &mesh)?;
        let material = Material::new(&model.material, model.plane);
        let clamped = mesh.nodes_on(&model.dirichlet)?;
        let dofs = Dofs::new(mesh.nodes.len(), &clamped);
        if dofs.n_free == 0 {
            return Err(Error::scene("boundary.dirichlet", "clamps every node: there is nothing to solve"));
        }
        let loads = build_loads(&model, &mesh, &dofs)?;
        let (u0, v0) = initial_data(&mesh, &dofs, &model.initial.displacement, &model.initial.velocity)?;
        let contact = match &model.contact {
            Some(c) => Some(build_contact(c, &model.contact_sides, &mesh, &dofs, &clamped)?),
            None => None,
        };
        if let Some(c) = &contact {
            check_initial_admissible(c, &mesh, &u0)?;
        }
        let (steps, k) = (model.time.steps, model.time.step);
        Ok(Problem { model, mesh, material, dofs, loads, u0, v0, contact, k, steps })
    }

    /// The time of step n.
    pub fn time(&self, n: usize) -> f64 {
        n as f64 * self.k
    }
}

/// Every side the model names exists on the mesh.
fn check_sides(model: &Model, mesh: &Mesh) -> Result<()> {
    let names = mesh.side_list();
    let side_err = |key: String, s: &str| Error::scene(key, format!("no side named {s:?}; the mesh has {names}"));
    for (i, s) in model.dirichlet.iter().enumerate() {
        if mesh.side(s).is_none() {
            return Err(side_err(format!("boundary.dirichlet[{i}]"), s));
        }
    }
    for (i, s) in model.contact_sides.iter().enumerate() {
        if mesh.side(s).is_none() {
            return Err(side_err(format!("boundary.contact[{i}]"), s));
        }
    }
    for (i, tr) in model.loads.traction.iter().enumerate() {
        if mesh.side(&tr.side).is_none() {
            return Err(side_err(format!("loads.traction[{i}].side"), &tr.side));
        }
    }
    Ok(())
}

/// f(t): the body load f0, the tractions f2 and the known load f3 on Γ3 (every contact side;
/// for manufactured solutions with contact), checked finite at t = 0 and t = T.
pub fn build_loads(model: &Model, mesh: &Mesh, dofs: &Dofs) -> Result<LoadVector> {
    let edges_of = |side: &str| mesh.side(side).map(|s| s.edges.clone()).unwrap_or_default();
    let mut surface: Vec<(Vec<[usize; 2]>, VecExpr, String)> =
        model.loads.traction.iter().map(|tr| (edges_of(&tr.side), tr.value.clone(), tr.path.clone())).collect();
    if let Some(f3) = &model.loads.contact_surface {
        for side in &model.contact_sides {
            surface.push((edges_of(side), f3.clone(), "loads.contact_surface".into()));
        }
    }
    let loads = LoadVector::new(mesh, dofs, &model.loads.body, &surface);
    loads.check_finite(0.0)?;
    loads.check_finite(model.time.end)?;
    Ok(loads)
}

/// (S.0) u^0 ∈ K^h: the initial state does not penetrate beyond the bound g.
fn check_initial_admissible(c: &ContactModel, mesh: &Mesh, u0: &[f64]) -> Result<()> {
    if c.n() == 0 {
        return Err(Error::scene(
            "boundary.contact",
            "the contact sides have no node off the clamped sides (Γ̄3 \\ Γ̄1 is empty)",
        ));
    }
    let Some(g) = c.constraint else { return Ok(()) };
    let d0 = c.penetration(u0);
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
    Ok(())
}

fn build_mesh(domain: &Domain, scene_dir: &Path) -> Result<Mesh> {
    let mesh = match domain {
        Domain::Rectangle { size, cells } => Mesh::rectangle(size[0], size[1], cells[0], cells[1]),
        Domain::Gmsh { file } => {
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

/// The contact model of the contact sides: nodes, normals, weights, gap, and the laws the
/// contact section switches on.
fn build_contact(c: &ContactParams, sides: &[String], mesh: &Mesh, dofs: &Dofs, clamped: &[bool]) -> Result<ContactModel> {
    let side = mesh.side_nodes(sides, clamped)?;
    let mut gap = Vec::with_capacity(side.nodes.len());
    for &v in &side.nodes {
        let p = mesh.nodes[v];
        let g = c.gap.eval(p[0], p[1], 0.0);
        if !g.is_finite() {
            return Err(Error::scene("contact.gap", format!("evaluates to {g} at node {v} ({}, {})", p[0], p[1])));
        }
        gap.push(g);
    }
    let compliance = NormalLaw::compliance(c.compliance);
    let (normal, constraint) = match (c.enforcement, c.bound) {
        (Enforcement::Exact, Bound::Finite(g)) => (compliance.clone(), Some(g)),
        (Enforcement::Exact, Bound::Infinite) => (compliance.clone(), None),
        (Enforcement::Penalty { epsilon }, Bound::Finite(g)) => (NormalLaw::penalized(c.compliance, g, epsilon), None),
        // validation refuses the penalty without a finite bound
        (Enforcement::Penalty { .. }, Bound::Infinite) => {
            return Err(Error::scene("contact.enforcement", "penalty needs a finite penetration_bound"));
        }
    };
    let cap = match (c.friction_bound, c.bound) {
        (FrictionBound::Capped, Bound::Finite(g)) => Some(g),
        _ => None,
    };
    let p_tau = FrictionBoundLaw { compliance: compliance.clone(), cap };
    // μ ≡ 0 is frictionless (validation warns); a compliance bound with p ≡ 0 is refused by
    // validation, and would be frictionless too
    let zero_bound = c.friction_bound != FrictionBound::Total && p_tau.compliance.is_zero();
    let friction = c.friction.clone().filter(|mu| !(zero_bound || (mu.is_constant() && mu.mu(0.0) == 0.0)));
    // contact nodes are off Γ̄1 (side_nodes excludes clamped nodes), so both DOFs are free
    let mut node_dofs = Vec::with_capacity(side.nodes.len());
    for &v in &side.nodes {
        match (dofs.map[2 * v], dofs.map[2 * v + 1]) {
            (Some(dx), Some(dy)) => node_dofs.extend([dx, dy]),
            _ => return Err(Error::scene("boundary.contact", format!("contact node {v} has a clamped DOF"))),
        }
    }
    Ok(ContactModel::new(side, gap, node_dofs, normal, compliance, constraint, c.bound, c.enforcement, friction, (c.friction_bound, c.friction_bound_at), p_tau))
}
