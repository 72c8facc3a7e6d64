//! `dyncontact run`: the time loop with outputs, progress, checkpoints, interruption, and a
//! summary that says how the run ended.
//!
//! A run owns its folder (output/folder.rs): it locks it, refuses a folder holding files that
//! are not a run's, writes summary.json with status `running` before anything else and only
//! then replaces an earlier run's files. However it ends, the folder stays valid: history.csv
//! holds every completed step, series.pvd lists exactly the frames on disk, and summary.json says
//! `completed`, `failed` (with the step, time, residuals and a suggestion; also when an output
//! could not be written) or `interrupted` (with where it stopped; a checkpoint of that step is
//! written so `--resume` continues from it). A run killed outright leaves `running`.
//!
//! A resumed run proves first that the folder's files belong together (output/resume.rs): the
//! checkpoint's checksum and run, its inputs, the history row of its step, the frames.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use crate::checkpoint::{Checkpoint, Counters};
use crate::error::{Error, Result};
use crate::failure::RunStatus;
use crate::output::summary::{RunDetails, Timing};
use crate::output::{ModelInfo, Summary, Writer, folder, write_atomic};
use crate::problem::Problem;
use crate::simulation::{Settings, Simulation, StepRecord};
use crate::step::delassus::FactorCounts;

/// Options of a run.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    pub out: PathBuf,
    /// show a progress bar (only on a terminal)
    pub progress: bool,
    /// write DIR/checkpoint.json every N steps
    pub checkpoint_every: Option<usize>,
    /// continue from DIR/checkpoint.json
    pub resume: bool,
    /// the effective scene (overrides applied) to keep as DIR/scene.toml, which `--resume DIR`
    /// reads back; None: the folder's scene.toml is not the run's to write (a sweep's point,
    /// whose scene.toml the sweep wrote)
    pub scene_text: Option<String>,
    /// where the scene came from, for summary.json: the file as given and the `--set` overrides
    pub origin: Origin,
    /// stop cleanly (as if interrupted) after this step — for tests and batch control
    pub stop_after: Option<usize>,
    /// set by a signal handler to stop cleanly at the end of the current step
    pub interrupt: Option<Arc<AtomicBool>>,
}

/// Where a run's scene came from, recorded in summary.json (`scene_file`, `overrides`).
#[derive(Debug, Clone, Default)]
pub struct Origin {
    /// the scene file as the user gave it (`<embedded academic scene>` for the default scene)
    pub scene_file: Option<String>,
    /// the `--set` overrides in the order given, as typed
    pub overrides: Vec<String>,
}

/// Run a problem to its end time, writing every output. On a solver failure the files written
/// so far stay valid, summary.json says `"status": "failed"` and why, and the error is returned.
pub fn run(problem: &Problem, opts: &RunOptions) -> Result<Summary> {
    run_with(problem, Settings::from_problem(problem), opts)
}

/// A run that writes nothing: the same time loop, summary (as summary.json would say it: the
/// status, iteration totals, (E.1) residuals, warnings) and failures as [`run`], with every
/// record handed to `each` with the state after it — the initial record (t = 0) first. The
/// Python package's `dc.run(scene, out=None)` is this. `interrupt` stops it at the end of the
/// current step with [`Error::Interrupted`] (no checkpoint: there is no folder).
pub fn run_in_memory(
    problem: &Problem,
    origin: &Origin,
    interrupt: Option<&AtomicBool>,
    mut each: impl FnMut(&StepRecord, &Simulation),
) -> Result<Summary> {
    let start = Instant::now();
    let mut sim = Simulation::new(problem)?;
    let opts = RunOptions { origin: origin.clone(), ..RunOptions::default() };
    let mut summary = new_summary(problem, &sim, &opts, start, String::new());
    summary.details().effective_scene = None;
    let mut first_cap: Option<usize> = None;
    each(&sim.initial_record(), &sim);
    let mut steps = sim.steps();
    let ended = loop {
        if interrupt.is_some_and(|f| f.load(Ordering::SeqCst)) && steps.simulation().state.n < problem.steps {
            let n = steps.simulation().state.n;
            break Err(Error::Interrupted { step: n, time: problem.time(n) });
        }
        let Some(rec) = steps.next() else { break Ok(()) };
        match rec {
            Ok(rec) => {
                tally(&mut summary, &mut first_cap, &rec);
                each(&rec, steps.simulation());
            }
            Err(e) => break Err(e),
        }
    };
    let details = summary.details();
    details.set_contact_counts(sim.delassus_factors.all_counts());
    details.wall_time_s = start.elapsed().as_secs_f64();
    details.timing.total_s = details.wall_time_s;
    details.peak_memory_mb = crate::resources::peak_memory().map(|b| b / 1e6);
    ended?;
    finish_warnings(problem, summary.details(), first_cap);
    summary.status = RunStatus::Completed;
    Ok(summary)
}

