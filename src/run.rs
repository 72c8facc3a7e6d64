//! `dyncontact run`: the time loop with outputs, progress, checkpoints, interruption, and a
//! summary that says how the run ended.
//!
//! However it ends, the folder stays valid: history.csv holds every completed step,
//! series.pvd lists exactly the frames on disk, and summary.json says `completed`, `failed`
//! (with the step, time, residuals and a suggestion) or `interrupted` (with where it stopped;
//! a checkpoint of that step is written so `--resume` continues from it).

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

use crate::checkpoint::{fingerprint, Checkpoint, Counters};
use crate::error::{Error, Result};
use crate::failure::RunStatus;
use crate::output::summary::Timing;
use crate::output::{ModelInfo, Summary, Writer};
use crate::problem::Problem;
use crate::simulation::{Settings, Simulation, StepRecord};

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
    /// stop cleanly (as if interrupted) after this step — for tests and batch control
    pub stop_after: Option<usize>,
    /// set by a signal handler to stop cleanly at the end of the current step
    pub interrupt: Option<Arc<AtomicBool>>,
}

/// Run a problem to its end time, writing every output. On a solver failure the files written
/// so far stay valid, summary.json says `"status": "failed"` and why, and the error is returned.
pub fn run(problem: &Problem, opts: &RunOptions) -> Result<Summary> {
    run_with(problem, Settings::from_problem(problem), opts)
}

/// summary.json of a run that could not start — its scene, mesh or operators were refused —
/// in an output folder that exists (a sweep's point folder): `"status": "failed"` with the
/// reason and its kind, so every point of a sweep is read the same way.
pub fn write_failed_start(out: &std::path::Path, scene: &str, e: &Error) -> Result<()> {
    let json = serde_json::json!({
        "scene": scene,
        "status": "failed",
        "failure": e.to_string(),
        "failure_kind": e.kind(),
        "steps_completed": 0,
    });
    let text = serde_json::to_string_pretty(&json).map_err(|e| Error::Output(format!("summary.json: {e}")))?;
    crate::output::write_atomic(&out.join("summary.json"), text.as_bytes())
}

/// The run's counters in the form a checkpoint stores.
fn counters(s: &Summary, first_cap: Option<usize>) -> Counters {
    Counters {
        newton_iterations_total: s.newton_iterations_total,
        fixed_point_iterations_total: s.fixed_point_iterations_total,
        fixed_point_iterations_max: s.fixed_point_iterations_max,
        fixed_point_cap_hits: s.fixed_point_cap_hits,
        unfrozen_fallbacks: s.unfrozen_fallbacks,
        first_cap,
        max_abs_energy_residual: s.max_abs_energy_residual.to_bits(),
        max_relative_energy_residual: s.max_relative_energy_residual.to_bits(),
    }
}

/// The summary's counters continued from a checkpoint.
fn restore_counters(summary: &mut Summary, c: &Counters) {
    summary.newton_iterations_total = c.newton_iterations_total;
    summary.fixed_point_iterations_total = c.fixed_point_iterations_total;
    summary.fixed_point_iterations_max = c.fixed_point_iterations_max;
    summary.fixed_point_cap_hits = c.fixed_point_cap_hits;
    summary.unfrozen_fallbacks = c.unfrozen_fallbacks;
    summary.max_abs_energy_residual = f64::from_bits(c.max_abs_energy_residual);
    summary.max_relative_energy_residual = f64::from_bits(c.max_relative_energy_residual);
}

/// Add one step's iterations, timings and (E.1) residual to the summary.
fn tally(summary: &mut Summary, first_cap: &mut Option<usize>, rec: &StepRecord) {
    let r = &rec.report;
    summary.newton_iterations_total += r.inner_iterations;
    summary.fixed_point_iterations_total += r.fixed_point_iterations;
    summary.fixed_point_iterations_max = summary.fixed_point_iterations_max.max(r.fixed_point_iterations);
    if !r.fixed_point_converged() {
        summary.fixed_point_cap_hits += 1;
        first_cap.get_or_insert(rec.step);
    }
    summary.unfrozen_fallbacks += usize::from(r.fallback.is_some());
    let res = rec.energy.residual.abs();
    summary.max_abs_energy_residual = summary.max_abs_energy_residual.max(res);
    if rec.energy_scale > 0.0 {
        summary.max_relative_energy_residual = summary.max_relative_energy_residual.max(res / rec.energy_scale);
    }
    summary.steps_completed = rec.step;
    summary.final_time = rec.t;
    summary.timing.free_solve_s += rec.timing.free_solve;
    summary.timing.contact_solve_s += rec.timing.contact_solve;
    summary.timing.recovery_s += rec.timing.recovery;
    summary.timing.products_s += rec.timing.products;
    summary.timing.balance_s += rec.timing.balance;
}

