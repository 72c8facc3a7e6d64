//! Sweeps (SCENES.md, "Overrides and sweeps"): many runs of one scene, each point a scene with
//! some keys set, run into its own folder.
//!
//! A sweep file names a base scene (a file relative to it, or `"default"`), fixed overrides
//! (`[set]`, applied to every point) and axes. An axis is a key with its values, or — for keys
//! that change together (a scheme with its mass and inner solver) — a named list of override
//! tables (`sets`); `labels` name the values in sweep.csv and the charts. `mode = "grid"` runs
//! the Cartesian product of the axes (the first axis slowest), `"zip"` advances them together.
//!
//! ```toml
//! name = "penalty-sweep"
//! base = "academic.toml"
//! mode = "grid"
//! [[axis]]
//! key = "contact.penalty"
//! values = [1e-3, 1e-4, 1e-5]
//! [[axis]]
//! name = "variant"
//! sets = [{ "time.scheme" = "midpoint" }, { "time.scheme" = "backward-euler", "solver.mass" = "consistent" }]
//! labels = ["midpoint", "backward-euler"]
//! [set]
//! "contact.enforcement" = "penalty"
//! [plot]
//! figures = ["max_penetration", "friction_dissipation"]
//! ```
//!
//! The flow is one way: [`Plan::from_file`] resolves and validates every point (a bad point
//! refuses the whole sweep, naming its axis values and the key); [`Plan::write`] lays out
//! `DIR/sweep.json`, `DIR/points/<id>/scene.toml`, `DIR/Snakefile` and `DIR/config.yaml`;
//! [`runner::run`] runs the points in parallel (each one `run` into its folder, a point already
//! completed with the same scene skipped); [`collect::collect`] reads the folders into
//! `DIR/sweep.csv` and `DIR/plots/` — the same files whether the points ran here or as
//! Snakemake jobs on a cluster (`dyncontact sweep collect DIR`).

pub mod collect;
pub mod refine;
pub mod runner;
pub mod snakemake;

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::output::write_atomic;
use crate::overrides::Override;
use crate::scene::{DEFAULT_SCENE, Scene};

/// The most points a sweep may have.
pub const MAX_POINTS: usize = 100_000;

/// The sweep file (TOML).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepFile {
    pub name: String,
    #[serde(default)]
    pub description: String,
    /// a scene file relative to the sweep file, or "default" (the embedded academic scene)
    #[serde(default = "default_base")]
    pub base: String,
    #[serde(default)]
    pub mode: Mode,
    #[serde(default, rename = "axis")]
    pub axes: Vec<AxisSpec>,
    /// overrides of every point: dotted key → value
    #[serde(default)]
    pub set: toml::Table,
    #[serde(default)]
    pub plot: PlotSpec,
}

fn default_base() -> String {
    "default".into()
}

/// How the axes combine.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// the Cartesian product (the first axis slowest)
    #[default]
    Grid,
    /// the axes advance together (all of one length)
    Zip,
}

/// One axis as written: `key` with `values`, or `name` with `sets` (override tables).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AxisSpec {
    pub key: Option<String>,
    #[serde(default)]
    pub values: Vec<toml::Value>,
    pub name: Option<String>,
    #[serde(default)]
    pub sets: Vec<toml::Table>,
    /// names of the values (sweep.csv, charts); default: the values themselves
    #[serde(default)]
    pub labels: Vec<String>,
}

/// What the collector charts.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PlotSpec {
    /// sweep.csv figures drawn against every numeric axis (DIR/plots/<axis>.svg)
    #[serde(default = "default_figures")]
    pub figures: Vec<String>,
}

impl Default for PlotSpec {
    fn default() -> PlotSpec {
        PlotSpec { figures: default_figures() }
    }
}

fn default_figures() -> Vec<String> {
    // iterations as a mean per step: a total grows with the number of steps
    [
        "max_normal_force",
        "max_penetration",
        "friction_dissipation",
        "max_relative_energy_residual",
        "newton_iterations_per_step",
    ]
    .map(String::from)
    .to_vec()
}

/// A resolved axis: its column in sweep.csv, the label of each value, the numbers when every
/// value is one (a numeric axis gets a chart), and the overrides of each value.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Axis {
    pub column: String,
    pub labels: Vec<String>,
    pub numbers: Option<Vec<f64>>,
    #[serde(skip)]
    pub overrides: Vec<Vec<Override>>,
}

/// One point: its id, the value it takes on each axis, and its scene (TOML text, validated).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Point {
    pub id: String,
    pub choice: Vec<usize>,
    #[serde(skip)]
    pub scene_text: String,
    /// the point's estimated peak memory (MB) and a conservative run time (minutes), for the
    /// cluster's resources
    pub mem_mb: u64,
    pub runtime_min: u64,
}

