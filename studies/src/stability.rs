//! Stability map (`cargo xtask stability`).
//!
//! For each variant (midpoint, trapezoid, backward Euler, midpoint with the modified mass R.1,
//! midpoint with velocity persistency R.2, midpoint with the unfrozen Newton N.4) one
//! parameter is varied at a time around a base scene and every run is classified
//! ([`RunClass`]):
//!
//! - the time step k, from well inside the (C.k) limit to well beyond it;
//! - the penalty ε of Problem P_ε down to 1e-12;
//! - the friction decay α (steeper velocity weakening);
//! - the impact velocity (fixtures/scenes/impact_friction.toml, v0 scaled);
//! - the relaxation θ of (F.1) at a k beyond (C.k);
//! - the Newton iteration cap (a dedicated row that shows the inner-solver failure mode);
//! - the penalty ε on the impact scene made elastic (no viscosity): the stiff impact where a
//!   force rule other than the discrete gradient (the trapezoid's average) creates energy.
//!
//! The base scene is the academic scene on 16 × 8 cells with T = 1 s (k = 5e-4, inside this
//! mesh's (C.k) limit 6.94e-4); the impact sweeps use impact_friction.toml (T = 0.3 s). The
//! quick sweep (`--quick`) runs the extreme value of each sweep with T = 0.02 s. Writes `OUT/stability.csv` (one row per run) and
//! `OUT/stability.svg` (per sweep, a grid of parameter value × variant coloured by class).

use std::path::Path;
use std::time::Instant;

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use dyncontact::energy::EnergyTerms;
use dyncontact::error::{Error, Result};
use dyncontact::failure::{FailureKind, RunStatus};
use dyncontact::model::kinds::{self, EnforcementKind, FixedPointAcceleration, InnerSolver, MassKind, SchemeKind};
use dyncontact::output::Summary;
use dyncontact::output::summary::ModelInfo;
use dyncontact::output::write_atomic;
use dyncontact::problem::Problem;
use dyncontact::scene::Scene;
use dyncontact::simulation::Simulation;

use dyncontact::output::csv::{csv_field, csv_table};
use dyncontact::output::loglog::chart_error;
use dyncontact::output::style;
use dyncontact::sweep::runner::{self, RunnerOptions};
use dyncontact::sweep::{Base, Plan, SweepFile};

/// Options of the stability sweep.
#[derive(Debug, Clone, Default)]
pub struct StabilityOptions {
    /// a small sweep for smoke tests
    pub quick: bool,
    /// runs at once (0: the number of cores)
    pub jobs: usize,
}

/// Horizon of the full sweep (s): the academic scene's own T = 1, so the whole stick–slip
/// phase driven by the tangential traction (t ≥ 0.2 s) is in every run (the full sweep takes
/// about a minute in release).
pub const FULL_END: f64 = 1.0;
/// Horizon of the impact sweeps (s): impact_friction.toml's own T (every contact regime).
pub const IMPACT_END: f64 = 0.3;
/// Horizon of the quick sweep (s).
pub const QUICK_END: f64 = 0.02;
/// Base time step: the academic scene's k, inside the 16 × 8 mesh's (C.k) limit 6.94e-4.
pub const BASE_STEP: f64 = 5e-4;
/// The time step of the relaxation sweep: beyond (C.k) (6.94e-4 on the base mesh).
pub const BEYOND_CK_STEP: f64 = 1e-3;
/// The (E.1) defect, relative to the energy scale, under which an energy-conserving variant
/// (midpoint) counts as converged.
pub const DEFECT_TOLERANCE: f64 = 1e-9;
/// "energy grew": max_n (E^n − E^0 − W^n) / scale^n above this. The midpoint rule satisfies
/// E^n − E^0 − W^n = −(dissipations) + Σ(E.1 defects) ≤ Σ defects; the map measured per-step
/// defects ≤ 4e-16 of the scale with exact enforcement and ≤ 1.2e-13 with ε = 1e-9, so over
/// ≤ 8000 steps the sum stays below 1e-9 and 1e-6 leaves three decades for rounding and solver
/// tolerance. Backward Euler's defects are negative (it loses energy); the trapezoid's have
/// either sign. The only gains the map found are 0.66–0.68 of the scale (trapezoid, stiff
/// penalty impact), so any threshold between 1e-9 and 1e-2 gives the same map.
pub const GAIN_TOLERANCE: f64 = 1e-6;

/// How a run ended. The order is the precedence of the classification (a stop beats an energy
/// gain, which beats a capped fixed point, ...).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum RunClass {
    /// A NaN or infinity appeared (in a record, or caught by the library's non-finite guard).
    NonFinite,
    /// The run stopped with a failure of the inner (Newton) solver (`Error::Solver`).
    NewtonFailed,
    /// The run was refused with another error (invalid input, factorization).
    ClearError,
    /// Stored energy E = kinetic + elastic + compliance exceeded E^0 + external work by more
    /// than [`GAIN_TOLERANCE`] of the energy scale.
    EnergyGrew,
    /// Completed, but some step hit max_fixed_point_iterations (F.1 did not converge).
    FixedPointCapped,
    /// Completed and every fixed point converged, but an energy-conserving (midpoint) variant
    /// has an (E.1) defect above [`DEFECT_TOLERANCE`] of the energy scale.
    EnergyDefect,
    /// Completed, every fixed point converged, (E.1) defect ≤ 1e-9 of the energy scale for the
    /// energy-conserving variants.
    Converged,
}

impl RunClass {
    pub const ALL: [RunClass; 7] = [
        RunClass::Converged,
        RunClass::EnergyDefect,
        RunClass::FixedPointCapped,
        RunClass::EnergyGrew,
        RunClass::NewtonFailed,
        RunClass::ClearError,
        RunClass::NonFinite,
    ];

