//! Coulomb friction with the whole contact force (`friction_bound = "total"`): the
//! Signorini–Coulomb branch of the model (compliance 0, g = 0), its refusal where friction
//! would silently vanish, and where the friction bound is evaluated (`friction_bound_at`).
//!
//! Closed forms: the sliding block of spec/model.md §7.3 (B.3) with N the whole normal force,
//! and a bar hitting a rigid wall obliquely, where Coulomb's law fixes the tangential force at
//! μ times the normal force while the face slips and momentum balance fixes the tangential
//! impulse exactly.

use crate::common;

use common::{fixture, mean_velocity_x, problem, records};
use dyncontact::linalg;
use dyncontact::reference::sliding_block_velocity;
use dyncontact::scene::{BoundAt, FrictionBound, FrictionLaw, NumOrStr, Scene};
use dyncontact::simulation::Simulation;
use dyncontact::step::NodeStatus;
use dyncontact::step::fixed_point::Inner;
use dyncontact::step::newton::NewtonSettings;

/// The sliding block of B.3 on a rigid foundation (Signorini, g = 0) with Coulomb friction
/// bounded by the whole contact force.
fn signorini_coulomb_block() -> Scene {
    let mut s = fixture("sliding_block");
    let c = s.contact.as_mut().expect("contact");
    c.compliance = 0.0;
    c.penetration_bound = NumOrStr::Num(0.0);
    c.friction_bound = FrictionBound::Total;
    s
}

/// (Co.1) A scene with friction whose compliance bound is identically zero (compliance 0) is
/// refused, and the message names `friction_bound = "total"`.
#[test]
fn co1_friction_on_a_zero_compliance_bound_is_refused() {
    for bound in [FrictionBound::Capped, FrictionBound::Uncapped] {
        let mut s = signorini_coulomb_block();
        s.contact.as_mut().expect("contact").friction_bound = bound;
        let e = s.validate().expect_err("refused").to_string();
        println!("{e}");
        assert!(e.starts_with("contact.friction_bound:"), "names the key: {e}");
        assert!(e.contains("friction_bound = \"total\""), "names the remedy: {e}");
    }
    // frictionless Signorini stays valid
    let mut s = signorini_coulomb_block();
    let c = s.contact.as_mut().expect("contact");
    c.friction_bound = FrictionBound::Capped;
    c.friction.law = FrictionLaw::None;
    (c.friction.static_, c.friction.kinetic, c.friction.decay) = (None, None, None);
    s.validate().expect("frictionless Signorini is valid");
}

/// (Co.1) (B.3) On the Signorini–Coulomb branch every slipping node carries t_i = μ(|v̄_i|)(q_i + λ_i)
/// (to 1e-6 of the step's largest S: the fixed point stops when S moves by less than 1e-8 of that
/// scale, or y by less than 1e-8 of its scale, which moves S by μ' a_v Δy N ≪ 1e-6), and the pulled
/// block follows the rigid-block closed form with N the whole normal force within 5e-3 absolute
/// (1.5% of the final 0.33 m/s). The rigid-block form ignores the elastic start-up: on a rigid
/// foundation it lasts two shear-wave transits of the height (2 × 0.2 m / 196 m/s = 2 ms) at an
/// acceleration up to c1/m = 2 m/s², i.e. up to 4e-3; the shear vibration it leaves spreads the
/// nodal slip rates, and with a convex μ(v) the mean friction is below μ(v̄)N (measured: a
/// further 1.1e-3 over the slide; 4.2e-3 in all).
#[test]
fn co1_b3_signorini_coulomb_block_slides_with_closed_form() {
    let p = problem(signorini_coulomb_block());
    let mut sim = Simulation::new(&p).expect("setup");
    let (m, n, ft, a, b, alpha, t0) = (2.0, 10.0, 7.0, 0.6, 0.3, 20.0, 0.1);
    let mu = |r: f64| (a - b) * (-alpha * r).exp() + b;
    let (mut worst, mut law_defect): (f64, f64) = (0.0, 0.0);
    let mut steps = sim.steps();
    while let Some(rec) = steps.next() {
        let rec = rec.expect("step");
        if rec.t >= t0 {
            let exact = sliding_block_velocity(m, n, ft, a, b, alpha, rec.t - t0);
            worst = worst.max((mean_velocity_x(steps.simulation()) - exact).abs());
            // Coulomb's law node by node: a slipping node carries t = S = μ(|v̄|)(q + λ)
            let s_scale = rec.nodes.iter().map(|nr| nr.bound).fold(0.0, f64::max);
            for nr in rec.nodes.iter().filter(|nr| nr.status == NodeStatus::Slip) {
                let s_law = mu(nr.v_t.abs()) * (nr.p + nr.lambda);
                law_defect =
                    law_defect.max((nr.friction.abs() - nr.bound).abs().max((nr.bound - s_law).abs()) / s_scale);
            }
        }
    }
    println!(
        "Signorini–Coulomb B.3: worst |v_h − v| = {worst:.3e}, final v_h = {:.5}; Coulomb law defect {law_defect:.2e}",
        mean_velocity_x(&sim)
    );
    common::measured(
        "coulomb::co1_b3_signorini_coulomb_block_slides_with_closed_form",
        "B.3 Signorini–Coulomb velocity error",
        worst,
        "≤ 5e-3",
    );
    assert!(law_defect <= 1e-6, "a slipping node is off Coulomb's law by {law_defect:.2e}");
    assert!(worst <= 5e-3, "sliding velocity off the closed form by {worst:.3e}");
}

