//! Work–precision benchmark (`dyncontact-studies bench`, run by `cargo xtask bench`).
//!
//! All runs use the academic scene (`Scene::default_scene()`: a 2×1 m Kelvin–Voigt block
//! clamped on the left, pressed onto a compliant foundation with a penetration bound, then
//! driven tangentially from t = 0.2 s under exponential velocity weakening), shortened to a
//! horizon T. Five parts:
//!
//! 1. **Work–precision** (`work_precision.csv`, `work_precision.svg`): schemes × inner solvers ×
//!    masses × levels of joint refinement (h and k halved together), each run's error against a
//!    fine reference and its wall time. Two error measures, both over the whole trajectory and
//!    computable across meshes:
//!    - `error_force`: the relative L²(0, T) error of the total contact force per unit thickness
//!      (F_ν, F_τ) (history rows `normal_force`, `tangential_force`). A step's force is the mean
//!      force over its step (impulse / k) for every scheme, so it is compared with the reference
//!      averaged over the same step: the error of the piecewise-constant force histories.
//!    - `error_disp`: the relative L²(0, T) error of the displacement at [`PROBES`], points that
//!      are nodes of every nested structured mesh, compared at the run's step times.
//! 2. **The floor**: per run, the time of two sparse triangular-solve pairs with the run's own
//!    factor of A_k (free solve + recovery solve: what a step with contact cost before the step
//!    split its pair around the contact solve; a step that splits now reads less, `Simulation::step`),
//!    and time per step ÷ floor.
//!    Also on the default scene itself (`floor.csv`): min and median over repeated runs.
//! 3. **The race** (`race.csv`, `race.svg`): `newton` (F.1, the paper's sequence of convex
//!    problems) against `newton-unfrozen` (N.4, F.1 as fallback) on the academic friction law and
//!    a 5× steeper one, at a k inside (C.k) and beyond it: time and linear-algebra work per step,
//!    and the largest per-step difference of their solutions from the same state.
//! 4. **Scaling** (`scaling.csv`, `scaling.svg`, studies/src/scaling.rs): the contact solve per
//!    step against the number of contact nodes, dense and sparse Delassus operator.
//! 5. **Bookkeeping** (`bookkeeping.csv`, studies/src/bookkeeping.rs): the share of a step spent
//!    outside the solves ((E.1) terms, records, outputs) at 66k unknowns.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use plotters::coord::Shift;
use plotters::prelude::*;

use dyncontact::error::{Error, Result};
use dyncontact::failure::ContactFailure;
use dyncontact::model::Model;
use dyncontact::model::kinds::{self, InnerSolver, MassKind, SchemeKind};
use dyncontact::output::style::{self, PALETTE, font};
use dyncontact::output::{ModelInfo, write_atomic};
use dyncontact::problem::Problem;
use dyncontact::scene::Scene;
use dyncontact::simulation::Simulation;
use dyncontact::step::fixed_point::Inner;
use dyncontact::step::newton::NewtonSettings;

use crate::convergence::{
    Level, RunStats, Trajectory, displacement_error, force_errors, impulse_error, joint_levels, probe_dofs, simulate,
};
use dyncontact::output::csv::{csv_field, csv_table};
use dyncontact::output::loglog::{chart_error, log_range, loglog_slope};

/// Options of the benchmark.
#[derive(Debug, Clone, Default)]
pub struct BenchOptions {
    /// a small configuration for smoke tests
    pub quick: bool,
    /// only part 2 on the default scene (floor.csv)
    pub floor_only: bool,
    /// only part 5 (bookkeeping.csv)
    pub bookkeeping_only: bool,
    /// only part 4b, the thick 3-D boxes (thick.csv, thick.svg)
    pub thick_only: bool,
    /// part 4b also runs 64×32×24 (158,400 unknowns, 2,112 contact nodes: minutes of setup, GBs)
    pub thick_largest: bool,
    /// part 4b also runs 80×40×32 and 96×48×32: pressed in the hierarchical form, and their
    /// shaking window (up to 465,696 unknowns and ~18 GB; 1,600 pressing steps each at
    /// 1.25e-4, inside (C.k): expect hours)
    pub thick_beyond: bool,
}

/// The columns of work_precision.csv.
pub const WORK_PRECISION_COLUMNS: &str = "scheme,inner,mass,cells,k,steps,wall_time_s,time_per_step_s,floor_s,ratio_to_floor,\
error_force,error_disp,newton_iterations,fixed_point_iterations,error_normal_force,error_tangential_force,error_impulse,status";

/// The columns of race.csv.
pub const RACE_COLUMNS: &str = "case,decay,k,ck_limit,inside_ck,method,steps,wall_time_s,time_per_step_s,contact_time_per_step_s,\
newton_iterations_per_step,fixed_point_iterations_per_step,unfrozen_steps,fallback_steps,setup_delassus_s,max_velocity_difference,\
max_force_difference,differing_steps,status";

/// Two methods differ on a step when their contact velocities or forces differ by more than
/// this, relative to the step's velocity and force scales (tests/solver/unfrozen.rs).
const AGREEMENT_TOLERANCE: f64 = 1e-6;

/// What the race runs: the mesh, the horizon, the friction laws (multiples of the scene's
/// decay α) and the steps beyond (C.k); the step inside (C.k) is derived from the limit.
#[derive(Debug, Clone)]
struct RacePlan {
    cells: [i64; 2],
    t_end: f64,
    decay_factors: Vec<f64>,
    beyond: Vec<f64>,
}

