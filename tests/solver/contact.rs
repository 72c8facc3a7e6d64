//! The contact step (spec/model.md §4.3–§4.5): model no more than a scene needs, the twin inner
//! solvers, the fixed point (F.1) as a majorization–minimization, and the Alart–Curnier
//! parameters' irrelevance to the solution (N.1–N.3).

use crate::common;

use common::{fixture, problem, records, records_with};
use dyncontact::linalg;
use dyncontact::problem::Problem;
use dyncontact::scene::{Bound, BoundAt, FixedPointAcceleration, FrictionBound, FrictionLaw, NumOrStr};
use dyncontact::simulation::{Settings, Simulation};
use dyncontact::step::conic::ConicSettings;
use dyncontact::step::delassus::DelassusFactors;
use dyncontact::step::fixed_point::{F1Start, FixedPointSettings, Inner, StepReport};
use dyncontact::step::newton::{self, NewtonSettings};
use dyncontact::step::{StepData, conic};
use faer::linalg::solvers::DenseSolveCore;

/// A frictionless scene does zero fixed-point iterations (one convex solve per step).
#[test]
fn f1_frictionless_does_no_fixed_point_iterations() {
    let mut s = fixture("impact_friction");
    s.contact.as_mut().expect("contact").friction.law = FrictionLaw::None;
    let c = s.contact.as_mut().expect("contact");
    c.friction.static_ = None;
    c.friction.kinetic = None;
    c.friction.decay = None;
    let recs = records(&problem(s));
    assert!(recs.iter().all(|r| r.report.fixed_point_iterations == 0 && r.report.friction_unknowns == 0));
    assert!(recs.iter().any(|r| r.contact_nodes > 0), "the scene must touch the foundation");
}

/// A constant-μ scene does exactly one convex solve per step: the bound S = μ p_τ(û) is known
/// before the solve (p_τ at the predictor û, decision 2 as refined in spec/README.md).
#[test]
fn f1_constant_mu_does_one_convex_solve_per_step() {
    let mut s = fixture("impact_friction");
    let f = &mut s.contact.as_mut().expect("contact").friction;
    f.law = FrictionLaw::Constant;
    f.coefficient = Some(0.4);
    (f.static_, f.kinetic, f.decay) = (None, None, None);
    let recs = records(&problem(s));
    assert!(recs[1..].iter().all(|r| r.report.fixed_point_iterations == 1), "constant μ needed more than one solve");
    assert!(recs.iter().any(|r| r.slip_nodes > 0) && recs.iter().any(|r| r.contact_nodes > 0));
}

/// A scene with g = "inf" (pure normal compliance) has no multipliers: the model says so,
/// every step report counts 0 multipliers, and no λ is ever nonzero.
#[test]
fn s4_infinite_bound_has_no_multipliers() {
    let mut s = fixture("impact_friction");
    s.contact.as_mut().expect("contact").penetration_bound = NumOrStr::Str("inf".into());
    let p = problem(s);
    let c = p.contact.as_ref().expect("contact");
    assert!(c.constraint.is_none() && c.bound == Bound::Infinite);
    assert_eq!(dyncontact::output::ModelInfo::of(&p).multipliers, 0);
    let recs = records(&p);
    assert!(recs.iter().all(|r| r.report.multipliers == 0));
    assert!(recs.iter().all(|r| r.nodes.iter().all(|n| n.lambda == 0.0)));
    // without the bound the penetration is free to exceed the g of the original scene
    assert!(recs.iter().any(|r| r.max_penetration > 0.01));
}

/// Relative distance between two vectors.
fn rel(a: &[f64], b: &[f64], scale: f64) -> f64 {
    a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / scale
}

/// Solve the frozen problem of every step with both inner solvers and compare.
/// Returns the worst relative differences (velocity, force) over the run.
fn twins_on(p: &Problem, steps: usize) -> (f64, f64) {
    let newton_set = NewtonSettings { tolerance: 1e-12, ..NewtonSettings::default() };
    let conic_set = ConicSettings { tolerance: 1e-11, max_rounds: 100, verbose: false };
    let (mut worst_v, mut worst_f) = (0.0f64, 0.0f64);
    // the S of the converged fixed point, then one frozen solve by each twin
    common::each_frozen_step(p, steps, newton_set, |sim, data, factors, s, _| {
        let a = newton::solve(data, factors, s, &sim.state.lambda, &sim.state.t_fric, &newton_set).expect("newton");
        let b = conic::solve(data, s, &conic_set).expect("conic");
        let vs = data.velocity_scale(&a.y).max(1e-300);
        let ra = data.forces(&a.y, &a.lambda, &a.t);
        let rb = data.forces(&b.y, &b.lambda, &b.t);
        // the conic solver works in r̃ = r/V with V the velocity scale, so its absolute force
        // accuracy is relative to V/‖W‖ as well as to the forces themselves
        let w_norm = (0..data.delassus.dim())
            .map(|i| (0..data.delassus.dim()).map(|j| data.delassus[(i, j)].abs()).sum::<f64>())
            .fold(0.0, f64::max);
        let fs = linalg::norm_inf(&ra).max(data.velocity_scale(&data.y_free) / w_norm).max(1e-300);
        if linalg::norm_inf(&ra) > 0.0 {
            let (dv, df) = (rel(&a.y, &b.y, vs), rel(&ra, &rb, fs));
            if std::env::var_os("TWIN_DEBUG").is_some() && (dv > 1e-6 || df > 1e-6) {
                println!(
                    "step {}: dv {dv:.3e} df {df:.3e} vs {vs:.3e} fs {fs:.3e} y_newton {:?} y_conic {:?} status {:?} {:?}",
                    sim.state.n + 1,
                    &a.y[..6],
                    &b.y[..6],
                    &a.status[..3],
                    &b.status[..3]
                );
            }
            worst_v = worst_v.max(dv);
            worst_f = worst_f.max(df);
        }
    });
    (worst_v, worst_f)
}

/// The twins `newton` and `conic` solve the same frozen step problem (S.6) to the same
/// solution on every step of four scenes: a frictional impact (separation, compliance,
/// active constraint, stick, slip), a coarse academic scene, the penalty problem, and the
/// start of the default academic scene.
/// Tolerance 1e-5 relative: Newton stops at 1e-12 of the velocity scale; Clarabel's interior
/// point stops at gap/feasibility 1e-11 on the scaled program, which bounds its primal error
/// by about the square root of the gap, 3.2e-6, at degenerate (weakly active, stick-to-slip)
/// contacts — 1e-5 is that bound with a factor 3 of margin. Regular steps agree to ~1e-8.
#[test]
fn s6_twins_newton_and_conic_agree() {
    let mut academic = fixture("academic");
    academic.domain.cells = Some([16, 8].to_vec());
    academic.time.step = 1e-3;
    academic.time.end = 0.3;
    let mut penalty = fixture("impact_friction");
    let c = penalty.contact.as_mut().expect("contact");
    c.enforcement = dyncontact::scene::EnforcementKind::Penalty;
    c.penalty = Some(1e-3);
    // the start of the default academic scene: at rest the constraint is 1e12 velocity scales
    // away, which stalled the interior point before the conic solver left such rows out
    let mut start = fixture("academic");
    start.time.end = 0.02;
    for (name, s, steps) in [
        ("impact_friction", fixture("impact_friction"), 400),
        ("academic 16x8", academic, 300),
        ("penalty", penalty, 300),
        ("academic 32x16, first 40 steps", start, 40),
    ] {
        let p = problem(s);
        let (v, f) = twins_on(&p, steps);
        println!("{name}: worst relative difference: velocity {v:.3e}, force {f:.3e}");
        common::measured(
            "contact::s6_twins_newton_and_conic_agree",
            &format!("twins: velocity difference ({name})"),
            v,
            "≤ 1e-5",
        );
        common::measured(
            "contact::s6_twins_newton_and_conic_agree",
            &format!("twins: force difference ({name})"),
            f,
            "≤ 1e-5",
        );
        assert!(v <= 1e-5 && f <= 1e-5, "{name}: the twins disagree: velocity {v:.3e}, force {f:.3e}");
    }
}

