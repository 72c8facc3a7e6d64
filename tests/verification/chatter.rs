//! Velocity chatter of the midpoint rule at contact nodes, and its remedies.
//!
//! With exact enforcement, (S.1) gives v^{n+1} = 2(u^{n+1} − u^n)/k − v^n: a node that stays on
//! the constraint (u_ν^{n+1} = u_ν^n = g) or sticks has v^{n+1} = −v^n. Its end-point velocity
//! flips sign every step, so |v^{n+1} + v^n| ≡ 0 there; the chatter measure used here is the
//! velocity such a node should not have, max |v_c^{n+1}| (= ½|v^{n+1} − v^n|), and the kinetic
//! energy trapped on those nodes, ½ Σ m_i (v_c,i^{n+1})². Variants compared: midpoint, midpoint
//! with the modified mass (R.1), midpoint with velocity-level persistency (R.2), and backward
//! Euler.

use crate::common;

use common::{fixture, problem, records};
use dyncontact::reference::bar_impact_force;
use dyncontact::scene::{MassKind, Scene, SchemeKind};
use dyncontact::simulation::StepRecord;

#[derive(Debug, Clone, Copy, PartialEq)]
enum Variant {
    Midpoint,
    ModifiedMass,
    Persistency,
    BackwardEuler,
}

const VARIANTS: [Variant; 4] = [Variant::Midpoint, Variant::ModifiedMass, Variant::Persistency, Variant::BackwardEuler];

impl Variant {
    /// The variant in the scene file's words (the chart's legend).
    fn label(self) -> &'static str {
        match self {
            Variant::Midpoint => "midpoint",
            Variant::ModifiedMass => "midpoint, mass = \"modified\" (R.1)",
            Variant::Persistency => "midpoint, persistency = true (R.2)",
            Variant::BackwardEuler => "backward-euler",
        }
    }
}

fn with(mut s: Scene, v: Variant) -> Scene {
    match v {
        Variant::Midpoint => {}
        Variant::ModifiedMass => s.solver.mass = MassKind::Modified,
        Variant::Persistency => s.solver.persistency = true,
        Variant::BackwardEuler => s.time.scheme = SchemeKind::BackwardEuler,
    }
    s
}

/// B.1 contact-force error: ∫|F_h − F| dt / ∫F dt over [0, 2.4] (the closed form is ρ c v0 H
/// on [0, 2L/c]).
fn force_error(recs: &[StepRecord], k: f64) -> f64 {
    let (height, v0) = (0.1, 0.1);
    let (mut num, mut den) = (0.0, 0.0);
    for r in recs.iter().skip(1).filter(|r| r.t <= 2.4) {
        // the force of step n acts over (t_n − k, t_n]: compare with the closed form's mean there
        let exact =
            0.5 * (bar_impact_force(1.0, 1.0, 1.0, v0, r.t - k) + bar_impact_force(1.0, 1.0, 1.0, v0, r.t)) * height;
        num += (r.normal_force - exact).abs() * k;
        den += exact * k;
    }
    num / den
}

/// The normal-force history of a run (t, force), for the comparison chart.
fn force_history(s: Scene) -> Vec<(f64, f64)> {
    records(&problem(s)).iter().map(|r| (r.t, r.normal_force)).collect()
}

struct Measures {
    chatter: f64,
    trapped: f64,
    force_error: f64,
    residual: f64,
    persistency: f64,
    exit_speed: f64,
}

fn measure(s: Scene) -> Measures {
    let k = s.time.step;
    let p = problem(s);
    let recs = records(&p);
    let last = recs.last().expect("records");
    Measures {
        chatter: recs.iter().map(|r| r.chatter).fold(0.0, f64::max),
        trapped: recs.iter().map(|r| r.trapped_kinetic).fold(0.0, f64::max),
        force_error: force_error(&recs, k),
        residual: recs.iter().map(|r| r.energy.residual.abs() / r.energy_scale).fold(0.0, f64::max),
        persistency: last.energy.persistency_dissipation,
        exit_speed: (2.0 * last.energy.kinetic / 0.1).sqrt(),
    }
}

