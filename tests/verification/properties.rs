//! Property tests (proptest) of the element matrices, the loads and the contact laws:
//! identities that must hold for every input, checked on random inputs. Tolerances are
//! round-off bounds (a few ulps times the size of the terms) unless stated.

// index loops over nodes read like the conditions they check (several arrays at once)
#![allow(clippy::needless_range_loop)]

use dyncontact::fem::assemble::{Dofs, assemble_full};
use dyncontact::fem::{LoadVector, element};
use dyncontact::linalg;
use dyncontact::mesh::PlaneMesh;
use dyncontact::model::MaterialParams;
use dyncontact::model::expr::VecExpr;
use dyncontact::model::laws::{FrictionBoundLaw, FrictionCoefficient, NormalForceRule, NormalLaw};
use dyncontact::model::material::Material;
use dyncontact::scene::{MassKind, Plane};
use dyncontact::step::newton::{self, NewtonSettings, friction_residual, normal_residual};
use dyncontact::step::{NodeData, StepData};
use nalgebra::{Matrix3, SMatrix, SymmetricEigen};
use proptest::prelude::*;

fn material(young: f64, poisson: f64, theta: f64, zeta: f64, plane: Plane) -> Material {
    Material::new(&MaterialParams { density: 1.3, young, poisson, theta, zeta }, plane)
}

/// A non-degenerate triangle: three points with area ≥ 5% of the squared diameter.
fn triangle() -> impl Strategy<Value = [[f64; 2]; 3]> {
    prop::array::uniform3(prop::array::uniform2(-2.0..2.0f64)).prop_filter("non-degenerate", |x| {
        let a = 0.5 * ((x[1][0] - x[0][0]) * (x[2][1] - x[0][1]) - (x[2][0] - x[0][0]) * (x[1][1] - x[0][1]));
        let d2 = (0..3)
            .map(|i| (x[i][0] - x[(i + 1) % 3][0]).powi(2) + (x[i][1] - x[(i + 1) % 3][1]).powi(2))
            .fold(0.0, f64::max);
        a.abs() >= 0.05 * d2 && d2 > 1e-2
    })
}

/// The three rigid modes of a triangle: translations x, y and the rotation (−y, x).
fn rigid_modes(x: [[f64; 2]; 3]) -> [SMatrix<f64, 6, 1>; 3] {
    let mut t = [SMatrix::<f64, 6, 1>::zeros(); 3];
    for k in 0..3 {
        t[0][2 * k] = 1.0;
        t[1][2 * k + 1] = 1.0;
        t[2][2 * k] = -x[k][1];
        t[2][2 * k + 1] = x[k][0];
    }
    t
}