/// What the benchmark runs.
#[derive(Debug, Clone)]
struct BenchPlan {
    t_end: f64,
    /// coarse to fine; h and k halved together
    levels: Vec<Level>,
    reference: Level,
    schemes: Vec<SchemeKind>,
    inners: Vec<InnerSolver>,
    masses: Vec<MassKind>,
    /// the conic twin runs on the coarsest `conic_levels` levels only (it is ~30× slower)
    conic_levels: usize,
    race: RacePlan,
    /// repetitions of the default scene for time per step ÷ floor (min and median reported);
    /// its horizon (the scene's own end in the full plan)
    floor_repeats: usize,
    floor_end: Option<f64>,
    /// the same for the 3-D default fixture (academic3d, 24×12×8 cells: ~45 s a run)
    floor3d_repeats: usize,
    floor3d_end: Option<f64>,
}

impl BenchPlan {
    /// The full benchmark (~5 min in release): T = 0.3 s; the reference is one level finer than
    /// the finest bench level (two levels finer would cost ~8× the whole benchmark).
    fn full() -> BenchPlan {
        BenchPlan {
            t_end: 0.3,
            levels: joint_levels(4),
            reference: Level { cells: [128, 64], k: 1.25e-4 },
            schemes: vec![SchemeKind::Midpoint, SchemeKind::Trapezoid, SchemeKind::BackwardEuler],
            inners: vec![InnerSolver::Newton, InnerSolver::Conic],
            masses: vec![MassKind::Lumped, MassKind::Consistent],
            conic_levels: 3,
            race: RacePlan { cells: [32, 16], t_end: 0.5, decay_factors: vec![1.0, 5.0], beyond: vec![5e-4, 1e-3] },
            floor_repeats: 5,
            floor_end: None,
            floor3d_repeats: 2,
            floor3d_end: None,
        }
    }

    /// The smoke-test configuration: 2 levels, newton only, T = 0.05 s.
    fn quick() -> BenchPlan {
        BenchPlan {
            t_end: 0.05,
            levels: joint_levels(2),
            reference: Level { cells: [32, 16], k: 5e-4 },
            schemes: vec![SchemeKind::Midpoint, SchemeKind::Trapezoid, SchemeKind::BackwardEuler],
            inners: vec![InnerSolver::Newton],
            masses: vec![MassKind::Lumped, MassKind::Consistent],
            conic_levels: 0,
            race: RacePlan { cells: [16, 8], t_end: 0.05, decay_factors: vec![1.0, 5.0], beyond: vec![1e-3] },
            floor_repeats: 2,
            floor_end: Some(0.05),
            floor3d_repeats: 1,
            floor3d_end: Some(0.005),
        }
    }
}

/// One configuration of the work–precision sweep.
#[derive(Debug, Clone, Copy)]
struct RunSpec {
    scheme: SchemeKind,
    inner: InnerSolver,
    mass: MassKind,
    level: Level,
}

impl RunSpec {
    fn label(&self) -> String {
        format!(
            "{}/{}/{} {}x{} k={:e}",
            kinds::name(&self.scheme),
            kinds::name(&self.inner),
            kinds::name(&self.mass),
            self.level.cells[0],
            self.level.cells[1],
            self.level.k
        )
    }

    /// The academic scene at this configuration, shortened to `t_end`, validated.
    fn model(&self, t_end: f64) -> Result<Model> {
        let mut s = Scene::default_scene();
        s.domain.cells = Some(self.level.cells.to_vec());
        s.time.step = self.level.k;
        s.time.end = t_end;
        s.time.scheme = self.scheme;
        s.solver.inner = self.inner;
        s.solver.mass = self.mass;
        s.validate()
    }
}

/// One row of work_precision.csv.
#[derive(Debug, Clone)]
struct WorkRow {
    spec: RunSpec,
    stats: RunStats,
    /// [vector, normal, tangential]
    error_force: [f64; 3],
    /// force averaged over windows of the coarsest step
    error_impulse: f64,
    error_disp: f64,
    status: String,
}

impl WorkRow {
    fn time_per_step(&self) -> f64 {
        self.stats.step_time_s / self.stats.steps.max(1) as f64
    }
    fn ok(&self) -> bool {
        self.status == "ok"
    }
    fn group(&self) -> (SchemeKind, InnerSolver, MassKind) {
        (self.spec.scheme, self.spec.inner, self.spec.mass)
    }
}

/// Run one configuration and measure its errors against the reference; a failed run becomes a
/// row whose status says why (the conic twin can stall, and that is a result).
fn work_row(spec: RunSpec, plan: &BenchPlan, reference: &Trajectory) -> Result<WorkRow> {
    let p = Problem::new(spec.model(plan.t_end)?, Path::new("."))?;
    let probes = probe_dofs(&p)?;
    match simulate(&p, &probes) {
        Ok((traj, stats)) => Ok(WorkRow {
            spec,
            stats,
            error_force: force_errors(&traj, reference)?,
            error_impulse: impulse_error(&traj, reference, plan.levels[0].k)?,
            error_disp: displacement_error(&traj, reference)?,
            status: "ok".into(),
        }),
        Err(e) => Ok(WorkRow {
            spec,
            stats: RunStats { steps: p.steps, ..RunStats::default() },
            error_force: [f64::NAN; 3],
            error_impulse: f64::NAN,
            error_disp: f64::NAN,
            status: format!("failed: {e}"),
        }),
    }
}

/// The configurations of the sweep, conic restricted to the coarse levels.
fn run_specs(plan: &BenchPlan) -> Vec<RunSpec> {
    let mut v = Vec::new();
    for &scheme in &plan.schemes {
        for &inner in &plan.inners {
            for &mass in &plan.masses {
                for (l, &level) in plan.levels.iter().enumerate() {
                    if inner == InnerSolver::Conic && l >= plan.conic_levels {
                        continue;
                    }
                    v.push(RunSpec { scheme, inner, mass, level });
                }
            }
        }
    }
    v
}

