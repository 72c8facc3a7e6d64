//! Closed-form benchmarks of spec/model.md §7: the bar hitting a rigid wall (B.1), the bar hitting
//! a compliant layer of finite depth, exactly and with the penalty (B.2), and the block
//! sliding with velocity-weakening friction (B.3). Each scene is a fixture with its closed
//! form derived in its header; each test states the tolerance the mesh and the step allow.

use crate::common;

use common::{fixture, mean_velocity_x, problem, records};
use dyncontact::reference::{CompliantLayer, bar_impact_force, sliding_block_velocity};
use dyncontact::scene::EnforcementKind as Enforcement;
use dyncontact::simulation::{Simulation, StepRecord};

/// Mean of a column over the records with t in [t0, t1].
fn mean_over(recs: &[StepRecord], t0: f64, t1: f64, f: impl Fn(&StepRecord) -> f64) -> f64 {
    let sel: Vec<f64> = recs.iter().filter(|r| r.t >= t0 && r.t <= t1).map(f).collect();
    sel.iter().sum::<f64>() / sel.len() as f64
}

/// (B.1) Bar on a rigid wall: over the contact interval the mean contact force is ρ c v0 per
/// unit height, contact ends at 2L/c, and the bar leaves with speed v0.
///
/// Tolerances: the force is compared in the mean over [0.1, 1.9] because the midpoint rule
/// with exact enforcement makes the contact force alternate from step to step (the midpoint
/// chatter; the impulse per pair of steps is right): 1% — the dispersion of 100 P1 cells at
/// c k/h = 0.25 smears the wave fronts over a few cells, ~1% of the bar. Release time within
/// 2 h/c + 2k (the front crosses a cell in h/c). Exit speed within 1%: the constraint
/// dissipation of the impact (0.77% of the energy, measured) costs 0.4% of the speed.
#[test]
fn b1_bar_impact_matches_closed_form() {
    let p = problem(fixture("bar_impact"));
    let recs = records(&p);
    let (rho, young, length, height, v0) = (1.0, 1.0, 1.0, 0.1, 0.1);
    let expected = bar_impact_force(rho, young, length, v0, 1.0) * height;
    let mean = mean_over(&recs, 0.1, 1.9, |r| r.normal_force);
    let release = recs
        .iter()
        .filter(|r| r.t > 1.0)
        .find(|r| r.normal_force == 0.0)
        .map(|r| r.t)
        .expect("the bar leaves the wall");
    let c = (young / rho).sqrt();
    let h = length / 100.0;
    // exit speed from the kinetic energy after release (the bar moves rigidly, up to the
    // small elastic vibration left by the discrete wave)
    let last = recs.last().expect("records");
    let v_exit = (2.0 * last.energy.kinetic / (rho * length * height)).sqrt();
    println!(
        "B.1: mean force {mean:.6e} (closed form {expected:.6e}, {:+.3}%), release at {release:.4} (2L/c = {:.4}), exit speed {v_exit:.5} (v0 = {v0}), constraint dissipation {:.3e} of {:.3e}",
        100.0 * (mean / expected - 1.0),
        2.0 * length / c,
        last.energy.constraint_dissipation,
        0.5 * rho * length * height * v0 * v0
    );
    common::measured(
        "analytic::b1_bar_impact_matches_closed_form",
        "B.1 mean contact force, relative error",
        mean / expected - 1.0,
        "|·| ≤ 1e-2",
    );
    common::measured(
        "analytic::b1_bar_impact_matches_closed_form",
        "B.1 exit speed / v0 − 1",
        v_exit / v0 - 1.0,
        "|·| ≤ 1e-2",
    );
    assert!((mean / expected - 1.0).abs() <= 0.01, "mean contact force off by more than 1%");
    assert!((release - 2.0 * length / c).abs() <= 2.0 * h / c + 2.0 * p.k, "release time {release}");
    assert!((v_exit / v0 - 1.0).abs() <= 0.01, "exit speed {v_exit}");
}