    /// The name used in the CSV, the chart and the report.
    pub fn label(self) -> &'static str {
        match self {
            RunClass::Converged => "converged",
            RunClass::EnergyDefect => "E.1 defect",
            RunClass::FixedPointCapped => "fixed point capped",
            RunClass::EnergyGrew => "energy grew",
            RunClass::NewtonFailed => "newton failed",
            RunClass::ClearError => "clear error",
            RunClass::NonFinite => "non-finite",
        }
    }

    /// Two-letter code of the printed map.
    pub fn code(self) -> &'static str {
        match self {
            RunClass::Converged => "ok",
            RunClass::EnergyDefect => "df",
            RunClass::FixedPointCapped => "FP",
            RunClass::EnergyGrew => "EG",
            RunClass::NewtonFailed => "NF",
            RunClass::ClearError => "CE",
            RunClass::NonFinite => "NaN",
        }
    }

    fn color(self) -> RGBColor {
        match self {
            RunClass::Converged => style::PALETTE[2],
            RunClass::EnergyDefect => style::OLIVE,
            RunClass::FixedPointCapped => style::PALETTE[1],
            RunClass::EnergyGrew => style::PALETTE[3],
            RunClass::NewtonFailed => style::PALETTE[4],
            RunClass::ClearError => style::PALETTE[7],
            RunClass::NonFinite => BLACK,
        }
    }
}

/// A scheme with its solver options.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Variant {
    pub name: &'static str,
    pub scheme: SchemeKind,
    pub mass: MassKind,
    pub persistency: bool,
    pub inner: InnerSolver,
}

impl Variant {
    /// Midpoint-based variants satisfy (E.1) exactly (up to solver tolerance).
    pub fn energy_conserving(&self) -> bool {
        self.scheme == SchemeKind::Midpoint
    }

    /// Set the scheme and solver options on a scene. The map is of the paper's plain (F.1)
    /// iteration (`fixed_point_acceleration = "none"`): where it slows down and caps beyond
    /// (C.k) is what the map shows.
    pub fn apply(&self, s: &mut Scene) {
        s.solver.fixed_point_acceleration = FixedPointAcceleration::None;
        s.time.scheme = self.scheme;
        s.solver.mass = self.mass;
        s.solver.persistency = self.persistency;
        s.solver.inner = self.inner;
    }
}

/// The variants of the map (rows of every grid).
pub fn variants() -> Vec<Variant> {
    let v = |name, scheme, mass, persistency, inner| Variant { name, scheme, mass, persistency, inner };
    vec![
        v("midpoint", SchemeKind::Midpoint, MassKind::Lumped, false, InnerSolver::Newton),
        v("trapezoid", SchemeKind::Trapezoid, MassKind::Lumped, false, InnerSolver::Newton),
        v("backward-euler", SchemeKind::BackwardEuler, MassKind::Lumped, false, InnerSolver::Newton),
        v("midpoint+modified-mass", SchemeKind::Midpoint, MassKind::Modified, false, InnerSolver::Newton),
        v("midpoint+persistency", SchemeKind::Midpoint, MassKind::Lumped, true, InnerSolver::Newton),
        v("midpoint+newton-unfrozen", SchemeKind::Midpoint, MassKind::Lumped, false, InnerSolver::NewtonUnfrozen),
    ]
}

/// The variant of a given name.
pub fn variant(name: &str) -> Option<Variant> {
    variants().into_iter().find(|v| v.name == name)
}

/// The parameter a sweep varies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Sweep {
    /// time.step k (base scene)
    Step,
    /// contact.penalty ε with enforcement = penalty (base scene)
    Penalty,
    /// contact.friction.decay α (base scene)
    Decay,
    /// the factor on the initial velocity of impact_friction.toml
    Impact,
    /// solver.relaxation θ at k = BEYOND_CK_STEP (base scene)
    Relaxation,
    /// solver.max_newton_iterations (base scene)
    NewtonCap,
    /// contact.penalty ε on the impact scene made elastic (no viscosity): the stiff-penalty
    /// impact where a scheme without a discrete gradient can create energy
    ElasticImpactPenalty,
}

impl Sweep {
    pub const ALL: [Sweep; 7] = [
        Sweep::Step,
        Sweep::Penalty,
        Sweep::Decay,
        Sweep::Impact,
        Sweep::Relaxation,
        Sweep::NewtonCap,
        Sweep::ElasticImpactPenalty,
    ];

