//! Thick 3-D bodies (`cargo xtask bench`, part 4b; alone with `--thick-only`): the academic3d
//! box refined in all three directions — 24×12×8, 32×16×12, 48×24×16 (and 64×32×24 with
//! `--thick-largest`) — where W does not decay and stays dense, so the contact solve runs in the
//! velocity form (conjugate gradients on (W⁻¹)_FF + Ĝ_F). Each box runs its first `steps` steps
//! (the pressing phase: half the contact nodes slipping outward) twice from the same setup
//! data: with the near-field preconditioner (the Cholesky factor of W⁻¹'s near field, today's
//! form) and with node blocks (the form before it). Per step: the free solve and the contact
//! solve, min and median over the steps; per run: the setup split (assembly, factorization of
//! A_k, W and W⁻¹) and the process's peak memory.

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use dyncontact::error::{Error, Result};
use dyncontact::output::csv::csv_table;
use dyncontact::output::loglog::{self, LogSeries, loglog_slope};
use dyncontact::problem::Problem;
use dyncontact::scene::Scene;
use dyncontact::simulation::Simulation;

/// What the thick part runs.
#[derive(Debug, Clone)]
pub struct ThickPlan {
    pub boxes: Vec<[i64; 3]>,
    /// steps of academic3d's k = 5e-4 from t = 0
    pub steps: usize,
}

impl ThickPlan {
    /// The family up to 48×24×16 (1,225 contact nodes), 40 steps each.
    pub fn full(largest: bool) -> ThickPlan {
        let mut boxes = vec![[24, 12, 8], [32, 16, 12], [48, 24, 16]];
        if largest {
            boxes.push([64, 32, 24]);
        }
        ThickPlan { boxes, steps: 40 }
    }
    /// The smoke test's plan: the smallest boxes whose W has the GEMV_FROM (256) components the
    /// velocity form needs (12×6×4 has 252: no velocity form, no row).
    pub fn quick() -> ThickPlan {
        ThickPlan { boxes: vec![[16, 8, 4], [20, 10, 6]], steps: 3 }
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
    /// setup seconds: assembly, factorization of A_k, W and W⁻¹ (with its near field)
    pub assembly: f64,
    pub factorization: f64,
    pub delassus: f64,
    /// how the run computed W and W⁻¹ ("schur" from SCHUR_FROM components on, else "solves")
    pub route: &'static str,
    /// seconds W and W⁻¹ take by d n_c solve pairs and W's Cholesky inverse (the route before
    /// the Schur complement), measured beside the run (near-field rows only, else NaN)
    pub delassus_solves: f64,
    pub newton_iterations: usize,
    pub cg_iterations: usize,
    /// the share of W⁻¹'s entries in its near field
    pub near_density: f64,
    /// the values the hierarchical form stores against m² (NaN in the dense forms)
    pub h_share: f64,
    /// the process's peak resident memory after the run, MB
    pub peak_mb: f64,
}

fn scene(cells: [i64; 3], steps: usize) -> Result<Scene> {
    let mut s = Scene::from_toml(include_str!("../../fixtures/scenes/academic3d.toml"), "academic3d.toml")?;
    s.name = format!("thick_{}x{}x{}", cells[0], cells[1], cells[2]);
    s.domain.cells = Some(cells.to_vec());
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

/// The forms a box runs in: W⁻¹'s and W's products through their hierarchical forms with the
/// near-field preconditioner (`auto`'s from HMATRIX_FROM components on; forced here at every
/// size so the slope spans the family), the dense products with the near field, node blocks
/// (dense).
pub const FORMS: [&str; 3] = ["hierarchical", "near field", "node blocks"];

/// One run in `form` (one of FORMS).
fn measure(p: &Problem, cells: [i64; 3], form: &'static str) -> Result<ThickRow> {
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
    // the route before: W by the solves, then its Cholesky inverse (timed, then dropped)
    let delassus_solves = match (form == FORMS[0], p.contact.as_ref()) {
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
    let (mut free, mut contact, mut newton) = (Vec::new(), Vec::new(), 0);
    for rec in sim.steps() {
        let rec = rec?;
        free.push(rec.timing.free_solve);
        contact.push(rec.timing.contact_solve);
        newton += rec.report.inner_iterations;
    }
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
        assembly: t.assembly,
        factorization: t.factorization,
        delassus: t.delassus,
        route: t.delassus_route,
        delassus_solves,
        newton_iterations: newton,
        cg_iterations: counts.velocity_iterations,
        near_density,
        peak_mb: dyncontact::resources::peak_memory().unwrap_or(f64::NAN) / 1e6,
    })
}

/// Every box in every form.
pub fn run(plan: &ThickPlan, progress: &dyn Fn(&str)) -> Result<Vec<ThickRow>> {
    let mut rows = Vec::new();
    for &cells in &plan.boxes {
        let p = Problem::from_scene(&scene(cells, plan.steps)?, Path::new("."))?;
        for form in FORMS {
            progress(&format!("thick: {}x{}x{}, {form}", cells[0], cells[1], cells[2]));
            rows.push(measure(&p, cells, form)?);
        }
    }
    Ok(rows)
}

/// thick.csv.
pub fn csv(rows: &[ThickRow]) -> String {
    csv_table(
        "cells,unknowns,contact_nodes,form,steps,free_min_s,free_median_s,contact_min_s,contact_median_s,\
contact_over_free,assembly_s,factorization_s,delassus_s,delassus_route,delassus_by_solves_s,newton_iterations,cg_iterations,near_density,h_share,peak_mb",
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
            ]
        }),
    )
}

