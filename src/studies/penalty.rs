//! `dyncontact study penalty`: the ε → 0 study of spec/model.md §5.3. The exact problem P (the
//! constraint with multipliers) and the penalty problem P_ε are run on the same mesh and step;
//! for each ε it reports
//!   e_V(ε) = max_n ‖u_ε^n − u^n‖_V / max_n ‖u^n‖_V   (‖v‖_V = ‖ε(v)‖_{L²}),
//!   e_H(ε) = max_n ‖v_ε^n − v^n‖_{L²} / max_n ‖v^n‖_{L²},
//!   δ(ε)   = max_{n,i} (u_ε,ν,i^n − g)_+ (the penetration beyond the bound),
//! and the least-squares log–log slopes of e_V, e_H and δ against ε. E.0 bounds δ by O(ε^½);
//! B.2 gives O(ε) under steady pressing.

use std::path::Path;
use std::time::Instant;

use crate::error::{Error, Result};
use crate::fem::assemble::{assemble_full, restrict};
use crate::linalg::{self, SpMat};
use crate::model::kinds::{Bound, EnforcementKind, FixedPointAcceleration, MassKind};
use crate::problem::Problem;
use crate::scene::Scene;
use crate::simulation::{NodeRecord, Simulation};

use super::harness::{self, loglog_slope};

/// One row of the study.
#[derive(Debug, Clone, Copy)]
pub struct PenaltyRow {
    pub eps: f64,
    pub e_v: f64,
    pub e_h: f64,
    pub delta: f64,
    pub wall_time_s: f64,
}

/// The study's result: rows and fitted slopes (e_V, e_H, δ).
#[derive(Debug, Clone)]
pub struct PenaltyStudy {
    pub rows: Vec<PenaltyRow>,
    pub slope_e_v: f64,
    pub slope_e_h: f64,
    pub slope_delta: f64,
    pub reference_wall_time_s: f64,
}

/// The default ε list of spec/model.md §5.3.
pub const DEFAULT_EPS: [f64; 6] = [1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7];

/// ‖·‖_V (strain) and ‖·‖_{L²} (ρ = 1) Gram matrices on the free DOFs of `p`.
fn norm_matrices(p: &Problem) -> Result<(SpMat, SpMat)> {
    let mut unit = p.material;
    // ε(v):ε(v) = ε_xx² + ε_yy² + γ²/2: the operator with λ = 0, μ = ½ (and ρ = 1 for L²)
    unit.lambda = 0.0;
    unit.mu_lame = 0.5;
    unit.theta = 0.0;
    unit.zeta = 0.0;
    unit.rho = 1.0;
    let mesh = p.mesh.plane().ok_or_else(|| Error::Output("the penalty study runs on 2-D scenes".into()))?;
    let (m, k, _) = assemble_full(mesh, &unit, MassKind::Consistent)?;
    Ok((restrict(&k, &p.dofs)?, restrict(&m, &p.dofs)?))
}

fn norm(a: &SpMat, x: &[f64]) -> f64 {
    linalg::quad(a, x, x).max(0.0).sqrt()
}

/// (E.0) The penetration beyond the bound of one step, max_i (u_ν,i − g)_+: the energy
/// estimate of P_ε bounds it by C ε^½ (the study measures the rate).
pub fn penetration_beyond_bound(nodes: &[NodeRecord], g: f64) -> f64 {
    nodes.iter().map(|n| (n.u_n - g).max(0.0)).fold(0.0, f64::max)
}