/// (R.1) (R.2) On B.1: the midpoint rule chatters (pinned: trapped kinetic energy > 0 on the
/// node held at the wall); the modified mass traps no kinetic energy and persistency removes
/// the chatter, both keeping (E.1) exact (≤ 1e-12 of the energy scale, round-off); every
/// variant's contact-force error and order in k (c k/h fixed at 0.25, 50 → 200 cells) is
/// printed, and the remedies' force error is below the plain midpoint's.
#[test]
fn r1_r2_bar_impact_chatter_and_remedies() {
    println!("variant            chatter     trapped KE   force err   (E.1) rel   persistency  exit speed");
    let mut errs = Vec::new();
    for v in VARIANTS {
        let m = measure(with(fixture("bar_impact"), v));
        println!(
            "{:<18} {:.3e}   {:.3e}    {:.3e}   {:.1e}     {:.3e}    {:.5}",
            format!("{v:?}"),
            m.chatter,
            m.trapped,
            m.force_error,
            m.residual,
            m.persistency,
            m.exit_speed
        );
        match v {
            Variant::Midpoint => {
                assert!(m.trapped > 0.0 && m.chatter > 0.0, "the midpoint chatter is gone: update the documentation")
            }
            Variant::ModifiedMass => assert_eq!(m.trapped, 0.0, "the modified mass traps kinetic energy"),
            Variant::Persistency => {
                assert_eq!(m.chatter, 0.0, "persistency left chatter");
                assert!(m.persistency > 0.0, "persistency removed nothing");
            }
            Variant::BackwardEuler => {}
        }
        if v != Variant::BackwardEuler {
            assert!(m.residual <= 1e-12, "{v:?}: (E.1) defect {:.3e}", m.residual);
        }
        common::measured(
            "chatter::r1_r2_bar_impact_chatter_and_remedies",
            &format!("B.1 force error, {v:?}"),
            m.force_error,
            "reported",
        );
        errs.push(m.force_error);
    }
    assert!(errs[1] < errs[0] && errs[2] < errs[0], "the remedies do not reduce the force error: {errs:?}");
    // the comparison chart: contact force histories of the four variants against ρ c v0 H
    let series: Vec<dyncontact::output::plots::Series> = VARIANTS
        .iter()
        .map(|&v| dyncontact::output::plots::Series {
            name: v.label().to_string(),
            points: force_history(with(fixture("bar_impact"), v)).into_iter().filter(|p| p.0 <= 2.4).collect(),
        })
        .collect();
    let svg = dyncontact::output::plots::line_chart(
        "B.1: contact force of a bar hitting a rigid wall, per variant",
        "t [s]",
        "normal force [N/m]",
        &series,
        &[("closed form ρ c v0 H".to_string(), 0.01)],
    )
    .expect("chart");
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("chatter");
    std::fs::create_dir_all(&dir).expect("dir");
    std::fs::write(dir.join("b1_forces.svg"), &svg).expect("write");
    assert!(svg.matches("<polyline").count() >= 5, "four variants and the closed form");
    // orders under joint refinement at a fixed Courant number
    for v in VARIANTS {
        let e: Vec<f64> = [50, 100, 200]
            .iter()
            .map(|&c| {
                let mut s = with(fixture("bar_impact"), v);
                s.domain.cells = Some([c, 1].to_vec());
                s.time.step = 0.25 / c as f64;
                s.time.end = 2.5;
                measure(s).force_error
            })
            .collect();
        let orders: Vec<f64> = e.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
        println!("{v:?}: force error {e:?} for 50, 100, 200 cells (k = h/4): orders {orders:?}");
    }
}

/// (R.1) (R.2) On the academic scene (coarse, first 0.5 s): the midpoint rule traps kinetic
/// energy on nodes that stay on the constraint or in stick; the modified mass traps none;
/// persistency removes the chatter and books a nonnegative dissipation; (E.1) stays ≤ 1e-9.
#[test]
fn r1_r2_academic_chatter_and_remedies() {
    let mut base = fixture("academic");
    base.domain.cells = Some([16, 8].to_vec());
    base.time.step = 1e-3;
    base.time.end = 0.5;
    for v in VARIANTS {
        let p = problem(with(base.clone(), v));
        let recs = records(&p);
        let chatter = recs.iter().map(|r| r.chatter).fold(0.0, f64::max);
        let trapped = recs.iter().map(|r| r.trapped_kinetic).fold(0.0, f64::max);
        let res = recs.iter().map(|r| r.energy.residual.abs() / r.energy_scale).fold(0.0, f64::max);
        let last = recs.last().expect("records");
        println!(
            "{:<14} chatter {chatter:.3e}, trapped KE {trapped:.3e}, (E.1) {res:.1e}, persistency {:.3e}, friction {:.4e}",
            format!("{v:?}"),
            last.energy.persistency_dissipation,
            last.energy.friction_dissipation
        );
        match v {
            Variant::Midpoint => assert!(chatter > 0.0 && trapped > 0.0),
            Variant::ModifiedMass => assert_eq!(trapped, 0.0),
            Variant::Persistency => assert!(chatter == 0.0 && last.energy.persistency_dissipation >= 0.0),
            Variant::BackwardEuler => {}
        }
        if v != Variant::BackwardEuler {
            assert!(res <= 1e-9, "{v:?}: (E.1) defect {res:.3e}");
        }
    }
}