/// (B.1) (E.1) The energy lost at the impact (the constraint dissipation of exact
/// enforcement) is the kinetic energy of the contact node stopped by the wall: it falls like
/// h under refinement at a fixed Courant number c k/h = 0.25 (order 1 ± 0.1), and it does
/// *not* fall with k alone at fixed h (spec/model.md §6 expected it would; measured: it grows by
/// ~15% per halving of k at 100 cells — pinned here as the scheme's known behaviour).
#[test]
fn b1_impact_dissipation_falls_with_h_not_with_k() {
    let run = |cells: i64, k: f64| {
        let mut s = fixture("bar_impact");
        s.domain.cells = Some([cells, 1].to_vec());
        s.time.step = k;
        s.time.end = 2.5;
        records(&problem(s)).last().expect("records").energy.constraint_dissipation
    };
    let by_h: Vec<f64> = [50, 100, 200].iter().map(|&c| run(c, 0.25 / c as f64)).collect();
    let orders: Vec<f64> = by_h.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
    let by_k: Vec<f64> = [5e-3, 2.5e-3, 1.25e-3].iter().map(|&k| run(100, k)).collect();
    println!("B.1 impact dissipation, h = 1/50, 1/100, 1/200 at c k/h = 0.25: {by_h:?}, orders {orders:?}");
    println!("B.1 impact dissipation at h = 1/100, k = 5e-3, 2.5e-3, 1.25e-3: {by_k:?}");
    common::measured(
        "analytic::b1_impact_dissipation_falls_with_h_not_with_k",
        "B.1 impact dissipation order in h",
        orders[orders.len() - 1],
        "1 ± 0.1",
    );
    assert!(orders.iter().all(|o| (o - 1.0).abs() <= 0.1), "impact dissipation is not O(h): {orders:?}");
    assert!(by_k[2] >= by_k[0], "at fixed h the dissipation now falls with k — update the documentation: {by_k:?}");
}

fn layer() -> CompliantLayer {
    CompliantLayer { rho: 1.0, young: 100.0, v0: 1.0, k_n: 200.0, g: 0.03 }
}

/// (B.2) (P.5) (S.4) Bar on a compliant layer of depth g, exact enforcement: the penetration
/// follows v0 τ (1 − e^{−t/τ}) until it reaches g, then stays at g, and the mean total
/// reaction is ρ c v0 per unit height.
///
/// Tolerances: penetration within 0.5% of g: 400 cells at c k/h = 0.4 resolve τ = 0.05 with 500
/// steps and the wall node sees the bar's impedance up to dispersion; the bound g is exact
/// (round-off). Mean reaction over [0.08, 0.18] within 1%, as in B.1.
#[test]
fn b2_compliant_layer_penetration_matches_closed_form() {
    let p = problem(fixture("compliant_layer"));
    let recs = records(&p);
    let l = layer();
    let height = 0.05;
    let mut worst: f64 = 0.0;
    for r in recs.iter().filter(|r| r.t <= 0.18) {
        worst = worst.max((r.max_penetration - l.penetration_exact(r.t)).abs());
        assert!(r.max_penetration <= l.g * (1.0 + 1e-12), "penetration {} beyond g at t = {}", r.max_penetration, r.t);
    }
    let mean = mean_over(&recs, 0.08, 0.18, |r| r.normal_force) / height;
    println!(
        "B.2 exact: worst |δ_h − δ| = {worst:.3e} ({:.3}% of g), t* = {:.5}, mean reaction {mean:.5} (ρ c v0 = {:.5})",
        100.0 * worst / l.g,
        l.t_star().unwrap_or(f64::NAN),
        l.impedance() * l.v0
    );
    common::measured(
        "analytic::b2_compliant_layer_penetration_matches_closed_form",
        "B.2 penetration error / g",
        worst / l.g,
        "≤ 5e-3",
    );
    assert!(worst <= 5e-3 * l.g, "penetration off the closed form by {worst:.3e}");
    assert!((mean / (l.impedance() * l.v0) - 1.0).abs() <= 0.01, "mean reaction {mean}");
}

