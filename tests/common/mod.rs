//! Helpers shared by the integration tests: fixture scenes and in-memory runs.
#![allow(dead_code)]

use dyncontact::problem::Problem;
use dyncontact::scene::Scene;
use dyncontact::simulation::{Settings, Simulation, StepRecord};

/// The repository's root: this file serves the solver's tests (the package at the root) and the
/// studies' (the `studies/` package below it).
pub fn root() -> std::path::PathBuf {
    let manifest = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    if manifest.join("fixtures").is_dir() { manifest } else { manifest.join("..") }
}

/// A scene of fixtures/scenes by name (without .toml).
pub fn fixture(name: &str) -> Scene {
    let path = root().join("fixtures/scenes").join(format!("{name}.toml"));
    Scene::from_file(&path).unwrap_or_else(|e| panic!("fixture {name}: {e}"))
}

pub fn problem(scene: Scene) -> Problem {
    let dir = root().join("fixtures/scenes");
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
    let dir =
        std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).parent().map(|p| p.join("verify")).unwrap_or_default();
    let _ = std::fs::create_dir_all(&dir);
    let line =
        serde_json::json!({"test": test, "quantity": quantity, "value": value, "expected": expected}).to_string();
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
/// condensed contact problem, the factor cache the (F.1) solve warmed (a cache of this loop's
/// own, so the run's path is not changed) and the friction bound S of its converged (F.1) (Newton
/// inner solver with `set`): the per-step comparisons of two solvers from the same state.
pub fn each_frozen_step(
    p: &Problem,
    steps: usize,
    set: dyncontact::step::newton::NewtonSettings,
    mut look: impl FnMut(
        &Simulation,
        &dyncontact::step::StepData,
        &mut dyncontact::step::delassus::DelassusFactors,
        &[f64],
        &[f64],
    ),
) {
    let mut sim = Simulation::new(p).unwrap_or_else(|e| panic!("setup: {e}"));
    let c = p.contact.as_ref().expect("a scene with contact");
    let mut factors = dyncontact::step::delassus::DelassusFactors::default();
    for rec in sim
        .steps()
        .before_each(|sim| {
            let (w, _) = sim.free_velocity();
            let y_free = c.restrict(&w);
            let (data, p_hat) = sim.step_data(y_free.clone()).expect("data");
            let inner = dyncontact::step::fixed_point::Inner::Newton(set);
            let (_, s, _) = sim.solve_frozen_sequence(&data, &mut factors, &p_hat, &inner, None).expect("F.1");
            look(sim, &data, &mut factors, &s, &y_free);
        })
        .take(steps.min(p.steps))
    {
        rec.unwrap_or_else(|e| panic!("step: {e}"));
    }
}

/// Run to the end; the problem, the final displacement, and the regimes seen (some node
/// separated, some slipping, some on the constraint) — the manufactured solutions with contact.
pub fn run_regimes(s: Scene) -> (Problem, Vec<f64>, (bool, bool, bool)) {
    let p = problem(s);
    let (u, seen) = {
        let mut sim = Simulation::new(&p).expect("setup");
        let (mut sep, mut slip, mut active) = (false, false, false);
        for r in sim.steps() {
            let r = r.expect("step");
            sep |= r.contact_nodes < r.nodes.len();
            slip |= r.slip_nodes > 0;
            active |= r.nodes.iter().any(|n| n.lambda > 0.0);
        }
        (sim.state.u.clone(), (sep, slip, active))
    };
    (p, u, seen)
}

/// Observed orders of errors under halving.
pub fn orders(e: &[f64]) -> Vec<f64> {
    e.windows(2).map(|w| (w[0] / w[1]).log2()).collect()
}

/// The manufactured solutions with contact: the energy-norm order in h at the finest level is
/// 1 ± 0.2 (P1) and the midpoint order in k 2 ± 0.3 (the friction bound at the predictor and
/// the slip rate at the midpoint are O(k²) consistent, with larger constants); printed and
/// recorded as `test`, `label`.
pub fn assert_contact_orders(test: &str, label: &str, en: &[f64], ek: &[f64]) {
    let (oh, ok) = (orders(en), orders(ek));
    println!("{label}: energy errors {en:?}, orders in h {oh:?}");
    println!("{label}: ‖u_k − u_(k/2)‖ {ek:?}, orders in k {ok:?}");
    let (lh, lk) = (oh[oh.len() - 1], ok[ok.len() - 1]);
    measured(test, &format!("{label}: energy order in h"), lh, "1 ± 0.2");
    measured(test, &format!("{label}: midpoint order in k"), lk, "2 ± 0.3");
    assert!((lh - 1.0).abs() <= 0.2, "{label}: energy order in h {lh}");
    assert!((lk - 2.0).abs() <= 0.3, "{label}: midpoint order in k {lk}");
}

/// ‖u_k − u_(k/2)‖ (consistent-mass L²) at the end of runs of `scene(k)` for successive k of `ks`:
/// the midpoint rule's self-convergence in time (the space error cancels on one mesh).
pub fn self_convergence_in_k(ks: &[f64], scene: impl Fn(f64) -> Scene) -> Vec<f64> {
    let sols: Vec<(Problem, Vec<f64>)> = ks
        .iter()
        .map(|&k| {
            let (p, u, _) = run_regimes(scene(k));
            (p, u)
        })
        .collect();
    sols.windows(2).map(|w| l2_diff(&w[0].0, &w[0].1, &w[1].1)).collect()
}

/// The contact regime a manufactured solution with contact is built in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Regime {
    Separation,
    Slip,
    Constraint,
}

impl Regime {
    /// The run saw the regime it was built in: `seen` = (some node separated, some slipping,
    /// some on the constraint) from [`run_regimes`].
    pub fn assert_seen(self, seen: (bool, bool, bool)) {
        match self {
            Regime::Separation => assert!(seen.0 && !seen.1 && !seen.2, "{self:?}: regimes seen {seen:?}"),
            Regime::Slip => assert!(seen.1 && !seen.2, "{self:?}: regimes seen {seen:?}"),
            Regime::Constraint => assert!(seen.2, "{self:?}: regimes seen {seen:?}"),
        }
    }
}

/// The in-plane components (x, y) of nodal vectors of a 2-D problem (`Dofs::expand_dim` gives
/// three, z = 0).
pub fn in_plane(u: &[[f64; 3]]) -> Vec<[f64; 2]> {
    u.iter().map(|u| [u[0], u[1]]).collect()
}

/// Every file below `dir` (its path relative to `dir`) with its bytes, sorted, but the files
/// named `skip` (a folder's lock, which every process that writes the folder takes).
pub fn files_below(dir: &std::path::Path, skip: &str) -> Vec<(std::path::PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).expect("read_dir").flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.file_name().is_some_and(|n| n != skip) {
                let rel = p.strip_prefix(dir).expect("below").to_path_buf();
                out.push((rel, std::fs::read(&p).expect("read")));
            }
        }
    }
    out.sort();
    out
}