/// (N.2) (N.3) The Alart–Curnier parameters do not change the solution: rescaling ρ_ν and
/// ρ_τ by 10 and by 1/10 gives the same contact velocities and forces (to 1e-9 relative:
/// three solves each stopped at 1e-12 of the velocity scale, amplified by the condition of
/// the small contact system).
#[test]
fn n2_n3_alart_curnier_parameters_do_not_change_the_solution() {
    let mut s = fixture("impact_friction");
    s.time.end = 0.2;
    let p = problem(s);
    let mut sim = Simulation::new(&p).expect("setup");
    let mut worst = 0.0f64;
    let mut factors = DelassusFactors::default();
    for rec in sim
        .steps()
        .before_each(|sim| {
            let (w, _) = sim.free_velocity();
            let c = p.contact.as_ref().expect("contact");
            let (data, p_hat) = sim.step_data(c.restrict(&w)).expect("data");
            let base = NewtonSettings { tolerance: 1e-12, max_iterations: 100, ..NewtonSettings::default() };
            let (_, sb, _) =
                sim.solve_frozen_sequence(&data, &mut factors, &p_hat, &Inner::Newton(base), None).expect("F.1");
            let a = newton::solve(&data, &mut factors, &sb, &sim.state.lambda, &sim.state.t_fric, &base).expect("base");
            for scale in [10.0, 0.1] {
                let set = NewtonSettings { scale_normal: scale, scale_tangent: scale, ..base };
                let b = newton::solve(&data, &mut factors, &sb, &sim.state.lambda, &sim.state.t_fric, &set)
                    .expect("rescaled");
                let vs = data.velocity_scale(&a.y).max(1e-300);
                worst = worst.max(rel(&a.y, &b.y, vs));
                let (ra, rb) = (data.forces(&a.y, &a.lambda, &a.t), data.forces(&b.y, &b.lambda, &b.t));
                let fs = linalg::norm_inf(&ra);
                if fs > 0.0 {
                    worst = worst.max(rel(&ra, &rb, fs));
                }
            }
        })
        .take(p.steps)
    {
        rec.expect("step");
    }
    println!("worst relative change under rescaling: {worst:.3e}");
    common::measured(
        "contact::n2_n3_alart_curnier_parameters_do_not_change_the_solution",
        "change under r ×10, ×0.1",
        worst,
        "≤ 1e-9",
    );
    assert!(worst <= 1e-9, "rescaled Alart–Curnier parameters changed the solution by {worst:.3e}");
}

/// ∫_a^x DP(a, s) ds by 20-point Gauss–Legendre on pieces split at the hinges.
fn compliance_potential(law: &dyncontact::model::laws::NormalLaw, a: f64, x: f64) -> f64 {
    const N: usize = 20;
    // nodes/weights of Gauss–Legendre by Newton on P_N
    let mut nodes = [0.0; N];
    let mut weights = [0.0; N];
    for i in 0..N {
        let mut z = (std::f64::consts::PI * (i as f64 + 0.75) / (N as f64 + 0.5)).cos();
        for _ in 0..100 {
            let (mut p1, mut p2) = (1.0, 0.0);
            for j in 0..N {
                let p3 = p2;
                p2 = p1;
                p1 = ((2 * j + 1) as f64 * z * p2 - j as f64 * p3) / (j + 1) as f64;
            }
            let pp = N as f64 * (z * p1 - p2) / (z * z - 1.0);
            let dz = p1 / pp;
            z -= dz;
            if dz.abs() < 1e-16 {
                nodes[i] = z;
                weights[i] = 2.0 / ((1.0 - z * z) * pp * pp);
                break;
            }
        }
    }
    let mut cuts = vec![a, x];
    for h in &law.hinges {
        if (h.s - a) * (h.s - x) < 0.0 {
            cuts.push(h.s);
        }
    }
    cuts.sort_by(f64::total_cmp);
    let sign = if x >= a { 1.0 } else { -1.0 };
    let mut total = 0.0;
    for w in cuts.windows(2) {
        let (lo, hi) = (w[0], w[1]);
        for k in 0..N {
            let s = 0.5 * (hi - lo) * nodes[k] + 0.5 * (hi + lo);
            total += 0.5 * (hi - lo) * weights[k] * law.discrete_gradient(a, s);
        }
    }
    sign * total
}

/// The true (unfrozen) step functional of (S.6) in the contact velocities y:
/// ½(y − y_free)ᵀW⁻¹(y − y_free) + Σ (ω/a_d) F(d^{n+1}(y)) + Σ (ω p̂_τ/a_v) ψ(v̄(y)).
fn step_functional(
    data: &StepData,
    winv: &faer::Mat<f64>,
    mu: &dyncontact::model::laws::FrictionCoefficient,
    p_hat: &[f64],
    y: &[f64],
) -> f64 {
    let m = y.len();
    let e: Vec<f64> = (0..m).map(|j| y[j] - data.y_free[j]).collect();
    let mut phi = 0.0;
    for i in 0..m {
        for j in 0..m {
            phi += 0.5 * e[i] * winv[(i, j)] * e[j];
        }
    }
    for (i, nd) in data.nodes.iter().enumerate() {
        phi += nd.omega / data.a_d * compliance_potential(data.law, nd.d_n, data.d_end(i, y));
        phi += nd.omega * p_hat[i] / data.a_v * mu.psi(data.slip(i, y));
    }
    phi
}

/// (F.1) (C.k) Under (C.k), the fixed point is a majorization–minimization: the true step
/// functional does not increase over the fixed-point iterations (checked on every step of the
/// academic scene at k = 3e-4 < the (C.k) limit 3.47e-4, over the first 0.4 s; allowance
/// 1e-10 of |Φ| for the inner solver's tolerance). This is the plain iteration's property
/// (`fixed_point_acceleration = "none"`); the Anderson extrapolation gives it up for speed and
/// reaches the same fixed point (`f1_anderson_reaches_the_plain_fixed_point`).
#[test]
fn f1_step_functional_decreases_under_ck() {
    let mut s = fixture("academic");
    s.solver.fixed_point_acceleration = FixedPointAcceleration::None;
    s.time.step = 2.5e-4;
    s.time.end = 0.4;
    let p = problem(s);
    let info = dyncontact::output::ModelInfo::of(&p);
    assert!(info.ck_step_limit.expect("C.k applies") > p.k, "the test step must satisfy (C.k)");
    let mu = p.contact.as_ref().and_then(|c| c.friction.clone()).expect("friction");
    let mut sim = Simulation::new(&p).expect("setup");
    let wmat = sim.delassus.as_ref().expect("W").to_dense();
    let winv = wmat.partial_piv_lu().inverse();
    let (mut checked, mut worst) = (0usize, 0.0f64);
    let mut factors = DelassusFactors::default();
    for rec in sim
        .steps()
        .before_each(|sim| {
            let (w, _) = sim.free_velocity();
            let c = p.contact.as_ref().expect("contact");
            let (data, p_hat) = sim.step_data(c.restrict(&w)).expect("data");
            let mut trace = Vec::new();
            let inner = Inner::Newton(NewtonSettings { tolerance: 1e-12, ..NewtonSettings::default() });
            sim.solve_frozen_sequence(&data, &mut factors, &p_hat, &inner, Some(&mut trace)).expect("F.1");
            let phis: Vec<f64> = trace.iter().map(|y| step_functional(&data, &winv, &mu, &p_hat, y)).collect();
            for w in phis.windows(2) {
                let allowance = 1e-10 * w[0].abs().max(w[1].abs());
                worst = worst.max((w[1] - w[0]) / w[0].abs().max(1e-300));
                assert!(w[1] <= w[0] + allowance, "step {}: Φ rose from {} to {}", sim.state.n + 1, w[0], w[1]);
                checked += 1;
            }
        })
        .take(p.steps)
    {
        rec.expect("step");
    }
    println!(
        "checked {checked} fixed-point iterations; largest relative change of Φ {worst:.3e} (negative = decrease)"
    );
    assert!(checked > 100, "too few fixed-point iterations to check");
}

