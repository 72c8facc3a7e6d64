//! Thick 3-D bodies (`cargo xtask bench`, part 4b; alone with `--thick-only`): the academic3d
//! box refined in all three directions — 24×12×8, 32×16×12, 48×24×16 (and 64×32×24 with
//! `--thick-largest`) — where W does not decay and stays dense, so the contact solve runs in the
//! velocity form (conjugate gradients on (W⁻¹)_FF + Ĝ_F). Each box runs its first `steps` steps
//! (the pressing phase: half the contact nodes slipping outward) twice from the same setup
//! data: with the near-field preconditioner (the Cholesky factor of W⁻¹'s near field, today's
//! form) and with node blocks (the form before it). Per step: the free solve (A_k's whole forward
//! pass and the backward pass over the part of its factor the contact unknowns reach, since the
//! step splits its solve pair: `Simulation::step`) and the contact solve, min and median over the
//! steps, and the recovery; one whole solve pair timed after the steps (the yardstick the free
//! solve was before the split) and one timed right after each step, with the median of the
//! contact solve over it step by step (a ratio of two timings at about the same speed of the
//! machine); per run: the setup split (assembly, factorization of A_k, W and W⁻¹), the run's
//! peak memory (the process's peak started again before each run: setup and steps with their
//! adjacent pairs, not the route-before timing beside it) and `check`'s estimate of it.
//!
//! The shaking window (thick_shaking.csv): each box at academic3d's step scaled with its cell
//! height, k = 5e-4 · 8/n_z (inside (C.k) on every box: the refinement a convergence study
//! makes), pressed until the shaking starts (t = 0.2 s, in the form and start the run picks
//! itself), then the same state run over 0.02 s three times ([`SHAKING_RUNS`]): F.1 from the
//! predictor's S (the paper's start), F.1 as the fixture runs it (`fixed_point_start = "auto"`:
//! from the unfrozen Newton's root inside (C.k)), and the unfrozen Newton (N.4,
//! `"newton-unfrozen"`): per step the free and contact solves and the convex solves and Newton
//! iterations each spends — where the shaking's cost comes from.
//!
//! The issue's own measure (thick_run.csv, [`run_whole`]): each box run from t = 0 over
//! academic3d's first 0.3 s as a user runs it — the scene's own k = 5e-4 (beyond (C.k) from 544
//! nodes on), its solver settings, `contact_solve = "auto"` — with the free and contact solve
//! per step over the whole run (the table: their means), the pressed and shaken steps'
//! means apart, and solve pairs timed beside it.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use dyncontact::error::{Error, Result};
use dyncontact::output::csv::csv_table;
use dyncontact::output::loglog::{self, LogSeries, loglog_slope};
use dyncontact::problem::ConvexityLimit;
use dyncontact::problem::Problem;
use dyncontact::scene::Scene;
use dyncontact::scene::{FixedPointStart, InnerSolver};
use dyncontact::simulation::{Settings, Simulation};
use dyncontact::step::delassus::DelassusFactors;

/// What the thick part runs.
#[derive(Debug, Clone)]
pub struct ThickPlan {
    pub boxes: Vec<[i64; 3]>,
    /// boxes beyond the family, run in the hierarchical form only (the dense forms and the
    /// route-before timing — d·n_c solve pairs — would add over an hour there)
    pub beyond: Vec<[i64; 3]>,
    /// steps of academic3d's k = 5e-4 from t = 0
    pub steps: usize,
}

impl ThickPlan {
    /// The family up to 48×24×16 (1,200 contact nodes; 64×32×24 with `largest`), 40 steps each.
    pub fn full(largest: bool) -> ThickPlan {
        let mut boxes = vec![[24, 12, 8], [32, 16, 12], [48, 24, 16]];
        if largest {
            boxes.push([64, 32, 24]);
        }
        ThickPlan { boxes, beyond: Vec::new(), steps: 40 }
    }
    /// With `--thick-beyond`: the slope past the family's 2,112 contact nodes — 80×40×32 (3,280
    /// nodes, 324,720 unknowns, ~11 GB) and 96×48×32 (4,704 nodes, 465,696 unknowns, `check`
    /// estimates 18.5 GiB), hierarchical form only.
    pub fn with_beyond(mut self) -> ThickPlan {
        self.beyond = vec![[80, 40, 32], [96, 48, 32]];
        self
    }
    /// The smoke test's plan: the smallest boxes whose W has the GEMV_FROM (256) components the
    /// velocity form needs (12×6×4 has 252: no velocity form, no row).
    pub fn quick() -> ThickPlan {
        ThickPlan { boxes: vec![[16, 8, 4], [20, 10, 6]], beyond: Vec::new(), steps: 3 }
    }
}

/// One run of one box with one preconditioner.
#[derive(Debug, Clone)]
pub struct ThickRow {
    pub cells: [i64; 3],
    pub unknowns: usize,
    pub contact_nodes: usize,
    /// one of FORMS
    pub form: &'static str,
    pub steps: usize,
    /// per step, seconds: [min, median]
    pub free: [f64; 2],
    pub contact: [f64; 2],
    pub recovery: [f64; 2],
    /// one whole solve pair with A_k's factor (seconds, median of PAIR_REPEATS after the steps):
    /// the yardstick of the "3× the free solve", which was one pair before the step split
    /// its pair around the contact solve (the free solve is now a forward pass and a partial
    /// backward one)
    pub pair: f64,
    /// one whole solve pair timed right after each step, and the contact solve against it
    pub adjacent: Adjacent,
    /// setup seconds: assembly, factorization of A_k, W and W⁻¹ (with its near field)
    pub assembly: f64,
    pub factorization: f64,
    pub delassus: f64,
    /// how the run computed W and W⁻¹ ("schur" from SCHUR_FROM components on, else "solves")
    pub route: &'static str,
    /// seconds W and W⁻¹ take by d n_c solve pairs and W's Cholesky inverse (the route before
    /// the Schur complement), measured beside the run (the hierarchical rows of the family, else NaN)
    pub delassus_solves: f64,
    pub newton_iterations: usize,
    pub cg_iterations: usize,
    /// the share of W⁻¹'s entries in its near field
    pub near_density: f64,
    /// the values the hierarchical form stores against m² (NaN in the dense forms)
    pub h_share: f64,
    /// the run's peak resident memory (setup and steps), MB: the process's peak started again
    /// before it, so no earlier row and not the route-before timing count
    pub peak_mb: f64,
    /// `check`'s estimate of that peak (`Estimate::total`), MB
    pub estimate_mb: f64,
    /// the entries of A_k's factor, and how its unknowns are ordered
    pub factor_entries: usize,
    pub fill_order: &'static str,
}

