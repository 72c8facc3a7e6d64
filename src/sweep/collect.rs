//! `DIR/sweep.csv` and `DIR/plots/` from the points' folders: the same files whether the points
//! ran here (`dyncontact sweep`) or as Snakemake jobs (`dyncontact sweep collect DIR`).
//!
//! sweep.csv has one row per point: `point`, one column per axis (named by its key or name, the
//! value's label), `status`, `wall_time_s`, the figures of [`FIGURES`] (from the point's
//! history.csv and summary.json; empty where the run gave none), `reason` (why it failed,
//! or why it is corrupt) and, last, `warnings` (the run's summary.json warnings joined by `; `:
//! a point that ran beyond (C.k) says so; [`warnings_line`] is the one line printed after a
//! sweep).
//!
//! Every point's files are checked before its figures are read: summary.json readable with a
//! known status; history.csv with one row per completed step (steps_completed + 1 rows, steps
//! 0, 1, … in order), every value a finite number; a completed point's inputs (the scene and
//! the files it reads) unchanged since it ran. A point that fails a check is `corrupt`, with the
//! reason, and no figure of it is reported. Statuses: completed, failed, interrupted, running
//! (a run in progress, or killed), missing (not run yet), corrupt.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;

use serde::Deserialize;

use super::{Plan, Point};
use crate::error::{Error, Result};
use crate::failure::RunStatus;
use crate::output::Summary;
use crate::output::csv::csv_field;
use crate::output::plots::{Options, Panel, Series, stacked_chart};
use crate::output::write_atomic;

/// The figures of sweep.csv, in column order (SCENES.md: final energies, cumulative
/// dissipations, max normal force, max penetration, max |energy_residual|, iteration totals),
/// then the iteration totals' means per step (total / steps_completed: a total grows with the
/// number of steps, so against time.step it reads the wrong way round).
pub const FIGURES: [&str; 20] = [
    "final_kinetic",
    "final_elastic",
    "final_compliance",
    "external_work",
    "viscous_dissipation",
    "friction_dissipation",
    "constraint_dissipation",
    "persistency_dissipation",
    "max_normal_force",
    "max_tangential_force",
    "max_penetration",
    "max_abs_energy_residual",
    "max_relative_energy_residual",
    "newton_iterations",
    "fixed_point_iterations",
    "fixed_point_cap_hits",
    "steps_completed",
    "final_time",
    "newton_iterations_per_step",
    "fixed_point_iterations_per_step",
];

/// A point's `status` in sweep.csv: how its run ended (its summary.json's status), or why no
/// run of it can be read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PointStatus {
    /// the point's summary.json says how its run ended
    Run(RunStatus),
    /// not run yet: no summary.json
    Missing,
    /// its files do not agree (the row's reason says why): none of its figures is reported
    Corrupt,
}

impl PointStatus {
    /// The word sweep.csv writes: the run's status, `missing` or `corrupt`.
    pub fn as_str(self) -> &'static str {
        match self {
            PointStatus::Run(s) => s.as_str(),
            PointStatus::Missing => "missing",
            PointStatus::Corrupt => "corrupt",
        }
    }

    /// Whether the point's run completed.
    pub fn is_completed(self) -> bool {
        self == PointStatus::Run(RunStatus::Completed)
    }
}

impl std::fmt::Display for PointStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// One row of sweep.csv.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    pub point: String,
    /// the label of each axis' value
    pub axes: Vec<String>,
    pub status: PointStatus,
    pub wall_time_s: Option<f64>,
    /// the run's space dimension (2 or 3), where its summary.json says it
    pub dim: Option<usize>,
    /// the figures of [`FIGURES`], as written (empty: not available)
    pub figures: Vec<String>,
    pub reason: String,
    /// the run's warnings (summary.json `warnings`: (C.k), (F.1) cap hits, (E.1) guard, …)
    pub warnings: Vec<String>,
}

impl Row {
    /// The value of figure `name` as a number, if the row has it.
    pub fn figure(&self, name: &str) -> Option<f64> {
        let i = FIGURES.iter().position(|f| *f == name)?;
        self.figures.get(i)?.parse().ok()
    }
}

/// The `status` of a point folder's summary.json, as the word it stores (None: there is no
/// summary that reads as one).
pub fn point_status(pd: &Path) -> Option<RunStatus> {
    Summary::read(pd).map(|s| s.status)
}

