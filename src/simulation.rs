//! The time loop. One step reads as the model's step (spec/model.md §4.2–§4.5):
//! free solve A_k⁻¹ b^n → contact solve on the contact DOFs through the Delassus operator (F.1
//! around the inner solver) → recovery solve → advance (S.1) → balance (E.1).
//!
//! [`Simulation::steps`] is the one loop every caller drives (`run`, the studies, the tests):
//! an iterator of [`StepRecord`]s, in the way scikit-fem's examples `yield` from their time
//! loop.

use std::time::Instant;

use crate::defaults::{CONIC_TOLERANCE_FLOOR, RESPONSES_ADVANTAGE};
use crate::energy::{self, EnergyTerms, StepEnergy};
use crate::error::{Error, Result};
use crate::failure::{ContactFailure, SolverFailure, StepFailureCause};
use crate::fem::Operators;
use crate::fem::thickness::{ThicknessStep, ThicknessStrain};
use crate::linalg;
use crate::model::contact::ContactModel;
use crate::model::kinds::{
    BoundAt, EnergyResidualAction, FixedPointAcceleration, FixedPointStart, FrictionBound, InnerSolver, SchemeKind,
};
use crate::problem::Problem;
use crate::scheme::{ContactKinematics, StateProducts, StepOperator};
use crate::step::conic::ConicSettings;
use crate::step::fixed_point::{self, F1Start, FixedPointSettings, Inner, NormalPart, StepReport};
use crate::step::newton::NewtonSettings;
use crate::step::{ContactSolution, NodeData, NodeStatus, StepData, delassus};

/// (R.2) Velocity-level persistency: on a node that stayed on the constraint (dir = ν) or in
/// stick (dir = τ) over the step, set the end-point velocity component v_c^{n+1} = 0 instead
/// of the −v_c^n that (S.1) gives; returns the kinetic energy removed, ½ m (v_c^{n+1})² ≥ 0
/// (diagonal mass m), which (E.1) books as the persistency dissipation.
pub fn persist_velocity(v_new: &mut [f64], dofs: &[usize], dir: &[f64; 3], m: f64) -> f64 {
    let vc = component(v_new, dofs, dir);
    for (c, &dof) in dofs.iter().enumerate() {
        v_new[dof] -= vc * dir[c];
    }
    0.5 * m * vc * vc
}

/// e · v at a node with DOFs `dofs` (d of them).
fn component(v: &[f64], dofs: &[usize], e: &[f64; 3]) -> f64 {
    let mut s = e[0] * v[dofs[0]];
    for (c, &dof) in dofs.iter().enumerate().skip(1) {
        s += e[c] * v[dof];
    }
    s
}

/// Per-node contact quantities after a step (contact.csv).
#[derive(Debug, Clone, Copy)]
pub struct NodeRecord {
    /// d = u_ν − gap at t_{n+1}
    pub u_n: f64,
    /// u_τ at t_{n+1}
    pub u_t: f64,
    /// the slip rate the law saw (v̄)
    pub v_t: f64,
    /// compliance pressure q
    pub p: f64,
    pub lambda: f64,
    /// −t: friction traction on the body along τ
    pub friction: f64,
    /// the frozen friction bound S used
    pub bound: f64,
    pub status: NodeStatus,
    /// v̄ in global components (along τ in 2-D; in the tangent plane in 3-D)
    pub v_t_vec: [f64; 3],
    /// −t in global components: the friction traction on the body
    pub friction_vec: [f64; 3],
}

/// Wall-clock split of the setup, in seconds.
#[derive(Debug, Clone, Copy, Default)]
pub struct SetupTiming {
    pub assembly: f64,
    /// the factorization of A_k
    pub factorization: f64,
    /// W = H A_k⁻¹ Hᵀ (and W⁻¹ for the velocity form)
    pub delassus: f64,
    /// how W was computed: "solves", "schur", "probed" (`delassus::Built::route`), or "" without contact
    pub delassus_route: &'static str,
    /// (Ck.1)'s test through W (0 where it did not run)
    pub sharp_convexity: f64,
}

/// Wall-clock split of one step, in seconds.
#[derive(Debug, Clone, Copy, Default)]
pub struct StepTiming {
    pub free_solve: f64,
    /// the contact solve, (F.1) included
    pub contact_solve: f64,
    pub recovery: f64,
    /// K u, K v, C v, M v of the new state (read by (E.1) and the next right-hand side)
    pub products: f64,
    /// the (E.1) increments, persistency and the contact records, products excluded
    pub balance: f64,
}

/// One history.csv row plus the nodal contact data.
#[derive(Debug, Clone)]
pub struct StepRecord {
    pub step: usize,
    pub t: f64,
    pub energy: EnergyTerms,
    /// the energy scale (for relative residuals)
    pub energy_scale: f64,
    pub normal_force: f64,
    /// the total friction force on the body along τ (2-D, signed), or its magnitude (3-D)
    pub tangential_force: f64,
    /// −Σ ω_i t_i in global components (z = 0 in 2-D)
    pub friction_force: [f64; 3],
    pub max_penetration: f64,
    /// max |v_c^{n+1}| over nodes that stayed on the constraint (normal component) or in
    /// stick (tangential component) over the step: the velocity they should not have
    pub chatter: f64,
    /// ½ Σ m_i (v_c,i^{n+1})² over the same nodes (diagonal mass): kinetic energy trapped there
    pub trapped_kinetic: f64,
    /// nodes that carry load (q + λ > 0): the stick and slip nodes under a friction law, every
    /// such node without one
    pub contact_nodes: usize,
    /// nodes in slip, in stick (both 0 without a friction law: a frictionless node is neither)
    pub slip_nodes: usize,
    pub stick_nodes: usize,
    pub report: StepReport,
    pub nodes: Vec<NodeRecord>,
    pub timing: StepTiming,
    /// (E.1) the step's relative residual exceeded `solver.energy_residual_limit` and the scene
    /// asked for a warning instead of a failure
    pub energy_guard_exceeded: bool,
}

