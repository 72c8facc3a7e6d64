//! (Ps.1) Plane stress with a viscosity not proportional to the elasticity: ε_zz is an internal
//! variable per triangle (src/fem/thickness.rs). Three checks, each able to fail on its own:
//! - with A ∝ B the variable reproduces the algebraic reduction λ* = 2λμ/(λ + 2μ), θ* = 2θζ/(θ + 2ζ)
//!   that plane stress used before (two independent routes to the same discrete answer);
//! - a free plate pulled by a uniaxial stress creeps as the 3-D Kelvin–Voigt closed form says,
//!   with two time constants (volumetric and deviatoric) that no proportional reduction has;
//! - (E.1) holds with the energy and the dissipation of ε_zz, on the academic scene with contact,
//!   friction and the bound.

use crate::common;

use common::{fixture, problem};
use dyncontact::model::kinds::{Plane, SchemeKind};
use dyncontact::problem::Problem;
use dyncontact::scene::Scene;
use dyncontact::simulation::Simulation;

/// (Ps.1) With A = βB the internal variable gives the algebraic reduction's run: the frictional
/// impact (impact_friction: compliance, the bound, friction) in plane stress with θ = 0.75,
/// ζ = 0.5 (θ/ζ = λ/μ = 1.5), run once with the reduced constants and once with ε_zz carried per
/// triangle. Every step's normal force (against the run's largest), energies (against the
/// energy scale) and the final displacement agree to 1e-9:
/// the two routes factor different (equal in exact arithmetic) step matrices, so they differ by
/// round-off, which the Newton tolerance (1e-10 of the velocity scale) bounds per step.
#[test]
fn ps1_proportional_viscosity_variable_equals_the_algebraic_reduction() {
    let reduced = problem(fixture_plane_stress_proportional());
    assert!(reduced.material.thickness.is_none(), "A ∝ B: the algebraic reduction");
    let mut variable = problem(fixture_plane_stress_proportional());
    variable.material = variable.material.with_thickness_variable();
    let (mut a, mut b) = (Simulation::new(&reduced).expect("setup"), Simulation::new(&variable).expect("setup"));
    assert!(b.ops.thickness.is_some() && a.ops.thickness.is_none());
    let (mut worst_force, mut worst_energy, mut worst_u) = (0.0_f64, 0.0_f64, 0.0_f64);
    let (mut loaded, mut forces) = (0, Vec::new());
    for (ra, rb) in a.steps().zip(b.steps()) {
        let (ra, rb) = (ra.expect("step"), rb.expect("step"));
        forces.push((ra.normal_force, rb.normal_force));
        loaded += usize::from(ra.normal_force > 0.0);
        let (ea, eb) = (ra.energy.to_array(), rb.energy.to_array());
        for k in 0..8 {
            worst_energy = worst_energy.max((ea[k] - eb[k]).abs() / ra.energy_scale);
        }
    }
    let force_scale = forces.iter().fold(0.0_f64, |m, f| m.max(f.0.abs()));
    for (fa, fb) in &forces {
        worst_force = worst_force.max((fa - fb).abs() / force_scale);
    }
    let u_scale = a.state.u.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    for (x, y) in a.state.u.iter().zip(&b.state.u) {
        worst_u = worst_u.max((x - y).abs() / u_scale);
    }
    println!(
        "A ∝ B, variable vs reduction over {} steps ({loaded} in contact): normal force {worst_force:.2e}, energies {worst_energy:.2e}, u {worst_u:.2e}",
        reduced.steps
    );
    assert!(loaded > 50, "the impact must load the contact ({loaded} steps)");
    assert!(worst_force <= 1e-9 && worst_energy <= 1e-9 && worst_u <= 1e-9);
    common::measured(
        "plane_stress::ps1_proportional_viscosity_variable_equals_the_algebraic_reduction",
        "largest relative difference of normal force, energies and u",
        worst_force.max(worst_energy).max(worst_u),
        "≤ 1e-9",
    );
}

fn fixture_plane_stress_proportional() -> Scene {
    let mut s = fixture("impact_friction");
    s.domain.plane = Some(Plane::Stress);
    s.material.viscosity.theta = 0.75;
    s.material.viscosity.zeta = 0.5;
    s
}

