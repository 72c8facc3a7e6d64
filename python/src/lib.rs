//! `dyncontact._dyncontact`: the PyO3 module under the Python package `dyncontact`
//! (python/dyncontact/__init__.py is the thin Python layer: results as numpy arrays and meshio
//! meshes). Everything here calls the library the command line calls, so results are the CLI's
//! bit for bit; the GIL is released while the solver runs.

mod collect;
mod errors;
mod interrupt;
mod scene;
mod simulation;
mod values;

use std::path::{Path, PathBuf};

use dyncontact::mesh::Geometry;
use dyncontact::output::HISTORY;
use dyncontact::problem::Problem;
use dyncontact::run::{Origin, RunOptions};
use dyncontact::sweep::collect::PointStatus;
use dyncontact::{Error, sweep};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::collect::{Collected, ContactColumn};
use crate::errors::{py_result, to_py};
use crate::interrupt::interruptible;
use crate::scene::PyScene;

/// Where a run's scene came from, for summary.json (the CLI's `scene_file`, `overrides`).
fn origin(scene: &PyScene) -> Origin {
    Origin { scene_file: Some(scene.file.clone()), overrides: scene.overrides.clone() }
}

/// The command a sweep's Snakefile runs `dyncontact` with when the sweep is written from Python:
/// this interpreter with `-m dyncontact` (python/dyncontact/__main__.py, the command line of
/// [`dyncontact::cli`]). This process's executable would be the interpreter itself, and
/// `python sweep point …` is not a command; without a known interpreter, `dyncontact` on the
/// PATH (the package's console script).
fn launcher(py: Python<'_>) -> Vec<String> {
    let executable = py
        .import("sys")
        .and_then(|sys| sys.getattr("executable"))
        .and_then(|e| e.extract::<String>())
        .unwrap_or_default();
    if executable.is_empty() {
        vec!["dyncontact".to_string()]
    } else {
        vec![executable, "-m".to_string(), "dyncontact".to_string()]
    }
}

/// The command line: `python -m dyncontact ARGS…` and the `dyncontact` console script run
/// `cli_main(["dyncontact", *ARGS])` — the CLI's own code (its signal handling included), the
/// GIL released; returns the exit code — 101 for a panic, as the executable exits (the panic's
/// message is printed as there), not a Python exception. For `__main__` only: the CLI's signal
/// handlers stay installed after it returns.
#[pyfunction]
fn cli_main(py: Python<'_>, argv: Vec<std::ffi::OsString>) -> u8 {
    const PANICKED: u8 = 101;
    let launcher = launcher(py);
    py.detach(|| {
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| dyncontact::cli::main(argv, Some(&launcher))))
            .unwrap_or(PANICKED)
    })
}

/// An (n, d) float64 array of the first `d` components of 3-vectors.
pub fn vectors<'py>(py: Python<'py>, x: &[[f64; 3]], d: usize) -> Bound<'py, PyAny> {
    let flat: Vec<f64> = x.iter().flat_map(|p| p[..d].iter().copied()).collect();
    Array2::from_shape_vec((x.len(), d), flat).expect("n × d values").into_pyarray(py).into_any()
}

/// The reference mesh: {"points": (n, 3) float64, "cell_type": "triangle" | "tetra",
/// "cells": (cells, 3 | 4) int64, "dimension": d}.
fn mesh<'py>(py: Python<'py>, problem: &Problem) -> PyResult<Bound<'py, PyDict>> {
    let m = &problem.mesh;
    let points: Vec<[f64; 3]> = (0..m.n_nodes()).map(|i| m.point(i)).collect();
    let (kind, k, cells): (&str, usize, Vec<i64>) = match m {
        Geometry::Plane(g) => ("triangle", 3, g.cells.iter().flatten().map(|&i| i as i64).collect()),
        Geometry::Solid(g) => ("tetra", 4, g.cells.iter().flatten().map(|&i| i as i64).collect()),
    };
    let d = PyDict::new(py);
    d.set_item("points", vectors(py, &points, 3))?;
    d.set_item("cell_type", kind)?;
    d.set_item("cells", Array2::from_shape_vec((cells.len() / k, k), cells).expect("cells").into_pyarray(py))?;
    d.set_item("dimension", m.dim())?;
    Ok(d)
}

/// The history.csv column names, in order.
#[pyfunction]
fn history_columns() -> Vec<&'static str> {
    HISTORY.iter().map(|(name, _)| *name).collect()
}