/// summary.json of a run that could not start — its scene, mesh or operators were refused —
/// in an output folder that holds no earlier run (a sweep's point folder, or a new folder):
/// `"status": "failed"` with the reason and its kind, so every point of a sweep is read the same
/// way. A folder holding an earlier run (or anything else) is left as it is: a run that did not
/// start damages nothing.
pub fn write_failed_start(out: &Path, scene: &str, e: &Error) -> Result<()> {
    if !out.is_dir() || !matches!(folder::check_fresh(out), Ok(false)) {
        return Ok(());
    }
    write_summary(out, &Summary::failed_start(scene, e))
}

/// The run's counters in the form a checkpoint stores (`contact`: the contact solve's counts).
fn counters(s: &RunDetails, first_cap: Option<usize>, contact: FactorCounts) -> Counters {
    Counters {
        contact,
        newton_iterations_total: s.newton_iterations_total,
        fixed_point_iterations_total: s.fixed_point_iterations_total,
        fixed_point_iterations_max: s.fixed_point_iterations_max,
        fixed_point_cap_hits: s.fixed_point_cap_hits,
        unfrozen_fallbacks: s.unfrozen_fallbacks,
        first_cap,
        max_abs_energy_residual: s.max_abs_energy_residual.to_bits(),
        max_relative_energy_residual: s.max_relative_energy_residual.to_bits(),
        energy_guard_exceeded_steps: s.energy_guard_exceeded_steps,
    }
}

/// The summary's counters continued from a checkpoint.
fn restore_counters(summary: &mut RunDetails, c: &Counters) {
    summary.newton_iterations_total = c.newton_iterations_total;
    summary.fixed_point_iterations_total = c.fixed_point_iterations_total;
    summary.fixed_point_iterations_max = c.fixed_point_iterations_max;
    summary.fixed_point_cap_hits = c.fixed_point_cap_hits;
    summary.unfrozen_fallbacks = c.unfrozen_fallbacks;
    summary.max_abs_energy_residual = f64::from_bits(c.max_abs_energy_residual);
    summary.max_relative_energy_residual = f64::from_bits(c.max_relative_energy_residual);
    summary.energy_guard_exceeded_steps = c.energy_guard_exceeded_steps;
}

/// Add one step's iterations, timings and (E.1) residual to the summary.
fn tally(summary: &mut Summary, first_cap: &mut Option<usize>, rec: &StepRecord) {
    summary.steps_completed = rec.step;
    let summary = summary.details();
    let r = &rec.report;
    summary.newton_iterations_total += r.inner_iterations;
    summary.fixed_point_iterations_total += r.fixed_point_iterations;
    summary.fixed_point_iterations_max = summary.fixed_point_iterations_max.max(r.fixed_point_iterations);
    if !r.fixed_point_converged() {
        summary.fixed_point_cap_hits += 1;
        first_cap.get_or_insert(rec.step);
    }
    summary.unfrozen_fallbacks += usize::from(r.fallback.is_some());
    summary.energy_guard_exceeded_steps += usize::from(rec.energy_guard_exceeded);
    let res = rec.energy.residual.abs();
    summary.max_abs_energy_residual = summary.max_abs_energy_residual.max(res);
    if rec.energy_scale > 0.0 {
        summary.max_relative_energy_residual = summary.max_relative_energy_residual.max(res / rec.energy_scale);
    }
    summary.final_time = rec.t;
    summary.timing.free_solve_s += rec.timing.free_solve;
    summary.timing.contact_solve_s += rec.timing.contact_solve;
    summary.timing.recovery_s += rec.timing.recovery;
    summary.timing.products_s += rec.timing.products;
    summary.timing.balance_s += rec.timing.balance;
}