/// The inputs fingerprint of a point's scene with its files as they are now.
fn current_inputs(pd: &Path, scene_text: &str) -> Option<String> {
    let model = crate::scene::Scene::from_toml(scene_text, "scene.toml").and_then(|s| s.validate()).ok()?;
    crate::fingerprint::inputs(&model, pd).ok()
}

/// Why the JSON `v` of a summary.json is not a [`Summary`] (`e`: serde's reason): no status, an
/// unknown status, no steps_completed, or another key missing or of the wrong form.
fn not_a_summary(v: &serde_json::Value, e: &serde_json::Error) -> String {
    let Some(status) = v.get("status").and_then(|v| v.as_str()) else {
        return "summary.json has no status".into();
    };
    if serde_json::from_value::<RunStatus>(status.into()).is_err() {
        return format!("summary.json has the unknown status {status:?}");
    }
    if v.get("steps_completed").and_then(|v| v.as_u64()).is_none() {
        return "summary.json has no steps_completed".into();
    }
    format!("summary.json is not a summary of this version ({e})")
}

/// Read every point of the sweep in `dir` (its sweep.json and point folders).
pub fn rows(dir: &Path) -> Result<(Plan, Vec<Row>)> {
    let plan = Plan::read(dir)?;
    let rows = plan.points.iter().map(|p| row(&plan, p, &Plan::point_dir(dir, &p.id))).collect::<Result<Vec<_>>>()?;
    Ok((plan, rows))
}

/// A point folder's summary when its files agree ([`check_point`]); otherwise its status in
/// sweep.csv with the reason: `missing` (no summary.json) or `corrupt`.
fn checked_summary(pd: &Path) -> std::result::Result<Summary, (PointStatus, String)> {
    let sp = pd.join("summary.json");
    if !sp.exists() {
        return Err((PointStatus::Missing, String::new()));
    }
    let value = std::fs::read_to_string(&sp)
        .map_err(|e| e.to_string())
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).map_err(|e| e.to_string()))
        .map_err(|e| (PointStatus::Corrupt, format!("summary.json is not readable JSON ({e})")))?;
    let summary = Summary::deserialize(&value).map_err(|e| (PointStatus::Corrupt, not_a_summary(&value, &e)))?;
    check_point(&summary, pd).map_err(|reason| (PointStatus::Corrupt, reason))?;
    Ok(summary)
}

/// A point folder's status as sweep.csv gives it: its run's, where its files agree (a completed
/// point's inputs unchanged since it ran), else `missing` or `corrupt`.
pub fn checked_status(pd: &Path) -> PointStatus {
    match checked_summary(pd) {
        Ok(s) => PointStatus::Run(s.status),
        Err((status, _)) => status,
    }
}