/// academic3d's file on `cells`, named `{prefix}_{cells}`: every other key as the file sets it.
fn academic3d_box(prefix: &str, cells: [i64; 3]) -> Result<Scene> {
    let mut s = Scene::from_toml(include_str!("../../fixtures/scenes/academic3d.toml"), "academic3d.toml")?;
    s.name = format!("{prefix}_{}x{}x{}", cells[0], cells[1], cells[2]);
    s.domain.cells = Some(cells.to_vec());
    Ok(s)
}

fn scene(cells: [i64; 3], steps: usize) -> Result<Scene> {
    let mut s = academic3d_box("thick", cells)?;
    s.time.end = s.time.step * steps as f64;
    s.output.every = 0;
    // the family's premise: W stays dense (`auto` keeps it so from 24×12×8 on; the quick plan's
    // small boxes decay enough for `auto` to probe them sparse)
    s.solver.contact_solve = dyncontact::model::kinds::ContactSolve::Dense;
    Ok(s)
}

fn min_median(mut v: Vec<f64>) -> [f64; 2] {
    v.sort_by(f64::total_cmp);
    if v.is_empty() { [f64::NAN; 2] } else { [v[0], v[v.len() / 2]] }
}

/// One whole solve pair timed right after each step of a run (`steps_with_adjacent_pairs`).
#[derive(Debug, Clone, Copy)]
pub struct Adjacent {
    /// the pairs' median seconds
    pub pair: f64,
    /// the contact solve over the pair after it, step by step: [min, median, max]
    pub ratio: [f64; 3],
}

/// The columns thick.csv and thick_shaking.csv append for [`Adjacent`].
const ADJACENT_COLUMNS: &str = "adjacent_pair_median_s,contact_over_adjacent_pair_min,\
contact_over_adjacent_pair_median,contact_over_adjacent_pair_max";

impl Adjacent {
    fn of(pairs: Vec<f64>, mut ratios: Vec<f64>) -> Adjacent {
        ratios.sort_by(f64::total_cmp);
        let (min, max) = (ratios.first().copied(), ratios.last().copied());
        let median = ratios.get(ratios.len() / 2).copied();
        let ratio = [min, median, max].map(|v| v.unwrap_or(f64::NAN));
        Adjacent { pair: min_median(pairs)[1], ratio }
    }

    /// The values of ADJACENT_COLUMNS.
    fn fields(&self) -> [String; 4] {
        let [min, median, max] = self.ratio;
        [format!("{:.6e}", self.pair), format!("{min:.3}"), format!("{median:.3}"), format!("{max:.3}")]
    }
}

/// Repetitions of the solve pair timed beside each run (`ThickRow::pair`).
pub const PAIR_REPEATS: usize = 9;

/// The right-hand side the solve pairs are timed with (a fixed pattern, no load evaluation).
fn pair_rhs(sim: &Simulation) -> Vec<f64> {
    (0..sim.stepper.factor().dim()).map(|l| ((l * 7919 + 13) % 101) as f64 / 101.0 - 0.5).collect()
}

/// The seconds of one whole solve pair with the run's factor of A_k on `b`.
fn pair_once(sim: &Simulation, b: &[f64]) -> f64 {
    let mut x = b.to_vec();
    let clock = Instant::now();
    sim.stepper.solve_in_place(&mut x);
    clock.elapsed().as_secs_f64()
}

/// The median time of one whole solve pair with the run's factor of A_k, seconds.
fn solve_pair(sim: &Simulation) -> f64 {
    let b = pair_rhs(sim);
    min_median((0..PAIR_REPEATS).map(|_| pair_once(sim, &b)).collect())[1]
}

/// The steps of a run with one whole solve pair timed right after each (`ThickRow::adjacent`):
/// calls `each` with every record, and returns the pairs' seconds and the step-by-step ratios
/// of the contact solve to its adjacent pair. The machine's speed drifts between runs and
/// within one (this 2-core machine: the same 40 steps 86 → 163 ms per contact solve within half
/// an hour); a ratio taken step by step sees both solves at about the same speed, where the pair
/// timed after the steps does not (it reduces the drift; it does not remove it).
fn steps_with_adjacent_pairs(
    sim: &mut Simulation,
    mut each: impl FnMut(&dyncontact::simulation::StepRecord),
) -> Result<(Vec<f64>, Vec<f64>)> {
    let b = pair_rhs(sim);
    let (mut pairs, mut ratios) = (Vec::new(), Vec::new());
    let mut steps = sim.steps();
    while let Some(rec) = steps.next() {
        let rec = rec?;
        let pair = pair_once(steps.simulation(), &b);
        ratios.push(rec.timing.contact_solve / pair);
        pairs.push(pair);
        each(&rec);
    }
    Ok((pairs, ratios))
}

/// The forms a box runs in: W⁻¹'s and W's products through their hierarchical forms with the
/// near-field preconditioner (`auto`'s from HMATRIX_FROM components on; forced here at every
/// size so the slope spans the family), the dense products with the near field, node blocks
/// (dense).
pub const FORMS: [&str; 3] = ["hierarchical", "near field", "node blocks"];

