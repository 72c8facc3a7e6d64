//! (V.1) (V.2) The computed steps satisfy the discrete variational inequalities of spec/model.md §3:
//! for random test functions z (admissible ones for V.2), the margin
//! R(z) + Σ ω p_τ ψ⁰(v̄_τ; z_τ) is ≥ 0 (see src/variational.rs).
//!
//! Tolerance: −1e-7 of the margin's scale. The inequality is exact for the solution of the
//! unfrozen problem; the computed step satisfies it up to the fixed point's tolerance (S is
//! μ(|v̄|) p_τ to 1e-8 relative) and the Newton tolerance (1e-10 on velocities).

use crate::common;

use common::{fixture, problem};
use dyncontact::scene::EnforcementKind as Enforcement;
use dyncontact::simulation::Simulation;
use dyncontact::variational::{StepPair, admissible, hemivariational_margin, variational_margin};

/// xorshift64*: reproducible random test functions without a dependency.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
    fn vector(&mut self, n: usize) -> Vec<f64> {
        (0..n).map(|_| self.next()).collect()
    }
}

/// Run `p` and check every step with `per_step` random test functions: the margin of (V.2) for
/// admissible z when `exact` (and the bite: pushing a node on the constraint further in gives
/// exactly −ω λ), of (V.1) for any z otherwise; each margin ≥ −1e-7 of its scale. Returns
/// (smallest relative margin, test functions checked, bites checked).
fn check_steps(p: &dyncontact::problem::Problem, seed: u64, per_step: usize, exact: bool) -> (f64, usize, usize) {
    let mut sim = Simulation::new(p).expect("setup");
    let mut rng = Rng(seed);
    let (mut worst, mut checked, mut bites) = (f64::INFINITY, 0usize, 0usize);
    let c = p.contact.as_ref().expect("contact");
    let (mut u0, mut v0, mut s0) = (sim.state.u.clone(), sim.state.v.clone(), sim.state.eps_zz.clone());
    let mut steps = sim.steps();
    while let Some(rec) = steps.next() {
        let rec = rec.expect("step");
        let sim = steps.simulation();
        let pair = StepPair { sim, u_before: &u0, v_before: &v0, eps_zz_before: &s0 };
        for _ in 0..per_step {
            let mut z = rng.vector(p.dofs.n_free);
            if exact {
                admissible(&pair, &mut z);
            }
            let (m, scale) = if exact { variational_margin(&pair, &z) } else { hemivariational_margin(&pair, &z) };
            worst = worst.min(m / scale);
            assert!(m >= -1e-7 * scale, "step {}: margin {m:.3e} (scale {scale:.3e})", sim.state.n);
            checked += 1;
        }
        if let Some(i) = rec.nodes.iter().position(|n| n.lambda > 0.0).filter(|_| exact) {
            let mut z = vec![0.0; p.dofs.n_free];
            let n = c.frames[i].normal;
            for (k, &dof) in c.node_dofs(i).iter().enumerate() {
                z[dof] = n[k];
            }
            let (m, scale) = variational_margin(&pair, &z);
            let expected = -c.omega[i] * rec.nodes[i].lambda;
            assert!(
                (m - expected).abs() <= 1e-8 * scale,
                "inadmissible z: margin {m:.6e}, expected −ωλ = {expected:.6e}"
            );
            bites += 1;
        }
        (u0, v0, s0) = (sim.state.u.clone(), sim.state.v.clone(), sim.state.eps_zz.clone());
    }
    (worst, checked, bites)
}

/// (V.1) Problem P_ε (penalty ε = 1e-4) on the frictional impact: every step satisfies the
/// discrete hemivariational inequality for 20 random z ∈ V^h (margin ≥ −1e-7 of its scale).
#[test]
fn v1_penalty_steps_satisfy_the_hemivariational_inequality() {
    let mut s = fixture("impact_friction");
    let c = s.contact.as_mut().expect("contact");
    c.enforcement = Enforcement::Penalty;
    c.penalty = Some(1e-4);
    let p = problem(s);
    let (worst, checked, _) = check_steps(&p, 0x9e37_79b9_7f4a_7c15, 20, false);
    println!("V.1: {checked} random test functions, smallest relative margin {worst:.3e}");
    common::measured(
        "variational::v1_penalty_steps_satisfy_the_hemivariational_inequality",
        "V.1 smallest relative margin",
        worst,
        "≥ −1e-7",
    );
}