/// A new run's identity: the time, the process and the folder, hashed.
fn new_run_id(out: &Path) -> String {
    let now = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_nanos()).unwrap_or(0);
    crate::fingerprint::text(&format!("{now} {} {}", std::process::id(), out.display()))
}

/// The summary of a run that is starting.
fn new_summary(problem: &Problem, sim: &Simulation, opts: &RunOptions, start: Instant, run_id: String) -> Summary {
    let mut info = ModelInfo::of(problem);
    info.set_sharp_convexity(sim.sharp_convexity, sim.settings.fixed_point.start);
    let t = sim.setup_timing;
    let details = RunDetails {
        description: problem.model.description.clone(),
        run_id,
        scene_file: opts.origin.scene_file.clone(),
        overrides: opts.origin.overrides.clone(),
        effective_scene: (opts.scene_text.is_some() || opts.out.join("scene.toml").is_file())
            .then(|| "scene.toml".to_string()),
        inputs_fingerprint: problem.inputs_fingerprint.clone(),
        warnings: info.warnings(),
        model: info,
        final_time: 0.0,
        wall_time_s: 0.0,
        peak_memory_mb: None,
        timing: Timing {
            setup_s: start.elapsed().as_secs_f64(),
            assembly_s: t.assembly,
            factorization_s: t.factorization,
            delassus_s: t.delassus,
            sharp_convexity_s: t.sharp_convexity,
            ..Timing::default()
        },
        contact_solve: sim.delassus.as_ref().map_or("none", |w| w.form()).to_string(),
        contact_solve_sparse: sim.delassus.as_ref().and_then(|w| w.sparse_stats()),
        contact_factorizations: 0,
        contact_factor_reuses: 0,
        contact_pcg_solves: 0,
        contact_pcg_iterations: 0,
        contact_velocity_solves: 0,
        contact_velocity_iterations: 0,
        newton_iterations_total: 0,
        fixed_point_iterations_total: 0,
        fixed_point_iterations_max: 0,
        fixed_point_cap_hits: 0,
        unfrozen_fallbacks: 0,
        max_abs_energy_residual: 0.0,
        max_relative_energy_residual: 0.0,
        energy_guard_exceeded_steps: 0,
    };
    Summary {
        version: env!("CARGO_PKG_VERSION").to_string(),
        scene: problem.model.name.clone(),
        status: RunStatus::Running,
        failure: None,
        failure_kind: None,
        steps_completed: 0,
        run: Some(details),
    }
}

/// A fresh run takes its folder: summary.json says `running`, the earlier run's files go, the
/// CSV files start with the state at t = 0.
fn start_fresh(
    problem: &Problem,
    sim: &Simulation,
    opts: &RunOptions,
    summary: &mut Summary,
    replaced: bool,
) -> Result<Writer> {
    write_summary(&opts.out, summary)?;
    folder::clear(&opts.out)?;
    if replaced {
        summary
            .details()
            .warnings
            .push(format!("{} held an earlier run's outputs: they were replaced", opts.out.display()));
    }
    write_scene(opts)?;
    let mut w = Writer::create(&opts.out, problem)?;
    w.record(&sim.initial_record(), problem, &sim.state, problem.steps == 0)?;
    Ok(w)
}

/// DIR/scene.toml: the run's effective scene (when it has one to write and the file does not
/// hold it already).
fn write_scene(opts: &RunOptions) -> Result<()> {
    let Some(text) = &opts.scene_text else { return Ok(()) };
    let path = opts.out.join("scene.toml");
    if std::fs::read_to_string(&path).is_ok_and(|t| t == *text) {
        return Ok(());
    }
    write_atomic(&path, text.as_bytes())
}

