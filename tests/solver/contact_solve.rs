//! The two forms of the contact solve — the dense Delassus operator W = H A_k⁻¹ Hᵀ and the
//! sparse one probed and truncated at 1e-12 of its diagonal (src/step/delassus/sparse.rs) — give the
//! same answers, and `contact_solve = "auto"` picks the form the sizes call for.
//!
//! Why the answers can agree to ~1e-10: the sparse operator drops entries below 1e-12 of the
//! diagonal (its measured apply error on a random force is ~1e-12 of the response), so a step
//! solved with it differs from the dense step by about that times the conditioning of the
//! Newton matrix; whole trajectories are compared only over stretches without stick–slip
//! transitions, where round-off is not amplified (README, "Speed").

use crate::common;

use common::{fixture, measured, problem};
use dyncontact::linalg;
use dyncontact::problem::Problem;
use dyncontact::scene::{ContactSolve, Scene};
use dyncontact::simulation::Simulation;
use dyncontact::step::delassus::{self, DelassusFactors};
use dyncontact::step::newton::{self, NewtonSettings};

/// Largest |a − b| over the largest |a| (or 1e-300).
fn rel(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs())) / linalg::norm_inf(a).max(1e-300)
}

fn with_form(mut s: Scene, form: ContactSolve) -> Scene {
    s.solver.contact_solve = form;
    s
}

/// A strip [n, 16] of the academic material and loads, contact on the bottom, `steps` steps of
/// k: n + 1 contact nodes, W decaying within ~16 nodes.
fn strip(n: i64, k: f64, steps: usize) -> Scene {
    let mut s = fixture("academic");
    s.domain.size = Some([n as f64 / 16.0, 1.0].to_vec());
    s.domain.cells = Some([n, 16].to_vec());
    s.time.step = k;
    s.time.end = k * steps as f64;
    s
}

/// Per step from the same state: the F.1 bound of the dense solve, then one frozen Newton solve
/// with each form of W; the worst relative differences of the contact velocities and forces.
fn per_step(p: &Problem, steps: usize) -> (f64, f64) {
    let c = p.contact.as_ref().expect("contact");
    let positions: Vec<[f64; 3]> =
        c.nodes.iter().map(|&i| p.mesh.plane().expect("a 2-D mesh").nodes[i]).map(|x| [x[0], x[1], 0.0]).collect();
    let setup = Simulation::new(p).expect("setup");
    let w_sparse = delassus::build(setup.stepper.factor(), c, &positions, ContactSolve::Sparse);
    assert_eq!(w_sparse.form(), "sparse");
    let set = NewtonSettings { tolerance: 1e-12, ..NewtonSettings::default() };
    let (mut worst_v, mut worst_f) = (0.0f64, 0.0f64);
    let mut sparse_factors = DelassusFactors::default();
    common::each_frozen_step(p, steps, set, |sim, dense, dense_factors, s, y_free| {
        let a = newton::solve(dense, dense_factors, s, &sim.state.lambda, &sim.state.t_fric, &set).expect("dense");
        let (mut sparse, _) = sim.step_data(y_free.to_vec()).expect("data");
        sparse.delassus = &w_sparse;
        let b =
            newton::solve(&sparse, &mut sparse_factors, s, &sim.state.lambda, &sim.state.t_fric, &set).expect("sparse");
        let (ra, rb) = (dense.forces(&a.y, &a.lambda, &a.t), sparse.forces(&b.y, &b.lambda, &b.t));
        if linalg::norm_inf(&ra) > 0.0 {
            worst_v = worst_v.max(rel(&a.y, &b.y));
            worst_f = worst_f.max(rel(&ra, &rb));
        }
    });
    (worst_v, worst_f)
}