/// Run the study for `scene` (its contact section must have a finite penetration bound).
pub fn penalty_study(scene: &Scene, scene_dir: &Path, eps_list: &[f64]) -> Result<PenaltyStudy> {
    let c = scene.contact.as_ref().ok_or_else(|| Error::scene("contact", "the penalty study needs a scene with contact"))?;
    if Scene::bound_of(c)? == Bound::Infinite {
        return Err(Error::scene("contact.penetration_bound", "the penalty study needs a finite g (it penalizes u_ν > g)"));
    }
    if let Some(e) = eps_list.iter().find(|e| !(e.is_finite() && **e > 0.0)) {
        return Err(Error::scene("--eps", format!("every ε must be > 0, got {e}")));
    }
    // the study is of the paper's plain (F.1) iteration on both problems: beyond (C.k) a
    // trajectory is reproducible only to a few percent across fixed-point variants (README,
    // "Speed"), which at ε ≤ 1e-5 is the size of the penalty error itself
    let mut scene = scene.clone();
    scene.solver.fixed_point_acceleration = FixedPointAcceleration::None;
    let scene = &scene;
    let mut exact_scene = scene.clone();
    if let Some(c) = exact_scene.contact.as_mut() {
        c.enforcement = EnforcementKind::Exact;
        c.penalty = None;
    }
    let exact = Problem::from_scene(&exact_scene, scene_dir)?;
    let g = match exact.contact.as_ref().map(|c| c.bound) {
        Some(Bound::Finite(g)) => g,
        _ => return Err(Error::scene("contact.penetration_bound", "must be finite")),
    };
    let (kv, mh) = norm_matrices(&exact)?;
    // the reference trajectory, kept in memory (two vectors per step)
    let clock = Instant::now();
    let mut sim = Simulation::new(&exact)?;
    let mut reference = Vec::with_capacity(exact.steps);
    let mut steps = sim.steps();
    while let Some(rec) = steps.next() {
        rec?;
        let state = &steps.simulation().state;
        reference.push((state.u.clone(), state.v.clone()));
    }
    let reference_wall_time_s = clock.elapsed().as_secs_f64();
    let u_max = reference.iter().map(|(u, _)| norm(&kv, u)).fold(0.0, f64::max).max(f64::MIN_POSITIVE);
    let v_max = reference.iter().map(|(_, v)| norm(&mh, v)).fold(0.0, f64::max).max(f64::MIN_POSITIVE);
    let mut rows = Vec::new();
    for &eps in eps_list {
        let mut s = scene.clone();
        if let Some(c) = s.contact.as_mut() {
            c.enforcement = EnforcementKind::Penalty;
            c.penalty = Some(eps);
        }
        let pen = Problem::from_scene(&s, scene_dir)?;
        let clock = Instant::now();
        let mut sim = Simulation::new(&pen)?;
        let (mut e_v, mut e_h, mut delta): (f64, f64, f64) = (0.0, 0.0, 0.0);
        let mut steps = sim.steps();
        for (u_ref, v_ref) in &reference {
            let Some(rec) = steps.next() else { break };
            let rec = rec?;
            let state = &steps.simulation().state;
            let du: Vec<f64> = state.u.iter().zip(u_ref).map(|(a, b)| a - b).collect();
            let dv: Vec<f64> = state.v.iter().zip(v_ref).map(|(a, b)| a - b).collect();
            e_v = e_v.max(norm(&kv, &du));
            e_h = e_h.max(norm(&mh, &dv));
            delta = delta.max(penetration_beyond_bound(&rec.nodes, g));
        }
        rows.push(PenaltyRow { eps, e_v: e_v / u_max, e_h: e_h / v_max, delta, wall_time_s: clock.elapsed().as_secs_f64() });
    }
    let eps: Vec<f64> = rows.iter().map(|r| r.eps).collect();
    let col = |f: fn(&PenaltyRow) -> f64| rows.iter().map(f).collect::<Vec<f64>>();
    Ok(PenaltyStudy {
        slope_e_v: loglog_slope(&eps, &col(|r| r.e_v)),
        slope_e_h: loglog_slope(&eps, &col(|r| r.e_h)),
        slope_delta: loglog_slope(&eps, &col(|r| r.delta)),
        rows,
        reference_wall_time_s,
    })
}

impl PenaltyStudy {
    /// study/penalty.csv.
    pub fn csv(&self) -> String {
        harness::csv_table(
            "eps,e_V,e_H,delta,wall_time_s",
            self.rows.iter().map(|r| [r.eps, r.e_v, r.e_h, r.delta, r.wall_time_s].map(|x| x.to_string()).to_vec()),
        )
    }

    /// study/penalty.svg: e_V, e_H and δ against ε on log–log axes.
    pub fn svg(&self, title: &str) -> Result<String> {
        type Measure = (&'static str, f64, fn(&PenaltyRow) -> f64);
        let series: [Measure; 3] = [
            ("e_V", self.slope_e_v, |r| r.e_v),
            ("e_H", self.slope_e_h, |r| r.e_h),
            ("δ (penetration beyond g)", self.slope_delta, |r| r.delta),
        ];
        let series: Vec<harness::LogSeries> = series
            .iter()
            .map(|(name, slope, f)| harness::LogSeries {
                name: format!("{name}, slope {slope:.2}"),
                points: self.rows.iter().map(|r| (r.eps, f(r))).collect(),
            })
            .collect();
        harness::loglog_chart("study/penalty.svg", title, ("ε (penalty compliance)", "error"), &series, (2.0, 3.0))
    }

    /// Write study/penalty.csv and study/penalty.svg under `dir`.
    pub fn write(&self, dir: &Path, title: &str) -> Result<()> {
        let svg = self.svg(title)?;
        harness::write_files(&dir.join("study"), &[("penalty.csv", self.csv().as_bytes()), ("penalty.svg", svg.as_bytes())])
    }
}