fn check_operator(ke: &SMatrix<f64, 6, 6>, x: [[f64; 2]; 3]) -> Result<(), TestCaseError> {
    let scale = ke.amax();
    prop_assert!((ke - ke.transpose()).amax() <= 1e-13 * scale, "not symmetric");
    for mode in rigid_modes(x) {
        prop_assert!((ke * mode).amax() <= 1e-12 * scale * (1.0 + mode.amax()), "a rigid mode is not in the kernel");
    }
    let mut eig: Vec<f64> = SymmetricEigen::new(*ke).eigenvalues.iter().copied().collect();
    eig.sort_by(f64::total_cmp);
    // exactly three zero eigenvalues (round-off), the other three clearly positive
    prop_assert!(eig[..3].iter().all(|e| e.abs() <= 1e-11 * scale), "kernel larger than rigid modes: {eig:?}");
    prop_assert!(eig[3] >= 1e-6 * scale, "a deformation mode has no energy: {eig:?}");
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// (P.1) (P.2) On every non-degenerate triangle, K_e (from B) and C_e (from A) are
    /// symmetric positive semi-definite with exactly the three rigid-body modes in the kernel.
    #[test]
    fn p1_p2_element_matrices_symmetric_psd_with_rigid_kernel(
        x in triangle(), young in 0.1..1e4f64, poisson in -0.9..0.49f64, theta in 0.0..10.0f64, zeta in 0.01..10.0f64,
        stress in any::<bool>(),
    ) {
        let plane = if stress { Plane::Stress } else { Plane::Strain };
        let mat = material(young, poisson, theta, zeta, Plane::Strain);
        check_operator(&element::operator_matrix(x, &mat.elasticity()), x)?;
        check_operator(&element::operator_matrix(x, &mat.viscosity()), x)?;
        // plane stress constants (with proportional viscosity: the algebraic reduction)
        let (l, m) = dyncontact::model::material::lame(young, poisson);
        let ps = material(young, poisson, 0.5 * l / m * zeta, 0.5 * zeta, plane);
        check_operator(&element::operator_matrix(x, &ps.elasticity()), x)?;
        let d: Matrix3<f64> = ps.elasticity();
        prop_assert!(d.symmetric_eigenvalues().iter().all(|e| *e > 0.0), "B is not positive definite");
    }

    /// (P.2) Lumped and consistent mass matrices both carry ρ·area per component, and the
    /// consistent element mass is symmetric positive definite.
    #[test]
    fn p2_mass_matrices_sum_to_rho_area(x in triangle(), rho in 0.01..100.0f64) {
        let (_, area) = element::gradients(x);
        for me in [element::consistent_mass(area.abs(), rho), element::lumped_mass(area.abs(), rho)] {
            for c in 0..2 {
                let s: f64 = (0..3).flat_map(|i| (0..3).map(move |j| (i, j))).map(|(i, j)| me[(2 * i + c, 2 * j + c)]).sum();
                prop_assert!((s - rho * area.abs()).abs() <= 1e-14 * rho * area.abs() * 10.0);
            }
            prop_assert!(SymmetricEigen::new(me).eigenvalues.iter().all(|e| *e > 0.0));
        }
    }

    /// (P.2) Assembled over a mesh, both mass matrices sum to ρ·|Ω| per component.
    #[test]
    fn p2_assembled_mass_sums_to_rho_area(lx in 0.1..5.0f64, ly in 0.1..5.0f64, nx in 1usize..8, ny in 1usize..8, consistent in any::<bool>()) {
        let mesh = PlaneMesh::rectangle(lx, ly, nx, ny);
        let mat = material(100.0, 0.3, 0.0, 0.0, Plane::Strain);
        let kind = if consistent { MassKind::Consistent } else { MassKind::Lumped };
        let (m, _, _) = assemble_full(&mesh, &mat, kind).expect("assembly");
        let ones_x: Vec<f64> = (0..2 * mesh.nodes.len()).map(|i| if i % 2 == 0 { 1.0 } else { 0.0 }).collect();
        let total = linalg::quad(&m, &ones_x, &ones_x);
        prop_assert!((total - mat.rho * lx * ly).abs() <= 1e-12 * mat.rho * lx * ly);
    }

    /// (P.4) A constant body force integrates to f0·|Ω| and a constant traction to f2·|side|.
    #[test]
    fn p4_constant_loads_sum_to_force(lx in 0.1..5.0f64, ly in 0.1..5.0f64, nx in 1usize..8, ny in 1usize..8, fx in -10.0..10.0f64, fy in -10.0..10.0f64) {
        let mesh = PlaneMesh::rectangle(lx, ly, nx, ny);
        let dofs = Dofs::with_dim(mesh.nodes.len(), &vec![false; mesh.nodes.len()], 2);
        let body = VecExpr::parse(&[format!("{fx}"), format!("{fy}")], &["x", "y", "t"], "b").expect("expr");
        let f = LoadVector::new(&mesh, &dofs, &body, &[]).at(0.3);
        let (sx, sy): (f64, f64) = (f.iter().step_by(2).sum(), f.iter().skip(1).step_by(2).sum());
        let tol = 1e-12 * (fx.abs() + fy.abs() + 1.0) * lx * ly;
        prop_assert!((sx - fx * lx * ly).abs() <= tol && (sy - fy * lx * ly).abs() <= tol);
        let top = mesh.side("top").expect("top").facets.clone();
        let tr = VecExpr::parse(&[format!("{fy}"), format!("{fx}")], &["x", "y", "t"], "t").expect("expr");
        let g = LoadVector::new(&mesh, &dofs, &VecExpr::zero(2), &[(top, tr, "t".into())]).at(0.0);
        let (gx, gy): (f64, f64) = (g.iter().step_by(2).sum(), g.iter().skip(1).step_by(2).sum());
        prop_assert!((gx - fy * lx).abs() <= 1e-12 * (fy.abs() + 1.0) * lx && (gy - fx * lx).abs() <= 1e-12 * (fx.abs() + 1.0) * lx);
    }

    /// (P.3) Clamping a side removes both DOFs of each of its nodes and nothing else.
    #[test]
    fn p3_clamped_dofs_are_eliminated(nx in 1usize..10, ny in 1usize..10) {
        let mesh = PlaneMesh::rectangle(1.0, 1.0, nx, ny);
        let clamped = mesh.nodes_on(&["left".to_string()]).expect("left");
        let dofs = Dofs::with_dim(mesh.nodes.len(), &clamped, 2);
        prop_assert_eq!(dofs.n_free, 2 * (mesh.nodes.len() - (ny + 1)));
        for (k, c) in clamped.iter().enumerate() {
            prop_assert_eq!(dofs.map[2 * k].is_none(), *c);
            prop_assert_eq!(dofs.map[2 * k + 1].is_none(), *c);
        }
    }

    /// (P.5) p is zero for r ≤ 0 and nondecreasing; so is p_ε (Pe.5).
    #[test]
    fn p5_compliance_is_monotone_and_zero_below(c in 0.0..1e4f64, r1 in -1.0..1.0f64, r2 in -1.0..1.0f64, g in 0.0..0.5f64, eps in 1e-8..1.0f64) {
        for law in [NormalLaw::compliance(c), NormalLaw::penalized(c, g, eps)] {
            if r1 <= 0.0 {
                prop_assert_eq!(law.p(r1), 0.0);
            }
            let (lo, hi) = if r1 < r2 { (r1, r2) } else { (r2, r1) };
            prop_assert!(law.p(lo) <= law.p(hi));
            prop_assert!(law.energy(lo.min(0.0)) == 0.0);
        }
    }

    /// (S.3) (Pe.5) The discrete gradient satisfies DP(a, b)(b − a) = P(b) − P(a) and
    /// DP(a, a) = p(a), for the compliance and the penalized law, every sign combination; its
    /// b-derivative matches central differences away from the kinks.
    #[test]
    fn s3_discrete_gradient_identity(c in 0.0..1e4f64, a in -0.1..0.1f64, b in -0.1..0.1f64, g in 0.0..0.05f64, eps in 1e-6..1.0f64) {
        for law in [NormalLaw::compliance(c), NormalLaw::penalized(c, g, eps)] {
            let lhs = law.discrete_gradient(a, b) * (b - a);
            let rhs = law.energy(b) - law.energy(a);
            let scale = law.energy(a).abs() + law.energy(b).abs() + 1e-300;
            prop_assert!((lhs - rhs).abs() <= 1e-12 * scale, "DP(a,b)(b−a) = {lhs}, P(b) − P(a) = {rhs}");
            prop_assert_eq!(law.discrete_gradient(a, a), law.p(a));
            // derivative in b (skip points within h of a kink, where it jumps)
            let h = 1e-7;
            let near_kink = law.hinges.iter().any(|k| (b - k.s).abs() < 10.0 * h || (a - k.s).abs() < 10.0 * h) || (a - b).abs() < 10.0 * h;
            if !near_kink {
                let fd = (law.discrete_gradient(a, b + h) - law.discrete_gradient(a, b - h)) / (2.0 * h);
                let an = law.discrete_gradient_db(a, b);
                let hs = law.hinges.iter().map(|k| k.c).fold(0.0, f64::max);
                prop_assert!((fd - an).abs() <= 1e-5 * hs + 1e-9, "∂_b DP = {an}, finite difference {fd}");
            }
        }
    }

    /// (P.6) μ laws: μ(0) is the static value; the exponential law is monotone between a and b
    /// and |μ'| ≤ L_μ; the table interpolates its points and is constant beyond the last.
    #[test]
    fn p6_friction_coefficient_laws(a in 0.0..2.0f64, b in 0.0..2.0f64, alpha in 0.0..100.0f64, r in 0.0..10.0f64) {
        let mu = FrictionCoefficient::Exponential { a, b, alpha };
        prop_assert!((mu.mu(0.0) - a).abs() <= 1e-15 * (1.0 + a));
        let v = mu.mu(r);
        prop_assert!(v >= a.min(b) - 1e-15 && v <= a.max(b) + 1e-15);
        prop_assert!(mu.dmu(r).abs() <= mu.lipschitz() * (1.0 + 1e-12));
        let table = FrictionCoefficient::Table(vec![[0.0, a], [0.5, b], [1.5, 0.5 * (a + b)]]);
        prop_assert_eq!(table.mu(0.0), a);
        prop_assert!((table.mu(0.5) - b).abs() <= 1e-15);
        prop_assert_eq!(table.mu(1.5 + r), 0.5 * (a + b));
        prop_assert!((table.mu(0.25) - 0.5 * (a + b)).abs() <= 1e-14);
        prop_assert!(table.dmu(r).abs() <= table.lipschitz() + 1e-14);
        prop_assert_eq!(FrictionCoefficient::Constant(a).mu(r), a);
    }

    /// (P.6) The capped friction-bound normal part p_τ(r) = p(min(r_+, g)) equals p on [0, g],
    /// saturates at p(g) beyond, is 0 for r ≤ 0; uncapped it is p.
    #[test]
    fn p6_capped_bound_saturates_at_g(c in 0.0..1e4f64, g in 0.0..0.1f64, r in -0.2..0.2f64) {
        let law = NormalLaw::compliance(c);
        let capped = FrictionBoundLaw { compliance: law.clone(), cap: Some(g) };
        let uncapped = FrictionBoundLaw { compliance: law.clone(), cap: None };
        let expect = if r <= 0.0 { 0.0 } else if r <= g { law.p(r) } else { law.p(g) };
        prop_assert_eq!(capped.p_tau(r), expect);
        prop_assert!(capped.p_tau(r) <= capped.sup());
        prop_assert_eq!(uncapped.p_tau(r), law.p(r));
    }

    /// (P.8) ψ' = μ(|ξ|) sgn ξ away from 0 (central differences, error O(h²μ'')), and the
    /// one-sided slopes at 0 are ±μ(0): the Clarke subdifferential at 0 is [−μ(0), μ(0)].
    #[test]
    fn p8_psi_derivative_is_mu_and_subdifferential_at_zero(a in 0.0..2.0f64, b in 0.0..2.0f64, alpha in 0.0..50.0f64, xi in -3.0..3.0f64) {
        let laws = [
            FrictionCoefficient::Exponential { a, b, alpha },
            FrictionCoefficient::Table(vec![[0.0, a], [0.4, b], [1.0, 0.3 * a + 0.2]]),
            FrictionCoefficient::Constant(a),
        ];
        for mu in laws {
            let h = 1e-6;
            let kinks = [0.0f64, 0.4, 1.0];
            if kinks.iter().all(|k| (xi.abs() - k).abs() > 10.0 * h) {
                let fd = (mu.psi(xi + h) - mu.psi(xi - h)) / (2.0 * h);
                prop_assert!((fd - mu.mu(xi.abs()) * xi.signum()).abs() <= 1e-6 * (1.0 + mu.lipschitz()), "ψ' = {fd}, μ sgn ξ = {}", mu.mu(xi.abs()) * xi.signum());
            }
            let h0 = 1e-9;
            let right = (mu.psi(h0) - mu.psi(0.0)) / h0;
            let left = (mu.psi(0.0) - mu.psi(-h0)) / h0;
            prop_assert!((right - mu.mu(0.0)).abs() <= mu.lipschitz() * h0 + 1e-6);
            prop_assert!((left + mu.mu(0.0)).abs() <= mu.lipschitz() * h0 + 1e-6);
        }
    }

    /// (N.2) The Alart–Curnier normal residual vanishes exactly on the complementarity set
    /// {λ ≥ 0, y ≤ β, λ(y − β) = 0} and nowhere else, for any parameter ρ > 0.
    #[test]
    fn n2_normal_residual_zero_iff_complementarity(lambda in -1.0..1.0f64, y in -1.0..1.0f64, beta in -1.0..1.0f64, rho in 1e-3..1e3f64, on_set in 0u8..3) {
        let (l, yy) = match on_set {
            0 => (lambda.abs(), beta),          // active: λ ≥ 0, y = β
            1 => (0.0, beta - y.abs() - 1e-3), // inactive: λ = 0, y < β
            _ => (lambda, y),                   // anywhere
        };
        let r = normal_residual(l, yy, beta, rho);
        let comp = l >= 0.0 && yy <= beta && (l * (yy - beta)).abs() <= 1e-15;
        if comp { prop_assert!(r.abs() <= 1e-15 * (1.0 + l.abs() / rho + beta.abs()), "residual {r} on the set"); }
        else { prop_assert!(r != 0.0, "zero residual off the set: λ {l}, y {yy}, β {beta}"); }
    }
}