/// (S.6) The sparse and the dense contact solve give the same step solution from the same state
/// on every step of the academic scene's start (pressing, then sliding: 600 steps) and of the
/// frictional impact, to 2e-9: the truncation at 1e-12 of the diagonal times the conditioning
/// of W_UU + D (≤ ~1e3 here); measured 1.5e-12 (academic) and 6.2e-10 (the impact's release,
/// where a node is weakly active).
#[test]
fn sparse_and_dense_contact_solves_agree_per_step() {
    for (name, steps) in [("academic", 600), ("impact_friction", usize::MAX)] {
        let p = problem(fixture(name));
        let (dv, df) = per_step(&p, steps.min(p.steps));
        println!("{name}: sparse vs dense W, worst per-step difference: velocity {dv:.3e}, force {df:.3e}");
        measured(
            "sparse_and_dense_contact_solves_agree_per_step",
            &format!("{name}: per-step force difference"),
            df,
            "≤ 2e-9",
        );
        assert!(dv <= 2e-9 && df <= 2e-9, "{name}: velocity {dv:.3e}, force {df:.3e}");
    }
}

/// (S.6) A strip with 1,025 contact nodes, coarse in time (10 steps of 2e-3 while the load
/// presses it on): the sparse run (W from 65 colours, 133 solves instead of 2,050) gives the
/// dense run's forces and energies at every step to 1e-9 of their largest values, and `auto`
/// picks the sparse form there and the dense form on the academic scene. Both runs solve Newton
/// to 1e-13 and (F.1) to 1e-12 (the defaults 1e-10 and 1e-8 leave each step's solution that far
/// from the exact one, and the two forms' paths — the dense one in velocity form by conjugate
/// gradients — differ by that much: measured 3.6e-9 over the 10 steps), so the difference
/// measured is the truncation's.
#[test]
fn large_strip_sparse_equals_dense() {
    let runs: Vec<Vec<[f64; 4]>> = [ContactSolve::Dense, ContactSolve::Sparse]
        .into_iter()
        .map(|form| {
            let mut scene = with_form(strip(1024, 2e-3, 10), form);
            scene.solver.newton_tolerance = 1e-13;
            scene.solver.fixed_point_tolerance = 1e-12;
            let p = problem(scene);
            let mut sim = Simulation::new(&p).expect("setup");
            let w = sim.delassus.as_ref().expect("W");
            assert_eq!(w.form(), if form == ContactSolve::Dense { "dense" } else { "sparse" });
            if let Some(st) = w.sparse_stats() {
                println!(
                    "sparse W: radius {:.3}, {} colours, {} solves, density {:.4}, apply error {:.2e}",
                    st.radius, st.colours, st.solves, st.density, st.apply_error
                );
                // the truncation is 1e-12 of the diagonal; its effect on a response is of that order
                assert!(st.apply_error <= 1e-10, "apply error {:.3e}", st.apply_error);
                assert!(st.solves < 200, "{} solves", st.solves);
            }
            sim.steps()
                .map(|r| {
                    let r = r.expect("step");
                    [r.normal_force, r.tangential_force, r.energy.kinetic, r.energy.elastic]
                })
                .collect()
        })
        .collect();
    let mut worst = 0.0f64;
    for q in 0..4 {
        let a: Vec<f64> = runs[0].iter().map(|r| r[q]).collect();
        let b: Vec<f64> = runs[1].iter().map(|r| r[q]).collect();
        worst = worst.max(rel(&a, &b));
    }
    println!("strip 1024: sparse vs dense over 10 steps, worst relative difference {worst:.3e}");
    measured("large_strip_sparse_equals_dense", "worst relative difference of forces and energies", worst, "≤ 1e-9");
    assert!(worst <= 1e-9, "{worst:.3e}");
    for (scene, form) in [(strip(1024, 2e-3, 1), "sparse"), (fixture("academic"), "dense")] {
        let p = problem(scene);
        let sim = Simulation::new(&p).expect("setup");
        assert_eq!(sim.delassus.as_ref().expect("W").form(), form, "auto on {}", p.model.name);
    }
}