/// One run in `form` (one of FORMS); `route_before` also times W by the d·n_c solve pairs
/// beside the hierarchical run.
fn measure(p: &Problem, cells: [i64; 3], form: &'static str, route_before: bool) -> Result<ThickRow> {
    let estimate_mb = dyncontact::resources::estimate(&p.model, Path::new("."))?.total() / 1e6;
    dyncontact::resources::reset_peak_memory();
    let clock = Instant::now();
    let mut sim = Simulation::new(p)?;
    let _setup = clock.elapsed();
    let near = form != "node blocks";
    let positions: Vec<[f64; 3]> =
        p.contact.as_ref().map_or(Vec::new(), |c| c.nodes.iter().map(|&i| p.mesh.point(i)).collect());
    let w = sim.delassus.take();
    sim.inverse = sim.inverse.take().map(|i| {
        let i = if near { i.with_near_field() } else { i.without_near_field() };
        if let (true, Some(w)) = (form == "hierarchical", w.as_ref()) {
            i.compressed(w, &positions)
        } else {
            i.without_compression()
        }
    });
    sim.delassus = w;
    let h_share = sim.inverse.as_ref().and_then(|i| i.hierarchical()).map_or(f64::NAN, |h| h.storage_share());
    let near_density = sim.inverse.as_ref().map_or(0.0, |i| i.near_field_density());
    if sim.inverse.is_none() {
        return Err(Error::Study(format!("thick: {cells:?} does not run in velocity form")));
    }
    let t = sim.setup_timing;
    let (mut free, mut contact, mut recovery, mut newton) = (Vec::new(), Vec::new(), Vec::new(), 0);
    let (adjacent_pairs, ratios) = steps_with_adjacent_pairs(&mut sim, |rec| {
        free.push(rec.timing.free_solve);
        contact.push(rec.timing.contact_solve);
        recovery.push(rec.timing.recovery);
        newton += rec.report.inner_iterations;
    })?;
    let peak_mb = dyncontact::resources::peak_memory().unwrap_or(f64::NAN) / 1e6;
    let pair = solve_pair(&sim);
    // the route before: W by the solves, then its Cholesky inverse (timed, then dropped)
    let delassus_solves = match (form == FORMS[0] && route_before, p.contact.as_ref()) {
        (true, Some(c)) => {
            let clock = Instant::now();
            let built = dyncontact::step::delassus::build_with_responses(
                sim.stepper.factor(),
                None,
                c,
                &positions,
                dyncontact::model::kinds::ContactSolve::Dense,
            );
            let inverse = dyncontact::step::delassus::InverseDelassus::new(&built.w, c.dim, None);
            let seconds = clock.elapsed().as_secs_f64();
            drop((built, inverse));
            seconds
        }
        _ => f64::NAN,
    };
    let counts = sim.delassus_factors.all_counts();
    Ok(ThickRow {
        cells,
        unknowns: p.dofs.n_free,
        contact_nodes: p.contact.as_ref().map_or(0, |c| c.n()),
        form,
        h_share,
        steps: free.len(),
        free: min_median(free),
        contact: min_median(contact),
        recovery: min_median(recovery),
        pair,
        adjacent: Adjacent::of(adjacent_pairs, ratios),
        assembly: t.assembly,
        factorization: t.factorization,
        delassus: t.delassus,
        route: t.delassus_route,
        delassus_solves,
        newton_iterations: newton,
        cg_iterations: counts.velocity_iterations,
        near_density,
        peak_mb,
        estimate_mb,
        factor_entries: sim.stepper.factor().factor_len(),
        fill_order: sim.stepper.factor().fill_order().name(),
    })
}

/// Every box in every form.
pub fn run(plan: &ThickPlan, progress: &dyn Fn(&str)) -> Result<Vec<ThickRow>> {
    let mut rows = Vec::new();
    for &cells in &plan.boxes {
        let p = Problem::from_scene(&scene(cells, plan.steps)?, Path::new("."))?;
        for form in FORMS {
            progress(&format!("thick: {}x{}x{}, {form}", cells[0], cells[1], cells[2]));
            rows.push(measure(&p, cells, form, true)?);
        }
    }
    for &cells in &plan.beyond {
        let p = Problem::from_scene(&scene(cells, plan.steps)?, Path::new("."))?;
        progress(&format!("thick, beyond the family: {}x{}x{}, {}", cells[0], cells[1], cells[2], FORMS[0]));
        rows.push(measure(&p, cells, FORMS[0], false)?);
    }
    Ok(rows)
}

/// thick.csv.
pub fn csv(rows: &[ThickRow]) -> String {
    csv_table(
        &format!(
            "cells,unknowns,contact_nodes,form,steps,free_min_s,free_median_s,contact_min_s,contact_median_s,\
contact_over_free,assembly_s,factorization_s,delassus_s,delassus_route,delassus_by_solves_s,newton_iterations,cg_iterations,near_density,h_share,peak_mb,estimate_mb,factor_entries,fill_order,\
recovery_min_s,recovery_median_s,pair_median_s,contact_over_pair,{ADJACENT_COLUMNS}"
        ),
        rows.iter().map(|r| {
            vec![
                format!("{}x{}x{}", r.cells[0], r.cells[1], r.cells[2]),
                r.unknowns.to_string(),
                r.contact_nodes.to_string(),
                r.form.to_string(),
                r.steps.to_string(),
                format!("{:.6e}", r.free[0]),
                format!("{:.6e}", r.free[1]),
                format!("{:.6e}", r.contact[0]),
                format!("{:.6e}", r.contact[1]),
                format!("{:.3}", r.contact[1] / r.free[1]),
                format!("{:.3}", r.assembly),
                format!("{:.3}", r.factorization),
                format!("{:.3}", r.delassus),
                r.route.to_string(),
                if r.delassus_solves.is_nan() { String::new() } else { format!("{:.3}", r.delassus_solves) },
                r.newton_iterations.to_string(),
                r.cg_iterations.to_string(),
                format!("{:.4}", r.near_density),
                if r.h_share.is_nan() { String::new() } else { format!("{:.4}", r.h_share) },
                format!("{:.0}", r.peak_mb),
                format!("{:.0}", r.estimate_mb),
                r.factor_entries.to_string(),
                r.fill_order.to_string(),
                format!("{:.6e}", r.recovery[0]),
                format!("{:.6e}", r.recovery[1]),
                format!("{:.6e}", r.pair),
                format!("{:.3}", r.contact[1] / r.pair),
            ]
            .into_iter()
            .chain(r.adjacent.fields())
            .collect()
        }),
    )
}