/// (F.1) The fixed point with relaxation θ < 1 converges to the same steps as θ = 1 (to the
/// fixed-point tolerance 1e-8, amplified over 200 steps: 1e-5 relative on the force history).
#[test]
fn f1_relaxation_gives_the_same_solution() {
    let mut s = fixture("academic");
    s.domain.cells = Some([16, 8].to_vec());
    s.time.end = 0.1;
    s.time.step = 5e-4;
    let p = problem(s);
    let a = records(&p);
    let mut set = Settings::from_problem(&p);
    set.fixed_point.relaxation = 0.5;
    set.fixed_point.max_iterations = 200;
    let b = records_with(&p, set);
    let scale = a.iter().map(|r| r.normal_force.abs() + r.tangential_force.abs()).fold(0.0, f64::max);
    let diff = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x.tangential_force - y.tangential_force).abs() + (x.normal_force - y.normal_force).abs())
        .fold(0.0, f64::max);
    let fa: usize = a.iter().map(|r| r.report.fixed_point_iterations).sum();
    let fb: usize = b.iter().map(|r| r.report.fixed_point_iterations).sum();
    println!("θ = 1: {fa} fixed-point iterations, θ = 0.5: {fb}; force difference {:.3e} of {scale:.3e}", diff);
    assert!(diff <= 1e-5 * scale, "relaxed fixed point differs by {diff:.3e}");
    assert!(b.iter().all(|r| r.report.fixed_point_converged()));
}

/// Worst per-step differences between the reduced Newton system (Cholesky on the force
/// unknowns, factorization reused; in 3-D also the slipping nodes' frames and conjugate
/// gradients, or the velocity form) and the full m × m LU, each solving the frozen problem of
/// the converged F.1 bound from the same state to `tolerance`; and the worst difference between
/// the simulation's warm factor cache and a fresh one (0: the same bits).
fn reduced_vs_full(p: &Problem, steps: usize, tolerance: f64) -> (f64, f64, f64) {
    let reduced = NewtonSettings { tolerance, ..NewtonSettings::default() };
    let full = NewtonSettings { reduced: false, ..reduced };
    let (mut worst_v, mut worst_f, mut warm_cold) = (0.0f64, 0.0f64, 0.0f64);
    common::each_frozen_step(p, steps, reduced, |sim, data, warm, s, _| {
        let a = newton::solve(data, warm, s, &sim.state.lambda, &sim.state.t_fric, &reduced).expect("reduced");
        let b = newton::solve(data, warm, s, &sim.state.lambda, &sim.state.t_fric, &full).expect("full");
        let mut cold = DelassusFactors::default();
        let a_cold =
            newton::solve(data, &mut cold, s, &sim.state.lambda, &sim.state.t_fric, &reduced).expect("reduced, cold");
        let vs = data.velocity_scale(&a.y).max(1e-300);
        warm_cold = warm_cold
            .max(rel(&a_cold.y, &a.y, vs))
            .max(rel(&a_cold.lambda, &a.lambda, 1.0))
            .max(rel(&a_cold.t, &a.t, 1.0));
        let ra = data.forces(&a.y, &a.lambda, &a.t);
        let rb = data.forces(&b.y, &b.lambda, &b.t);
        if linalg::norm_inf(&ra) > 0.0 {
            worst_v = worst_v.max(rel(&a.y, &b.y, vs));
            worst_f = worst_f.max(rel(&ra, &rb, linalg::norm_inf(&ra)));
        }
    });
    (worst_v, worst_f, warm_cold)
}

/// (S.6) The reduced Newton system (Cholesky of W_UU + D on the force unknowns, its
/// factorization reused while U and D do not change) gives the same step solution as the full
/// m × m LU on every step of a frictional impact, the compliant layer and the start of the
/// default academic scene, to 1e-12 (the two directions are the same linear algebra in another
/// order, so they differ by round-off, measured ≤ 1.1e-15; 1e-12 leaves room for the
/// conditioning of W_UU); and a reused factorization gives the same bits as a fresh one.
#[test]
fn reduced_newton_system_agrees_with_the_full_one() {
    for (name, steps) in [("impact_friction", usize::MAX), ("compliant_layer", usize::MAX), ("academic", 600)] {
        let p = problem(fixture(name));
        let (dv, df, warm_cold) = reduced_vs_full(&p, steps, 1e-12);
        println!(
            "{name}: reduced vs full Newton system, worst per-step difference: velocity {dv:.3e}, force {df:.3e}; cache warm vs cold {warm_cold:.1e}"
        );
        assert!(dv <= 1e-12 && df <= 1e-12, "{name}: velocity {dv:.3e}, force {df:.3e}");
        assert!(warm_cold == 0.0, "{name}: a reused factorization changed the answer ({warm_cold:.3e})");
    }
}

/// (S.6) (N.3) In 3-D a slipping node's friction force follows its velocity across the slip (the
/// disk's 2 × 2 block), and the reduced directions take it in two ways: in force form in each
/// slipping node's (ẑ, ẑ^⊥) frame (sliding_block3d, 147 contact unknowns), and in velocity form
/// with W⁻¹ and conjugate gradients (academic3d at 12×8×4 cells, 324 unknowns; the first 0.3 s:
/// pressing with half the nodes slipping outward, then shaking). Each gives the full m × m LU's
/// step solution on every step, all solving Newton to 1e-13 of the velocity scale: velocities to
/// 1e-12 (10× the tolerance; measured 5.1e-16 in force form, 9.7e-14 in velocity form, whose
/// inexact directions reach the tolerance by another path) and forces to 1e-9 of the largest
/// force (a force follows from velocities through W⁻¹, whose entries are ~1e3× the velocity
/// scale's inverse here: measured 7.3e-11); a fresh factor cache gives the warm one's solution
/// to the same bounds. The velocity form is checked to run exactly where its rule says.
#[test]
fn reduced_newton_system_agrees_with_the_full_one_in_3d() {
    let mut big = fixture("academic3d");
    big.domain.cells = Some(vec![12, 8, 4]);
    big.time.end = 0.3;
    for (name, s, steps) in
        [("sliding_block3d", fixture("sliding_block3d"), 400), ("academic3d 12×8×4", big, usize::MAX)]
    {
        let p = problem(s);
        let (dv, df, warm_cold) = reduced_vs_full(&p, steps, 1e-13);
        println!(
            "{name}: reduced vs full Newton system in 3-D, worst per-step difference: velocity {dv:.3e}, force {df:.3e}; cache warm vs cold {warm_cold:.1e}"
        );
        common::measured(
            "reduced_newton_system_agrees_with_the_full_one_in_3d",
            &format!("{name}: per-step force difference"),
            df,
            "≤ 1e-9",
        );
        assert!(dv <= 1e-12 && df <= 1e-9, "{name}: velocity {dv:.3e}, force {df:.3e}");
        assert!(warm_cold <= 1e-9, "{name}: warm and cold factor caches differ by {warm_cold:.3e}");
        let sim = Simulation::new(&p).expect("setup");
        assert_eq!(
            sim.inverse.is_some(),
            p.contact.as_ref().is_some_and(|c| c.dim * c.n() >= 256),
            "{name}: the velocity form's rule"
        );
    }
}