/// (S.6) The recovery through the kept responses G = A_k⁻¹ Hᵀ equals the recovery by a solve:
/// for force vectors with every node, half the nodes and one node loaded, G r and A_k⁻¹ Hᵀ r
/// agree to 1e-13 of their size (the same solves summed in another order: round-off of a
/// well-conditioned A_k; measured ~1e-16), and H G is W to the same digits.
#[test]
fn recovery_by_responses_equals_recovery_by_solve() {
    let p = problem(fixture("academic"));
    let c = p.contact.as_ref().expect("contact");
    let sim = Simulation::new(&p).expect("setup");
    let a = sim.stepper.factor();
    let (w, g) = delassus::dense_with_responses(a, c, true);
    let g = g.expect("kept responses");
    let m = w.nrows();
    let mut worst = 0.0f64;
    for stride in [1, 2, m] {
        let r: Vec<f64> =
            (0..m).map(|l| if l % stride == 0 { ((l * 37 % 11) as f64 - 5.0) * 1e3 } else { 0.0 }).collect();
        let mut by_solve = vec![0.0; a.dim()];
        c.scatter_add(&r, &mut by_solve);
        a.solve_in_place(&mut by_solve);
        let mut by_g = vec![0.0; a.dim()];
        for (l, &rl) in r.iter().enumerate() {
            for (x, gi) in by_g.iter_mut().zip(g.col_as_slice(l)) {
                *x += gi * rl;
            }
        }
        worst = worst.max(rel(&by_solve, &by_g));
        let hg = c.restrict(&by_g);
        let wr: Vec<f64> = (0..m).map(|j| (0..m).map(|l| w[(j, l)] * r[l]).sum()).collect();
        worst = worst.max(rel(&wr, &hg));
    }
    println!("G r against A_k⁻¹ Hᵀ r and H G r against W r: worst {worst:.3e}");
    measured("recovery_by_responses_equals_recovery_by_solve", "relative difference", worst, "≤ 1e-13");
    assert!(worst <= 1e-13, "responses and solve differ by {worst:.3e}");
}

/// W and W⁻¹ of the scene's A_k by the Schur complement on the contact unknowns, and by d n_c
/// solve pairs (the solves' W⁻¹ by its Cholesky inverse): the largest entry-wise differences
/// relative to the largest entry of each.
fn schur_against_solves(p: &Problem) -> (f64, f64) {
    use faer::linalg::solvers::DenseSolveCore;
    let c = p.contact.as_ref().expect("contact");
    let sim = Simulation::new(p).expect("setup");
    let stepper = dyncontact::scheme::StepOperator::new(&sim.ops, p.model.time.scheme, p.k).expect("A_k");
    let k = stepper.matrix().expect("A_k before release");
    // a budget below the second factor's exact size (known after its symbolic analysis): the
    // route declines, and the run takes the solves
    let positions = Some(sim.ops.positions.as_slice());
    assert!(delassus::delassus_pair(k, positions, c, Some(1e3)).is_none(), "a 1 kB budget refuses the Schur route");
    let (w, winv) = delassus::delassus_pair(k, positions, c, None).expect("Schur");
    let w0 = delassus::dense(stepper.factor(), c);
    let winv0 = w0.llt(faer::Side::Lower).expect("W is positive definite").inverse();
    ((&w - &w0).norm_max() / w0.norm_max(), (&winv - &winv0).norm_max() / winv0.norm_max())
}

/// (S.6) W = H A_k⁻¹ Hᵀ from the trailing Schur complement of A_k (the contact unknowns ordered
/// last: W⁻¹ = R S Rᵀ, W = R S⁻¹ Rᵀ) equals W from the solves to round-off — on the academic
/// strip (2-D), academic3d at 12×8×4 (axis-aligned frames) and the Gmsh block with contact on
/// its cylindrical hole (every node's frame rotated): within 1e-12 of the largest entry, the
/// round-off of either route (machine ε times the conditioning of A_k's blocks, ≤ ~1e3 here);
/// measured 4e-16 … 2e-15.
#[test]
fn schur_complement_gives_the_delassus_operator_of_the_solves() {
    let mut hole = fixture("gmsh_block3d");
    hole.boundary.contact = vec!["hole".to_string()];
    let mut box3 = fixture("academic3d");
    box3.domain.cells = Some(vec![12, 8, 4]);
    for (name, s) in [("academic", fixture("academic")), ("academic3d 12x8x4", box3), ("gmsh_block3d hole", hole)] {
        let p = problem(s);
        let (dw, dwinv) = schur_against_solves(&p);
        println!("{name}: Schur vs solves, W {dw:.3e}, W⁻¹ {dwinv:.3e}");
        measured("schur_complement_gives_the_delassus_operator_of_the_solves", name, dw.max(dwinv), "≤ 1e-12");
        assert!(dw <= 1e-12 && dwinv <= 1e-12, "{name}: W {dw:.3e}, W⁻¹ {dwinv:.3e}");
    }
}