fn points(rows: &[ThickRow], form: &str, value: fn(&ThickRow) -> f64) -> Vec<(f64, f64)> {
    rows.iter().filter(|r| r.form == form).map(|r| (r.contact_nodes as f64, value(r))).collect()
}

/// The log–log slope of the median contact solve per step against n_c for `form`, over the
/// rows whose box is in `boxes`.
pub fn slope(rows: &[ThickRow], form: &str, boxes: &[[i64; 3]]) -> f64 {
    let (x, y): (Vec<f64>, Vec<f64>) = rows
        .iter()
        .filter(|r| r.form == form && boxes.contains(&r.cells))
        .map(|r| (r.contact_nodes as f64, r.contact[1]))
        .unzip();
    if x.len() >= 2 { loglog_slope(&x, &y) } else { f64::NAN }
}

/// The slopes between neighbouring boxes of `form` (in the order run), each with its two n_c.
pub fn segment_slopes(rows: &[ThickRow], form: &str) -> Vec<(usize, usize, f64)> {
    let r: Vec<&ThickRow> = rows.iter().filter(|r| r.form == form).collect();
    r.windows(2)
        .map(|w| {
            let (x, y) = ([w[0], w[1]].map(|r| r.contact_nodes as f64), [w[0], w[1]].map(|r| r.contact[1]));
            (w[0].contact_nodes, w[1].contact_nodes, loglog_slope(&x, &y))
        })
        .collect()
}

/// thick.svg: the median contact solve per step of both forms and the free solve, against n_c.
pub fn svg(rows: &[ThickRow], plan: &ThickPlan) -> Result<String> {
    let series = vec![
        LogSeries {
            name: "contact solve, hierarchical W⁻¹ + near field".into(),
            points: points(rows, "hierarchical", |r| r.contact[1]),
        },
        LogSeries {
            name: "contact solve, dense W⁻¹ + near field (before)".into(),
            points: points(rows, "near field", |r| r.contact[1]),
        },
        LogSeries {
            name: "contact solve, node blocks (before)".into(),
            points: points(rows, "node blocks", |r| r.contact[1]),
        },
        LogSeries {
            name: "free solve (forward pass + backward over the contact reach)".into(),
            points: points(rows, "hierarchical", |r| r.free[1]),
        },
    ];
    let title = format!("thick academic3d boxes, first {} steps: median seconds per step", plan.steps);
    loglog::loglog_chart("thick.svg", &title, ("contact nodes n_c", "seconds per step"), &series, (1.0, 3.0))
}

/// The printed lines of the thick part.
pub fn report(rows: &[ThickRow], plan: &ThickPlan) -> String {
    let mut s = String::from("thick 3-D boxes (academic3d refined, velocity form): per step min / median\n");
    let _ = writeln!(
        s,
        "{:>10} {:>8} {:>6} {:<13} {:>17} {:>19} {:>8} {:>8} {:>8} {:>8} {:>8} {:>10} {:>17} {:>8} {:>8} {:>15} {:>9}",
        "cells",
        "unknowns",
        "n_c",
        "form",
        "free[ms]",
        "contact[ms]",
        "c/free",
        "rec[ms]",
        "pair[ms]",
        "c/pair",
        "c/adj",
        "A_k+W[s]",
        "W route (solves)",
        "Newton",
        "CG",
        "peak (est.) MB",
        "L[M]"
    );
    for r in rows {
        let _ = writeln!(
            s,
            "{:>10} {:>8} {:>6} {:<13} {:>8.1} /{:>7.1} {:>9.1} /{:>8.1} {:>8.2} {:>8.1} {:>8.1} {:>8.2} {:>8.2} {:>4.1}+{:<5.1} {:>7} ({:>7.1}) {:>8} {:>8} {:>7.0} ({:>5.0}) {:>6.1} {}",
            format!("{}x{}x{}", r.cells[0], r.cells[1], r.cells[2]),
            r.unknowns,
            r.contact_nodes,
            r.form,
            1e3 * r.free[0],
            1e3 * r.free[1],
            1e3 * r.contact[0],
            1e3 * r.contact[1],
            r.contact[1] / r.free[1],
            1e3 * r.recovery[1],
            1e3 * r.pair,
            r.contact[1] / r.pair,
            r.adjacent.ratio[1],
            r.factorization,
            r.delassus,
            r.route,
            r.delassus_solves,
            r.newton_iterations,
            r.cg_iterations,
            r.peak_mb,
            r.estimate_mb,
            r.factor_entries as f64 / 1e6,
            if r.fill_order == "nested dissection" { "ND" } else { "AMD" }
        );
    }
    let family = &plan.boxes;
    let _ = writeln!(
        s,
        "median contact solve per step against n_c along the family: log–log slope {:.2} hierarchical, {:.2} with the near field, {:.2} with node blocks",
        slope(rows, "hierarchical", family),
        slope(rows, "near field", family),
        slope(rows, "node blocks", family)
    );
    let segments: Vec<String> =
        segment_slopes(rows, "hierarchical").iter().map(|(a, b, s)| format!("{a} → {b}: {s:.2}")).collect();
    let _ = writeln!(s, "hierarchical, between neighbouring boxes: {}", segments.join(", "));
    if let Some(last) = family.last().filter(|_| !plan.beyond.is_empty()) {
        let past: Vec<[i64; 3]> = std::iter::once(*last).chain(plan.beyond.iter().copied()).collect();
        let _ = writeln!(
            s,
            "hierarchical, from the family's largest box on ({} boxes): log–log slope {:.2}",
            past.len(),
            slope(rows, "hierarchical", &past)
        );
    }
    s
}