/// The summary of a run that is starting.
fn new_summary(problem: &Problem, sim: &Simulation, start: Instant) -> Summary {
    let info = ModelInfo::of(problem);
    let t = sim.setup_timing;
    Summary {
        scene: problem.model.name.clone(),
        description: problem.model.description.clone(),
        status: RunStatus::Running,
        failure: None,
        failure_kind: None,
        warnings: info.warnings(),
        model: info,
        steps_completed: 0,
        final_time: 0.0,
        wall_time_s: 0.0,
        timing: Timing {
            setup_s: start.elapsed().as_secs_f64(),
            assembly_s: t.assembly,
            factorization_s: t.factorization,
            delassus_s: t.delassus,
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
    }
}

/// Where the run writes: a new folder, or the folder of a checkpoint to resume (the state and
/// the counters are restored from it).
fn open_writer(
    problem: &Problem,
    sim: &mut Simulation,
    opts: &RunOptions,
    scene_hash: &str,
    summary: &mut Summary,
    first_cap: &mut Option<usize>,
) -> Result<Writer> {
    if !opts.resume {
        let mut w = Writer::create(&opts.out, problem)?;
        w.record(&sim.initial_record(), problem, &sim.state, problem.steps == 0)?;
        return Ok(w);
    }
    let cp = Checkpoint::read(&opts.out)?;
    if cp.scene_hash != scene_hash {
        return Err(Error::Output(format!(
            "{}: the checkpoint was written for a different scene (or another version of it); resume needs the same scene",
            opts.out.join("checkpoint.json").display()
        )));
    }
    sim.restore(cp.state())?;
    if let (Some(key), Some(w)) = (&cp.factor, sim.delassus.as_ref()) {
        sim.delassus_factors.restore(w, key).ok_or_else(|| {
            Error::Output(format!("{}: the checkpoint's contact factorization does not fit this scene", opts.out.join("checkpoint.json").display()))
        })?;
    }
    restore_counters(summary, &cp.counters);
    summary.steps_completed = cp.step;
    summary.final_time = problem.time(cp.step);
    *first_cap = cp.counters.first_cap;
    summary.warnings.push(format!("resumed from the checkpoint of step {}", cp.step));
    Writer::reopen(&opts.out, problem, cp.step)
}

fn progress_bar(opts: &RunOptions, steps: usize, at: usize) -> Option<indicatif::ProgressBar> {
    opts.progress.then(|| {
        let b = indicatif::ProgressBar::new(steps as u64);
        if let Ok(style) = indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} steps  {elapsed_precise} (eta {eta})  {msg}") {
            b.set_style(style);
        }
        b.set_position(at as u64);
        b
    })
}

/// As [`run`] with explicit solver settings.
pub fn run_with(problem: &Problem, settings: Settings, opts: &RunOptions) -> Result<Summary> {
    let start = Instant::now();
    let scene_hash = fingerprint(&format!("{:?}", problem.model));
    let mut sim = match Simulation::with_settings(problem, settings) {
        Ok(sim) => sim,
        Err(e) => {
            if opts.out.is_dir() && !opts.resume {
                write_failed_start(&opts.out, &problem.model.name, &e)?;
            }
            return Err(e);
        }
    };
    let mut summary = new_summary(problem, &sim, start);
    let mut first_cap: Option<usize> = None;
    let mut writer = open_writer(problem, &mut sim, opts, &scene_hash, &mut summary, &mut first_cap)?;
    let bar = progress_bar(opts, problem.steps, sim.state.n);
    let stop_now =
        |n: usize| opts.stop_after.is_some_and(|s| n >= s) || opts.interrupt.as_ref().is_some_and(|f| f.load(Ordering::SeqCst));
    let finish_timing = |summary: &mut Summary| {
        summary.wall_time_s = start.elapsed().as_secs_f64();
        summary.timing.total_s = summary.wall_time_s;
    };
    let mut steps = sim.steps();
    while let Some(rec) = steps.next() {
        let rec = match rec {
            Ok(r) => r,
            Err(e) => {
                summary.status = RunStatus::Failed;
                summary.failure = Some(e.to_string());
                summary.failure_kind = Some(e.kind().to_string());
                finish_timing(&mut summary);
                writer.write_summary(&summary)?;
                if let Some(b) = &bar {
                    b.abandon_with_message("failed");
                }
                return Err(e);
            }
        };
        tally(&mut summary, &mut first_cap, &rec);
        let counts = steps.simulation().delassus_factors.all_counts();
        (summary.contact_factorizations, summary.contact_factor_reuses) = (counts.factorizations, counts.reuses);
        (summary.contact_pcg_solves, summary.contact_pcg_iterations) = (counts.pcg_solves, counts.pcg_iterations);
        (summary.contact_velocity_solves, summary.contact_velocity_iterations) = (counts.velocity_solves, counts.velocity_iterations);
        let state = &steps.simulation().state;
        let t_out = Instant::now();
        let last = state.n == problem.steps;
        let stopping = !last && stop_now(state.n);
        writer.record(&rec, problem, state, last)?;
        if opts.checkpoint_every.is_some_and(|c| c > 0 && state.n % c == 0) || stopping {
            let factor = steps.simulation().delassus_factors.key();
            Checkpoint::new(scene_hash.clone(), state, counters(&summary, first_cap), factor).write(&opts.out)?;
        }
        summary.timing.output_s += t_out.elapsed().as_secs_f64();
        if let Some(b) = &bar {
            b.inc(1);
        }
        if stopping {
            summary.status = RunStatus::Interrupted;
            summary.failure_kind = Some("interrupted".to_string());
            summary.failure = Some(format!(
                "stopped after step {} (t = {}); checkpoint.json holds that step: continue with --resume {}",
                state.n,
                rec.t,
                opts.out.display()
            ));
            finish_timing(&mut summary);
            writer.finish(&summary, problem, state)?;
            if let Some(b) = &bar {
                b.abandon_with_message("interrupted");
            }
            return Err(Error::Interrupted { step: state.n, time: rec.t });
        }
    }
    if let Some(b) = &bar {
        b.finish();
    }
    if summary.fixed_point_cap_hits > 0 {
        summary.warnings.push(format!(
            "the fixed point (F.1) hit max_fixed_point_iterations = {} on {} steps (first at step {}); those steps use the last \
             iterate — raise the cap, use relaxation < 1 or a smaller time.step",
            problem.model.solver.max_fixed_point_iterations,
            summary.fixed_point_cap_hits,
            first_cap.unwrap_or(0)
        ));
    }
    summary.status = RunStatus::Completed;
    finish_timing(&mut summary);
    writer.finish(&summary, problem, &sim.state)?;
    Ok(summary)
}