    /// Short name (CSV column `sweep`).
    pub fn key(self) -> &'static str {
        match self {
            Sweep::Step => "step",
            Sweep::Penalty => "penalty",
            Sweep::Decay => "decay",
            Sweep::Impact => "impact",
            Sweep::Relaxation => "relaxation",
            Sweep::NewtonCap => "newton-cap",
            Sweep::ElasticImpactPenalty => "impact-penalty",
        }
    }

    /// The varied parameter (scene key).
    pub fn parameter(self) -> &'static str {
        match self {
            Sweep::Step => "time.step",
            Sweep::Penalty => "contact.penalty",
            Sweep::Decay => "contact.friction.decay",
            Sweep::Impact => "initial.velocity factor",
            Sweep::Relaxation => "solver.relaxation",
            Sweep::NewtonCap => "solver.max_newton_iterations",
            Sweep::ElasticImpactPenalty => "contact.penalty",
        }
    }

    fn title(self) -> String {
        match self {
            Sweep::Step => "time step k (academic 16×8)".into(),
            Sweep::Penalty => "penalty ε (P_ε, k = 5e-4)".into(),
            Sweep::Decay => "friction decay α (k = 5e-4)".into(),
            Sweep::Impact => "impact velocity × v0 (impact_friction)".into(),
            Sweep::Relaxation => format!("relaxation θ of F.1 (k = {BEYOND_CK_STEP:.0e} > C.k)"),
            Sweep::NewtonCap => "max Newton iterations (k = 5e-4)".into(),
            Sweep::ElasticImpactPenalty => "penalty ε, elastic impact (impact_friction, no viscosity)".into(),
        }
    }

    fn format_value(self, v: f64) -> String {
        match self {
            _ if v == 0.0 => "0".into(),
            Sweep::Step | Sweep::Penalty | Sweep::ElasticImpactPenalty => {
                format!("{v:.3e}").replace(".000e", "e").replace(".500e", ".5e").replace(".250e", ".25e")
            }
            _ => format!("{v}"),
        }
    }

    /// The values of the full sweep.
    pub fn values(self) -> Vec<f64> {
        match self {
            Sweep::Step => vec![1.25e-4, 2.5e-4, 5e-4, 1e-3, 2e-3, 4e-3],
            // ε = 0 (the limit, Problem P) is not a valid penalty: the clear-error column
            Sweep::Penalty => vec![1e-3, 1e-5, 1e-7, 1e-9, 1e-12, 0.0],
            Sweep::Decay => vec![20.0, 100.0, 500.0, 2000.0],
            Sweep::Impact => vec![0.5, 1.0, 4.0, 16.0],
            Sweep::Relaxation => vec![1.0, 0.7, 0.4],
            Sweep::NewtonCap => vec![50.0, 4.0, 2.0, 1.0],
            Sweep::ElasticImpactPenalty => vec![1e-3, 1e-5, 1e-7, 1e-9, 1e-12],
        }
    }

    /// The sweep of a case label's key (`Sweep::key`).
    pub fn from_key(key: &str) -> Option<Sweep> {
        Sweep::ALL.into_iter().find(|s| s.key() == key)
    }

    /// Values of the full sweep that no scene may take (a sweep refuses such a point before
    /// anything runs): the map records them as refused with their validation error.
    pub fn refused_values(self) -> Vec<f64> {
        match self {
            Sweep::Penalty => vec![0.0],
            _ => Vec::new(),
        }
    }

    /// The values of the quick sweep (the extreme ones).
    pub fn quick_values(self) -> Vec<f64> {
        match self {
            Sweep::Step => vec![5e-4, 4e-3],
            Sweep::Penalty => vec![1e-12],
            Sweep::Decay => vec![2000.0],
            Sweep::Impact => vec![16.0],
            Sweep::Relaxation => vec![0.4],
            Sweep::NewtonCap => vec![1.0],
            Sweep::ElasticImpactPenalty => vec![1e-7],
        }
    }
}

/// The base scene: the embedded academic scene on 16 × 8 cells, horizon `end`, k = 5e-4.
pub fn base_scene(end: f64) -> Scene {
    let mut s = Scene::default_scene();
    s.name = "stability".into();
    s.domain.cells = Some([16, 8].to_vec());
    s.time.end = end;
    s.time.step = BASE_STEP;
    s
}

const IMPACT_SCENE: &str =
    include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/../fixtures/scenes/impact_friction.toml"));

/// fixtures/scenes/impact_friction.toml (embedded) with horizon `end` (its k = 5e-4).
pub fn impact_scene(end: f64) -> Result<Scene> {
    let mut s = Scene::from_toml(IMPACT_SCENE, "fixtures/scenes/impact_friction.toml")?;
    s.time.end = end;
    Ok(s)
}

/// One run of the map: a sweep, its parameter value and a variant.
#[derive(Debug, Clone, Copy)]
pub struct MapRun {
    pub sweep: Sweep,
    pub value: f64,
    pub variant: Variant,
}

impl MapRun {
    /// The scene of this case with horizon `end`.
    pub fn scene(&self, end: f64) -> Result<Scene> {
        let mut s = match self.sweep {
            Sweep::Impact | Sweep::ElasticImpactPenalty => impact_scene(end.min(IMPACT_END))?,
            _ => base_scene(end),
        };
        let v = self.value;
        match self.sweep {
            Sweep::Step => s.time.step = v,
            Sweep::Penalty | Sweep::ElasticImpactPenalty => {
                if self.sweep == Sweep::ElasticImpactPenalty {
                    s.material.viscosity.theta = 0.0;
                    s.material.viscosity.zeta = 0.0;
                }
                if let Some(c) = s.contact.as_mut() {
                    c.enforcement = EnforcementKind::Penalty;
                    c.penalty = Some(v);
                }
            }
            Sweep::Decay => {
                if let Some(c) = s.contact.as_mut() {
                    c.friction.decay = Some(v);
                }
            }
            Sweep::Impact => {
                let v0 = s.initial.velocity.clone().unwrap_or_else(|| vec!["0".into(), "0".into()]);
                let (a, b) = (&v0[0], &v0[1]);
                s.initial.velocity = Some(vec![format!("{v}*({a})"), format!("{v}*({b})")]);
            }
            Sweep::Relaxation => {
                s.time.step = BEYOND_CK_STEP;
                s.solver.relaxation = v;
            }
            Sweep::NewtonCap => s.solver.max_newton_iterations = v as i64,
        }
        self.variant.apply(&mut s);
        Ok(s)
    }
}

/// What one run measured.
#[derive(Debug, Clone)]
pub struct Measured {
    pub class: RunClass,
    pub steps_completed: usize,
    pub steps_planned: usize,
    pub k: f64,
    /// (C.k) limit of the run's problem as `ModelInfo` gives it (None: no limit or not built)
    pub ck_limit: Option<f64>,
    /// the (C.k) limit for this run's scheme: `ck_limit` is derived for the midpoint slip
    /// rate v̄ = (v^n + v^{n+1})/2; backward Euler's friction sees v^{n+1}, which doubles the
    /// concave part of the step functional and halves the limit
    /// fixed-point iterations (convex solves) per step: mean and max over completed steps
    pub fp_mean: f64,
    pub fp_max: usize,
    /// steps that hit max_fixed_point_iterations
    pub fp_capped_steps: usize,
    /// inner (Newton) iterations: total and largest per step
    pub newton_total: usize,
    pub newton_max: usize,
    /// newton-unfrozen only: steps that fell back to F.1
    pub fallbacks: usize,
    /// max_n |(E.1) defect_n| / scale_n
    pub max_defect: f64,
    /// Σ_n (E.1) defect_n / final scale: the net energy the scheme created (> 0) or destroyed
    /// (< 0) numerically over the run
    pub drift: f64,
    /// max_n (E^n − E^0 − W^n) / scale_n: the largest net gain over the loads' work
    pub max_gain: f64,
    /// the final energy terms (t of the last completed step)
    pub final_energy: EnergyTerms,
    /// the final energy scale
    pub scale: f64,
    pub wall_time_s: f64,
    /// the error that stopped the run, or other remarks
    pub note: String,
}