/// work_precision.csv.
fn work_csv(rows: &[WorkRow]) -> String {
    csv_table(
        WORK_PRECISION_COLUMNS,
        rows.iter().map(|r| {
            let st = &r.stats;
            let tps = r.time_per_step();
            let ratio = if st.floor_s > 0.0 { tps / st.floor_s } else { f64::NAN };
            vec![
                kinds::name(&r.spec.scheme),
                kinds::name(&r.spec.inner),
                kinds::name(&r.spec.mass),
                format!("{}x{}", r.spec.level.cells[0], r.spec.level.cells[1]),
                format!("{:e}", r.spec.level.k),
                st.steps.to_string(),
                format!("{:.6e}", st.wall_time_s),
                format!("{tps:.6e}"),
                format!("{:.6e}", st.floor_s),
                format!("{ratio:.4}"),
                format!("{:.6e}", r.error_force[0]),
                format!("{:.6e}", r.error_disp),
                st.newton_iterations.to_string(),
                st.fixed_point_iterations.to_string(),
                format!("{:.6e}", r.error_force[1]),
                format!("{:.6e}", r.error_force[2]),
                format!("{:.6e}", r.error_impulse),
                csv_field(&r.status),
            ]
        }),
    )
}

/// Observed orders of one group: pairwise log2(e_l / e_{l+1}) between consecutive levels (h and k
/// halve together) and the least-squares slope against k, for one error measure.
fn observed_orders(rows: &[&WorkRow], error: Measure) -> (Vec<f64>, f64) {
    let ok: Vec<&&WorkRow> = rows.iter().filter(|r| r.ok()).collect();
    let errs: Vec<f64> = ok.iter().map(|r| error(r)).collect();
    let ks: Vec<f64> = ok.iter().map(|r| r.spec.level.k).collect();
    (errs.windows(2).map(|w| (w[0] / w[1]).log2()).collect(), loglog_slope(&ks, &errs))
}

/// The rows of each scheme × inner × mass group, in sweep order.
fn groups(rows: &[WorkRow]) -> Vec<Vec<&WorkRow>> {
    let mut out: Vec<Vec<&WorkRow>> = Vec::new();
    for r in rows {
        match out.iter_mut().find(|g| g[0].group() == r.group()) {
            Some(g) => g.push(r),
            None => out.push(vec![r]),
        }
    }
    out
}

fn group_label(r: &WorkRow) -> String {
    format!("{}/{}/{}", kinds::name(&r.spec.scheme), kinds::name(&r.spec.inner), kinds::name(&r.spec.mass))
}

/// The colour of a scheme × mass pair (newton and conic share it; the line style differs).
fn group_color(r: &WorkRow) -> RGBColor {
    let s = match r.spec.scheme {
        SchemeKind::Midpoint => 0,
        SchemeKind::Trapezoid => 1,
        SchemeKind::BackwardEuler => 2,
    };
    let m = usize::from(r.spec.mass != MassKind::Lumped);
    PALETTE[(2 * s + m) % PALETTE.len()]
}

/// An error measure of a work–precision row.
type Measure = fn(&WorkRow) -> f64;

/// One log–log panel of work_precision.svg: `error` of each group against wall time.
fn work_panel(
    area: &DrawingArea<SVGBackend<'_>, Shift>,
    rows: &[WorkRow],
    error: Measure,
    y_desc: &str,
    legend: bool,
) -> Result<()> {
    let err = chart_error("work_precision.svg");
    let ok: Vec<&WorkRow> = rows.iter().filter(|r| r.ok()).collect();
    let (x0, x1) = log_range(ok.iter().map(|r| r.stats.wall_time_s));
    let (y0, y1) = log_range(ok.iter().map(|r| error(r)));
    let mut chart = ChartBuilder::on(area)
        .caption(y_desc, font(style::SUBCAPTION))
        .margin(10)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_desc("wall time [s]")
        .y_desc(y_desc)
        .x_label_formatter(&|v| format!("{v:.0e}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()
        .map_err(|e| err(&e))?;
    for g in groups(rows) {
        let pts: Vec<(f64, f64)> = g
            .iter()
            .filter(|r| r.ok())
            .map(|r| (r.stats.wall_time_s, error(r)))
            .filter(|p| p.0 > 0.0 && p.1 > 0.0 && p.1.is_finite())
            .collect();
        if pts.is_empty() {
            continue;
        }
        let color = group_color(g[0]);
        let style = ShapeStyle::from(&color).stroke_width(2);
        let newton = g[0].spec.inner != InnerSolver::Conic;
        let drawn = if newton {
            chart.draw_series(LineSeries::new(pts.clone(), style)).map_err(|e| err(&e))?
        } else {
            chart.draw_series(DashedLineSeries::new(pts.clone(), 8, 5, style)).map_err(|e| err(&e))?
        };
        drawn.label(group_label(g[0])).legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
        if newton {
            chart.draw_series(pts.iter().map(|p| Circle::new(*p, 4, color.filled()))).map_err(|e| err(&e))?;
        } else {
            chart.draw_series(pts.iter().map(|p| TriangleMarker::new(*p, 6, color.filled()))).map_err(|e| err(&e))?;
        }
    }
    if legend {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerLeft)
            .label_font(font(style::SMALL))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .draw()
            .map_err(|e| err(&e))?;
    }
    Ok(())
}

/// work_precision.svg: the step-resolved force, impulse and displacement errors against wall
/// time, log–log, one line per scheme × inner × mass (newton solid with circles, conic dashed
/// with triangles).
fn work_svg(rows: &[WorkRow], title: &str) -> Result<String> {
    let err = chart_error("work_precision.svg");
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (1950, 640)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let root = root.titled(title, font(style::CAPTION)).map_err(|e| err(&e))?;
        let panels = root.split_evenly((1, 3));
        work_panel(
            &panels[0],
            rows,
            |r| r.error_force[0],
            "contact force (F_ν, F_τ) per step: relative L² error",
            true,
        )?;
        work_panel(
            &panels[1],
            rows,
            |r| r.error_impulse,
            "force averaged over the coarsest step: relative L² error",
            false,
        )?;
        work_panel(&panels[2], rows, |r| r.error_disp, "probe displacements: relative L² error", false)?;
        root.present().map_err(|e| err(&e))?;
    }
    Ok(svg)
}