/// A free 1 × 0.5 plate (no clamped side, no contact) pulled by σ0 on `right` and −σ0 on `left`
/// from t = 0, in plane stress with θ = 50, ζ = 5 (θ/ζ = 10 against λ/μ = 1.5), ρ = 1e-9 so that
/// inertia is negligible (the wave crosses the plate in 3e-5 of the creep time).
fn creep_plate(scheme: SchemeKind, k: f64, end: f64) -> Problem {
    let text = format!(
        r#"
name = "creep"
[domain]
kind = "rectangle"
size = [1.0, 0.5]
cells = [4, 2]
plane = "stress"
[boundary]
dirichlet = []
contact = []
[material]
density = 1.0e-9
young = 1000.0
poisson = 0.3
viscosity = {{ theta = 50.0, zeta = 5.0 }}
[loads]
body = ["0", "0"]
[[loads.traction]]
side = "right"
value = ["1.0", "0"]
[[loads.traction]]
side = "left"
value = ["-1.0", "0"]
[time]
end = {end}
step = {k}
scheme = "{}"
"#,
        match scheme {
            SchemeKind::Midpoint => "midpoint",
            SchemeKind::Trapezoid => "trapezoid",
            SchemeKind::BackwardEuler => "backward-euler",
        }
    );
    let scene = Scene::from_toml(&text, "creep.toml").expect("creep scene");
    problem(scene)
}

/// The 3-D Kelvin–Voigt body under a uniaxial stress σ0 from t = 0 (quasi-static): the trace
/// obeys (3λ + 2μ) tr ε + (3θ + 2ζ) tr ε̇ = σ0 and the deviator 2μ e + 2ζ ė = dev σ, so
/// ε_zz(t) = σ0/(3K)(1 − e^{−t K/V}) − σ0/(6μ)(1 − e^{−t μ/ζ}) and
/// ε_xx(t) = σ0/(3K)(1 − e^{−t K/V}) + σ0/(3μ)(1 − e^{−t μ/ζ}) with K = 3λ + 2μ, V = 3θ + 2ζ.
fn creep_closed_form(t: f64) -> (f64, f64) {
    let (young, poisson, theta, zeta, sigma0) = (1000.0, 0.3, 50.0, 5.0, 1.0);
    let lambda = young * poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson));
    let mu = young / (2.0 * (1.0 + poisson));
    let (big_k, big_v) = (3.0 * lambda + 2.0 * mu, 3.0 * theta + 2.0 * zeta);
    let volume = sigma0 / (3.0 * big_k) * (1.0 - (-t * big_k / big_v).exp());
    let shear = 1.0 - (-t * mu / zeta).exp();
    (volume + sigma0 / (3.0 * mu) * shear, volume - sigma0 / (6.0 * mu) * shear)
}