/// The stored energy E = kinetic + elastic + compliance.
pub fn stored(e: &EnergyTerms) -> f64 {
    e.kinetic + e.elastic + e.compliance
}

/// The class of a run from its facts (see [`RunClass`] for the precedence): `failure_kind` is
/// the kind of the error that stopped it (summary.json's `failure_kind`, [`Error::kind`] in
/// process), so a run measured in process and one read from its folder are classified by the
/// same rule.
pub fn classify(
    failure_kind: Option<FailureKind>,
    non_finite: bool,
    m: &Measured,
    energy_conserving: bool,
) -> RunClass {
    match failure_kind {
        _ if non_finite => RunClass::NonFinite,
        Some(FailureKind::NonFinite) => RunClass::NonFinite,
        Some(FailureKind::Solver) => RunClass::NewtonFailed,
        Some(_) => RunClass::ClearError,
        None if m.max_gain > GAIN_TOLERANCE => RunClass::EnergyGrew,
        None if m.fp_capped_steps > 0 => RunClass::FixedPointCapped,
        None if energy_conserving && m.max_defect > DEFECT_TOLERANCE => RunClass::EnergyDefect,
        None => RunClass::Converged,
    }
}

/// Run `scene` to its end (or its first error) and classify the run.
pub fn run_scene(scene: &Scene, energy_conserving: bool) -> Measured {
    let clock = Instant::now();
    let mut m = Measured::empty((scene.time.end / scene.time.step).round() as usize, scene.time.step);
    let (stop, non_finite) = simulate(scene, &mut m);
    if let Some(e) = &stop {
        m.note = e.to_string();
    } else if non_finite {
        m.note = format!("a non-finite energy term reached the caller at step {}", m.steps_completed + 1);
    }
    if !m.max_gain.is_finite() {
        m.max_gain = 0.0;
    }
    m.class = classify(stop.as_ref().map(Error::kind), non_finite, &m, energy_conserving);
    m.wall_time_s = clock.elapsed().as_secs_f64();
    m
}

impl Measured {
    /// Nothing measured yet (a run of `steps` steps of size `k`).
    pub fn empty(steps: usize, k: f64) -> Measured {
        Measured {
            class: RunClass::Converged,
            steps_completed: 0,
            steps_planned: steps,
            k,
            ck_limit: None,
            fp_mean: 0.0,
            fp_max: 0,
            fp_capped_steps: 0,
            newton_total: 0,
            newton_max: 0,
            fallbacks: 0,
            max_defect: 0.0,
            drift: 0.0,
            max_gain: f64::NEG_INFINITY,
            final_energy: EnergyTerms::default(),
            scale: 0.0,
            wall_time_s: 0.0,
            note: String::new(),
        }
    }
}

/// The time loop of [`run_scene`]: fills `m`, returns the stopping error and whether a
/// non-finite value reached the caller.
fn simulate(scene: &Scene, m: &mut Measured) -> (Option<Error>, bool) {
    let problem = match Problem::from_scene(scene, Path::new(".")) {
        Ok(p) => p,
        Err(e) => return (Some(e), false),
    };
    m.ck_limit = ModelInfo::of(&problem).ck_step_limit;
    m.steps_planned = problem.steps;
    let mut sim = match Simulation::new(&problem) {
        Ok(s) => s,
        Err(e) => return (Some(e), false),
    };
    let mut tally = Tally::new(stored(&sim.state.energy));
    m.final_energy = sim.state.energy;
    let mut out = (None, false);
    for rec in sim.steps() {
        let rec = match rec {
            Ok(r) => r,
            Err(e) => {
                out.0 = Some(e);
                break;
            }
        };
        let e = rec.energy;
        if e.to_array().iter().chain([&rec.energy_scale]).any(|x| !x.is_finite()) {
            out.1 = true;
            break;
        }
        let r = &rec.report;
        m.fallbacks += usize::from(r.fallback.is_some());
        tally.step(m, e, rec.energy_scale, r.fixed_point_iterations, r.fixed_point_converged(), r.inner_iterations);
    }
    tally.finish(m);
    out
}

/// The per-step sums of a run's [`Measured`], the same for a run in process and one read from
/// its files: the stored energy at t = 0, the fixed-point iterations, the (E.1) defects.
struct Tally {
    e0: f64,
    fp_sum: usize,
    cum_defect: f64,
}

impl Tally {
    fn new(e0: f64) -> Tally {
        Tally { e0, fp_sum: 0, cum_defect: 0.0 }
    }
    /// One completed step: its energy terms, energy scale, convex solves (and whether F.1
    /// converged) and Newton iterations.
    fn step(&mut self, m: &mut Measured, e: EnergyTerms, energy_scale: f64, fp: usize, converged: bool, newton: usize) {
        m.steps_completed += 1;
        self.fp_sum += fp;
        m.fp_max = m.fp_max.max(fp);
        m.fp_capped_steps += usize::from(!converged);
        m.newton_total += newton;
        m.newton_max = m.newton_max.max(newton);
        let scale = energy_scale.max(f64::MIN_POSITIVE);
        m.max_defect = m.max_defect.max(e.residual.abs() / scale);
        self.cum_defect += e.residual;
        m.max_gain = m.max_gain.max((stored(&e) - self.e0 - e.external_work) / scale);
        m.final_energy = e;
        m.scale = scale;
    }
    fn finish(self, m: &mut Measured) {
        if m.steps_completed > 0 {
            m.fp_mean = self.fp_sum as f64 / m.steps_completed as f64;
            m.drift = self.cum_defect / m.scale;
        }
    }
}

