//! summary.json: what the scene switched on, sizes, timings, iteration counts, the largest
//! (E.1) residual, warnings and the final status.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::failure::{FailureKind, RunStatus};
use crate::model::contact::ContactModel;
use crate::model::kinds::{self, Bound, BoundAt, ContactSolve, FixedPointAcceleration, FrictionBound, InnerSolver};
use crate::model::laws::FrictionCoefficient;
use crate::model::{ContactParams, Enforcement};
use crate::problem::{ConvexityLimit, Problem};
use crate::step::fixed_point::F1Start;

/// How the contact solve's words name F.1's start at the unfrozen Newton's root, and the start
/// that the setup decides by (Ck.1).
const ROOT_START: &str = ", started at the root of the unfrozen Newton (N.4)";
const ROOT_START_IF_SHARP: &str =
    ", started at the root of the unfrozen Newton (N.4) if (Ck.1), the sharp (C.k) through W, holds (tested at setup)";

/// The model a scene switches on — printed by `dyncontact check`, stored in summary.json.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct ModelInfo {
    pub plane: String,
    pub material: String,
    pub contact: String,
    pub normal_law: String,
    pub constraint: String,
    pub friction: String,
    pub friction_bound: String,
    /// the form of the contact solve and how F.1 updates S
    pub contact_solve: String,
    pub scheme: String,
    pub inner_solver: String,
    pub mass: String,
    pub nodes: usize,
    /// the space dimension d
    pub dim: usize,
    pub triangles: usize,
    pub tetrahedra: usize,
    pub velocity_unknowns: usize,
    pub contact_nodes: usize,
    pub multipliers: usize,
    pub friction_unknowns: usize,
    pub steps: usize,
    pub step: f64,
    /// (C.k): the largest k for which the unfrozen step problem is convex, and where
    pub ck_step_limit: Option<f64>,
    pub ck_limiting_node: Option<usize>,
    /// the limiting node for messages: by its tag in the mesh file where there is one
    #[serde(skip)]
    pub ck_limiting_name: String,
    /// why (C.k) gives no limit, when it does not
    pub ck_note: String,
    /// (Ck.1), the sharp form of (C.k) through W, as the run's setup found it: true when every
    /// step problem is strictly convex, false when the test did not show it; null where it did not
    /// run (it runs beyond (C.k) with the bound at the predictor and a dense W; `check` never
    /// builds W)
    #[serde(default)]
    pub ck_sharp: Option<bool>,
    /// whether (Ck.1) applies to the scene at all (the bound at the predictor, not the total
    /// bound), so that a run's setup tests it where W is dense
    #[serde(skip)]
    pub ck_sharp_applies: bool,
    /// the unit of every numeric column of history.csv and contact.csv (forces and energies per
    /// unit thickness in 2-D, absolute in 3-D); absent from summaries written before it
    #[serde(default)]
    pub units: super::units::Units,
    /// where the model switched on is less than the scene states (from validation)
    #[serde(skip)]
    pub scene_warnings: Vec<String>,
}