/// A condensed step problem as the strategy draws it: n, then the vectors and scalars the tests unpack.
type StepProblem = (usize, Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>, f64, f64);

/// A random condensed step problem: n nodes, SPD W, compliance with the bound g.
fn step_problem() -> impl Strategy<Value = StepProblem> {
    (1usize..5).prop_flat_map(|n| {
        let m = 2 * n;
        (
            Just(n),
            prop::collection::vec(-1.0..1.0f64, m * m),
            prop::collection::vec(-2.0..2.0f64, m),
            prop::collection::vec(-0.02..0.02f64, n),
            prop::collection::vec(-1.0..1.0f64, n),
            prop::collection::vec(0.0..5.0f64, n),
            100.0..5000.0f64,
            1e-4..1e-2f64,
        )
    })
}

fn build(n: usize, wraw: &[f64]) -> faer::Mat<f64> {
    let m = 2 * n;
    // W = B Bᵀ/m + 0.05 I: symmetric positive definite, scale ~ k/m for k ~ 0.05
    faer::Mat::<f64>::from_fn(m, m, |i, j| {
        let s: f64 = (0..m).map(|l| wraw[i * m + l] * wraw[j * m + l]).sum::<f64>() / m as f64;
        0.05 * (s + if i == j { 0.05 } else { 0.0 })
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(150))]

    /// (N.3) (S.5) At the Newton solution of random frozen step problems, the friction return
    /// map holds: |t_i| ≤ S_i and t_i v̄_i = S_i |v̄_i| (relative 1e-8: the solver's tolerance
    /// 1e-12 on velocities times the problem's force/velocity ratio), and all Alart–Curnier
    /// residuals vanish for any r_ν, r_τ > 0 (ρ rescaled by 10 and 0.1).
    #[test]
    fn n3_friction_return_map((n, wraw, y_free, d_n, v_t, s, c, k) in step_problem(), bound in any::<bool>()) {
        let w = dyncontact::step::delassus::Delassus::Dense(build(n, &wraw));
        let law = NormalLaw::compliance(c);
        let g = 0.01;
        let nodes: Vec<NodeData> = (0..n).map(|i| NodeData {
            omega: 0.1, d_n: d_n[i].min(g), d_aff: d_n[i].min(g) + 0.5 * k * 0.3, v_aff: [0.5 * v_t[i], 0.0], bound: bound.then_some(g),
        }).collect();
        let mut factors = dyncontact::step::delassus::DelassusFactors::default();
        let data = StepData { delassus: &w, y_free: y_free.clone(), nodes, a_d: 0.5 * k, a_v: 0.5, force_rule: NormalForceRule::DiscreteGradient, law: &law, friction: true, dim: 2, inverse: None };
        let set = NewtonSettings { tolerance: 1e-12, max_iterations: 100, ..NewtonSettings::default() };
        let sol = newton::solve(&data, &mut factors, &s, &vec![0.0; n], &vec![0.0; n], &set);
        prop_assert!(sol.is_ok(), "Newton failed: {:?}", sol.err());
        let sol = sol.expect("checked");
        let smax = s.iter().fold(1e-300f64, |m, v| m.max(*v));
        let vs = data.velocity_scale(&sol.y);
        for i in 0..n {
            let vbar = data.slip(i, &sol.y);
            prop_assert!(sol.t[i].abs() <= s[i] * (1.0 + 1e-12) + 1e-12 * smax, "|t| = {} > S = {}", sol.t[i].abs(), s[i]);
            if vbar.abs() > 1e-8 * vs {
                prop_assert!((sol.t[i] * vbar - s[i] * vbar.abs()).abs() <= 1e-8 * smax * vbar.abs(), "slip without t = S sgn v̄");
            }
            for rho in [0.3, 3.0, 300.0] {
                prop_assert!(friction_residual(sol.t[i], vbar, s[i], rho, 0.5).abs() <= 1e-8 * vs, "N.3 residual with ρ = {rho}");
                if let Some(beta) = data.beta(i) {
                    prop_assert!(normal_residual(sol.lambda[i], sol.y[2 * i], beta, rho).abs() <= 1e-8 * vs + 1e-10 * sol.lambda[i].abs() / rho, "N.2 residual with ρ = {rho}");
                }
            }
        }
    }
}