/// (Co.1) (B.3) Below the static threshold (F_t = 5.5 ≤ μ(0) N = 6) the block on the rigid
/// foundation stays stuck: |mean velocity| ≤ 1e-4 (the elastic vibration of the loading; 0.33
/// when sliding) and every node in contact sticks at the end.
#[test]
fn co1_b3_signorini_coulomb_block_sticks_below_threshold() {
    let mut s = signorini_coulomb_block();
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
        "stuck: largest |mean velocity| {worst:.3e}; stick {} of {} in contact",
        last.stick_nodes, last.contact_nodes
    );
    assert!(worst <= 1e-4, "the block moved: {worst:.3e}");
    assert!(last.contact_nodes > 0 && last.stick_nodes == last.contact_nodes, "not every contact node sticks");
}

/// (Co.1) A bar hits a rigid wall obliquely (normal speed v0 = 0.1, tangential w0 = 0.2, μ = 0.3,
/// Signorini–Coulomb): on every step where the face slips, the tangential force is μ times the
/// normal force (to the fixed-point tolerance 1e-8, relative, with margin: 1e-6), and the body's
/// tangential momentum changes by exactly the tangential impulse k F_τ τ_y of each step (lumped
/// mass, free body: the elastic and viscous forces sum to zero over a rigid mode; round-off).
#[test]
fn co1_oblique_bar_impact_slips_with_coulomb_force() {
    let mut s = fixture("bar_impact");
    s.initial.velocity = Some(vec!["-0.1".into(), "0.2".into()]);
    let c = s.contact.as_mut().expect("contact");
    c.friction_bound = FrictionBound::Total;
    c.friction.law = FrictionLaw::Constant;
    c.friction.coefficient = Some(0.3);
    let p = problem(s);
    let recs = records(&p);
    let peak = recs.iter().map(|r| r.normal_force).fold(0.0, f64::max);
    let mut slipping_steps = 0;
    for r in &recs {
        if r.contact_nodes > 0 && r.slip_nodes == r.contact_nodes && r.normal_force > 1e-2 * peak {
            slipping_steps += 1;
            let ratio = r.tangential_force.abs() / (0.3 * r.normal_force);
            assert!((ratio - 1.0).abs() <= 1e-6, "step {}: |F_t| / (μ F_n) = {ratio}", r.step);
        }
    }
    assert!(slipping_steps > 100, "the face should slip through the impact ({slipping_steps} steps)");
    // momentum: P_y(t_{n+1}) − P_y(t_n) = k (force on the body)_y; τ = (−ν_2, ν_1) = (0, −1) on the left side
    let mut sim = Simulation::new(&p).expect("setup");
    let momentum_y = |sim: &Simulation| -> f64 {
        sim.ops.m_lumped.iter().zip(&sim.state.v).skip(1).step_by(2).map(|(m, v)| m * v).sum()
    };
    let p0 = momentum_y(&sim);
    let (mut impulse, mut worst) = (0.0, 0.0f64);
    let mut steps = sim.steps();
    while let Some(rec) = steps.next() {
        let rec = rec.expect("step");
        impulse -= p.k * rec.tangential_force; // τ_y = −1
        worst = worst.max((momentum_y(steps.simulation()) - p0 - impulse).abs());
    }
    let scale: f64 = 0.1 * 0.2; // m w0 (ρ = 1, area 0.1)
    println!(
        "oblique impact: {slipping_steps} slipping steps, tangential impulse {impulse:.6e}, worst momentum defect {worst:.3e}"
    );
    assert!(impulse < 0.0, "friction opposes the +y slip");
    // round-off of sums over 202 nodes accumulated over 1200 steps: far below 1e-10 of m w0
    assert!(worst <= 1e-10 * scale, "momentum defect {worst:.3e}");
}