/// (S.6) A run takes the Schur route where it should (a dense W of ≥ SCHUR_FROM components whose
/// responses are not kept: academic3d at 24×12×8, 936 contact unknowns) and its steps are the
/// steps of the same run with W and W⁻¹ from the solves: over the first 20 steps (pressing, half
/// the nodes slipping) the velocities agree within 1e-11 of their largest entry and the
/// multipliers and friction forces within 1e-8 of theirs — Newton's tolerance (1e-10 of the velocity scale, the
/// default) passed through W⁻¹ (~1e3× the velocity scale's inverse), with W itself equal to
/// ~1e-15.
#[test]
fn a_run_with_the_schur_delassus_takes_the_steps_of_the_solves() {
    let mut s = fixture("academic3d");
    s.domain.cells = Some(vec![24, 12, 8]);
    s.time.end = 20.0 * s.time.step;
    s.output.every = 0;
    let p = problem(s);
    let c = p.contact.as_ref().expect("contact");
    let mut a = Simulation::new(&p).expect("setup");
    assert_eq!(a.setup_timing.delassus_route, "schur", "936 components, responses not kept");
    let mut b = Simulation::new(&p).expect("setup");
    let positions: Vec<[f64; 3]> = c.nodes.iter().map(|&i| p.mesh.point(i)).collect();
    let built = delassus::build_with_responses(b.stepper.factor(), None, c, &positions, ContactSolve::Dense);
    assert_eq!(built.route, "solves");
    b.inverse = delassus::InverseDelassus::new(&built.w, c.dim, None);
    b.delassus = Some(built.w);
    assert!(a.inverse.is_some() && b.inverse.is_some(), "both in velocity form");
    let (mut worst_v, mut worst_l) = (0.0f64, 0.0f64);
    for _ in 0..20 {
        a.step().expect("schur step");
        b.step().expect("solves step");
        worst_v = worst_v.max(rel(&a.state.v, &b.state.v));
        worst_l = worst_l.max(rel(&a.state.lambda, &b.state.lambda)).max(rel(&a.state.t_fric, &b.state.t_fric));
    }
    println!("Schur vs solves over 20 steps: velocity {worst_v:.3e}, forces {worst_l:.3e}");
    measured("a_run_with_the_schur_delassus_takes_the_steps_of_the_solves", "velocity", worst_v, "≤ 1e-11");
    assert!(worst_v <= 1e-11 && worst_l <= 1e-8, "velocity {worst_v:.3e}, forces {worst_l:.3e}");
    assert!(linalg::norm_inf(&a.state.t_fric) > 0.0, "friction acted");
}

