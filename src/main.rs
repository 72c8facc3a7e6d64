//! The dyncontact command line (the README's contract): `run`, `check`, `study`,
//! `export-operators`. Thin: it calls the library.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use clap::{Parser, Subcommand};
use dyncontact::output::ModelInfo;
use dyncontact::problem::Problem;
use dyncontact::run::{run, RunOptions};
use dyncontact::scene::Scene;
use dyncontact::{resources, studies, Error};

#[derive(Parser)]
#[command(name = "dyncontact", version, about = "Dynamic viscoelastic contact with normal compliance, finite penetration and slip-rate-dependent friction")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene (default: the embedded academic scene) and write its outputs.
    Run {
        /// scene file (TOML); omitted: the embedded default scene `academic`
        scene: Option<PathBuf>,
        /// output folder (default: out/<scene name>)
        #[arg(long)]
        out: Option<PathBuf>,
        /// write DIR/checkpoint.json every N steps
        #[arg(long, value_name = "N")]
        checkpoint_every: Option<usize>,
        /// continue the run in DIR from its checkpoint.json (same scene)
        #[arg(long, value_name = "DIR", conflicts_with = "out")]
        resume: Option<PathBuf>,
        /// stop cleanly after step N, writing a checkpoint (batch control, tests)
        #[arg(long, value_name = "N", hide = true)]
        stop_after: Option<usize>,
    },
    /// Studies: `study penalty [SCENE] [--eps LIST]` — the ε → 0 study of Problem P_ε against P.
    Study {
        #[command(subcommand)]
        study: StudyKind,
    },
    /// Write the assembled M, K, C and f(0) of a scene for the Python cross-check.
    #[command(hide = true)]
    ExportOperators {
        scene: PathBuf,
        #[arg(long)]
        out: PathBuf,
    },
    /// Validate a scene and print the model it switches on, without solving.
    Check {
        /// scene file (TOML)
        scene: PathBuf,
    },
}

#[derive(Subcommand)]
enum StudyKind {
    /// Run the exact problem and the penalty problem for each ε on the same mesh and step;
    /// write study/penalty.csv and study/penalty.svg and print the fitted slopes.
    Penalty {
        /// scene file (TOML); omitted: the embedded default scene
        scene: Option<PathBuf>,
        /// comma-separated ε values (default 1e-2,1e-3,1e-4,1e-5,1e-6,1e-7)
        #[arg(long, value_delimiter = ',')]
        eps: Option<Vec<f64>>,
        /// output folder (default: out/<scene name>); files go to its study/ subfolder
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Work–precision benchmark: error against a fine reference vs wall time, for schemes ×
    /// inner solvers × masses × refinement levels; the linear-algebra floor; F.1 vs N.4.
    Bench {
        /// output folder (default: target/bench)
        #[arg(long)]
        out: Option<PathBuf>,
        /// a small configuration (smoke test)
        #[arg(long)]
        quick: bool,
        /// only the floor part (time per step ÷ floor on the default scene; floor.csv)
        #[arg(long)]
        floor_only: bool,
        /// only the bookkeeping part (the (E.1) terms and outputs at 66k unknowns; bookkeeping.csv)
        #[arg(long)]
        bookkeeping_only: bool,
    },
    /// Stability map: sweeps of k, ε, the friction decay, the impact speed and θ per scheme,
    /// each run classified (converged, fixed point failed, Newton failed, energy grew, error).
    Stability {
        /// output folder (default: target/stability)
        #[arg(long)]
        out: Option<PathBuf>,
        /// a small sweep (smoke test)
        #[arg(long)]
        quick: bool,
    },
    /// Where the friction bound is evaluated: the predictor against u_ν^{n+½} of the iterate,
    /// convergence in k for c_ν = 1e3 … 1e8 on the academic scene and the pulled block.
    BoundAt {
        /// output folder (default: target/bound_at)
        #[arg(long)]
        out: Option<PathBuf>,
        /// two compliances and two levels (smoke test)
        #[arg(long)]
        quick: bool,
    },
}

/// println! that never panics: a closed stdout (`dyncontact run | head -1`) is ignored.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

/// eprintln! that never panics on a closed stderr.
macro_rules! esay {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}

fn load(scene: Option<&Path>) -> Result<(Scene, PathBuf), Error> {
    match scene {
        None => Ok((Scene::default_scene(), PathBuf::from("."))),
        Some(p) => {
            let s = Scene::from_file(p)?;
            let dir = p.parent().map(Path::to_path_buf).unwrap_or_else(|| PathBuf::from("."));
            Ok((s, dir))
        }
    }
}

fn main() -> ExitCode {
    // faer's default (a rayon pool over every core) costs more than it gains on the small dense
    // Newton matrices of the contact solve and gains nothing on 2 cores for the sparse factor:
    // measured on the academic scene 2.35 s → 1.80 s (contact solve 1.75 s → 1.09 s) with
    // identical outputs, and at 1024×512 cells the factorization 7.0 s → 6.5 s.
    faer::set_global_parallelism(faer::Par::Seq);
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Run { scene, out, checkpoint_every, resume, stop_after } => {
            cmd_run(scene.as_deref(), out.as_deref(), *checkpoint_every, resume.as_deref(), *stop_after)
        }
        Command::Study { study: StudyKind::Penalty { scene, eps, out } } => cmd_penalty(scene.as_deref(), eps.as_deref(), out.as_deref()),
        Command::Study { study: StudyKind::Bench { out, quick, floor_only, bookkeeping_only } } => {
            let out = out.clone().unwrap_or_else(|| PathBuf::from("target/bench"));
            studies::bench::run(&out, &studies::bench::BenchOptions { quick: *quick, floor_only: *floor_only, bookkeeping_only: *bookkeeping_only }).map(|report| say!("{report}"))
        }
        Command::Study { study: StudyKind::Stability { out, quick } } => {
            let out = out.clone().unwrap_or_else(|| PathBuf::from("target/stability"));
            studies::stability::run(&out, &studies::stability::StabilityOptions { quick: *quick }).map(|report| say!("{report}"))
        }
        Command::Study { study: StudyKind::BoundAt { out, quick } } => {
            let out = out.clone().unwrap_or_else(|| PathBuf::from("target/bound_at"));
            studies::bound_at::run(&out, &studies::bound_at::BoundAtOptions { quick: *quick }).map(|report| say!("{report}"))
        }
        Command::ExportOperators { scene, out } => load(Some(scene)).and_then(|(s, dir)| {
            let problem = Problem::from_scene(&s, &dir)?;
            dyncontact::output::export::export_operators(&problem, out)?;
            say!("operators of {} written to {}", problem.model.name, out.display());
            Ok(())
        }),
        Command::Check { scene } => cmd_check(scene),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            esay!("error: {e}");
            match e {
                Error::Interrupted { .. } => ExitCode::from(130),
                e if e.is_solver_failure() => ExitCode::from(2),
                _ => ExitCode::from(1),
            }
        }
    }
}

