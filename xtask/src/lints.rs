//! The lints, checked by the build itself: cargo runs the workspace's crates through clippy's
//! driver, as `cargo clippy -- -D warnings` does (`RUSTC_WORKSPACE_WRAPPER` = clippy-driver,
//! its arguments in `CLIPPY_ARGS`), but under `cargo test --no-run` and maturin instead of
//! `cargo check`. The driver compiles as rustc does and adds clippy's lints, so one build both
//! makes the test binaries and checks every lint; a lint is an error that stops that build.
//!
//! Why not `cargo clippy` after the build: it checks every dependency a second time in its own
//! (metadata-only) mode — faer's, nalgebra's, clarabel's, pyo3's — 200–280 s of the CI's 30
//! minutes on two cores. Through the wrapper the dependencies are built once (the driver lints
//! only the workspace's crates; the others are compiled as before, with their lints capped).
//!
//! Both builds that share artifacts (the tests' and the wheel's) are wrapped alike, so the
//! wheel's reuses what the tests' compiled: the driver records `CLIPPY_ARGS` among its inputs.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

/// `-D warnings`, in the encoding `cargo clippy` hands its driver (each argument followed by the
/// separator). Clippy's own convention, not a documented interface: hence the canary below.
const CLIPPY_ARGS: &str = "-D__CLIPPY_HACKERY__warnings__CLIPPY_HACKERY__";

/// clippy-driver beside the cargo that built xtask (and runs it): the toolchain's `bin/`, where
/// `cargo clippy` finds it too.
fn driver() -> Option<PathBuf> {
    let cargo = PathBuf::from(env!("CARGO"));
    let driver = cargo.with_file_name(if cfg!(windows) { "clippy-driver.exe" } else { "clippy-driver" });
    driver.is_file().then_some(driver)
}

fn wrap<'c>(cmd: &'c mut Command, driver: &Path) -> &'c mut Command {
    cmd.env("RUSTC_WORKSPACE_WRAPPER", driver).env("CLIPPY_ARGS", CLIPPY_ARGS)
}

/// The canary: a one-function crate with a lint clippy warns of by default (`needless_return`),
/// built in `<target>/verify/lint-canary` through the wrapper. The wrapper is used only if that
/// build fails on exactly that lint — so a toolchain whose driver stopped reading `CLIPPY_ARGS`
/// (or lints nothing) gets `cargo clippy` instead of builds that pass unlinted.
fn canary(target: &Path, driver: &Path) -> Result<(), String> {
    let dir = target.join("verify").join("lint-canary");
    std::fs::create_dir_all(dir.join("src")).map_err(|e| format!("create {}: {e}", dir.display()))?;
    let manifest =
        "[package]\nname = \"lint-canary\"\nversion = \"0.0.0\"\nedition = \"2024\"\npublish = false\n\n[workspace]\n";
    let lib = "/// `needless_return`: clippy's style group, a warning by default, an error under -D warnings.\npub fn one() -> i32 {\n    return 1;\n}\n";
    for (file, text) in [("Cargo.toml", manifest), ("src/lib.rs", lib)] {
        std::fs::write(dir.join(file), text).map_err(|e| format!("write {}: {e}", dir.join(file).display()))?;
    }
    let out = wrap(Command::new(env!("CARGO")).args(["build", "--quiet", "--offline"]), driver)
        .arg("--manifest-path")
        .arg(dir.join("Cargo.toml"))
        .env("CARGO_TARGET_DIR", dir.join("target"))
        .output()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    let stderr = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() && stderr.contains("needless_return") {
        Ok(())
    } else if out.status.success() {
        Err("the lint canary built through clippy-driver without its lint".into())
    } else {
        Err(format!("the lint canary failed otherwise: {}", stderr.lines().take(4).collect::<Vec<_>>().join(" ")))
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

/// Lint what `cmd` (a cargo or maturin build) compiles of the workspace, with `-D warnings`.
/// Returns false, and leaves `cmd` as it was, when the toolchain has no clippy-driver or the
/// canary did not fail on its lint: the caller then runs `cargo clippy` itself.
pub fn through_clippy(cmd: &mut Command, target: &Path) -> bool {
    match linting_driver(target) {
        Some(driver) => {
            wrap(cmd, driver);
            true
        }
        None => false,
    }
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