impl StepRecord {
    /// A record of step `step` at time `t` with every quantity zero.
    pub fn empty(step: usize, t: f64) -> StepRecord {
        StepRecord {
            step,
            t,
            energy: EnergyTerms::default(),
            energy_scale: 0.0,
            normal_force: 0.0,
            tangential_force: 0.0,
            friction_force: [0.0; 3],
            max_penetration: 0.0,
            chatter: 0.0,
            trapped_kinetic: 0.0,
            contact_nodes: 0,
            slip_nodes: 0,
            stick_nodes: 0,
            report: StepReport::default(),
            nodes: Vec::new(),
            timing: StepTiming::default(),
            energy_guard_exceeded: false,
        }
    }
}

/// Solver settings taken from the model (and adjustable by tests and studies).
#[derive(Debug, Clone, Copy)]
pub struct Settings {
    pub inner: Inner,
    pub fixed_point: FixedPointSettings,
    /// (E.1) as a run-time guard: Some for the midpoint scheme, where the balance is an identity
    /// of the step's equations (the other schemes' residual is their own energy error)
    pub energy_guard: Option<EnergyGuard>,
}

/// The (E.1) guard: a step whose relative residual exceeds `limit` fails, or with `warn_only`
/// is flagged in its record.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnergyGuard {
    pub limit: f64,
    pub warn_only: bool,
}

impl Settings {
    pub fn from_problem(p: &Problem) -> Settings {
        Settings::from_solver(p, &p.model.solver)
    }

    /// The settings of `p` with the solver parameters `s` instead of its own (the studies that
    /// run one problem with several solvers).
    pub fn from_solver(p: &Problem, s: &crate::model::SolverParams) -> Settings {
        let newton = NewtonSettings {
            tolerance: s.newton_tolerance,
            max_iterations: s.max_newton_iterations,
            ..NewtonSettings::default()
        };
        let inner = match s.inner {
            InnerSolver::Newton => Inner::Newton(newton),
            InnerSolver::Conic => Inner::Conic(ConicSettings {
                tolerance: s.newton_tolerance.max(CONIC_TOLERANCE_FLOOR),
                ..ConicSettings::default()
            }),
            InnerSolver::NewtonUnfrozen => Inner::NewtonUnfrozen(newton),
        };
        Settings {
            inner,
            fixed_point: FixedPointSettings {
                tolerance: s.fixed_point_tolerance,
                max_iterations: s.max_fixed_point_iterations,
                relaxation: s.relaxation,
                anderson: s.fixed_point_acceleration == FixedPointAcceleration::Anderson,
                start: f1_start(p, s),
            },
            energy_guard: (p.model.time.scheme == SchemeKind::Midpoint).then_some(EnergyGuard {
                limit: s.energy_residual_limit,
                warn_only: s.energy_residual_action == EnergyResidualAction::Warn,
            }),
        }
    }
}

/// Where (F.1) starts (`solver.fixed_point_start`) with the solver parameters `s`: at the
/// predictor for "predictor", at the unfrozen Newton's root for "unfrozen"; for "auto", at the
/// root from ROOT_START_FROM contact unknowns on where the step problem is convex with a varying
/// μ, so its root is the only fixed point of F.1 and the start changes where F.1 begins, not
/// where it ends (inside (C.k): `Root`; beyond it: `RootIfSharpConvex`, for the setup to decide
/// by (Ck.1)), and S is Anderson-extrapolated (θ = 1 and "anderson"; the plain iteration keeps
/// the paper's start as well as its update).
/// Only the Newton inner solver with the bound at the predictor starts at the root (N.4's system).
pub fn f1_start(p: &Problem, s: &crate::model::SolverParams) -> F1Start {
    let applies = s.inner == InnerSolver::Newton
        && p.contact.as_ref().is_some_and(|c| {
            c.friction.is_some() && c.friction_bound != FrictionBound::Total && c.bound_at == BoundAt::Predictor
        });
    if !applies {
        return F1Start::Predictor;
    }
    match s.fixed_point_start {
        FixedPointStart::Predictor => F1Start::Predictor,
        FixedPointStart::Unfrozen => F1Start::Root,
        FixedPointStart::Auto => {
            let auto = s.fixed_point_acceleration == FixedPointAcceleration::Anderson
                && s.relaxation == 1.0
                && p.contact.as_ref().is_some_and(|c| c.dim * c.n() >= crate::defaults::ROOT_START_FROM);
            match p.convexity_limit() {
                crate::problem::ConvexityLimit::Step { k, .. } if auto && p.k <= k => F1Start::Root,
                crate::problem::ConvexityLimit::Step { .. } if auto => F1Start::RootIfSharpConvex,
                _ => F1Start::Predictor,
            }
        }
    }
}

/// The state at the end of step n: everything the next step reads (and a checkpoint stores).
#[derive(Debug, Clone, PartialEq)]
pub struct State {
    pub n: usize,
    pub u: Vec<f64>,
    pub v: Vec<f64>,
    /// multipliers λ_i and friction forces t_i of the last step (warm starts)
    pub lambda: Vec<f64>,
    pub t_fric: Vec<f64>,
    pub energy: EnergyTerms,
    pub energy_scale: f64,
    /// contact nodes on the constraint (λ > 0) / in stick at the end of the last step (R.2)
    pub active: Vec<bool>,
    pub stick: Vec<bool>,
    /// (Ps.1) the out-of-plane strain s = ε_zz per triangle where it is an internal variable
    /// (plane stress, A not proportional to B); empty otherwise
    pub eps_zz: Vec<f64>,
}