/// F.1 (Newton inner solver) on the step `sim` is about to take, from its state, once per
/// fixed-point setting: each run's contact forces and report.
fn f1_from_the_state<const N: usize>(
    sim: &Simulation,
    p: &Problem,
    factors: &mut DelassusFactors,
    runs: [FixedPointSettings; N],
) -> [(Vec<f64>, StepReport); N] {
    let (w, _) = sim.free_velocity();
    let c = p.contact.as_ref().expect("contact");
    let (data, p_hat) = sim.step_data(c.restrict(&w)).expect("data");
    let normal = dyncontact::step::fixed_point::NormalPart::Predictor(&p_hat);
    let vn = c.restrict(&sim.state.v);
    runs.map(|fp| {
        let (sol, _, report) = dyncontact::step::fixed_point::solve(
            &data,
            factors,
            c.friction.as_ref(),
            &normal,
            &vn,
            &sim.state.lambda,
            &sim.state.t_fric,
            &Inner::Newton(NewtonSettings::default()),
            &fp,
            None,
        )
        .expect("F.1");
        (data.forces(&sol.y, &sol.lambda, &sol.t), report)
    })
}

/// (F.1) The Anderson-extrapolated fixed point and the plain one, each from the same state on
/// every step of the academic scene's first 0.6 s (press, then stick–slip), give the same step
/// solution to 1e-6 of the force scale: both stop when ‖G(S) − S‖ ≤ 1e-8 ‖S‖, which puts each
/// within 1e-8/(1 − ρ) of the fixed point for a contraction factor ρ (≤ 0.99 here: F.1 needs at
/// most 50 iterations); and the extrapolation saves convex solves (reported).
#[test]
fn f1_anderson_reaches_the_plain_fixed_point() {
    let mut s = fixture("academic");
    s.time.end = 0.6;
    let p = problem(s);
    let mut sim = Simulation::new(&p).expect("setup");
    let plain = FixedPointSettings { anderson: false, ..sim.settings.fixed_point };
    let accelerated = FixedPointSettings { anderson: true, ..sim.settings.fixed_point };
    let (mut worst, mut solves) = (0.0f64, [0usize; 2]);
    let mut factors = DelassusFactors::default();
    for rec in sim.steps().before_each(|sim| {
        let [(fa, ra), (fb, rb)] = f1_from_the_state(sim, &p, &mut factors, [plain, accelerated]);
        solves[0] += ra.fixed_point_iterations;
        solves[1] += rb.fixed_point_iterations;
        if linalg::norm_inf(&fa) > 0.0 {
            worst = worst.max(rel(&fa, &fb, linalg::norm_inf(&fa)));
        }
    }) {
        rec.expect("step");
    }
    println!(
        "F.1 plain vs Anderson from the same state: worst force difference {worst:.3e}; convex solves {} vs {}",
        solves[0], solves[1]
    );
    assert!(worst <= 1e-6, "{worst:.3e}");
    assert!(solves[1] < solves[0], "the extrapolation should save solves: {solves:?}");
}

/// (F.1, N.4, C.k) Inside (C.k) F.1 may start at the unfrozen Newton's root
/// (`fixed_point_start = "auto"`): the unfrozen step problem is convex there, so its root is
/// F.1's only fixed point, and the start changes the cost, not the answer. On academic3d at
/// 12×8×4 cells (108 contact nodes, 324 unknowns in velocity form) over 0.3 s at k = 5e-4, inside
/// its (C.k) limit 1.04e-3 (pressed, then shaken: slip, stick, separation), each step is solved from the
/// same state three ways: from the predictor's S to fixed_point_tolerance = 1e-13 (the
/// reference), from the root, and from the predictor at the default 1e-8. Requirement: the
/// root start's forces are within 1e-9 of the force scale of the reference's — it solves the
/// unfrozen system to Newton's 1e-10 of the velocity scale, then F.1's frozen solve at its S
/// to the same, and W⁻¹ maps that to forces with a factor ≲ 10 (measured 3.5e-11) — closer
/// than the predictor's start at F.1's default tolerance (measured 9.1e-9), and with fewer
/// Newton iterations (measured 2,395 against 4,207).
#[test]
fn f1_root_start_reaches_the_fixed_point_inside_ck() {
    let p = academic3d_12x8x4(None);
    let limit = dyncontact::output::ModelInfo::of(&p).ck_step_limit.expect("C.k applies");
    assert!(limit > p.k, "the test step must satisfy (C.k): {limit:e}");
    root_start_against_the_reference(&p, None, "f1_root_start_reaches_the_fixed_point_inside_ck");
}

/// (Ck.1, F.1, N.4) Beyond (C.k) but inside its sharp form (Ck.1), F.1 starts at the unfrozen
/// Newton's root as well (`fixed_point_start = "auto"`; the setup tests (Ck.1) through W): the
/// step problem is convex there too, so the root is F.1's only fixed point. The same comparison
/// as the test above on academic3d at 12×8×4 cells over 0.3 s at k = 1.2e-3, 1.15× the (C.k)
/// limit 1.04e-3 and inside (Ck.1) (λ_max 0.894 at this k, probed), with the same requirement
/// and the same reasons for its bounds.
#[test]
fn f1_root_start_reaches_the_fixed_point_inside_ck1_beyond_ck() {
    let p = academic3d_12x8x4(Some(1.2e-3));
    let limit = dyncontact::output::ModelInfo::of(&p).ck_step_limit.expect("C.k applies");
    assert!(limit < p.k, "the test step must exceed (C.k): {limit:e}");
    root_start_against_the_reference(&p, Some(true), "f1_root_start_reaches_the_fixed_point_inside_ck1_beyond_ck");
}

/// academic3d at 12×8×4 cells over 0.3 s, at its own k or at `step`.
fn academic3d_12x8x4(step: Option<f64>) -> Problem {
    let mut s = fixture("academic3d");
    s.domain.cells = Some(vec![12, 8, 4]);
    s.time.end = 0.3;
    s.output.every = 0;
    if let Some(k) = step {
        s.time.step = k;
    }
    problem(s)
}