/// (S.6) W⁻¹'s and W's products through their hierarchical forms (W⁻¹ to HMATRIX_TOLERANCE =
/// 1e-12 of max|W⁻¹| for the exact directions and at the loosest certified ε of
/// HMATRIX_LOOSE_TOLERANCES, 1e-6 here, for the loose ones; W to HMATRIX_TOLERANCE_W = 1e-14 of
/// max|W|) give the steps of the dense products: academic3d at 24×12×8 (936 contact unknowns,
/// compressed by the run from HMATRIX_FROM = 400 on; its dense twin `without_compression`) over
/// its first 20 steps (pressing, half the nodes
/// slipping). W⁻¹ reaches only the Newton directions and W's residual moves by ~1e-14 of its
/// scale, so the steps agree to Newton's tolerance as in the Schur test above: velocities within
/// 1e-11 of their largest entry, multipliers and friction forces within 1e-8 of theirs.
#[test]
fn a_run_with_the_hierarchical_inverse_takes_the_steps_of_the_dense_one() {
    let mut s = fixture("academic3d");
    s.domain.cells = Some(vec![24, 12, 8]);
    s.time.end = 20.0 * s.time.step;
    s.output.every = 0;
    let p = problem(s);
    let mut a = Simulation::new(&p).expect("setup");
    a.inverse = a.inverse.take().map(|i| i.without_compression());
    assert!(a.inverse.as_ref().is_some_and(|i| i.hierarchical().is_none()), "the dense products");
    let mut b = Simulation::new(&p).expect("setup");
    assert!(
        b.inverse.as_ref().is_some_and(|i| i.hierarchical().is_some() && i.hierarchical_w().is_some()),
        "the run compresses W⁻¹ and W from HMATRIX_FROM on"
    );
    let share = b.inverse.as_ref().and_then(|i| i.hierarchical()).map(|h| h.storage_share()).expect("compressed");
    let (mut worst_v, mut worst_l, mut newton) = (0.0f64, 0.0f64, [0usize; 2]);
    for _ in 0..20 {
        newton[0] += a.step().expect("dense step").report.inner_iterations;
        newton[1] += b.step().expect("hierarchical step").report.inner_iterations;
        worst_v = worst_v.max(rel(&a.state.v, &b.state.v));
        worst_l = worst_l.max(rel(&a.state.lambda, &b.state.lambda)).max(rel(&a.state.t_fric, &b.state.t_fric));
    }
    let eps = b.inverse.as_ref().and_then(|i| i.hierarchical_loose()).map(|h| h.tolerance()).expect("a loose form");
    println!(
        "hierarchical (ε {eps:e}) vs dense W⁻¹ over 20 steps: velocity {worst_v:.3e}, forces {worst_l:.3e}, Newton {newton:?}, stored {share:.3}"
    );
    measured("a_run_with_the_hierarchical_inverse_takes_the_steps_of_the_dense_one", "velocity", worst_v, "≤ 1e-11");
    assert!(worst_v <= 1e-11 && worst_l <= 1e-8, "velocity {worst_v:.3e}, forces {worst_l:.3e}");
    assert!(share < 1.0, "the far field compressed: {share:.3} of the dense values");
    assert!(linalg::norm_inf(&a.state.t_fric) > 0.0, "friction acted");
}

/// (S.6) A run compresses W⁻¹ where it should: a dense W of ≥ HMATRIX_FROM (400) components
/// in velocity form — a wide, thin academic3d box (40×20×2 cells: 861 contact nodes, 2,583
/// unknowns, cheap to factor) with the dense form asked for — and its first 3 steps are those of
/// the dense products to Newton's tolerance: velocities within 1e-11 of their largest entry (the
/// bound of the test above), and the contact forces within Newton's tolerance (1e-10) of the
/// velocity scale read through W, max|W δr| with r = ω (λ, t) — the units the stopping test
/// measures them in. (Read entry by entry the friction forces differ by 2.1e-7 of the largest:
/// the loose directions change the path to the accepted solve, and on this thin box the
/// difference lies where W nearly vanishes — W maps it to 1.5e-14 of the velocity scale, as
/// small as the velocities' own difference. The exact-only form of the same hierarchical W⁻¹
/// follows the dense path: 3.8e-13 entry by entry.)
#[test]
fn auto_compresses_w_inverse_from_hmatrix_from_components() {
    let mut s = fixture("academic3d");
    s.domain.cells = Some(vec![40, 20, 2]);
    s.time.end = 3.0 * s.time.step;
    s.output.every = 0;
    let p = problem(with_form(s, ContactSolve::Dense));
    let m = p.contact.as_ref().map_or(0, |c| c.dim * c.n());
    assert!(m >= dyncontact::defaults::HMATRIX_FROM, "{m} components");
    let mut a = Simulation::new(&p).expect("setup");
    assert!(
        a.inverse.as_ref().is_some_and(|i| i.hierarchical().is_some() && i.hierarchical_w().is_some()),
        "W⁻¹ and W compressed at {m} components"
    );
    let mut b = Simulation::new(&p).expect("setup");
    b.inverse = b.inverse.take().map(|i| i.without_compression());
    let c = p.contact.as_ref().expect("contact");
    let (d, n) = (c.dim, c.n());
    let w = match b.delassus.as_ref() {
        Some(delassus::Delassus::Dense(w)) => w.clone(),
        _ => panic!("a dense W"),
    };
    let (mut worst_v, mut worst_l, mut worst_wr) = (0.0f64, 0.0f64, 0.0f64);
    for _ in 0..3 {
        a.step().expect("hierarchical step");
        b.step().expect("dense step");
        worst_v = worst_v.max(rel(&b.state.v, &a.state.v));
        worst_l = worst_l.max(rel(&b.state.lambda, &a.state.lambda)).max(rel(&b.state.t_fric, &a.state.t_fric));
        // δr = ω (δλ, δt) in W's components (normal first, then the d − 1 tangential ones)
        let mut dr = vec![0.0; d * n];
        for i in 0..n {
            dr[d * i] = c.omega[i] * (a.state.lambda[i] - b.state.lambda[i]);
            for j in 0..d - 1 {
                dr[d * i + 1 + j] = c.omega[i] * (a.state.t_fric[(d - 1) * i + j] - b.state.t_fric[(d - 1) * i + j]);
            }
        }
        let w_dr = &w * faer::ColRef::from_slice(&dr);
        let w_dr = (0..d * n).map(|l| w_dr[l].abs()).fold(0.0, f64::max);
        worst_wr = worst_wr.max(w_dr / linalg::norm_inf(&b.state.v));
    }
    println!(
        "40×20×2, hierarchical vs dense W⁻¹ over 3 steps: velocity {worst_v:.3e}, forces {worst_l:.3e} (through W {worst_wr:.3e} of the velocity scale)"
    );
    measured("auto_compresses_w_inverse_from_hmatrix_from_components", "forces through W", worst_wr, "≤ 1e-10");
    assert!(worst_v <= 1e-11 && worst_wr <= 1e-10, "velocity {worst_v:.3e}, forces through W {worst_wr:.3e}");
}

