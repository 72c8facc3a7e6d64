//! `dyncontact run`: the time loop with outputs, progress and a summary that says how it ended.

use std::path::PathBuf;
use std::time::Instant;

use crate::error::Result;
use crate::output::summary::Timing;
use crate::output::{ModelInfo, Summary, Writer};
use crate::problem::Problem;
use crate::simulation::{Settings, Simulation};

/// Options of a run.
#[derive(Debug, Clone)]
pub struct RunOptions {
    pub out: PathBuf,
    /// show a progress bar (only on a terminal)
    pub progress: bool,
}

/// Run a problem to its end time, writing every output. On a solver failure the files written
/// so far stay valid, summary.json says `"status": "failed"` and why, and the error is returned.
pub fn run(problem: &Problem, opts: &RunOptions) -> Result<Summary> {
    run_with(problem, Settings::from_problem(problem), opts)
}

/// As [`run`] with explicit solver settings.
pub fn run_with(problem: &Problem, settings: Settings, opts: &RunOptions) -> Result<Summary> {
    let start = Instant::now();
    let mut sim = Simulation::with_settings(problem, settings)?;
    let [assembly_s, factorization_s, delassus_s] = sim.setup_timing;
    let info = ModelInfo::of(problem);
    let mut summary = Summary {
        scene: problem.scene.name.clone(),
        description: problem.scene.description.clone(),
        status: "running".into(),
        failure: None,
        model: info.clone(),
        steps_completed: 0,
        final_time: 0.0,
        wall_time_s: 0.0,
        timing: Timing { setup_s: start.elapsed().as_secs_f64(), assembly_s, factorization_s, delassus_s, ..Timing::default() },
        newton_iterations_total: 0,
        fixed_point_iterations_total: 0,
        fixed_point_iterations_max: 0,
        fixed_point_cap_hits: 0,
        max_abs_energy_residual: 0.0,
        max_relative_energy_residual: 0.0,
        warnings: info.ck_warning().into_iter().collect(),
    };
    let mut writer = Writer::create(&opts.out, &sim)?;
    let t_out = Instant::now();
    writer.record(&sim.initial_record(), &sim, problem.steps == 0)?;
    summary.timing.output_s += t_out.elapsed().as_secs_f64();
    let bar = opts.progress.then(|| {
        let b = indicatif::ProgressBar::new(problem.steps as u64);
        if let Ok(style) = indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} steps  {elapsed_precise} (eta {eta})  {msg}") {
            b.set_style(style);
        }
        b
    });
    let mut first_cap: Option<usize> = None;
    for n in 0..problem.steps {
        let rec = match sim.step() {
            Ok(r) => r,
            Err(e) => {
                summary.status = "failed".into();
                summary.failure = Some(e.to_string());
                summary.wall_time_s = start.elapsed().as_secs_f64();
                summary.timing.total_s = summary.wall_time_s;
                writer.write_summary(&summary)?;
                if let Some(b) = &bar {
                    b.abandon_with_message("failed");
                }
                return Err(e);
            }
        };
        let [tf, tc, tr] = sim.timing;
        summary.timing.free_solve_s += tf;
        summary.timing.contact_solve_s += tc;
        summary.timing.recovery_s += tr;
        let r = &rec.report;
        summary.newton_iterations_total += r.inner_iterations;
        summary.fixed_point_iterations_total += r.fixed_point_iterations;
        summary.fixed_point_iterations_max = summary.fixed_point_iterations_max.max(r.fixed_point_iterations);
        if !r.fixed_point_converged {
            summary.fixed_point_cap_hits += 1;
            first_cap.get_or_insert(rec.step);
        }
        let res = rec.energy.residual.abs();
        summary.max_abs_energy_residual = summary.max_abs_energy_residual.max(res);
        if rec.energy_scale > 0.0 {
            summary.max_relative_energy_residual = summary.max_relative_energy_residual.max(res / rec.energy_scale);
        }
        summary.steps_completed = rec.step;
        summary.final_time = rec.t;
        let t_out = Instant::now();
        writer.record(&rec, &sim, n + 1 == problem.steps)?;
        summary.timing.output_s += t_out.elapsed().as_secs_f64();
        if let Some(b) = &bar {
            b.inc(1);
        }
    }
    if let Some(b) = &bar {
        b.finish();
    }
    if summary.fixed_point_cap_hits > 0 {
        summary.warnings.push(format!(
            "the fixed point (F.1) hit max_fixed_point_iterations = {} on {} steps (first at step {}); those steps use the last \
             iterate — raise the cap, use relaxation < 1 or a smaller time.step",
            problem.scene.solver.max_fixed_point_iterations,
            summary.fixed_point_cap_hits,
            first_cap.unwrap_or(0)
        ));
    }
    summary.status = "completed".into();
    summary.wall_time_s = start.elapsed().as_secs_f64();
    summary.timing.total_s = summary.wall_time_s;
    writer.finish(&summary, &sim)?;
    Ok(summary)
}
