//! `dyncontact refine` (SCENES.md, "Solution verification"): a scene run on a sequence of
//! systematically refined meshes and steps, and every solution figure of sweep.csv with its
//! observed order, its Richardson extrapolation and Roache's grid convergence index (the
//! solver's costs are listed per level, without an estimate).
//!
//! The levels ℓ = 0 … N−1 (coarsest first) are the points of a sweep with one axis `level`
//! (a `sets` axis): level ℓ has `domain.cells` × r^ℓ in every direction (`what = h`),
//! `time.step` / r^ℓ (`what = k`), or both (`what = both`, the default). So `refine` lays out,
//! runs, resumes and collects exactly as `dyncontact sweep` does (DIR/sweep.csv, DIR/Snakefile;
//! `dyncontact sweep collect DIR` gathers sweep.csv after Snakemake), then writes
//! `DIR/refine.csv` and `DIR/plots/refine_<figure>.svg` from sweep.csv's rows.
//!
//! From the three finest levels f1 (finest), f2, f3 and the ratio r: the observed order
//! (G.1) p = ln((f3 − f2)/(f2 − f1)) / ln r, the extrapolation (G.2)
//! f_ext = f1 + (f1 − f2)/(r^p − 1), and (G.3) GCI = F_s |(f1 − f2)/f1| / (r^p − 1) with
//! F_s = 1.25. A figure is `asymptotic` when the three values converge monotonically
//! (0 < (f3 − f2)/(f2 − f1) < 1) and p lies in [p_e/2, 2 p_e], p_e the scheme's expected order
//! ([`expected_order`]); otherwise the row says why in its `note` and is kept.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::collect::{self, Row};
use super::runner::{self, Outcome, RunnerOptions};
use super::{AxisSpec, Base, Mode, Plan, PlotSpec, SweepFile};
use crate::error::{Error, Result};
use crate::model::kinds::SchemeKind;
use crate::output::csv::csv_field;
use crate::output::plots::{Options, Panel, Series, stacked_chart};
use crate::output::write_atomic;
use crate::overrides::Override;

/// Roache's safety factor for a three-level study (with the observed order).
pub const SAFETY_FACTOR: f64 = 1.25;

/// The default number of levels.
pub const DEFAULT_LEVELS: usize = 3;

/// The most levels: each level multiplies the cells by r^d and the steps by r.
pub const MAX_LEVELS: usize = 8;

/// Two values closer than this many units of round-off of their magnitude are equal: a figure
/// that the levels reproduce to round-off (a bound met exactly) is exact, not noise to fit.
const ROUND_OFF_ULPS: f64 = 8.0;

/// The figures of sweep.csv that `refine` estimates: the values of the solution (final
/// energies, cumulative dissipations, force and penetration maxima, the (E.1) residuals). The
/// solver's counts (iterations, cap hits, steps, final time) are costs, not discretized
/// quantities: refine.csv lists their values per level without an estimate.
pub const FIGURES: [&str; 13] = [
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
];

/// A figure of sweep.csv that is a cost of the solver, not one of [`FIGURES`]: refine.csv lists
/// its values per level without an estimate, and draws no chart of it.
fn is_cost(figure: &str) -> bool {
    collect::FIGURES.contains(&figure) && !FIGURES.contains(&figure)
}

/// What is refined from level to level.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum What {
    /// the mesh: domain.cells × r^ℓ in every direction
    H,
    /// the step: time.step / r^ℓ
    K,
    /// both together at the same ratio
    Both,
}

impl What {
    /// What is refined, in words: "h", "k", or "h and k".
    pub fn words(self) -> &'static str {
        match self {
            What::H => "h (domain.cells)",
            What::K => "k (time.step)",
            What::Both => "h and k together",
        }
    }
    fn refines_h(self) -> bool {
        self != What::K
    }
    fn refines_k(self) -> bool {
        self != What::H
    }
}

