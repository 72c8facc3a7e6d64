//! The lints, checked by the builds verify runs anyway: cargo runs the workspace's crates through
//! clippy's driver, as `cargo clippy` does (`RUSTC_WORKSPACE_WRAPPER` = clippy-driver, its
//! arguments in `CLIPPY_ARGS`, here none), but under `cargo test --no-run` and maturin instead of
//! `cargo check`. The driver is rustc's own driver with clippy's lints added, and with clippy's
//! settings: MIR optimizations off, the null and alignment checks of raw-pointer accesses off,
//! format_args not flattened and `--cfg clippy` (LLVM still optimizes at the profile's level). So
//! one build both makes the test binaries and reports every lint, as a warning that verify counts
//! as a failure (`-D warnings` as a check, without stopping the build and so the tests).
//!
//! Why not `cargo clippy` after the build: it checks every dependency a second time in its own
//! (metadata-only) mode — faer's, nalgebra's, clarabel's, pyo3's — 200–280 s of the CI's 30–34
//! minutes before, on two cores. Through the wrapper the dependencies are built once (the driver
//! lints only the workspace's crates; the others are compiled by plain rustc, as before).
//!
//! The test build and the wheel's are wrapped alike: the wrapper (cargo's) and `CLIPPY_ARGS` (the
//! driver's) are among the workspace crates' build inputs, so the wheel's build reuses the
//! dyncontact the tests' compiled only if both are wrapped the same way (measured: it does).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

/// clippy-driver beside the cargo that built xtask (and runs it): the toolchain's `bin/`, where
/// `cargo clippy` finds it too.
fn driver() -> Option<PathBuf> {
    let cargo = PathBuf::from(env!("CARGO"));
    let driver = cargo.with_file_name(if cfg!(windows) { "clippy-driver.exe" } else { "clippy-driver" });
    driver.is_file().then_some(driver)
}

/// No arguments to the driver (clippy's default lints, reported as warnings): set all the same,
/// so that a `CLIPPY_ARGS` in the caller's environment changes neither the lints nor the
/// artifacts.
fn wrap<'c>(cmd: &'c mut Command, driver: &Path) -> &'c mut Command {
    cmd.env("RUSTC_WORKSPACE_WRAPPER", driver).env("CLIPPY_ARGS", "")
}

/// The canary: a one-function crate with a lint clippy warns of by default (`needless_return`),
/// built in `<target>/verify/lint-canary` through the wrapper. The wrapper is used only if that
/// build reports exactly that lint — so a toolchain whose driver lints nothing through the
/// wrapper gets `cargo clippy` instead of builds that pass unlinted.
fn canary(target: &Path, driver: &Path) -> Result<(), String> {
    let dir = target.join("verify").join("lint-canary");
    std::fs::create_dir_all(dir.join("src")).map_err(|e| format!("create {}: {e}", dir.display()))?;
    let manifest =
        "[package]\nname = \"lint-canary\"\nversion = \"0.0.0\"\nedition = \"2024\"\npublish = false\n\n[workspace]\n";
    let lib =
        "/// `needless_return`: clippy's style group, a warning by default.\npub fn one() -> i32 {\n    return 1;\n}\n";
    for (file, text) in [("Cargo.toml", manifest), ("src/lib.rs", lib)] {
        std::fs::write(dir.join(file), text).map_err(|e| format!("write {}: {e}", dir.join(file).display()))?;
    }
    let out = wrap(Command::new(env!("CARGO")).args(["build", "--offline"]), driver)
        .arg("--manifest-path")
        .arg(dir.join("Cargo.toml"))
        .env("CARGO_TARGET_DIR", dir.join("target"))
        .output()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    let stderr = String::from_utf8_lossy(&out.stderr);
    match (out.status.success(), stderr.contains("clippy::needless_return")) {
        (true, true) => Ok(()),
        (true, false) => Err("the lint canary built through clippy-driver without its lint".into()),
        (false, _) => {
            Err(format!("the lint canary did not build: {}", stderr.lines().take(4).collect::<Vec<_>>().join(" ")))
        }
    }
}