/// A resumed run: the checkpoint (read and checked: checksum, finite values) must belong to the
/// folder's run and inputs, the folder's files must agree with it; then the state and counters
/// are restored and the files cut back to its step.
fn start_resumed(
    problem: &Problem,
    sim: &mut Simulation,
    opts: &RunOptions,
    cp: &Checkpoint,
    summary: &mut Summary,
    first_cap: &mut Option<usize>,
) -> Result<Writer> {
    crate::output::resume::check(&opts.out, problem, cp)?;
    sim.restore(cp.state())?;
    sim.resume_solver(&cp.solver).ok_or_else(|| {
        Error::folder(
            opts.out.join("checkpoint.json"),
            "the checkpoint's contact factorization does not fit this scene",
        )
    })?;
    summary.steps_completed = cp.step;
    sim.delassus_factors.continue_counts(cp.counters.contact);
    let details = summary.details();
    restore_counters(details, &cp.counters);
    details.set_contact_counts(cp.counters.contact);
    details.final_time = problem.time(cp.step);
    *first_cap = cp.counters.first_cap;
    details.warnings.push(format!("resumed from the checkpoint of step {}", cp.step));
    write_summary(&opts.out, summary)?;
    write_scene(opts)?;
    Writer::reopen(&opts.out, problem, cp.step)
}

/// The identity a resumed run keeps: the checkpoint's run, which must be the run whose
/// summary.json is in the folder. Read before anything is built, so a folder that cannot be
/// resumed is refused at once.
///
/// The inputs must be the checkpoint's (its fingerprint), with one exception: a later
/// `time.end`, which extends the run (a completed one too: its last step is always
/// checkpointed). That is proved without trusting the folder's scene.toml: the scene it holds
/// must have the checkpoint's fingerprint (so it is the scene the checkpoint was computed
/// from), and that scene with only its `time.end` (and so its number of steps) replaced by the
/// new one must have the new scene's fingerprint (so nothing else differs).
fn resumable(out: &Path, problem: &Problem) -> Result<Checkpoint> {
    let cp = Checkpoint::read(out)?;
    let refuse = |m: String| Error::folder(out, m);
    let summary = Summary::read(out)
        .ok_or_else(|| refuse("summary.json is missing or unreadable: the folder's run cannot be identified, so its checkpoint is not resumed".into()))?;
    let run_id = summary.run.as_ref().map_or("", |d| d.run_id.as_str());
    if run_id != cp.run_id {
        return Err(refuse(format!(
            "checkpoint.json belongs to another run (run {}) than summary.json (run {:?}): the files were not written by one run",
            cp.run_id, run_id
        )));
    }
    let extends = cp.inputs != problem.inputs_fingerprint && extension_of(out, problem, &cp)?;
    if cp.inputs != problem.inputs_fingerprint && !extends {
        return Err(refuse(
            "checkpoint.json was written for other inputs (the scene or a file it reads, such as its mesh, changed since): resume needs the same scene and mesh (only a later time.end may differ)"
                .into(),
        ));
    }
    if summary.status == RunStatus::Completed && !extends {
        return Err(refuse(format!(
            "the run is completed ({} steps): there is nothing to resume (a later time.end extends it: --resume {} --set time.end=T)",
            summary.steps_completed,
            out.display()
        )));
    }
    Ok(cp)
}

/// Whether `problem` is the checkpoint's scene with only a later `time.end` (see
/// [`resumable`]): false when the folder's scene.toml is missing, is not the checkpoint's scene,
/// or differs from `problem` in anything else; Err when the end is not later than the
/// checkpoint's step.
fn extension_of(out: &Path, problem: &Problem, cp: &Checkpoint) -> Result<bool> {
    let Ok(text) = std::fs::read_to_string(out.join("scene.toml")) else { return Ok(false) };
    let Ok(mut old) = crate::scene::Scene::from_toml(&text, "scene.toml").and_then(|s| s.validate()) else {
        return Ok(false);
    };
    if crate::fingerprint::inputs(&old, out).ok().as_deref() != Some(cp.inputs.as_str()) {
        return Ok(false);
    }
    old.time.end = problem.model.time.end;
    old.time.steps = problem.model.time.steps;
    if crate::fingerprint::inputs(&old, out).ok().as_deref() != Some(problem.inputs_fingerprint.as_str()) {
        return Ok(false);
    }
    if problem.steps <= cp.step {
        return Err(Error::folder(
            out,
            format!(
                "time.end = {} is not later than the checkpoint's step {} (t = {}): a resumed run goes on from it",
                problem.model.time.end,
                cp.step,
                problem.time(cp.step)
            ),
        ));
    }
    Ok(true)
}

