//! Behaviour is pinned across restructurings: every fixture scene is run through the CLI and
//! its history.csv and contact.csv are compared with the outputs recorded in
//! fixtures/regression/<scene>/ before the code was restructured.
//!
//! The comparison is bit for bit on the text. Where a value differs, the test reports the
//! first difference and fails; there is no tolerance, because nothing in a restructuring that
//! keeps the arithmetic order may change a digit. (If a future change reorders a floating-point
//! sum on purpose, it must re-record these files in the same commit and say why.)
//!
//! Each time the pins were re-recorded, and by how much every output moved, is in CHANGELOG.md
//! ("Pinned outputs re-recorded").

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The first line where two CSV texts differ, with both lines.
fn first_difference(recorded: &str, now: &str) -> Option<String> {
    let (a, b): (Vec<&str>, Vec<&str>) = (recorded.lines().collect(), now.lines().collect());
    for (i, (x, y)) in a.iter().zip(&b).enumerate() {
        if x != y {
            return Some(format!("line {}: recorded\n  {x}\nnow\n  {y}", i + 1));
        }
    }
    (a.len() != b.len()).then(|| format!("{} lines recorded, {} now", a.len(), b.len()))
}

/// Fixtures pinned at another resolution than they ship with (a text substitution in a copy of
/// the scene): academic3d, the 3-D default fixture at 24×12×8 cells (45 s in release), is
/// pinned at 8×4×4 (the same physics on 45 contact nodes; its full run is measured by the bench).
const PINNED_COARSER: &[(&str, &str, &str)] = &[("academic3d", "cells = [24, 12, 8]", "cells = [8, 4, 4]")];

fn run_scene(name: &str, out: &Path) {
    let mut scene = root().join("fixtures/scenes").join(format!("{name}.toml"));
    if let Some((_, from, to)) = PINNED_COARSER.iter().find(|(n, _, _)| *n == name) {
        let text = std::fs::read_to_string(&scene).expect("the fixture");
        assert!(text.contains(from), "{name}: the fixture no longer has `{from}`");
        std::fs::create_dir_all(out).expect("the output folder");
        scene = out.join(format!("{name}.toml"));
        std::fs::write(&scene, text.replace(from, to)).expect("the coarser copy");
    }
    let st = Command::new(env!("CARGO_BIN_EXE_dyncontact"))
        .arg("run")
        .arg(&scene)
        .arg("--out")
        .arg(out)
        .output()
        .expect("the dyncontact binary runs");
    assert!(st.status.success(), "{name}: run failed: {}", String::from_utf8_lossy(&st.stderr));
}

/// Requirement: every fixture scene gives history.csv and contact.csv identical, digit for
/// digit, to the outputs recorded before the restructuring.
#[test]
fn fixture_outputs_unchanged_bit_for_bit() {
    let recorded_root = root().join("fixtures/regression");
    let mut names: Vec<String> = std::fs::read_dir(root().join("fixtures/scenes"))
        .expect("fixtures/scenes")
        .flatten()
        .filter_map(|e| e.path().file_stem().map(|s| s.to_string_lossy().to_string()))
        .collect();
    names.sort();
    let mut failures = Vec::new();
    for name in &names {
        let recorded = recorded_root.join(name);
        assert!(recorded.is_dir(), "{name}: no recorded outputs in fixtures/regression/{name}");
        let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("regression").join(name);
        run_scene(name, &out);
        for file in ["history.csv", "contact.csv"] {
            let a = std::fs::read_to_string(recorded.join(file)).expect("recorded file");
            let b = std::fs::read_to_string(out.join(file)).expect("new file");
            if let Some(d) = first_difference(&a, &b) {
                failures.push(format!("{name}/{file}: {d}"));
            }
        }
    }
    assert!(failures.is_empty(), "outputs changed:\n{}", failures.join("\n"));
}