/// When academic3d's shaking starts: its right-side traction is `if(t >= 0.2, …, 0)`.
pub const SHAKING_FROM: f64 = 0.2;

/// What the shaking window runs.
#[derive(Debug, Clone)]
pub struct ShakePlan {
    pub boxes: Vec<[i64; 3]>,
    /// the window from the shaking onset, in steps of academic3d's k = 5e-4 (each box runs the
    /// same simulated time at its own step, [`shaking_step`])
    pub steps: usize,
}

impl ShakePlan {
    /// The thick family's boxes over 0.02 s of shaking (40 steps of 5e-4; 64×32×24 with
    /// `largest`: its 1,200 pressing steps at 1.67e-4 and three windows of 120 steps took 15–24
    /// min, by the progress lines, of the 43 min `--thick-only --thick-largest` run of
    /// 2026-11-28; the bench adds the boxes
    /// of `--thick-beyond`, 1,600 pressing steps each at 1.25e-4: not run since the window moved
    /// inside (C.k), expect hours).
    pub fn full(largest: bool) -> ShakePlan {
        ShakePlan { boxes: ThickPlan::full(largest).boxes, steps: 40 }
    }
    /// The smoke test's plan: the smallest box of the quick thick plan, 3 shaking steps.
    pub fn quick() -> ShakePlan {
        ShakePlan { boxes: ThickPlan::quick().boxes[..1].to_vec(), steps: 3 }
    }
}

/// The runs of the shaking window: a label (thick_shaking.csv's `inner`), the inner solver and
/// F.1's start, as the scene names them.
pub const SHAKING_RUNS: [(&str, InnerSolver, FixedPointStart); 3] = [
    ("newton-predictor", InnerSolver::Newton, FixedPointStart::Predictor),
    ("newton", InnerSolver::Newton, FixedPointStart::Auto),
    ("newton-unfrozen", InnerSolver::NewtonUnfrozen, FixedPointStart::Auto),
];

/// A box's shaking scene: pressed until SHAKING_FROM, then `steps` steps of academic3d's k of
/// shaking in simulated time, at the box's [`shaking_step`], in the form the run picks itself
/// (dense products below HMATRIX_FROM = 400 components, hierarchical above; node blocks below
/// NEAR_FIELD_FROM = 1,200, the near field above).
fn shaking_scene(cells: [i64; 3], steps: usize) -> Result<Scene> {
    let mut s = scene(cells, 1)?;
    s.time.step = shaking_step(cells);
    let pressing = (SHAKING_FROM / s.time.step).round() as usize;
    let window = (steps as f64 * ACADEMIC3D_STEP / s.time.step).round() as usize;
    s.time.end = s.time.step * (pressing + window) as f64;
    s.solver.contact_solve = dyncontact::model::kinds::ContactSolve::Auto;
    Ok(s)
}

/// The shaking window's step on a box: academic3d's k = 5e-4 scaled with the cell height,
/// 5e-4 · 8/n_z (never above 5e-4): (C.k) bounds k by a multiple of the contact nodes' mass over
/// their area, which shrinks with the height, so this keeps every box of the family inside it
/// (margins of 4%: limits 5.21e-4, 3.47e-4, 2.60e-4, 1.74e-4 from 24×12×8 to 64×32×24).
pub fn shaking_step(cells: [i64; 3]) -> f64 {
    ACADEMIC3D_STEP * (8.0 / cells[2] as f64).min(1.0)
}

/// academic3d's time step.
const ACADEMIC3D_STEP: f64 = 5e-4;

/// One solver's shaking window on one box.
#[derive(Debug, Clone)]
pub struct ShakeRow {
    pub cells: [i64; 3],
    pub unknowns: usize,
    pub contact_nodes: usize,
    /// the label of one of SHAKING_RUNS
    pub inner: &'static str,
    /// the time step, s ([`shaking_step`])
    pub step: f64,
    pub steps: usize,
    /// per step, seconds: [min, median]
    pub free: [f64; 2],
    pub contact: [f64; 2],
    /// one whole solve pair with A_k's factor, as [`ThickRow::pair`]
    pub pair: f64,
    /// as [`ThickRow::adjacent`]
    pub adjacent: Adjacent,
    /// convex solves of F.1 over the window (0 where N.4 solved every step)
    pub convex_solves: usize,
    pub newton_iterations: usize,
    pub cg_iterations: usize,
    /// N.4 steps that fell back to F.1
    pub fallbacks: usize,
    /// nodes slipping and sticking at the window's last step
    pub slip_nodes: usize,
    pub stick_nodes: usize,
}