/// Each step of `p` solved from the same state by F.1 three ways — from the predictor's S to
/// 1e-13 (the reference), from the unfrozen root, from the predictor at the default 1e-8 — with
/// the requirements of [`f1_root_start_reaches_the_fixed_point_inside_ck`]; `sharp`: what the
/// setup must have found of (Ck.1) (None: not tested, inside (C.k)).
fn root_start_against_the_reference(p: &Problem, sharp: Option<bool>, name: &str) {
    let mut sim = Simulation::new(p).expect("setup");
    assert_eq!(sim.sharp_convexity, sharp, "what the setup found of (Ck.1)");
    assert_eq!(
        sim.settings.fixed_point.start,
        F1Start::Root,
        "auto starts at the root where the step problem is convex"
    );
    assert!(sim.inverse.is_some(), "the velocity form (the thick family's path)");
    let root = sim.settings.fixed_point;
    let predictor = FixedPointSettings { start: F1Start::Predictor, ..root };
    let reference = FixedPointSettings { tolerance: 1e-13, max_iterations: 200, ..predictor };
    let (mut worst, mut worst_predictor, mut newton_its, mut slipped) = (0.0f64, 0.0f64, [0usize; 2], 0usize);
    let mut accepted_at_once = 0usize;
    let mut factors = DelassusFactors::default();
    for rec in sim.steps().before_each(|sim| {
        let [(fa, ra), (fb, rb), (fd, rd)] = f1_from_the_state(sim, p, &mut factors, [reference, root, predictor]);
        assert_eq!(ra.fixed_point, dyncontact::failure::FixedPointStatus::Converged, "the reference converges");
        assert!(rb.started_unfrozen && rb.fallback.is_none(), "the unfrozen Newton converges on a convex step problem");
        newton_its[0] += rb.inner_iterations;
        newton_its[1] += rd.inner_iterations;
        slipped += usize::from(rd.fixed_point_iterations > 1);
        accepted_at_once += usize::from(rb.fixed_point_iterations == 1);
        let scale = linalg::norm_inf(&fa);
        if scale > 0.0 {
            worst = worst.max(rel(&fa, &fb, scale));
            worst_predictor = worst_predictor.max(rel(&fa, &fd, scale));
        }
    }) {
        rec.expect("step");
    }
    common::measured(name, "worst per-step force difference to the 1e-13 fixed point, root start", worst, "≤ 1e-9");
    println!(
        "root start: {worst:.3e}; predictor start at 1e-8: {worst_predictor:.3e}; Newton iterations root {} vs predictor {}; {slipped} steps iterated, {accepted_at_once} of {} accepted after one convex solve",
        newton_its[0], newton_its[1], p.steps
    );
    assert!(slipped > 0, "the window must make F.1 iterate (slip-rate-dependent S)");
    // the root is the fixed point to Newton's tolerance, so F.1's test accepts its S after the
    // one solve that confirms it (measured: every step)
    assert_eq!(accepted_at_once, p.steps, "steps accepted after one convex solve from the root");
    assert!(worst <= 1e-9 && worst < worst_predictor, "{worst:.3e} against {worst_predictor:.3e}");
    assert!(newton_its[0] < newton_its[1], "the root start should save Newton iterations: {newton_its:?}");
}

/// (F.1, C.k) Where F.1 starts at the unfrozen root: `fixed_point_start = "auto"` only inside
/// (C.k) (academic3d at 12×8×4: limit 1.04e-3) with a varying μ, with Anderson's update (θ =
/// 1), the Newton inner solver, the bound at the predictor and at least ROOT_START_FROM (256)
/// contact unknowns; "unfrozen" beyond (C.k) too; "predictor" never.
#[test]
fn f1_root_start_rule() {
    use dyncontact::scene::{FixedPointStart, InnerSolver};
    let start = |cells: [i64; 3], edit: &dyn Fn(&mut dyncontact::scene::Scene)| {
        let mut s = fixture("academic3d");
        s.domain.cells = Some(cells.to_vec());
        edit(&mut s);
        Settings::from_problem(&problem(s)).fixed_point.start
    };
    let starts = |cells: [i64; 3], edit: &dyn Fn(&mut dyncontact::scene::Scene)| start(cells, edit) == F1Start::Root;
    assert!(starts([12, 8, 4], &|_| ()), "inside (C.k), 324 unknowns");
    assert_eq!(
        start([12, 8, 4], &|s| s.time.step = 2e-3),
        F1Start::RootIfSharpConvex,
        "beyond (C.k): the setup decides by (Ck.1)"
    );
    assert_eq!(
        start([12, 6, 4], &|s| s.time.step = 2e-3),
        F1Start::Predictor,
        "beyond (C.k) below ROOT_START_FROM: no test"
    );
    assert_eq!(
        start([12, 8, 4], &|s| s.solver.mass = dyncontact::scene::MassKind::Consistent),
        F1Start::RootIfSharpConvex,
        "the consistent mass: (C.k) with the lumped masses over d + 2 (2.08e-4) is below k, (Ck.1) decides"
    );
    for (what, edit) in [
        (
            "θ < 1",
            &(|s: &mut dyncontact::scene::Scene| s.solver.relaxation = 0.7) as &dyn Fn(&mut dyncontact::scene::Scene),
        ),
        ("conic", &|s| s.solver.inner = InnerSolver::Conic),
        ("bound at the midpoint", &|s| s.contact.as_mut().expect("contact").friction_bound_at = BoundAt::Midpoint),
        ("total bound", &|s| s.contact.as_mut().expect("contact").friction_bound = FrictionBound::Total),
    ] {
        let beyond = |s: &mut dyncontact::scene::Scene| {
            s.time.step = 2e-3;
            edit(s);
        };
        assert_eq!(start([12, 8, 4], &beyond), F1Start::Predictor, "beyond (C.k) with {what}: no root start");
    }
    assert!(!starts([12, 6, 4], &|_| ()), "252 contact unknowns: below ROOT_START_FROM");
    assert!(!starts([12, 8, 4], &|s| s.solver.fixed_point_acceleration = FixedPointAcceleration::None));
    assert!(!starts([12, 8, 4], &|s| s.solver.fixed_point_start = FixedPointStart::Predictor));
    assert!(!starts([12, 8, 4], &|s| s.solver.inner = InnerSolver::Conic));
    assert!(!starts([12, 8, 4], &|s| s.solver.relaxation = 0.7), "θ < 1: the plain update");
    assert!(!starts([12, 8, 4], &|s| s.contact.as_mut().expect("contact").friction_bound_at = BoundAt::Midpoint));
    assert!(!starts([12, 8, 4], &|s| s.contact.as_mut().expect("contact").friction_bound = FrictionBound::Total));
    assert!(
        !starts([12, 8, 4], &|s| {
            let f = &mut s.contact.as_mut().expect("contact").friction;
            (f.law, f.coefficient, f.static_, f.kinetic, f.decay) =
                (FrictionLaw::Constant, Some(0.4), None, None, None);
        }),
        "a constant μ: one convex solve already"
    );
    assert!(starts([12, 8, 4], &|s| {
        s.time.step = 2e-3;
        s.solver.fixed_point_start = FixedPointStart::Unfrozen;
    }));
}