/// One case of the race: a friction law and a step.
#[derive(Debug, Clone)]
struct RaceCase {
    label: String,
    decay: f64,
    k: f64,
    ck_limit: Option<f64>,
}

/// One row of race.csv: a method on a case, with the case's agreement measures.
#[derive(Debug, Clone)]
struct RaceRow {
    case: RaceCase,
    method: InnerSolver,
    stats: RunStats,
    agreement: Agreement,
    status: String,
}

/// Per-step comparison of F.1 and N.4 from the same state, along the F.1 trajectory.
#[derive(Debug, Clone, Copy, Default)]
struct Agreement {
    max_dv: f64,
    max_df: f64,
    differing: usize,
}

/// The academic scene on the race mesh with decay α, step k and an inner solver, validated.
fn race_model(race: &RacePlan, decay: f64, k: f64, inner: InnerSolver) -> Result<Model> {
    let mut s = Scene::default_scene();
    s.domain.cells = Some(race.cells.to_vec());
    s.time.end = race.t_end;
    s.time.step = k;
    s.solver.inner = inner;
    s.contact
        .as_mut()
        .ok_or_else(|| Error::scene("contact", "the race needs the academic scene's contact"))?
        .friction
        .decay = Some(decay);
    s.validate()
}

/// The scene's own friction decay α (the race's base law).
fn base_decay() -> Result<f64> {
    Scene::default_scene()
        .contact
        .and_then(|c| c.friction.decay)
        .ok_or_else(|| Error::scene("contact.friction.decay", "the race needs an exponential law"))
}

/// The largest step 1e-3 / 2^j inside the (C.k) limit (a whole number of steps over T).
fn step_inside(limit: f64) -> f64 {
    let mut k = 1e-3;
    for _ in 0..30 {
        if k <= limit {
            break;
        }
        k /= 2.0;
    }
    k
}

/// The race cases: per friction law, a step inside (C.k) (from `ModelInfo::ck_step_limit`) and
/// the plan's steps beyond it.
fn race_cases(race: &RacePlan) -> Result<Vec<RaceCase>> {
    let alpha0 = base_decay()?;
    let mut cases = Vec::new();
    for &f in &race.decay_factors {
        let decay = alpha0 * f;
        let probe = Problem::new(race_model(race, decay, race.beyond[0], InnerSolver::Newton)?, Path::new("."))?;
        let ck_limit = ModelInfo::of(&probe).ck_step_limit;
        let mut ks: Vec<f64> = ck_limit.map(step_inside).into_iter().chain(race.beyond.iter().copied()).collect();
        ks.sort_by(f64::total_cmp);
        ks.dedup();
        for k in ks {
            cases.push(RaceCase { label: format!("α={decay} k={k:e}"), decay, k, ck_limit });
        }
    }
    Ok(cases)
}

fn inner_failure(e: ContactFailure) -> Error {
    Error::Study(format!("bench race: {}", dyncontact::failure::StepFailureCause::Contact(e)))
}

/// The Newton settings of a simulation whose inner solver is `newton`.
fn newton_settings(sim: &Simulation) -> Result<NewtonSettings> {
    match sim.settings.inner {
        Inner::Newton(s) | Inner::NewtonUnfrozen(s) => Ok(s),
        Inner::Conic(_) => Err(Error::Study("bench race: the comparison needs a Newton inner solver".into())),
    }
}

/// (N.4) against (F.1) step by step from the same state (the F.1 trajectory): the largest
/// difference of the contact velocities and forces, relative to the step's scales, and the
/// number of steps where they differ beyond [`AGREEMENT_TOLERANCE`] (tests/solver/unfrozen.rs).
fn agreement(p: &Problem) -> Result<Agreement> {
    let mut sim = Simulation::new(p)?;
    let set = newton_settings(&sim)?;
    let c = p.contact.as_ref().ok_or_else(|| Error::Study("bench race: the scene has no contact".into()))?;
    let mut a = Agreement::default();
    let mut steps = sim.steps();
    // the comparison's own factor cache: re-solving a step leaves the run's path alone
    let mut factors = dyncontact::step::delassus::DelassusFactors::default();
    while steps.simulation().state.n < p.steps {
        {
            let sim = steps.simulation();
            let (v_free, _) = sim.free_velocity();
            let (data, p_hat) =
                sim.step_data(c.restrict(&v_free)).ok_or_else(|| Error::Study("bench race: no contact data".into()))?;
            let (f1, _, _) = sim
                .solve_frozen_sequence(&data, &mut factors, &p_hat, &Inner::Newton(set), None)
                .map_err(inner_failure)?;
            let (un, _, _) = sim
                .solve_frozen_sequence(&data, &mut factors, &p_hat, &Inner::NewtonUnfrozen(set), None)
                .map_err(inner_failure)?;
            let vs = data.velocity_scale(&f1.y).max(1e-300);
            let (ra, rb) = (data.forces(&f1.y, &f1.lambda, &f1.t), data.forces(&un.y, &un.lambda, &un.t));
            let fs = dyncontact::linalg::norm_inf(&ra).max(1e-300);
            let dv = f1.y.iter().zip(&un.y).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / vs;
            let df = ra.iter().zip(&rb).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / fs;
            a.max_dv = a.max_dv.max(dv);
            a.max_df = a.max_df.max(df);
            a.differing += usize::from(dv > AGREEMENT_TOLERANCE || df > AGREEMENT_TOLERANCE);
        }
        if let Some(rec) = steps.next() {
            rec?;
        }
    }
    Ok(a)
}