/// The options of a refinement study.
#[derive(Debug, Clone, Copy)]
pub struct RefineOptions {
    /// number of levels N ≥ 3
    pub levels: usize,
    /// refinement ratio r > 1 between consecutive levels
    pub ratio: f64,
    pub what: What,
    /// the run [0, T] is split into this many equal windows for the windowed impulses (1: the
    /// whole run only); it must divide the coarsest level's number of steps. None: the default,
    /// [`DEFAULT_WINDOWS`] when it divides them, else the largest number below it that does
    pub windows: Option<usize>,
}

impl Default for RefineOptions {
    fn default() -> RefineOptions {
        RefineOptions { levels: DEFAULT_LEVELS, ratio: 2.0, what: What::Both, windows: None }
    }
}

/// The default number of impulse windows.
pub const DEFAULT_WINDOWS: usize = 4;

/// The impulses `refine` estimates from each level's history.csv besides [`FIGURES`]: the
/// integrals over time of the contact force, Σ_n (t_n − t_{n−1}) F_n with F_n the step's force —
/// `normal_impulse` of `normal_force`, `friction_impulse_x`, `_y` (and `_z` in 3-D) of the
/// friction force's global components — over the whole run and, with `windows` > 1, over each
/// window ((w−1)T/W, wT/W] as `<name>_w<w>`. A force maximum is a value at one instant that an
/// impact's peak makes erratic under refinement; an impulse is the momentum the contact
/// exchanges, which converges.
pub fn impulse_figures(dim: usize, windows: usize) -> Vec<String> {
    let names: &[&str] = if dim == 3 {
        &["normal_impulse", "friction_impulse_x", "friction_impulse_y", "friction_impulse_z"]
    } else {
        &["normal_impulse", "friction_impulse_x", "friction_impulse_y"]
    };
    let mut figures: Vec<String> = names.iter().map(|n| n.to_string()).collect();
    if windows > 1 {
        for w in 1..=windows {
            figures.extend(names.iter().map(|n| format!("{n}_w{w}")));
        }
    }
    figures
}

/// The impulses of [`impulse_figures`] from a history.csv's text, in that order. Parsed here
/// rather than by `collect::History`, which skips malformed rows: a skipped step would shift
/// every window's sum, so a row that does not read is an error naming it.
pub fn impulses(history: &str, dim: usize, windows: usize) -> std::result::Result<Vec<f64>, String> {
    let mut lines = history.lines();
    let header: Vec<&str> = lines.next().ok_or("history.csv is empty")?.split(',').collect();
    let column = |name: &str| header.iter().position(|h| *h == name).ok_or(format!("history.csv has no {name}"));
    let forces = ["normal_force", "friction_force_x", "friction_force_y", "friction_force_z"];
    let mut cols = vec![column("t")?];
    for f in &forces[..1 + dim] {
        cols.push(column(f)?);
    }
    let mut rows: Vec<Vec<f64>> = Vec::new();
    for (i, line) in lines.enumerate() {
        let fields: Vec<&str> = line.split(',').collect();
        let row = cols
            .iter()
            .map(|&c| fields.get(c).and_then(|v| v.parse::<f64>().ok()))
            .collect::<Option<Vec<f64>>>()
            .ok_or(format!("history.csv row {}: not a number in t or a force column", i + 2))?;
        rows.push(row);
    }
    let steps = rows.len().saturating_sub(1);
    if steps == 0 || windows == 0 || !steps.is_multiple_of(windows) {
        return Err(format!("{steps} steps do not split into {windows} equal windows"));
    }
    let n_f = 1 + dim;
    let mut total = vec![0.0; n_f];
    let mut per_window = vec![vec![0.0; n_f]; windows];
    for n in 1..=steps {
        let k = rows[n][0] - rows[n - 1][0];
        let w = (n - 1) * windows / steps;
        for f in 0..n_f {
            total[f] += k * rows[n][1 + f];
            per_window[w][f] += k * rows[n][1 + f];
        }
    }
    let mut out = total;
    if windows > 1 {
        per_window.into_iter().for_each(|w| out.extend(w));
    }
    Ok(out)
}

/// The expected order p_e of a figure's error in the refined parameter: 1 when h is refined
/// (P1 elements: order 1 in the energy norm, and `both` is limited by h); when only k is
/// refined, 2 for the midpoint and trapezoid schemes, 1 for backward Euler.
pub fn expected_order(what: What, scheme: SchemeKind) -> f64 {
    match (what, scheme) {
        (What::K, SchemeKind::BackwardEuler) => 1.0,
        (What::K, _) => 2.0,
        _ => 1.0,
    }
}

