//! `dyncontact study penalty`: the ε → 0 study of spec/model.md §5.3. The exact problem P (the
//! constraint with multipliers) and the penalty problem P_ε are run on the same mesh and step;
//! for each ε it reports
//!   e_V(ε) = max_n ‖u_ε^n − u^n‖_V / max_n ‖u^n‖_V   (‖v‖_V = ‖ε(v)‖_{L²}),
//!   e_H(ε) = max_n ‖v_ε^n − v^n‖_{L²} / max_n ‖v^n‖_{L²},
//!   δ(ε)   = max_{n,i} (u_ε,ν,i^n − g)_+ (the penetration beyond the bound),
//! and the least-squares log–log slopes of e_V, e_H and δ against ε. E.0 bounds δ by O(ε^½);
//! B.2 gives O(ε) under steady pressing. The runs are a sweep (fixtures/sweeps/penalty.toml:
//! the point "exact" and one point per ε, each writing trajectory.f64); [`collect`] reads them.

use std::path::Path;

use crate::error::{Error, Result};
use crate::failure::RunStatus;
use crate::fem::assemble::{assemble_full, restrict};
use crate::linalg::{self, SpMat};
use crate::model::kinds::{Bound, MassKind};
use crate::output::trajectory::{self, TrajectoryRecord};
use crate::overrides::Override;
use crate::problem::Problem;
use crate::scene::Scene;
use crate::sweep::runner::{self, RunnerOptions};
use crate::sweep::{Base, Plan, SweepFile};

use crate::output::csv::csv_table;
use crate::output::loglog::{self, LogSeries, loglog_slope};
use crate::output::write_files;

/// One row of the study.
#[derive(Debug, Clone, Copy)]
pub struct PenaltyRow {
    pub eps: f64,
    pub e_v: f64,
    pub e_h: f64,
    pub delta: f64,
    pub wall_time_s: f64,
}

/// The study's result: rows and fitted slopes (e_V, e_H, δ).
#[derive(Debug, Clone)]
pub struct PenaltyStudy {
    pub rows: Vec<PenaltyRow>,
    pub slope_e_v: f64,
    pub slope_e_h: f64,
    pub slope_delta: f64,
    pub reference_wall_time_s: f64,
}

/// The default ε list of spec/model.md §5.3.
pub const DEFAULT_EPS: [f64; 6] = [1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7];

/// ‖·‖_V (strain) and ‖·‖_{L²} (ρ = 1) Gram matrices on the free DOFs of `p`.
fn norm_matrices(p: &Problem) -> Result<(SpMat, SpMat)> {
    let mut unit = p.material;
    // ε(v):ε(v) = ε_xx² + ε_yy² + γ²/2: the operator with λ = 0, μ = ½ (and ρ = 1 for L²)
    unit.lambda = 0.0;
    unit.mu_lame = 0.5;
    unit.theta = 0.0;
    unit.zeta = 0.0;
    unit.rho = 1.0;
    let mesh = p.mesh.plane().ok_or_else(|| Error::Study("the penalty study runs on 2-D scenes".into()))?;
    let (m, k, _) = assemble_full(mesh, &unit, MassKind::Consistent)?;
    Ok((restrict(&k, &p.dofs)?, restrict(&m, &p.dofs)?))
}

fn norm(a: &SpMat, x: &[f64]) -> f64 {
    linalg::quad(a, x, x).max(0.0).sqrt()
}

/// (E.0) The penetration beyond the bound of one step, max_i (u_ν,i − g)_+ = (max_i u_ν,i − g)_+
/// (rounding is monotone, so the two are the same number): the energy estimate of P_ε bounds it
/// by C ε^½ (the study measures the rate). `max_penetration` is history.csv's column.
pub fn penetration_beyond_bound(max_penetration: f64, g: f64) -> f64 {
    (max_penetration - g).max(0.0)
}

/// The study's sweep file (fixtures/sweeps/penalty.toml), embedded.
const SWEEP: &str = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/sweeps/penalty.toml"));

/// The label of the reference point (exact enforcement) on the sweep's `eps` axis.
pub const EXACT: &str = "exact";

/// The study's sweep: fixtures/sweeps/penalty.toml, with the ε list replaced when given (the
/// point "exact" and one point per ε).
pub fn sweep_file(eps_list: Option<&[f64]>) -> Result<SweepFile> {
    let mut sweep = crate::sweep::parse(SWEEP, "fixtures/sweeps/penalty.toml")?;
    if let Some(eps) = eps_list {
        if let Some(e) = eps.iter().find(|e| !(e.is_finite() && **e > 0.0)) {
            return Err(Error::scene("--eps", format!("every ε must be a finite number > 0, got {e}")));
        }
        let mut distinct = eps.to_vec();
        distinct.sort_by(f64::total_cmp);
        distinct.dedup();
        if distinct.len() < 2 {
            return Err(Error::scene(
                "--eps",
                format!("the study fits log–log slopes: it needs at least two different values of ε, got {eps:?}"),
            ));
        }
        if distinct.len() < eps.len() {
            return Err(Error::scene("--eps", format!("a value of ε is given twice: {eps:?}")));
        }
        let axis = &mut sweep.axes[0];
        axis.sets.truncate(1);
        axis.labels.truncate(1);
        for &e in eps {
            let mut t = toml::Table::new();
            t.insert("contact.enforcement".into(), toml::Value::String("penalty".into()));
            t.insert("contact.penalty".into(), toml::Value::Float(e));
            axis.sets.push(t);
            axis.labels.push(format!("{e:e}"));
        }
    }
    Ok(sweep)
}