/// Both methods on one case: timed runs, then the per-step agreement.
fn race_rows(race: &RacePlan, case: &RaceCase) -> Result<Vec<RaceRow>> {
    let mut rows = Vec::new();
    for method in [InnerSolver::Newton, InnerSolver::NewtonUnfrozen] {
        let p = Problem::new(race_model(race, case.decay, case.k, method)?, Path::new("."))?;
        let (stats, status) = match simulate(&p, &[]) {
            Ok((_, st)) => (st, "ok".to_string()),
            Err(e) => (RunStats { steps: p.steps, ..RunStats::default() }, format!("failed: {e}")),
        };
        rows.push(RaceRow { case: case.clone(), method, stats, agreement: Agreement::default(), status });
    }
    let p = Problem::new(race_model(race, case.decay, case.k, InnerSolver::Newton)?, Path::new("."))?;
    let agreement = match agreement(&p) {
        Ok(a) => a,
        Err(e) => {
            for r in &mut rows {
                r.status = format!("{}; comparison failed: {e}", r.status);
            }
            Agreement { max_dv: f64::NAN, max_df: f64::NAN, differing: 0 }
        }
    };
    for r in &mut rows {
        r.agreement = agreement;
    }
    Ok(rows)
}

impl RaceRow {
    fn per_step(&self, x: f64) -> f64 {
        x / self.stats.steps.max(1) as f64
    }
    fn inside(&self) -> Option<bool> {
        self.case.ck_limit.map(|l| self.case.k <= l)
    }
}

/// race.csv.
fn race_csv(rows: &[RaceRow]) -> String {
    csv_table(
        RACE_COLUMNS,
        rows.iter().map(|r| {
            let st = &r.stats;
            vec![
                csv_field(&r.case.label),
                r.case.decay.to_string(),
                format!("{:e}", r.case.k),
                r.case.ck_limit.map_or("".into(), |l| format!("{l:.6e}")),
                r.inside().map_or("", |b| if b { "yes" } else { "no" }).to_string(),
                kinds::name(&r.method),
                st.steps.to_string(),
                format!("{:.6e}", st.wall_time_s),
                format!("{:.6e}", r.per_step(st.step_time_s)),
                format!("{:.6e}", r.per_step(st.contact_time_s)),
                format!("{:.4}", r.per_step(st.newton_iterations as f64)),
                format!("{:.4}", r.per_step(st.fixed_point_iterations as f64)),
                st.unfrozen.to_string(),
                st.fallbacks.to_string(),
                format!("{:.6e}", st.setup_delassus_s),
                format!("{:.3e}", r.agreement.max_dv),
                format!("{:.3e}", r.agreement.max_df),
                r.agreement.differing.to_string(),
                csv_field(&r.status),
            ]
        }),
    )
}

/// One bar panel of race.csv: `value` per case, F.1 and N.4 side by side.
fn race_panel(
    area: &DrawingArea<SVGBackend<'_>, Shift>,
    rows: &[RaceRow],
    value: fn(&RaceRow) -> f64,
    y_desc: &str,
) -> Result<()> {
    let err = chart_error("race.svg");
    let labels: Vec<String> = rows
        .iter()
        .step_by(2)
        .map(|r| format!("{}{}", r.case.label, if r.inside() == Some(true) { " (C.k)" } else { "" }))
        .collect();
    let y1 = rows.iter().map(value).filter(|v| v.is_finite()).fold(0.0f64, f64::max).max(1e-12) * 1.15;
    let n = labels.len();
    let mut chart = ChartBuilder::on(area)
        .caption(y_desc, font(style::SUBCAPTION))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(-0.5..(n as f64 - 0.5), 0.0..y1)
        .map_err(|e| err(&e))?;
    let fmt = |v: &f64| {
        let i = v.round();
        if (v - i).abs() < 1e-6 && i >= 0.0 {
            labels.get(i as usize).cloned().unwrap_or_default()
        } else {
            String::new()
        }
    };
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(n.max(1))
        .x_label_formatter(&fmt)
        .x_label_style(font(style::TINY))
        .y_desc(y_desc)
        .draw()
        .map_err(|e| err(&e))?;
    for (m, (method, color)) in
        [(InnerSolver::Newton, PALETTE[0]), (InnerSolver::NewtonUnfrozen, PALETTE[1])].into_iter().enumerate()
    {
        let x_off = if m == 0 { -0.38 } else { 0.02 };
        let bars: Vec<Rectangle<(f64, f64)>> = rows
            .iter()
            .filter(|r| r.method == method)
            .enumerate()
            .filter(|(_, r)| value(r).is_finite())
            .map(|(i, r)| {
                Rectangle::new([(i as f64 + x_off, 0.0), (i as f64 + x_off + 0.36, value(r))], color.filled())
            })
            .collect();
        let name = if method == InnerSolver::Newton { "newton (F.1)" } else { "newton-unfrozen (N.4)" };
        chart
            .draw_series(bars)
            .map_err(|e| err(&e))?
            .label(name)
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 15, y + 5)], color.filled()));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(|e| err(&e))?;
    Ok(())
}

/// race.svg: contact-solve time and Newton iterations per step.
fn race_svg(rows: &[RaceRow], title: &str) -> Result<String> {
    let err = chart_error("race.svg");
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (1400, 560)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let root = root.titled(title, font(style::CAPTION)).map_err(|e| err(&e))?;
        let panels = root.split_evenly((1, 2));
        race_panel(&panels[0], rows, |r| 1e3 * r.per_step(r.stats.contact_time_s), "contact solve per step [ms]")?;
        race_panel(&panels[1], rows, |r| r.per_step(r.stats.newton_iterations as f64), "Newton iterations per step")?;
        root.present().map_err(|e| err(&e))?;
    }
    Ok(svg)
}

/// Best effort progress line on stderr (the benchmark runs for minutes).
fn progress(msg: &str) {
    use std::io::Write as _;
    let _ = writeln!(std::io::stderr(), "bench: {msg}");
}

