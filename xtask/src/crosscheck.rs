//! `cargo xtask crosscheck`: compare dyncontact's finite-element operators with scikit-fem, read
//! its VTU frames back with meshio (the README, "Verification"), and compare a dynamic contact
//! run with GetFEM (Debian's python3-getfem, installed with apt when missing).
//!
//! Steps:
//! 1. a Python venv at `target/crosscheck-venv` with `xtask/crosscheck/requirements.txt`
//!    (pip runs only when the requirements changed since the last install: a marker file in the
//!    venv holds a hash of their text);
//! 2. for each `fixtures/scenes/crosscheck_*.toml`: `dyncontact export-operators` writes M, K, C
//!    and f(0) on all DOFs, and `check_operators.py` reassembles them with scikit-fem and
//!    compares entry by entry (relative tolerance 1e-12; the reasoning is in the script). The
//!    scikit-fem operators are saved under `fixtures/reference/<scene>_{M,K,C}.mtx`,
//!    `<scene>_f.txt` for Rust tests that run without Python;
//! 3. `solid_operators.py` assembles M, K, C of a 3-D box of tetrahedra and of the unstructured
//!    Gmsh mesh fixtures/meshes/holed_block.msh with scikit-fem into
//!    `fixtures/reference/{box3d,holed_block}_*.mtx` (tests/crosscheck.rs compares dyncontact's);
//! 4. short `dyncontact run`s of [`RUN_SCENES`] (2-D and 3-D), whose `series.pvd` and frames
//!    `check_frames.py` reads with meshio;
//! 5. the GetFEM dynamic-contact checks, and the sweeps' Snakemake path (src/workflow.rs).
//!
//! The solver is the binary `target/debug/dyncontact`, built only if it is missing: `cargo run`
//! from here would rebuild dependencies with other features than `cargo test` uses (cargo's
//! feature unification differs between the two). After changing the solver, rebuild it (`cargo build -p dyncontact --bin
//! dyncontact`, or `cargo test`, which builds it too).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

/// The scenes whose `run` output is read back with meshio (short runs, see the scene files): a
/// 2-D one and a 3-D one.
const RUN_SCENES: [&str; 2] = ["crosscheck_strain", "cantilever3d"];
/// Marker in the venv: hash of the requirements text last installed successfully.
const MARKER: &str = "requirements.hash";