/// (G.1) The observed order of three levels f1 (finest), f2, f3 at ratio r:
/// p = ln((f3 − f2)/(f2 − f1)) / ln r. None when (f3 − f2)/(f2 − f1) is not a positive finite
/// number (oscillatory or non-monotone convergence, or f2 = f1).
pub fn observed_order(f1: f64, f2: f64, f3: f64, r: f64) -> Option<f64> {
    let q = (f3 - f2) / (f2 - f1);
    (q.is_finite() && q > 0.0).then(|| q.ln() / r.ln())
}

/// (G.2) Richardson extrapolation of the finest two levels with order p at ratio r:
/// f_ext = f1 + (f1 − f2)/(r^p − 1).
pub fn richardson_extrapolation(f1: f64, f2: f64, r: f64, p: f64) -> f64 {
    f1 + (f1 - f2) / (r.powf(p) - 1.0)
}

/// (G.3) Roache's grid convergence index of the finest level, relative to it (a fraction):
/// GCI = F_s |(f1 − f2)/f1| / (r^p − 1), F_s = [`SAFETY_FACTOR`]. The band f_ext ± GCI·|f1|
/// is the discretization uncertainty. Not finite when f1 = 0 (a relative index is undefined).
pub fn gci_fine(f1: f64, f2: f64, r: f64, p: f64) -> f64 {
    SAFETY_FACTOR * ((f1 - f2) / f1).abs() / (r.powf(p) - 1.0)
}

/// One figure's estimate from its levels.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// (G.1), when defined
    pub order: Option<f64>,
    /// (G.2), when defined
    pub extrapolated: Option<f64>,
    /// (G.3), when defined (a fraction of |f1|)
    pub gci: Option<f64>,
    /// monotone convergence with p in [p_e/2, 2 p_e] (or the levels equal)
    pub asymptotic: bool,
    /// why a value is missing or the figure is not asymptotic (empty when it is, with all values)
    pub note: String,
}

/// Whether a and b agree to round-off of their magnitude.
fn same(a: f64, b: f64) -> bool {
    (a - b).abs() <= ROUND_OFF_ULPS * f64::EPSILON * a.abs().max(b.abs())
}

impl Estimate {
    /// The estimate from the values of the levels (coarsest first; None where a level has no
    /// value) at ratio r with the expected order p_e: (G.1)–(G.3) on the three finest levels.
    /// Three equal values (to round-off) are exact: no order, f_ext = f1, GCI 0, asymptotic.
    pub fn of(values: &[Option<f64>], r: f64, p_expected: f64) -> Estimate {
        let none = |note: String| Estimate { order: None, extrapolated: None, gci: None, asymptotic: false, note };
        let n = values.len();
        if n < 3 {
            return none(format!("{n} levels: three are needed"));
        }
        let (Some(f3), Some(f2), Some(f1)) = (values[n - 3], values[n - 2], values[n - 1]) else {
            return none("a level of the three finest has no value".into());
        };
        if ![f1, f2, f3].iter().all(|f| f.is_finite()) {
            return none("a value is not finite".into());
        }
        if same(f1, f2) && same(f2, f3) {
            return Estimate {
                order: None,
                extrapolated: Some(f1),
                gci: Some(0.0),
                asymptotic: true,
                note: "the three finest levels agree to round-off: no discretization error seen".into(),
            };
        }
        let Some(p) = observed_order(f1, f2, f3, r) else {
            let q = (f3 - f2) / (f2 - f1);
            let why = if q.is_finite() {
                format!("oscillatory convergence ((f3 − f2)/(f2 − f1) = {q:.3e} ≤ 0): no order")
            } else {
                "the two finest levels are equal but the third differs: no order".into()
            };
            return none(why);
        };
        if p <= 0.0 {
            return Estimate {
                order: Some(p),
                extrapolated: None,
                gci: None,
                asymptotic: false,
                note: format!("not converging (p = {p:.3} ≤ 0): no extrapolation"),
            };
        }
        let extrapolated = Some(richardson_extrapolation(f1, f2, r, p));
        let (gci, mut notes) = if f1 == 0.0 {
            (None, vec!["f1 = 0: a GCI relative to it is undefined".to_string()])
        } else {
            (Some(gci_fine(f1, f2, r, p)), Vec::new())
        };
        let in_band = (0.5 * p_expected..=2.0 * p_expected).contains(&p);
        if !in_band {
            notes.push(format!(
                "p = {p:.3} outside [{:.3}, {:.3}] (expected {p_expected}): not in the asymptotic range",
                0.5 * p_expected,
                2.0 * p_expected
            ));
        }
        Estimate { order: Some(p), extrapolated, gci, asymptotic: in_band, note: notes.join("; ") }
    }
}