/// The printed summary of the work–precision part.
fn work_report(plan: &BenchPlan, rows: &[WorkRow], ref_stats: &RunStats) -> String {
    let mut s = String::new();
    let r = plan.reference;
    let _ = writeln!(
        s,
        "work–precision: academic scene, T = {} s; reference midpoint/newton/lumped at {}x{}, k = {:e} \
         (one level finer than the finest bench level; {} steps, {:.1} s)",
        plan.t_end, r.cells[0], r.cells[1], r.k, ref_stats.steps, ref_stats.wall_time_s
    );
    if plan.inners.contains(&InnerSolver::Conic) && plan.conic_levels < plan.levels.len() {
        let _ =
            writeln!(s, "conic runs only on the {} coarsest levels (it is ~30x slower than newton)", plan.conic_levels);
    }
    let _ = writeln!(
        s,
        "{:<38} {:>6} {:>9} {:>8} {:>9} {:>8} {:>8} {:>8} {:>8} {:>8} {:>8} {:>7} {:>6}",
        "run",
        "steps",
        "wall[s]",
        "step[ms]",
        "floor[ms]",
        "step/flr",
        "e_force",
        "e_Fn",
        "e_Ft",
        "e_imp",
        "e_disp",
        "newton",
        "fp"
    );
    for w in rows {
        let st = &w.stats;
        let name = format!("{} {}x{}", group_label(w), w.spec.level.cells[0], w.spec.level.cells[1]);
        if !w.ok() {
            let _ = writeln!(s, "{name:<38} {}", w.status);
            continue;
        }
        let _ = writeln!(
            s,
            "{name:<38} {:>6} {:>9.3} {:>8.3} {:>9.4} {:>8.1} {:>8.2e} {:>8.2e} {:>8.2e} {:>8.2e} {:>8.2e} {:>7} {:>6}",
            st.steps,
            st.wall_time_s,
            1e3 * w.time_per_step(),
            1e3 * st.floor_s,
            w.time_per_step() / st.floor_s,
            w.error_force[0],
            w.error_force[1],
            w.error_force[2],
            w.error_impulse,
            w.error_disp,
            st.newton_iterations,
            st.fixed_point_iterations
        );
    }
    let _ = writeln!(
        s,
        "e_force: (F_ν, F_τ) per step (e_Fn, e_Ft: each alone); e_imp: the force averaged over windows of {:e} s \
         (the coarsest step); e_disp: displacements at the probe nodes; all relative L²(0, T). step/flr: time per step \
         over the floor (two A_k solves); newton: Newton iterations (conic: interior-point iterations); fp: convex solves in F.1",
        plan.levels[0].k
    );
    let _ = writeln!(
        s,
        "observed orders (h and k halved together; pairwise log2 ratios, then the least-squares slope). The reference \
         is one level finer, so for the reference's own scheme the last pair is biased upward by -log2(1 - 2^-p):"
    );
    let list = |v: &[f64]| v.iter().map(|x| format!("{x:5.2}")).collect::<Vec<_>>().join(" ");
    let measures: [(&str, Measure); 3] =
        [("force", |r| r.error_force[0]), ("impulse", |r| r.error_impulse), ("disp", |r| r.error_disp)];
    for g in groups(rows) {
        let parts: Vec<String> = measures
            .iter()
            .map(|(name, f)| {
                let (pairs, fit) = observed_orders(&g, *f);
                format!("{name} [{}] fit {fit:5.2}", list(&pairs))
            })
            .collect();
        let _ = writeln!(s, "  {:<33} {}", group_label(g[0]), parts.join("; "));
    }
    s
}

/// The printed summary of the race.
fn race_report(race: &RacePlan, rows: &[RaceRow]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "race: newton (F.1) vs newton-unfrozen (N.4), academic scene {}x{}, T = {} s",
        race.cells[0], race.cells[1], race.t_end
    );
    let _ = writeln!(
        s,
        "{:<22} {:>10} {:>7} {:<16} {:>9} {:>11} {:>9} {:>7} {:>8} {:>9} {:>9} {:>9} {:>5}",
        "case",
        "(C.k) k<=",
        "inside",
        "method",
        "step[ms]",
        "contact[ms]",
        "newton/st",
        "fp/st",
        "unfrozen",
        "fallbacks",
        "max|dy|",
        "max|dr|",
        "diff"
    );
    for r in rows {
        let st = &r.stats;
        if r.status != "ok" {
            let _ = writeln!(s, "{:<22} {:<16} {}", r.case.label, kinds::name(&r.method), r.status);
            continue;
        }
        let _ = writeln!(
            s,
            "{:<22} {:>10} {:>7} {:<16} {:>9.3} {:>11.3} {:>9.2} {:>7.2} {:>8} {:>9} {:>9.1e} {:>9.1e} {:>5}",
            r.case.label,
            r.case.ck_limit.map_or("-".into(), |l| format!("{l:.3e}")),
            r.inside().map_or("-", |b| if b { "yes" } else { "no" }),
            kinds::name(&r.method),
            1e3 * r.per_step(st.step_time_s),
            1e3 * r.per_step(st.contact_time_s),
            r.per_step(st.newton_iterations as f64),
            r.per_step(st.fixed_point_iterations as f64),
            st.unfrozen,
            st.fallbacks,
            r.agreement.max_dv,
            r.agreement.max_df,
            r.agreement.differing
        );
    }
    if let Some(r) = rows.first() {
        let _ = writeln!(
            s,
            "setup: Delassus operator W (2 n_c solves, once per run) {:.2} ms; max|dy|, max|dr|: per-step F.1 vs N.4 from the same state \
             (relative); diff: steps differing by more than {AGREEMENT_TOLERANCE:e}",
            1e3 * r.stats.setup_delassus_s
        );
    }
    s
}