/// Raise what stopped a run: a KeyboardInterrupt from the signal handlers as the library's
/// interruption (its message says where the run stopped), any other exception a handler raised
/// (a user's SIGALRM handler's TimeoutError) as it is, else the run's error.
fn outcome<T>(py: Python<'_>, r: dyncontact::Result<T>, signal: Option<PyErr>) -> PyResult<T> {
    let keyboard = signal.as_ref().is_none_or(|s| s.is_instance_of::<pyo3::exceptions::PyKeyboardInterrupt>(py));
    match (r, signal) {
        (Err(e @ (Error::Interrupted { .. } | Error::SweepInterrupted { .. })), _) if keyboard => Err(to_py(py, &e)),
        (_, Some(sig)) => Err(sig),
        (r, None) => py_result(py, r),
    }
}

/// Run `scene` writing nothing. Returns {"history": {column: float64 array}, "contact":
/// {column: array}, "summary": JSON text, "frames": [{"step", "t", fields...}], "mesh": ...}.
#[pyfunction]
#[pyo3(signature = (scene, progress = false))]
fn run_memory<'py>(py: Python<'py>, scene: &PyScene, progress: bool) -> PyResult<Bound<'py, PyDict>> {
    let (result, signal) = interruptible(py, |flag| {
        let problem = scene.problem(None)?;
        let mut collected = Collected::new(&problem);
        let bar = progress.then(|| indicatif::ProgressBar::new(problem.steps as u64));
        let summary = dyncontact::run::run_in_memory(&problem, &origin(scene), Some(&flag), |rec, sim| {
            collected.record(rec, &problem, &sim.state);
            if let Some(b) = &bar {
                b.set_position(rec.step as u64);
            }
        });
        if let Some(b) = &bar {
            b.finish_and_clear();
        }
        let json = summary.and_then(|s| s.to_json());
        json.map(|j| (problem, collected, j))
    })?;
    // nothing was written: the library's message would point at outputs and a checkpoint
    if let Err(Error::Interrupted { step, time }) = &result
        && signal.as_ref().is_none_or(|s| s.is_instance_of::<pyo3::exceptions::PyKeyboardInterrupt>(py))
    {
        return Err(pyo3::exceptions::PyKeyboardInterrupt::new_err(format!(
            "interrupted after step {step} (t = {time}); nothing was written (out=None)"
        )));
    }
    let (problem, collected, json) = outcome(py, result, signal)?;
    let out = PyDict::new(py);
    let history = PyDict::new(py);
    for ((name, _), col) in HISTORY.iter().zip(collected.history) {
        history.set_item(*name, PyArray1::from_vec(py, col))?;
    }
    out.set_item("history", history)?;
    let contact = PyDict::new(py);
    let has_contact = problem.contact.is_some();
    for (name, col) in collected.contact {
        match col {
            ContactColumn::Numbers(x) => contact.set_item(name, PyArray1::from_vec(py, x))?,
            ContactColumn::Statuses(s) => contact.set_item(name, PyList::new(py, s)?)?,
        }
    }
    out.set_item("contact", contact)?;
    out.set_item("has_contact", has_contact)?;
    out.set_item("summary", json)?;
    let dim = problem.mesh.dim();
    let frames = PyList::empty(py);
    for f in collected.frames {
        let d = PyDict::new(py);
        d.set_item("step", f.step)?;
        d.set_item("t", f.t)?;
        d.set_item("u", vectors(py, &f.u, dim))?;
        d.set_item("v", vectors(py, &f.v, dim))?;
        let c = &f.contact;
        d.set_item("contact_pressure", PyArray1::from_iter(py, c.iter().map(|n| n.pressure)))?;
        d.set_item("compliance_pressure", PyArray1::from_iter(py, c.iter().map(|n| n.q)))?;
        d.set_item("lambda", PyArray1::from_iter(py, c.iter().map(|n| n.lambda)))?;
        let friction: Vec<[f64; 3]> = c.iter().map(|n| n.friction).collect();
        d.set_item("friction", vectors(py, &friction, dim))?;
        d.set_item("contact_status", PyArray1::from_iter(py, c.iter().map(|n| n.status)))?;
        let nc = f.stress.len() / 6;
        d.set_item("stress", Array2::from_shape_vec((nc, 6), f.stress).expect("6 per cell").into_pyarray(py))?;
        frames.append(d)?;
    }
    out.set_item("frames", frames)?;
    out.set_item("mesh", mesh(py, &problem)?)?;
    Ok(out)
}