/// The shaking window of every box, three runs each ([`SHAKING_RUNS`]); every box's step is
/// checked against (C.k) before any runs.
pub fn run_shaking(plan: &ShakePlan, progress: &dyn Fn(&str)) -> Result<Vec<ShakeRow>> {
    let mut rows = Vec::new();
    // every box checked before the first one's hours of runs; its problem built again below
    // rather than all kept (GBs for the largest boxes)
    for &cells in &plan.boxes {
        let p = Problem::from_scene(&shaking_scene(cells, plan.steps)?, Path::new("."))?;
        if !matches!(p.convexity_limit(), ConvexityLimit::Step { k, .. } if p.k <= k) {
            return Err(Error::Study(format!("thick shaking: k = {:e} on {cells:?} is beyond (C.k)", p.k)));
        }
    }
    for &cells in &plan.boxes {
        let s = shaking_scene(cells, plan.steps)?;
        let pressing = (SHAKING_FROM / s.time.step).round() as usize;
        let p = Problem::from_scene(&s, Path::new("."))?;
        progress(&format!(
            "thick shaking: {}x{}x{}, k = {:.3e}, {pressing} pressing steps",
            cells[0], cells[1], cells[2], p.k
        ));
        let mut sim = Simulation::new(&p)?;
        for rec in sim.steps().take(pressing) {
            rec?;
        }
        let onset = sim.state.clone();
        for (inner, solver, start) in SHAKING_RUNS {
            progress(&format!("thick shaking: {}x{}x{}, {inner}", cells[0], cells[1], cells[2]));
            sim.restore(onset.clone())?;
            // every run starts cold: a fresh factor cache, the same state
            sim.delassus_factors = DelassusFactors::default();
            let mut variant = p.model.solver;
            (variant.inner, variant.fixed_point_start) = (solver, start);
            sim.settings = Settings::from_solver(&p, &variant);
            let (mut free, mut contact) = (Vec::new(), Vec::new());
            let (mut convex, mut newton_iterations, mut fallbacks, mut last) = (0, 0, 0, (0, 0));
            let (adjacent_pairs, ratios) = steps_with_adjacent_pairs(&mut sim, |rec| {
                free.push(rec.timing.free_solve);
                contact.push(rec.timing.contact_solve);
                convex += rec.report.fixed_point_iterations;
                newton_iterations += rec.report.inner_iterations;
                fallbacks += usize::from(rec.report.fallback.is_some());
                last = (rec.slip_nodes, rec.stick_nodes);
            })?;
            let pair = solve_pair(&sim);
            rows.push(ShakeRow {
                cells,
                unknowns: p.dofs.n_free,
                contact_nodes: p.contact.as_ref().map_or(0, |c| c.n()),
                inner,
                step: p.k,
                steps: free.len(),
                free: min_median(free),
                contact: min_median(contact),
                pair,
                adjacent: Adjacent::of(adjacent_pairs, ratios),
                convex_solves: convex,
                newton_iterations,
                cg_iterations: sim.delassus_factors.all_counts().velocity_iterations,
                fallbacks,
                slip_nodes: last.0,
                stick_nodes: last.1,
            });
        }
    }
    Ok(rows)
}

/// thick_shaking.csv.
pub fn shaking_csv(rows: &[ShakeRow]) -> String {
    csv_table(
        &format!(
            "cells,unknowns,contact_nodes,inner,step_s,steps,free_min_s,free_median_s,contact_min_s,contact_median_s,\
contact_over_free,convex_solves,newton_iterations,cg_iterations,fallbacks,slip_nodes,stick_nodes,pair_median_s,\
contact_over_pair,{ADJACENT_COLUMNS}"
        ),
        rows.iter().map(|r| {
            vec![
                format!("{}x{}x{}", r.cells[0], r.cells[1], r.cells[2]),
                r.unknowns.to_string(),
                r.contact_nodes.to_string(),
                r.inner.to_string(),
                format!("{:e}", r.step),
                r.steps.to_string(),
                format!("{:.6e}", r.free[0]),
                format!("{:.6e}", r.free[1]),
                format!("{:.6e}", r.contact[0]),
                format!("{:.6e}", r.contact[1]),
                format!("{:.3}", r.contact[1] / r.free[1]),
                r.convex_solves.to_string(),
                r.newton_iterations.to_string(),
                r.cg_iterations.to_string(),
                r.fallbacks.to_string(),
                r.slip_nodes.to_string(),
                r.stick_nodes.to_string(),
                format!("{:.6e}", r.pair),
                format!("{:.3}", r.contact[1] / r.pair),
            ]
            .into_iter()
            .chain(r.adjacent.fields())
            .collect()
        }),
    )
}

/// The printed lines of the shaking window.
pub fn shaking_report(rows: &[ShakeRow]) -> String {
    let mut s = format!(
        "thick 3-D boxes while shaken (from t = {SHAKING_FROM} s, k = 5e-4 · 8/n_z inside (C.k), the same state for every run): per step min / median\n"
    );
    let _ = writeln!(
        s,
        "{:>10} {:>6} {:>9} {:<16} {:>17} {:>19} {:>8} {:>8} {:>8} {:>8} {:>12} {:>12} {:>8} {:>9}",
        "cells",
        "n_c",
        "k",
        "inner",
        "free[ms]",
        "contact[ms]",
        "c/free",
        "pair[ms]",
        "c/pair",
        "c/adj",
        "convex/step",
        "Newton/step",
        "CG",
        "fallbacks"
    );
    for r in rows {
        let per = |v: usize| v as f64 / r.steps.max(1) as f64;
        let _ = writeln!(
            s,
            "{:>10} {:>6} {:>9.3e} {:<16} {:>8.1} /{:>7.1} {:>9.1} /{:>8.1} {:>8.2} {:>8.1} {:>8.2} {:>8.2} {:>12.1} {:>12.1} {:>8} {:>9}",
            format!("{}x{}x{}", r.cells[0], r.cells[1], r.cells[2]),
            r.contact_nodes,
            r.step,
            r.inner,
            1e3 * r.free[0],
            1e3 * r.free[1],
            1e3 * r.contact[0],
            1e3 * r.contact[1],
            r.contact[1] / r.free[1],
            1e3 * r.pair,
            r.contact[1] / r.pair,
            r.adjacent.ratio[1],
            per(r.convex_solves),
            per(r.newton_iterations),
            r.cg_iterations,
            r.fallbacks
        );
    }
    s
}

