//! `cargo xtask crosscheck`: compare dyncontact's finite-element operators with scikit-fem, read
//! its VTU frames back with meshio (the README, "Verification"), and compare a dynamic contact
//! run with GetFEM (Debian's python3-getfem, installed with apt when missing).
//!
//! Steps:
//! 1. [`prepare`]: a Python venv at `<target>/crosscheck-venv` with `xtask/crosscheck/requirements.txt`
//!    (pip runs only when the requirements changed since the last install: a marker file in the
//!    venv holds a hash of their text), and python3-getfem for Debian's Python. `verify` runs it
//!    on a thread while cargo builds: both wait mostly on the network;
//! 2. for each `fixtures/scenes/crosscheck_*.toml`: `dyncontact export-operators` writes M, K, C
//!    and f(0) on all DOFs, and `check_operators.py` reassembles them with scikit-fem and
//!    compares entry by entry (relative tolerance 1e-12; the reasoning is in the script). The
//!    scikit-fem operators are saved under `fixtures/reference/<scene>_{M,K,C}.mtx`,
//!    `<scene>_f.txt` for Rust tests that run without Python;
//! 3. `solid_operators.py` assembles M, K, C of a 3-D box of tetrahedra and of the unstructured
//!    Gmsh mesh fixtures/meshes/holed_block.msh with scikit-fem into
//!    `fixtures/reference/{box3d,holed_block}_*.mtx` (tests/verification/crosscheck.rs compares dyncontact's);
//! 4. short `dyncontact run`s of [`RUN_SCENES`] (2-D and 3-D), whose `series.pvd` and frames
//!    `check_frames.py` reads with meshio (the last frame also with VTK's XML reader);
//! 5. the GetFEM dynamic-contact checks (`getfem/*.py`: every GetFEM step converged, a bound at
//!    each refinement level), and the sweeps' Snakemake path (src/workflow.rs);
//! 6. the Python package (src/python.rs): its wheel built with maturin and installed in the venv,
//!    `pytest python/tests`, `examples/python/*.py`.
//!
//! The solver is the `dyncontact` binary of the test build (`cargo test -p dyncontact --no-run`,
//! which `verify` has just run): never a binary left over from an earlier build.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use crate::process::{exec, fresh_dir, rel, spawn};

/// The scenes whose `run` output is read back with meshio and VTK (short runs, see the scene files): a
/// 2-D one and a 3-D one.
const RUN_SCENES: [&str; 2] = ["crosscheck_strain", "cantilever3d"];
/// Marker in the venv: hash of the requirements text last installed successfully.
const MARKER: &str = "requirements.hash";

/// What [`prepare`] made ready: the venv's Python and how the setup went (for the report).
pub struct Prepared {
    python: PathBuf,
    lines: String,
}

/// The Python side of the cross-check, ready to run: the venv with the pinned requirements and
/// Debian's python3-getfem. Takes no solver binary, so it can run while cargo builds.
pub fn prepare(root: &Path, target: &Path) -> Result<Prepared, String> {
    let t = Instant::now();
    let (python, pip_ran) =
        ensure_venv(&target.join("crosscheck-venv"), &root.join("xtask").join("crosscheck").join("requirements.txt"))?;
    let mut lines = String::new();
    let _ = writeln!(
        lines,
        "  venv {}: {} ({:.1} s)",
        rel(root, &python),
        if pip_ran { "requirements installed" } else { "requirements unchanged, pip skipped" },
        t.elapsed().as_secs_f64()
    );
    let t = Instant::now();
    let getfem = ensure_getfem()?;
    let _ = writeln!(lines, "  GetFEM for {GETFEM_PYTHON}: {getfem} ({:.1} s)", t.elapsed().as_secs_f64());
    Ok(Prepared { python, lines })
}