/// Run `scene` into the folder `out` as `dyncontact run SCENE --out OUT` does (history.csv,
/// contact.csv, frames, summary.json, charts, scene.toml; a checkpoint when stopped), or with
/// `resume` continue the run in `out` from its checkpoint as `dyncontact run --resume OUT`
/// does; `stop_after` is the CLI's hidden `--stop-after N` (tests). Returns {"mesh": ...}; the
/// Python layer reads the files.
#[pyfunction]
#[pyo3(signature = (scene, out, progress = false, checkpoint_every = None, resume = false, stop_after = None))]
fn run_folder<'py>(
    py: Python<'py>,
    scene: &PyScene,
    out: PathBuf,
    progress: bool,
    checkpoint_every: Option<usize>,
    resume: bool,
    stop_after: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let (result, signal) = interruptible(py, |flag| {
        let problem = match scene.problem((!resume).then_some(out.as_path())) {
            Ok(p) => p,
            Err(e) => {
                // in a folder that exists (a sweep's point) summary.json says why nothing ran
                if out.is_dir() && !resume {
                    dyncontact::run::write_failed_start(&out, &scene.name, &e)?;
                }
                return Err(e);
            }
        };
        let opts = RunOptions {
            out: out.clone(),
            progress,
            checkpoint_every,
            resume,
            scene_text: Some(scene.effective.clone()),
            origin: origin(scene),
            stop_after,
            interrupt: Some(flag),
        };
        dyncontact::run::run(&problem, &opts).map(|_| problem)
    })?;
    let problem = outcome(py, result, signal)?;
    let d = PyDict::new(py);
    d.set_item("mesh", mesh(py, &problem)?)?;
    Ok(d)
}

/// Run a sweep as `dyncontact sweep SWEEP --out OUT --jobs N` does; returns the path of
/// sweep.csv. `sweep` is a sweep file's path or a dict of its tables (its `base` read from the
/// current folder); `set` holds overrides of every point (as `--set`).
#[pyfunction]
#[pyo3(signature = (sweep, out = None, jobs = None, set = None, plan_only = false, oversubscribe = false, progress = false))]
#[allow(clippy::too_many_arguments)]
fn run_sweep(
    py: Python<'_>,
    sweep: &Bound<'_, PyAny>,
    out: Option<PathBuf>,
    jobs: Option<usize>,
    set: Option<&Bound<'_, PyAny>>,
    plan_only: bool,
    oversubscribe: bool,
    progress: bool,
) -> PyResult<PathBuf> {
    let args = match set {
        Some(s) => values::set_arguments(s)?,
        None => Vec::new(),
    };
    let extra = py_result(py, values::overrides(&args))?;
    let plan = if let Ok(d) = sweep.cast::<PyDict>() {
        let text = toml::to_string(&values::table(d, "")?)
            .map_err(|e| pyo3::exceptions::PyValueError::new_err(format!("the dict is not a TOML table: {e}")))?;
        sweep::parse(&text, "<dict>").and_then(|s| sweep::Plan::resolve(&s, Path::new("."), &extra))
    } else {
        let path: PathBuf = sweep.extract()?;
        sweep::Plan::from_file(&path, &extra)
    };
    let plan = py_result(py, plan)?;
    let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    let jobs = jobs.unwrap_or(cores).max(1);
    if jobs > cores && !oversubscribe {
        return Err(to_py(
            py,
            &Error::scene(
                "jobs",
                format!(
                    "{jobs} points at once on {cores} cores: each point runs on one core, so more would share the cores and multiply the memory; give oversubscribe=True to run them anyway"
                ),
            ),
        ));
    }
    let dir = out.unwrap_or_else(|| PathBuf::from("out").join(&plan.name));
    let launcher = launcher(py);
    let (result, signal) = interruptible(py, |flag| -> dyncontact::Result<PathBuf> {
        use dyncontact::sweep::{collect, runner};
        let _lock = sweep::lock(&dir)?;
        let done = plan.write(&dir, &launcher)?;
        if plan_only {
            return Ok(dir.join("sweep.csv"));
        }
        let opts = runner::RunnerOptions { jobs, progress, interrupt: Some(flag.clone()) };
        runner::run_points(&plan, &dir, &done, &opts)?;
        let (_, rows) = collect::collect(&dir)?;
        if flag.load(std::sync::atomic::Ordering::SeqCst) {
            use dyncontact::failure::RunStatus;
            let finished = rows
                .iter()
                .filter(|r| matches!(r.status, PointStatus::Run(RunStatus::Completed | RunStatus::Failed)))
                .count();
            return Err(Error::SweepInterrupted { finished, total: rows.len() });
        }
        let corrupt: Vec<String> = rows
            .iter()
            .filter(|r| r.status == PointStatus::Corrupt)
            .map(|r| format!("{}: {}", r.point, r.reason))
            .collect();
        if !corrupt.is_empty() {
            return Err(Error::folder(
                &dir,
                format!(
                    "{} points are corrupt (sweep.csv says why; no figure of theirs is reported): {}",
                    corrupt.len(),
                    corrupt.join("; ")
                ),
            ));
        }
        Ok(dir.join("sweep.csv"))
    })?;
    outcome(py, result, signal)
}