/// (B.2) (Pe.5) With the penalty ε, the overshoot beyond g tends to
/// e_∞ = ε(ρcv0 − k_n g)/(1 + ε k_n): the largest overshoot before the reflected wave returns
/// matches e_∞ (1 − e^{−(t−t*)/τ_ε}) within 2% (as above, plus the discrete t*), for
/// ε = 1e-3 and 1e-4, so it falls like ε.
#[test]
fn b2_penalty_overshoot_matches_closed_form() {
    let l = layer();
    let mut over = Vec::new();
    for eps in [1e-3, 1e-4] {
        let mut s = fixture("compliant_layer");
        let c = s.contact.as_mut().expect("contact");
        c.enforcement = Enforcement::Penalty;
        c.penalty = Some(eps);
        let recs = records(&problem(s));
        let (mut worst, mut peak): (f64, f64) = (0.0, 0.0);
        for r in recs.iter().filter(|r| r.t <= 0.18) {
            worst = worst.max((r.max_penetration - l.penetration_penalty(eps, r.t)).abs());
            peak = peak.max(r.max_penetration - l.g);
        }
        let e_inf = l.penalty_overshoot_limit(eps);
        println!(
            "B.2 penalty ε = {eps:e}: peak overshoot {peak:.5e}, e_∞ = {e_inf:.5e} ({:+.3}%), worst |δ_h − δ_ε| = {worst:.3e}",
            100.0 * (peak / e_inf - 1.0)
        );
        common::measured(
            "analytic::b2_penalty_overshoot_matches_closed_form",
            &format!("B.2 penalty overshoot / e_∞ − 1 (ε = {eps:e})"),
            peak / e_inf - 1.0,
            "|·| ≤ 2e-2",
        );
        assert!((peak / e_inf - 1.0).abs() <= 0.02, "overshoot {peak:.4e} vs e_∞ {e_inf:.4e}");
        assert!(worst <= 5e-3 * l.g + 0.02 * e_inf, "penetration history off by {worst:.3e}");
        over.push(peak);
    }
    // e_∞ = ε(ρcv0 − k_n g)/(1 + εk_n) is O(ε) but not exactly linear: its own slope between
    // 1e-3 and 1e-4 is 0.929; the two 2% bounds above allow log10(1.02²) = 0.017 around it
    let slope = (over[0] / over[1]).log10();
    let exact = (l.penalty_overshoot_limit(1e-3) / l.penalty_overshoot_limit(1e-4)).log10();
    println!("B.2 penalty: log-log slope of the overshoot in ε: {slope:.4} (closed form {exact:.4})");
    assert!((slope - exact).abs() <= 0.017, "overshoot slope {slope} vs closed form {exact}");
}

/// (B.3) (P.6) The pulled block slides with the closed-form velocity
/// v(s) = (1/α) ln[(c2 + (c1 − c2) e^{α c1 s/m})/c1] (spec/model.md §7.3): within 3e-3 absolute
/// (2% of the velocity at s = 0.2) over s ∈ [0, 0.2]. The bound: the block's elastic
/// transient (~1 ms) shifts the start by at most 1 ms × the largest acceleration c1/m = 2,
/// i.e. 2e-3, and the rocking mode the pull excites modulates N by ±20% at a 3 ms period,
/// which averages to ~1e-3 in v (measured).
#[test]
fn b3_sliding_block_matches_closed_form() {
    let p = problem(fixture("sliding_block"));
    let mut sim = Simulation::new(&p).expect("setup");
    let (m, n, ft, a, b, alpha, t0) = (2.0, 10.0, 7.0, 0.6, 0.3, 20.0, 0.1);
    let mut worst: f64 = 0.0;
    let mut steps = sim.steps();
    while let Some(rec) = steps.next() {
        let rec = rec.expect("step");
        if rec.t >= t0 {
            let exact = sliding_block_velocity(m, n, ft, a, b, alpha, rec.t - t0);
            worst = worst.max((mean_velocity_x(steps.simulation()) - exact).abs());
        }
    }
    let v_end = mean_velocity_x(&sim);
    let exact_end = sliding_block_velocity(m, n, ft, a, b, alpha, p.time(sim.state.n) - t0);
    println!("B.3: worst |v_h − v| = {worst:.3e}; at the end v_h = {v_end:.5}, closed form {exact_end:.5}");
    common::measured(
        "analytic::b3_sliding_block_matches_closed_form",
        "B.3 sliding velocity error (absolute)",
        worst,
        "≤ 3e-3",
    );
    assert!(worst <= 3e-3, "sliding velocity off the closed form by {worst:.3e}");
}