/// What a run needs beyond its [`State`] to continue bit for bit after a checkpoint: the key
/// of the contact solve's kept factorization (U, D and the slip frames: the next Newton systems
/// are solved or preconditioned with that factor). Opaque to the checkpoint, which stores it as
/// it is ([`Simulation::solver_state`]) and hands it back ([`Simulation::resume_solver`]); its
/// JSON is the key's own (null without one), checkpoint format 4's `factor` field.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(transparent)]
pub struct SolverState {
    factor: Option<delassus::FactorKey>,
}

/// The constant operators and the state of a run.
pub struct Simulation<'p> {
    pub problem: &'p Problem,
    pub ops: Operators,
    pub stepper: StepOperator,
    pub settings: Settings,
    /// W = H A_k⁻¹ Hᵀ (None without contact)
    pub delassus: Option<delassus::Delassus>,
    /// the factor cache of the Newton matrices W'_UU + D: each step's contact solve reuses,
    /// replaces and counts its kept factor (see [`Simulation::step`])
    pub delassus_factors: delassus::DelassusFactors,
    /// W⁻¹ for Newton directions in velocity form (dense, well-conditioned W), or None
    pub inverse: Option<delassus::InverseDelassus>,
    /// G = A_k⁻¹ Hᵀ (n × d n_c), kept beside a dense W when small (the recovery reads its
    /// columns instead of solving)
    responses: Option<faer::Mat<f64>>,
    /// the part of A_k's factor the contact unknowns reach, when the step splits its solves
    /// there (see [`Simulation::step`]): a supernodal factor, no kept responses
    reach: Option<crate::linalg::Reach>,
    /// K u^n, K v^n, C v^n, M v^n: the (E.1) terms of the last step formed them, the next
    /// right-hand side (S.2) reads them
    products: StateProducts,
    pub kinematics: ContactKinematics,
    /// (Ck.1) at setup: Some(true) when W showed every step problem strictly convex, Some(false)
    /// when it did not; None where the test did not run (it runs beyond (C.k), with the bound at
    /// the predictor and the dense W)
    pub sharp_convexity: Option<bool>,
    pub state: State,
    pub setup_timing: SetupTiming,
}

/// The free motion of a step (see [`Simulation::step`]).
enum FreeMotion {
    /// v_free = A_k⁻¹ b, whole
    Whole(Vec<f64>),
    /// z = L⁻¹ P b (the forward half, in the factor's order) and x = L⁻ᵀ z solved over the contact
    /// unknowns' reach (its rows final, the rest to finish)
    Split { z: Vec<f64>, x: Vec<f64> },
}

/// What the contact solve of one step produced.
struct ContactStep {
    sol: ContactSolution,
    /// the friction bound S of the last convex solve
    s_bound: Vec<f64>,
    /// d^n per contact node
    d_n: Vec<f64>,
    /// the contact forces r = [ω(q + λ), ω t] per node
    r: Vec<f64>,
    report: StepReport,
}

