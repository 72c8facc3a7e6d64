//! Running a sweep's points on this machine: `jobs` worker threads take the points in order,
//! each point one `run` into its folder (the same library call as `dyncontact run`), a progress
//! bar over points. The parallelism is across points: the caller keeps each point's numerics
//! sequential by setting faer's global parallelism to `Par::Seq` once, at its start, as
//! `dyncontact`'s `main` does (a library sets no process-wide state). A point already completed with the same
//! scene and inputs is skipped, so an interrupted sweep resumes; a point that fails is recorded
//! with its reason (its summary.json says `failed` and why) and the others go on.
//!
//! A point that reaches a final outcome — completed, or failed in a way that running it again
//! would repeat (the solver, its input) — gets the marker `points/<id>.done`: the output of the
//! Snakefile's rule, which runs one point with `dyncontact sweep point points/<id>` ([`run_one`],
//! the same code as here). An interrupted, killed or disk-full point has no marker, so Snakemake
//! runs it again.

use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use super::Plan;
use crate::error::{Error, FailureKind, Result};
use crate::problem::Problem;
use crate::run::{RunOptions, run_locked, write_failed_start};
use crate::scene::Scene;
use crate::simulation::Settings;

/// How a sweep runs here.
#[derive(Debug, Clone, Default)]
pub struct RunnerOptions {
    /// worker threads (at least 1)
    pub jobs: usize,
    /// a progress bar over points (on a terminal)
    pub progress: bool,
    /// set by a signal handler: running points stop at the end of their step, no new one starts
    pub interrupt: Option<Arc<AtomicBool>>,
}

/// How one point ended here.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// completed earlier with the same scene: not run again
    Skipped,
    Completed,
    /// failed, with the reason (also in its summary.json)
    Failed(String),
    /// stopped by an interrupt (its checkpoint and files stay valid)
    Interrupted,
    /// not started (the sweep was interrupted first)
    NotRun,
}

impl std::fmt::Display for Outcome {
    /// The words sweep.csv uses (`completed`, `failed`, `interrupted`), a failure with its reason:
    /// what `dyncontact sweep point` prints.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Outcome::Skipped => f.write_str("skipped (completed earlier with the same scene)"),
            Outcome::Completed => f.write_str("completed"),
            Outcome::Failed(reason) => write!(f, "failed: {reason}"),
            Outcome::Interrupted => f.write_str("interrupted"),
            Outcome::NotRun => f.write_str("not run"),
        }
    }
}

