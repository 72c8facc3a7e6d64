//! Model → discrete problem: the mesh with Γ1, Γ2, Γ3, the material, the loads, the initial
//! data (S.0) and the contact model. Everything the time loop needs, checked once.
//!
//! A `Problem` is built only from a validated [`Model`] (see `Scene::validate`); the
//! mesh-dependent checks (side names, the clamped set, u^0 ∈ K^h) are made here.

use std::path::Path;

use crate::defaults;
use crate::error::{Error, Result};
use crate::fem::assemble::nodal_masses;
use crate::fem::{Dofs, LoadVector};
use crate::mesh::solid::SolidMesh;
use crate::mesh::{self, Geometry, PlaneMesh};
use crate::model::contact::ContactModel;
use crate::model::expr::VecExpr;
use crate::model::kinds::{Bound, FrictionBound, SchemeKind};
use crate::model::laws::{FrictionBoundLaw, NormalLaw};
use crate::model::material::Material;
use crate::model::{ContactParams, Domain, Enforcement, Model};
use crate::scene::Scene;
use crate::scheme::ContactKinematics;

/// The discrete problem of one scene.
pub struct Problem {
    /// the validated scene this problem was built from
    pub model: Model,
    pub mesh: Geometry,
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
    /// the fingerprint of everything the run reads: the model and the mesh file's bytes
    pub inputs_fingerprint: String,
}

impl Problem {
    /// Validate a scene and build its problem; `scene_dir` resolves a relative Gmsh path.
    pub fn from_scene(scene: &Scene, scene_dir: &Path) -> Result<Problem> {
        Problem::new(scene.validate()?, scene_dir)
    }

    /// Build from a validated model; `scene_dir` resolves a relative Gmsh path.
    pub fn new(mut model: Model, scene_dir: &Path) -> Result<Problem> {
        let mesh = build_mesh(&model.domain, scene_dir)?;
        // of the model as validated (before the mesh sets its dimension), as a sweep computes it
        let inputs_fingerprint = crate::fingerprint::inputs(&model, scene_dir)?;
        match_dimension(&mut model, &mesh)?;
        check_sides(&model, &mesh)?;
        let material = Material::new(&model.material, model.plane.unwrap_or_default());
        let clamped = mesh.nodes_on(&model.dirichlet)?;
        let dofs = Dofs::with_dim(mesh.n_nodes(), &clamped, mesh.dim());
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
        Ok(Problem { model, mesh, material, dofs, loads, u0, v0, contact, k, steps, inputs_fingerprint })
    }

    /// The time of step n, t_n = n k ([`step_time`]).
    pub fn time(&self, n: usize) -> f64 {
        step_time(n, self.k)
    }

    /// The time at which the step from t_n samples the load: f^{n+½} = f(t_n + k/2) (decision
    /// 7), or f(t_{n+1}) for backward Euler — the time of step n + 1 as the run writes it.
    pub fn load_time(&self, n: usize) -> f64 {
        match self.model.time.scheme {
            SchemeKind::BackwardEuler => self.time(n + 1),
            _ => self.time(n) + 0.5 * self.k,
        }
    }

    /// Every time-dependent load is finite at every time the run samples it: (S.2)'s
    /// f^{n+½} = f(t_n + k/2) (f(t_{n+1}) for backward Euler), n = 0 … N − 1, at every
    /// quadrature point — when that takes at most [`defaults::CHECK_LOAD_EVALUATIONS`]
    /// evaluations. [`Problem::new`] checks t = 0 and t = T only; a load like 1/(t − 0.00075)
    /// is finite there and at every t_n of k = 5e-4, and infinite at the load time of step 1.
    pub fn check_load_times(&self) -> Result<LoadScan> {
        let budget = defaults::CHECK_LOAD_EVALUATIONS;
        if self.loads.is_constant() {
            return Ok(LoadScan::Constant);
        }
        // a time costs ~10 evaluations besides its points (t_n's decimal: a format and a parse)
        let evaluations = self.loads.scan_cost(self.steps).saturating_add(10 * self.steps);
        if evaluations > budget {
            return Ok(LoadScan::TooCostly { evaluations });
        }
        self.loads.check_finite_at((0..self.steps).map(|n| self.load_time(n)))?;
        Ok(LoadScan::Scanned { times: self.steps })
    }