/// One point's row.
fn row(plan: &Plan, p: &Point, pd: &Path) -> Result<Row> {
    let axes: Vec<String> = plan.axes.iter().zip(&p.choice).map(|(a, &c)| a.labels[c].clone()).collect();
    let bare = |status: PointStatus, reason: String| Row {
        point: p.id.clone(),
        axes: axes.clone(),
        status,
        wall_time_s: None,
        dim: None,
        figures: vec![String::new(); FIGURES.len()],
        reason,
        warnings: Vec::new(),
    };
    let summary = match checked_summary(pd) {
        Ok(s) => s,
        Err((status, reason)) => return Ok(bare(status, reason)),
    };
    let mut figures: HashMap<&str, String> = HashMap::new();
    // from summary.json, each number as JSON writes it
    let json = |x: serde_json::Value| x.to_string();
    figures.insert("steps_completed", json(summary.steps_completed.into()));
    if let Some(d) = &summary.run {
        for (fig, v) in [
            ("max_abs_energy_residual", json(d.max_abs_energy_residual.into())),
            ("max_relative_energy_residual", json(d.max_relative_energy_residual.into())),
            ("newton_iterations", json(d.newton_iterations_total.into())),
            ("fixed_point_iterations", json(d.fixed_point_iterations_total.into())),
            ("fixed_point_cap_hits", json(d.fixed_point_cap_hits.into())),
            ("final_time", json(d.final_time.into())),
        ] {
            figures.insert(fig, v);
        }
        // the means per step of a run that did a step
        let steps = summary.steps_completed;
        if steps > 0 {
            let per_step = |total: usize| json((total as f64 / steps as f64).into());
            figures.insert("newton_iterations_per_step", per_step(d.newton_iterations_total));
            figures.insert("fixed_point_iterations_per_step", per_step(d.fixed_point_iterations_total));
        }
    }
    // from history.csv: the last row and the maxima
    if let Some(h) = History::read(&pd.join("history.csv")) {
        for (fig, col) in [
            ("final_kinetic", "kinetic"),
            ("final_elastic", "elastic"),
            ("final_compliance", "compliance"),
            ("external_work", "external_work"),
            ("viscous_dissipation", "viscous_dissipation"),
            ("friction_dissipation", "friction_dissipation"),
            ("constraint_dissipation", "constraint_dissipation"),
            ("persistency_dissipation", "persistency_dissipation"),
        ] {
            if let Some(v) = h.last(col) {
                figures.insert(fig, v);
            }
        }
        for (fig, col, abs) in [
            ("max_normal_force", "normal_force", false),
            ("max_tangential_force", "tangential_force", true),
            ("max_penetration", "max_penetration", false),
        ] {
            if let Some(v) = h.max(col, abs) {
                figures.insert(fig, crate::output::csv::real(v));
            }
        }
    }
    // an interrupted point runs again from its start: its message (with a resume path that
    // names this folder) is not its reason
    let reason = if summary.status == RunStatus::Interrupted {
        "interrupted: runs again when the sweep runs again".to_string()
    } else {
        summary.failure.clone().unwrap_or_default()
    };
    Ok(Row {
        point: p.id.clone(),
        axes,
        status: PointStatus::Run(summary.status),
        wall_time_s: summary.run.as_ref().map(|d| d.wall_time_s),
        dim: summary.run.as_ref().map(|d| d.model.dim),
        figures: FIGURES.iter().map(|f| figures.remove(f).unwrap_or_default()).collect(),
        reason,
        warnings: summary.run.as_ref().map(|d| d.warnings.clone()).unwrap_or_default(),
    })
}

/// A point's files agree: a known status; history.csv, where the run wrote one, with
/// steps_completed + 1 whole rows of finite numbers, steps in order; a completed run with its
/// history and with the inputs it ran with. Err: why not.
fn check_point(summary: &Summary, pd: &Path) -> std::result::Result<(), String> {
    let (status, steps) = (summary.status, summary.steps_completed);
    let hp = pd.join("history.csv");
    if !hp.exists() {
        // a run that could not start writes no history; any run that started does
        return if status == RunStatus::Failed && steps == 0 {
            Ok(())
        } else {
            Err(format!("history.csv is missing for a {status} run of {steps} steps"))
        };
    }
    let text = std::fs::read_to_string(&hp).map_err(|e| format!("history.csv cannot be read ({e})"))?;
    let mut lines = text.lines();
    let width = lines.next().map(|h| h.split(',').count()).ok_or("history.csv is empty")?;
    let mut rows = 0usize;
    for (i, line) in lines.enumerate() {
        let fields: Vec<&str> = line.split(',').collect();
        if fields.len() != width {
            return Err(format!(
                "history.csv row {} has {} fields, not {width} (a truncated file?)",
                i + 2,
                fields.len()
            ));
        }
        if fields[0].parse::<usize>() != Ok(i) {
            return Err(format!("history.csv row {} is not step {i}", i + 2));
        }
        if let Some((c, v)) = fields.iter().enumerate().find(|(_, v)| !v.parse::<f64>().is_ok_and(f64::is_finite)) {
            return Err(format!("history.csv row {} column {} holds {v:?}, not a finite number", i + 2, c + 1));
        }
        rows += 1;
    }
    // a running (or killed) run may be one row ahead of its last summary
    if rows != steps + 1 && !(status == RunStatus::Running && rows > steps) {
        return Err(format!(
            "history.csv has {rows} rows of steps where summary.json reports {steps} steps (so {} rows)",
            steps + 1
        ));
    }
    let scene_text =
        std::fs::read_to_string(pd.join("scene.toml")).map_err(|e| format!("scene.toml cannot be read ({e})"))?;
    if status == RunStatus::Completed
        && summary.run.as_ref().map(|d| d.inputs_fingerprint.as_str()) != current_inputs(pd, &scene_text).as_deref()
    {
        return Err(
            "its inputs changed since it ran (the scene, or a file it reads such as its mesh): run the sweep again"
                .into(),
        );
    }
    Ok(())
}