/// Run every point of `plan` that is not `done` (from [`Plan::write`]) into its folder below
/// `dir`. Returns each point's outcome, in the plan's order. Each point's numerics use faer's
/// global parallelism as the caller set it (`Par::Seq` keeps `jobs` points on `jobs` cores).
pub fn run_points(plan: &Plan, dir: &Path, done: &[bool], opts: &RunnerOptions) -> Result<Vec<Outcome>> {
    let n = plan.points.len();
    let outcomes: Vec<Mutex<Outcome>> = (0..n)
        .map(|i| Mutex::new(if done.get(i).copied().unwrap_or(false) { Outcome::Skipped } else { Outcome::NotRun }))
        .collect();
    let todo: Vec<usize> = (0..n).filter(|&i| !done.get(i).copied().unwrap_or(false)).collect();
    let bar = opts.progress.then(|| {
        let b = indicatif::ProgressBar::new(n as u64);
        if let Ok(style) =
            indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} points  {elapsed_precise} (eta {eta})  {msg}")
        {
            b.set_style(style);
        }
        b.set_position((n - todo.len()) as u64);
        b
    });
    // the memory of each point; a point too large for this machine (its free memory measured
    // once, before any point runs) refuses the sweep before anything starts, as `run` refuses
    // it (it may be meant for a larger machine: `--plan-only` lays the sweep out for a cluster)
    let available = crate::resources::available_memory();
    let mut largest = 0.0f64;
    let mut too_large = Vec::new();
    let todo: Vec<usize> = todo
        .into_iter()
        .filter(|&i| match estimate(plan, dir, i) {
            Ok(e) => {
                if let Err(refused) = crate::resources::check_fits(&e, available) {
                    too_large.push(super::point_error(&plan.points[i].id, &plan.describe(&plan.points[i]), refused));
                }
                largest = largest.max(e.total());
                true
            }
            Err(e) => {
                // its scene no longer validates (a file it reads changed): that point fails
                let pd = Plan::point_dir(dir, &plan.points[i].id);
                let _ = super::clear_outputs(&pd);
                let _ = write_failed_start(&pd, &plan.points[i].id, &e);
                let _ = crate::output::write_atomic(&marker(&pd), b"");
                if let Ok(mut slot) = outcomes[i].lock() {
                    *slot = Outcome::Failed(e.to_string());
                }
                false
            }
        })
        .collect();
    if !too_large.is_empty() {
        let n = too_large.len();
        let more =
            if n > 1 { format!(" (and {} more point{})", n - 1, if n == 2 { "" } else { "s" }) } else { String::new() };
        let advice = format!(
            "{more}. No point ran: run this sweep where its points fit, or lay it out with --plan-only for a cluster (config.yaml gives each point's memory)"
        );
        return Err(match too_large.swap_remove(0) {
            Error::Scene { path, message } => Error::Scene { path, message: message + &advice },
            other => other,
        });
    }
    // the points that run at once must fit together
    let at_once = opts.jobs.clamp(1, todo.len().max(1));
    if let Some(avail) = available.filter(|a| at_once as f64 * largest > *a) {
        return Err(Error::scene(
            "--jobs",
            format!(
                "{at_once} points at once would need about {:.0} MB (the largest point {:.0} MB each) but {:.0} MB are available: lower --jobs",
                at_once as f64 * largest / 1e6,
                largest / 1e6,
                avail / 1e6
            ),
        ));
    }
    let next = AtomicUsize::new(0);
    let stopped = || opts.interrupt.as_ref().is_some_and(|f| f.load(Ordering::SeqCst));
    std::thread::scope(|scope| {
        for _ in 0..at_once {
            scope.spawn(|| {
                loop {
                    if stopped() {
                        break;
                    }
                    let k = next.fetch_add(1, Ordering::SeqCst);
                    let Some(&i) = todo.get(k) else { break };
                    let p = &plan.points[i];
                    let pd = Plan::point_dir(dir, &p.id);
                    // a panic in one point (none is known: every failure path returns an error) is that
                    // point's failure, not the sweep's
                    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                        run_point(&pd, &p.scene_text, opts.interrupt.clone())
                    }))
                    .unwrap_or_else(|_| {
                        let reason = "the run panicked (report it with this point's scene.toml)".to_string();
                        let e = Error::Internal(reason);
                        let _ = write_failed_start(&pd, &p.id, &e);
                        Outcome::Failed(e.to_string())
                    });
                    if let Some(b) = &bar {
                        b.inc(1);
                        if let Outcome::Failed(reason) = &outcome {
                            b.set_message(format!("{} failed: {}", p.id, reason.chars().take(60).collect::<String>()));
                        }
                    }
                    if let Ok(mut slot) = outcomes[i].lock() {
                        *slot = outcome;
                    }
                }
            });
        }
    });
    if let Some(b) = &bar {
        b.finish();
    }
    Ok(outcomes.into_iter().map(|m| m.into_inner().unwrap_or(Outcome::NotRun)).collect())
}

/// The memory estimate of point `i` of `plan` in its folder below `dir` (its scene validated
/// again: a file it reads may have changed since the plan).
fn estimate(plan: &Plan, dir: &Path, i: usize) -> Result<crate::resources::Estimate> {
    let pd = Plan::point_dir(dir, &plan.points[i].id);
    let model = Scene::from_toml(&plan.points[i].scene_text, "scene.toml")?.validate()?;
    crate::resources::estimate(&model, &pd)
}

/// The points of `plan` too large for the memory this machine has available now, each as the
/// refusal that running the sweep here would give (a key path, the point, the estimate): for a
/// warning where the sweep is only laid out (`--plan-only`, for a cluster's larger nodes).
pub fn too_large_here(plan: &Plan, dir: &Path) -> Vec<Error> {
    let available = crate::resources::available_memory();
    (0..plan.points.len())
        .filter_map(|i| {
            let refused = crate::resources::check_fits(&estimate(plan, dir, i).ok()?, available).err()?;
            Some(super::point_error(&plan.points[i].id, &plan.describe(&plan.points[i]), refused))
        })
        .collect()
}