/// One run of the default scene for the floor part.
struct FloorRun {
    per_step: f64,
    floor: f64,
    contact_per_step: f64,
    stats: RunStats,
}

const FLOOR_2D: &str = "default scene (academic, 2-D, 32 contact nodes)";
const FLOOR_3D: &str = "3-D default fixture (academic3d, 24x12x8 cells, 312 contact nodes, friction on the disk)";
const FLOOR_3D_BLOCK: &str = "sliding_block3d (3-D, 49 contact nodes, friction on the disk)";

/// Part 2, the floor on the default scene (`academic`, as `cargo run --release -- run` runs it,
/// without outputs): time per step ÷ the floor of two triangular-solve pairs, `repeats` times.
fn floor_runs(plan: &BenchPlan) -> Result<Vec<FloorRun>> {
    floor_runs_of(plan.floor_repeats, plan.floor_end, Scene::default_scene())
}

/// The 3-D rows of part 2, as `run` runs them without outputs: the 3-D default fixture
/// academic3d (Ex-A extruded, 312 contact nodes, shaken obliquely) and the sliding_block3d
/// fixture (B.3 pulled at 30°, 49 contact nodes).
fn floor_runs_3d(plan: &BenchPlan) -> Result<(Vec<FloorRun>, Vec<FloorRun>)> {
    let academic = Scene::from_toml(include_str!("../../fixtures/scenes/academic3d.toml"), "academic3d.toml")?;
    let block = Scene::from_toml(include_str!("../../fixtures/scenes/sliding_block3d.toml"), "sliding_block3d.toml")?;
    Ok((
        floor_runs_of(plan.floor3d_repeats, plan.floor3d_end, academic)?,
        floor_runs_of(plan.floor_repeats, plan.floor_end, block)?,
    ))
}

/// floor3d.csv (both 3-D scenes, a `scene` column first) and their printed lines.
fn floor3d_report(plan: &BenchPlan) -> Result<(String, String)> {
    let (academic, block) = floor_runs_3d(plan)?;
    let (csv_a, text_a) = floor_report(&academic, FLOOR_3D);
    let (csv_b, text_b) = floor_report(&block, FLOOR_3D_BLOCK);
    let mut csv = format!("scene,contact_nodes,{}", csv_a.lines().next().unwrap_or_default());
    csv.push('\n');
    for (name, nc, body) in [("academic3d", 312, &csv_a), ("sliding_block3d", 49, &csv_b)] {
        for line in body.lines().skip(1) {
            let _ = writeln!(csv, "{name},{nc},{line}");
        }
    }
    Ok((csv, text_a + &text_b))
}

fn floor_runs_of(repeats: usize, end: Option<f64>, mut scene: Scene) -> Result<Vec<FloorRun>> {
    if let Some(end) = end {
        scene.time.end = end;
    }
    let p = Problem::from_scene(&scene, Path::new("."))?;
    (0..repeats)
        .map(|_| {
            let (_, stats) = simulate(&p, &[])?;
            let steps = stats.steps as f64;
            Ok(FloorRun {
                per_step: stats.step_time_s / steps,
                floor: stats.floor_s,
                contact_per_step: stats.contact_time_s / steps,
                stats,
            })
        })
        .collect()
}

/// floor.csv and the printed lines of the floor part: min and median over the repetitions.
fn floor_report(runs: &[FloorRun], what: &str) -> (String, String) {
    let mut csv = String::from(
        "run,steps,time_per_step_s,floor_s,ratio_to_floor,contact_per_step_s,newton_iterations,fixed_point_iterations,factorizations,factor_reuses\n",
    );
    for (i, r) in runs.iter().enumerate() {
        let st = &r.stats;
        let _ = writeln!(
            csv,
            "{i},{},{:.6e},{:.6e},{:.3},{:.6e},{},{},{},{}",
            st.steps,
            r.per_step,
            r.floor,
            r.per_step / r.floor,
            r.contact_per_step,
            st.newton_iterations,
            st.fixed_point_iterations,
            st.factorizations,
            st.factor_reuses
        );
    }
    let stat = |f: &dyn Fn(&FloorRun) -> f64| {
        let mut v: Vec<f64> = runs.iter().map(f).collect();
        v.sort_by(f64::total_cmp);
        (v[0], v[v.len() / 2])
    };
    let (step_min, step_med) = stat(&|r| r.per_step);
    let (floor_min, floor_med) = stat(&|r| r.floor);
    let (ratio_min, ratio_med) = stat(&|r| r.per_step / r.floor);
    let (contact_min, contact_med) = stat(&|r| r.contact_per_step);
    let st = &runs[0].stats;
    let text = format!(
        "floor: {what}, {} steps, {} runs (min / median): time per step {:.1} / {:.1} µs, floor (two A_k \
         solve pairs) {:.1} / {:.1} µs, ratio {:.2} / {:.2} (of the minima: {:.2}, the least noisy estimate); contact solve {:.1} / {:.1} µs per step; {} Newton iterations, \
         {} convex solves, Newton matrices factored {} times and reused {} times\n",
        st.steps,
        runs.len(),
        1e6 * step_min,
        1e6 * step_med,
        1e6 * floor_min,
        1e6 * floor_med,
        ratio_min,
        ratio_med,
        step_min / floor_min,
        1e6 * contact_min,
        1e6 * contact_med,
        st.newton_iterations,
        st.fixed_point_iterations,
        st.factorizations,
        st.factor_reuses
    );
    (csv, text)
}

/// Write one output file under `out`.
fn write(out: &Path, name: &str, text: &str) -> Result<()> {
    write_atomic(&out.join(name), text.as_bytes())
}

