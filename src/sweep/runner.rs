//! Running a sweep's points on this machine: `jobs` worker threads take the points in order,
//! each point one `run` into its folder (the same library call as `dyncontact run`, numerics
//! sequential inside each), a progress bar over points. A point already completed with the same
//! scene is skipped, so an interrupted sweep resumes; a point that fails is recorded with its
//! reason (its summary.json says `failed` and why) and the others go on.

use std::path::Path;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use super::Plan;
use crate::error::{Error, Result};
use crate::problem::Problem;
use crate::run::{run, write_failed_start, RunOptions};
use crate::scene::Scene;

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

/// Run every point of `plan` that is not `done` (from [`Plan::write`]) into its folder below
/// `dir`. Returns each point's outcome, in the plan's order.
pub fn run_points(plan: &Plan, dir: &Path, done: &[bool], opts: &RunnerOptions) -> Result<Vec<Outcome>> {
    let n = plan.points.len();
    let outcomes: Vec<Mutex<Outcome>> = (0..n).map(|i| Mutex::new(if done.get(i).copied().unwrap_or(false) { Outcome::Skipped } else { Outcome::NotRun })).collect();
    let todo: Vec<usize> = (0..n).filter(|&i| !done.get(i).copied().unwrap_or(false)).collect();
    let bar = opts.progress.then(|| {
        let b = indicatif::ProgressBar::new(n as u64);
        if let Ok(style) = indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} points  {elapsed_precise} (eta {eta})  {msg}") {
            b.set_style(style);
        }
        b.set_position((n - todo.len()) as u64);
        b
    });
    // points too large for this machine (its free memory measured once, before any point runs)
    // are refused as `run` refuses them, before anything starts
    let available = crate::resources::available_memory();
    let todo: Vec<usize> = todo
        .into_iter()
        .filter(|&i| {
            let pd = Plan::point_dir(dir, &plan.points[i].id);
            let fits = Scene::from_toml(&plan.points[i].scene_text, "scene.toml")
                .and_then(|s| s.validate())
                .and_then(|m| crate::resources::check_fits(&crate::resources::estimate(&m, &pd)?, available));
            match fits {
                Ok(()) => true,
                Err(e) => {
                    let _ = super::clear_outputs(&pd);
                    let _ = write_failed_start(&pd, &plan.points[i].id, &e);
                    if let Ok(mut slot) = outcomes[i].lock() {
                        *slot = Outcome::Failed(e.to_string());
                    }
                    false
                }
            }
        })
        .collect();
    let next = AtomicUsize::new(0);
    let stopped = || opts.interrupt.as_ref().is_some_and(|f| f.load(Ordering::SeqCst));
    // each point's numerics run sequentially: the parallelism is across points
    faer::set_global_parallelism(faer::Par::Seq);
    std::thread::scope(|scope| {
        for _ in 0..opts.jobs.clamp(1, todo.len().max(1)) {
            scope.spawn(|| loop {
                if stopped() {
                    break;
                }
                let k = next.fetch_add(1, Ordering::SeqCst);
                let Some(&i) = todo.get(k) else { break };
                let p = &plan.points[i];
                let pd = Plan::point_dir(dir, &p.id);
                // a panic in one point (none is known: every failure path returns an error) is that
                // point's failure, not the sweep's
                let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| run_point(&pd, &p.scene_text, opts.interrupt.clone())))
                    .unwrap_or_else(|_| {
                        let reason = "the run panicked (a defect of dyncontact: please report it with this point's scene.toml)".to_string();
                        let _ = write_failed_start(&pd, &p.id, &Error::Output(reason.clone()));
                        Outcome::Failed(reason)
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
            });
        }
    });
    if let Some(b) = &bar {
        b.finish();
    }
    Ok(outcomes.into_iter().map(|m| m.into_inner().unwrap_or(Outcome::NotRun)).collect())
}

/// One point: its folder cleared (but its scene.toml), its scene read, validated and run into
/// `pd` (a failure before the run starts writes summary.json saying why). The memory check of
/// `run` is left out: it measures the memory free now, which the other points running take.
fn run_point(pd: &Path, text: &str, interrupt: Option<Arc<AtomicBool>>) -> Outcome {
    if let Err(e) = super::clear_outputs(pd) {
        return Outcome::Failed(e.to_string());
    }
    let scene = Scene::from_toml(text, &pd.join("scene.toml").display().to_string());
    let name = scene.as_ref().map(|s| s.name.clone()).unwrap_or_default();
    let problem = scene.and_then(|s| s.validate()).and_then(|model| Problem::new(model, pd));
    let problem = match problem {
        Ok(p) => p,
        Err(e) => {
            let _ = write_failed_start(pd, &name, &e);
            return Outcome::Failed(e.to_string());
        }
    };
    let opts = RunOptions { out: pd.to_path_buf(), progress: false, checkpoint_every: None, resume: false, stop_after: None, interrupt };
    match run(&problem, &opts) {
        Ok(_) => Outcome::Completed,
        Err(Error::Interrupted { .. }) => Outcome::Interrupted,
        Err(e) => Outcome::Failed(e.to_string()),
    }
}