/// The base scene without `contact.enforcement` and `contact.penalty` (the study's points set
/// them); its text unchanged when it has neither.
fn without_penalty(base: &Base) -> Result<Base> {
    let mut table: toml::Table =
        base.text.parse().map_err(|e: toml::de::Error| crate::scene::parse::syntax_error(&base.label, "", &e))?;
    let Some(toml::Value::Table(contact)) = table.get_mut("contact") else { return Ok(base.clone()) };
    let (had_enforcement, had_penalty) = (contact.remove("enforcement").is_some(), contact.remove("penalty").is_some());
    if !had_enforcement && !had_penalty {
        return Ok(base.clone());
    }
    let text = toml::to_string(&table).map_err(|e| Error::Output(format!("{}: {e}", base.label)))?;
    Ok(Base { text, label: base.label.clone(), dir: base.dir.clone() })
}

/// Run the study: the sweep of the ε list (default: the file's) on `base` with `overrides`,
/// its points in `work` (`jobs` at once; points completed earlier with the same scene are
/// skipped), then the collector. The scene must have contact with a finite penetration bound.
/// `launcher`: the command the sweep's Snakefile runs `dyncontact` with.
pub fn penalty_study(
    base: &Base,
    overrides: &[Override],
    eps_list: Option<&[f64]>,
    work: &Path,
    jobs: usize,
    launcher: &[String],
) -> Result<PenaltyStudy> {
    let sweep = sweep_file(eps_list)?;
    // the study sets the enforcement and ε of every point: a base scene's own penalty would
    // make its exact reference point invalid
    let base = &without_penalty(base)?;
    let scene = crate::sweep::scene_for(&sweep, base, overrides)?;
    if scene.boundary.contact.is_empty() {
        return Err(Error::scene("boundary.contact", "the penalty study needs a scene with a contact side"));
    }
    let c = scene
        .contact
        .as_ref()
        .ok_or_else(|| Error::scene("contact", "the penalty study needs a scene with contact"))?;
    if Scene::bound_of(c)? == Bound::Infinite {
        return Err(Error::scene(
            "contact.penetration_bound",
            "the penalty study needs a finite g (it penalizes u_ν > g)",
        ));
    }
    let plan = Plan::resolve_with(&sweep, base, overrides)?;
    let done = plan.write(work, launcher)?;
    let outcomes =
        runner::run_points(&plan, work, &done, &RunnerOptions { jobs: jobs.max(1), progress: false, interrupt: None })?;
    // a point that failed before its run wrote a summary (its folder refused, say): the
    // runner's reason, which `collect` cannot read from the folder
    for (point, outcome) in plan.points.iter().zip(&outcomes) {
        let pd = Plan::point_dir(work, &point.id);
        if let runner::Outcome::Failed(reason) = outcome
            && crate::sweep::collect::point_status(&pd).is_none()
        {
            return Err(Error::Study(format!(
                "point {} of the penalty study failed without a summary: {reason} ({})",
                point.id,
                pd.display()
            )));
        }
    }
    collect(&plan, work)
}