/// (R.1) The modified mass keeps the total mass and the centre of mass of the lumped mass
/// (to round-off, 1e-13 relative), puts zero mass on every contact node, and keeps every other
/// free node's mass positive — on the academic mesh, the bar and an unstructured Gmsh mesh.
#[test]
fn r1_modified_mass_keeps_total_mass_and_centre_of_mass() {
    use dyncontact::fem::assemble::modified_masses;
    let mut half_disk = fixture("crosscheck_gmsh");
    half_disk.boundary.contact = vec!["flat".into()];
    half_disk.boundary.dirichlet = vec![];
    half_disk.loads.traction.clear();
    half_disk.contact = fixture("impact_friction").contact;
    for (name, s) in
        [("academic", fixture("academic")), ("bar_impact", fixture("bar_impact")), ("half disk", half_disk)]
    {
        let p = problem(s);
        let c = p.contact.as_ref().expect("contact");
        let m = modified_masses(&p.mesh, &p.material, &p.dofs, &c.nodes).expect("modified mass");
        let mut lumped = vec![0.0; p.mesh.plane().expect("a 2-D mesh").nodes.len()];
        for tri in &p.mesh.plane().expect("a 2-D mesh").cells {
            let x = [
                p.mesh.plane().expect("a 2-D mesh").nodes[tri[0]],
                p.mesh.plane().expect("a 2-D mesh").nodes[tri[1]],
                p.mesh.plane().expect("a 2-D mesh").nodes[tri[2]],
            ];
            let a = dyncontact::fem::element::gradients(x).1.abs();
            for &v in tri {
                lumped[v] += p.material.rho * a / 3.0;
            }
        }
        let moments = |w: &[f64]| {
            let t: f64 = w.iter().sum();
            let mx: f64 = w.iter().zip(&p.mesh.plane().expect("a 2-D mesh").nodes).map(|(m, x)| m * x[0]).sum();
            let my: f64 = w.iter().zip(&p.mesh.plane().expect("a 2-D mesh").nodes).map(|(m, x)| m * x[1]).sum();
            (t, mx, my)
        };
        let (t0, x0, y0) = moments(&lumped);
        let (t1, x1, y1) = moments(&m);
        println!(
            "{name}: total {t0:.6e} → {t1:.6e}, centre ({:.6}, {:.6}) → ({:.6}, {:.6}), min mass {:.3e}",
            x0 / t0,
            y0 / t0,
            x1 / t1,
            y1 / t1,
            m.iter().zip(0..).filter(|(_, j)| !c.nodes.contains(j)).map(|(v, _)| *v).fold(f64::INFINITY, f64::min)
        );
        let scale = p.mesh.bbox_diameter();
        assert!((t1 - t0).abs() <= 1e-13 * t0, "{name}: total mass changed");
        assert!(
            (x1 / t1 - x0 / t0).abs() <= 1e-13 * scale && (y1 / t1 - y0 / t0).abs() <= 1e-13 * scale,
            "{name}: centre of mass moved"
        );
        assert!(c.nodes.iter().all(|&i| m[i] == 0.0));
        assert!(
            m.iter()
                .enumerate()
                .filter(|(j, _)| !c.nodes.contains(j) && p.dofs.map[2 * j].is_some())
                .all(|(_, v)| *v > 0.0)
        );
    }
}