/// A sweep with every point resolved and validated.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Plan {
    pub name: String,
    pub description: String,
    pub mode: Mode,
    pub base: String,
    pub axes: Vec<Axis>,
    pub points: Vec<Point>,
    pub figures: Vec<String>,
}

impl Plan {
    /// Read a sweep file and resolve it; `extra` overrides every point after its own (`--set`).
    pub fn from_file(path: &Path, extra: &[Override]) -> Result<Plan> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::read(path, e))?;
        let file = path.display().to_string();
        let sweep = parse(&text, &file)?;
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_else(|| PathBuf::from("."));
        Plan::resolve(&sweep, &dir, extra)
    }

    /// Resolve a parsed sweep: `dir` is where its `base` path is read from.
    pub fn resolve(sweep: &SweepFile, dir: &Path, extra: &[Override]) -> Result<Plan> {
        let base = Base::of(sweep, dir)?;
        Plan::resolve_with(sweep, &base, extra)
    }

    /// Resolve a parsed sweep on a given base scene (a study that embeds its scenes).
    pub fn resolve_with(sweep: &SweepFile, base: &Base, extra: &[Override]) -> Result<Plan> {
        crate::scene::check_name("name", &sweep.name)?;
        crate::scene::check_text("description", &sweep.description)?;
        let (base_text, base_label, base_dir) = (&base.text, &base.label, &base.dir);
        let fixed = fixed_overrides(sweep)?;
        let axes = sweep.axes.iter().enumerate().map(|(a, spec)| resolve_axis(a, spec)).collect::<Result<Vec<_>>>()?;
        for (a, axis) in axes.iter().enumerate() {
            if axes[..a].iter().any(|b| b.column == axis.column) {
                return Err(Error::scene(format!("axis[{a}]"), format!("the column {:?} names two axes", axis.column)));
            }
        }
        check_conflicts(&fixed, &axes, extra)?;
        // a misspelled figure would chart nothing: refused, with the figures there are
        for (i, f) in sweep.plot.figures.iter().enumerate() {
            if !collect::FIGURES.contains(&f.as_str()) {
                return Err(Error::scene(
                    format!("plot.figures[{i}]"),
                    format!("unknown figure {f:?}: the figures are {}", collect::FIGURES.join(", ")),
                ));
            }
        }
        let choices = combinations(&axes, sweep.mode)?;
        let width = choices.len().saturating_sub(1).to_string().len().max(3);
        let mut points = Vec::with_capacity(choices.len());
        for (index, choice) in choices.into_iter().enumerate() {
            let id = format!("p{index:0width$}");
            let mut ovs = fixed.clone();
            for (axis, &c) in axes.iter().zip(&choice) {
                ovs.extend(axis.overrides[c].iter().cloned());
            }
            ovs.extend(extra.iter().cloned());
            let label = describe(&axes, &choice);
            let refuse = |e: Error| point_error(&id, &label, e);
            let scene_text = point_text(base_text, base_label, base_dir, &ovs, &sweep.name).map_err(refuse)?;
            let axis_keys: Vec<&str> =
                axes.iter().zip(&choice).flat_map(|(a, &c)| a.overrides[c].iter().map(|o| o.key.as_str())).collect();
            let (mem_mb, runtime_min) = check_point(&scene_text, &id, &axis_keys).map_err(refuse)?;
            points.push(Point { id, choice, scene_text, mem_mb, runtime_min });
        }
        Ok(Plan {
            name: sweep.name.clone(),
            description: sweep.description.clone(),
            mode: sweep.mode,
            base: base_label.clone(),
            axes,
            points,
            figures: sweep.plot.figures.clone(),
        })
    }

    /// The folder of point `id` below `dir`.
    pub fn point_dir(dir: &Path, id: &str) -> PathBuf {
        dir.join("points").join(id)
    }

    /// Lay the sweep out in `dir`: sweep.json (what the collector reads), every point's
    /// scene.toml (rewritten only when it changed — a changed scene also drops the point's old
    /// outputs, so the point runs again), the Snakefile and config.yaml. Returns, per point,
    /// whether its folder already holds a completed run of the same scene whose files agree.
    /// `launcher`: the command the Snakefile runs `dyncontact` with ([`snakemake::this_executable`]
    /// for the CLI).
    ///
    /// Nothing a user computed is dropped: `dir` must be new, empty or a sweep's (it has
    /// sweep.json), and every completed run in it must have its scene in this plan — one whose
    /// scene another point now has (the axes changed) moves to that point's folder with its
    /// marker; a sweep that would drop or overwrite any other is refused before anything is
    /// written. A point whose files do not agree (`corrupt`) loses its marker, so it runs again
    /// here or under Snakemake.
    pub fn write(&self, dir: &Path, launcher: &[String]) -> Result<Vec<bool>> {
        check_folder(dir)?;
        let points = dir.join("points");
        let completed = completed_runs(&points);
        self.refuse_dropping(dir, &completed)?;
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        let json = serde_json::to_string_pretty(self).map_err(|e| Error::Output(format!("sweep.json: {e}")))?;
        write_atomic(&dir.join("sweep.json"), json.as_bytes())?;
        std::fs::create_dir_all(&points).map_err(|e| Error::io(&points, e))?;
        self.move_completed(&points, &completed)?;
        let mut done = Vec::with_capacity(self.points.len());
        for p in &self.points {
            let pd = Plan::point_dir(dir, &p.id);
            std::fs::create_dir_all(&pd).map_err(|e| Error::io(&pd, e))?;
            let sp = pd.join("scene.toml");
            let same = std::fs::read_to_string(&sp).is_ok_and(|t| t == p.scene_text);
            if !same {
                clear_outputs(&pd)?;
                remove_marker(&pd)?;
                write_atomic(&sp, p.scene_text.as_bytes())?;
            }
            let status = collect::checked_status(&pd);
            if status == collect::PointStatus::Corrupt {
                // its files do not agree: it runs again, whether or not it had reached a final outcome
                remove_marker(&pd)?;
            }
            done.push(same && status.is_completed());
        }
        snakemake::write(self, dir, launcher)?;
        Ok(done)
    }

    /// Refuse a plan that would drop or overwrite a completed run in `points/` (see
    /// [`Plan::write`]): one whose scene no point of this plan has. Names them, with their
    /// axis values in the sweep that ran them (the folder's sweep.json).
    fn refuse_dropping(&self, dir: &Path, completed: &[Completed]) -> Result<()> {
        let kept = |c: &Completed| c.scene.as_ref().is_some_and(|t| self.points.iter().any(|p| p.scene_text == *t));
        let dropped: Vec<&Completed> = completed.iter().filter(|c| !kept(c)).collect();
        if dropped.is_empty() {
            return Ok(());
        }
        let before = Plan::read(dir).ok();
        let name = |c: &Completed| {
            let values = before
                .as_ref()
                .and_then(|b| b.points.iter().find(|p| p.id == c.name).map(|p| format!(" ({})", b.describe(p))));
            format!("points/{}{}", c.name, values.unwrap_or_default())
        };
        let mut shown = dropped.iter().take(5).map(|c| name(c)).collect::<Vec<_>>().join(", ");
        if dropped.len() > 5 {
            shown.push_str(", …");
        }
        let n = dropped.len();
        Err(Error::folder(
            dir,
            format!(
                "holds {n} completed point{} whose scene this sweep does not have: {shown}; running this sweep here would drop or overwrite {}. Give another folder with --out, or move or remove {} (points/<id> and points/<id>.done) by hand first",
                if n == 1 { "" } else { "s" },
                if n == 1 { "it" } else { "them" },
                if n == 1 { "that folder" } else { "those folders" },
            ),
        ))
    }

    /// Move completed runs whose scene another point now has (the axes changed) into that
    /// point's folder, each with its marker: first all aside (`points/.moving-<id>`), then into
    /// place, so two runs that trade places are both kept. A folder that an earlier move left
    /// aside (interrupted) is moved on like the others.
    fn move_completed(&self, points: &Path, completed: &[Completed]) -> Result<()> {
        let own = |c: &Completed| self.points.iter().any(|p| p.id == c.name && c.scene.as_ref() == Some(&p.scene_text));
        let mut moves: Vec<(&str, &str)> = Vec::new();
        for p in &self.points {
            if completed.iter().any(|c| c.name == p.id && own(c)) {
                continue;
            }
            if let Some(c) = completed.iter().find(|c| {
                c.scene.as_ref() == Some(&p.scene_text) && !own(c) && !moves.iter().any(|(from, _)| *from == c.name)
            }) {
                moves.push((&c.name, &p.id));
            }
        }
        // the markers go first (a marker must not claim a folder that moved away), then the
        // folders; a moved run gets its marker back in its new place
        let had: Vec<bool> = moves.iter().map(|(from, _)| runner::marker(&points.join(from)).exists()).collect();
        for (from, to) in &moves {
            remove_marker(&points.join(from))?;
            remove_marker(&points.join(to))?;
        }
        for (from, to) in &moves {
            let aside = points.join(format!(".moving-{to}"));
            if *from != aside.file_name().unwrap_or_default().to_string_lossy() {
                std::fs::rename(points.join(from), &aside).map_err(|e| Error::io(&aside, e))?;
            }
        }
        for ((_, to), had) in moves.iter().zip(had) {
            let (aside, target) = (points.join(format!(".moving-{to}")), points.join(to));
            if target.exists() {
                // not a completed run (or a second copy of one kept elsewhere): refuse_dropping
                // refused the plan otherwise
                std::fs::remove_dir_all(&target).map_err(|e| Error::io(&target, e))?;
            }
            std::fs::rename(&aside, &target).map_err(|e| Error::io(&target, e))?;
            if had {
                write_atomic(&runner::marker(&target), b"")?;
            }
        }
        Ok(())
    }

    /// Read the plan a sweep wrote to `dir` (sweep.json), checked: ids of the form p0…, one
    /// choice per axis within its values.
    pub fn read(dir: &Path) -> Result<Plan> {
        let p = dir.join("sweep.json");
        let text = std::fs::read_to_string(&p)
            .map_err(|e| Error::folder(&p, format!("cannot be read ({e}): is this a sweep's folder?")))?;
        let plan: Plan =
            serde_json::from_str(&text).map_err(|e| Error::folder(&p, format!("not a sweep folder's plan ({e})")))?;
        for pt in &plan.points {
            let fits = pt.choice.len() == plan.axes.len()
                && pt.choice.iter().zip(&plan.axes).all(|(&c, a)| c < a.labels.len());
            if !is_id(&pt.id) || !fits {
                return Err(Error::folder(
                    &p,
                    format!("point {:?} does not fit the plan's axes (edited by hand?)", pt.id),
                ));
            }
        }
        Ok(plan)
    }

    /// "axis = label, …" of a point.
    pub fn describe(&self, p: &Point) -> String {
        describe(&self.axes, &p.choice)
    }
}