impl<'p> Simulation<'p> {
    pub fn new(problem: &'p Problem) -> Result<Simulation<'p>> {
        Simulation::with_settings(problem, Settings::from_problem(problem))
    }

    /// Assemble, factor A_k once, and compute the Delassus operator once (the fast path).
    pub fn with_settings(problem: &'p Problem, settings: Settings) -> Result<Simulation<'p>> {
        let clock = Instant::now();
        let contact_nodes: &[usize] = problem.contact.as_ref().map(|c| c.nodes.as_slice()).unwrap_or(&[]);
        let ops =
            Operators::new(&problem.mesh, &problem.material, problem.model.solver.mass, &problem.dofs, contact_nodes)?;
        let assembly = clock.elapsed().as_secs_f64();
        let clock = Instant::now();
        let mut stepper = StepOperator::new(&ops, problem.model.time.scheme, problem.k)?;
        let factorization = clock.elapsed().as_secs_f64();
        let clock = Instant::now();
        let mut delassus_route = "";
        let (delassus, responses, inverse) = match problem.contact.as_ref() {
            Some(c) => {
                let positions: Vec<[f64; 3]> = c.nodes.iter().map(|&i| problem.mesh.point(i)).collect();
                let built = delassus::build_with_responses(
                    stepper.factor(),
                    stepper.matrix().map(|a| (a, Some(ops.positions.as_slice()))),
                    c,
                    &positions,
                    problem.model.solver.contact_solve,
                );
                let inverse = delassus::InverseDelassus::new(&built.w, c.dim, built.winv).map(|i| {
                    if i.winv.nrows() >= crate::defaults::HMATRIX_FROM { i.compressed(&built.w, &positions) } else { i }
                });
                delassus_route = built.route;
                (Some(built.w), built.responses, inverse)
            }
            None => (None, None, None),
        };
        stepper.release_matrix();
        let t_delassus = clock.elapsed().as_secs_f64();
        // (Ck.1) with the exact W beyond (C.k) (where f1_start leaves every RootIfSharpConvex):
        // it decides that start and the (C.k) warning
        let clock = Instant::now();
        let mut settings = settings;
        let beyond_ck =
            matches!(problem.convexity_limit(), crate::problem::ConvexityLimit::Step { k, .. } if problem.k > k);
        let sharp_convexity = match (problem.contact.as_ref(), &delassus) {
            (Some(c), Some(delassus::Delassus::Dense(w))) if beyond_ck && c.bound_at == BoundAt::Predictor => {
                delassus::sharp_convex(w, c, stepper.contact_kinematics().a_v)
            }
            _ => None,
        };
        if settings.fixed_point.start == F1Start::RootIfSharpConvex {
            settings.fixed_point.start = if sharp_convexity == Some(true) { F1Start::Root } else { F1Start::Predictor };
        }
        let t_sharp = clock.elapsed().as_secs_f64();
        let reach =
            problem.contact.as_ref().filter(|_| responses.is_none()).and_then(|c| stepper.factor().reach(&c.dofs));
        let nc = problem.contact.as_ref().map(ContactModel::n).unwrap_or(0);
        let (u, v) = (problem.u0.clone(), problem.v0.clone());
        // (Ps.1) s^0 and its part of the stored energy
        let (eps_zz, eps_zz_energy) = ops
            .thickness
            .as_ref()
            .map(|th| {
                let e0 = th.trace(&u);
                let s0 = th.initial(&e0);
                let energy = th.energy(&s0, &e0);
                (s0, energy)
            })
            .unwrap_or_default();
        let mut energy = EnergyTerms {
            kinetic: energy::half_quad(&ops.m, &v),
            elastic: energy::half_quad(&ops.k, &u) + eps_zz_energy,
            ..EnergyTerms::default()
        };
        if let Some(c) = &problem.contact {
            energy.compliance = c.penetration(&u).iter().zip(&c.omega).map(|(d, w)| w * c.normal.energy(*d)).sum();
        }
        // finite fields whose energies overflow: refused as input, before a row of history.csv
        for (value, key, what, with) in [
            (energy.kinetic, "initial.velocity", "kinetic energy ½ vᵀ M v", "material.density"),
            (energy.elastic, "initial.displacement", "elastic energy ½ uᵀ K u", "material.young"),
            (energy.compliance, "initial.displacement", "compliance energy", "contact.compliance"),
        ] {
            if !value.is_finite() {
                return Err(Error::scene(
                    key,
                    format!("the initial {what} is {value}: {key} (with {with}) is too large for f64 once squared"),
                ));
            }
        }
        let state = State {
            n: 0,
            u,
            v,
            lambda: vec![0.0; nc],
            t_fric: vec![0.0; nc * problem.contact.as_ref().map_or(1, |c| c.dim - 1)],
            energy,
            energy_scale: energy.scale(),
            active: vec![false; nc],
            stick: vec![false; nc],
            eps_zz,
        };
        let products = StateProducts::of(&ops, &state.u, &state.v);
        Ok(Simulation {
            problem,
            kinematics: stepper.contact_kinematics(),
            ops,
            stepper,
            settings,
            delassus,
            delassus_factors: delassus::DelassusFactors::default(),
            inverse,
            responses,
            reach,
            products,
            state,
            sharp_convexity,
            setup_timing: SetupTiming {
                assembly,
                factorization,
                delassus: t_delassus,
                delassus_route,
                sharp_convexity: t_sharp,
            },
        })
    }

    /// The part of A_k's factor the contact unknowns reach, when the step splits its free solve
    /// and recovery there (see [`Simulation::step`]); None when it solves them whole.
    pub fn reach(&self) -> Option<&crate::linalg::Reach> {
        self.reach.as_ref()
    }

    /// The remaining steps of the scene, one record each: `for rec in sim.steps() { … }`.
    /// The iterator ends after the scene's last step, or after the first failure (which is its
    /// last item). `Steps::simulation` gives the state between steps.
    pub fn steps(&mut self) -> Steps<'_, 'p> {
        Steps { sim: self, failed: false }
    }

    /// The row of t = 0: the initial state's quantities. No step has solved for λ or the
    /// friction force yet, so they are 0; the normal response q_i = p(u_ν,i) of an initial
    /// penetration (p_ε under `enforcement = "penalty"`, as a step reports it) is the state's
    /// own, and the normal force Σ ω_i q_i and the statuses follow it
    /// (a node with q_i > 0 is in contact: under a friction law in stick when its initial
    /// tangential velocity is zero, else slipping).
    pub fn initial_record(&self) -> StepRecord {
        let mut nodes = Vec::new();
        let (mut normal_force, mut counts) = (0.0, [0usize; 3]);
        if let Some(c) = &self.problem.contact {
            let d = c.penetration(&self.state.u);
            for (i, &d_i) in d.iter().enumerate() {
                let v_tan = c.tangential(i, &self.state.v);
                let (p_i, v_t) = (c.normal.p(d_i), c.tangential_size(i, &self.state.v));
                let status = NodeStatus::classify(p_i, 0.0, c.friction.as_ref().map(|_| v_t == 0.0));
                normal_force += c.omega[i] * p_i;
                match status {
                    NodeStatus::Separated => {}
                    NodeStatus::Stick => counts = [counts[0] + 1, counts[1] + 1, counts[2]],
                    NodeStatus::Slip => counts = [counts[0] + 1, counts[1], counts[2] + 1],
                    NodeStatus::Contact => counts[0] += 1,
                }
                nodes.push(NodeRecord {
                    u_n: d_i,
                    u_t: c.tangential_size(i, &self.state.u),
                    v_t,
                    p: p_i,
                    lambda: 0.0,
                    friction: 0.0,
                    bound: 0.0,
                    status,
                    v_t_vec: c.global(i, &v_tan),
                    friction_vec: [0.0; 3],
                });
            }
        }
        StepRecord {
            step: 0,
            t: 0.0,
            energy: self.state.energy,
            energy_scale: self.state.energy_scale,
            normal_force,
            contact_nodes: counts[0],
            stick_nodes: counts[1],
            slip_nodes: counts[2],
            tangential_force: 0.0,
            max_penetration: if nodes.is_empty() {
                0.0
            } else {
                nodes.iter().map(|nr| nr.u_n).fold(f64::NEG_INFINITY, f64::max)
            },
            nodes,
            ..StepRecord::empty(0, 0.0)
        }
    }

    fn failure(&self, cause: StepFailureCause) -> Error {
        let step = self.state.n + 1;
        Error::Solver(Box::new(SolverFailure { step, time: self.problem.time(step), cause }))
    }

    /// Advance one step: free solve → contact solve → recovery → advance (S.1) → balance (E.1).
    ///
    /// The free solve and the recovery (S.2) are one solve pair with A_k's factor L (of P A_k Pᵀ)
    /// split around the contact solve, which needs only the free motion's contact velocities:
    /// - free solve: z = L⁻¹ P b (the whole forward pass), and y_free = H v_free from the backward
    ///   pass over the part of L the contact unknowns reach ([`Reach`](crate::linalg::Reach));
    /// - recovery: z ← z − L⁻¹ P Hᵀ r (the forward pass over that part only: Hᵀ r is zero off the
    ///   contact unknowns), then v^{n+1} = Pᵀ L⁻ᵀ z (the whole backward pass).
    ///
    /// Two whole passes and two over the reach instead of two solve pairs (one pair when no
    /// force acts: the backward pass is finished off the reach); v^{n+1} = A_k⁻¹(b − Hᵀ r) as
    /// before, to round-off. Where the responses G = A_k⁻¹ Hᵀ are kept (small problems) or the
    /// factor is simplicial, v_free is solved whole and the recovery subtracts G r or a solve.
    pub fn step(&mut self) -> Result<StepRecord> {
        let clock = Instant::now();
        let (b, f) = self.rhs();
        if let Some(entry) = f.iter().position(|x| !x.is_finite()) {
            // name the load and where it is not finite (an expression like 1/(t − t0))
            let t = self.problem.load_time(self.state.n);
            return Err(self
                .problem
                .loads
                .check_finite(t)
                .err()
                .unwrap_or_else(|| self.failure(StepFailureCause::NonFinite { entry })));
        }
        let factor = self.stepper.factor();
        // the free motion, and its contact velocities H v_free (None without contact)
        let (free, y_free) = match (&self.reach, &self.problem.contact) {
            (Some(reach), Some(c)) => {
                let z = factor.forward(&b);
                let (x, at) = factor.backward_over(reach, &z);
                (FreeMotion::Split { z, x }, Some(c.restrict(&at)))
            }
            (_, c) => {
                let mut v_free = b;
                self.stepper.solve_in_place(&mut v_free);
                let y_free = c.as_ref().map(|c| c.restrict(&v_free));
                (FreeMotion::Whole(v_free), y_free)
            }
        };
        let mut timing = StepTiming { free_solve: clock.elapsed().as_secs_f64(), ..StepTiming::default() };
        // the factor cache leaves the simulation for the contact solve, which reads the
        // operators and the state (shared) and updates the cache (exclusive), and comes back
        let mut factors = std::mem::take(&mut self.delassus_factors);
        let solved = y_free.and_then(|y_free| self.contact_solve(&mut factors, y_free));
        self.delassus_factors = factors;
        let contact = match solved {
            Some(Ok(cs)) => Some(cs),
            Some(Err(e)) => return Err(self.failure(StepFailureCause::Contact(e))),
            None => None,
        };
        timing.contact_solve = clock.elapsed().as_secs_f64() - timing.free_solve;
        let clock = Instant::now();
        let v_new = self.recover(free, contact.as_ref());
        timing.recovery = clock.elapsed().as_secs_f64();
        let u_new = self.stepper.displacement(&self.state.u, &self.state.v, &v_new);
        if let Some(entry) = u_new.iter().chain(&v_new).position(|x| !x.is_finite()) {
            return Err(self.failure(StepFailureCause::NonFinite { entry }));
        }
        self.balance(u_new, v_new, &f, contact, timing)
    }

    /// The contact solve of the step for the free motion's contact velocities `y_free` (None
    /// without contact), with the factor cache `factors`.
    fn contact_solve(
        &self,
        factors: &mut delassus::DelassusFactors,
        y_free: Vec<f64>,
    ) -> Option<std::result::Result<ContactStep, ContactFailure>> {
        let (data, p_tau_hat) = self.step_data(y_free)?;
        let d_n = data.nodes.iter().map(|nd| nd.d_n).collect();
        Some(self.solve_frozen_sequence(&data, factors, &p_tau_hat, &self.settings.inner, None).map(
            |(sol, s_bound, report)| {
                let r = data.forces(&sol.y, &sol.lambda, &sol.t);
                ContactStep { sol, s_bound, d_n, r, report }
            },
        ))
    }

    /// (S.2) Recovery: v^{n+1} = v_free − A_k⁻¹ Hᵀ r with the contact forces r of the solution
    /// (v_free without contact or forces).
    /// - split free motion (see [`Simulation::step`]): z ← z − L⁻¹ P Hᵀ r by the forward pass over
    ///   the contact unknowns' reach, then v^{n+1} = Pᵀ L⁻ᵀ z by the whole backward pass; without a
    ///   force, v_free by finishing the free solve's backward pass off the reach;
    /// - whole v_free: by the kept responses G = A_k⁻¹ Hᵀ, column by column over the nonzero
    ///   forces, when that reads at most [`RESPONSES_ADVANTAGE`](crate::defaults::RESPONSES_ADVANTAGE)
    ///   times the entries a solve pair reads (2 × the factor's), else by a solve.
    fn recover(&self, free: FreeMotion, contact: Option<&ContactStep>) -> Vec<f64> {
        let c = self.problem.contact.as_ref();
        let forces = contact.map_or(0, |cs| cs.r.iter().filter(|v| **v != 0.0).count());
        let mut v_new = match free {
            FreeMotion::Split { mut z, x, .. } => {
                let (factor, reach) = (self.stepper.factor(), self.reach.as_ref());
                return match (reach, c, contact) {
                    (Some(reach), Some(c), Some(cs)) if forces > 0 => {
                        let mut hr = vec![0.0; z.len()];
                        c.scatter_add(&cs.r, &mut hr);
                        factor.forward_sub(reach, &hr, &mut z);
                        factor.backward(z)
                    }
                    // no force: v_free, its backward pass finished off the reach
                    (Some(reach), ..) => factor.backward_rest(reach, x),
                    (None, ..) => factor.backward(z),
                };
            }
            FreeMotion::Whole(v_free) => v_free,
        };
        let (Some(c), Some(cs)) = (c, contact) else { return v_new };
        if let Some(g) = self.responses.as_ref().filter(|_| {
            (forces * v_new.len()) as f64 <= RESPONSES_ADVANTAGE * 2.0 * self.stepper.factor().factor_len() as f64
        }) {
            for (l, &rl) in cs.r.iter().enumerate() {
                if rl != 0.0 {
                    for (vi, gi) in v_new.iter_mut().zip(g.col_as_slice(l)) {
                        *vi -= gi * rl;
                    }
                }
            }
        } else if forces > 0 {
            let mut corr = vec![0.0; v_new.len()];
            c.scatter_add(&cs.r, &mut corr);
            self.stepper.solve_in_place(&mut corr);
            for (vi, ci) in v_new.iter_mut().zip(&corr) {
                *vi -= ci;
            }
        }
        v_new
    }

    /// (E.1) terms of the step, (R.2) persistency, the contact records; the energy guard; then
    /// the state moves to t_{n+1} (a step that fails the guard leaves it at t_n).
    fn balance(
        &mut self,
        u_new: Vec<f64>,
        mut v_new: Vec<f64>,
        f: &[f64],
        contact: Option<ContactStep>,
        timing: StepTiming,
    ) -> Result<StepRecord> {
        let clock = Instant::now();
        let mut p_new = StateProducts::of(&self.ops, &u_new, &v_new);
        let t_products = clock.elapsed().as_secs_f64();
        let clock = Instant::now();
        let (u, v) = (&self.state.u, &self.state.v);
        let du: Vec<f64> = u_new.iter().zip(u).map(|(a, b)| a - b).collect();
        let dv: Vec<f64> = v_new.iter().zip(v).map(|(a, b)| a - b).collect();
        let p = &self.products;
        let mut se = StepEnergy {
            d_kinetic: energy::increment_with(&dv, &p.mv, &p_new.mv),
            d_elastic: energy::increment_with(&du, &p.ku, &p_new.ku),
            work: linalg::dot(&du, f),
            viscous: self.stepper.viscous_work(&du, &p.cv, &p_new.cv),
            ..StepEnergy::default()
        };
        // (Ps.1) the out-of-plane strain follows the step's in-plane trace; its energy and
        // dissipation complete (E.1)
        let eps_zz_new = match self.thickness() {
            Some((th, st)) => {
                let s = &self.state.eps_zz;
                let s_new = th.advance(st, s, &p.eu, &p_new.eu);
                se.d_elastic += th.energy_increment(s, &p.eu, &s_new, &p_new.eu);
                se.viscous += th.viscous_work(st.k, s, &p.eu, &s_new, &p_new.eu);
                s_new
            }
            None => Vec::new(),
        };
        let mut rec = StepRecord {
            timing: StepTiming { products: t_products, ..timing },
            ..StepRecord::empty(self.state.n + 1, self.problem.time(self.state.n + 1))
        };
        if let (Some(c), Some(cs)) = (&self.problem.contact, &contact) {
            self.contact_terms(c, cs, &u_new, &du, &mut se, &mut rec);
            if self.persistency(c, cs, &mut v_new, &mut se, &mut rec) {
                p_new = StateProducts::of(&self.ops, &u_new, &v_new);
            }
            self.state.lambda.clone_from(&cs.sol.lambda);
            self.state.t_fric.clone_from(&cs.sol.t);
            rec.report = cs.report.clone();
        }
        let energy = self.state.energy.advance(&se);
        let scale = self.state.energy_scale.max(energy.scale());
        // no NaN or infinity in history.csv, whichever scheme (the guard below is the midpoint's)
        if !(scale.is_finite() && energy.residual.is_finite()) {
            return Err(self.failure(StepFailureCause::NonFiniteEnergy));
        }
        if let Some(guard) = self.settings.energy_guard {
            let relative = if scale > 0.0 { energy.residual.abs() / scale } else { energy.residual.abs() };
            // NaN fails too
            if !(relative <= guard.limit) {
                if !guard.warn_only {
                    return Err(self.failure(StepFailureCause::EnergyBalance { relative, limit: guard.limit }));
                }
                rec.energy_guard_exceeded = true;
            }
        }
        self.state.energy = energy;
        self.state.energy_scale = scale;
        self.state.u = u_new;
        self.state.v = v_new;
        self.state.eps_zz = eps_zz_new;
        self.state.n += 1;
        self.products = p_new;
        rec.energy = self.state.energy;
        rec.energy_scale = self.state.energy_scale;
        rec.timing.balance = clock.elapsed().as_secs_f64();
        Ok(rec)
    }

    /// (E.1) The contact terms: the compliance energy Σ ω_i (P(d_i') − P(d_i)), the friction
    /// dissipation Σ ω_i S_i |Δu_τ,i| and the constraint dissipation Σ ω_i λ_i (g − d_i^n); with
    /// them the forces and counts of the history row and the contact.csv records.
    fn contact_terms(
        &self,
        c: &ContactModel,
        cs: &ContactStep,
        u_new: &[f64],
        du: &[f64],
        se: &mut StepEnergy,
        rec: &mut StepRecord,
    ) {
        let (sol, s_bound) = (&cs.sol, &cs.s_bound);
        let d_new = c.penetration(u_new);
        let mut max_pen = f64::NEG_INFINITY;
        for i in 0..c.n() {
            let omega = c.omega[i];
            se.d_compliance += omega * (c.normal.energy(d_new[i]) - c.normal.energy(cs.d_n[i]));
            se.friction += omega
                * s_bound[i]
                * if c.dim == 2 {
                    c.components(i, du).1.abs()
                } else {
                    let d = c.tangential(i, du);
                    d[0].hypot(d[1])
                };
            if let Some(g) = c.constraint {
                se.constraint += omega * sol.lambda[i] * (g - cs.d_n[i]);
            }
            rec.normal_force += omega * (sol.q[i] + sol.lambda[i]);
            // the friction traction −t, d − 1 components per node
            let td = c.dim - 1;
            let t_i: [f64; 2] = std::array::from_fn(|j| if j < td { sol.t[td * i + j] } else { 0.0 });
            let friction_vec = c.global(i, &[-t_i[0], -t_i[1]]);
            for (f, v) in rec.friction_force.iter_mut().zip(friction_vec) {
                *f += omega * v;
            }
            if c.dim == 2 {
                rec.tangential_force -= omega * sol.t[i];
            }
            max_pen = max_pen.max(d_new[i]);
            // a frictionless node in contact counts in contact_nodes only: neither stick nor slip
            match sol.status[i] {
                NodeStatus::Separated => {}
                NodeStatus::Stick => rec.stick_nodes += 1,
                NodeStatus::Slip => rec.slip_nodes += 1,
                NodeStatus::Contact => {}
            }
            rec.contact_nodes += usize::from(sol.status[i] != NodeStatus::Separated);
            let kin = self.kinematics;
            let v_now = c.tangential(i, &self.state.v);
            let vbar: [f64; 2] = std::array::from_fn(|j| {
                if j + 1 < c.dim { kin.a_v * (sol.y[c.dim * i + 1 + j] + kin.b_v * v_now[j]) } else { 0.0 }
            });
            let (v_t, friction) =
                if c.dim == 2 { (vbar[0], -sol.t[i]) } else { (vbar[0].hypot(vbar[1]), t_i[0].hypot(t_i[1])) };
            rec.nodes.push(NodeRecord {
                u_n: d_new[i],
                u_t: c.tangential_size(i, u_new),
                v_t,
                p: sol.q[i],
                lambda: sol.lambda[i],
                friction,
                bound: s_bound[i],
                status: sol.status[i],
                v_t_vec: c.global(i, &vbar),
                friction_vec,
            });
        }
        if c.dim == 3 {
            rec.tangential_force = rec.friction_force.iter().map(|f| f * f).sum::<f64>().sqrt();
        }
        rec.max_penetration = if rec.nodes.is_empty() { 0.0 } else { max_pen };
    }

    /// (R.2) on nodes that stayed on the constraint or in stick over the step: either remove
    /// the velocity they keep (`solver.persistency`) and book it, or measure it as chatter.
    /// Returns whether it changed v^{n+1}.
    fn persistency(
        &mut self,
        c: &ContactModel,
        cs: &ContactStep,
        v_new: &mut [f64],
        se: &mut StepEnergy,
        rec: &mut StepRecord,
    ) -> bool {
        let persistency = self.problem.model.solver.persistency;
        let mut removed = 0.0;
        for i in 0..c.n() {
            let now_active = cs.sol.lambda[i] > 0.0;
            let now_stick = cs.sol.status[i] == NodeStatus::Stick;
            let dofs = c.node_dofs(i);
            let m = self.ops.m_lumped[dofs[0]];
            let frame = &c.frames[i];
            // the normal component if the node stayed on the constraint, the tangential ones if it stayed in stick
            let normal = (self.state.active[i] && now_active).then_some(&frame.normal);
            let tangents = frame.tangents[..c.dim - 1].iter().filter(|_| self.state.stick[i] && now_stick);
            for dir in normal.into_iter().chain(tangents) {
                let vc = component(v_new, dofs, dir);
                if persistency {
                    removed += persist_velocity(v_new, dofs, dir, m);
                } else {
                    rec.chatter = rec.chatter.max(vc.abs());
                    rec.trapped_kinetic += 0.5 * m * vc * vc;
                }
            }
            self.state.active[i] = now_active;
            self.state.stick[i] = now_stick;
        }
        if persistency {
            se.d_kinetic = energy::increment(&self.ops.m, &self.state.v, v_new);
            se.persistency = removed;
        }
        persistency
    }

    /// The free velocity A_k⁻¹ b^n of the current state and the load used.
    pub fn free_velocity(&self) -> (Vec<f64>, Vec<f64>) {
        let (mut v_free, f) = self.rhs();
        self.stepper.solve_in_place(&mut v_free);
        (v_free, f)
    }

    /// The step's right-hand side b^n (S.2) and the load f^{n+½} it holds.
    fn rhs(&self) -> (Vec<f64>, Vec<f64>) {
        let f = self.problem.loads.at(self.problem.load_time(self.state.n));
        (self.stepper.rhs(&self.products, &f, self.ops.thickness.as_ref(), &self.state.eps_zz), f)
    }

    /// The condensed contact problem of the current state for a given free contact velocity
    /// `y_free`, and p_τ(û) per node. None without contact.
    pub fn step_data(&self, y_free: Vec<f64>) -> Option<(StepData<'_>, Vec<f64>)> {
        let (c, w) = (self.problem.contact.as_ref()?, self.delassus.as_ref()?);
        let d_n = c.penetration(&self.state.u);
        let vn = c.restrict(&self.state.v);
        let kin = self.kinematics;
        let nodes: Vec<NodeData> = (0..c.n())
            .map(|i| NodeData {
                omega: c.omega[i],
                d_n: d_n[i],
                d_aff: d_n[i] + kin.a_d * kin.b_d * vn[c.dim * i],
                v_aff: std::array::from_fn(
                    |j| if j + 1 < c.dim { kin.a_v * kin.b_v * vn[c.dim * i + 1 + j] } else { 0.0 },
                ),
                bound: c.constraint,
            })
            .collect();
        let p_tau_hat: Vec<f64> = (0..c.n()).map(|i| c.p_tau.p_tau(d_n[i] + kin.p_d * vn[c.dim * i])).collect();
        let data = StepData {
            delassus: w,
            y_free,
            nodes,
            a_d: kin.a_d,
            a_v: kin.a_v,
            force_rule: kin.force,
            law: &c.normal,
            friction: c.friction.is_some(),
            dim: c.dim,
            inverse: self.inverse.as_ref(),
        };
        Some((data, p_tau_hat))
    }

    /// (F.1) on the current state with a given inner solver and the factor cache `factors` (the
    /// run's own, [`delassus_factors`](Self::delassus_factors), in a step; a caller that
    /// re-solves a step from outside passes its own, so the run's path is not changed); `trace`
    /// collects the contact velocities of every convex solve. Without contact there is nothing
    /// to solve: an empty solution.
    pub fn solve_frozen_sequence(
        &self,
        data: &StepData,
        factors: &mut delassus::DelassusFactors,
        p_tau_hat: &[f64],
        inner: &Inner,
        trace: Option<&mut Vec<Vec<f64>>>,
    ) -> std::result::Result<(ContactSolution, Vec<f64>, StepReport), ContactFailure> {
        let Some(c) = &self.problem.contact else {
            return fixed_point::solve(
                data,
                factors,
                None,
                &NormalPart::Total,
                &[],
                &[],
                &[],
                inner,
                &self.settings.fixed_point,
                trace,
            );
        };
        let normal = match (c.friction_bound, c.bound_at) {
            (FrictionBound::Total, _) => NormalPart::Total,
            (_, BoundAt::Midpoint) => NormalPart::Midpoint { law: &c.p_tau, weight: self.kinematics.p_w },
            (_, BoundAt::Predictor) => NormalPart::Predictor(p_tau_hat),
        };
        let vn = c.restrict(&self.state.v);
        fixed_point::solve(
            data,
            factors,
            c.friction.as_ref(),
            &normal,
            &vn,
            &self.state.lambda,
            &self.state.t_fric,
            inner,
            &self.settings.fixed_point,
            trace,
        )
    }

    /// (Ps.1) The out-of-plane strain's operator and this step's coefficients, where ε_zz is a
    /// variable.
    pub fn thickness(&self) -> Option<(&ThicknessStrain, &ThicknessStep)> {
        self.ops.thickness.as_ref().zip(self.stepper.thickness.as_ref())
    }

    /// The solver state a checkpoint stores beside [`State`] (see [`SolverState`]).
    pub fn solver_state(&self) -> SolverState {
        SolverState { factor: self.delassus_factors.key() }
    }

    /// Continue with a checkpoint's solver state: rebuild the kept factorization of its key.
    /// None when the key does not fit this scene's Delassus operator (or its matrix is not
    /// positive definite); a key without a Delassus operator (no contact) is ignored.
    pub fn resume_solver(&mut self, s: &SolverState) -> Option<()> {
        match (&s.factor, self.delassus.as_ref()) {
            (Some(key), Some(w)) => self.delassus_factors.restore(w, key),
            _ => Some(()),
        }
    }

    /// Continue from a checkpointed state (sizes must match this problem).
    pub fn restore(&mut self, s: State) -> Result<()> {
        let cur = &self.state;
        if s.u.len() != cur.u.len()
            || s.v.len() != cur.v.len()
            || s.lambda.len() != cur.lambda.len()
            || s.t_fric.len() != cur.t_fric.len()
            || s.eps_zz.len() != cur.eps_zz.len()
        {
            return Err(Error::Checkpoint("it does not match this problem's sizes".into()));
        }
        if s.n > self.problem.steps {
            return Err(Error::Checkpoint(format!(
                "it is at step {}, beyond the scene's {} steps",
                s.n, self.problem.steps
            )));
        }
        self.state = s;
        self.products = StateProducts::of(&self.ops, &self.state.u, &self.state.v);
        Ok(())
    }

    pub fn scheme(&self) -> SchemeKind {
        self.stepper.kind
    }
}

/// The time loop as an iterator of step records (see [`Simulation::steps`]).
pub struct Steps<'s, 'p> {
    sim: &'s mut Simulation<'p>,
    failed: bool,
}

impl<'s, 'p> Steps<'s, 'p> {
    /// The simulation between steps (its state is that of the last record returned).
    pub fn simulation(&self) -> &Simulation<'p> {
        self.sim
    }

    /// The same loop, calling `look` with the simulation before each step (to examine or
    /// re-solve a step from its own state, as the twin and agreement checks do).
    pub fn before_each<F: FnMut(&Simulation<'p>)>(self, look: F) -> BeforeEach<'s, 'p, F> {
        BeforeEach { steps: self, look }
    }
}

/// [`Steps`] with a look at the state before each step (see [`Steps::before_each`]).
pub struct BeforeEach<'s, 'p, F> {
    steps: Steps<'s, 'p>,
    look: F,
}

impl<'p, F: FnMut(&Simulation<'p>)> Iterator for BeforeEach<'_, 'p, F> {
    type Item = Result<StepRecord>;

    fn next(&mut self) -> Option<Result<StepRecord>> {
        let sim = &*self.steps.sim;
        if self.steps.failed || sim.state.n >= sim.problem.steps {
            return None;
        }
        (self.look)(sim);
        self.steps.next()
    }
}

impl Iterator for Steps<'_, '_> {
    type Item = Result<StepRecord>;

    fn next(&mut self) -> Option<Result<StepRecord>> {
        if self.failed || self.sim.state.n >= self.sim.problem.steps {
            return None;
        }
        let rec = self.sim.step();
        self.failed = rec.is_err();
        Some(rec)
    }
}
