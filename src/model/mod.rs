//! The model of spec/model.md §1–§2: material (P.1), contact laws (P.5, P.6, P.8, Pe.5), the
//! contact model a scene switches on, the expression strings of loads and data, and
//! [`Model`], the typed scene that validation produces once and everything downstream reads.

pub mod contact;
pub mod expr;
pub mod kinds;
pub mod laws;
pub mod material;

use expr::{Expr, VecExpr};
use kinds::{
    Bound, BoundAt, ContactSolve, EnergyResidualAction, FixedPointAcceleration, FixedPointStart, FrictionBound,
    InnerSolver, MassKind, Plane, SchemeKind,
};
use laws::FrictionCoefficient;

/// A validated scene: every range checked, every expression parsed, every law built. It is
/// produced by `Scene::validate` (the one place where scene values are checked) and is all
/// `Problem::new` reads; nothing downstream re-parses or re-defaults a scene value.
#[derive(Debug, Clone)]
pub struct Model {
    pub name: String,
    pub description: String,
    pub domain: Domain,
    /// the space dimension d (2 or 3)
    pub dim: usize,
    /// the plane reduction as the scene gave it (2-D only: refused for a 3-D mesh; None: strain)
    pub plane: Option<Plane>,
    /// Γ1: clamped sides
    pub dirichlet: Vec<String>,
    /// Γ3: contact sides (empty: no contact)
    pub contact_sides: Vec<String>,
    pub material: MaterialParams,
    pub loads: Loads,
    /// (P.7) u0 and v0 as fields in x, y
    pub initial: Initial,
    /// None when the scene has no contact side
    pub contact: Option<ContactParams>,
    pub time: TimeParams,
    pub solver: SolverParams,
    /// a frame every `output_every` steps (0: no frames)
    pub output_every: usize,
    /// write trajectory.f64 (u, v at every step)
    pub output_trajectory: bool,
    /// where the model switched on is less than the scene states (or a choice has no effect):
    /// printed by `check` and `run`, stored in summary.json
    pub warnings: Vec<String>,
}

/// The body's geometry.
#[derive(Debug, Clone, PartialEq)]
pub enum Domain {
    /// [0, Lx] × [0, Ly] cut into nx × ny cells of two triangles
    Rectangle { size: [f64; 2], cells: [usize; 2] },
    /// [0, Lx] × [0, Ly] × [0, Lz] cut into nx × ny × nz cells of six tetrahedra
    Box { size: [f64; 3], cells: [usize; 3] },
    /// a Gmsh file, the path as written in the scene (relative to the scene's folder)
    Gmsh { file: String },
}

impl Domain {
    /// The mesh file a `gmsh` domain reads (a relative path resolved against `scene_dir`).
    pub fn mesh_path(&self, scene_dir: &std::path::Path) -> Option<std::path::PathBuf> {
        match self {
            Domain::Gmsh { file } => {
                Some(if std::path::Path::new(file).is_absolute() { file.into() } else { scene_dir.join(file) })
            }
            _ => None,
        }
    }

    /// The mesh file of a Gmsh domain, checked to be a file (refused naming `domain.file`
    /// otherwise); None for the structured domains.
    pub fn mesh_file(&self, scene_dir: &std::path::Path) -> crate::error::Result<Option<std::path::PathBuf>> {
        let Some(path) = self.mesh_path(scene_dir) else { return Ok(None) };
        let shown = path.display().to_string();
        if !path.exists() {
            let relative = match self {
                Domain::Gmsh { file } if std::path::Path::new(file).is_relative() => format!(
                    " ({file:?} is read relative to the scene's folder, {:?})",
                    if scene_dir.as_os_str().is_empty() { ".".to_string() } else { scene_dir.display().to_string() }
                ),
                _ => String::new(),
            };
            return Err(crate::error::Error::scene(
                "domain.file",
                format!("mesh file {shown:?} does not exist{relative}"),
            ));
        }
        if !path.is_file() {
            return Err(crate::error::Error::scene(
                "domain.file",
                format!("{shown:?} is a folder, not a Gmsh .msh file"),
            ));
        }
        Ok(Some(path))
    }
}

/// Material constants as the scene gives them (SI).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MaterialParams {
    pub density: f64,
    pub young: f64,
    pub poisson: f64,
    /// A ε = θ tr(ε) I + 2ζ ε
    pub theta: f64,
    pub zeta: f64,
}

/// A traction f2 on one Γ2 side.
#[derive(Debug, Clone)]
pub struct Traction {
    pub side: String,
    pub value: VecExpr,
    /// the scene key path of `value`, for messages (`loads.traction[0].value`)
    pub path: String,
}

/// Loads as parsed expressions in x, y, t.
#[derive(Debug, Clone)]
pub struct Loads {
    /// f0
    pub body: VecExpr,
    /// f2, one per Γ2 side
    pub traction: Vec<Traction>,
    /// f3 on every contact side (manufactured solutions with contact); None when zero
    pub contact_surface: Option<VecExpr>,
}

/// (P.7) Initial displacement and velocity as fields in x, y.
#[derive(Debug, Clone)]
pub struct Initial {
    pub displacement: VecExpr,
    pub velocity: VecExpr,
}

/// How the penetration bound is enforced.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Enforcement {
    /// Problem P: the constraint d ≤ g with multipliers
    Exact,
    /// Problem P_ε: the penalty (r − g)_+/ε added to p (Pe.5)
    Penalty { epsilon: f64 },
}

/// The contact section, typed.
#[derive(Debug, Clone)]
pub struct ContactParams {
    /// gap(x, y); the laws see d = u·ν − gap
    pub gap: Expr,
    /// c_ν of p(r) = c_ν r_+
    pub compliance: f64,
    pub bound: Bound,
    pub enforcement: Enforcement,
    pub friction_bound: FrictionBound,
    /// where the normal part of a compliance bound is taken
    pub friction_bound_at: BoundAt,
    /// None: frictionless (`law = "none"`)
    pub friction: Option<FrictionCoefficient>,
}

/// The time grid and scheme.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeParams {
    pub end: f64,
    /// k
    pub step: f64,
    /// N = T/k (a whole number, checked)
    pub steps: usize,
    pub scheme: SchemeKind,
}

/// Solver choices and tolerances.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverParams {
    pub inner: InnerSolver,
    pub mass: MassKind,
    pub newton_tolerance: f64,
    pub fixed_point_tolerance: f64,
    pub max_newton_iterations: usize,
    pub max_fixed_point_iterations: usize,
    /// θ of (F.1)
    pub relaxation: f64,
    /// (R.2) velocity-level persistency
    pub persistency: bool,
    /// dense or sparse Delassus operator (auto: from the sizes)
    pub contact_solve: ContactSolve,
    /// Anderson extrapolation of S in (F.1), or the plain iteration
    pub fixed_point_acceleration: FixedPointAcceleration,
    /// where (F.1) starts: the predictor's S, or the unfrozen Newton's root (auto: where (C.k) or
    /// (Ck.1) shows the step problem convex)
    pub fixed_point_start: FixedPointStart,
    /// the (E.1) guard of a midpoint run: the largest relative residual of a step, and what a
    /// step beyond it does
    pub energy_residual_limit: f64,
    pub energy_residual_action: EnergyResidualAction,
}