impl ModelInfo {
    pub fn of(p: &Problem) -> ModelInfo {
        let s = &p.model;
        let m = &s.material;
        let material = if m.theta > 0.0 || m.zeta > 0.0 {
            format!(
                "Kelvin–Voigt: E = {}, ν = {}, ρ = {}, θ = {}, ζ = {}",
                m.young, m.poisson, m.density, m.theta, m.zeta
            )
        } else {
            format!("elastic (no viscosity): E = {}, ν = {}, ρ = {}", m.young, m.poisson, m.density)
        };
        let material = match (&p.material.thickness, &p.material.plane) {
            (Some(_), _) => {
                format!("{material}; plane stress with ε_zz an internal variable per triangle (θ/ζ ≠ λ/μ: Ps.1)")
            }
            (None, kinds::Plane::Stress) if s.dim == 2 => {
                format!("{material}; plane stress with ε_zz eliminated (reduced λ*, θ*)")
            }
            _ => material,
        };
        let mut info = ModelInfo {
            plane: if s.dim == 3 { "-".into() } else { kinds::name(&s.plane.unwrap_or_default()) },
            material,
            contact: "none (no contact side): one linear solve per step".into(),
            normal_law: "-".into(),
            constraint: "-".into(),
            friction: "-".into(),
            friction_bound: "-".into(),
            contact_solve: "-".into(),
            scheme: kinds::name(&s.time.scheme),
            inner_solver: kinds::name(&s.solver.inner),
            mass: kinds::name(&s.solver.mass),
            dim: p.mesh.dim(),
            nodes: p.mesh.n_nodes(),
            triangles: p.mesh.plane().map_or(0, |m| m.cells.len()),
            tetrahedra: p.mesh.solid().map_or(0, |m| m.cells.len()),
            velocity_unknowns: p.dofs.n_free,
            contact_nodes: 0,
            multipliers: 0,
            friction_unknowns: 0,
            steps: p.steps,
            step: p.k,
            ck_step_limit: None,
            ck_limiting_node: None,
            ck_limiting_name: String::new(),
            ck_note: "no velocity-dependent friction: every step problem is convex".into(),
            ck_sharp: None,
            ck_sharp_applies: false,
            units: super::units::Units::of(p.mesh.dim()),
            scene_warnings: s.warnings.clone(),
        };
        if let (Some(c), Some(cs)) = (&p.contact, &s.contact) {
            info.describe_contact(p, c, cs);
        }
        info
    }

    /// The contact lines: sides, normal law, constraint, friction and its bound.
    fn describe_contact(&mut self, p: &Problem, c: &ContactModel, cs: &ContactParams) {
        self.contact = format!("on sides {}: {} contact nodes", p.model.contact_sides.join(", "), c.n());
        let m = c.dim * c.n();
        let form = match p.model.solver.contact_solve {
            ContactSolve::Dense => format!("dense Delassus operator W ({m} × {m})"),
            ContactSolve::Sparse => format!(
                "sparse Delassus operator W ({m} × {m}, probed, entries below {:e} of the diagonal dropped)",
                crate::defaults::DELASSUS_TRUNCATION
            ),
            ContactSolve::Auto if m < crate::defaults::SPARSE_FROM => {
                format!("dense Delassus operator W ({m} × {m}; auto: below {} unknowns)", crate::defaults::SPARSE_FROM)
            }
            ContactSolve::Auto => format!(
                "auto: W ({m} × {m}) probed at setup, sparse if its decay keeps ≤ {}% of the entries, else dense (summary.json says which)",
                100.0 * crate::defaults::SPARSE_DENSITY
            ),
        };
        let update = match p.model.solver.fixed_point_acceleration {
            FixedPointAcceleration::Anderson => "F.1 with Anderson extrapolation of S",
            FixedPointAcceleration::None => "plain F.1",
        };
        let update = match crate::simulation::f1_start(p, &p.model.solver) {
            F1Start::Predictor => update.to_string(),
            F1Start::Root => format!("{update}{ROOT_START}"),
            F1Start::RootIfSharpConvex => format!("{update}{ROOT_START_IF_SHARP}"),
        };
        self.contact_solve = format!("{form}; {update}");
        self.contact_nodes = c.n();
        self.normal_law = if cs.compliance > 0.0 {
            format!("normal compliance p(r) = {} r_+", cs.compliance)
        } else {
            "no compliance (p ≡ 0)".into()
        };
        let g_finite = match cs.bound {
            Bound::Finite(g) => Some(g),
            Bound::Infinite => None,
        };
        self.constraint = match (g_finite, cs.enforcement) {
            (None, _) => "none (g = inf): pure normal compliance, no multipliers".into(),
            (Some(g), Enforcement::Exact) if cs.compliance == 0.0 && g == 0.0 => {
                "Signorini (g = 0, p ≡ 0): exact, one multiplier λ per contact node".into()
            }
            (Some(g), Enforcement::Exact) => {
                format!("u_ν ≤ g = {g}, exact (Problem P): one multiplier λ per contact node")
            }
            (Some(g), Enforcement::Penalty { epsilon }) => {
                format!("penalty (Problem P_ε): p_ε = p + (r − {g})_+/ε with ε = {epsilon}, no multipliers")
            }
        };
        if c.constraint.is_some() {
            self.multipliers = c.n();
        }
        self.friction = match &c.friction {
            None => "none: frictionless, no fixed point".into(),
            Some(mu) => format!("{}: {}", coefficient(mu), step_solves(mu, cs, p.model.solver.inner)),
        };
        if c.friction.is_some() {
            self.friction_unknowns = c.n() * (c.dim - 1);
            let at = match cs.friction_bound_at {
                BoundAt::Predictor => "r at the predictor u_ν^n + (k/2) v_ν^n",
                BoundAt::Midpoint => "r = u_ν^{n+½} of the iterate, updated in the fixed point",
            };
            self.friction_bound = match (cs.friction_bound, g_finite) {
                (FrictionBound::Total, _) => {
                    "μ(‖v̄‖) (q + λ) (total: Coulomb with the whole contact force, fixed point on S)".into()
                }
                (FrictionBound::Capped, Some(g)) => format!("μ(‖v̄‖) p(min(r_+, {g})) (capped), {at}"),
                _ => format!("μ(‖v̄‖) p(r) (uncapped), {at}"),
            };
            self.convexity_limit(p);
        }
    }