/// `dyncontact run`: a run with a progress bar, Ctrl-C as a clean stop, and a one-line report.
fn cmd_run(
    scene: Option<&Path>,
    out: Option<&Path>,
    checkpoint_every: Option<usize>,
    resume: Option<&Path>,
    stop_after: Option<usize>,
) -> Result<(), Error> {
    let (s, dir) = load(scene)?;
    let out = resume.or(out).map(Path::to_path_buf).unwrap_or_else(|| PathBuf::from("out").join(&s.name));
    let model = s.validate()?;
    // refuse before anything large is built
    resources::check_fits(&resources::estimate(&model, &dir)?, resources::available_memory())?;
    let problem = Problem::new(model, &dir)?;
    let interrupt = Arc::new(AtomicBool::new(false));
    let flag = interrupt.clone();
    // a second Ctrl-C while the step finishes is ignored: the step completes and the files stay valid
    let _ = ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst));
    let opts = RunOptions {
        out: out.clone(),
        progress: std::io::stdout().is_terminal(),
        checkpoint_every,
        resume: resume.is_some(),
        stop_after,
        interrupt: Some(interrupt),
    };
    let summary = run(&problem, &opts)?;
    say!(
        "{}: {} steps in {:.2} s, max |(E.1) residual| = {:.3e} ({:.3e} relative), Newton iterations {}, fixed-point iterations {}",
        summary.scene,
        summary.steps_completed,
        summary.wall_time_s,
        summary.max_abs_energy_residual,
        summary.max_relative_energy_residual,
        summary.newton_iterations_total,
        summary.fixed_point_iterations_total
    );
    for w in &summary.warnings {
        esay!("warning: {w}");
    }
    say!("outputs in {}", out.display());
    Ok(())
}

/// `dyncontact study penalty`: the ε → 0 study, printed and written under OUT/study.
fn cmd_penalty(scene: Option<&Path>, eps: Option<&[f64]>, out: Option<&Path>) -> Result<(), Error> {
    let (s, dir) = load(scene)?;
    let out = out.map(Path::to_path_buf).unwrap_or_else(|| PathBuf::from("out").join(&s.name));
    let eps = eps.map(<[f64]>::to_vec).unwrap_or_else(|| studies::penalty::DEFAULT_EPS.to_vec());
    let st = studies::penalty::penalty_study(&s, &dir, &eps)?;
    say!("penalty study of {} (exact reference: {:.2} s)", s.name, st.reference_wall_time_s);
    say!("{:>10} {:>12} {:>12} {:>12} {:>10}", "eps", "e_V", "e_H", "delta", "time [s]");
    for r in &st.rows {
        say!("{:>10.1e} {:>12.4e} {:>12.4e} {:>12.4e} {:>10.2}", r.eps, r.e_v, r.e_h, r.delta, r.wall_time_s);
    }
    say!("log-log slopes: e_V {:.3}, e_H {:.3}, delta {:.3}", st.slope_e_v, st.slope_e_h, st.slope_delta);
    st.write(&out, &format!("{}: P_ε → P as ε → 0", s.name))?;
    say!("written {}", out.join("study").display());
    Ok(())
}

/// `dyncontact check`: validate, build the problem, and print the model it switches on.
fn cmd_check(scene: &Path) -> Result<(), Error> {
    let (s, dir) = load(Some(scene))?;
    let model = s.validate()?;
    let estimate = resources::estimate(&model, &dir)?;
    if let Err(e) = resources::check_fits(&estimate, resources::available_memory()) {
        // too large for this machine: say what it would take without building it
        say!("scene {} is valid", model.name);
        for l in estimate.lines() {
            say!("  {l}");
        }
        esay!("warning: `run` would refuse it: {e}");
        return Ok(());
    }
    let problem = Problem::new(model, &dir)?;
    let info = ModelInfo::of(&problem);
    say!("scene {} is valid", problem.model.name);
    for l in info.lines().into_iter().chain(estimate.lines()) {
        say!("  {l}");
    }
    for w in info.warnings() {
        esay!("warning: {w}");
    }
    Ok(())
}