    /// (C.k) for this problem: the largest step for which the unfrozen step problem is convex,
    /// k ≤ m_i/(a_v ω_i p̄_τ L_μ) over the contact nodes ([`ContactModel::convex_step_limit`] with
    /// the nodal masses of the scene's mass matrix and the scheme's slip-rate factor a_v), or why
    /// no step bounds it. The argument needs M ⪰ diag(m_i): the lumped (or modified) masses
    /// themselves, and for the consistent mass the lumped ones over d + 2 (a P1 element's
    /// consistent mass is ρ|T|/((d+1)(d+2)) (I + 11ᵀ) ⪰ its lumped mass ρ|T|/(d+1) over d + 2).
    pub fn convexity_limit(&self) -> ConvexityLimit {
        let Some(c) = self.contact.as_ref().filter(|c| c.friction.is_some()) else {
            return ConvexityLimit::NoFriction;
        };
        let mut masses =
            nodal_masses(&self.mesh, &self.material, self.model.solver.mass, &self.dofs, &c.nodes).unwrap_or_default();
        if self.model.solver.mass == crate::model::kinds::MassKind::Consistent {
            let below = (c.dim + 2) as f64;
            masses.iter_mut().for_each(|m| *m /= below);
        }
        let a_v = ContactKinematics::of(self.model.time.scheme, self.k).a_v;
        let limit = if masses.is_empty() { None } else { c.convex_step_limit(&masses, a_v) };
        if let Some((k, i)) = limit {
            ConvexityLimit::Step { k, node: c.nodes[i] }
        } else if c.friction_bound == FrictionBound::Total {
            ConvexityLimit::TotalBound
        } else if !c.p_tau.sup().is_finite() && c.friction.as_ref().is_some_and(|m| m.lipschitz() > 0.0) {
            ConvexityLimit::Unbounded
        } else {
            ConvexityLimit::Convex
        }
    }
}

/// (C.k) for a problem: the step size up to which the unfrozen step problem is convex, or why no
/// step size bounds it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ConvexityLimit {
    /// no contact or no friction: every step problem is convex
    NoFriction,
    /// convex for steps up to `k`, limited at mesh node `node`; k = 0 when the mass matrix puts
    /// no mass on a contact node (the modified mass): then no step is admissible
    Step { k: f64, node: usize },
    /// the total bound follows the contact force, which no constant bounds: no limit
    TotalBound,
    /// p_τ is unbounded (g = inf or uncapped) and μ varies: no step size makes every state's
    /// step problem convex
    Unbounded,
    /// μ is constant or p_τ ≡ 0: every step problem is convex
    Convex,
}

/// A Gmsh mesh decides the dimension: a scene whose vectors are all zero (or absent) takes the
/// mesh's, one that gives d-component vectors must match it.
fn match_dimension(model: &mut Model, mesh: &Geometry) -> Result<()> {
    let d = mesh.dim();
    if d == 3 && model.plane.is_some() {
        return Err(Error::scene(
            "domain.plane",
            format!(
                "is a 2-D key (plane strain or stress); the mesh is three-dimensional ({} tetrahedra): remove it",
                mesh.n_cells()
            ),
        ));
    }
    if model.dim == d {
        return Ok(());
    }
    let l = &model.loads;
    let all_zero = l.body.is_zero()
        && l.contact_surface.as_ref().is_none_or(VecExpr::is_zero)
        && l.traction.iter().all(|t| t.value.is_zero())
        && model.initial.displacement.is_zero()
        && model.initial.velocity.is_zero();
    if !all_zero {
        return Err(Error::scene(
            "domain.file",
            format!(
                "the mesh is {d}-D ({} {}) but the scene's vectors (loads, initial data) have {} components",
                mesh.n_cells(),
                if d == 3 { "tetrahedra" } else { "triangles" },
                model.dim
            ),
        ));
    }
    model.dim = d;
    model.loads.body = VecExpr::zero(d);
    model.loads.contact_surface = None;
    for t in &mut model.loads.traction {
        t.value = VecExpr::zero(d);
    }
    model.initial.displacement = VecExpr::zero(d);
    model.initial.velocity = VecExpr::zero(d);
    Ok(())
}

/// Every side the model names exists on the mesh.
fn check_sides(model: &Model, mesh: &Geometry) -> Result<()> {
    let names = mesh.side_list();
    let side_err = |key: String, s: &str| Error::scene(key, format!("no side named {s:?}; the mesh has {names}"));
    for (i, s) in model.dirichlet.iter().enumerate() {
        if !mesh.has_side(s) {
            return Err(side_err(format!("boundary.dirichlet[{i}]"), s));
        }
    }
    for (i, s) in model.contact_sides.iter().enumerate() {
        if !mesh.has_side(s) {
            return Err(side_err(format!("boundary.contact[{i}]"), s));
        }
    }
    for (i, tr) in model.loads.traction.iter().enumerate() {
        if !mesh.has_side(&tr.side) {
            return Err(side_err(format!("loads.traction[{i}].side"), &tr.side));
        }
    }
    Ok(())
}

