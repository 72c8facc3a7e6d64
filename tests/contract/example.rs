//! The library's example (examples/steps.rs) runs: scene text → validate → Problem →
//! Simulation → `for rec in sim.steps()` — the README's promise that the library is the
//! pipeline, compiled as an example and run here.

#[path = "../../examples/steps.rs"]
mod steps;

/// The example runs the coarse academic scene for 0.05 s (50 steps) without an error.
#[test]
fn the_library_example_runs_the_academic_scene() {
    steps::main().expect("examples/steps.rs");
}