/// One row of the map.
#[derive(Debug, Clone)]
pub struct RunResult {
    pub case: MapRun,
    pub m: Measured,
}

/// Run one case of the map in this process (horizon [`QUICK_END`] or [`FULL_END`]): the map
/// itself runs its cases as sweeps ([`map_runs`]); this is what a test compares that path with.
pub fn run_case(case: &MapRun, quick: bool) -> RunResult {
    let end = if quick { QUICK_END } else { FULL_END };
    let m = match case.scene(end) {
        Ok(s) => run_scene(&s, case.variant.energy_conserving()),
        Err(e) => {
            let mut m = Measured::empty(0, f64::NAN);
            m.class = RunClass::ClearError;
            m.note = e.to_string();
            m
        }
    };
    RunResult { case: *case, m }
}

/// Every case of the sweep, sweep by sweep, value by value, variant by variant.
pub fn cases(quick: bool) -> Vec<MapRun> {
    let mut out = Vec::new();
    for sweep in Sweep::ALL {
        let values = if quick { sweep.quick_values() } else { sweep.values() };
        for value in values {
            for variant in variants() {
                out.push(MapRun { sweep, value, variant });
            }
        }
    }
    out
}

/// The map's sweep files (fixtures/sweeps/stability_*.toml) with their base scenes, embedded
/// so the map runs from any folder: the academic scene's cases and the impact's.
const SWEEPS: [(&str, &str, &str); 2] = [
    (
        "stability_academic.toml",
        include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/../fixtures/sweeps/stability_academic.toml")),
        dyncontact::scene::DEFAULT_SCENE,
    ),
    (
        "stability_impact.toml",
        include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/../fixtures/sweeps/stability_impact.toml")),
        IMPACT_SCENE,
    ),
];

/// A case label of the sweep files, "<sweep key> <value>".
pub fn parse_case(label: &str) -> Option<(Sweep, f64)> {
    let (key, value) = label.split_once(' ')?;
    Some((Sweep::from_key(key)?, value.parse().ok()?))
}

/// The map's sweeps resolved (every point validated): the full map, or the quick one (each
/// case's quick values, horizon [`QUICK_END`]).
pub fn plans(quick: bool) -> Result<Vec<(SweepFile, Base, Plan)>> {
    let mut out = Vec::new();
    for (file, text, base_text) in SWEEPS {
        let mut sweep = dyncontact::sweep::parse(text, &format!("fixtures/sweeps/{file}"))?;
        let extra = if quick {
            // keep the cases whose value is among its sweep's quick values
            let case = &mut sweep.axes[0];
            let keep: Vec<bool> = case
                .labels
                .iter()
                .map(|l| parse_case(l).is_some_and(|(sw, v)| sw.quick_values().contains(&v)))
                .collect();
            let mut k = keep.iter();
            case.sets.retain(|_| *k.next().unwrap_or(&false));
            let mut k = keep.iter();
            case.labels.retain(|_| *k.next().unwrap_or(&false));
            vec![dyncontact::overrides::Override::new("time.end", toml::Value::Float(QUICK_END))?]
        } else {
            Vec::new()
        };
        let base = Base {
            text: base_text.to_string(),
            label: format!("the base of fixtures/sweeps/{file}"),
            dir: std::path::PathBuf::from("."),
        };
        let plan = Plan::resolve_with(&sweep, &base, &extra)?;
        out.push((sweep, base, plan));
    }
    Ok(out)
}

/// Run the map's sweeps under `out/sweeps/` (`out/sweeps-quick/` for the quick map: its scenes
/// are others, and a sweep folder never drops completed points) (in parallel, `opts.jobs` at
/// once; points completed earlier with the same scene are skipped) and read every point back as a [`RunResult`], with
/// the refused values added: in the order of [`cases`].
pub fn map_runs(out: &Path, opts: &StabilityOptions) -> Result<Vec<RunResult>> {
    let jobs =
        if opts.jobs == 0 { std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1) } else { opts.jobs };
    let mut found: Vec<RunResult> = Vec::new();
    for (sweep, base, plan) in plans(opts.quick)? {
        let dir = out.join(if opts.quick { "sweeps-quick" } else { "sweeps" }).join(&plan.name);
        let done = plan.write(&dir, &dyncontact::sweep::snakemake::this_executable())?;
        runner::run_points(&plan, &dir, &done, &RunnerOptions { jobs, progress: false, interrupt: None })?;
        for p in &plan.points {
            let case_label = &plan.axes[0].labels[p.choice[0]];
            let variant_label = &plan.axes[1].labels[p.choice[1]];
            let (Some((sw, value)), Some(v)) = (parse_case(case_label), variant(variant_label)) else {
                return Err(Error::folder(
                    &dir,
                    format!(
                        "point {} has the case {case_label:?} / variant {variant_label:?}, which the map does not know",
                        p.id
                    ),
                ));
            };
            let m = measure_point(&Plan::point_dir(&dir, &p.id), v.energy_conserving())?;
            found.push(RunResult { case: MapRun { sweep: sw, value, variant: v }, m });
        }
        // the refused values of this file's sweeps, validated as the points would be
        if !opts.quick {
            for sw in Sweep::ALL {
                for value in sw.refused_values() {
                    let Some(proto) = plan
                        .points
                        .iter()
                        .find(|p| parse_case(&plan.axes[0].labels[p.choice[0]]).is_some_and(|(s, _)| s == sw))
                    else {
                        continue;
                    };
                    let case_set = &plan.axes[0].overrides[proto.choice[0]];
                    for (vi, v) in variants().into_iter().enumerate() {
                        let mut ovs: Vec<dyncontact::overrides::Override> = case_set
                            .iter()
                            .map(|o| {
                                if o.key == "contact.penalty" {
                                    dyncontact::overrides::Override { value: toml::Value::Float(value), ..o.clone() }
                                } else {
                                    o.clone()
                                }
                            })
                            .collect();
                        ovs.extend(plan.axes[1].overrides[vi].iter().cloned());
                        found.push(RunResult {
                            case: MapRun { sweep: sw, value, variant: v },
                            m: refused(dyncontact::sweep::scene_for(&sweep, &base, &ovs)),
                        });
                    }
                }
            }
        }
    }
    // the order of `cases`, with the refused values where the full sweep lists them
    let mut rows = Vec::with_capacity(found.len());
    for c in cases(opts.quick) {
        let pos = found
            .iter()
            .position(|r| r.case.sweep == c.sweep && r.case.value == c.value && r.case.variant.name == c.variant.name);
        match pos {
            Some(i) => rows.push(found.swap_remove(i)),
            None => {
                return Err(Error::Study(format!(
                    "the map's sweeps have no run of {} = {} / {}",
                    c.sweep.key(),
                    c.value,
                    c.variant.name
                )));
            }
        }
    }
    for r in &rows {
        eprintln!(
            "{:<10} {:<10} {:<24} {:<18} {:>5}/{:<5} steps {:>7.2} s",
            r.case.sweep.key(),
            r.case.sweep.format_value(r.case.value),
            r.case.variant.name,
            r.m.class.label(),
            r.m.steps_completed,
            r.m.steps_planned,
            r.m.wall_time_s
        );
    }
    Ok(rows)
}