/// The study from its sweep's folder `dir`: e_V, e_H and δ of every ε point against the point
/// "exact", from their trajectory.f64 and history.csv (the steps paired one to one).
pub fn collect(plan: &Plan, dir: &Path) -> Result<PenaltyStudy> {
    let axis = &plan.axes[0];
    let point = |label: &str| plan.points.iter().find(|p| axis.labels[p.choice[0]] == label);
    let exact_point = point(EXACT).ok_or_else(|| Error::folder(dir, format!("the sweep has no point {EXACT:?}")))?;
    let exact_dir = Plan::point_dir(dir, &exact_point.id);
    let failed = |pd: &Path, id: &str| -> Result<()> {
        match crate::sweep::collect::point_status(pd) {
            Some(RunStatus::Completed) => Ok(()),
            other => Err(Error::Study(format!(
                "point {id} of the penalty study ended {:?}: see {}",
                other.map_or("without a summary", RunStatus::as_str),
                pd.join("summary.json").display()
            ))),
        }
    };
    failed(&exact_dir, &exact_point.id)?;
    let exact = Problem::from_scene(&Scene::from_file(&exact_dir.join("scene.toml"))?, &exact_dir)?;
    let g = match exact.contact.as_ref().map(|c| c.bound) {
        Some(Bound::Finite(g)) => g,
        _ => return Err(Error::scene("contact.penetration_bound", "must be finite")),
    };
    let (kv, mh) = norm_matrices(&exact)?;
    // the reference trajectory: every step after t = 0
    let reference: Vec<TrajectoryRecord> =
        trajectory::read(&exact_dir.join("trajectory.f64"))?.into_iter().skip(1).collect();
    let reference_wall_time_s = wall_time(&exact_dir);
    let u_max = reference.iter().map(|r| norm(&kv, &r.u)).fold(0.0, f64::max).max(f64::MIN_POSITIVE);
    let v_max = reference.iter().map(|r| norm(&mh, &r.v)).fold(0.0, f64::max).max(f64::MIN_POSITIVE);
    let mut rows = Vec::new();
    for p in plan.points.iter().filter(|p| axis.labels[p.choice[0]] != EXACT) {
        let label = &axis.labels[p.choice[0]];
        let eps: f64 = label
            .parse()
            .map_err(|_| Error::Study(format!("point {}: the ε label {label:?} is not a number", p.id)))?;
        let pd = Plan::point_dir(dir, &p.id);
        failed(&pd, &p.id)?;
        let run = trajectory::read(&pd.join("trajectory.f64"))?;
        let penetration = crate::sweep::collect::History::read(&pd.join("history.csv"))
            .and_then(|h| h.numbers("max_penetration"))
            .unwrap_or_default();
        let (mut e_v, mut e_h, mut delta): (f64, f64, f64) = (0.0, 0.0, 0.0);
        for (n, r) in reference.iter().enumerate() {
            let Some(q) = run.get(n + 1) else { break };
            let du: Vec<f64> = q.u.iter().zip(&r.u).map(|(a, b)| a - b).collect();
            let dv: Vec<f64> = q.v.iter().zip(&r.v).map(|(a, b)| a - b).collect();
            e_v = e_v.max(norm(&kv, &du));
            e_h = e_h.max(norm(&mh, &dv));
            if let Some(&d) = penetration.get(n + 1) {
                delta = delta.max(penetration_beyond_bound(d, g));
            }
        }
        rows.push(PenaltyRow { eps, e_v: e_v / u_max, e_h: e_h / v_max, delta, wall_time_s: wall_time(&pd) });
    }
    let eps: Vec<f64> = rows.iter().map(|r| r.eps).collect();
    let col = |f: fn(&PenaltyRow) -> f64| rows.iter().map(f).collect::<Vec<f64>>();
    Ok(PenaltyStudy {
        slope_e_v: loglog_slope(&eps, &col(|r| r.e_v)),
        slope_e_h: loglog_slope(&eps, &col(|r| r.e_h)),
        slope_delta: loglog_slope(&eps, &col(|r| r.delta)),
        rows,
        reference_wall_time_s,
    })
}

/// summary.json's wall time of a point (0 when missing).
fn wall_time(pd: &Path) -> f64 {
    std::fs::read_to_string(pd.join("summary.json"))
        .ok()
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
        .and_then(|v| v.get("wall_time_s").and_then(serde_json::Value::as_f64))
        .unwrap_or(0.0)
}

impl PenaltyStudy {
    /// study/penalty.csv.
    pub fn csv(&self) -> String {
        csv_table(
            "eps,e_V,e_H,delta,wall_time_s",
            self.rows
                .iter()
                .map(|r| [r.eps, r.e_v, r.e_h, r.delta, r.wall_time_s].map(crate::output::csv::real).to_vec()),
        )
    }

    /// study/penalty.svg: e_V, e_H and δ against ε on log–log axes.
    pub fn svg(&self, title: &str) -> Result<String> {
        type Measure = (&'static str, f64, fn(&PenaltyRow) -> f64);
        let series: [Measure; 3] = [
            ("e_V", self.slope_e_v, |r| r.e_v),
            ("e_H", self.slope_e_h, |r| r.e_h),
            ("δ (penetration beyond g)", self.slope_delta, |r| r.delta),
        ];
        let series: Vec<LogSeries> = series
            .iter()
            .map(|(name, slope, f)| LogSeries {
                name: format!("{name}, slope {slope:.2}"),
                points: self.rows.iter().map(|r| (r.eps, f(r))).collect(),
            })
            .collect();
        loglog::loglog_chart("study/penalty.svg", title, ("ε (penalty compliance)", "error"), &series, (2.0, 3.0))
    }

    /// Write study/penalty.csv and study/penalty.svg under `dir`.
    pub fn write(&self, dir: &Path, title: &str) -> Result<()> {
        let svg = self.svg(title)?;
        write_files(&dir.join("study"), &[("penalty.csv", self.csv().as_bytes()), ("penalty.svg", svg.as_bytes())])
    }
}