/// (N.1–N.3, F.1) The frozen problem's solution does not depend on where Newton starts: F.1 starts
/// its second and later convex solves at the last one's contact velocities (`solve_from`) instead
/// of at the response of the warm-started forces to the free motion. On academic3d at 12×8×4
/// cells over 0.3 s (324 contact unknowns in velocity form; pressed, then shaken: stick, slip,
/// separation), each step's first convex problem is solved, S is moved by 0.1% (an F.1 update's
/// size in the middle of a step), and the moved problem is solved from both starts (measured:
/// 8.4e-11 in velocities, 1.7e-9 in forces, 1,136 against 1,065 iterations). Requirement: the
/// two solutions agree to 1e-9 of the velocity scale and 1e-7 of the force scale — each stops
/// at ‖F‖_∞ ≤ 1e-10 of the velocity scale (NEWTON_TOLERANCE), the difference of two such
/// solutions is that times W's conditioning (~100 here) in forces — and the start at the nearby
/// solution takes fewer Newton iterations in total (counted, reported).
#[test]
fn f1_newton_from_the_last_solution_gives_the_same_solution() {
    let mut s = fixture("academic3d");
    s.domain.cells = Some(vec![12, 8, 4]);
    s.time.end = 0.3;
    let p = problem(s);
    let mut sim = Simulation::new(&p).expect("setup");
    assert!(sim.inverse.is_some(), "the velocity form runs at this size");
    let set = NewtonSettings::default();
    // statuses seen, by their VTU code: separated, stick, slip, contact
    let (mut worst_y, mut worst_f, mut iterations, mut statuses) = (0.0f64, 0.0f64, [0usize; 2], [false; 4]);
    let mut factors = DelassusFactors::default();
    for rec in sim.steps().before_each(|sim| {
        let (w, _) = sim.free_velocity();
        let c = p.contact.as_ref().expect("contact");
        let (data, p_hat) = sim.step_data(c.restrict(&w)).expect("data");
        let mu = c.friction.as_ref().expect("friction");
        let (lambda, t) = (&sim.state.lambda, &sim.state.t_fric);
        // F.1's first bound: S at the predictor from v^n
        let normal = dyncontact::step::fixed_point::NormalPart::Predictor(&p_hat);
        let s0 = dyncontact::step::fixed_point::friction_bound(&data, mu, &normal, &c.restrict(&sim.state.v), lambda);
        let first = newton::solve(&data, &mut factors, &s0, lambda, t, &set).expect("first solve");
        let s1: Vec<f64> = s0.iter().map(|v| 1.001 * v).collect();
        let fresh = newton::solve(&data, &mut factors, &s1, &first.lambda, &first.t, &set).expect("fresh start");
        let warm =
            newton::solve_from(&data, &mut factors, &s1, &first.y, &first.lambda, &first.t, &set).expect("warm start");
        iterations[0] += fresh.iterations;
        iterations[1] += warm.iterations;
        for st in &fresh.status {
            statuses[st.code() as usize] = true;
        }
        worst_y = worst_y.max(rel(&fresh.y, &warm.y, data.velocity_scale(&fresh.y)));
        let (fa, fb) = (data.forces(&fresh.y, &fresh.lambda, &fresh.t), data.forces(&warm.y, &warm.lambda, &warm.t));
        if linalg::norm_inf(&fa) > 0.0 {
            worst_f = worst_f.max(rel(&fa, &fb, linalg::norm_inf(&fa)));
        }
    }) {
        rec.expect("step");
    }
    println!(
        "Newton from the free motion vs from the last solution: velocities {worst_y:.3e}, forces {worst_f:.3e}; \
         iterations {} vs {}; separated/stick/slip seen {statuses:?}",
        iterations[0], iterations[1]
    );
    common::measured(
        "f1_newton_from_the_last_solution_gives_the_same_solution",
        "per-step force difference, Newton from the free motion vs from the last solution",
        worst_f,
        "≤ 1e-7",
    );
    assert!(statuses[..3].iter().all(|&seen| seen), "separation, stick and slip must all occur: {statuses:?}");
    assert!(worst_y <= 1e-9 && worst_f <= 1e-7, "velocities {worst_y:.3e}, forces {worst_f:.3e}");
    assert!(iterations[1] < iterations[0], "the nearby start should save iterations: {iterations:?}");
}

/// (C.k) The problem states its convexity limit and the summary reports that number: the academic
/// scene is limited at a contact node, the modified mass admits no step (k = 0), and the total
/// bound gives no limit.
#[test]
fn ck_limit_is_the_problems_and_the_summary_reports_it() {
    use dyncontact::problem::ConvexityLimit;
    use dyncontact::scene::{FrictionBound, MassKind};
    let p = problem(fixture("academic"));
    let ConvexityLimit::Step { k, node } = p.convexity_limit() else { panic!("{:?}", p.convexity_limit()) };
    let info = dyncontact::output::ModelInfo::of(&p);
    // exact: the summary carries the problem's number, not a recomputation
    assert_eq!((info.ck_step_limit, info.ck_limiting_node), (Some(k), Some(node)));
    // `check` prints the limit as 3.4722e-4: half a unit of its last digit
    assert!((k - 3.4722e-4).abs() <= 5e-9, "{k}");
    let mut modified = fixture("academic");
    modified.solver.mass = MassKind::Modified;
    assert!(matches!(problem(modified).convexity_limit(), ConvexityLimit::Step { k: 0.0, .. }));
    let mut total = fixture("academic");
    total.contact.as_mut().expect("contact").friction_bound = FrictionBound::Total;
    assert_eq!(problem(total).convexity_limit(), ConvexityLimit::TotalBound);
}

/// (Ck.1) The sharp test decides the condition it states, and (C.k) implies it: on academic (2-D,
/// 32 contact nodes; lumped, and consistent mass, whose (C.k) takes the lumped masses over d + 2)
/// and academic3d at 8×4×4 (40 nodes), for k from 0.5 to 4 times the (C.k)
/// limit, `sharp_convex` (a Cholesky factorization of W's tangent block) says true exactly when
/// λ_max(D^½ H_τ A_k⁻¹ H_τᵀ D^½) < 1 − δ, formed here independently of W and of its frame
/// ordering: A_k = M/k + C/2 + kK/4 assembled dense from the operators (midpoint), H_τ the
/// Cartesian tangent vectors of each contact node at its DOFs, A_k⁻¹ by nalgebra's Cholesky and
/// λ_max by a symmetric eigensolver; and it says true wherever k satisfies (C.k) (A_k ⪰ M/k, so
/// W ⪯ k M⁻¹). A λ within 1e-9 of the threshold would make the comparison a matter of round-off
/// and fails the test (the two routes agree to ~1e-12 here: W's solves and the dense ones).
#[test]
fn ck1_is_the_eigenvalue_condition_and_follows_from_ck() {
    use dyncontact::problem::ConvexityLimit;
    use dyncontact::step::delassus::{Delassus, SHARP_CONVEXITY_MARGIN, sharp_convex};
    let dense = |a: &dyncontact::linalg::SpMat| {
        let mut m = nalgebra::DMatrix::<f64>::zeros(a.nrows(), a.ncols());
        for j in 0..a.ncols() {
            for (&i, &v) in a.symbolic().row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
                m[(i, j)] += v;
            }
        }
        m
    };
    use dyncontact::scene::MassKind;
    let lumped_factors = [0.5, 0.9, 1.1, 1.3, 1.6, 2.0, 3.0, 4.0];
    for (name, cells, mass, factors) in [
        ("academic", None, MassKind::Lumped, &lumped_factors[..]),
        ("academic3d", Some(vec![8, 4, 4]), MassKind::Lumped, &lumped_factors[..]),
        // (C.k) over d + 2 is far inside: measured λ_max 0.94 at 4×
        ("academic", None, MassKind::Consistent, &[0.5, 1.0, 2.0, 4.0, 6.0, 8.0][..]),
    ] {
        let (mut sharp_inside, mut beyond_ck_inside_sharp) = (0, 0);
        for &factor in factors {
            let mut s = fixture(name);
            if let Some(c) = &cells {
                s.domain.cells = Some(c.clone());
            }
            s.solver.mass = mass;
            let limit = match problem(s.clone()).convexity_limit() {
                ConvexityLimit::Step { k, .. } => k,
                other => panic!("{name}: {other:?}"),
            };
            s.time.step = factor * limit;
            s.time.end = 10.0 * s.time.step;
            let p = problem(s);
            assert_eq!(p.model.time.scheme, dyncontact::scene::SchemeKind::Midpoint, "A_k below is the midpoint's");
            let sim = Simulation::new(&p).expect("setup");
            assert!(sim.ops.thickness.is_none(), "plane strain: A_k has no plane-stress term");
            let c = p.contact.as_ref().expect("contact");
            let Some(Delassus::Dense(w)) = sim.delassus.as_ref() else { panic!("{name}: the dense W") };
            let a_k = dense(&sim.ops.m) / p.k + dense(&sim.ops.c) * 0.5 + dense(&sim.ops.k) * (0.25 * p.k);
            let (d, n) = (c.dim, c.n());
            let scale = sim.kinematics.a_v * c.friction.as_ref().expect("friction").lipschitz() * c.p_tau.sup();
            let mut h_t = nalgebra::DMatrix::<f64>::zeros(a_k.nrows(), (d - 1) * n);
            for i in 0..n {
                for a in 0..d - 1 {
                    for (q, &dof) in c.node_dofs(i).iter().enumerate() {
                        h_t[(dof, i * (d - 1) + a)] = (scale * c.omega[i]).sqrt() * c.frames[i].tangents[a][q];
                    }
                }
            }
            let g = a_k.cholesky().expect("A_k is positive definite").solve(&h_t);
            let b = h_t.transpose() * g;
            let b = (&b + b.transpose()) * 0.5;
            let lambda_max = b.symmetric_eigenvalues().max();
            let threshold = 1.0 - SHARP_CONVEXITY_MARGIN;
            assert!(
                (lambda_max - threshold).abs() > 1e-9,
                "{name} at {factor}× (C.k): λ_max {lambda_max} at the threshold"
            );
            let sharp = sharp_convex(w, c, sim.kinematics.a_v).expect("(Ck.1) applies");
            println!("{name} k = {factor} × (C.k): λ_max {lambda_max:.6}, sharp {sharp}");
            assert_eq!(sharp, lambda_max < threshold, "{name} at {factor}× (C.k): λ_max {lambda_max}");
            if factor <= 1.0 {
                assert!(sharp, "{name}: (C.k) holds at {factor}× its limit, so (Ck.1) must");
            }
            sharp_inside += usize::from(sharp);
            beyond_ck_inside_sharp += usize::from(sharp && factor > 1.0);
        }
        assert!(
            sharp_inside < factors.len(),
            "{name}: some k must fail (Ck.1) for the comparison to test both answers"
        );
        assert!(beyond_ck_inside_sharp > 0, "{name}: (Ck.1) should admit some k beyond (C.k)");
    }
}