/// The measure of a value no scene may take: the error its scene is refused with (a clear error).
fn refused(scene: Result<Scene>) -> Measured {
    let planned =
        scene.as_ref().map(|s| ((s.time.end / s.time.step).round() as usize, s.time.step)).unwrap_or((0, f64::NAN));
    let mut m = Measured::empty(planned.0, planned.1);
    let e = match scene.and_then(|s| s.validate().map(|_| ())) {
        Err(e) => e,
        Ok(()) => Error::Study("expected to be refused, but the scene is valid".into()),
    };
    m.class = RunClass::ClearError;
    m.note = e.to_string();
    m.max_gain = 0.0;
    m
}

/// The [`Measured`] of a run from its folder (history.csv, summary.json) — the same numbers
/// [`run_scene`] finds in process (tested): the per-step (E.1) defects, fixed-point and Newton
/// counts and energies of history.csv, the steps, k, (C.k) limit, fallbacks, wall time and
/// failure (kind and message) of summary.json; a row with a non-finite energy term ends the
/// run there, as a non-finite value reaching the caller.
pub fn measure_point(pd: &Path, energy_conserving: bool) -> Result<Measured> {
    let summary = Summary::read(pd).ok_or_else(|| {
        Error::folder(pd.join("summary.json"), "missing or not a summary of this version: the point cannot be measured")
    })?;
    let (steps, k) = match &summary.run {
        Some(d) => (d.model.steps, d.model.step),
        None => {
            // a run that could not start: its scene says what it would have run
            let s = Scene::from_file(&pd.join("scene.toml"))?;
            ((s.time.end / s.time.step).round() as usize, s.time.step)
        }
    };
    let mut m = Measured::empty(steps, k);
    if let Some(d) = &summary.run {
        m.ck_limit = d.model.ck_step_limit;
        m.fallbacks = d.unfrozen_fallbacks;
        m.wall_time_s = d.wall_time_s;
    }
    let mut non_finite = false;
    if let Some(h) = dyncontact::sweep::collect::History::read(&pd.join("history.csv")) {
        let col = |name: &str| {
            h.numbers(name).ok_or_else(|| Error::folder(pd.join("history.csv"), format!("no column {name}")))
        };
        let terms: Vec<Vec<f64>> = [
            "kinetic",
            "elastic",
            "compliance",
            "external_work",
            "viscous_dissipation",
            "friction_dissipation",
            "constraint_dissipation",
            "persistency_dissipation",
            "energy_residual",
            "energy_scale",
        ]
        .iter()
        .map(|n| col(n))
        .collect::<Result<_>>()?;
        let (fp, converged, newton) =
            (col("fixed_point_iterations")?, col("fixed_point_converged")?, col("newton_iterations")?);
        let energy = |r: usize| EnergyTerms::from_array(std::array::from_fn(|j| terms[j][r]));
        if !h.rows.is_empty() {
            let mut tally = Tally::new(stored(&energy(0)));
            m.final_energy = energy(0);
            for r in 1..h.rows.len() {
                if terms.iter().any(|t| !t[r].is_finite()) {
                    non_finite = true;
                    break;
                }
                tally.step(&mut m, energy(r), terms[9][r], fp[r] as usize, converged[r] != 0.0, newton[r] as usize);
            }
            tally.finish(&mut m);
        }
    }
    let failed = summary.status == RunStatus::Failed;
    if non_finite {
        m.note = format!("a non-finite energy term reached the caller at step {}", m.steps_completed + 1);
    } else if failed {
        m.note = summary.failure.clone().unwrap_or_default();
    }
    if !m.max_gain.is_finite() {
        m.max_gain = 0.0;
    }
    m.class = classify(if failed { summary.failure_kind } else { None }, non_finite, &m, energy_conserving);
    Ok(m)
}

/// The CSV header of stability.csv.
pub const CSV_HEADER: &str = "sweep,parameter,value,variant,scheme,mass,persistency,inner,class,steps_completed,steps_planned,k,\
ck_limit,fp_mean,fp_max,fp_capped_steps,newton_total,newton_max_step,unfrozen_fallbacks,max_e1_defect,energy_drift,\
max_energy_gain,wall_time_s,note";