/// (S.6) The compression of W⁻¹ is certified, not assumed: on academic3d at 22×16×2 cells (1,173
/// contact unknowns, the dense W asked for) `compressed` keeps as its loose form the loosest ε
/// of HMATRIX_LOOSE_TOLERANCES (1e-6 of max|W⁻¹|) because ‖H − W⁻¹‖_F ≤ 0.1 / ‖W‖_∞ ≤ 0.1 λ_min(W⁻¹);
/// so H is positive definite with λ_min(H) ≥ 0.9 λ_min(W⁻¹) (Weyl). Checked here on H's dense
/// form (its products with the identity's columns): ‖H − W⁻¹‖_F is the one the compression
/// reports to 1e-6 of itself (the remainders carry round-off ~1e-16 of max|W⁻¹| per entry,
/// ~1e-10 of a norm of ~1e-5 max|W⁻¹|), and H's least eigenvalue is at least 0.9 of W⁻¹'s less
/// the eigensolver's round-off (1e-12 of the largest).
#[test]
fn the_hierarchical_inverse_is_certified_positive_definite() {
    let mut s = with_form(fixture("academic3d"), ContactSolve::Dense);
    s.domain.cells = Some(vec![22, 16, 2]);
    let p = problem(s);
    let c = p.contact.as_ref().expect("contact");
    let positions: Vec<[f64; 3]> = c.nodes.iter().map(|&i| p.mesh.point(i)).collect();
    let mut sim = Simulation::new(&p).expect("setup");
    let w = sim.delassus.take().expect("a dense W");
    let inverse = sim.inverse.take().expect("velocity form").compressed(&w, &positions);
    let h = inverse.hierarchical_loose().expect("a loose form");
    let m = inverse.winv.nrows();
    assert_eq!(h.tolerance(), dyncontact::defaults::HMATRIX_LOOSE_TOLERANCES[0], "the loosest ε certified");
    let mut dense_h = faer::Mat::<f64>::zeros(m, m);
    for j in 0..m {
        let e: Vec<f64> = (0..m).map(|l| if l == j { 1.0 } else { 0.0 }).collect();
        for (i, v) in h.apply(&e).into_iter().enumerate() {
            dense_h[(i, j)] = v;
        }
    }
    let error = (&dense_h - &inverse.winv).norm_l2();
    let extremes = |a: &faer::Mat<f64>| {
        let ev = a.self_adjoint_eigenvalues(faer::Side::Lower).expect("eigenvalues");
        (ev.iter().copied().fold(f64::INFINITY, f64::min), ev.iter().copied().fold(0.0f64, f64::max))
    };
    let (lmin, lmax) = extremes(&inverse.winv);
    let (lmin_h, _) = extremes(&dense_h);
    println!(
        "ε {:e}: ‖H − W⁻¹‖_F {error:.3e} (reported {:.3e}) = {:.2e} λ_min(W⁻¹); λ_min {lmin:.4e} → {lmin_h:.4e}",
        h.tolerance(),
        h.error_frobenius(),
        error / lmin
    );
    measured(
        "the_hierarchical_inverse_is_certified_positive_definite",
        "‖H − W⁻¹‖_F / λ_min(W⁻¹)",
        error / lmin,
        "≤ 0.1",
    );
    assert!((error - h.error_frobenius()).abs() <= 1e-6 * error, "{error:e} against {:e}", h.error_frobenius());
    assert!(error <= 0.1 * lmin, "certificate: {error:e} against λ_min {lmin:e}");
    assert!(lmin_h >= 0.9 * lmin - 1e-12 * lmax, "λ_min(H) {lmin_h:e} against λ_min(W⁻¹) {lmin:e}");
}