/// A point's history.csv: its header and rows (numbers as written).
pub struct History {
    pub columns: Vec<String>,
    pub rows: Vec<Vec<String>>,
}

impl History {
    /// None when the file is missing or empty.
    pub fn read(p: &Path) -> Option<History> {
        let text = std::fs::read_to_string(p).ok()?;
        let mut lines = text.lines();
        let columns: Vec<String> = lines.next()?.split(',').map(str::to_string).collect();
        let rows = lines
            .map(|l| l.split(',').map(str::to_string).collect::<Vec<_>>())
            .filter(|r| r.len() == columns.len())
            .collect();
        Some(History { columns, rows })
    }
    pub fn column(&self, name: &str) -> Option<usize> {
        self.columns.iter().position(|c| c == name)
    }
    /// Column `name` as numbers (NaN where unreadable).
    pub fn numbers(&self, name: &str) -> Option<Vec<f64>> {
        let c = self.column(name)?;
        Some(self.rows.iter().map(|r| r[c].parse().unwrap_or(f64::NAN)).collect())
    }
    fn last(&self, name: &str) -> Option<String> {
        let c = self.column(name)?;
        self.rows.last().map(|r| r[c].clone())
    }
    fn max(&self, name: &str, abs: bool) -> Option<f64> {
        let v = self.numbers(name)?;
        v.into_iter().map(|x| if abs { x.abs() } else { x }).filter(|x| x.is_finite()).reduce(f64::max)
    }
}

/// sweep.csv of `rows`.
pub fn csv(plan: &Plan, rows: &[Row]) -> String {
    let mut s = String::from("point");
    for a in &plan.axes {
        s.push(',');
        s.push_str(&csv_field(&a.column));
    }
    s.push_str(",status,wall_time_s");
    for f in FIGURES {
        s.push(',');
        s.push_str(f);
    }
    s.push_str(",reason,warnings\n");
    for r in rows {
        let _ = write!(s, "{}", r.point);
        for a in &r.axes {
            let _ = write!(s, ",{}", csv_field(a));
        }
        let _ = write!(s, ",{},{}", r.status, r.wall_time_s.map(|t| format!("{t:.3}")).unwrap_or_default());
        for f in &r.figures {
            let _ = write!(s, ",{f}");
        }
        let _ = writeln!(s, ",{},{}", csv_field(&r.reason), csv_field(&r.warnings.join("; ")));
    }
    s
}

/// One line on the points whose runs warned (None: none did): those that ran beyond the (C.k)
/// step limit, then those with other warnings, each with its point ids (sweep.csv's `warnings`
/// column has the words).
pub fn warnings_line(rows: &[Row]) -> Option<String> {
    let ids = |pick: &dyn Fn(&Row) -> bool| -> Vec<&str> {
        rows.iter().filter(|r| pick(r)).map(|r| r.point.as_str()).collect()
    };
    let beyond_ck = |r: &Row| r.warnings.iter().any(|w| w.contains("(C.k)"));
    let ck = ids(&beyond_ck);
    let other = ids(&|r: &Row| r.warnings.iter().any(|w| !w.contains("(C.k)")));
    let listed = |v: &[&str]| {
        let mut s = v.iter().take(10).copied().collect::<Vec<_>>().join(", ");
        if v.len() > 10 {
            s.push_str(", …");
        }
        s
    };
    let n = rows.len();
    let mut parts = Vec::new();
    if !ck.is_empty() {
        parts.push(format!("{} of {n} points ran beyond (C.k): {}", ck.len(), listed(&ck)));
    }
    if !other.is_empty() {
        parts.push(format!("{} of {n} points have other warnings: {}", other.len(), listed(&other)));
    }
    (!parts.is_empty()).then(|| format!("{} (sweep.csv: warnings)", parts.join("; ")))
}