/// (Ps.1) The free plate creeps as the closed form: at t = 0.02 (between the deviatoric time
/// ζ/μ = 0.013 and the volumetric one V/K = 0.064, where neither has settled) ε_zz in every
/// triangle and the stretch (u_x(right) − u_x(left))/L match the 3-D law. The midpoint rule's
/// error falls with order 2 ± 0.1 in k (k = 1e-3 → 2.5e-4: the scheme's order; the inertia
/// left by ρ = 1e-9 is ~1e-8 of ε, below the finest error), backward Euler's with order 1 ± 0.1.
#[test]
fn ps1_free_plate_creeps_as_the_3d_kelvin_voigt_closed_form() {
    let end = 0.02;
    let (want_xx, want_zz) = creep_closed_form(end);
    for (scheme, order) in [(SchemeKind::Midpoint, 2.0), (SchemeKind::BackwardEuler, 1.0)] {
        let mut errors = Vec::new();
        for k in [1e-3, 5e-4, 2.5e-4] {
            let p = creep_plate(scheme, k, end);
            let mut sim = Simulation::new(&p).expect("setup");
            for rec in sim.steps() {
                rec.expect("step");
            }
            let s = &sim.state.eps_zz;
            assert_eq!(s.len(), p.mesh.n_cells());
            let spread = s.iter().fold(0.0_f64, |m, x| m.max((x - s[0]).abs()));
            // the state is homogeneous: every triangle has the same ε_zz to round-off
            assert!(spread <= 1e-9 * s[0].abs(), "ε_zz not uniform: spread {spread:.2e}");
            let u = p.dofs.expand_dim(&sim.state.u);
            let (right, left): (Vec<f64>, Vec<f64>) = (0..p.mesh.n_nodes())
                .map(|i| (p.mesh.point(i)[0], u[i][0]))
                .fold((vec![], vec![]), |(mut r, mut l), (x, ux)| {
                    if x == 1.0 {
                        r.push(ux)
                    } else if x == 0.0 {
                        l.push(ux)
                    }
                    (r, l)
                });
            let stretch = right.iter().sum::<f64>() / right.len() as f64 - left.iter().sum::<f64>() / left.len() as f64;
            let err = ((s[0] - want_zz) / want_zz).abs().max(((stretch - want_xx) / want_xx).abs());
            println!(
                "{scheme:?} k = {k:e}: ε_zz {:.9e} (closed form {want_zz:.9e}), ε_xx {stretch:.9e} ({want_xx:.9e}), error {err:.2e}",
                s[0]
            );
            errors.push(err);
        }
        let orders = common::orders(&errors);
        println!("{scheme:?}: orders {orders:?}");
        for p in &orders {
            assert!((p - order).abs() <= 0.1, "{scheme:?}: order {p} (errors {errors:?})");
        }
        common::measured(
            "plane_stress::ps1_free_plate_creeps_as_the_3d_kelvin_voigt_closed_form",
            &format!("{scheme:?}: relative error at the finest k"),
            *errors.last().expect("errors"),
            "order in k as the scheme's",
        );
    }
}

/// (Ps.1) (E.1) with ε_zz as a variable: the academic scene (compliance, the bound, the
/// slip-rate-dependent friction, the oblique pull) in plane stress with its own θ = 2, ζ = 1.5
/// (θ/ζ = 1.33 against λ/μ = 1.5), first 0.5 s, with the midpoint rule and the trapezoid (the
/// same ε_zz rule; its contact forces end-point averaged), and the unstructured Gmsh square
/// (the same θ, ζ, no contact) to t = 0.2: every step's residual is within 1e-12 of the energy
/// scale (the Newton and fixed-point tolerances, as for plane strain), and the viscous
/// dissipation — which now includes ∫ 2θ ė ṡ + Θ ṡ² — never decreases.
#[test]
fn ps1_energy_balance_holds_with_the_out_of_plane_strain() {
    for (name, scheme, end) in [
        ("academic", SchemeKind::Midpoint, 0.5),
        ("academic", SchemeKind::Trapezoid, 0.5),
        ("gmsh_square", SchemeKind::Midpoint, 0.2),
    ] {
        let mut s = fixture(name);
        s.domain.plane = Some(Plane::Stress);
        s.time.end = end;
        s.time.scheme = scheme;
        let p = problem(s);
        assert!(p.material.thickness.is_some());
        let recs = common::records(&p);
        let worst =
            recs.iter().map(|r| r.energy.residual.abs() / r.energy_scale.max(f64::MIN_POSITIVE)).fold(0.0, f64::max);
        let decreasing =
            recs.windows(2).filter(|w| w[1].energy.viscous_dissipation < w[0].energy.viscous_dissipation).count();
        let contact = recs.iter().filter(|r| r.contact_nodes > 0).count();
        println!(
            "plane stress {name}, {scheme:?}: (E.1) ≤ {worst:.2e} of the scale over {} steps ({contact} with contact)",
            recs.len() - 1
        );
        assert!(p.contact.is_none() || contact > 100, "{name}: the block must reach the foundation");
        assert!(worst <= 1e-12, "{name}, {scheme:?}: (E.1) residual {worst:.3e} of the scale");
        assert_eq!(decreasing, 0, "{name}, {scheme:?}: viscous dissipation decreased on {decreasing} steps");
        common::measured(
            "plane_stress::ps1_energy_balance_holds_with_the_out_of_plane_strain",
            &format!("{name}, {scheme:?}: largest (E.1) residual / energy scale"),
            worst,
            "≤ 1e-12",
        );
    }
}