/// (S.6) The velocity form's preconditioner: the Cholesky factor of W⁻¹'s near field (its
/// node blocks above NEAR_FIELD_TOLERANCE of the diagonal; taken from NEAR_FIELD_FROM unknowns on, forced here)
/// in place of node blocks changes the path of conjugate gradients, not the Newton solution: on academic3d at 12×8×4 cells (324 contact unknowns;
/// pressing with half the nodes slipping outward, then shaking: slip, stick and separation), each
/// step's frozen problem solved to 1e-13 of the velocity scale both ways gives velocities within
/// 1e-12 (10× the tolerance, as the force form's comparison above) and forces within 1e-9 of the
/// largest force (through W⁻¹, ~1e3× the velocity scale's inverse: the bound above), and the near
/// field needs fewer iterations in all (it keeps ≤ 25% of W⁻¹'s entries).
#[test]
fn near_field_preconditioner_gives_the_node_block_solution() {
    let mut s = fixture("academic3d");
    s.domain.cells = Some(vec![12, 8, 4]);
    s.time.end = 0.3;
    let p = problem(s);
    let set = NewtonSettings { tolerance: 1e-13, ..NewtonSettings::default() };
    let c = p.contact.as_ref().expect("contact");
    let sim0 = Simulation::new(&p).expect("setup");
    assert!(
        !sim0.inverse.as_ref().expect("the velocity form at 324 unknowns").has_near_field(),
        "below NEAR_FIELD_FROM the run keeps node blocks"
    );
    let near = dyncontact::step::delassus::InverseDelassus::new(sim0.delassus.as_ref().expect("W"), c.dim, None)
        .expect("W⁻¹")
        .with_near_field();
    let density = near.near_field_density();
    assert!(density > 0.0 && density <= 0.25, "near field density {density}");
    let (worst_v, worst_f, statuses, fa, fb) = against_the_run(&p, sim0.delassus.as_ref().expect("W"), &near, set);
    let (ia, ib) = (fa.all_counts(), fb.all_counts());
    println!(
        "near field ({:.2}% of W⁻¹): {} iterations in {} solves; node blocks: {} in {}; worst per-step difference: velocity {worst_v:.3e}, force {worst_f:.3e}; statuses {statuses:?}",
        100.0 * density,
        ia.velocity_iterations,
        ia.velocity_solves,
        ib.velocity_iterations,
        ib.velocity_solves
    );
    common::measured(
        "near_field_preconditioner_gives_the_node_block_solution",
        "per-step force difference, near field vs node blocks",
        worst_f,
        "≤ 1e-9",
    );
    assert!(["Separated", "Stick", "Slip"].iter().all(|s| statuses.contains(*s)), "statuses seen: {statuses:?}");
    assert!(worst_v <= 1e-12 && worst_f <= 1e-9, "velocity {worst_v:.3e}, force {worst_f:.3e}");
    assert!(ia.velocity_solves > 0 && ib.velocity_solves > 0, "both ran in velocity form");
    assert!(ia.velocity_iterations < ib.velocity_iterations, "the near field saves iterations");
}

/// Each step of `p`'s run, its frozen problem solved to `set` with the run's own operators and
/// with `w` and `inverse` instead: the largest differences of the velocities (of the velocity
/// scale) and of the forces (of the largest force), the statuses seen, and the factor caches of
/// the solves with `inverse` and of the run's.
fn against_the_run(
    p: &Problem,
    w: &dyncontact::step::delassus::Delassus,
    inverse: &dyncontact::step::delassus::InverseDelassus,
    set: NewtonSettings,
) -> (f64, f64, std::collections::BTreeSet<String>, DelassusFactors, DelassusFactors) {
    let (mut worst_v, mut worst_f) = (0.0f64, 0.0f64);
    let (mut fa, mut fb) = (DelassusFactors::default(), DelassusFactors::default());
    let mut statuses = std::collections::BTreeSet::new();
    common::each_frozen_step(p, usize::MAX, set, |sim, data, _, s, _| {
        let other = StepData {
            delassus: w,
            y_free: data.y_free.clone(),
            nodes: data.nodes.clone(),
            a_d: data.a_d,
            a_v: data.a_v,
            force_rule: data.force_rule,
            law: data.law,
            friction: data.friction,
            dim: data.dim,
            inverse: Some(inverse),
        };
        let a = newton::solve(&other, &mut fa, s, &sim.state.lambda, &sim.state.t_fric, &set).expect("with `inverse`");
        let b = newton::solve(data, &mut fb, s, &sim.state.lambda, &sim.state.t_fric, &set).expect("the run's");
        statuses.extend(a.status.iter().map(|st| format!("{st:?}")));
        let ra = other.forces(&a.y, &a.lambda, &a.t);
        if linalg::norm_inf(&ra) > 0.0 {
            let vs = data.velocity_scale(&a.y).max(1e-300);
            worst_v = worst_v.max(rel(&a.y, &b.y, vs));
            worst_f = worst_f.max(rel(&ra, &data.forces(&b.y, &b.lambda, &b.t), linalg::norm_inf(&ra)));
        }
    });
    (worst_v, worst_f, statuses, fa, fb)
}

