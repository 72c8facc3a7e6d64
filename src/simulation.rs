//! The time loop: one step is (1) the free velocity A_k⁻¹ b^n, (2) the contact problem on the
//! contact DOFs through the Delassus operator (F.1 around the inner solver), (3) the recovery
//! solve, (4) the displacement update (S.1) and the energy balance (E.1).

use faer::Mat;

use crate::energy::{self, EnergyTerms, StepEnergy};
use crate::error::{Error, Result, SolverFailure};
use crate::fem::Operators;
use crate::linalg;
use crate::problem::Problem;
use crate::scene::{InnerSolver, SchemeKind};
use crate::scheme::{ContactRule, StepOperator};
use crate::step::conic::ConicSettings;
use crate::step::fixed_point::{self, FixedPointSettings, Inner, StepReport};
use crate::step::newton::NewtonSettings;
use crate::step::{delassus, NodeData, NodeStatus, StepData};


/// (R.2) Velocity-level persistency: on a node that stayed on the constraint (dir = ν) or in
/// stick (dir = τ) over the step, set the end-point velocity component v_c^{n+1} = 0 instead
/// of the −v_c^n that (S.1) gives; returns the kinetic energy removed, ½ m (v_c^{n+1})² ≥ 0
/// (diagonal mass m), which (E.1) books as the persistency dissipation.
pub fn persist_velocity(w: &mut [f64], dofs: [usize; 2], dir: [f64; 2], m: f64) -> f64 {
    let [dx, dy] = dofs;
    let wc = dir[0] * w[dx] + dir[1] * w[dy];
    w[dx] -= wc * dir[0];
    w[dy] -= wc * dir[1];
    0.5 * m * wc * wc
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
    pub tangential_force: f64,
    pub max_penetration: f64,
    /// max |v_c^{n+1}| over nodes that stayed on the constraint (normal component) or in
    /// stick (tangential component) over the step: the velocity they should not have
    pub chatter: f64,
    /// ½ Σ m_i (v_c,i^{n+1})² over the same nodes (diagonal mass): kinetic energy trapped there
    pub trapped_kinetic: f64,
    pub contact_nodes: usize,
    pub slip_nodes: usize,
    pub stick_nodes: usize,
    pub report: StepReport,
    pub nodes: Vec<NodeRecord>,
}

/// Solver settings taken from the scene (and adjustable by tests and studies).
#[derive(Debug, Clone, Copy)]
pub struct Settings {
    pub inner: Inner,
    pub fixed_point: FixedPointSettings,
}

impl Settings {
    pub fn from_problem(p: &Problem) -> Settings {
        let s = &p.scene.solver;
        let inner = match s.inner {
            InnerSolver::Newton => Inner::Newton(NewtonSettings {
                tolerance: s.newton_tolerance,
                max_iterations: s.max_newton_iterations as usize,
                ..NewtonSettings::default()
            }),
            InnerSolver::Conic => Inner::Conic(ConicSettings { tolerance: s.newton_tolerance.max(1e-12), ..ConicSettings::default() }),
            InnerSolver::NewtonUnfrozen => Inner::NewtonUnfrozen(NewtonSettings {
                tolerance: s.newton_tolerance,
                max_iterations: s.max_newton_iterations as usize,
                ..NewtonSettings::default()
            }),
        };
        Settings {
            inner,
            fixed_point: FixedPointSettings {
                tolerance: s.fixed_point_tolerance,
                max_iterations: s.max_fixed_point_iterations as usize,
                relaxation: s.relaxation,
            },
        }
    }
}

/// The state and the constant operators of a run.
pub struct Simulation<'p> {
    pub problem: &'p Problem,
    pub ops: Operators,
    pub stepper: StepOperator,
    pub settings: Settings,
    /// W = H A_k⁻¹ Hᵀ (None without contact)
    pub delassus: Option<Mat<f64>>,
    pub rule: ContactRule,
    pub n: usize,
    pub u: Vec<f64>,
    pub v: Vec<f64>,
    pub lambda: Vec<f64>,
    pub t_fric: Vec<f64>,
    /// contact nodes on the constraint (λ > 0) / in stick at the end of the last step
    pub active: Vec<bool>,
    pub stick: Vec<bool>,
    pub energy: EnergyTerms,
    energy_scale: f64,
    /// wall-clock split of the last step: free solve, contact solve, recovery (seconds)
    pub timing: [f64; 3],
    /// setup: assembly, factorization of A_k, Delassus operator (seconds)
    pub setup_timing: [f64; 3],
}