/// (B.3) Below the static threshold (F_t = 5.5 ≤ N a = 6) the block stays stuck: its mean
/// velocity stays within the elastic vibration of the loading (≤ 1e-4, against 0.33 when
/// sliding), and every contact node sticks at the end. The pull is ramped smoothly: a sudden
/// pull excites the rocking mode (N varies by ±20%), the unloaded trailing edge breaks away
/// first and, with velocity weakening, the block then slides below μ(0)N — measured, and
/// physical for an elastic block, but outside the rigid-block closed form.
#[test]
fn b3_block_sticks_below_the_static_threshold() {
    let mut s = fixture("sliding_block");
    s.loads.body.as_mut().expect("the fixture gives a body force")[0] =
        "27.5*if(t < 0.1, 0, if(t < 0.15, 0.5*(1 - cos(pi*(t - 0.1)/0.05)), 1))".into();
    let p = problem(s);
    let mut sim = Simulation::new(&p).expect("setup");
    let mut worst: f64 = 0.0;
    let mut last = None;
    let mut steps = sim.steps();
    while let Some(rec) = steps.next() {
        last = Some(rec.expect("step"));
        worst = worst.max(mean_velocity_x(steps.simulation()).abs());
    }
    let last = last.expect("steps");
    println!(
        "B.3 stuck: largest |mean velocity| {worst:.3e}; stick nodes at the end {} of {}",
        last.stick_nodes,
        last.nodes.len()
    );
    assert_eq!(sliding_block_velocity(2.0, 10.0, 5.5, 0.6, 0.3, 20.0, 0.1), 0.0);
    assert!(worst <= 1e-4, "the block moved: {worst:.3e}");
    assert_eq!(last.stick_nodes, last.nodes.len());
}

/// (B.4) Hertz: a rigid cylinder (R = 10) indenting an elastic block, Signorini, quasi-static
/// (fixtures/scenes/hertz.toml). At the end the total contact force equals the load P = 7.77
/// (0.1%: the kinetic energy is ~1e-9 of the elastic, equilibrium), the contact zone's
/// half-width is within one cell of a = 0.300, and the nodal pressure q + λ is within 5% of p0
/// of p0 sqrt(1 − s²/a²) at every node — the finite depth (6.7 a, not a half-space) and
/// h = a/9.6 allow a few percent (measured 2%).
#[test]
fn b4_hertz_pressure_matches_closed_form() {
    let p = problem(fixture("hertz"));
    let recs = records(&p);
    let last = recs.last().expect("records");
    let c = p.contact.as_ref().expect("contact");
    let (load, radius, h) = (7.77, 10.0, 4.0 / 128.0);
    let (a, p0) = (
        dyncontact::reference::hertz_pressure(load, radius, 1000.0, 0.3, 0.0).0,
        dyncontact::reference::hertz_pressure(load, radius, 1000.0, 0.3, 0.0).1,
    );
    let (mut worst, mut half_width): (f64, f64) = (0.0, 0.0);
    for (i, n) in last.nodes.iter().enumerate() {
        let s = p.mesh.plane().expect("a 2-D mesh").nodes[c.nodes[i]][0] - 2.0;
        let (_, exact) = dyncontact::reference::hertz_pressure(load, radius, 1000.0, 0.3, s);
        worst = worst.max((n.p + n.lambda - exact).abs());
        if n.p + n.lambda > 0.0 {
            half_width = half_width.max(s.abs());
        }
    }
    println!(
        "B.4: total force {:.5} (P = {load}), half-width {half_width:.4} (a = {a:.4}, h = {h:.4}), worst |p_h − p| = {worst:.4} ({:.2}% of p0 = {p0:.3}), kinetic/elastic {:.1e}",
        last.normal_force,
        100.0 * worst / p0,
        last.energy.kinetic / last.energy.elastic
    );
    common::measured(
        "analytic::b4_hertz_pressure_matches_closed_form",
        "B.4 pressure error / p0",
        worst / p0,
        "≤ 5e-2",
    );
    assert!((last.normal_force / load - 1.0).abs() <= 1e-3, "total force {}", last.normal_force);
    assert!(half_width <= a && half_width >= a - h, "contact half-width {half_width} vs a = {a}");
    assert!(worst <= 0.05 * p0, "pressure off by {worst:.4} ({:.2}% of p0)", 100.0 * worst / p0);
}