/// The base scene of a sweep: its text, how messages name it, and the folder its relative
/// paths (a Gmsh file) are read from.
#[derive(Debug, Clone)]
pub struct Base {
    pub text: String,
    pub label: String,
    pub dir: PathBuf,
}

impl Base {
    /// The sweep's `base`: "default" (the embedded academic scene) or a file relative to `dir`.
    pub fn of(sweep: &SweepFile, dir: &Path) -> Result<Base> {
        if sweep.base == "default" {
            // relative paths a sweep sets (a Gmsh file) are read from the sweep's folder
            return Ok(Base {
                text: DEFAULT_SCENE.to_string(),
                label: "<embedded academic scene>".into(),
                dir: dir.to_path_buf(),
            });
        }
        let p = dir.join(&sweep.base);
        let text = std::fs::read_to_string(&p)
            .map_err(|e| Error::scene("base", format!("cannot read {}: {e}", p.display())))?;
        Ok(Base {
            text,
            label: p.display().to_string(),
            dir: p.parent().map(Path::to_path_buf).unwrap_or_else(|| PathBuf::from(".")),
        })
    }
}

/// A point's error as the sweep refuses it: the key path of the inner error kept (what
/// [`Error::key`] and the Python package's `SceneError.key` give), the point and its axis
/// values said in the message, and the place in the generated scene (a file never written, its
/// line and column) left out: `contact.penaltyy: in sweep point p000 (contact.penaltyy = 0.001):
/// unknown field …`. An error that names no key (a mesh file) is keyed `point <id>`.
fn point_error(id: &str, label: &str, e: Error) -> Error {
    let at = format!("in sweep point {id} ({label})");
    match e {
        Error::Scene { path, message } => Error::Scene { path, message: format!("{at}: {message}") },
        Error::Expression { path, message } => Error::Expression { path, message: format!("{at}: {message}") },
        Error::SceneSyntax { path, message, .. } if !path.is_empty() => {
            let what = message.strip_prefix(&format!("{path}: ")).unwrap_or(&message);
            let what = match what.split_once(": ") {
                Some((place, rest)) if place.starts_with("TOML parse error") => rest,
                _ => what,
            };
            Error::Scene { message: format!("{at}: {what}"), path }
        }
        other => Error::scene(format!("point {id}"), format!("({label}) {other}")),
    }
}