/// Run the benchmark and write its CSV and SVG files under `out`.
pub fn run(out: &Path, opts: &BenchOptions) -> Result<String> {
    let clock = Instant::now();
    let plan = if opts.quick { BenchPlan::quick() } else { BenchPlan::full() };
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    let bk_plan = if opts.quick {
        crate::bookkeeping::BookkeepingPlan::quick()
    } else {
        crate::bookkeeping::BookkeepingPlan::full()
    };
    if opts.bookkeeping_only {
        let rows = crate::bookkeeping::run_part(&bk_plan, out)?;
        write(out, "bookkeeping.csv", &crate::bookkeeping::csv(&rows))?;
        return Ok(crate::bookkeeping::report(&rows));
    }
    let thick_plan = if opts.quick {
        (crate::thick::ThickPlan::quick(), crate::thick::ShakePlan::quick(), crate::thick::RunPlan::quick())
    } else {
        let thick = crate::thick::ThickPlan::full(opts.thick_largest);
        let thick = if opts.thick_beyond { thick.with_beyond() } else { thick };
        let mut shaking = crate::thick::ShakePlan::full(opts.thick_largest);
        shaking.boxes.extend(&thick.beyond);
        (thick, shaking, crate::thick::RunPlan::full(opts.thick_largest))
    };
    if opts.thick_only {
        return thick_part(&thick_plan, out, &progress);
    }
    if opts.floor_only {
        let (floor_csv, floor_text) = floor_report(&floor_runs(&plan)?, FLOOR_2D);
        write(out, "floor.csv", &floor_csv)?;
        let (csv3, text3) = floor3d_report(&plan)?;
        write(out, "floor3d.csv", &csv3)?;
        return Ok(floor_text + &text3);
    }

    let reference_spec = RunSpec {
        scheme: SchemeKind::Midpoint,
        inner: InnerSolver::Newton,
        mass: MassKind::Lumped,
        level: plan.reference,
    };
    progress(&format!("reference {}", reference_spec.label()));
    let p_ref = Problem::new(reference_spec.model(plan.t_end)?, Path::new("."))?;
    let (reference, ref_stats) = simulate(&p_ref, &probe_dofs(&p_ref)?)?;

    let mut rows = Vec::new();
    for spec in run_specs(&plan) {
        progress(&spec.label());
        rows.push(work_row(spec, &plan, &reference)?);
    }
    write(out, "work_precision.csv", &work_csv(&rows))?;
    let title = format!("work–precision, academic scene, T = {} s (newton solid, conic dashed)", plan.t_end);
    write(out, "work_precision.svg", &work_svg(&rows, &title)?)?;

    progress("floor: the default scene");
    let (floor_csv, floor_text) = floor_report(&floor_runs(&plan)?, FLOOR_2D);
    write(out, "floor.csv", &floor_csv)?;
    progress("floor: the 3-D default fixture and the 3-D block");
    let (csv3, text3) = floor3d_report(&plan)?;
    write(out, "floor3d.csv", &csv3)?;
    let floor_text = floor_text + &text3;

    let scaling_plan =
        if opts.quick { crate::scaling::ScalingPlan::quick() } else { crate::scaling::ScalingPlan::full() };
    let scaling_rows = crate::scaling::run(&scaling_plan, &progress)?;
    write(out, "scaling.csv", &crate::scaling::csv(&scaling_rows))?;
    write(out, "scaling.svg", &crate::scaling::svg(&scaling_rows, &scaling_plan)?)?;
    let thick_text = thick_part(&thick_plan, out, &progress)?;

    progress("bookkeeping: the default scene's body at 256 x 128 without contact, with outputs");
    let bk_rows = crate::bookkeeping::run_part(&bk_plan, out)?;
    write(out, "bookkeeping.csv", &crate::bookkeeping::csv(&bk_rows))?;

    let mut race = Vec::new();
    for case in race_cases(&plan.race)? {
        progress(&format!("race {}", case.label));
        race.extend(race_rows(&plan.race, &case)?);
    }
    write(out, "race.csv", &race_csv(&race))?;
    let title =
        format!("F.1 vs N.4, academic scene {}x{}, T = {} s", plan.race.cells[0], plan.race.cells[1], plan.race.t_end);
    write(out, "race.svg", &race_svg(&race, &title)?)?;

    let mut report = work_report(&plan, &rows, &ref_stats);
    report.push('\n');
    report.push_str(&floor_text);
    report.push('\n');
    report.push_str(&crate::scaling::report(&scaling_rows));
    report.push('\n');
    report.push_str(&thick_text);
    report.push('\n');
    report.push_str(&crate::bookkeeping::report(&bk_rows));
    report.push('\n');
    report.push_str(&race_report(&plan.race, &race));
    let _ = writeln!(
        report,
        "\ntotal benchmark wall time {:.1} s; outputs in {}",
        clock.elapsed().as_secs_f64(),
        out.display()
    );
    write(out, "report.txt", &report)?;
    Ok(report)
}

/// Part 4b: the thick 3-D boxes (thick.csv, thick.svg) pressed, shaken three ways
/// (thick_shaking.csv) and run from t = 0 as a user runs them (thick_run.csv), and their printed
/// lines.
fn thick_part(
    (plan, shaking, whole): &(crate::thick::ThickPlan, crate::thick::ShakePlan, crate::thick::RunPlan),
    out: &Path,
    progress: &dyn Fn(&str),
) -> Result<String> {
    let rows = crate::thick::run(plan, progress)?;
    write(out, "thick.csv", &crate::thick::csv(&rows))?;
    write(out, "thick.svg", &crate::thick::svg(&rows, plan)?)?;
    let shaken = crate::thick::run_shaking(shaking, progress)?;
    write(out, "thick_shaking.csv", &crate::thick::shaking_csv(&shaken))?;
    let runs = crate::thick::run_whole(whole, progress)?;
    write(out, "thick_run.csv", &crate::thick::run_csv(&runs))?;
    Ok(crate::thick::report(&rows, plan)
        + "\n"
        + &crate::thick::shaking_report(&shaken)
        + "\n"
        + &crate::thick::run_report(&runs, whole))
}