/// A refinement study laid out: its sweep plan and what each level is.
#[derive(Debug, Clone)]
pub struct Refinement {
    pub plan: Plan,
    pub options: RefineOptions,
    /// the characteristic size of each level: h (the largest cell edge) when h is refined, else k
    pub sizes: Vec<f64>,
    /// "h [m]" or "k [s]"
    pub size_name: &'static str,
    /// p_e of [`expected_order`]
    pub expected_order: f64,
    /// the scene's dimension (2 or 3): the friction impulses' components
    pub dim: usize,
    /// the impulse windows (the option resolved: see [`RefineOptions::windows`])
    pub windows: usize,
}

/// One row of refine.csv.
#[derive(Debug, Clone)]
pub struct RefineRow {
    pub figure: String,
    /// the value of each level as sweep.csv writes it (coarsest first; empty: none)
    pub values: Vec<String>,
    pub estimate: Estimate,
}

/// Build the refinement sweep of `base` with `extra` overrides (`--set`, applied to the base
/// before the levels refine it): refuses a Gmsh
/// mesh (`domain.file`) when h is refined, fewer than 3 or more than [`MAX_LEVELS`] levels, a ratio ≤ 1, a cell
/// count or step count that r^ℓ does not keep whole.
pub fn plan(base: &Base, extra: &[Override], name: &str, opts: &RefineOptions) -> Result<Refinement> {
    if !(3..=MAX_LEVELS).contains(&opts.levels) {
        return Err(Error::scene("--levels", format!("{} levels: give 3 to {MAX_LEVELS}", opts.levels)));
    }
    let r = opts.ratio;
    if !(r.is_finite() && r > 1.0) {
        return Err(Error::scene("--ratio", format!("{r}: the refinement ratio must be > 1")));
    }
    let probe = SweepFile {
        name: name.to_string(),
        description: String::new(),
        base: String::new(),
        mode: Mode::Zip,
        axes: Vec::new(),
        set: toml::Table::new(),
        plot: PlotSpec::default(),
    };
    // the --set overrides become the base of every level: a level's own keys (cells, step) are
    // then those of the overridden scene, refined
    let mut table: toml::Table =
        base.text.parse().map_err(|e: toml::de::Error| crate::scene::parse::syntax_error(&base.label, "", &e))?;
    crate::overrides::apply_all(&mut table, extra)?;
    let text = toml::to_string(&table).map_err(|e| Error::Output(format!("{}: {e}", base.label)))?;
    let base = &Base { text, label: base.label.clone(), dir: base.dir.clone() };
    let scene = super::scene_for(&probe, base, &[])?;
    // a rectangle's or box's `file`, a mesh's `size` and `cells` are ignored keys (said by the
    // scene's warnings): the kind decides
    let gmsh = scene.domain.kind == crate::model::kinds::DomainKind::Gmsh;
    if let (true, Some(f)) = (gmsh, &scene.domain.file)
        && opts.what.refines_h()
    {
        return Err(Error::scene(
            "domain.file",
            format!(
                "is the Gmsh mesh {f:?}: `refine` refines domain.cells and cannot refine a mesh file; give a rectangle or box domain with cells (or refine the time step only: --what k)"
            ),
        ));
    }
    let cells = match scene.domain.cells.clone().filter(|_| !gmsh) {
        Some(cells) => cells,
        None if opts.what.refines_h() => {
            return Err(Error::scene(
                "domain.cells",
                "is missing: `refine` refines the cells of a rectangle or box domain",
            ));
        }
        None => Vec::new(),
    };
    // the dimension: the cells' count, or a mesh file's own (--what k)
    let dim = if cells.is_empty() {
        crate::problem::build_mesh(&scene.validate()?.domain, &base.dir)?.dim()
    } else {
        cells.len()
    };
    let (end, step) = (scene.time.end, scene.time.step);
    let whole = |x: f64| (x - x.round()).abs() <= 1e-9 * x.abs().max(1.0);
    let steps0 = end / step;
    let divides = |w: usize| w == 1 || (w > 1 && whole(steps0) && (steps0.round() as usize).is_multiple_of(w));
    let windows = match opts.windows {
        None => (1..=DEFAULT_WINDOWS).rev().find(|&w| divides(w)).unwrap_or(1),
        Some(w) if divides(w) => w,
        Some(w) => {
            return Err(Error::scene(
                "--windows",
                format!(
                    "{w}: the coarsest level's {steps0} steps (time.end / time.step) do not split into {w} equal windows of whole steps; give --windows N with N dividing the steps (1: the whole run only)"
                ),
            ));
        }
    };
    let mut sets = Vec::with_capacity(opts.levels);
    let mut sizes = Vec::with_capacity(opts.levels);
    let edge0 = match &scene.domain.size {
        Some(size) if size.len() == cells.len() => {
            size.iter().zip(&cells).map(|(l, &n)| l / n.max(1) as f64).fold(0.0, f64::max)
        }
        _ => 1.0,
    };
    for level in 0..opts.levels {
        let factor = r.powi(level as i32);
        let mut t = toml::Table::new();
        if opts.what.refines_h() {
            let mut refined = Vec::with_capacity(cells.len());
            for &n in &cells {
                let m = n as f64 * factor;
                if !whole(m) {
                    return Err(Error::scene(
                        "domain.cells",
                        format!(
                            "{n} cells × {r}^{level} = {m} is not a whole number: choose cells or --ratio so that it is"
                        ),
                    ));
                }
                refined.push(toml::Value::Integer(m.round() as i64));
            }
            t.insert("domain.cells".into(), toml::Value::Array(refined));
        }
        let k = if opts.what.refines_k() { step / factor } else { step };
        if opts.what.refines_k() {
            let steps = end / k;
            if !whole(steps) {
                return Err(Error::scene(
                    "time.step",
                    format!(
                        "{step} / {r}^{level} = {k:e} gives time.end / step = {steps} steps, not a whole number: choose time.step and --ratio so that every level has a whole number of steps"
                    ),
                ));
            }
            t.insert("time.step".into(), toml::Value::Float(k));
        }
        sizes.push(if opts.what.refines_h() { edge0 / factor } else { k });
        sets.push(t);
    }
    let sweep = SweepFile {
        axes: vec![AxisSpec {
            key: None,
            values: Vec::new(),
            name: Some("level".into()),
            sets,
            labels: (0..opts.levels).map(|l| l.to_string()).collect(),
        }],
        plot: PlotSpec { figures: vec!["max_normal_force".into(), "max_penetration".into()] },
        ..probe
    };
    let plan = Plan::resolve_with(&sweep, base, &[])?;
    Ok(Refinement {
        plan,
        options: *opts,
        sizes,
        size_name: if opts.what.refines_h() { "h [m]" } else { "k [s]" },
        expected_order: expected_order(opts.what, scene.time.scheme),
        dim,
        windows,
    })
}