/// Collect the sweep in `dir`: write sweep.csv and plots/<axis>.svg; returns the rows.
pub fn collect(dir: &Path) -> Result<(Plan, Vec<Row>)> {
    let (plan, rows) = rows(dir)?;
    write_atomic(&dir.join("sweep.csv"), csv(&plan, &rows).as_bytes())?;
    let plots = dir.join("plots");
    std::fs::create_dir_all(&plots).map_err(|e| Error::io(&plots, e))?;
    // the figures' units: those of the completed points' dimension, where they share one
    let dims: Vec<usize> = rows.iter().filter(|r| r.status.is_completed()).filter_map(|r| r.dim).collect();
    let dim = dims.first().copied().filter(|d| dims.iter().all(|e| e == d));
    for (a, axis) in plan.axes.iter().enumerate() {
        if axis.numbers.is_some() && !plan.figures.is_empty() {
            let svg = chart(&plan, &rows, a, dim)?;
            write_atomic(&plots.join(format!("{}.svg", file_name(&axis.column))), svg.as_bytes())?;
        }
    }
    Ok((plan, rows))
}

/// A file name for a column (`contact.penalty` → `contact.penalty`, other characters → `_`).
fn file_name(column: &str) -> String {
    column
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() || c == '.' || c == '-' || c == '_' { c } else { '_' })
        .collect()
}

/// Whether values span at least two decades (all positive): the axis is drawn logarithmic.
fn spans_decades(v: &[f64]) -> bool {
    let pos: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    !pos.is_empty()
        && pos.iter().all(|&x| x > 0.0)
        && pos.iter().copied().fold(0.0, f64::max) >= 100.0 * pos.iter().copied().fold(f64::INFINITY, f64::min)
}

/// plots/<axis>.svg: one panel per chosen figure against the axis' numbers, a line per
/// combination of the other axes' values (completed points only); the figures' axes in the
/// units of dimension `dim` (the name alone where the points do not share one).
fn chart(plan: &Plan, rows: &[Row], a: usize, dim: Option<usize>) -> Result<String> {
    let axis = &plan.axes[a];
    let numbers = axis.numbers.as_deref().unwrap_or_default();
    let log_x = spans_decades(numbers);
    // the lines: the other axes' values
    let mut groups: Vec<String> = Vec::new();
    for p in &plan.points {
        let k = group_key(plan, p, a);
        if !groups.contains(&k) {
            groups.push(k);
        }
    }
    let mut panels_data: Vec<(String, Vec<Series>, bool)> = Vec::new();
    for fig in &plan.figures {
        let mut series = Vec::new();
        let mut all = Vec::new();
        for key in &groups {
            let mut pts: Vec<(f64, f64)> = rows
                .iter()
                .zip(&plan.points)
                .filter(|(r, p)| r.status.is_completed() && group_key(plan, p, a) == *key)
                .filter_map(|(r, p)| Some((numbers[p.choice[a]], r.figure(fig)?)))
                .collect();
            pts.sort_by(|x, y| x.0.total_cmp(&y.0));
            all.extend(pts.iter().map(|q| q.1));
            series.push(Series { name: if key.is_empty() { fig.clone() } else { key.clone() }, points: pts });
        }
        let log_y = spans_decades(&all);
        panels_data.push((fig.clone(), series, log_y));
    }
    let y_descs: Vec<String> = panels_data
        .iter()
        .map(|(fig, _, _)| dim.map_or_else(|| fig.clone(), |d| crate::output::units::figure_axis(fig, d)))
        .collect();
    let panels: Vec<(Panel, f64)> = panels_data
        .iter()
        .zip(&y_descs)
        .map(|((fig, series, log_y), y_desc)| {
            (Panel { title: fig, x_desc: &axis.column, y_desc, series, hlines: &[], log: (log_x, *log_y) }, 1.0)
        })
        .collect();
    let opts = Options { markers: true, ..Options::default() };
    stacked_chart(&panels, &opts).map_err(|e| Error::Output(format!("plots/{}.svg: {e}", file_name(&axis.column))))
}

fn group_key(plan: &Plan, p: &Point, a: usize) -> String {
    plan.axes
        .iter()
        .enumerate()
        .filter(|(b, _)| *b != a)
        .map(|(b, ax)| format!("{} = {}", ax.column, ax.labels[p.choice[b]]))
        .collect::<Vec<_>>()
        .join(", ")
}