fn points(rows: &[ThickRow], form: &str, value: fn(&ThickRow) -> f64) -> Vec<(f64, f64)> {
    rows.iter().filter(|r| r.form == form).map(|r| (r.contact_nodes as f64, value(r))).collect()
}

/// The log–log slope of the median contact solve per step against n_c for `form`.
pub fn slope(rows: &[ThickRow], form: &str) -> f64 {
    let (x, y): (Vec<f64>, Vec<f64>) = points(rows, form, |r| r.contact[1]).into_iter().unzip();
    if x.len() >= 2 { loglog_slope(&x, &y) } else { f64::NAN }
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
        LogSeries { name: "free solve (one A_k solve pair)".into(), points: points(rows, "near field", |r| r.free[1]) },
    ];
    let title = format!("thick academic3d boxes, first {} steps: median seconds per step", plan.steps);
    loglog::loglog_chart("thick.svg", &title, ("contact nodes n_c", "seconds per step"), &series, (1.0, 3.0))
}

/// The printed lines of the thick part.
pub fn report(rows: &[ThickRow]) -> String {
    let mut s = String::from("thick 3-D boxes (academic3d refined, velocity form): per step min / median\n");
    let _ = writeln!(
        s,
        "{:>10} {:>8} {:>6} {:<13} {:>17} {:>19} {:>8} {:>10} {:>17} {:>8} {:>8} {:>7}",
        "cells",
        "unknowns",
        "n_c",
        "form",
        "free[ms]",
        "contact[ms]",
        "c/free",
        "A_k+W[s]",
        "W route (solves)",
        "Newton",
        "CG",
        "peakMB"
    );
    for r in rows {
        let _ = writeln!(
            s,
            "{:>10} {:>8} {:>6} {:<13} {:>8.1} /{:>7.1} {:>9.1} /{:>8.1} {:>8.2} {:>4.1}+{:<5.1} {:>7} ({:>7.1}) {:>8} {:>8} {:>7.0}",
            format!("{}x{}x{}", r.cells[0], r.cells[1], r.cells[2]),
            r.unknowns,
            r.contact_nodes,
            r.form,
            1e3 * r.free[0],
            1e3 * r.free[1],
            1e3 * r.contact[0],
            1e3 * r.contact[1],
            r.contact[1] / r.free[1],
            r.factorization,
            r.delassus,
            r.route,
            r.delassus_solves,
            r.newton_iterations,
            r.cg_iterations,
            r.peak_mb
        );
    }
    let _ = writeln!(
        s,
        "median contact solve per step against n_c: log–log slope {:.2} hierarchical, {:.2} with the near field, {:.2} with node blocks",
        slope(rows, "hierarchical"),
        slope(rows, "near field"),
        slope(rows, "node blocks")
    );
    s
}