/// What [`Problem::check_load_times`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LoadScan {
    /// no load depends on t: checked at t = 0 by [`Problem::new`]
    Constant,
    /// every load time of the run checked: finite
    Scanned { times: usize },
    /// not scanned: it would take this many evaluations, more than the budget
    TooCostly { evaluations: usize },
}

impl LoadScan {
    /// The line `check` prints for it (none for constant loads).
    pub fn line(&self) -> Option<String> {
        match *self {
            LoadScan::Scanned { times: 1 } => Some("loads          : finite at the time the step samples them".into()),
            LoadScan::Scanned { times } => {
                Some(format!("loads          : finite at each of the {times} times the steps sample them"))
            }
            _ => None,
        }
    }

    /// The warning `check` gives when it did not scan.
    pub fn warning(&self) -> Option<String> {
        match *self {
            LoadScan::TooCostly { evaluations } => Some(format!(
                "the time-dependent loads were checked at t = 0 and t = T only: every load time would take \
                 {evaluations} evaluations (more than {}); `run` stops at the first step whose load is not finite",
                defaults::CHECK_LOAD_EVALUATIONS
            )),
            _ => None,
        }
    }
}

/// t_n = n k as the run writes and samples it: the product n·k in f64, or the 15-digit decimal
/// nearest to it when that decimal is within 4 units in the last place. For a step given as a
/// short decimal (k = 1e-3) the product is within 2 units of n times that decimal, so step 700
/// is t = 0.7 (the decimal the scene means) and not 0.7000000000000001; for any other k (1/3 as
/// 0.3333333333333333) the product stays, and t_n moves from n·k by at most 4 units either way.
pub fn step_time(n: usize, k: f64) -> f64 {
    let t = n as f64 * k;
    if t == 0.0 || !t.is_finite() {
        return t;
    }
    let ulp = f64::from_bits(t.to_bits() + 1) - t;
    match format!("{t:.14e}").parse::<f64>() {
        Ok(short) if short.is_finite() && (short - t).abs() <= 4.0 * ulp => short,
        _ => t,
    }
}

/// f(t): the body load f0, the tractions f2 and the known load f3 on Γ3 (every contact side;
/// for manufactured solutions with contact), checked finite at t = 0 and t = T.
pub fn build_loads(model: &Model, mesh: &Geometry, dofs: &Dofs) -> Result<LoadVector> {
    let loads = match mesh {
        Geometry::Plane(m) => LoadVector::new(
            m,
            dofs,
            &model.loads.body,
            &surface_loads(model, |side| m.side(side).map(|s| s.facets.clone()).unwrap_or_default()),
        ),
        Geometry::Solid(m) => LoadVector::solid(
            m,
            dofs,
            &model.loads.body,
            &surface_loads(model, |side| m.side(side).map(|s| s.facets.clone()).unwrap_or_default()),
        ),
    };
    loads.check_finite(0.0)?;
    loads.check_finite(model.time.end)?;
    Ok(loads)
}

/// The loaded sides' facets with their load and key path: the tractions f2, and f3 on every
/// contact side.
fn surface_loads<F: Clone>(model: &Model, facets_of: impl Fn(&str) -> Vec<F>) -> Vec<(Vec<F>, VecExpr, String)> {
    let mut surface: Vec<(Vec<F>, VecExpr, String)> =
        model.loads.traction.iter().map(|tr| (facets_of(&tr.side), tr.value.clone(), tr.path.clone())).collect();
    if let Some(f3) = &model.loads.contact_surface {
        for side in &model.contact_sides {
            surface.push((facets_of(side), f3.clone(), "loads.contact_surface".into()));
        }
    }
    surface
}