impl<'p> Simulation<'p> {
    pub fn new(problem: &'p Problem) -> Result<Simulation<'p>> {
        Simulation::with_settings(problem, Settings::from_problem(problem))
    }

    pub fn with_settings(problem: &'p Problem, settings: Settings) -> Result<Simulation<'p>> {
        let clock = std::time::Instant::now();
        let contact_nodes: &[usize] = problem.contact.as_ref().map(|c| c.nodes.as_slice()).unwrap_or(&[]);
        let ops = Operators::new(&problem.mesh, &problem.material, problem.scene.solver.mass, &problem.dofs, contact_nodes)?;
        let t_assembly = clock.elapsed().as_secs_f64();
        let clock = std::time::Instant::now();
        let stepper = StepOperator::new(&ops, problem.scene.time.scheme, problem.k)?;
        let t_factor = clock.elapsed().as_secs_f64();
        let clock = std::time::Instant::now();
        let delassus = problem.contact.as_ref().map(|c| delassus::delassus(stepper.factor(), c));
        let t_delassus = clock.elapsed().as_secs_f64();
        let nc = problem.contact.as_ref().map(|c| c.n()).unwrap_or(0);
        let u = problem.u0.clone();
        let v = problem.v0.clone();
        let mut energy = EnergyTerms {
            kinetic: energy::half_quad(&ops.m, &v),
            elastic: energy::half_quad(&ops.k, &u),
            ..EnergyTerms::default()
        };
        if let Some(c) = &problem.contact {
            energy.compliance = c.penetration(&u).iter().zip(&c.omega).map(|(d, w)| w * c.normal.energy(*d)).sum();
        }
        let energy_scale = energy.scale();
        Ok(Simulation {
            problem,
            rule: stepper.contact_rule(),
            ops,
            stepper,
            settings,
            delassus,
            n: 0,
            u,
            v,
            lambda: vec![0.0; nc],
            t_fric: vec![0.0; nc],
            active: vec![false; nc],
            stick: vec![false; nc],
            energy,
            energy_scale,
            timing: [0.0; 3],
            setup_timing: [t_assembly, t_factor, t_delassus],
        })
    }

    /// The row of t = 0.
    pub fn initial_record(&self) -> StepRecord {
        let mut nodes = Vec::new();
        let mut max_pen = f64::NEG_INFINITY;
        if let Some(c) = &self.problem.contact {
            let d = c.penetration(&self.u);
            for i in 0..c.n() {
                let (_, ut) = c.components(i, &self.u);
                let (_, vt) = c.components(i, &self.v);
                max_pen = max_pen.max(d[i]);
                nodes.push(NodeRecord {
                    u_n: d[i],
                    u_t: ut,
                    v_t: vt,
                    p: c.compliance.p(d[i]),
                    lambda: 0.0,
                    friction: 0.0,
                    bound: 0.0,
                    status: NodeStatus::Separated,
                });
            }
        }
        StepRecord {
            step: 0,
            t: 0.0,
            energy: self.energy,
            energy_scale: self.energy_scale,
            normal_force: 0.0,
            tangential_force: 0.0,
            max_penetration: if nodes.is_empty() { 0.0 } else { max_pen },
            chatter: 0.0,
            trapped_kinetic: 0.0,
            contact_nodes: 0,
            slip_nodes: 0,
            stick_nodes: 0,
            report: StepReport { fixed_point_converged: true, ..StepReport::default() },
            nodes,
        }
    }

    fn failure(&self, what: String, residuals: String, suggestion: &str) -> Error {
        Error::Solver(Box::new(SolverFailure {
            step: self.n + 1,
            time: self.problem.time(self.n + 1),
            what,
            residuals,
            suggestion: suggestion.to_string(),
        }))
    }

    /// Advance one step.
    pub fn step(&mut self) -> Result<StepRecord> {
        let p = self.problem;
        let clock = std::time::Instant::now();
        let (mut w, f) = self.free_velocity();
        let t_free = clock.elapsed().as_secs_f64();
        let mut report = StepReport { fixed_point_converged: true, ..StepReport::default() };
        let mut t_contact = 0.0;
        let mut t_recover = 0.0;
        let mut contact_out = None;
        if let (Some(c), Some(_)) = (&p.contact, &self.delassus) {
            let clock = std::time::Instant::now();
            let y_free = c.restrict(&w);
            let (data, p_tau_hat) = self.step_data(y_free).ok_or_else(|| self.failure("no contact data".into(), String::new(), ""))?;
            let (sol, s, rep) = self.solve_frozen_sequence(&data, &p_tau_hat, &self.settings.inner, None).map_err(|e| {
                self.failure(
                    format!("the {} solver failed in fixed-point iteration {} ({})", e.solver, e.fixed_point_iteration, e.reason),
                    format!("after {} iterations the relative residual is {:.3e}", e.iterations, e.residual),
                    "a smaller time.step, solver.relaxation < 1, a larger contact.penalty, or more solver.max_newton_iterations",
                )
            })?;
            report = rep;
            t_contact = clock.elapsed().as_secs_f64();
            let clock = std::time::Instant::now();
            let r = data.forces(&sol.y, &sol.lambda, &sol.t);
            if r.iter().any(|v| *v != 0.0) {
                let mut corr = vec![0.0; w.len()];
                c.scatter_add(&r, &mut corr);
                self.stepper.solve_in_place(&mut corr);
                for (wi, ci) in w.iter_mut().zip(&corr) {
                    *wi -= ci;
                }
            }
            t_recover = clock.elapsed().as_secs_f64();
            let d_n: Vec<f64> = data.nodes.iter().map(|nd| nd.d_n).collect();
            contact_out = Some((sol, s, d_n));
        }
        let u_new = self.stepper.displacement(&self.u, &self.v, &w);
        if let Some(bad) = u_new.iter().chain(&w).position(|x| !x.is_finite()) {
            return Err(self.failure(
                format!("a non-finite value appeared in the solution (entry {bad})"),
                "the loads or the step produced NaN or infinity".into(),
                "check the load expressions and use a smaller time.step",
            ));
        }
        // --- energy balance (E.1) ---
        let du: Vec<f64> = u_new.iter().zip(&self.u).map(|(a, b)| a - b).collect();
        let vc = self.stepper.viscous_velocity(&self.v, &w);
        let mut se = StepEnergy {
            d_kinetic: energy::increment(&self.ops.m, &self.v, &w),
            d_elastic: energy::increment(&self.ops.k, &self.u, &u_new),
            work: linalg::dot(&du, &f),
            viscous: linalg::quad(&self.ops.c, &du, &vc),
            ..StepEnergy::default()
        };
        let mut rec_nodes = Vec::new();
        let (mut fn_sum, mut ft_sum, mut max_pen) = (0.0, 0.0, f64::NEG_INFINITY);
        let (mut n_contact, mut n_slip, mut n_stick) = (0, 0, 0);
        if let (Some(c), Some((sol, s, d_n))) = (&p.contact, &contact_out) {
            let d_new = c.penetration(&u_new);
            for i in 0..c.n() {
                let w_i = c.omega[i];
                se.d_compliance += w_i * (c.normal.energy(d_new[i]) - c.normal.energy(d_n[i]));
                let (_, dut) = c.components(i, &du);
                se.friction += w_i * s[i] * dut.abs();
                if let Some(g) = c.constraint {
                    se.constraint += w_i * sol.lambda[i] * (g - d_n[i]);
                }
                fn_sum += w_i * (sol.q[i] + sol.lambda[i]);
                ft_sum -= w_i * sol.t[i];
                max_pen = max_pen.max(d_new[i]);
                match sol.status[i] {
                    NodeStatus::Separated => {}
                    NodeStatus::Stick => {
                        n_contact += 1;
                        n_stick += 1;
                    }
                    NodeStatus::Slip => {
                        n_contact += 1;
                        n_slip += 1;
                    }
                }
                let (_, ut) = c.components(i, &u_new);
                let vbar = self.rule.a_v * (sol.y[2 * i + 1] + self.rule.b_v * c.components(i, &self.v).1);
                rec_nodes.push(NodeRecord {
                    u_n: d_new[i],
                    u_t: ut,
                    v_t: vbar,
                    p: sol.q[i],
                    lambda: sol.lambda[i],
                    friction: -sol.t[i],
                    bound: s[i],
                    status: sol.status[i],
                });
            }
            self.lambda.clone_from(&sol.lambda);
            self.t_fric.clone_from(&sol.t);
        }
        let (mut chatter, mut trapped) = (0.0f64, 0.0f64);
        if let (Some(c), Some((sol, _, _))) = (&p.contact, &contact_out) {
            let persistency = p.scene.solver.persistency;
            let mut removed = 0.0;
            for i in 0..c.n() {
                let now_active = sol.lambda[i] > 0.0;
                let now_stick = sol.status[i] == NodeStatus::Stick;
                let [dx, dy] = c.dofs[i];
                let m = self.ops.m_lumped[dx];
                for (persistent, dir) in [(self.active[i] && now_active, c.normals[i]), (self.stick[i] && now_stick, c.tangent(i))] {
                    if !persistent {
                        continue;
                    }
                    let wc = dir[0] * w[dx] + dir[1] * w[dy];
                    if persistency {
                        removed += persist_velocity(&mut w, [dx, dy], dir, m);
                    } else {
                        chatter = chatter.max(wc.abs());
                        trapped += 0.5 * m * wc * wc;
                    }
                }
                self.active[i] = now_active;
                self.stick[i] = now_stick;
            }
            if persistency {
                se.d_kinetic = energy::increment(&self.ops.m, &self.v, &w);
                se.persistency = removed;
            }
        }
        self.energy = self.energy.advance(&se);
        self.energy_scale = self.energy_scale.max(self.energy.scale());
        self.u = u_new;
        self.v = w;
        self.n += 1;
        self.timing = [t_free, t_contact, t_recover];
        Ok(StepRecord {
            step: self.n,
            t: p.time(self.n),
            energy: self.energy,
            energy_scale: self.energy_scale,
            normal_force: fn_sum,
            tangential_force: ft_sum,
            max_penetration: if rec_nodes.is_empty() { 0.0 } else { max_pen },
            chatter,
            trapped_kinetic: trapped,
            contact_nodes: n_contact,
            slip_nodes: n_slip,
            stick_nodes: n_stick,
            report,
            nodes: rec_nodes,
        })
    }

    /// The free velocity A_k⁻¹ b^n of the current state and the load used.
    pub fn free_velocity(&self) -> (Vec<f64>, Vec<f64>) {
        let f = self.problem.loads.at(self.stepper.load_time(self.problem.time(self.n)));
        let mut w = self.stepper.rhs(&self.u, &self.v, &f);
        self.stepper.solve_in_place(&mut w);
        (w, f)
    }

    /// The condensed contact problem of the current state for a given free contact velocity
    /// `y_free`, and p_τ(û) per node. None without contact.
    pub fn step_data(&self, y_free: Vec<f64>) -> Option<(StepData<'_>, Vec<f64>)> {
        let (c, wmat) = (self.problem.contact.as_ref()?, self.delassus.as_ref()?);
        let d_n = c.penetration(&self.u);
        let vn = c.restrict(&self.v);
        let rule = self.rule;
        let nodes: Vec<NodeData> = (0..c.n())
            .map(|i| NodeData {
                omega: c.omega[i],
                d_n: d_n[i],
                d_aff: d_n[i] + rule.a_d * rule.b_d * vn[2 * i],
                v_aff: rule.a_v * rule.b_v * vn[2 * i + 1],
                bound: c.constraint,
            })
            .collect();
        let p_tau_hat: Vec<f64> = (0..c.n()).map(|i| c.p_tau.p_tau(d_n[i] + rule.p_d * vn[2 * i])).collect();
        let data = StepData {
            w: wmat,
            y_free,
            nodes,
            a_d: rule.a_d,
            a_v: rule.a_v,
            rule: rule.force,
            law: &c.normal,
            friction: c.friction.is_some(),
        };
        Some((data, p_tau_hat))
    }

    /// (F.1) on the current state with a given inner solver; `trace` collects the contact
    /// velocities of every convex solve.
    pub fn solve_frozen_sequence(
        &self,
        data: &StepData,
        p_tau_hat: &[f64],
        inner: &Inner,
        trace: Option<&mut Vec<Vec<f64>>>,
    ) -> std::result::Result<(crate::step::ContactSolution, Vec<f64>, StepReport), fixed_point::InnerFailure> {
        let c = self.problem.contact.as_ref().ok_or_else(|| fixed_point::InnerFailure {
            solver: "none",
            iterations: 0,
            residual: 0.0,
            reason: "the problem has no contact".into(),
            fixed_point_iteration: 0,
        })?;
        let vn = c.restrict(&self.v);
        fixed_point::solve(data, c.friction.as_ref(), p_tau_hat, &vn, &self.lambda, &self.t_fric, inner, &self.settings.fixed_point, trace)
    }

    /// The state to checkpoint after the current step.
    pub fn state(&self) -> crate::checkpoint::State {
        crate::checkpoint::State {
            step: self.n,
            u: self.u.clone(),
            v: self.v.clone(),
            lambda: self.lambda.clone(),
            t_fric: self.t_fric.clone(),
            energy: self.energy,
            energy_scale: self.energy_scale,
            active: self.active.clone(),
            stick: self.stick.clone(),
        }
    }

    /// Continue from a checkpointed state (sizes must match this problem).
    pub fn restore(&mut self, s: crate::checkpoint::State) -> Result<()> {
        if s.u.len() != self.u.len() || s.v.len() != self.v.len() || s.lambda.len() != self.lambda.len() || s.t_fric.len() != self.t_fric.len() {
            return Err(Error::Output("the checkpoint does not match this problem's sizes".into()));
        }
        if s.step > self.problem.steps {
            return Err(Error::Output(format!("the checkpoint is at step {}, beyond the scene's {} steps", s.step, self.problem.steps)));
        }
        self.n = s.step;
        self.u = s.u;
        self.v = s.v;
        self.lambda = s.lambda;
        self.t_fric = s.t_fric;
        self.energy = s.energy;
        self.energy_scale = s.energy_scale;
        self.active = s.active;
        self.stick = s.stick;
        Ok(())
    }

    pub fn scheme(&self) -> SchemeKind {
        self.stepper.kind
    }
}