/// The sweep's `[set]` as leaf overrides.
fn fixed_overrides(sweep: &SweepFile) -> Result<Vec<Override>> {
    crate::overrides::leaves(&sweep.set).map_err(|e| Error::scene("set", e.to_string()))
}

/// Columns of sweep.csv an axis may not take.
fn reserved(column: &str) -> bool {
    ["point", "status", "wall_time_s", "reason"].contains(&column) || collect::FIGURES.contains(&column)
}

/// Refuse overrides that touch the same value from two places whose results sweep.csv would
/// misreport: `[set]` and an axis, two axes, `--set` and an axis — and any axis or `[set]` on
/// `name` (every point is named after the sweep).
fn check_conflicts(fixed: &[Override], axes: &[Axis], extra: &[Override]) -> Result<()> {
    let keys = |a: &Axis| -> Vec<Override> { a.overrides.iter().flatten().cloned().collect() };
    let name = [crate::overrides::Segment::Key("name".into())];
    for o in fixed.iter().chain(axes.iter().flat_map(|a| a.overrides.iter().flatten())) {
        if crate::overrides::overlap(&o.path, &name) {
            return Err(Error::scene(
                &o.key,
                "is set for every point (its name is the sweep's); a sweep cannot vary it",
            ));
        }
    }
    for (i, a) in axes.iter().enumerate() {
        let mine = keys(a);
        let against: Vec<(String, &Override)> = fixed
            .iter()
            .map(|o| ("[set]".to_string(), o))
            .chain(extra.iter().map(|o| ("--set".to_string(), o)))
            .chain(
                axes[..i]
                    .iter()
                    .enumerate()
                    .flat_map(|(j, b)| b.overrides.iter().flatten().map(move |o| (format!("axis[{j}]"), o))),
            )
            .collect();
        for m in &mine {
            if let Some((from, o)) = against.iter().find(|(_, o)| crate::overrides::overlap(&m.path, &o.path)) {
                return Err(Error::scene(
                    format!("axis[{i}]"),
                    format!(
                        "{} and {} of {from} set the same value: sweep.csv would report what did not run",
                        m.key, o.key
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// The scene of a sweep's base with its `[set]` and `overrides`, read but *not* validated — for
/// a study that records what a point outside the sweep (an invalid value) is refused with.
pub fn scene_for(sweep: &SweepFile, base: &Base, overrides: &[Override]) -> Result<Scene> {
    let mut ovs = fixed_overrides(sweep)?;
    ovs.extend(overrides.iter().cloned());
    let text = point_text(&base.text, &base.label, &base.dir, &ovs, &sweep.name)?;
    Scene::from_toml(&text, &base.label)
}

/// Lock a sweep folder for this process (`DIR/sweep.lock`): two sweeps of one folder at once
/// would run the same points into the same folders. Held while `sweep` or `sweep collect` runs.
/// A folder that is not a sweep's (nor new or empty) is refused first, with nothing written.
pub fn lock(dir: &Path) -> Result<crate::output::folder::Lock> {
    check_folder(dir)?;
    crate::output::folder::lock(dir, "sweep.lock")
}

/// A completed run in a sweep's `points/`: its folder's name (a point id, or `.moving-<id>`
/// where a move was interrupted) and its scene (None where scene.toml cannot be read).
struct Completed {
    name: String,
    scene: Option<String>,
}

/// The completed runs in `points` (a summary.json that says `completed`, whether or not the
/// rest of the folder agrees with it).
fn completed_runs(points: &Path) -> Vec<Completed> {
    let Ok(rd) = std::fs::read_dir(points) else { return Vec::new() };
    let mut found: Vec<Completed> = rd
        .flatten()
        .filter_map(|e| {
            let name = e.file_name().to_string_lossy().to_string();
            let named = is_id(&name) || name.strip_prefix(".moving-").is_some_and(is_id);
            let completed = collect::point_status(&e.path()) == Some(crate::failure::RunStatus::Completed);
            (named && e.path().is_dir() && completed)
                .then(|| Completed { scene: std::fs::read_to_string(e.path().join("scene.toml")).ok(), name })
        })
        .collect();
    found.sort_by(|a, b| a.name.cmp(&b.name));
    found
}

/// Refuse a folder that is neither new, empty (but for the sweep's lock, taken first) nor a
/// sweep's (it has sweep.json), as `run` refuses a folder that is not a run's: a sweep writes
/// points/, sweep.json, sweep.csv, plots/, Snakefile and config.yaml there, which must not mix
/// with a user's files or another command's.
fn check_folder(dir: &Path) -> Result<()> {
    if dir.join("sweep.json").exists() {
        return Ok(());
    }
    let Ok(rd) = std::fs::read_dir(dir) else { return Ok(()) };
    let mut held: Vec<String> =
        rd.flatten().map(|e| e.file_name().to_string_lossy().to_string()).filter(|n| n != "sweep.lock").collect();
    if held.is_empty() {
        return Ok(());
    }
    held.sort();
    let more = if held.len() > 5 { ", …" } else { "" };
    let shown = held.iter().take(5).cloned().collect::<Vec<_>>().join(", ");
    Err(Error::folder(
        dir,
        format!(
            "is not a sweep's folder (it has no sweep.json) and holds {shown}{more}: a sweep writes only into a new or empty folder or a sweep's own, so give another folder with --out"
        ),
    ))
}

/// Remove a point's marker (`points/<id>.done`), if it has one.
fn remove_marker(pd: &Path) -> Result<()> {
    let m = runner::marker(pd);
    match std::fs::remove_file(&m) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(Error::io(&m, e)),
        _ => Ok(()),
    }
}

/// A point id: `p` and digits.
fn is_id(id: &str) -> bool {
    id.len() > 1 && id.starts_with('p') && id[1..].chars().all(|c| c.is_ascii_digit())
}

/// Remove a point folder's outputs, keeping its scene.toml and the lock of a run that may hold
/// it (a changed scene, or a run about to start over: nothing of an earlier run may be read as
/// this one's).
pub fn clear_outputs(pd: &Path) -> Result<()> {
    let Ok(entries) = std::fs::read_dir(pd) else { return Ok(()) };
    for e in entries.flatten() {
        let path = e.path();
        if path.file_name().is_some_and(|n| n == "scene.toml" || n == "run.lock") {
            continue;
        }
        let removed = if path.is_dir() { std::fs::remove_dir_all(&path) } else { std::fs::remove_file(&path) };
        removed.map_err(|err| Error::io(&path, err))?;
    }
    Ok(())
}

/// Parse a sweep file's text; errors name the key path as a scene's do.
pub fn parse(text: &str, file: &str) -> Result<SweepFile> {
    let de = toml::de::Deserializer::parse(text).map_err(|e| crate::scene::parse::syntax_error(file, "", &e))?;
    let mut sweep: SweepFile = serde_path_to_error::deserialize(de).map_err(|e| {
        let path = e.path().to_string();
        crate::scene::parse::syntax_error(file, &path, &e.into_inner())
    })?;
    // the override tables as written: a dotted key sets one leaf, an inline table is given whole
    if let Ok(source) = toml::de::DeTable::parse(text) {
        let source = source.get_ref();
        fn find<'a, 'i>(t: &'a toml::de::DeTable<'i>, k: &str) -> Option<&'a toml::de::DeValue<'i>> {
            t.iter().find(|(sk, _)| sk.get_ref().as_ref() == k).map(|(_, v)| v.get_ref())
        }
        if let Some(toml::de::DeValue::Table(set)) = find(source, "set") {
            sweep.set = crate::overrides::dotted_to_paths(&sweep.set, set, text);
        }
        if let Some(toml::de::DeValue::Array(axes)) = find(source, "axis") {
            for (spec, written) in sweep.axes.iter_mut().zip(axes.iter()) {
                let toml::de::DeValue::Table(written) = written.get_ref() else { continue };
                let Some(toml::de::DeValue::Array(sets)) = find(written, "sets") else { continue };
                for (t, w) in spec.sets.iter_mut().zip(sets.iter()) {
                    if let toml::de::DeValue::Table(w) = w.get_ref() {
                        *t = crate::overrides::dotted_to_paths(t, w, text);
                    }
                }
            }
        }
    }
    Ok(sweep)
}

/// An axis as written → its column, labels, numbers and overrides.
fn resolve_axis(a: usize, spec: &AxisSpec) -> Result<Axis> {
    let at = format!("axis[{a}]");
    let (column, overrides, shown): (String, Vec<Vec<Override>>, Vec<String>) = match (&spec.key, spec.sets.is_empty())
    {
        (Some(key), true) => {
            if spec.values.is_empty() {
                return Err(Error::scene(format!("{at}.values"), "is empty: an axis needs at least one value"));
            }
            if spec.name.is_some() || !spec.labels.is_empty() {
                return Err(Error::scene(
                    &at,
                    "an axis of `key` is named by its key and shows its values: `name` and `labels` go with `sets`",
                ));
            }
            let ovs = spec
                .values
                .iter()
                .map(|v| Override::new(key, v.clone()).map(|o| vec![o]))
                .collect::<Result<Vec<_>>>()
                .map_err(|e| Error::scene(format!("{at}.key"), e.to_string()))?;
            (key.clone(), ovs, spec.values.iter().map(show_value).collect())
        }
        (None, false) => {
            let Some(name) = &spec.name else {
                return Err(Error::scene(
                    format!("{at}.name"),
                    "missing: an axis of `sets` needs a name (its sweep.csv column)",
                ));
            };
            if !spec.values.is_empty() {
                return Err(Error::scene(format!("{at}.values"), "goes with `key`; an axis of `sets` has no values"));
            }
            let ovs = spec
                .sets
                .iter()
                .enumerate()
                .map(|(i, t)| {
                    if t.is_empty() {
                        return Err(Error::scene(
                            format!("{at}.sets[{i}]"),
                            "is empty: a value of the axis sets at least one key",
                        ));
                    }
                    crate::overrides::leaves(t).map_err(|e| Error::scene(format!("{at}.sets[{i}]"), e.to_string()))
                })
                .collect::<Result<Vec<_>>>()?;
            let shown = spec
                .sets
                .iter()
                .map(|t| t.iter().map(|(k, v)| format!("{k}={}", show_value(v))).collect::<Vec<_>>().join(" "))
                .collect();
            (name.clone(), ovs, shown)
        }
        (Some(_), false) => return Err(Error::scene(&at, "has both `key` and `sets`: give one")),
        (None, true) => return Err(Error::scene(&at, "needs `key` with `values`, or `name` with `sets`")),
    };
    let labels = if spec.labels.is_empty() {
        shown
    } else if spec.labels.len() == overrides.len() {
        spec.labels.clone()
    } else {
        return Err(Error::scene(
            format!("{at}.labels"),
            format!("has {} entries for {} values", spec.labels.len(), overrides.len()),
        ));
    };
    if column.trim().is_empty() || column.contains([',', '"']) || column.chars().any(char::is_control) {
        return Err(Error::scene(
            &at,
            format!("the column name {column:?} must be non-empty, without commas, quotes or control characters"),
        ));
    }
    for (i, l) in labels.iter().enumerate() {
        crate::scene::check_text(&format!("{at}.labels[{i}]"), l)?;
    }
    if reserved(&column) {
        return Err(Error::scene(&at, format!("{column:?} is a column of sweep.csv already: name the axis otherwise")));
    }
    // a numeric axis: the values (or, for `sets`, the labels) are all numbers
    let numbers: Option<Vec<f64>> = if spec.key.is_some() {
        spec.values.iter().map(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64))).collect()
    } else {
        labels.iter().map(|l| l.parse::<f64>().ok()).collect()
    };
    Ok(Axis { column, labels, numbers, overrides })
}

/// A value as it reads in sweep.csv: strings bare, numbers and the rest as TOML.
fn show_value(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => s.clone(),
        // as sweep.csv's other reals: 1e-30, not 0.000…001 (thirty digits)
        toml::Value::Float(f) => crate::output::csv::real(*f),
        other => other.to_string(),
    }
}

/// The choices (one value index per axis) of every point.
fn combinations(axes: &[Axis], mode: Mode) -> Result<Vec<Vec<usize>>> {
    if axes.is_empty() {
        return Ok(vec![Vec::new()]);
    }
    let lens: Vec<usize> = axes.iter().map(|a| a.labels.len()).collect();
    match mode {
        Mode::Zip => {
            if let Some(a) = lens.iter().position(|&l| l != lens[0]) {
                return Err(Error::scene(
                    "mode",
                    format!("\"zip\" needs axes of one length: axis[0] has {}, axis[{a}] {}", lens[0], lens[a]),
                ));
            }
            Ok((0..lens[0]).map(|i| vec![i; axes.len()]).collect())
        }
        Mode::Grid => {
            let total = lens.iter().try_fold(1usize, |acc, &l| acc.checked_mul(l)).filter(|&t| t <= MAX_POINTS);
            let Some(total) = total else {
                return Err(Error::scene("axis", format!("the grid has more than {MAX_POINTS} points")));
            };
            Ok((0..total)
                .map(|mut i| {
                    let mut c = vec![0; lens.len()];
                    for a in (0..lens.len()).rev() {
                        c[a] = i % lens[a];
                        i /= lens[a];
                    }
                    c
                })
                .collect())
        }
    }
}

fn describe(axes: &[Axis], choice: &[usize]) -> String {
    if axes.is_empty() {
        return "the base scene".into();
    }
    axes.iter().zip(choice).map(|(a, &c)| format!("{} = {}", a.column, a.labels[c])).collect::<Vec<_>>().join(", ")
}

/// The point's scene: the base text with its overrides, its name set to `name`, and a relative
/// mesh file made absolute (the point's scene lives in another folder).
fn point_text(base: &str, label: &str, base_dir: &Path, ovs: &[Override], name: &str) -> Result<String> {
    let mut table: toml::Table =
        base.parse().map_err(|e: toml::de::Error| crate::scene::parse::syntax_error(label, "", &e))?;
    crate::overrides::apply_all(&mut table, ovs)?;
    table.insert("name".into(), toml::Value::String(name.to_string()));
    if let Some(toml::Value::Table(d)) = table.get_mut("domain")
        && let Some(toml::Value::String(f)) = d.get("file")
        && Path::new(f).is_relative()
    {
        let abs = base_dir.join(f);
        let abs = abs.canonicalize().unwrap_or(abs);
        d.insert("file".into(), toml::Value::String(abs.display().to_string()));
    }
    toml::to_string(&table).map_err(|e| Error::Output(format!("{label}: {e}")))
}

/// Validate a point's scene as `run` would: the scene, then the problem (mesh and sides, the
/// gap and the initial state on it, loads, at every time a step samples them); its memory for a
/// cluster job (MB: the estimate ×1.5 + 100 — the estimate is within 0.91–1.17 of measured
/// peaks, and a job killed for its memory loses its work, so the margin is wide) and a
/// conservative run time (minutes: the estimated work at 0.1 Gflop/s, at least 10). An axis
/// over a key the point's scene does not use (`contact.penalty` with `enforcement = "exact"`)
/// is refused: its points would be the same run.
fn check_point(text: &str, id: &str, axis_keys: &[&str]) -> Result<(u64, u64)> {
    let scene = Scene::from_toml(text, &format!("points/{id}/scene.toml"))?;
    let model = scene.validate()?;
    for key in axis_keys {
        if let Some(w) = model.warnings.iter().find(|w| w.starts_with(&format!("{key} is not used"))) {
            return Err(Error::scene(*key, format!("a sweep axis over a key the scene does not use: {w}")));
        }
    }
    let e = crate::resources::estimate(&model, Path::new("."))?;
    // the problem's own checks, where the machine can hold it (a point meant for a larger
    // cluster node is checked by its run)
    if crate::resources::check_fits(&e, crate::resources::available_memory()).is_ok() {
        let problem = crate::problem::Problem::new(model.clone(), Path::new("."))?;
        problem.check_load_times()?;
    }
    let (solves, contact) = e.flops_per_step();
    let steps = model.time.steps as f64;
    let minutes = ((solves + contact) * steps / 1e8 / 60.0).ceil().max(10.0);
    Ok(((1.5 * e.total() / 1e6 + 100.0).ceil() as u64, minutes.min(1e7) as u64))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A point's refusal keeps the key path of the error inside it (a key, an expression, a
    /// key the scene's schema does not know), says the point and its axis values, and drops the
    /// generated scene's file and place; an error without a key is keyed by the point.
    #[test]
    fn a_point_error_keeps_the_inner_key_path() {
        let syntax = Error::SceneSyntax {
            file: "points/p000/scene.toml".into(),
            message: "contact.penaltyy: TOML parse error at line 13, column 1: unknown field `penaltyy`".into(),
            diagram: "13 | penaltyy = 0.001".into(),
            path: "contact.penaltyy".into(),
        };
        let e = point_error("p000", "contact.penaltyy = 0.001", syntax);
        assert_eq!(e.key(), Some("contact.penaltyy"));
        assert_eq!(
            e.to_string(),
            "contact.penaltyy: in sweep point p000 (contact.penaltyy = 0.001): unknown field `penaltyy`"
        );
        let scene = Error::scene("contact.compliance", "must be >= 0, got -1");
        let e = point_error("p001", "contact.compliance = -1", scene);
        assert_eq!(e.key(), Some("contact.compliance"));
        assert_eq!(
            e.to_string(),
            "contact.compliance: in sweep point p001 (contact.compliance = -1): must be >= 0, got -1"
        );
        let expr =
            Error::Expression { path: "loads.traction[0].value[1]".into(), message: "unknown variable z".into() };
        let e = point_error("p002", "the base scene", expr);
        assert!(matches!(e, Error::Expression { .. }) && e.key() == Some("loads.traction[0].value[1]"), "{e}");
        let mesh = Error::mesh("m.msh", "no such file");
        let e = point_error("p003", "domain.file = m.msh", mesh);
        assert_eq!(e.key(), Some("point p003"));
        assert_eq!(e.to_string(), "point p003: (domain.file = m.msh) mesh m.msh: no such file");
    }

    /// An axis value reads in sweep.csv as its other reals do: shortest round-trip, with an
    /// exponent outside 1e-5 ≤ |x| < 1e16 (1e-30 was thirty digits after the point).
    #[test]
    fn axis_values_read_as_sweep_reals() {
        assert_eq!(show_value(&toml::Value::Float(1e-30)), "1e-30");
        assert_eq!(show_value(&toml::Value::Float(1e-4)), "0.0001");
        assert_eq!(show_value(&toml::Value::Float(2.5e-3)), "0.0025");
        assert_eq!(show_value(&toml::Value::Integer(3)), "3");
        assert_eq!(show_value(&toml::Value::String("midpoint".into())), "midpoint");
    }
}