    /// What the run's setup found of (Ck.1) (`Simulation::sharp_convexity`) and where it made F.1
    /// start (`start`, resolved): the contact solve's words say where F.1 started and why, and a k
    /// beyond (C.k) that (Ck.1) admits is no longer warned of.
    pub fn set_sharp_convexity(&mut self, found: Option<bool>, start: F1Start) {
        self.ck_sharp = found;
        let words = match (start, found) {
            (F1Start::Root, _) => format!("{ROOT_START}: (Ck.1) holds (W shows every step problem strictly convex)"),
            (_, Some(false)) => ", started at the predictor: (Ck.1) does not hold".to_string(),
            _ => ", started at the predictor: (Ck.1) not tested (it needs the dense W)".to_string(),
        };
        self.contact_solve = self.contact_solve.replace(ROOT_START_IF_SHARP, &words);
    }

    /// (C.k) for the scene, as the problem states it: the step limit and the limiting node, or
    /// why there is none.
    fn convexity_limit(&mut self, p: &Problem) {
        self.ck_note = match p.convexity_limit() {
            ConvexityLimit::NoFriction => return,
            ConvexityLimit::Step { k, node } => {
                self.ck_step_limit = Some(k);
                self.ck_limiting_node = Some(node);
                // a step limit means friction with the capped or uncapped bound, never the total one
                self.ck_sharp_applies = p.contact.as_ref().is_some_and(|c| c.bound_at == BoundAt::Predictor);
                self.ck_limiting_name = p.mesh.node_name(node);
                if k == 0.0 {
                    "the modified mass puts zero mass on the contact nodes: the inertia no longer convexifies the \
                     friction term, so (C.k) admits no step; F.1 still applies"
                        .into()
                } else {
                    String::new()
                }
            }
            ConvexityLimit::TotalBound => {
                "the total bound follows the contact force, which no constant bounds: (C.k) gives no limit; F.1 \
                            iterates on S"
                    .into()
            }
            ConvexityLimit::Unbounded => {
                "p_τ is unbounded (g = inf or uncapped): no step size makes the step problem convex for every \
                            state; F.1 still applies (a majorization–minimization for velocity-weakening μ)"
                    .into()
            }
            ConvexityLimit::Convex => "μ is constant or p_τ ≡ 0: every step problem is convex".into(),
        };
    }