/// (S.0) u^0 ∈ K^h: the initial state does not penetrate beyond the bound g.
fn check_initial_admissible(c: &ContactModel, mesh: &Geometry, u0: &[f64]) -> Result<()> {
    if c.n() == 0 {
        return Err(Error::scene(
            "boundary.contact",
            "the contact sides have no node off the clamped sides (Γ̄3 \\ Γ̄1 is empty)",
        ));
    }
    let Some(g) = c.constraint else { return Ok(()) };
    let d0 = c.penetration(u0);
    if let Some(i) = (0..c.n()).find(|&i| d0[i] > g * (1.0 + 1e-12) + 1e-300) {
        return Err(Error::scene(
            "initial.displacement",
            format!(
                "the initial state penetrates beyond the bound: u_ν − gap = {:.6e} > g = {g} at {} {}; \
                 u0 must satisfy the constraint (S.0)",
                d0[i],
                mesh.node_name(c.nodes[i]),
                at(mesh, c.nodes[i])
            ),
        ));
    }
    Ok(())
}

/// Node v's coordinates for messages: "(x, y)" or "(x, y, z)".
fn at(mesh: &Geometry, v: usize) -> String {
    let p = mesh.point(v);
    if mesh.dim() == 3 { format!("({}, {}, {})", p[0], p[1], p[2]) } else { format!("({}, {})", p[0], p[1]) }
}

pub(crate) fn build_mesh(domain: &Domain, scene_dir: &Path) -> Result<Geometry> {
    let mesh = match domain {
        Domain::Rectangle { size, cells } => {
            Geometry::Plane(PlaneMesh::rectangle(size[0], size[1], cells[0], cells[1]))
        }
        Domain::Box { size, cells } => Geometry::Solid(SolidMesh::cuboid(*size, *cells)),
        Domain::Gmsh { .. } => {
            let path = domain.mesh_file(scene_dir)?.unwrap_or_default();
            mesh::gmsh::read_any(&path)?
        }
    };
    mesh.check()?;
    Ok(mesh)
}

/// (S.0) Discrete initial data u^0 = I_h u0, v^0 = I_h v0 (nodal interpolation; zero on Γ̄1).
pub fn initial_data(mesh: &Geometry, dofs: &Dofs, u0: &VecExpr, v0: &VecExpr) -> Result<(Vec<f64>, Vec<f64>)> {
    let mut out = Vec::new();
    for (e, path) in [(u0, "initial.displacement"), (v0, "initial.velocity")] {
        let d = mesh.dim();
        for k in 0..mesh.n_nodes() {
            let v = e.eval3(mesh.point(k), 0.0);
            if !v[..d].iter().all(|c| c.is_finite()) {
                let vals = v[..d].iter().map(|c| c.to_string()).collect::<Vec<_>>().join(", ");
                return Err(Error::Expression {
                    path: path.into(),
                    message: format!(
                        "evaluates to ({vals}) at {} {}; initial data must be finite",
                        mesh.node_name(k),
                        at(mesh, k)
                    ),
                });
            }
        }
        out.push(dofs.gather_dim(|k| e.eval3(mesh.point(k), 0.0)));
    }
    let v = out.pop().unwrap_or_default();
    let u = out.pop().unwrap_or_default();
    Ok((u, v))
}

/// The contact model of the contact sides: nodes, normals, weights, gap, and the laws the
/// contact section switches on.
fn build_contact(
    c: &ContactParams,
    sides: &[String],
    mesh: &Geometry,
    dofs: &Dofs,
    clamped: &[bool],
) -> Result<ContactModel> {
    let side = mesh.side_nodes(sides, clamped)?;
    let mut gap = Vec::with_capacity(side.nodes.len());
    for &v in &side.nodes {
        let p = mesh.point(v);
        let g = c.gap.eval3(p[0], p[1], p[2], 0.0);
        if !g.is_finite() {
            return Err(Error::scene(
                "contact.gap",
                format!("evaluates to {g} at {} {}", mesh.node_name(v), at(mesh, v)),
            ));
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

    // contact nodes are off Γ̄1 (side_nodes excludes clamped nodes), so all their DOFs are free
    let d = dofs.dim;
    let mut node_dofs = Vec::with_capacity(d * side.nodes.len());
    for &v in &side.nodes {
        for comp in 0..d {
            match dofs.map[d * v + comp] {
                Some(i) => node_dofs.push(i),
                None => {
                    return Err(Error::scene(
                        "boundary.contact",
                        format!("contact {} has a clamped DOF", mesh.node_name(v)),
                    ));
                }
            }
        }
    }
    Ok(ContactModel::new(
        side,
        d,
        gap,
        node_dofs,
        normal,
        compliance,
        constraint,
        c.bound,
        c.enforcement,
        friction,
        (c.friction_bound, c.friction_bound_at),
        p_tau,
    ))
}
