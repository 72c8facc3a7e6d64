//! The Python package's check (part of `cargo xtask crosscheck`, in the cross-check's venv):
//! 1. build the wheel with maturin (`python/`, the `dev` profile of the workspace — the profile
//!    of the solver binary under test — stripped) into `<target>/wheels`, timing it; the build
//!    goes through clippy's driver as the test build does (lints.rs), so it checks the Python
//!    crate's lints;
//! 2. install it into the venv (its dependencies, numpy and meshio, are the venv's pinned ones);
//! 3. `pytest python/tests` with `DYNCONTACT_BIN` the test build's binary (the tests compare
//!    histories with it bit for bit);
//! 4. every `examples/python/*.py`, each writing into `<target>/crosscheck/python-examples/<name>`.

use std::fmt::Write as _;
use std::path::Path;
use std::process::Command;
use std::time::Instant;

use crate::process::{exec, fresh_dir, rel, spawn};

/// Build, install and test the package. Ok((every step passed, report lines)); Err when a
/// program could not start or the wheel could not be built or installed.
pub fn check(root: &Path, target: &Path, bin: &Path, python: &Path) -> Result<(bool, String), String> {
    let mut report = String::new();
    let wheels = fresh_dir(&target.join("wheels"))?;
    let t = Instant::now();
    let mut maturin = Command::new(python);
    maturin
        .current_dir(root)
        .args(["-m", "maturin", "build", "--profile", "dev", "--strip", "--quiet", "-m"])
        .arg(root.join("python").join("Cargo.toml"))
        .arg("-o")
        .arg(&wheels);
    // wrapped as the test build is (lints.rs): it reuses that build's dyncontact and lints the
    // Python crate, which the test build does not compile (its warnings: in maturin's output)
    let linted = crate::lints::through_clippy(&mut maturin, target);
    maturin.env("CARGO_TERM_COLOR", "never"); // the warnings are read from the text
    let (built, output) = spawn(&mut maturin)?;
    if !built {
        return Err(format!("maturin could not build the wheel: {output}"));
    }
    let build_s = t.elapsed().as_secs_f64();
    let wheel = std::fs::read_dir(&wheels)
        .map_err(|e| format!("read {}: {e}", wheels.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .find(|p| p.extension().is_some_and(|x| x == "whl"))
        .ok_or_else(|| format!("maturin wrote no wheel into {}", wheels.display()))?;
    let size = std::fs::metadata(&wheel).map(|m| m.len()).unwrap_or(0);
    let _ = writeln!(report, "  wheel {} built in {build_s:.1} s, {:.2} MB", rel(root, &wheel), size as f64 / 1e6);
    let mut ok = true;
    if linted {
        let warnings = crate::lints::rendered_warnings(&output);
        let _ = writeln!(
            report,
            "  lints of the Python crate (clippy, in the wheel's build): {} warning(s)",
            warnings.len()
        );
        for w in &warnings {
            let _ = writeln!(report, "    {w}");
        }
        if !warnings.is_empty() {
            println!("{output}"); // the warnings in full, with clippy's help
        }
        ok &= warnings.is_empty();
    }
    exec(
        Command::new(python)
            .args(["-m", "pip", "install", "--disable-pip-version-check", "--quiet", "--no-deps", "--force-reinstall"])
            .arg(&wheel),
    )
    .map_err(|e| format!("pip could not install the wheel: {e}"))?;

    let t = Instant::now();
    let (passed, text) = spawn(
        Command::new(python)
            .current_dir(root)
            .env("PYTHONDONTWRITEBYTECODE", "1")
            .env("DYNCONTACT_BIN", bin)
            .env("MPLBACKEND", "Agg")
            .args(["-m", "pytest", "-q", "-p", "no:cacheprovider", "python/tests"]),
    )?;
    let summary = text.lines().rev().find(|l| l.contains(" passed") || l.contains(" failed")).unwrap_or("");
    let _ =
        writeln!(report, "  pytest python/tests: {} ({:.1} s)", summary.trim_matches('='), t.elapsed().as_secs_f64());
    if !passed {
        ok = false;
        for line in text.lines() {
            let _ = writeln!(report, "    {line}");
        }
    }

    let examples = root.join("examples").join("python");
    let mut scripts: Vec<_> = std::fs::read_dir(&examples)
        .map_err(|e| format!("read {}: {e}", examples.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "py"))
        .collect();
    scripts.sort();
    for script in scripts {
        let name = script.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let out = fresh_dir(&target.join("crosscheck").join("python-examples").join(&name))?;
        let t = Instant::now();
        let (passed, text) = spawn(
            Command::new(python)
                .current_dir(root)
                .env("PYTHONDONTWRITEBYTECODE", "1")
                .env("MPLBACKEND", "Agg")
                .arg(&script)
                .arg(&out),
        )?;
        let _ = writeln!(
            report,
            "  {} {} ({:.1} s)",
            rel(root, &script),
            if passed { "ran" } else { "FAILED" },
            t.elapsed().as_secs_f64()
        );
        if !passed {
            ok = false;
            for line in text.lines() {
                let _ = writeln!(report, "    {line}");
            }
        }
    }
    Ok((ok, report))
}