/// The issue's own measure (thick_run.csv): academic3d refined, run from t = 0 as a user runs
/// it — its own k = 5e-4 (beyond (C.k) from 544 contact nodes on), its own solver settings and
/// `contact_solve = "auto"` — over its first 0.3 s: 0.2 s of pressing, then 0.1 s of the
/// oblique shaking. The table was that run's free and contact solve per step (their
/// totals over the steps); here also the medians, each phase's means and a whole solve pair
/// timed after every `PAIR_EVERY`-th step.
#[derive(Debug, Clone)]
pub struct RunPlan {
    pub boxes: Vec<[i64; 3]>,
    /// simulated seconds from t = 0
    pub end: f64,
}

impl RunPlan {
    /// The family (64×32×24 with `largest`: ~10 min and ~4.3 GB here), the first 0.3 s.
    pub fn full(largest: bool) -> RunPlan {
        RunPlan { boxes: ThickPlan::full(largest).boxes, end: 0.3 }
    }
    /// The smoke test's plan: the smallest quick box, 3 steps.
    pub fn quick() -> RunPlan {
        RunPlan { boxes: ThickPlan::quick().boxes[..1].to_vec(), end: 3.0 * ACADEMIC3D_STEP }
    }
}

/// A solve pair is timed after the first step and every this many steps of a whole run, outside
/// the steps' own clocks (the per-step free and contact solves do not include it; the run's
/// wall time does: ~60 pairs over 600 steps, and each leaves the caches with A_k's factor, which
/// may slow the step after it — the bench's 48×24×16 means were 3–4% above a plain `run`'s in
/// one run, 5–12% in another).
const PAIR_EVERY: usize = 10;

/// One box's run over [`RunPlan::end`].
#[derive(Debug, Clone)]
pub struct RunRow {
    pub cells: [i64; 3],
    pub unknowns: usize,
    pub contact_nodes: usize,
    pub steps: usize,
    /// the time step, s
    pub step: f64,
    /// (C.k)'s limit on it (None: no limit applies)
    pub ck_limit: Option<f64>,
    /// whether (Ck.1) held at setup (None: not tested, inside (C.k) or not applicable)
    pub ck_sharp: Option<bool>,
    /// the form the run took (summary.json's `contact_solve`)
    pub form: String,
    /// per step over the whole run, seconds: mean, median (the ratio is that of the
    /// totals over the steps, which is the ratio of the means)
    pub free: [f64; 2],
    pub contact: [f64; 2],
    /// [free, contact] means per step while pressed and while shaken ([`first_shaken`])
    pub pressed: [f64; 2],
    pub shaken: [f64; 2],
    /// median of the solve pairs timed every PAIR_EVERY steps
    pub pair: f64,
    pub setup: f64,
    pub factorization: f64,
    pub delassus: f64,
    pub sharp_convexity: f64,
    /// the run's wall time, the solve pairs timed beside it included
    pub wall: f64,
    pub newton_iterations: usize,
    pub convex_solves: usize,
    pub peak_mb: f64,
    pub estimate_mb: f64,
}

impl RunRow {
    /// The ratio: the contact solve over the free solve, both per step over the run.
    pub fn ratio(&self) -> f64 {
        self.contact[0] / self.free[0]
    }
}

/// academic3d on `cells` from t = 0 to `end`, as its file sets it otherwise (no frames: the
/// in-memory run writes nothing).
fn whole_scene(cells: [i64; 3], end: f64) -> Result<Scene> {
    let mut s = academic3d_box("thick_run", cells)?;
    s.time.end = end;
    Ok(s)
}

/// The index of the first shaken step among steps ending at `t_end` (their count if none is):
/// the first step ending after SHAKING_FROM. academic3d's shaking traction is `if(t >= 0.2, …)`
/// and its midpoint scheme takes the loads at the step's middle, so the step ending at 0.2 is
/// the last pressed one (loads at 0.2 − k/2) and the next the first shaken (0.2 + k/2). The
/// 1e-9 s absorbs the round-off of n·k against 0.2 (steps of ≥ 1e-4 s).
fn first_shaken(t_end: &[f64]) -> usize {
    t_end.iter().position(|&t| t > SHAKING_FROM + 1e-9).unwrap_or(t_end.len())
}

/// The mean of `v` (NaN for none).
fn mean(v: &[f64]) -> f64 {
    if v.is_empty() { f64::NAN } else { v.iter().sum::<f64>() / v.len() as f64 }
}

/// Every box of the plan, one run each, in the order given.
pub fn run_whole(plan: &RunPlan, progress: &dyn Fn(&str)) -> Result<Vec<RunRow>> {
    let mut rows = Vec::new();
    for &cells in &plan.boxes {
        progress(&format!("thick run: {}x{}x{}, t = 0 … {} s", cells[0], cells[1], cells[2], plan.end));
        let p = Problem::from_scene(&whole_scene(cells, plan.end)?, Path::new("."))?;
        let estimate_mb = dyncontact::resources::estimate(&p.model, Path::new("."))?.total() / 1e6;
        dyncontact::resources::reset_peak_memory();
        let (mut free, mut contact, mut t_end, mut pairs) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut b = Vec::new();
        let summary = dyncontact::run::run_in_memory(&p, &Default::default(), None, |rec, sim| {
            if rec.step == 0 {
                return;
            }
            free.push(rec.timing.free_solve);
            contact.push(rec.timing.contact_solve);
            t_end.push(rec.t);
            if rec.step == 1 || rec.step % PAIR_EVERY == 0 {
                if b.is_empty() {
                    b = pair_rhs(sim);
                }
                pairs.push(pair_once(sim, &b));
            }
        })?;
        let d = summary
            .run
            .as_ref()
            .ok_or_else(|| Error::Study(format!("thick run: {cells:?} ended without its details")))?;
        let split = first_shaken(&t_end);
        let phase = |a: usize, b: usize| [mean(&free[a..b]), mean(&contact[a..b])];
        rows.push(RunRow {
            cells,
            unknowns: p.dofs.n_free,
            contact_nodes: p.contact.as_ref().map_or(0, |c| c.n()),
            steps: free.len(),
            step: p.k,
            ck_limit: d.model.ck_step_limit,
            ck_sharp: d.model.ck_sharp,
            form: d.contact_solve.clone(),
            pressed: phase(0, split),
            shaken: phase(split, free.len()),
            free: [mean(&free), min_median(free.clone())[1]],
            contact: [mean(&contact), min_median(contact.clone())[1]],
            pair: min_median(pairs)[1],
            setup: d.timing.setup_s,
            factorization: d.timing.factorization_s,
            delassus: d.timing.delassus_s,
            sharp_convexity: d.timing.sharp_convexity_s,
            wall: d.wall_time_s,
            newton_iterations: d.newton_iterations_total,
            convex_solves: d.fixed_point_iterations_total,
            peak_mb: d.peak_memory_mb.unwrap_or(f64::NAN),
            estimate_mb,
        });
    }
    Ok(rows)
}