/// Run the cross-check from the workspace root with the solver `bin` and what [`prepare`] made
/// ready. Ok: a report to print. Err: what failed (with the report so far, so the measured
/// differences are visible).
pub fn run(root: &Path, target: &Path, bin: &Path, prepared: &Prepared) -> Result<String, String> {
    let start = Instant::now();
    let scripts = root.join("xtask").join("crosscheck");
    let python = &prepared.python;
    let mut report = String::from("crosscheck: dyncontact vs scikit-fem 12 / meshio / GetFEM / Snakemake\n");
    report.push_str(&prepared.lines);
    let _ = writeln!(report, "  solver {}", rel(root, bin));

    let scenes = crosscheck_scenes(root)?;
    let out_root = target.join("crosscheck");
    let reference = root.join("fixtures").join("reference");
    std::fs::create_dir_all(&reference).map_err(|e| format!("create {}: {e}", reference.display()))?;
    let mut failures = Vec::new();

    for scene in &scenes {
        let name = stem(scene);
        let t = Instant::now();
        let out = fresh_dir(&out_root.join(&name))?;
        let result = checked(
            Command::new(bin).current_dir(root).arg("export-operators").arg(scene).arg("--out").arg(&out),
            python_cmd(python, root)
                .arg(scripts.join("check_operators.py"))
                .arg(&out)
                .arg("--reference")
                .arg(reference.join(&name)),
        );
        let _ = writeln!(report, "  {name} ({:.1} s)", t.elapsed().as_secs_f64());
        record(&mut report, &mut failures, &name, result);
    }

    // the 3-D box: scikit-fem's operators as references for tests/verification/crosscheck.rs (the Rust side
    // has no scene path for 3-D yet, so the comparison is the Rust test's)
    let t = Instant::now();
    let result =
        spawn(python_cmd(python, root).current_dir(&scripts).arg("solid_operators.py").arg(reference.join("box3d")));
    let _ = writeln!(report, "  3-D box operators with scikit-fem ({:.1} s)", t.elapsed().as_secs_f64());
    record(&mut report, &mut failures, "3-D box operators", result);
    let t = Instant::now();
    let msh = root.join("fixtures").join("meshes").join("holed_block.msh");
    let result = spawn(
        python_cmd(python, root)
            .current_dir(&scripts)
            .arg("solid_operators.py")
            .arg(reference.join("holed_block"))
            .arg(&msh),
    );
    let _ = writeln!(report, "  3-D Gmsh mesh operators with scikit-fem ({:.1} s)", t.elapsed().as_secs_f64());
    record(&mut report, &mut failures, "3-D Gmsh mesh operators", result);

    for run_scene in RUN_SCENES {
        let t = Instant::now();
        let scene = root.join("fixtures").join("scenes").join(format!("{run_scene}.toml"));
        let out = fresh_dir(&out_root.join(format!("run_{run_scene}")))?;
        let result = checked(
            Command::new(bin).current_dir(root).arg("run").arg(&scene).arg("--out").arg(&out),
            python_cmd(python, root).arg(scripts.join("check_frames.py")).arg(&out),
        );
        let _ =
            writeln!(report, "  frames of `dyncontact run {}` ({:.1} s)", rel(root, &scene), t.elapsed().as_secs_f64());
        record(&mut report, &mut failures, &format!("frames of {run_scene}"), result);
    }

    // the three GetFEM comparisons are independent single-threaded processes: run side by side
    let t = Instant::now();
    let getfem_dir = scripts.join("getfem");
    let results: Vec<_> = std::thread::scope(|scope| {
        let handles: Vec<_> = GETFEM_CHECKS
            .iter()
            .map(|c| {
                let (dir, out) = (&getfem_dir, out_root.join("getfem"));
                scope.spawn(move || {
                    let t = Instant::now();
                    (getfem_check(root, bin, dir, &out, c), t.elapsed().as_secs_f64())
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().unwrap_or_else(|_| (Err("the GetFEM check's thread panicked".into()), 0.0)))
            .collect()
    });
    let _ = writeln!(
        report,
        "  GetFEM: dynamic contact, {} comparisons side by side ({:.1} s)",
        GETFEM_CHECKS.len(),
        t.elapsed().as_secs_f64()
    );
    for (c, (result, seconds)) in GETFEM_CHECKS.iter().zip(results) {
        let _ = writeln!(report, "  GetFEM: {} ({seconds:.1} s)", c.what);
        record(&mut report, &mut failures, &format!("GetFEM dynamic contact ({})", c.what), result);
    }

    let t = Instant::now();
    let result = super::workflow::check(root, bin, python, &out_root.join("workflow"));
    let _ = writeln!(
        report,
        "  sweeps: in-process against Snakemake, and the stability map's job lists ({:.1} s)",
        t.elapsed().as_secs_f64()
    );
    record(&mut report, &mut failures, "sweeps with Snakemake", result);

    // the Python package: the wheel, its tests and examples in this venv (src/python.rs)
    let t = Instant::now();
    let result = super::python::check(root, target, bin, python);
    let _ = writeln!(report, "  Python package: wheel, pytest, examples ({:.1} s)", t.elapsed().as_secs_f64());
    match result {
        Ok((ok, text)) => {
            report.push_str(&text);
            if !ok {
                failures.push("Python package: check failed (see above)".to_string());
            }
        }
        Err(e) => failures.push(format!("Python package: {e}")),
    }

    let refs = rel(root, &reference);
    let _ = writeln!(report, "  scikit-fem reference operators written to {refs}/<scene>_{{M,K,C}}.mtx, <scene>_f.txt");
    let total = start.elapsed().as_secs_f64();
    if failures.is_empty() {
        let n = scenes.len();
        let _ = write!(
            report,
            "crosscheck OK: {n} scenes, tolerance 1e-12 relative, frames readable, GetFEM dynamic contact agrees with and without friction, Snakemake runs the sweep as in-process, the Python package's tests and examples pass ({total:.1} s)"
        );
        Ok(report)
    } else {
        let _ = writeln!(report, "crosscheck FAILED ({total:.1} s):");
        for f in &failures {
            let _ = writeln!(report, "  - {}", f.trim_end().replace('\n', "\n    "));
        }
        Err(report.trim_end().to_string())
    }
}

/// Debian's Python, which has GetFEM (python3-getfem); the cross-check venv's Python does not.
const GETFEM_PYTHON: &str = "/usr/bin/python3";

/// Debian's Python for the GetFEM scripts, isolated from the caller's environment as far as it
/// can be while keeping Debian's packages: `-E` ignores PYTHONPATH and the other PYTHON*
/// variables, `-s` the user's site-packages. OpenBLAS runs on one thread, so its sums are
/// taken in the same order whatever the number of cores.
fn getfem_python() -> Command {
    let mut c = Command::new(GETFEM_PYTHON);
    c.args(["-E", "-s"])
        .env("PYTHONDONTWRITEBYTECODE", "1")
        .env("PYTHONUNBUFFERED", "1")
        .env("OPENBLAS_NUM_THREADS", "1");
    c
}

/// python3-getfem importable by [`getfem_python`], installed with apt when it is missing (CI runs
/// as root). Ok: the package's version, whether apt ran, and the numpy GetFEM's Python imports.
fn ensure_getfem() -> Result<String, String> {
    let probe = || match spawn(
        getfem_python().args(["-c", "import getfem, numpy; print(f'numpy {numpy.__version__} from {numpy.__file__}')"]),
    ) {
        Ok((true, text)) => Ok(text.trim().to_string()),
        Ok((false, text)) | Err(text) => Err(text),
    };
    let (numpy, how) = match probe() {
        Ok(numpy) => (numpy, "present"),
        Err(_) => {
            exec(Command::new("apt-get").args(["update", "-qq"]))
                .and_then(|()| exec(Command::new("apt-get").args(["install", "-y", "-qq", "python3-getfem"])))
                .map_err(|e| {
                    format!(
                        "python3-getfem is missing and `apt-get install python3-getfem` failed (run it as root): {e}"
                    )
                })?;
            let numpy = probe().map_err(|e| {
                format!("python3-getfem was installed but `{GETFEM_PYTHON} -E -s -c 'import getfem'` still fails: {e}")
            })?;
            (numpy, "installed with apt")
        }
    };
    let version = match spawn(Command::new("dpkg-query").args(["-W", "-f", "${Version}", "python3-getfem"])) {
        Ok((true, v)) => v,
        _ => "(version unknown)".into(),
    };
    Ok(format!("python3-getfem {version} {how}, {numpy}"))
}

/// One GetFEM comparison: a script of `xtask/crosscheck/getfem`, its scene there and its case.
struct GetfemCheck {
    script: &'static str,
    scene: &'static str,
    case: Option<&'static str>,
    what: &'static str,
}

/// The GetFEM cross-checks of the dynamic contact solve, each a script that runs dyncontact and
/// GetFEM on the same bar and compares them: `bar_impact.py` (B.1, frictionless Signorini) and
/// `bar_friction.py` (the oblique impact: Signorini–Coulomb, and normal compliance + Coulomb in
/// GetFEM's weak-form language).
const GETFEM_CHECKS: [GetfemCheck; 3] = [
    GetfemCheck {
        script: "bar_impact.py",
        scene: "bar_impact_singular.toml",
        case: None,
        what: "B.1 on the singular mass",
    },
    GetfemCheck {
        script: "bar_friction.py",
        scene: "bar_friction.toml",
        case: Some("signorini-coulomb"),
        what: "oblique impact, Signorini–Coulomb",
    },
    GetfemCheck {
        script: "bar_friction.py",
        scene: "bar_friction.toml",
        case: Some("compliance-coulomb"),
        what: "oblique impact, compliance + Coulomb",
    },
];

fn getfem_check(
    root: &Path,
    bin: &Path,
    dir: &Path,
    out: &Path,
    check: &GetfemCheck,
) -> Result<(bool, String), String> {
    let folder =
        format!("{}{}", check.script.trim_end_matches(".py"), check.case.map(|c| format!("-{c}")).unwrap_or_default());
    let out = fresh_dir(&out.join(folder))?;
    let mut cmd = getfem_python();
    cmd.current_dir(root)
        .arg(dir.join(check.script))
        .arg("--dyncontact")
        .arg(bin)
        .arg("--scene")
        .arg(dir.join(check.scene))
        .arg("--out")
        .arg(&out);
    if let Some(case) = check.case {
        cmd.args(["--case", case]);
    }
    spawn(&mut cmd)
}

/// The venv's python, creating the venv and installing the requirements when needed. Returns
/// (python, whether pip ran).
fn ensure_venv(venv: &Path, requirements: &Path) -> Result<(PathBuf, bool), String> {
    let python = if cfg!(windows) { venv.join("Scripts").join("python.exe") } else { venv.join("bin").join("python") };
    if !python.exists() {
        if venv.exists() {
            // a half-made venv (interrupted creation): start over
            std::fs::remove_dir_all(venv).map_err(|e| format!("remove {}: {e}", venv.display()))?;
        }
        let py3 = std::env::var("PYTHON").unwrap_or_else(|_| "python3".into());
        exec(Command::new(&py3).arg("-m").arg("venv").arg(venv))
            .map_err(|e| format!("cannot create the Python venv (is `{py3} -m venv` available?): {e}"))?;
    }
    let text = std::fs::read(requirements).map_err(|e| format!("read {}: {e}", requirements.display()))?;
    let hash = format!("{:016x}\n", fnv1a(&text));
    let marker = venv.join(MARKER);
    if std::fs::read_to_string(&marker).is_ok_and(|m| m == hash) {
        return Ok((python, false));
    }
    let _ = std::fs::remove_file(&marker);
    exec(
        Command::new(&python)
            .args(["-m", "pip", "install", "--disable-pip-version-check", "--quiet", "-r"])
            .arg(requirements),
    )
    .map_err(|e| format!("pip install -r {} failed: {e}", requirements.display()))?;
    std::fs::write(&marker, hash).map_err(|e| format!("write {}: {e}", marker.display()))?;
    Ok((python, true))
}

/// `fixtures/scenes/crosscheck_*.toml`, sorted.
fn crosscheck_scenes(root: &Path) -> Result<Vec<PathBuf>, String> {
    let dir = root.join("fixtures").join("scenes");
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(&dir)
        .map_err(|e| format!("read {}: {e}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml") && stem(p).starts_with("crosscheck_"))
        .collect();
    scenes.sort();
    if scenes.is_empty() {
        return Err(format!("no crosscheck_*.toml scene in {}", dir.display()));
    }
    Ok(scenes)
}

/// The venv's python running a script from the root, leaving no __pycache__ behind.
fn python_cmd(python: &Path, root: &Path) -> Command {
    let mut c = Command::new(python);
    c.current_dir(root).env("PYTHONDONTWRITEBYTECODE", "1");
    c
}

/// Run dyncontact, then (if it succeeded) a check script on its output. Ok((the script passed,
/// its output)); Err when dyncontact failed or a program could not start.
fn checked(dyncontact: &mut Command, script: &mut Command) -> Result<(bool, String), String> {
    exec(dyncontact)?;
    spawn(script)
}

/// A check's outcome into the report (the script's lines) and, if it failed, into `failures`.
fn record(report: &mut String, failures: &mut Vec<String>, label: &str, result: Result<(bool, String), String>) {
    match result {
        Ok((ok, text)) => {
            push_lines(report, &text);
            if !ok {
                failures.push(format!("{label}: check failed (see above)"));
            }
        }
        Err(e) => failures.push(format!("{label}: {e}")),
    }
}

/// Script output into the report, indented, without the scripts' own "N passed, N failed" line.
fn push_lines(report: &mut String, text: &str) {
    for line in text.lines().filter(|l| !l.trim().is_empty() && !l.contains(" passed, ")) {
        let _ = writeln!(report, "    {line}");
    }
}

fn stem(p: &Path) -> String {
    p.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default()
}

/// FNV-1a, 64 bit: a hash that stays the same across Rust versions (unlike `DefaultHasher`).
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3))
}