fn progress_bar(opts: &RunOptions, steps: usize, at: usize) -> Option<indicatif::ProgressBar> {
    opts.progress.then(|| {
        let b = indicatif::ProgressBar::new(steps as u64);
        if let Ok(style) =
            indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} steps  {elapsed_precise} (eta {eta})  {msg}")
        {
            b.set_style(style);
        }
        b.set_position(at as u64);
        b
    })
}

/// summary.json, atomically (through a temporary file and a rename).
fn write_summary(out: &Path, summary: &Summary) -> Result<()> {
    write_atomic(&out.join("summary.json"), summary.to_json()?.as_bytes())
}

/// How the loop ended when it did not complete.
enum Stop {
    Interrupted { step: usize, time: f64 },
    Failed(Error),
}

/// As [`run`] with explicit solver settings.
pub fn run_with(problem: &Problem, settings: Settings, opts: &RunOptions) -> Result<Summary> {
    let lock = folder::lock_run(&opts.out)?;
    run_locked(problem, settings, opts, lock)
}

/// As [`run_with`] in a folder whose lock (`folder::lock_run(&opts.out)`) the caller already
/// holds: a sweep's point is cleared and run under one lock, so no other process can take the
/// folder between the two.
pub(crate) fn run_locked(
    problem: &Problem,
    settings: Settings,
    opts: &RunOptions,
    lock: folder::Lock,
) -> Result<Summary> {
    let start = Instant::now();
    // everything that can refuse the folder, before anything in it changes (a refusal leaves it
    // as it was: no run.lock either)
    let prepared = if opts.resume {
        resumable(&opts.out, problem).map(|cp| (Some(cp), false))
    } else {
        folder::check_fresh(&opts.out).map(|replaced| (None, replaced))
    };
    let (checkpoint, replaced) = match prepared {
        Ok(p) => p,
        Err(e) => {
            lock.discard();
            return Err(e);
        }
    };
    let _lock = lock;
    let mut sim = match Simulation::with_settings(problem, settings) {
        Ok(sim) => sim,
        Err(e) => {
            if !opts.resume {
                write_failed_start(&opts.out, &problem.model.name, &e)?;
            }
            return Err(e);
        }
    };
    let run_id = checkpoint.as_ref().map_or_else(|| new_run_id(&opts.out), |cp| cp.run_id.clone());
    let mut summary = new_summary(problem, &sim, opts, start, run_id);
    let mut first_cap: Option<usize> = None;
    let mut writer = match &checkpoint {
        Some(cp) => start_resumed(problem, &mut sim, opts, cp, &mut summary, &mut first_cap)?,
        None => start_fresh(problem, &sim, opts, &mut summary, replaced)?,
    };
    let bar = progress_bar(opts, problem.steps, sim.state.n);
    let ended = steps_loop(problem, &mut sim, opts, &mut writer, &mut summary, &mut first_cap, bar.as_ref());
    let details = summary.details();
    details.wall_time_s = start.elapsed().as_secs_f64();
    details.timing.total_s = details.wall_time_s;
    details.peak_memory_mb = crate::resources::peak_memory().map(|b| b / 1e6);
    match ended {
        Ok(()) => {
            if let Some(b) = &bar {
                b.finish();
            }
            finish_warnings(problem, summary.details(), first_cap);
            summary.status = RunStatus::Completed;
            match writer.finish(&summary, problem, &sim.state) {
                Ok(()) => Ok(summary),
                // every step is done, but an output is missing (a full disk while the charts
                // were written): summary.json must not say `completed`
                Err(e) => {
                    summary.status = RunStatus::Failed;
                    summary.failure = Some(format!("every step completed, but an output could not be written: {e}"));
                    summary.failure_kind = Some(e.kind());
                    if writer.write_summary(&summary).is_err() {
                        writer.write_summary_in_place(&summary);
                    }
                    Err(e)
                }
            }
        }
        Err(stop) => {
            let e = match stop {
                Stop::Interrupted { step, time } => {
                    summary.status = RunStatus::Interrupted;
                    summary.failure = Some(format!(
                        "stopped after step {step} (t = {time}); checkpoint.json holds that step: continue with --resume {}",
                        opts.out.display()
                    ));
                    Error::Interrupted { step, time }
                }
                Stop::Failed(e) => {
                    summary.status = RunStatus::Failed;
                    summary.failure = Some(e.to_string());
                    e
                }
            };
            summary.failure_kind = Some(e.kind());
            if let Some(b) = &bar {
                b.abandon_with_message(summary.status.as_str());
            }
            // the summary says how the run ended whenever it can be written at all (a full disk)
            let written = if summary.status == RunStatus::Interrupted {
                writer.finish(&summary, problem, &sim.state)
            } else {
                writer.write_summary(&summary)
            };
            if let Err(w) = written {
                writer.write_summary_in_place(&summary);
                if matches!(e, Error::Interrupted { .. }) {
                    return Err(w);
                }
            }
            Err(e)
        }
    }
}