/// thick_run.csv.
pub fn run_csv(rows: &[RunRow]) -> String {
    let opt = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v:e}"));
    csv_table(
        "cells,unknowns,contact_nodes,steps,step_s,ck_limit_s,ck_sharp,form,free_mean_s,free_median_s,\
contact_mean_s,contact_median_s,contact_over_free,pressed_free_mean_s,pressed_contact_mean_s,\
shaken_free_mean_s,shaken_contact_mean_s,pair_median_s,contact_mean_over_pair,setup_s,factorization_s,\
delassus_s,sharp_convexity_s,wall_s,newton_iterations,convex_solves,peak_mb,estimate_mb",
        rows.iter().map(|r| {
            vec![
                format!("{}x{}x{}", r.cells[0], r.cells[1], r.cells[2]),
                r.unknowns.to_string(),
                r.contact_nodes.to_string(),
                r.steps.to_string(),
                format!("{:e}", r.step),
                opt(r.ck_limit),
                r.ck_sharp.map_or(String::new(), |b| b.to_string()),
                r.form.clone(),
                format!("{:.6e}", r.free[0]),
                format!("{:.6e}", r.free[1]),
                format!("{:.6e}", r.contact[0]),
                format!("{:.6e}", r.contact[1]),
                format!("{:.3}", r.ratio()),
                format!("{:.6e}", r.pressed[0]),
                format!("{:.6e}", r.pressed[1]),
                format!("{:.6e}", r.shaken[0]),
                format!("{:.6e}", r.shaken[1]),
                format!("{:.6e}", r.pair),
                format!("{:.3}", r.contact[0] / r.pair),
                format!("{:.3}", r.setup),
                format!("{:.3}", r.factorization),
                format!("{:.3}", r.delassus),
                format!("{:.3}", r.sharp_convexity),
                format!("{:.3}", r.wall),
                r.newton_iterations.to_string(),
                r.convex_solves.to_string(),
                format!("{:.0}", r.peak_mb),
                format!("{:.0}", r.estimate_mb),
            ]
        }),
    )
}

/// The printed lines of the whole runs.
pub fn run_report(rows: &[RunRow], plan: &RunPlan) -> String {
    let mut s = format!(
        "thick 3-D boxes run as a user runs them (academic3d, t = 0 … {} s, its own k, solver and `auto` form): per step\n",
        plan.end
    );
    let _ = writeln!(
        s,
        "{:>10} {:>6} {:>9} {:>17} {:>19} {:>8} {:>17} {:>17} {:>8} {:>8} {:>9} {:>8} {:>8} {:>12}",
        "cells",
        "n_c",
        "k/(C.k)",
        "free[ms] mean/med",
        "contact[ms] mean/med",
        "c/free",
        "pressed c/free",
        "shaken c/free",
        "pair[ms]",
        "c/pair",
        "setup[s]",
        "Newton",
        "convex",
        "peak(check)"
    );
    for r in rows {
        let ratio = |p: [f64; 2]| if p[0] > 0.0 { p[1] / p[0] } else { f64::NAN };
        let _ = writeln!(
            s,
            "{:>10} {:>6} {:>9.2} {:>8.1} /{:>7.1} {:>9.1} /{:>8.1} {:>8.2} {:>17.2} {:>17.2} {:>8.1} {:>8.2} {:>9.1} {:>8} {:>8} {:>12}",
            format!("{}x{}x{}", r.cells[0], r.cells[1], r.cells[2]),
            r.contact_nodes,
            r.ck_limit.map_or(f64::NAN, |k| r.step / k),
            1e3 * r.free[0],
            1e3 * r.free[1],
            1e3 * r.contact[0],
            1e3 * r.contact[1],
            r.ratio(),
            ratio(r.pressed),
            ratio(r.shaken),
            1e3 * r.pair,
            r.contact[0] / r.pair,
            r.setup,
            r.newton_iterations,
            r.convex_solves,
            format!("{:.0} ({:.0})", r.peak_mb, r.estimate_mb)
        );
    }
    s
}

#[cfg(test)]
mod tests {
    /// The whole run's phases: the step ending at 0.2 s (loads at 0.2 − k/2 under the midpoint
    /// rule) is the last pressed one, the step after it the first shaken; n·k's round-off near
    /// 0.2 does not move the split; a run that ends before the shaking has no shaken step.
    #[test]
    fn the_step_ending_at_the_onset_is_the_last_pressed_one() {
        let k = 5e-4;
        let t_end: Vec<f64> = (1..=600).map(|n| n as f64 * k).collect();
        assert_eq!(super::first_shaken(&t_end), 400, "steps 1..=400 end at or before 0.2 s");
        assert_eq!(super::first_shaken(&[0.1995, 0.2 + 1e-15, 0.2005]), 2);
        assert_eq!(super::first_shaken(&[0.1995, 0.2]), 2, "no shaken step");
        assert_eq!(super::first_shaken(&[]), 0);
    }
}