impl Refinement {
    /// Lay the levels out in `dir`, run those not completed with the same scene (`jobs` at
    /// once), collect sweep.csv, and write refine.csv and the charts. Returns the points'
    /// outcomes and refine.csv's rows. `launcher`: the command the Snakefile runs `dyncontact`
    /// with.
    pub fn run(&self, dir: &Path, opts: &RunnerOptions, launcher: &[String]) -> Result<(Vec<Outcome>, Vec<RefineRow>)> {
        let done = self.plan.write(dir, launcher)?;
        let outcomes = runner::run_points(&self.plan, dir, &done, opts)?;
        let rows = self.collect(dir)?;
        Ok((outcomes, rows))
    }

    /// Collect the levels in `dir`: sweep.csv (as `sweep collect`), refine.csv and
    /// plots/refine_<figure>.svg.
    pub fn collect(&self, dir: &Path) -> Result<Vec<RefineRow>> {
        let (_, rows) = collect::collect(dir)?;
        let mut table = estimates(&rows, self.options.ratio, self.expected_order);
        table.extend(self.impulse_rows(dir, &rows));
        write_atomic(&dir.join("refine.csv"), csv(&table, self.options.levels).as_bytes())?;
        let plots = dir.join("plots");
        std::fs::create_dir_all(&plots).map_err(|e| Error::io(&plots, e))?;
        for row in &table {
            // a cost row has no estimate to draw
            if is_cost(&row.figure) {
                continue;
            }
            if let Some(svg) = chart(row, &self.sizes, self.size_name, self.dim)? {
                write_atomic(&plots.join(format!("refine_{}.svg", row.figure)), svg.as_bytes())?;
            }
        }
        Ok(table)
    }
}