/// (V.2) Problem P (exact constraint) on the frictional impact: every step satisfies the
/// discrete variational–hemivariational inequality for 20 random admissible z
/// (u_ν^{n+1} + z_ν ≤ g), margin ≥ −1e-7 of its scale; and the test bites — pushing a node on
/// the constraint further in (an inadmissible z) gives a negative margin of exactly −ω λ.
#[test]
fn v2_exact_steps_satisfy_the_variational_inequality() {
    let p = problem(fixture("impact_friction"));
    let (worst, checked, bites) = check_steps(&p, 0x0123_4567_89ab_cdef, 20, true);
    assert!(bites > 0, "the constraint was never active");
    println!(
        "V.2: {checked} admissible random test functions, smallest relative margin {worst:.3e}; {bites} inadmissible checks gave −ωλ"
    );
    common::measured(
        "variational::v2_exact_steps_satisfy_the_variational_inequality",
        "V.2 smallest relative margin",
        worst,
        "≥ −1e-7",
    );
}

/// (V.2) with ε_zz as an internal variable (Ps.1): the frictional impact in plane stress (its
/// θ = ζ = 0.5 are not proportional to the elasticity), the trace stress of the step in R(z);
/// the same margin and bite as in plane strain.
#[test]
fn v2_plane_stress_steps_satisfy_the_variational_inequality() {
    let mut s = fixture("impact_friction");
    s.domain.plane = Some(dyncontact::model::kinds::Plane::Stress);
    let p = problem(s);
    assert!(p.material.thickness.is_some());
    let (worst, checked, bites) = check_steps(&p, 0x2545_f491_4f6c_dd1d, 10, true);
    assert!(bites > 0, "the constraint was never active");
    println!(
        "V.2 in plane stress: {checked} admissible random test functions, smallest relative margin {worst:.3e}; {bites} bites"
    );
    common::measured(
        "variational::v2_plane_stress_steps_satisfy_the_variational_inequality",
        "V.2 smallest relative margin",
        worst,
        "≥ −1e-7",
    );
}

/// (V.1) (V.2) in 3-D: the academic3d fixture at 8×4×4 cells (friction on the disk, the constraint reached at
/// 0.1 s, oblique shaking from 0.2 s), first 0.4 s: every step satisfies the discrete
/// variational–hemivariational inequality for 10 random admissible z (margin ≥ −1e-7 of its
/// scale, as in 2-D) and pushing a node on the constraint further in gives exactly −ω λ; with
/// the penalty ε = 1e-4 the hemivariational one holds for random z.
#[test]
fn v1_v2_3d_steps_satisfy_the_inequalities() {
    for (label, penalty) in [("V.2 exact", false), ("V.1 penalty", true)] {
        let mut s = fixture("academic3d");
        s.domain.cells = Some(vec![8, 4, 4]);
        s.time.end = 0.4;
        if penalty {
            let c = s.contact.as_mut().expect("contact");
            c.enforcement = Enforcement::Penalty;
            c.penalty = Some(1e-4);
        }
        let p = problem(s);
        let (worst, checked, bites) = check_steps(&p, 0x5151_2727_9e37_79b9, 10, !penalty);
        assert!(penalty || bites > 0, "the constraint was never active");
        println!(
            "{label} in 3-D: {checked} random test functions, smallest relative margin {worst:.3e}; {bites} inadmissible checks gave −ωλ"
        );
        common::measured(
            "variational::v1_v2_3d_steps_satisfy_the_inequalities",
            &format!("{label}: smallest relative margin"),
            worst,
            "≥ −1e-7",
        );
    }
}