/// academic3d at 16×12×12 cells: a box as thick as it is wide, small enough for the suite.
fn thick_box() -> Problem {
    let mut s = fixture("academic3d");
    s.domain.cells = Some(vec![16, 12, 12]);
    problem(s)
}

/// (S.2) A_k of a thick box is factored under the nested dissection of its DOFs' positions
/// (`ordering`: its factor holds fewer than 0.85 of AMD's entries there) and that factor solves
/// A_k x = b as faer's AMD factor does: the two solutions agree within 1e-12 of the largest
/// entry (round-off of two backward-stable factorizations, machine ε times A_k's conditioning,
/// ~1e3 at this step), and so do W and W⁻¹ by the Schur complement (contact unknowns last)
/// under either order. Measured at 16×12×12 cells: 2,620,215 entries against 3,467,475 (0.756);
/// solves 5.8e-16, W 9.4e-16, W⁻¹ 1.2e-15 apart.
#[test]
fn a_thick_box_is_factored_under_the_nested_dissection() {
    use dyncontact::linalg::Cholesky;
    use dyncontact::ordering::FillOrder;
    let p = thick_box();
    let c = p.contact.as_ref().expect("contact");
    let sim = Simulation::new(&p).expect("setup");
    let stepper = dyncontact::scheme::StepOperator::new(&sim.ops, p.model.time.scheme, p.k).expect("A_k");
    let a = stepper.matrix().expect("A_k before release");
    let dissected = stepper.factor();
    let by_degree = Cholesky::new(a, "A_k", None).expect("AMD");
    let share = dissected.factor_len() as f64 / by_degree.factor_len() as f64;
    println!(
        "factor: {} entries under the dissection, {} under AMD ({share:.3})",
        dissected.factor_len(),
        by_degree.factor_len()
    );
    assert_eq!(dissected.fill_order(), FillOrder::NestedDissection, "share {share:.3}");
    assert_eq!(by_degree.fill_order(), FillOrder::MinimumDegree);
    let b: Vec<f64> = (0..a.nrows()).map(|l| ((l * 7919 + 13) % 101) as f64 / 101.0 - 0.5).collect();
    let (mut x, mut x0) = (b.clone(), b);
    dissected.solve_in_place(&mut x);
    by_degree.solve_in_place(&mut x0);
    let scale = x0.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let dx = x.iter().zip(&x0).fold(0.0f64, |m, (u, v)| m.max((u - v).abs())) / scale;
    let positions = Some(sim.ops.positions.as_slice());
    // the analysis the Schur route makes (its supernodal factor)
    let params = faer::sparse::linalg::cholesky::CholeskySymbolicParams {
        supernodal_flop_ratio_threshold: faer::sparse::linalg::SupernodalThreshold::FORCE_SUPERNODAL,
        ..Default::default()
    };
    let (_, schur_order) = dyncontact::ordering::analyse(a.symbolic(), positions, &c.dofs, params).expect("symbolic");
    assert_eq!(schur_order, FillOrder::NestedDissection, "the Schur complement's factor too");
    let (w, winv) = delassus::delassus_pair(a, positions, c, None).expect("Schur, dissected");
    let (w0, winv0) = delassus::delassus_pair(a, None, c, None).expect("Schur, AMD");
    let (dw, dwinv) = ((&w - &w0).norm_max() / w0.norm_max(), (&winv - &winv0).norm_max() / winv0.norm_max());
    println!("dissection vs AMD: solve {dx:.3e}, W {dw:.3e}, W⁻¹ {dwinv:.3e}");
    measured(
        "a_thick_box_is_factored_under_the_nested_dissection",
        "solve, W, W⁻¹ vs AMD",
        dx.max(dw).max(dwinv),
        "≤ 1e-12",
    );
    assert!(dx <= 1e-12 && dw <= 1e-12 && dwinv <= 1e-12, "solve {dx:.3e}, W {dw:.3e}, W⁻¹ {dwinv:.3e}");
    // a slender column keeps AMD: its dissection would hold more entries (measured 1.96× as many)
    let column = problem(fixture("column_impact3d"));
    let slender = Simulation::new(&column).expect("setup");
    assert_eq!(slender.stepper.factor().fill_order(), FillOrder::MinimumDegree);
}