/// Run a refinement study as `dyncontact refine SCENE --levels N --ratio R --what W --windows W
/// --out OUT --jobs J` does (the scene's own overrides apply before the levels refine it);
/// returns the path of refine.csv.
#[pyfunction]
#[pyo3(signature = (scene, levels = 3, ratio = 2.0, what = "both", windows = None, out = None, jobs = None, progress = false))]
#[allow(clippy::too_many_arguments)]
fn run_refine(
    py: Python<'_>,
    scene: &PyScene,
    levels: usize,
    ratio: f64,
    what: &str,
    windows: Option<usize>,
    out: Option<PathBuf>,
    jobs: Option<usize>,
    progress: bool,
) -> PyResult<PathBuf> {
    use dyncontact::sweep::refine::{self, RefineOptions, What};
    let what = match what {
        "h" => What::H,
        "k" => What::K,
        "both" => What::Both,
        other => {
            return Err(to_py(py, &Error::scene("--what", format!("{other:?}: give \"h\", \"k\" or \"both\""))));
        }
    };
    let opts = RefineOptions { levels, ratio, what, windows };
    let extra = py_result(py, values::overrides(&scene.overrides))?;
    let refinement = py_result(py, refine::plan(&scene.base(), &extra, &scene.name, &opts))?;
    let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    let jobs = jobs.unwrap_or(cores).max(1);
    let dir = out.unwrap_or_else(|| refine::default_dir(&scene.name));
    let launcher = launcher(py);
    let (result, signal) = interruptible(py, |flag| -> dyncontact::Result<PathBuf> {
        let _lock = sweep::lock(&dir)?;
        let ropts = sweep::runner::RunnerOptions { jobs, progress, interrupt: Some(flag.clone()) };
        let (outcomes, _) = refinement.run(&dir, &ropts, &launcher)?;
        if flag.load(std::sync::atomic::Ordering::SeqCst) {
            let finished = outcomes
                .iter()
                .filter(|o| !matches!(o, sweep::runner::Outcome::Interrupted | sweep::runner::Outcome::NotRun))
                .count();
            return Err(Error::SweepInterrupted { finished, total: outcomes.len() });
        }
        Ok(dir.join("refine.csv"))
    })?;
    outcome(py, result, signal)
}

#[pymodule]
fn _dyncontact(m: &Bound<'_, PyModule>) -> PyResult<()> {
    // as the command line (src/cli.rs says why): faer's thread pool costs more than it gains here
    faer::set_global_parallelism(faer::Par::Seq);
    m.add_class::<PyScene>()?;
    m.add_class::<simulation::PySimulation>()?;
    m.add_class::<simulation::Steps>()?;
    m.add_class::<simulation::PyStepRecord>()?;
    m.add_function(wrap_pyfunction!(history_columns, m)?)?;
    m.add_function(wrap_pyfunction!(run_memory, m)?)?;
    m.add_function(wrap_pyfunction!(run_folder, m)?)?;
    m.add_function(wrap_pyfunction!(run_sweep, m)?)?;
    m.add_function(wrap_pyfunction!(run_refine, m)?)?;
    m.add_function(wrap_pyfunction!(cli_main, m)?)?;
    m.add("DEFAULT_SCENE", dyncontact::scene::DEFAULT_SCENE)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