/// clippy-driver if it lints through the wrapper (the canary, run once per xtask process).
fn linting_driver(target: &Path) -> Option<&'static PathBuf> {
    static CHECKED: OnceLock<Option<PathBuf>> = OnceLock::new();
    CHECKED
        .get_or_init(|| {
            let driver = driver()?;
            match canary(target, &driver) {
                Ok(()) => Some(driver),
                Err(e) => {
                    println!("lints: {e}; cargo clippy checks them instead");
                    None
                }
            }
        })
        .as_ref()
}

/// Lint what `cmd` (a cargo or maturin build) compiles of the workspace: each lint a warning in
/// its output. Returns false, and leaves `cmd` as it was, when the toolchain has no clippy-driver
/// or the canary did not report its lint: the caller then runs `cargo clippy` itself.
pub fn through_clippy(cmd: &mut Command, target: &Path) -> bool {
    match linting_driver(target) {
        Some(driver) => {
            wrap(cmd, driver);
            true
        }
        None => false,
    }
}

/// The warnings in a build's rendered output (maturin's, which prints cargo's diagnostics as
/// cargo does): each `warning: …` line that a `--> file:line` follows, as `file:line: …`.
/// The summaries (`` `crate` (lib) generated 2 warnings ``) have no location and are left out.
pub fn rendered_warnings(output: &str) -> Vec<String> {
    let lines: Vec<&str> = output.lines().collect();
    let mut found = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let Some(message) = line.strip_prefix("warning: ") else { continue };
        let Some(at) = lines.get(i + 1).and_then(|l| l.trim_start().strip_prefix("--> ")) else { continue };
        found.push(format!("{}: {message}", at.trim()));
    }
    found
}

/// `cargo clippy <selection> -- -D warnings` on its own (`--quiet`): what the wrapped builds
/// could not lint. Ok, or the first errors and where they are.
pub fn clippy(root: &Path, selection: &[&str]) -> Result<(), String> {
    let out = Command::new(env!("CARGO"))
        .arg("clippy")
        .args(selection)
        .args(["--quiet", "--", "-D", "warnings"])
        .current_dir(root)
        .output()
        .map_err(|e| format!("cannot run cargo clippy: {e}"))?;
    if out.status.success() {
        return Ok(());
    }
    let text = String::from_utf8_lossy(&out.stderr);
    println!("{text}");
    let first: Vec<&str> =
        text.lines().filter(|l| l.starts_with("error") || l.trim_start().starts_with("-->")).take(6).collect();
    Err(format!("lints: cargo clippy {} -- -D warnings failed: {}", selection.join(" "), first.join(" ")))
}

#[cfg(test)]
mod tests {
    /// The wheel's lints are read from maturin's output: a located warning is found with its
    /// place, maturin's own lines and cargo's summary are not (the text is maturin 1.x's, with a
    /// lint injected into the Python crate).
    #[test]
    fn rendered_warnings_reads_the_located_warnings_only() {
        let output = "🍹 Building a mixed python/rust project
warning: unneeded `return` statement
   --> python/src/lib.rs:376:30
    |
376 | pub fn lint_probe() -> i32 { return 1; }
    |                              ^^^^^^^^
    = note: `#[warn(clippy::needless_return)]` on by default

warning: `dyncontact-python` (lib) generated 1 warning
📦 Built wheel for abi3 Python ≥ 3.9 to target/wheels/dyncontact-0.1.0-cp39-abi3-manylinux_2_35_x86_64.whl
";
        assert_eq!(super::rendered_warnings(output), ["python/src/lib.rs:376:30: unneeded `return` statement"]);
        assert!(super::rendered_warnings("📦 Built wheel\n").is_empty());
    }
}