/// (S.2) The step's split solve pair equals the whole one: with A_k's factor L (of P A_k Pᵀ)
/// supernodal, the free motion's contact velocities from the whole forward pass and the backward
/// pass over the contact unknowns' reach are those of the whole solve bit for bit (the same
/// kernels on the same rows); so is L⁻¹ P Hᵀ r by the forward pass over the reach, and v_free when
/// that backward pass is finished off the reach (a step without force). v^{n+1} =
/// Pᵀ L⁻ᵀ (L⁻¹ P b − L⁻¹ P Hᵀ r) equals A_k⁻¹ b − A_k⁻¹ Hᵀ r within 1e-14 of its largest entry (the
/// same passes summed in another order: round-off of a well-conditioned A_k; measured 2.0e-16
/// here). The reach is a strict part of the factor (measured 0.69 of its entries at 16×12×12),
/// and a run takes the split.
#[test]
fn the_split_solve_pair_equals_the_whole_one() {
    let p = thick_box();
    let c = p.contact.as_ref().expect("contact");
    let sim = Simulation::new(&p).expect("setup");
    let a = sim.stepper.factor();
    let reach = sim.reach().expect("the run splits its solves");
    let share = reach.entries() as f64 / a.factor_len() as f64;
    let n = a.dim();
    let b: Vec<f64> = (0..n).map(|l| ((l * 7919 + 13) % 101) as f64 / 101.0 - 0.5).collect();
    let mut whole = b.clone();
    a.solve_in_place(&mut whole);
    let z = a.forward(&b);
    let (x, at) = a.backward_over(reach, &z);
    assert!(c.restrict(&at) == c.restrict(&whole), "the contact velocities differ: {:.3e}", rel(&whole, &at));
    assert!(a.backward_rest(reach, x) == whole, "v_free finished off the reach differs from the whole solve");
    // forces on every node, and on one node only
    let mut worst = 0.0f64;
    for stride in [1, c.dofs.len()] {
        let r: Vec<f64> =
            (0..c.dofs.len()).map(|l| if l % stride == 0 { ((l * 37 % 11) as f64 - 5.0) * 1e3 } else { 0.0 }).collect();
        let mut hr = vec![0.0; n];
        c.scatter_add(&r, &mut hr);
        let mut minus = vec![0.0; n];
        a.forward_sub(reach, &hr, &mut minus);
        let forward: Vec<f64> = a.forward(&hr).iter().map(|v| -v).collect();
        assert!(minus == forward, "L⁻¹ P Hᵀ r over the reach differs from the whole pass");
        let mut corr = hr.clone();
        a.solve_in_place(&mut corr);
        let expected: Vec<f64> = whole.iter().zip(&corr).map(|(v, x)| v - x).collect();
        let mut z = z.clone();
        a.forward_sub(reach, &hr, &mut z);
        worst = worst.max(rel(&expected, &a.backward(z)));
    }
    println!("reach {share:.3} of the factor; v split against whole {worst:.3e}");
    measured("the_split_solve_pair_equals_the_whole_one", "relative difference of v", worst, "≤ 1e-14");
    assert!(share < 0.9, "the reach holds {share:.3} of the factor");
    assert!(worst <= 1e-14, "v differs by {worst:.3e}");
}