impl Refinement {
    /// The rows of the impulses ([`impulse_figures`]) from each completed level's history.csv;
    /// a level that did not complete, or whose history cannot be read, gives no value (the
    /// rows' note says which).
    fn impulse_rows(&self, dir: &Path, rows: &[Row]) -> Vec<RefineRow> {
        let names = impulse_figures(self.dim, self.windows);
        let mut values = vec![Vec::with_capacity(rows.len()); names.len()];
        let mut problems = Vec::new();
        for row in rows {
            let level: Option<Vec<f64>> = if row.status.is_completed() {
                let path = dir.join("points").join(&row.point).join("history.csv");
                let read = std::fs::read_to_string(&path).map_err(|e| e.to_string());
                match read.and_then(|text| impulses(&text, self.dim, self.windows)) {
                    Ok(v) => Some(v),
                    Err(e) => {
                        problems.push(format!("{}: {e}", path.display()));
                        None
                    }
                }
            } else {
                None
            };
            for (f, column) in values.iter_mut().enumerate() {
                column.push(level.as_ref().map(|v| crate::output::csv::real(v[f])).unwrap_or_default());
            }
        }
        names
            .into_iter()
            .zip(values)
            .map(|(figure, values)| {
                let numbers: Vec<Option<f64>> = values.iter().map(|v| v.parse().ok()).collect();
                let mut estimate = Estimate::of(&numbers, self.options.ratio, self.expected_order);
                if !problems.is_empty() {
                    estimate.note = [estimate.note, problems.join("; ")].join("; ");
                }
                RefineRow { figure, estimate, values }
            })
            .collect()
    }
}

/// The rows of refine.csv from sweep.csv's rows (one per level, coarsest first): a level that
/// did not complete gives no value. Every sweep.csv figure has its row, in sweep.csv's order:
/// those of [`FIGURES`] with their estimate, the solver's costs with their values and a note.
pub fn estimates(rows: &[Row], r: f64, p_expected: f64) -> Vec<RefineRow> {
    collect::FIGURES
        .iter()
        .map(|&fig| {
            let i = collect::FIGURES.iter().position(|f| *f == fig).unwrap_or(usize::MAX);
            let values: Vec<String> = rows
                .iter()
                .map(|row| {
                    if row.status.is_completed() {
                        row.figures.get(i).cloned().unwrap_or_default()
                    } else {
                        String::new()
                    }
                })
                .collect();
            let numbers: Vec<Option<f64>> = values.iter().map(|v| v.parse().ok()).collect();
            let estimate = if !is_cost(fig) {
                Estimate::of(&numbers, r, p_expected)
            } else {
                Estimate {
                    order: None,
                    extrapolated: None,
                    gci: None,
                    asymptotic: false,
                    note: "a cost of the solver, not a discretized quantity: not estimated".into(),
                }
            };
            RefineRow { figure: fig.to_string(), estimate, values }
        })
        .collect()
}

/// A number as refine.csv writes it (empty: none).
fn number(x: Option<f64>) -> String {
    x.map(crate::output::csv::real).unwrap_or_default()
}

