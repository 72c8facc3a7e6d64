//! The dyncontact command line (the README's contract): `run`, `check`, `sweep` (with `sweep
//! collect` and `sweep point`), `refine`, `study penalty`, and the hidden `export-operators` (the Python
//! cross-check's operators). Thin: it calls the library. The `dyncontact` executable is
//! [`main`] with this process's arguments; the Python package runs the same function
//! (`python -m dyncontact`), so a sweep's Snakefile written from Python runs its points there.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use crate::error::exit;
use crate::failure::RunStatus;
use crate::output::ModelInfo;
use crate::overrides::Override;
use crate::problem::Problem;
use crate::run::{RunOptions, run};
use crate::scene::Scene;
use crate::sweep::collect::PointStatus;
use crate::{Error, resources, study};
use clap::{Parser, Subcommand};
use std::ffi::OsString;

#[derive(Parser)]
#[command(
    name = "dyncontact",
    version,
    about = "Dynamic viscoelastic contact with normal compliance, finite penetration and slip-rate-dependent friction"
)]
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
        #[arg(long, value_name = "N", value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..))]
        checkpoint_every: Option<usize>,
        /// continue the run in DIR from its checkpoint.json: its scene is DIR/scene.toml (the
        /// effective scene the run wrote); `--set time.end=T` with a later T extends the run
        #[arg(long, value_name = "DIR", conflicts_with = "out")]
        resume: Option<PathBuf>,
        /// stop cleanly after step N, writing a checkpoint (batch control, tests)
        #[arg(long, value_name = "N", hide = true)]
        stop_after: Option<usize>,
        /// override a scene key by its dotted path, the value in TOML (repeatable):
        /// --set contact.penalty=1e-5 --set domain.cells=[64,32]
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
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
    /// Run many variants of one scene (a sweep file: axes, [set]) in parallel, each point into
    /// DIR/points/<id>, and collect DIR/sweep.csv and DIR/plots/; also writes DIR/Snakefile and
    /// DIR/config.yaml for running the same points with Snakemake. `sweep collect DIR` gathers
    /// sweep.csv from the point folders (after Snakemake).
    #[command(args_conflicts_with_subcommands = true)]
    Sweep {
        #[command(subcommand)]
        action: Option<SweepAction>,
        /// the sweep file (TOML)
        sweep: Option<PathBuf>,
        /// output folder (default: out/<sweep name>)
        #[arg(long)]
        out: Option<PathBuf>,
        /// points run at once (default: the number of cores)
        #[arg(long, value_name = "N", value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..))]
        jobs: Option<usize>,
        /// validate every point and write the folder (scenes, Snakefile), without running
        #[arg(long)]
        plan_only: bool,
        /// allow --jobs above the number of cores (each point runs on one core)
        #[arg(long)]
        oversubscribe: bool,
        /// override a key of every point, after the sweep's own (repeatable)
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// Solution verification: run the scene on N levels of refinement (domain.cells × R^ℓ and/or
    /// time.step / R^ℓ) as a sweep into DIR, and write DIR/refine.csv (every figure with its
    /// observed order (G.1), Richardson extrapolation (G.2), GCI (G.3) and whether the levels are
    /// in the asymptotic range) and DIR/plots/refine_<figure>.svg. Resumable like a sweep.
    Refine {
        /// scene file (TOML); omitted: the embedded default scene `academic`
        scene: Option<PathBuf>,
        /// number of levels (at least 3; the estimates use the three finest)
        #[arg(long, value_name = "N", default_value_t = crate::sweep::refine::DEFAULT_LEVELS)]
        levels: usize,
        /// refinement ratio between consecutive levels
        #[arg(long, value_name = "R", default_value_t = 2.0)]
        ratio: f64,
        /// what is refined: h (the cells), k (the step) or both together
        #[arg(long, value_enum, default_value = "both")]
        what: crate::sweep::refine::What,
        /// the impulses of the contact force are estimated over the whole run and over this many
        /// equal windows of it (1: the whole run only); it must divide the coarsest level's steps
        /// [default: 4, or 3, 2, 1 when 4 does not divide them]
        #[arg(long, value_name = "W")]
        windows: Option<usize>,
        /// output folder (default: out/<scene name>-refine)
        #[arg(long)]
        out: Option<PathBuf>,
        /// levels run at once (default: the number of cores)
        #[arg(long, value_name = "N", value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..))]
        jobs: Option<usize>,
        /// override a scene key by its dotted path, the value in TOML (repeatable)
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// Validate a scene and print the model it switches on, without solving.
    Check {
        /// scene file (TOML)
        scene: PathBuf,
        /// override a scene key by its dotted path, the value in TOML (repeatable)
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
}

#[derive(Subcommand)]
enum SweepAction {
    /// Gather DIR/sweep.csv and DIR/plots/ from the point folders of the sweep in DIR.
    Collect {
        /// the sweep's output folder
        dir: PathBuf,
    },
    /// Run one point of a sweep folder (DIR/points/<id>) from its scene.toml, as the sweep does
    /// (the Snakefile's rule); writes DIR/points/<id>.done when the outcome is final.
    Point {
        /// the point's folder, DIR/points/<id>
        point: PathBuf,
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
        /// output folder (default: out/<scene name>); files go to its study/ subfolder, the
        /// sweep's runs to study/penalty-sweep/
        #[arg(long)]
        out: Option<PathBuf>,
        /// runs at once (default: the number of cores)
        #[arg(long, value_name = "N", value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..))]
        jobs: Option<usize>,
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

/// The scene (the embedded default when `scene` is None) with the `--set` overrides, the
/// folder relative paths in it are read from, and the effective scene's text (what a run
/// writes to its folder as scene.toml), read by [`crate::scene::parse::load`].
fn load(scene: Option<&Path>, set: &[String]) -> Result<(Scene, PathBuf, String), Error> {
    let overrides = set.iter().map(|a| Override::parse(a)).collect::<Result<Vec<_>, Error>>()?;
    let (text, file, dir) = match scene {
        None => (crate::scene::DEFAULT_SCENE.to_string(), "<embedded academic scene>".to_string(), PathBuf::from(".")),
        Some(p) => (
            std::fs::read_to_string(p).map_err(|e| Error::read(p, e))?,
            p.display().to_string(),
            p.parent().map(Path::to_path_buf).unwrap_or_else(|| PathBuf::from(".")),
        ),
    };
    let (s, effective) = crate::scene::parse::load(&text, &file, &overrides, &dir)?;
    Ok((s, dir, effective))
}

/// SIGINT and SIGTERM as flags: `stop` is set by either (a run or a sweep stops at the end of
/// its step, writes a checkpoint and says so), `term` only by SIGTERM (for the exit code).
/// Installed before anything is read, so a signal during a long setup is not lost.
struct Signals {
    stop: Arc<AtomicBool>,
    term: Arc<AtomicBool>,
}

impl Signals {
    fn install() -> Signals {
        use signal_hook::consts::{SIGINT, SIGTERM};
        let (stop, term) = (Arc::new(AtomicBool::new(false)), Arc::new(AtomicBool::new(false)));
        // a second signal while the step finishes is ignored: the step completes and the files stay valid
        for (sig, flag) in [(SIGINT, &stop), (SIGTERM, &stop), (SIGTERM, &term)] {
            if let Err(e) = signal_hook::flag::register(sig, Arc::clone(flag)) {
                esay!("warning: cannot handle signal {sig} ({e}): it will end the process without a summary");
            }
        }
        Signals { stop, term }
    }
}

/// The command line `args` (the program's name first, as `std::env::args_os` gives it) run to
/// its end: the process's exit code (one of [`exit`]'s). `launcher`: the command a sweep's Snakefile runs
/// `dyncontact` with (None: this executable, [`crate::sweep::snakemake::this_executable`]).
pub fn main(args: impl IntoIterator<Item = OsString>, launcher: Option<&[String]>) -> u8 {
    // faer's default (a rayon pool over every core) costs more than it gains on the small dense
    // Newton matrices of the contact solve and gains nothing on 2 cores for the sparse factor:
    // measured on the academic scene 2.35 s → 1.80 s (contact solve 1.75 s → 1.09 s) with
    // identical outputs, and at 1024×512 cells the factorization 7.0 s → 6.5 s.
    faer::set_global_parallelism(faer::Par::Seq);
    let cli = match Cli::try_parse_from(args) {
        Ok(cli) => cli,
        Err(e) => {
            // --help and --version print to stdout and succeed; a wrong command line is a usage error
            let _ = e.print();
            return if e.use_stderr() { exit::USAGE } else { exit::OK };
        }
    };
    let signals = Signals::install();
    let stop = &signals.stop;
    let launcher = launcher.map(<[String]>::to_vec).unwrap_or_else(crate::sweep::snakemake::this_executable);
    let launcher = launcher.as_slice();
    let result = match &cli.command {
        Command::Run { scene, out, checkpoint_every, resume, stop_after, set } => {
            cmd_run(scene.as_deref(), set, out.as_deref(), *checkpoint_every, resume.as_deref(), *stop_after, stop)
        }
        Command::Study { study: StudyKind::Penalty { scene, eps, out, jobs } } => {
            cmd_penalty(scene.as_deref(), eps.as_deref(), out.as_deref(), *jobs, launcher)
        }
        Command::ExportOperators { scene, out } => load(Some(scene), &[]).and_then(|(s, dir, _)| {
            let problem = Problem::from_scene(&s, &dir)?;
            crate::output::export::export_operators(&problem, out)?;
            say!("operators of {} written to {}", problem.model.name, out.display());
            Ok(())
        }),
        Command::Check { scene, set } => cmd_check(scene, set),
        Command::Refine { scene, levels, ratio, what, windows, out, jobs, set } => {
            let opts =
                crate::sweep::refine::RefineOptions { levels: *levels, ratio: *ratio, what: *what, windows: *windows };
            cmd_refine(scene.as_deref(), &opts, out.as_deref(), *jobs, set, stop, launcher)
        }
        Command::Sweep { action: Some(SweepAction::Collect { dir }), .. } => cmd_collect(dir),
        Command::Sweep { action: Some(SweepAction::Point { point }), .. } => {
            faer::set_global_parallelism(faer::Par::Seq);
            crate::sweep::runner::run_one(point, Some(Arc::clone(stop))).map(|o| say!("{}: {o}", point.display()))
        }
        Command::Sweep { action: None, sweep: Some(file), out, jobs, plan_only, set, oversubscribe } => {
            cmd_sweep(file, out.as_deref(), *jobs, *plan_only, *oversubscribe, set, stop, launcher)
        }
        Command::Sweep { action: None, sweep: None, .. } => {
            Err(Error::scene("sweep", "give a sweep file (dyncontact sweep SWEEP.toml) or `collect DIR`"))
        }
    };
    match result {
        Ok(()) => exit::OK,
        Err(e) => {
            esay!("error: {e}");
            // TOML's quote of the source, with its caret, as the lines it is
            if let Error::SceneSyntax { diagram, .. } = &e
                && !diagram.is_empty()
            {
                esay!("{diagram}");
            }
            let code = e.exit_code();
            if code == exit::INTERRUPTED && signals.term.load(Ordering::SeqCst) { exit::TERMINATED } else { code }
        }
    }
}

/// `dyncontact run`: a run with a progress bar, Ctrl-C as a clean stop, and a one-line report.
fn cmd_run(
    scene: Option<&Path>,
    set: &[String],
    out: Option<&Path>,
    checkpoint_every: Option<usize>,
    resume: Option<&Path>,
    stop_after: Option<usize>,
    stop: &Arc<AtomicBool>,
) -> Result<(), Error> {
    // `--resume DIR` alone continues the run of DIR/scene.toml, the effective scene that run
    // wrote (its overrides applied); a folder from before scene.toml was written needs the scene
    let kept = resume.map(|d| d.join("scene.toml")).filter(|p| scene.is_none() && p.is_file());
    if let Some(d) = resume
        && scene.is_none()
        && kept.is_none()
        && d.is_dir()
    {
        return Err(Error::folder(
            d,
            "holds no scene.toml, the scene its run was computed from: give that scene, `dyncontact run SCENE --resume DIR`",
        ));
    }
    let (s, dir, effective) = load(scene.or(kept.as_deref()), set)?;
    let out = resume.or(out).map(Path::to_path_buf).unwrap_or_else(|| PathBuf::from("out").join(&s.name));
    crate::output::folder::check_target(&out)?;
    let prepared = s.validate().and_then(|model| {
        // refuse before anything large is built
        let estimate = resources::estimate(&model, &dir)?;
        resources::check_fits(&estimate, resources::available_memory())?;
        if resume.is_none() {
            resources::check_disk(&estimate, &out)?;
        }
        // a load that is not finite at a time a step samples it: refused before any output,
        // as `check` refuses it (beyond the scan's budget the step that meets it stops the run)
        let problem = Problem::new(model, &dir)?;
        problem.check_load_times()?;
        Ok(problem)
    });
    let problem = match prepared {
        Ok(p) => p,
        Err(e) => {
            // in a folder that exists (a sweep's point) summary.json says why nothing ran
            if out.is_dir() && resume.is_none() {
                crate::run::write_failed_start(&out, &s.name, &e)?;
            }
            return Err(e);
        }
    };
    let opts = RunOptions {
        out: out.clone(),
        progress: std::io::stdout().is_terminal(),
        checkpoint_every,
        resume: resume.is_some(),
        scene_text: Some(effective),
        origin: crate::run::Origin {
            scene_file: Some(
                scene.or(kept.as_deref()).map_or("<embedded academic scene>".to_string(), |p| p.display().to_string()),
            ),
            overrides: set.to_vec(),
        },
        stop_after,
        interrupt: Some(Arc::clone(stop)),
    };
    let mut summary = run(&problem, &opts)?;
    let (scene, steps) = (summary.scene.clone(), summary.steps_completed);
    let d = summary.details();
    say!(
        "{}: {} steps in {:.2} s, max |(E.1) residual| = {:.3e} ({:.3e} relative), Newton iterations {}, fixed-point iterations {}",
        scene,
        steps,
        d.wall_time_s,
        d.max_abs_energy_residual,
        d.max_relative_energy_residual,
        d.newton_iterations_total,
        d.fixed_point_iterations_total
    );
    for w in &d.warnings {
        esay!("warning: {w}");
    }
    say!("outputs in {}", out.display());
    Ok(())
}

/// `dyncontact study penalty`: the ε → 0 study (a sweep: fixtures/sweeps/penalty.toml on the
/// scene), printed and written under OUT/study.
fn cmd_penalty(
    scene: Option<&Path>,
    eps: Option<&[f64]>,
    out: Option<&Path>,
    jobs: Option<usize>,
    launcher: &[String],
) -> Result<(), Error> {
    let (s, _, _) = load(scene, &[])?;
    let base = match scene {
        None => crate::sweep::Base {
            text: crate::scene::DEFAULT_SCENE.to_string(),
            label: "<embedded academic scene>".into(),
            dir: PathBuf::from("."),
        },
        Some(p) => crate::sweep::Base {
            text: std::fs::read_to_string(p).map_err(|e| Error::read(p, e))?,
            label: p.display().to_string(),
            dir: p.parent().map(Path::to_path_buf).unwrap_or_else(|| PathBuf::from(".")),
        },
    };
    let out = out.map(Path::to_path_buf).unwrap_or_else(|| PathBuf::from("out").join(&s.name));
    let jobs = jobs.unwrap_or_else(|| std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1));
    let work = out.join("study").join("penalty-sweep");
    let st = study::penalty::penalty_study(&base, &[], eps, &work, jobs, launcher)?;
    say!(
        "penalty study of {} (exact reference: {:.2} s; runs in {})",
        s.name,
        st.reference_wall_time_s,
        work.display()
    );
    say!("{:>10} {:>12} {:>12} {:>12} {:>10}", "eps", "e_V", "e_H", "delta", "time [s]");
    for r in &st.rows {
        say!("{:>10.1e} {:>12.4e} {:>12.4e} {:>12.4e} {:>10.2}", r.eps, r.e_v, r.e_h, r.delta, r.wall_time_s);
    }
    say!("log-log slopes: e_V {:.3}, e_H {:.3}, delta {:.3}", st.slope_e_v, st.slope_e_h, st.slope_delta);
    st.write(&out, &format!("{}: P_ε → P as ε → 0", s.name))?;
    say!("written {}", out.join("study").display());
    Ok(())
}

/// `dyncontact sweep`: validate every point, lay the folder out, run the points here (skipping
/// those completed with the same scene), collect sweep.csv and the charts.
#[allow(clippy::too_many_arguments)]
fn cmd_sweep(
    file: &Path,
    out: Option<&Path>,
    jobs: Option<usize>,
    plan_only: bool,
    oversubscribe: bool,
    set: &[String],
    stop: &Arc<AtomicBool>,
    launcher: &[String],
) -> Result<(), Error> {
    use crate::sweep::{Plan, collect, runner};
    let extra = set.iter().map(|a| Override::parse(a)).collect::<Result<Vec<_>, Error>>()?;
    let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    let jobs = jobs.unwrap_or(cores).max(1);
    if jobs > cores && !oversubscribe {
        return Err(Error::scene(
            "--jobs",
            format!(
                "{jobs} points at once on {cores} cores: each point runs on one core, so more would share the cores and multiply the memory; give --oversubscribe to run them anyway"
            ),
        ));
    }
    let plan = Plan::from_file(file, &extra)?;
    let dir = out.map(Path::to_path_buf).unwrap_or_else(|| PathBuf::from("out").join(&plan.name));
    let _lock = crate::sweep::lock(&dir)?;
    let done = plan.write(&dir, launcher)?;
    say!(
        "sweep {}: {} ({} already completed), folder {}",
        plan.name,
        points(plan.points.len()),
        done.iter().filter(|d| **d).count(),
        dir.display()
    );
    if plan_only {
        // points meant for larger machines (a cluster's nodes): laid out, but said
        for e in runner::too_large_here(&plan, &dir) {
            esay!("warning: {e}; it runs only where that much memory is free (config.yaml gives its mem_mb)");
        }
        say!(
            "plan only: every point validated; run them with `dyncontact sweep {}` or with Snakemake in {}",
            file.display(),
            dir.display()
        );
        return Ok(());
    }
    let interrupt = Arc::clone(stop);
    let opts =
        runner::RunnerOptions { jobs, progress: std::io::stdout().is_terminal(), interrupt: Some(interrupt.clone()) };
    let outcomes = runner::run_points(&plan, &dir, &done, &opts)?;
    let (_, rows) = collect::collect(&dir)?;
    report_rows(&rows);
    let failed = outcomes.iter().filter(|o| matches!(o, runner::Outcome::Failed(_))).count();
    if failed > 0 {
        esay!("warning: {failed} of {} points failed (sweep.csv: status and reason)", plan.points.len());
    }
    say!("written {}", dir.join("sweep.csv").display());
    if interrupt.load(Ordering::SeqCst) {
        let finished = rows
            .iter()
            .filter(|r| matches!(r.status, PointStatus::Run(RunStatus::Completed | RunStatus::Failed)))
            .count();
        return Err(Error::SweepInterrupted { finished, total: rows.len() });
    }
    refuse_corrupt(&dir, &rows)
}

/// `dyncontact refine`: the levels as a sweep (validated, laid out, run here skipping those
/// completed with the same scene), then refine.csv and its charts; prints one line per figure.
#[allow(clippy::too_many_arguments)]
fn cmd_refine(
    scene: Option<&Path>,
    opts: &crate::sweep::refine::RefineOptions,
    out: Option<&Path>,
    jobs: Option<usize>,
    set: &[String],
    stop: &Arc<AtomicBool>,
    launcher: &[String],
) -> Result<(), Error> {
    use crate::sweep::{Base, refine, runner};
    let extra = set.iter().map(|a| Override::parse(a)).collect::<Result<Vec<_>, Error>>()?;
    // read as `run` reads it first: its errors name the user's lines
    let (s, _, _) = load(scene, set)?;
    let base = match scene {
        None => Base {
            text: crate::scene::DEFAULT_SCENE.to_string(),
            label: "<embedded academic scene>".into(),
            dir: PathBuf::from("."),
        },
        Some(p) => Base {
            text: std::fs::read_to_string(p).map_err(|e| Error::read(p, e))?,
            label: p.display().to_string(),
            dir: p.parent().map(Path::to_path_buf).unwrap_or_else(|| PathBuf::from(".")),
        },
    };
    let refinement = refine::plan(&base, &extra, &s.name, opts)?;
    let dir = out.map(Path::to_path_buf).unwrap_or_else(|| refine::default_dir(&s.name));
    let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    let jobs = jobs.unwrap_or(cores).max(1);
    let _lock = crate::sweep::lock(&dir)?;
    say!(
        "refine {}: {} levels at ratio {}, refining {}, impulses over the run and {} windows, folder {}",
        s.name,
        opts.levels,
        opts.ratio,
        opts.what.words(),
        refinement.windows,
        dir.display()
    );
    let interrupt = Arc::clone(stop);
    let ropts =
        runner::RunnerOptions { jobs, progress: std::io::stdout().is_terminal(), interrupt: Some(interrupt.clone()) };
    let (outcomes, table) = refinement.run(&dir, &ropts, launcher)?;
    say!("{:<30} {:>10} {:>14} {:>10}  asymptotic", "figure", "order", "extrapolated", "gci");
    let show = |x: Option<f64>, f: &dyn Fn(f64) -> String| x.map(f).unwrap_or_else(|| "-".into());
    for row in &table {
        let e = &row.estimate;
        say!(
            "{:<30} {:>10} {:>14} {:>10}  {}",
            row.figure,
            show(e.order, &|p| format!("{p:.3}")),
            show(e.extrapolated, &|x| format!("{x:.6e}")),
            show(e.gci, &|g| format!("{g:.2e}")),
            e.asymptotic
        );
    }
    let failed = outcomes.iter().filter(|o| matches!(o, runner::Outcome::Failed(_))).count();
    if failed > 0 {
        esay!("warning: {failed} of {} levels failed (sweep.csv: status and reason)", outcomes.len());
    }
    say!("written {}", dir.join("refine.csv").display());
    if interrupt.load(Ordering::SeqCst) {
        let finished =
            outcomes.iter().filter(|o| !matches!(o, runner::Outcome::Interrupted | runner::Outcome::NotRun)).count();
        return Err(Error::SweepInterrupted { finished, total: outcomes.len() });
    }
    let (_, rows) = crate::sweep::collect::rows(&dir)?;
    refuse_corrupt(&dir, &rows)
}

/// `dyncontact sweep collect DIR`: exits 4 when a point's files do not agree (`corrupt` in
/// sweep.csv, with the reason).
fn cmd_collect(dir: &Path) -> Result<(), Error> {
    let _lock = crate::sweep::lock(dir)?;
    let (_, rows) = crate::sweep::collect::collect(dir)?;
    report_rows(&rows);
    say!("written {}", dir.join("sweep.csv").display());
    refuse_corrupt(dir, &rows)
}

/// Err (a folder error) naming the corrupt points, if any.
fn refuse_corrupt(dir: &Path, rows: &[crate::sweep::collect::Row]) -> Result<(), Error> {
    let corrupt: Vec<String> = rows
        .iter()
        .filter(|r| r.status == PointStatus::Corrupt)
        .map(|r| format!("{}: {}", r.point, r.reason))
        .collect();
    if corrupt.is_empty() {
        return Ok(());
    }
    Err(Error::folder(
        dir,
        format!(
            "{} corrupt (sweep.csv says why; no figure of theirs is reported): {}",
            if corrupt.len() == 1 { "1 point is".to_string() } else { format!("{} points are", corrupt.len()) },
            corrupt.join("; ")
        ),
    ))
}

/// "1 point", "2 points".
fn points(n: usize) -> String {
    format!("{n} point{}", if n == 1 { "" } else { "s" })
}

/// The counts of a collected sweep by status.
fn report_rows(rows: &[crate::sweep::collect::Row]) {
    if let Some(line) = crate::sweep::collect::warnings_line(rows) {
        esay!("warning: {line}");
    }
    let count = |s: PointStatus| rows.iter().filter(|r| r.status == s).count();
    say!(
        "{}: {} completed, {} failed, {} interrupted, {} running, {} missing, {} corrupt",
        points(rows.len()),
        count(PointStatus::Run(RunStatus::Completed)),
        count(PointStatus::Run(RunStatus::Failed)),
        count(PointStatus::Run(RunStatus::Interrupted)),
        count(PointStatus::Run(RunStatus::Running)),
        count(PointStatus::Missing),
        count(PointStatus::Corrupt)
    );
}

/// `dyncontact check`: validate, build the problem, and print the model it switches on.
fn cmd_check(scene: &Path, set: &[String]) -> Result<(), Error> {
    let (s, dir, _) = load(Some(scene), set)?;
    let model = s.validate()?;
    let estimate = resources::estimate(&model, &dir)?;
    if let Err(e) = resources::check_fits(&estimate, resources::available_memory()) {
        // too large for this machine: say what it would take without building it
        say!("scene {} is valid", model.name);
        for l in estimate.lines() {
            say!("  {l}");
        }
        for w in &model.warnings {
            esay!("warning: {w}");
        }
        esay!("warning: `run` would refuse it: {e}");
        return Ok(());
    }
    let problem = Problem::new(model, &dir)?;
    let scan = problem.check_load_times()?;
    let info = ModelInfo::of(&problem);
    say!("scene {} is valid", problem.model.name);
    for l in info.lines().into_iter().chain(estimate.lines()) {
        say!("  {l}");
    }
    if let Some(l) = scan.line() {
        say!("  {l}");
    }
    if let Some(w) = scan.warning() {
        esay!("warning: {w}");
    }
    for w in info.warnings() {
        esay!("warning: {w}");
    }
    if let Err(e) = resources::check_disk(&estimate, &PathBuf::from("out").join(&problem.model.name)) {
        esay!("warning: `run` into out/{} would refuse it: {e}", problem.model.name);
    }
    Ok(())
}