/// (Co.2) (E.1) With the bound at u_ν^{n+½} of the iterate (`friction_bound_at = "midpoint"`) and
/// with the total bound on a compliant foundation, the discrete energy balance holds at every
/// step to 1e-10 of the energy scale (the last convex solve's frozen S is the S booked in the
/// friction dissipation; round-off and solver tolerance are ~1e-13 here). Reported: the friction
/// dissipation against the predictor's (the evaluation points differ by O(k²); the total bound
/// adds the constraint force λ to the normal part, so it differs by more).
#[test]
fn co2_bound_at_midpoint_and_total_keep_the_energy_balance() {
    let base = {
        let mut s = fixture("impact_friction");
        s.time.end = 0.15;
        s
    };
    let predictor = records(&problem(base.clone()));
    for (what, edit) in [
        (
            "midpoint",
            (|c: &mut dyncontact::scene::Contact| c.friction_bound_at = BoundAt::Midpoint)
                as fn(&mut dyncontact::scene::Contact),
        ),
        ("total", |c: &mut dyncontact::scene::Contact| c.friction_bound = FrictionBound::Total),
    ] {
        let mut s = base.clone();
        edit(s.contact.as_mut().expect("contact"));
        let recs = records(&problem(s));
        let worst =
            recs.iter().map(|r| r.energy.residual.abs() / r.energy_scale.max(f64::MIN_POSITIVE)).fold(0.0, f64::max);
        let friction =
            |rs: &[dyncontact::simulation::StepRecord]| rs.last().expect("records").energy.friction_dissipation;
        let change = (friction(&recs) - friction(&predictor)).abs() / friction(&predictor);
        println!(
            "{what}: largest (E.1) defect {worst:.2e}; friction dissipation {:.6e} vs predictor {:.6e} ({change:.2e})",
            friction(&recs),
            friction(&predictor)
        );
        assert!(worst <= 1e-10, "{what}: (E.1) defect {worst:.2e}");
        assert!(friction(&recs) > 0.0, "{what}: friction acts");
    }
}

/// (Co.3) The coupled Alart–Curnier Newton (`newton-unfrozen` with the total bound: the disk
/// radius follows the normal force) and the fixed point on S (F.1) give the same solution of
/// every step of the Signorini–Coulomb scenes, solved from the same state (the F.1 trajectory):
/// contact velocities and forces agree to 1e-6 of the step's scales (both solve to 1e-10 in
/// velocity and F.1 stops when S moves by less than 1e-8), and the coupled Newton needs no
/// fallback. In 3-D (the sliding_block3d fixture as a Signorini–Coulomb block, pulled at 30° to
/// the mesh axes) ∂t/∂N = μ ẑ couples the normal unknown to both tangential components.
#[test]
fn co3_coupled_newton_agrees_with_the_fixed_point() {
    let oblique = {
        let mut s = fixture("bar_impact");
        s.time.end = 1.0;
        s.initial.velocity = Some(vec!["-0.1".into(), "0.2".into()]);
        let c = s.contact.as_mut().expect("contact");
        c.friction_bound = FrictionBound::Total;
        c.friction.law = FrictionLaw::Constant;
        c.friction.coefficient = Some(0.3);
        s
    };
    let block = {
        let mut s = signorini_coulomb_block();
        s.time.end = 0.15;
        s
    };
    let block3d = {
        let mut s = fixture("sliding_block3d");
        s.time.end = 0.2;
        let c = s.contact.as_mut().expect("contact");
        c.compliance = 0.0;
        c.penetration_bound = NumOrStr::Num(0.0);
        c.friction_bound = FrictionBound::Total;
        s
    };
    let set = NewtonSettings::default();
    for (name, scene) in [("oblique impact", oblique), ("block", block), ("block 3-D", block3d)] {
        let p = problem(scene);
        let c = p.contact.as_ref().expect("contact");
        let mut sim = Simulation::new(&p).expect("setup");
        let (mut worst, mut fallbacks, mut it_f1, mut it_c) = (0.0f64, 0, 0, 0);
        let mut steps = sim.steps();
        // the comparison's own factor cache: re-solving a step leaves the run's path alone
        let mut factors = dyncontact::step::delassus::DelassusFactors::default();
        loop {
            let sim = steps.simulation();
            let (v_free, _) = sim.free_velocity();
            let (data, p_hat) = sim.step_data(c.restrict(&v_free)).expect("contact data");
            let (f1, _, r1) =
                sim.solve_frozen_sequence(&data, &mut factors, &p_hat, &Inner::Newton(set), None).expect("F.1");
            let (co, _, r2) = sim
                .solve_frozen_sequence(&data, &mut factors, &p_hat, &Inner::NewtonUnfrozen(set), None)
                .expect("coupled");
            (it_f1, it_c) = (it_f1 + r1.inner_iterations, it_c + r2.inner_iterations);
            fallbacks += usize::from(r2.fallback.is_some());
            let vs = data.velocity_scale(&f1.y).max(1e-300);
            let (ra, rb) = (data.forces(&f1.y, &f1.lambda, &f1.t), data.forces(&co.y, &co.lambda, &co.t));
            let fs = linalg::norm_inf(&ra).max(1e-300);
            let dv = f1.y.iter().zip(&co.y).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / vs;
            let df = ra.iter().zip(&rb).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / fs;
            worst = worst.max(dv).max(df);
            match steps.next() {
                Some(rec) => drop(rec.expect("step")),
                None => break,
            }
        }
        println!(
            "{name}: worst difference {worst:.2e}; {fallbacks} fallbacks; Newton iterations F.1 {it_f1}, coupled {it_c}"
        );
        common::measured(
            "coulomb::co3_coupled_newton_agrees_with_the_fixed_point",
            &format!("Co.3 vs F.1 per step, {name}"),
            worst,
            "≤ 1e-6",
        );
        assert!(worst <= 1e-6, "{name}: F.1 and the coupled Newton differ by {worst:.2e}");
        assert_eq!(fallbacks, 0, "{name}: the coupled Newton fell back to F.1");
    }
}