/// refine.csv: `figure`, `level_0` … `level_{N−1}` (coarsest first), `order`, `extrapolated`,
/// `gci`, `asymptotic`, `note`.
pub fn csv(table: &[RefineRow], levels: usize) -> String {
    let mut s = String::from("figure");
    for l in 0..levels {
        let _ = write!(s, ",level_{l}");
    }
    s.push_str(",order,extrapolated,gci,asymptotic,note\n");
    for row in table {
        s.push_str(&row.figure);
        for v in &row.values {
            let _ = write!(s, ",{v}");
        }
        let e = &row.estimate;
        let _ = writeln!(
            s,
            ",{},{},{},{},{}",
            number(e.order),
            number(e.extrapolated),
            number(e.gci),
            e.asymptotic,
            csv_field(&e.note)
        );
    }
    s
}

/// plots/refine_<figure>.svg: the levels' values against h (or k; a logarithmic axis when they
/// span a decade, else linear), with
/// the extrapolated value and its band f_ext ± GCI·|f1| as horizontal lines. None when no level
/// has a value.
fn chart(row: &RefineRow, sizes: &[f64], size_name: &str, dim: usize) -> Result<Option<String>> {
    let points: Vec<(f64, f64)> =
        sizes.iter().zip(&row.values).filter_map(|(&x, v)| Some((x, v.parse::<f64>().ok()?))).collect();
    if points.is_empty() {
        return Ok(None);
    }
    let e = &row.estimate;
    let f1 = points.last().map(|p| p.1).unwrap_or(0.0);
    let mut hlines = Vec::new();
    if let Some(fx) = e.extrapolated {
        hlines.push((format!("extrapolated (G.2) {}", crate::output::style::significant(fx, 7)), fx));
        if let Some(g) = e.gci.filter(|g| *g > 0.0) {
            let u = g * f1.abs();
            hlines.push((format!("+ GCI (G.3) {:.2}%", 100.0 * g), fx + u));
            hlines.push(("− GCI".to_string(), fx - u));
        }
    }
    let flag = if e.asymptotic { "asymptotic" } else { "not asymptotic" };
    let title = match e.order {
        Some(p) => format!("{}: observed order {p:.3} (G.1), {flag}", row.figure),
        None => format!("{}: {flag}", row.figure),
    };
    // a logarithmic axis where the levels span a decade (R^(N−1) ≥ 10); below that a log axis
    // has no decade tick and its labels repeat, so the axis is linear
    let (lo, hi) = points.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), p| (lo.min(p.0), hi.max(p.0)));
    let log_x = lo > 0.0 && hi >= 10.0 * lo;
    // the legend on the right (the finest levels, which approach f_ext, sit at the left), on
    // the side of the range the coarsest level leaves free
    let ys = points.iter().map(|p| p.1).chain(hlines.iter().map(|h| h.1)).filter(|y| y.is_finite());
    let (y_lo, y_hi) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), y| (lo.min(y), hi.max(y)));
    let coarsest = points.iter().max_by(|a, b| a.0.total_cmp(&b.0)).map_or(0.0, |p| p.1);
    let legend = if coarsest > 0.5 * (y_lo + y_hi) {
        crate::output::plots::SeriesLabelPosition::LowerRight
    } else {
        crate::output::plots::SeriesLabelPosition::UpperRight
    };
    let series = [Series { name: row.figure.clone(), points }];
    let y_desc = crate::output::units::figure_axis(&row.figure, dim);
    let panel = Panel {
        title: &title,
        x_desc: size_name,
        y_desc: &y_desc,
        series: &series,
        hlines: &hlines,
        log: (log_x, false),
    };
    let opts = Options { markers: true, legend, ..Options::default() };
    stacked_chart(&[(panel, 1.0)], &opts)
        .map(Some)
        .map_err(|e| Error::Output(format!("plots/refine_{}.svg: {e}", row.figure)))
}

/// The default folder of a refinement of the scene `name`: out/<name>-refine.
pub fn default_dir(name: &str) -> PathBuf {
    PathBuf::from("out").join(format!("{name}-refine"))
}