/// stability.csv: one row per run.
pub fn csv(rows: &[RunResult]) -> String {
    csv_table(
        CSV_HEADER,
        rows.iter().map(|r| {
            let (v, m) = (&r.case.variant, &r.m);
            vec![
                r.case.sweep.key().to_string(),
                r.case.sweep.parameter().to_string(),
                r.case.value.to_string(),
                v.name.to_string(),
                kinds::name(&v.scheme),
                kinds::name(&v.mass),
                v.persistency.to_string(),
                kinds::name(&v.inner),
                m.class.label().to_string(),
                m.steps_completed.to_string(),
                m.steps_planned.to_string(),
                m.k.to_string(),
                m.ck_limit.map(|v| format!("{v:.4e}")).unwrap_or_default(),
                format!("{:.4}", m.fp_mean),
                m.fp_max.to_string(),
                m.fp_capped_steps.to_string(),
                m.newton_total.to_string(),
                m.newton_max.to_string(),
                m.fallbacks.to_string(),
                format!("{:.3e}", m.max_defect),
                format!("{:.4e}", m.drift),
                format!("{:.4e}", m.max_gain),
                format!("{:.4}", m.wall_time_s),
                csv_field(&m.note),
            ]
        }),
    )
}

/// The sweeps present in `rows`, in order, with their values in order.
fn layout(rows: &[RunResult]) -> Vec<(Sweep, Vec<f64>)> {
    let mut out: Vec<(Sweep, Vec<f64>)> = Vec::new();
    for r in rows {
        let pos = match out.iter().position(|(s, _)| *s == r.case.sweep) {
            Some(p) => p,
            None => {
                out.push((r.case.sweep, Vec::new()));
                out.len() - 1
            }
        };
        if !out[pos].1.contains(&r.case.value) {
            out[pos].1.push(r.case.value);
        }
    }
    out
}

fn find<'a>(rows: &'a [RunResult], sweep: Sweep, value: f64, variant: &str) -> Option<&'a RunResult> {
    rows.iter().find(|r| r.case.sweep == sweep && r.case.value == value && r.case.variant.name == variant)
}

/// stability.svg: for each sweep a grid of parameter value (x) × variant (y), cells coloured by
/// class (annotated with the largest fixed-point count, or the step where the run stopped),
/// a red corner on the runs whose k exceeds their scheme's (C.k) limit, and a legend.
/// (83 lines: one chart drawn cell by cell; its layout constants read best in one place.)
pub fn svg(rows: &[RunResult]) -> Result<String> {
    let sweeps = layout(rows);
    let names: Vec<&'static str> = variants().iter().map(|v| v.name).collect();
    let (cols, panel_w, label_w, cell_h, head_h, foot_h) = (2usize, 680i32, 190i32, 26i32, 34i32, 40i32);
    let panel_h = head_h + cell_h * names.len() as i32 + foot_h;
    let panel_rows = sweeps.len().div_ceil(cols).max(1) as i32;
    let legend_h = 130i32;
    let (w, h) = (cols as i32 * panel_w, panel_rows * panel_h + legend_h + 40);
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (w as u32, h as u32)).into_drawing_area();
        let err = chart_error("stability.svg");
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let font = |size: i32| style::font(size).into_font();
        let centered = |size: i32| TextStyle::from(font(size)).pos(Pos::new(HPos::Center, VPos::Center));
        let right = |size: i32| TextStyle::from(font(size)).pos(Pos::new(HPos::Right, VPos::Center));
        root.draw(&Text::new(
            "Stability map: class of every run (one parameter varied at a time)",
            (w / 2, 18),
            centered(20),
        ))
        .map_err(|e| err(&e))?;
        for (p, (sweep, values)) in sweeps.iter().enumerate() {
            let (x0, y0) = ((p % cols) as i32 * panel_w, 36 + (p / cols) as i32 * panel_h);
            let grid_w = panel_w - label_w - 20;
            let cell_w = grid_w / values.len().max(1) as i32;
            let gx = x0 + label_w;
            let gy = y0 + head_h;
            root.draw(&Text::new(sweep.title(), (gx + grid_w / 2, y0 + 16), centered(15))).map_err(|e| err(&e))?;
            for (row, name) in names.iter().enumerate() {
                let yc = gy + row as i32 * cell_h + cell_h / 2;
                root.draw(&Text::new(name.to_string(), (gx - 8, yc), right(12))).map_err(|e| err(&e))?;
                for (col, &value) in values.iter().enumerate() {
                    let cx = gx + col as i32 * cell_w;
                    let cy = gy + row as i32 * cell_h;
                    let Some(r) = find(rows, *sweep, value, name) else {
                        continue;
                    };
                    let m = &r.m;
                    root.draw(&Rectangle::new([(cx, cy), (cx + cell_w, cy + cell_h)], m.class.color().filled()))
                        .map_err(|e| err(&e))?;
                    root.draw(&Rectangle::new([(cx, cy), (cx + cell_w, cy + cell_h)], WHITE.stroke_width(2)))
                        .map_err(|e| err(&e))?;
                    let text = match m.class {
                        RunClass::NewtonFailed | RunClass::NonFinite | RunClass::ClearError => {
                            format!("stop {}/{}", m.steps_completed, m.steps_planned)
                        }
                        _ if r.case.variant.inner == InnerSolver::NewtonUnfrozen => {
                            format!("fp ≤ {}, fb {}", m.fp_max, m.fallbacks)
                        }
                        _ => format!("fp ≤ {}", m.fp_max),
                    };
                    if m.ck_limit.is_some_and(|ck| m.k > ck) {
                        let corner =
                            vec![(cx + cell_w - 12, cy + 1), (cx + cell_w - 1, cy + 1), (cx + cell_w - 1, cy + 12)];
                        root.draw(&Polygon::new(corner, RED_CORNER.filled())).map_err(|e| err(&e))?;
                    }
                    let color = if m.class == RunClass::NonFinite { WHITE } else { BLACK };
                    root.draw(&Text::new(text, (cx + cell_w / 2, cy + cell_h / 2), centered(11).color(&color)))
                        .map_err(|e| err(&e))?;
                }
            }
            let fy = gy + cell_h * names.len() as i32;
            for (col, &value) in values.iter().enumerate() {
                let xc = gx + col as i32 * cell_w + cell_w / 2;
                root.draw(&Text::new(sweep.format_value(value), (xc, fy + 10), centered(12))).map_err(|e| err(&e))?;
            }
            root.draw(&Text::new(sweep.parameter(), (gx + grid_w / 2, fy + 28), centered(11))).map_err(|e| err(&e))?;
        }
        let ly = 36 + panel_rows * panel_h + 10;
        root.draw(&Text::new("class", (20, ly + 8), font(14))).map_err(|e| err(&e))?;
        for (i, class) in RunClass::ALL.iter().enumerate() {
            let (lx, lyy) = (20 + (i as i32 % 4) * 300, ly + 26 + (i as i32 / 4) * 26);
            let n = rows.iter().filter(|r| r.m.class == *class).count();
            root.draw(&Rectangle::new([(lx, lyy), (lx + 18, lyy + 16)], class.color().filled()))
                .map_err(|e| err(&e))?;
            root.draw(&Rectangle::new([(lx, lyy), (lx + 18, lyy + 16)], BLACK.stroke_width(1))).map_err(|e| err(&e))?;
            root.draw(&Text::new(format!("{} ({n} runs)", class.label()), (lx + 26, lyy + 2), font(13)))
                .map_err(|e| err(&e))?;
        }
        let (nx, ny) = (20, ly + 26 + 2 * 26 + 4);
        root.draw(&Polygon::new(vec![(nx, ny), (nx + 14, ny), (nx + 14, ny + 14)], RED_CORNER.filled()))
            .map_err(|e| err(&e))?;
        root.draw(&Text::new(
            "k above the run's (C.k) limit (ModelInfo's, halved for backward Euler; 0 with the modified mass).   \
             Cell text: largest fixed-point count of a step (fp ≤ N), or the steps completed when the run stopped; fb: steps where newton-unfrozen fell back to F.1.",
            (nx + 22, ny + 1),
            font(12),
        ))
        .map_err(|e| err(&e))?;
        root.present().map_err(|e| err(&e))?;
    }
    Ok(out)
}