/// (R.1) in 3-D: on the column of column_impact3d (B.1 with ν = 0, 100×1×1 cells) and on the
/// academic3d box (8×4×4 cells) the modified mass keeps the total mass and the centre of mass
/// (to round-off, 1e-13 relative), is zero on every contact node and positive on every other
/// free node; the column run with it traps no kinetic energy, keeps (E.1) to 1e-12 of the energy
/// scale (round-off), and its contact-force error ∫|F_h − F| dt / ∫F dt against ρ c v0 A on
/// [0, 2L/c] is below the lumped mass's (whose midpoint chatter alternates the force).
#[test]
fn r1_modified_mass_in_3d() {
    use dyncontact::fem::assemble::{modified_masses, solid_vertex_masses};
    let mut box3d = fixture("academic3d");
    box3d.domain.cells = Some(vec![8, 4, 4]);
    for (name, s) in [("column", fixture("column_impact3d")), ("academic3d 8×4×4", box3d)] {
        let p = problem(s);
        let c = p.contact.as_ref().expect("contact");
        let solid = p.mesh.solid().expect("a 3-D mesh");
        let m = modified_masses(&p.mesh, &p.material, &p.dofs, &c.nodes).expect("modified mass");
        let lumped = solid_vertex_masses(solid, &p.material);
        let moments = |w: &[f64]| -> [f64; 4] {
            let mut out = [w.iter().sum(), 0.0, 0.0, 0.0];
            for (mj, x) in w.iter().zip(&solid.nodes) {
                for k in 0..3 {
                    out[k + 1] += mj * x[k];
                }
            }
            out
        };
        let (a, b) = (moments(&lumped), moments(&m));
        let scale = p.mesh.bbox_diameter();
        println!(
            "{name}: total {:.6e} → {:.6e}, centre moves by {:.1e}",
            a[0],
            b[0],
            (1..4).map(|k| (b[k] / b[0] - a[k] / a[0]).abs()).fold(0.0, f64::max)
        );
        assert!((b[0] - a[0]).abs() <= 1e-13 * a[0], "{name}: total mass changed");
        assert!((1..4).all(|k| (b[k] / b[0] - a[k] / a[0]).abs() <= 1e-13 * scale), "{name}: centre of mass moved");
        assert!(c.nodes.iter().all(|&i| m[i] == 0.0), "{name}: a contact node keeps mass");
        assert!(
            (0..m.len()).filter(|j| !c.nodes.contains(j) && p.dofs.map[3 * j].is_some()).all(|j| m[j] > 0.0),
            "{name}: a free node without mass"
        );
    }
    // B.1 in 3-D with the lumped and the modified mass
    let error = |s: Scene| {
        let k = s.time.step;
        let recs = records(&problem(s));
        let (mut num, mut den) = (0.0, 0.0);
        for r in recs.iter().skip(1).filter(|r| r.t <= 2.4) {
            let exact = 0.5
                * (bar_impact_force(1.0, 1.0, 1.0, 0.1, r.t - k) + bar_impact_force(1.0, 1.0, 1.0, 0.1, r.t))
                * 0.01;
            num += (r.normal_force - exact).abs() * k;
            den += exact * k;
        }
        let trapped = recs.iter().map(|r| r.trapped_kinetic).fold(0.0, f64::max);
        let residual = recs.iter().map(|r| r.energy.residual.abs() / r.energy_scale.max(1e-300)).fold(0.0, f64::max);
        (num / den, trapped, residual)
    };
    let (e_lumped, trapped_lumped, _) = error(fixture("column_impact3d"));
    let (e_mod, trapped_mod, residual_mod) = error(with(fixture("column_impact3d"), Variant::ModifiedMass));
    println!(
        "column impact 3-D: force error lumped {e_lumped:.3e} (trapped KE {trapped_lumped:.2e}), modified {e_mod:.3e} (trapped {trapped_mod:.2e}, (E.1) {residual_mod:.1e})"
    );
    common::measured("chatter::r1_modified_mass_in_3d", "B.1 3-D force error, modified mass", e_mod, "< lumped");
    common::measured("chatter::r1_modified_mass_in_3d", "B.1 3-D force error, lumped mass", e_lumped, "reported");
    assert_eq!(trapped_mod, 0.0, "the modified mass traps kinetic energy");
    assert!(residual_mod <= 1e-12, "(E.1) defect {residual_mod:.3e}");
    assert!(e_mod < e_lumped, "the modified mass does not reduce the force error: {e_mod:.3e} vs {e_lumped:.3e}");
}