/// The steps of the run, each recorded (and checkpointed when asked); Err when it stops early.
fn steps_loop(
    problem: &Problem,
    sim: &mut Simulation,
    opts: &RunOptions,
    writer: &mut Writer,
    summary: &mut Summary,
    first_cap: &mut Option<usize>,
    bar: Option<&indicatif::ProgressBar>,
) -> std::result::Result<(), Stop> {
    let interrupted = || opts.interrupt.as_ref().is_some_and(|f| f.load(Ordering::SeqCst));
    let stop_now = |n: usize| opts.stop_after.is_some_and(|s| n >= s) || interrupted();
    let checkpoint =
        |sim: &Simulation, summary: &RunDetails, first_cap: Option<usize>, writer: &mut Writer| -> Result<()> {
            // the frames up to this step are on disk before a checkpoint says they are
            writer.wait()?;
            let solver = sim.solver_state();
            let counts = counters(summary, first_cap, sim.delassus_factors.all_counts());
            Checkpoint::new(&summary.run_id, &problem.inputs_fingerprint, &sim.state, counts, solver).write(&opts.out)
        };
    // a signal during the setup stops the run before its first step
    if interrupted() && sim.state.n < problem.steps {
        checkpoint(sim, summary.details(), *first_cap, writer).map_err(Stop::Failed)?;
        return Err(Stop::Interrupted { step: sim.state.n, time: problem.time(sim.state.n) });
    }
    let mut steps = sim.steps();
    while let Some(rec) = steps.next() {
        let rec = rec.map_err(Stop::Failed)?;
        tally(summary, first_cap, &rec);
        summary.details().set_contact_counts(steps.simulation().delassus_factors.all_counts());
        let state = &steps.simulation().state;
        let t_out = Instant::now();
        let last = state.n == problem.steps;
        let stopping = !last && stop_now(state.n);
        writer.record(&rec, problem, state, last).map_err(Stop::Failed)?;
        // the last step always: `--resume DIR` with a later time.end extends a completed run
        let asked = last || opts.checkpoint_every.is_some_and(|c| c > 0 && state.n.is_multiple_of(c));
        if asked || stopping {
            checkpoint(steps.simulation(), summary.details(), *first_cap, writer).map_err(Stop::Failed)?;
        }
        summary.details().timing.output_s += t_out.elapsed().as_secs_f64();
        if let Some(b) = bar {
            b.inc(1);
        }
        if stopping {
            return Err(Stop::Interrupted { step: state.n, time: rec.t });
        }
    }
    Ok(())
}

/// The warnings a completed run adds: (F.1) cap hits, (E.1) guard hits.
fn finish_warnings(problem: &Problem, summary: &mut RunDetails, first_cap: Option<usize>) {
    if summary.fixed_point_cap_hits > 0 {
        summary.warnings.push(format!(
            "the fixed point (F.1) hit max_fixed_point_iterations = {} on {} steps (first at step {}); those steps use the last \
             iterate — raise the cap or use a smaller time.step (beyond (C.k), relaxation < 1 made it worse on the \
             stability map)",
            problem.model.solver.max_fixed_point_iterations,
            summary.fixed_point_cap_hits,
            first_cap.unwrap_or(0)
        ));
    }
    if summary.energy_guard_exceeded_steps > 0 {
        summary.warnings.push(format!(
            "the energy balance (E.1) failed by more than solver.energy_residual_limit = {:e} of the energy scale on {} steps \
             (largest {:.3e}): their equations are not solved to the solvers' tolerance",
            problem.model.solver.energy_residual_limit, summary.energy_guard_exceeded_steps, summary.max_relative_energy_residual
        ));
    }
}