/// (S.6) The velocity form with W and W⁻¹ from the Schur complement of A_k on the contact
/// unknowns (`delassus::delassus_pair`; a run takes it from SCHUR_FROM components on, forced here)
/// gives the step solutions of W from the solves: on academic3d at 12×8×4 cells over 0.3 s
/// (pressing with half the nodes slipping outward, then shaking: slip, stick and separation),
/// each step's frozen problem solved to 1e-13 of the velocity scale both ways gives velocities
/// within 1e-12 and forces within 1e-9 of the largest force — the bounds of the preconditioner
/// comparison above (the operators themselves differ by ~1e-15).
#[test]
fn schur_delassus_gives_the_solves_step_solutions() {
    let mut s = fixture("academic3d");
    s.domain.cells = Some(vec![12, 8, 4]);
    s.time.end = 0.3;
    let p = problem(s);
    let set = NewtonSettings { tolerance: 1e-13, ..NewtonSettings::default() };
    let c = p.contact.as_ref().expect("contact");
    let sim0 = Simulation::new(&p).expect("setup");
    assert_eq!(sim0.setup_timing.delassus_route, "solves", "351 components: below SCHUR_FROM");
    let stepper = dyncontact::scheme::StepOperator::new(&sim0.ops, p.model.time.scheme, p.k).expect("A_k");
    let positions = Some(sim0.ops.positions.as_slice());
    let (w, winv) = dyncontact::step::delassus::delassus_pair(stepper.matrix().expect("A_k"), positions, c, None)
        .expect("the Schur complement");
    let w = dyncontact::step::delassus::Delassus::Dense(w);
    let inverse = dyncontact::step::delassus::InverseDelassus::new(&w, c.dim, Some(winv)).expect("W⁻¹");
    let (worst_v, worst_f, statuses, fa, _) = against_the_run(&p, &w, &inverse, set);
    println!(
        "Schur vs solves: worst per-step difference: velocity {worst_v:.3e}, force {worst_f:.3e}; statuses {statuses:?}"
    );
    common::measured(
        "schur_delassus_gives_the_solves_step_solutions",
        "per-step force difference, Schur vs solves",
        worst_f,
        "≤ 1e-9",
    );
    assert!(["Separated", "Stick", "Slip"].iter().all(|s| statuses.contains(*s)), "statuses seen: {statuses:?}");
    assert!(worst_v <= 1e-12 && worst_f <= 1e-9, "velocity {worst_v:.3e}, force {worst_f:.3e}");
    assert!(fa.all_counts().velocity_solves > 0, "the Schur run used the velocity form");
}

/// academic3d on a thin box, 22×16×2 cells (391 contact nodes, 1,173 components, cheap to
/// factor; W ill-conditioned), the dense form asked for, over 0.3 s (slip, stick and
/// separation): the problem, its dense W and the run's W⁻¹ (in the run's own forms).
fn thin_dense_box() -> (Problem, dyncontact::step::delassus::Delassus, dyncontact::step::delassus::InverseDelassus) {
    let mut s = fixture("academic3d");
    s.domain.cells = Some(vec![22, 16, 2]);
    s.solver.contact_solve = dyncontact::model::kinds::ContactSolve::Dense;
    s.time.end = 0.3;
    let p = problem(s);
    let mut sim0 = Simulation::new(&p).expect("setup");
    let w = sim0.delassus.take().expect("a dense W");
    let inverse = sim0.inverse.take().expect("velocity form");
    (p, w, inverse)
}

/// (S.6) An exact direction preconditioned by the near field lands where W is ill-conditioned:
/// its conjugate gradients stop once ‖W‖_∞ ‖ρ‖₂ (a bound of how far their residual ρ, in force
/// units, moves the momentum residual) is within 1e-13 of the velocity scale. On the thin
/// academic3d box of the test below (22×16×2 cells, 1,173 components, the dense form asked for,
/// the run's hierarchical forms; the near field forced below NEAR_FIELD_FROM, where a run keeps
/// node blocks) each step's frozen problem solved to 1e-13 of the velocity scale with the near
/// field gives the node blocks' solution: velocities within 1e-12, forces within 1e-9 of the
/// largest (the bounds of the comparisons above). Stopping relative to ‖F‖ instead (of the size
/// of ‖W ρ‖ only where W is well conditioned) left Newton's residual at 1.9e-12 of the scale
/// after 50 exact directions here.
#[test]
fn near_field_directions_land_on_an_ill_conditioned_w() {
    let (p, w, inverse) = thin_dense_box();
    let set = NewtonSettings { tolerance: 1e-13, ..NewtonSettings::default() };
    assert!(!inverse.has_near_field(), "node blocks below NEAR_FIELD_FROM");
    assert!(inverse.hierarchical().is_some(), "the hierarchical forms from HMATRIX_FROM on");
    let near = inverse.with_near_field();
    assert!(near.has_near_field(), "the near field forced");
    let (worst_v, worst_f, statuses, f_near, _) = against_the_run(&p, &w, &near, set);
    println!(
        "near field vs node blocks (thin box): worst per-step difference: velocity {worst_v:.3e}, force {worst_f:.3e}; statuses {statuses:?}"
    );
    common::measured(
        "near_field_directions_land_on_an_ill_conditioned_w",
        "per-step force difference, near field vs node blocks",
        worst_f,
        "≤ 1e-9",
    );
    assert!(["Separated", "Stick", "Slip"].iter().all(|s| statuses.contains(*s)), "statuses seen: {statuses:?}");
    assert!(worst_v <= 1e-12 && worst_f <= 1e-9, "velocity {worst_v:.3e}, force {worst_f:.3e}");
    assert!(f_near.all_counts().velocity_solves > 0, "the near-field solves used the velocity form");
}

/// (S.6) The velocity form with W⁻¹'s and W's products through their hierarchical forms
/// (`InverseDelassus::compressed`, which a run takes from HMATRIX_FROM = 400 components on)
/// gives the step solutions of the dense products (`without_compression`): on
/// academic3d at 22×16×2 cells (391 contact nodes, 1,173 components, cheap to factor; the dense W
/// asked for) over 0.3 s (slip, stick and separation), each step's frozen problem
/// solved to 1e-13 of the velocity scale both ways gives velocities within 1e-12 and forces
/// within 1e-9 of the largest force — the bounds of the comparisons above. W⁻¹ is compressed to
/// every entry within 1e-12 of its largest (the exact directions) and to the loosest certified ε
/// (1e-6 here, its error in norm within 1e-4 of its least eigenvalue: the loose ones) and
/// reaches only the Newton directions; W to 1e-14, so the residual itself moves by ~1e-14 of its
/// scale.
#[test]
fn hierarchical_delassus_gives_the_dense_step_solutions() {
    let (p, w, inverse) = thin_dense_box();
    let set = NewtonSettings { tolerance: 1e-13, ..NewtonSettings::default() };
    let share = inverse.hierarchical().map(|h| h.storage_share()).expect("the run compresses W⁻¹ from HMATRIX_FROM on");
    assert!(inverse.hierarchical_w().is_some(), "W compressed too");
    // the dense products the run's hierarchical ones are compared against
    let dense = inverse.without_compression();
    assert!(dense.hierarchical().is_none() && dense.hierarchical_w().is_none(), "dense products");
    let (worst_v, worst_f, statuses, _, f_run) = against_the_run(&p, &w, &dense, set);
    println!(
        "hierarchical ({share:.3} of W⁻¹'s values) vs dense: worst per-step difference: velocity {worst_v:.3e}, force {worst_f:.3e}; statuses {statuses:?}"
    );
    common::measured(
        "hierarchical_delassus_gives_the_dense_step_solutions",
        "per-step force difference, hierarchical vs dense products",
        worst_f,
        "≤ 1e-9",
    );
    assert!(["Separated", "Stick", "Slip"].iter().all(|s| statuses.contains(*s)), "statuses seen: {statuses:?}");
    assert!(share < 1.0, "the far field compressed: {share:.3} of the dense values");
    assert!(worst_v <= 1e-12 && worst_f <= 1e-9, "velocity {worst_v:.3e}, force {worst_f:.3e}");
    assert!(f_run.all_counts().velocity_solves > 0, "the hierarchical run used the velocity form");
}