/// The printed report: per sweep a map (variant × value, class codes), then one line per run.
pub fn report(rows: &[RunResult], wall_time_s: f64) -> String {
    let mut s = String::new();
    let names: Vec<&'static str> = variants().iter().map(|v| v.name).collect();
    s.push_str(&format!("stability map: {} runs in {:.1} s\n", rows.len(), wall_time_s));
    s.push_str("codes: ");
    for c in RunClass::ALL {
        s.push_str(&format!("{} = {}; ", c.code(), c.label()));
    }
    s.push('\n');
    for (sweep, values) in layout(rows) {
        s.push_str(&format!("\n{} ({})\n", sweep.title(), sweep.parameter()));
        s.push_str(&format!("{:<26}", "variant"));
        for v in &values {
            s.push_str(&format!("{:>10}", sweep.format_value(*v)));
        }
        s.push('\n');
        for name in &names {
            s.push_str(&format!("{name:<26}"));
            for v in &values {
                let code = find(rows, sweep, *v, name).map(|r| r.m.class.code()).unwrap_or("-");
                s.push_str(&format!("{code:>10}"));
            }
            s.push('\n');
        }
    }
    s.push_str(&format!(
        "\n{:<15}{:>8} {:<25}{:<19}{:>10}{:>8}{:>5}{:>6}{:>5}{:>8}{:>10}{:>11}{:>10}{:>8}\n",
        "sweep",
        "value",
        "variant",
        "class",
        "steps",
        "fp mean",
        "max",
        "caps",
        "fb",
        "newton",
        "max E.1",
        "drift",
        "max gain",
        "wall s"
    ));
    for r in rows {
        let m = &r.m;
        s.push_str(&format!(
            "{:<15}{:>8} {:<25}{:<19}{:>10}{:>8.2}{:>5}{:>6}{:>5}{:>8}{:>10.2e}{:>11.3e}{:>10.2e}{:>8.2}\n",
            r.case.sweep.key(),
            r.case.sweep.format_value(r.case.value),
            r.case.variant.name,
            m.class.label(),
            format!("{}/{}", m.steps_completed, m.steps_planned),
            m.fp_mean,
            m.fp_max,
            m.fp_capped_steps,
            m.fallbacks,
            m.newton_total,
            m.max_defect,
            m.drift,
            m.max_gain,
            m.wall_time_s
        ));
    }
    let stopped: Vec<&RunResult> = rows.iter().filter(|r| !r.m.note.is_empty()).collect();
    if !stopped.is_empty() {
        s.push_str("\nwhy runs stopped:\n");
        for r in stopped {
            s.push_str(&format!(
                "  {} = {} / {}: {}\n",
                r.case.sweep.key(),
                r.case.sweep.format_value(r.case.value),
                r.case.variant.name,
                r.m.note
            ));
        }
    }
    s
}

const RED_CORNER: RGBColor = RGBColor(200, 0, 0);

/// Run the map (its sweeps, in parallel) and write its CSV and SVG files under `out`.
pub fn run(out: &Path, opts: &StabilityOptions) -> Result<String> {
    let clock = Instant::now();
    let rows = map_runs(out, opts)?;
    let wall = clock.elapsed().as_secs_f64();
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    write_atomic(&out.join("stability.csv"), csv(&rows).as_bytes())?;
    write_atomic(&out.join("stability.svg"), svg(&rows)?.as_bytes())?;
    let mut s = report(&rows, wall);
    s.push_str(&format!(
        "\nwritten {} and {}\n",
        out.join("stability.csv").display(),
        out.join("stability.svg").display()
    ));
    Ok(s)
}