/// Run the cross-check from the workspace root. Ok: a report to print. Err: what failed (with the
/// report so far, so the measured differences are visible).
pub fn run(root: &Path) -> Result<String, String> {
    let start = Instant::now();
    let target = std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| root.join("target"), |d| root.join(d));
    let scripts = root.join("xtask").join("crosscheck");
    let mut report = String::from("crosscheck: dyncontact vs scikit-fem 12 / meshio\n");

    let t = Instant::now();
    let (python, pip_ran) = ensure_venv(&target.join("crosscheck-venv"), &scripts.join("requirements.txt"))?;
    let _ = writeln!(
        report,
        "  venv {}: {} ({:.1} s)",
        rel(root, &python),
        if pip_ran { "requirements installed" } else { "requirements unchanged, pip skipped" },
        t.elapsed().as_secs_f64()
    );
    let bin = ensure_binary(root, &target)?;

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
            Command::new(&bin).current_dir(root).arg("export-operators").arg(scene).arg("--out").arg(&out),
            python_cmd(&python, root)
                .arg(scripts.join("check_operators.py"))
                .arg(&out)
                .arg("--reference")
                .arg(reference.join(&name)),
        );
        let _ = writeln!(report, "  {name} ({:.1} s)", t.elapsed().as_secs_f64());
        record(&mut report, &mut failures, &name, result);
    }

    // the 3-D box: scikit-fem's operators as references for tests/crosscheck.rs (the Rust side
    // has no scene path for 3-D yet, so the comparison is the Rust test's)
    let t = Instant::now();
    let result = spawn(python_cmd(&python, root).current_dir(&scripts).arg("solid_operators.py").arg(reference.join("box3d")));
    let _ = writeln!(report, "  3-D box operators with scikit-fem ({:.1} s)", t.elapsed().as_secs_f64());
    record(&mut report, &mut failures, "3-D box operators", result);
    let t = Instant::now();
    let msh = root.join("fixtures").join("meshes").join("holed_block.msh");
    let result = spawn(python_cmd(&python, root).current_dir(&scripts).arg("solid_operators.py").arg(reference.join("holed_block")).arg(&msh));
    let _ = writeln!(report, "  3-D Gmsh mesh operators with scikit-fem ({:.1} s)", t.elapsed().as_secs_f64());
    record(&mut report, &mut failures, "3-D Gmsh mesh operators", result);

    for run_scene in RUN_SCENES {
        let t = Instant::now();
        let scene = root.join("fixtures").join("scenes").join(format!("{run_scene}.toml"));
        let out = fresh_dir(&out_root.join(format!("run_{run_scene}")))?;
        let result = checked(
            Command::new(&bin).current_dir(root).arg("run").arg(&scene).arg("--out").arg(&out),
            python_cmd(&python, root).arg(scripts.join("check_frames.py")).arg(&out),
        );
        let _ = writeln!(report, "  frames of `dyncontact run {}` ({:.1} s)", rel(root, &scene), t.elapsed().as_secs_f64());
        record(&mut report, &mut failures, &format!("frames of {run_scene}"), result);
    }

    for (which, what) in [("bar_impact", "B.1 on the singular mass"), ("bar_friction", "oblique impact, Signorini–Coulomb and compliance + Coulomb")] {
        let t = Instant::now();
        let result = getfem_check(root, &bin, &scripts.join("getfem"), &out_root.join("getfem"), which);
        let _ = writeln!(report, "  GetFEM: dynamic contact, {what} ({:.1} s)", t.elapsed().as_secs_f64());
        record(&mut report, &mut failures, &format!("GetFEM dynamic contact ({which})"), result);
    }

    let t = Instant::now();
    let result = super::workflow::check(root, &bin, &python, &out_root.join("workflow"));
    let _ = writeln!(report, "  sweeps: in-process against Snakemake, and the stability map's job lists ({:.1} s)", t.elapsed().as_secs_f64());
    record(&mut report, &mut failures, "sweeps with Snakemake", result);

    let refs = rel(root, &reference);
    let _ = writeln!(report, "  scikit-fem reference operators written to {refs}/<scene>_{{M,K,C}}.mtx, <scene>_f.txt");
    let total = start.elapsed().as_secs_f64();
    if failures.is_empty() {
        let n = scenes.len();
        let _ = write!(
            report,
            "crosscheck OK: {n} scenes, tolerance 1e-12 relative, frames readable, GetFEM dynamic contact agrees with and without friction, Snakemake runs the sweep as in-process ({total:.1} s)"
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

/// The GetFEM cross-checks of the dynamic contact solve, each a script that runs dyncontact and
/// GetFEM on the same bar and compares them: `getfem/bar_impact.py` (B.1, frictionless Signorini)
/// and `getfem/bar_friction.py` (the oblique impact: Signorini–Coulomb and normal compliance +
/// Coulomb in GetFEM's weak-form language). Installs Debian's python3-getfem with apt when it is
/// missing (CI runs as root). `which` is the script's stem; the scene is `<stem>` + `_singular`
/// for B.1 and `<stem>` for the friction case.
fn getfem_check(root: &Path, bin: &Path, dir: &Path, out: &Path, which: &str) -> Result<(bool, String), String> {
    let has_getfem = || Command::new(GETFEM_PYTHON).args(["-c", "import getfem"]).stdout(Stdio::null()).stderr(Stdio::null()).status().is_ok_and(|s| s.success());
    if !has_getfem() {
        exec(Command::new("apt-get").args(["update", "-qq"]))
            .and_then(|()| exec(Command::new("apt-get").args(["install", "-y", "-qq", "python3-getfem"])))
            .map_err(|e| format!("python3-getfem is missing and `apt-get install python3-getfem` failed (run it as root): {e}"))?;
        if !has_getfem() {
            return Err(format!("python3-getfem was installed but `{GETFEM_PYTHON} -c 'import getfem'` still fails"));
        }
    }
    let scene = if which == "bar_impact" { "bar_impact_singular.toml".to_string() } else { format!("{which}.toml") };
    let out = fresh_dir(&out.join(which))?;
    spawn(
        Command::new(GETFEM_PYTHON)
            .current_dir(root)
            .env("PYTHONDONTWRITEBYTECODE", "1")
            .env("PYTHONUNBUFFERED", "1")
            .arg(dir.join(format!("{which}.py")))
            .arg("--dyncontact")
            .arg(bin)
            .arg("--scene")
            .arg(dir.join(scene))
            .arg("--out")
            .arg(&out),
    )
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

/// `target/debug/dyncontact`, built with `cargo build -p dyncontact --bin dyncontact` if missing.
fn ensure_binary(root: &Path, target: &Path) -> Result<PathBuf, String> {
    let bin = target.join("debug").join(format!("dyncontact{}", std::env::consts::EXE_SUFFIX));
    if !bin.exists() {
        let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
        // cargo's progress goes straight to the terminal: a first build takes minutes
        let status = Command::new(cargo)
            .args(["build", "-p", "dyncontact", "--bin", "dyncontact"])
            .current_dir(root)
            .stdin(Stdio::null())
            .status()
            .map_err(|e| format!("cannot run cargo: {e}"))?;
        if !status.success() || !bin.exists() {
            return Err(format!("`cargo build -p dyncontact --bin dyncontact` failed ({status}) or did not produce {}", bin.display()));
        }
    }
    Ok(bin)
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

/// Run to completion with captured output; Err (with the end of the output) unless it exits with 0.
fn exec(cmd: &mut Command) -> Result<(), String> {
    let (ok, text) = spawn(cmd)?;
    if ok { Ok(()) } else { Err(text) }
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

/// Run to completion with captured output: Ok((exited with 0, stdout + stderr, or on failure the
/// command line and the end of its output)); Err only when the program could not start.
pub fn spawn(cmd: &mut Command) -> Result<(bool, String), String> {
    // the command line for messages, with paths shown relative to the working directory
    let cwd = cmd.get_current_dir().map(Path::to_path_buf);
    let short = |a: &std::ffi::OsStr| match &cwd {
        Some(d) => rel(d, Path::new(a)),
        None => a.to_string_lossy().into_owned(),
    };
    let shown = std::iter::once(short(cmd.get_program())).chain(cmd.get_args().map(short)).collect::<Vec<_>>().join(" ");
    let out = cmd.stdin(Stdio::null()).output().map_err(|e| format!("cannot start `{shown}`: {e}"))?;
    let mut text = String::from_utf8_lossy(&out.stdout).into_owned();
    text.push_str(&String::from_utf8_lossy(&out.stderr));
    let ok = out.status.success();
    if !ok {
        // keep the end of a long log (pip, a Python traceback)
        let lines: Vec<&str> = text.lines().collect();
        let tail = lines[lines.len().saturating_sub(40)..].join("\n");
        let code = out.status.code().map_or_else(|| out.status.to_string(), |c| format!("code {c}"));
        text = format!("`{shown}` exited with {code}:\n{tail}");
    }
    Ok((ok, text))
}

/// Script output into the report, indented, without the scripts' own "N passed, N failed" line.
fn push_lines(report: &mut String, text: &str) {
    for line in text.lines().filter(|l| !l.trim().is_empty() && !l.contains(" passed, ")) {
        let _ = writeln!(report, "    {line}");
    }
}

/// An empty directory (removed first if it exists: stale frames would spoil the frame count).
pub fn fresh_dir(dir: &Path) -> Result<PathBuf, String> {
    if dir.exists() {
        std::fs::remove_dir_all(dir).map_err(|e| format!("remove {}: {e}", dir.display()))?;
    }
    std::fs::create_dir_all(dir).map_err(|e| format!("create {}: {e}", dir.display()))?;
    Ok(dir.to_path_buf())
}

fn stem(p: &Path) -> String {
    p.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default()
}

fn rel(root: &Path, p: &Path) -> String {
    p.strip_prefix(root).unwrap_or(p).display().to_string()
}

/// FNV-1a, 64 bit: a hash that stays the same across Rust versions (unlike `DefaultHasher`).
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3))
}