    /// Human-readable lines for `dyncontact check`.
    pub fn lines(&self) -> Vec<String> {
        let mut v = vec![
            if self.dim == 3 {
                "dimension      : 3 (P1 tetrahedra)".to_string()
            } else {
                format!("dimension      : 2 (P1 triangles), plane {}", self.plane)
            },
            format!("material       : {}", self.material),
            format!("contact        : {}", self.contact),
            format!("normal law     : {}", self.normal_law),
            format!("constraint     : {}", self.constraint),
            format!("friction       : {}", self.friction),
            format!("friction bound : {}", self.friction_bound),
            format!("contact solve  : {}", self.contact_solve),
            format!("scheme         : {}, inner solver {}, {} mass", self.scheme, self.inner_solver, self.mass),
            format!(
                "sizes          : {} nodes, {}, {} velocity unknowns, {} contact nodes, {} multipliers, {} friction unknowns",
                self.nodes,
                if self.dim == 3 {
                    format!("{} tetrahedra", self.tetrahedra)
                } else {
                    format!("{} triangles", self.triangles)
                },
                self.velocity_unknowns,
                self.contact_nodes,
                self.multipliers,
                self.friction_unknowns
            ),
            format!("time           : {} steps of k = {}", self.steps, self.step),
        ];
        match self.ck_step_limit {
            Some(0.0) => v.push(format!("(C.k)          : no admissible step — {}", self.ck_note)),
            Some(k) => v.push(format!(
                "(C.k)          : the unfrozen step problem is convex for k <= {k:.4e} (limited at {})",
                self.ck_limiting_name
            )),
            None => v.push(format!("(C.k)          : no limit — {}", self.ck_note)),
        }
        v
    }

    /// Every warning about the scene's setup: (C.k), and the conic twin's cost on large contact
    /// sets (its dense KKT systems grow like n_c^3.6: 0.5 s per step at 65 contact nodes, 6 s at
    /// 129, measured in the dev profile).
    pub fn warnings(&self) -> Vec<String> {
        let mut w: Vec<String> = self.scene_warnings.clone();
        w.extend(self.ck_warning());
        if self.inner_solver == "conic" && self.contact_nodes > 64 {
            w.push(format!(
                "solver.inner = \"conic\" with {} contact nodes: the conic twin is a cross-check and its cost grows like \
                 n_c^3.6 (seconds per step beyond ~100 nodes); use \"newton\" for production runs",
                self.contact_nodes
            ));
        }
        w
    }

    /// The (C.k) warning, if time.step exceeds the limit.
    pub fn ck_warning(&self) -> Option<String> {
        let k = self.ck_step_limit?;
        if k == 0.0 {
            return (self.ck_sharp != Some(true)).then(|| format!("(C.k): {}", self.ck_note));
        }
        let sharp_pending = self.ck_sharp.is_none() && self.ck_sharp_applies;
        (self.step > k && self.ck_sharp != Some(true)).then(|| {
            format!(
                "time.step = {} exceeds the (C.k) limit {k:.4e} ({}), a sufficient condition for a convex step \
                 problem: F.1 may need more convex solves per step (relaxation < 1 does not help); steps that reach \
                 its cap are counted in summary.json, and a step whose Newton fails stops the run with its residuals{}",
                self.step,
                self.ck_limiting_name,
                if sharp_pending {
                    "; a run with a dense W tests the sharper (Ck.1) at setup, and where it holds this warning goes"
                } else {
                    ""
                }
            )
        })
    }
}

/// The friction coefficient in words.
fn coefficient(mu: &FrictionCoefficient) -> String {
    match mu {
        FrictionCoefficient::Constant(mu) => format!("constant μ = {mu}"),
        FrictionCoefficient::Exponential { a, b, alpha } => format!("μ(r) = ({a} − {b}) e^(−{alpha} r) + {b}"),
        FrictionCoefficient::Table(pts) => format!("table with {} points", pts.len()),
    }
}

