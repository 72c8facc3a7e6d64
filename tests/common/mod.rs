//! Helpers shared by the integration tests: fixture scenes and in-memory runs.
#![allow(dead_code)]

use dyncontact::problem::Problem;
use dyncontact::scene::Scene;
use dyncontact::simulation::{Settings, Simulation, StepRecord};

/// A scene of fixtures/scenes by name (without .toml).
pub fn fixture(name: &str) -> Scene {
    let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fixtures/scenes").join(format!("{name}.toml"));
    Scene::from_file(&path).unwrap_or_else(|e| panic!("fixture {name}: {e}"))
}

pub fn problem(scene: Scene) -> Problem {
    let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fixtures/scenes");
    Problem::from_scene(&scene, &dir).unwrap_or_else(|e| panic!("problem: {e}"))
}

/// Run to the end in memory and return every record (t = 0 first).
pub fn records(p: &Problem) -> Vec<StepRecord> {
    records_with(p, Settings::from_problem(p))
}

pub fn records_with(p: &Problem, settings: Settings) -> Vec<StepRecord> {
    let mut sim = Simulation::with_settings(p, settings).unwrap_or_else(|e| panic!("setup: {e}"));
    let mut out = vec![sim.initial_record()];
    out.extend(sim.steps().map(|rec| rec.unwrap_or_else(|e| panic!("step: {e}"))));
    out
}

/// Record a measured number for `cargo xtask verify`'s report (target/verify/measurements.jsonl):
/// the test, the quantity, the value and what was expected (the band asserted, or "reported").
pub fn measured(test: &str, quantity: &str, value: f64, expected: &str) {
    use std::io::Write;
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).parent().map(|p| p.join("verify")).unwrap_or_default();
    let _ = std::fs::create_dir_all(&dir);
    let line = serde_json::json!({"test": test, "quantity": quantity, "value": value, "expected": expected}).to_string();
    if let Ok(mut f) = std::fs::OpenOptions::new().create(true).append(true).open(dir.join("measurements.jsonl")) {
        let _ = f.write_all(format!("{line}\n").as_bytes());
    }
}

/// L² distance of two free-DOF fields on the mesh of `p` (consistent mass with ρ = 1), in 2-D or 3-D.
pub fn l2_diff(p: &Problem, a: &[f64], b: &[f64]) -> f64 {
    let mut mat = p.material;
    mat.rho = 1.0;
    let consistent = dyncontact::model::kinds::MassKind::Consistent;
    let (m, _, _) = match &p.mesh {
        dyncontact::mesh::Geometry::Plane(mesh) => dyncontact::fem::assemble::assemble_full(mesh, &mat, consistent),
        dyncontact::mesh::Geometry::Solid(mesh) => dyncontact::fem::assemble::assemble_solid(mesh, &mat, consistent),
    }
    .expect("assembly");
    let m = dyncontact::fem::assemble::restrict(&m, &p.dofs).expect("restrict");
    let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
    dyncontact::linalg::quad(&m, &d, &d).sqrt()
}

/// Mean x-velocity of the body (lumped-mass weighted).
pub fn mean_velocity_x(sim: &Simulation) -> f64 {
    let (mut mom, mut mass) = (0.0, 0.0);
    for (i, m) in sim.ops.m_lumped.iter().enumerate().step_by(2) {
        mom += m * sim.state.v[i];
        mass += m;
    }
    mom / mass
}

/// Run `p` for `steps` steps and, before each, hand `look` the simulation, the step's
/// condensed contact problem and the friction bound S of its converged (F.1) (Newton inner
/// solver with `set`): the per-step comparisons of two solvers from the same state.
pub fn each_frozen_step(
    p: &Problem,
    steps: usize,
    set: dyncontact::step::newton::NewtonSettings,
    mut look: impl FnMut(&Simulation, &dyncontact::step::StepData, &[f64], &[f64]),
) {
    let mut sim = Simulation::new(p).unwrap_or_else(|e| panic!("setup: {e}"));
    let c = p.contact.as_ref().expect("a scene with contact");
    for rec in sim
        .steps()
        .before_each(|sim| {
            let (w, _) = sim.free_velocity();
            let y_free = c.restrict(&w);
            let (data, p_hat) = sim.step_data(y_free.clone()).expect("data");
            let inner = dyncontact::step::fixed_point::Inner::Newton(set);
            let (_, s, _) = sim.solve_frozen_sequence(&data, &p_hat, &inner, None).expect("F.1");
            look(sim, &data, &s, &y_free);
        })
        .take(steps.min(p.steps))
    {
        rec.unwrap_or_else(|e| panic!("step: {e}"));
    }
}