/// The marker of a point's final outcome: `points/<id>.done` beside its folder.
pub fn marker(pd: &Path) -> std::path::PathBuf {
    pd.with_extension("done")
}

/// Whether a failure of this kind is a point's final outcome (running it again would repeat it).
fn is_final(kind: FailureKind) -> bool {
    matches!(kind, FailureKind::Solver | FailureKind::NonFinite | FailureKind::LinearAlgebra | FailureKind::Input)
}

/// `dyncontact sweep point points/<id>`: run one point of a sweep folder from its scene.toml, as
/// the in-process sweep does. Ok when the point reached a final outcome (its marker is written);
/// Err otherwise, with the reason.
pub fn run_one(pd: &Path, interrupt: Option<Arc<AtomicBool>>) -> Result<Outcome> {
    let sp = pd.join("scene.toml");
    let text = std::fs::read_to_string(&sp).map_err(|e| Error::read(&sp, e))?;
    match run_point(pd, &text, interrupt) {
        Outcome::Interrupted => Err(Error::Interrupted { step: 0, time: 0.0 }),
        o if marker(pd).exists() => Ok(o),
        Outcome::Failed(reason) => Err(Error::folder(pd, format!("the point did not reach a final outcome: {reason}"))),
        o => Ok(o),
    }
}

/// One point: its folder cleared (but its scene.toml), its scene read, validated and run into
/// `pd` (a failure before the run starts writes summary.json saying why); the marker written
/// when the outcome is final. The memory check of `run` is left out: it measures the memory
/// free now, which the other points running take.
fn run_point(pd: &Path, text: &str, interrupt: Option<Arc<AtomicBool>>) -> Outcome {
    let _ = std::fs::remove_file(marker(pd));
    let (outcome, kind) = run_point_once(pd, text, interrupt);
    if (matches!(outcome, Outcome::Completed) || kind.is_some_and(is_final))
        && let Err(e) = crate::output::write_atomic(&marker(pd), b"")
    {
        return Outcome::Failed(e.to_string());
    }
    outcome
}

/// [`run_point`] without the marker: the outcome and, for a failure, its kind.
fn run_point_once(pd: &Path, text: &str, interrupt: Option<Arc<AtomicBool>>) -> (Outcome, Option<FailureKind>) {
    // the point's folder is the sweep's: cleared and run under one lock (another process
    // running this point keeps it), held from here to the run's end
    let lock = match crate::output::folder::lock_run(pd).and_then(|lock| {
        super::clear_outputs(pd)?;
        Ok(lock)
    }) {
        Ok(lock) => lock,
        Err(e) => return (Outcome::Failed(e.to_string()), Some(e.kind())),
    };
    let scene = Scene::from_toml(text, &pd.join("scene.toml").display().to_string());
    let name = scene.as_ref().map(|s| s.name.clone()).unwrap_or_default();
    // refused before any step, as `dyncontact run` refuses it
    let problem = scene.and_then(|s| s.validate()).and_then(|model| Problem::new(model, pd)).and_then(|p| {
        p.check_load_times()?;
        Ok(p)
    });
    let problem = match problem {
        Ok(p) => p,
        Err(e) => {
            let _ = write_failed_start(pd, &name, &e);
            return (Outcome::Failed(e.to_string()), Some(e.kind()));
        }
    };
    let opts = RunOptions {
        out: pd.to_path_buf(),
        progress: false,
        checkpoint_every: None,
        resume: false,
        scene_text: None,
        origin: crate::run::Origin {
            scene_file: Some(pd.join("scene.toml").display().to_string()),
            overrides: Vec::new(),
        },
        stop_after: None,
        interrupt,
    };
    match run_locked(&problem, Settings::from_problem(&problem), &opts, lock) {
        Ok(_) => (Outcome::Completed, None),
        Err(Error::Interrupted { .. }) => (Outcome::Interrupted, Some(FailureKind::Interrupted)),
        Err(e) => (Outcome::Failed(e.to_string()), Some(e.kind())),
    }
}