/// What a step solves under the friction coefficient `mu`, the bound of `cs` and the inner
/// solver: one convex solve only where S is known before the solve (μ constant, its normal part
/// at the predictor); else the fixed point on S (F.1), where S follows the slip rate (μ not
/// constant), the iterate's midpoint u_ν^{n+½} or the whole contact force q + λ (the total
/// bound) — or Newton on the unfrozen problem with F.1 as its fallback (`newton-unfrozen`).
fn step_solves(mu: &FrictionCoefficient, cs: &ContactParams, inner: InnerSolver) -> String {
    let unfrozen = inner == InnerSolver::NewtonUnfrozen;
    match (cs.friction_bound, cs.friction_bound_at) {
        (FrictionBound::Total, _) if unfrozen => {
            "S = μ (q + λ) follows the contact force: Newton on the coupled Coulomb problem (Co.3), fixed point on S \
             (F.1) as its fallback"
                .into()
        }
        (FrictionBound::Total, _) => {
            "S = μ (q + λ) follows the contact force: fixed point on S (F.1), a convex solve per iteration".into()
        }
        (_, BoundAt::Midpoint) => {
            "S follows u_ν^{n+½} of the iterate: fixed point on S (F.1), a convex solve per iteration".into()
        }
        _ if mu.is_constant() => "S known at the predictor: one convex solve per step".into(),
        _ if unfrozen => "Newton on the unfrozen problem (N.4), fixed point on S (F.1) as its fallback".into(),
        _ => "S follows the slip rate: fixed point on S (F.1), a convex solve per iteration".into(),
    }
}

/// Wall-clock split of a run in seconds.
#[derive(Debug, Clone, Copy, Default, Serialize, Deserialize)]
pub struct Timing {
    pub setup_s: f64,
    pub assembly_s: f64,
    pub factorization_s: f64,
    pub delassus_s: f64,
    /// (Ck.1)'s test through W (0 where it did not run); absent from summaries written before it
    #[serde(default)]
    pub sharp_convexity_s: f64,
    pub free_solve_s: f64,
    pub contact_solve_s: f64,
    pub recovery_s: f64,
    /// K u, K v, C v, M v of each new state (one pass; the next right-hand side reads them)
    pub products_s: f64,
    /// the (E.1) increments, persistency and the contact records
    pub balance_s: f64,
    pub output_s: f64,
    pub total_s: f64,
}

/// summary.json: how a run ended and, for a run that started, what it did. Every summary.json
/// is this type: a run writes it when it takes its folder (`running`) and whenever it ends, and a
/// run that could not start writes [`Summary::failed_start`]. The keys are a public contract
/// (README, "Outputs"): the fields of [`RunDetails`] sit beside these, absent when the run never
/// started.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Summary {
    /// the dyncontact that wrote the folder
    pub version: String,
    pub scene: String,
    /// running (from the start) | completed | failed | interrupted
    pub status: RunStatus,
    pub failure: Option<String>,
    /// the kind of the failure (`Error::kind`: non_finite, solver, linear_algebra, input,
    /// interrupted, folder, output, internal)
    pub failure_kind: Option<FailureKind>,
    pub steps_completed: usize,
    /// what a run that started records (absent from the summary of a run that could not start)
    #[serde(flatten)]
    pub run: Option<RunDetails>,
}

impl Summary {
    /// The summary of a run that could not start (its scene, mesh or operators were refused):
    /// `failed` with the reason and its kind, no step done.
    pub fn failed_start(scene: &str, e: &Error) -> Summary {
        Summary {
            version: env!("CARGO_PKG_VERSION").to_string(),
            scene: scene.to_string(),
            status: RunStatus::Failed,
            failure: Some(e.to_string()),
            failure_kind: Some(e.kind()),
            steps_completed: 0,
            run: None,
        }
    }

    /// The details of a run that started: every summary a run keeps has them (empty ones are
    /// put in a summary that had none).
    pub fn details(&mut self) -> &mut RunDetails {
        self.run.get_or_insert_default()
    }

    /// The wall-clock split of the run (all zero for a run that did not start).
    pub fn timing(&self) -> Timing {
        self.run.as_ref().map(|d| d.timing).unwrap_or_default()
    }

    /// summary.json's text (pretty-printed JSON).
    pub fn to_json(&self) -> Result<String> {
        serde_json::to_string_pretty(self).map_err(|e| Error::Output(format!("summary.json: {e}")))
    }

    /// The summary in the folder `dir`, if it has a summary.json that reads as one.
    pub fn read(dir: &Path) -> Option<Summary> {
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).ok()?).ok()
    }
}

/// What a run that started records in summary.json, beside [`Summary`]'s keys.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct RunDetails {
    pub description: String,
    /// this run's identity: a fresh run makes a new one, a resumed run keeps it, and its
    /// checkpoint carries it (resume refuses a checkpoint of another run)
    pub run_id: String,
    /// the scene file as given (`<embedded academic scene>` for the default scene; a sweep
    /// point's own scene.toml); absent when the run was started from a library call without one
    #[serde(default)]
    pub scene_file: Option<String>,
    /// the `--set` overrides applied to it, in order, as typed
    #[serde(default)]
    pub overrides: Vec<String>,
    /// the effective scene (overrides applied) in the run folder: `scene.toml`, which
    /// `run --resume DIR` reads back
    #[serde(default)]
    pub effective_scene: Option<String>,
    /// the fingerprint of everything the run read: the scene as validated and the bytes of
    /// its mesh file (crate::fingerprint::inputs)
    pub inputs_fingerprint: String,
    pub model: ModelInfo,
    pub final_time: f64,
    pub wall_time_s: f64,
    /// the process's peak resident memory (Linux VmHWM) at the end of the run, in MB; in a
    /// sweep run in one process, shared by the points running at once
    pub peak_memory_mb: Option<f64>,
    pub timing: Timing,
    /// the form of the Delassus operator ("dense" | "sparse" | "none") and, for the sparse form,
    /// its probing facts (radius, colours, solves, density, measured apply error)
    pub contact_solve: String,
    pub contact_solve_sparse: Option<crate::step::delassus::SparseStats>,
    /// Newton matrices W_UU + D factored, and factorizations reused (unchanged sets)
    pub contact_factorizations: usize,
    pub contact_factor_reuses: usize,
    /// Newton systems solved by conjugate gradients preconditioned with a kept factor of a nearby
    /// matrix (3-D slip), and their iterations
    pub contact_pcg_solves: usize,
    pub contact_pcg_iterations: usize,
    /// Newton directions in velocity form (W⁻¹ kept, conjugate gradients on the free
    /// components; dense, well-conditioned W), and their iterations
    pub contact_velocity_solves: usize,
    pub contact_velocity_iterations: usize,
    pub newton_iterations_total: usize,
    pub fixed_point_iterations_total: usize,
    pub fixed_point_iterations_max: usize,
    pub fixed_point_cap_hits: usize,
    /// `newton-unfrozen`, or F.1's root start (`fixed_point_start`): steps where the unfrozen
    /// Newton failed and the fixed point (F.1) took over from the predictor
    pub unfrozen_fallbacks: usize,
    pub max_abs_energy_residual: f64,
    pub max_relative_energy_residual: f64,
    /// steps whose (E.1) residual exceeded `solver.energy_residual_limit` (with
    /// `energy_residual_action = "warn"`; with "fail" the first one ends the run)
    pub energy_guard_exceeded_steps: usize,
    pub warnings: Vec<String>,
}

impl RunDetails {
    /// The contact solve's counts so far (a resumed run's include the checkpoint's).
    pub fn set_contact_counts(&mut self, c: crate::step::delassus::FactorCounts) {
        (self.contact_factorizations, self.contact_factor_reuses) = (c.factorizations, c.reuses);
        (self.contact_pcg_solves, self.contact_pcg_iterations) = (c.pcg_solves, c.pcg_iterations);
        (self.contact_velocity_solves, self.contact_velocity_iterations) = (c.velocity_solves, c.velocity_iterations);
    }
}
