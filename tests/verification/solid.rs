//! Three dimensions, first layer: the structured box of tetrahedra, the P1
//! tetrahedron's element matrices, the assembled M, K, C of a box, surface normals and weights on
//! Γ3 and the tangent frames, and the mesh errors (inverted, degenerate, non-manifold).
//!
//! Why the expected values are what they are: P1 tetrahedra reproduce linear fields exactly, so
//! rigid motions are in the kernel of K (and C) to round-off, element and total masses are
//! ρ·volume exactly (up to summation round-off), and the Kuhn subdivision of a box tiles it
//! exactly (volumes and face areas add up to the box's). Tolerances are round-off bounds: a few
//! hundred ulps of the terms summed.

use dyncontact::fem::assemble::assemble_solid;
use dyncontact::fem::tet;
use dyncontact::linalg;
use dyncontact::mesh::{Side, SolidMesh};
use dyncontact::model::MaterialParams;
use dyncontact::model::contact::Frame;
use dyncontact::model::material::Material;
use dyncontact::scene::{MassKind, Plane};
use nalgebra::{SMatrix, SymmetricEigen};
use proptest::prelude::*;

fn material() -> Material {
    Material::new(&MaterialParams { density: 1.3, young: 1000.0, poisson: 0.3, theta: 2.0, zeta: 1.5 }, Plane::Strain)
}

/// The six rigid modes at the points x (translations, then rotations about x, y, z).
fn rigid_modes(x: &[[f64; 3]]) -> Vec<Vec<f64>> {
    let mut modes = vec![vec![0.0; 3 * x.len()]; 6];
    for (k, p) in x.iter().enumerate() {
        for c in 0..3 {
            modes[c][3 * k + c] = 1.0;
        }
        // ω × x for ω = e_x, e_y, e_z
        let rot = [[0.0, -p[2], p[1]], [p[2], 0.0, -p[0]], [-p[1], p[0], 0.0]];
        for (r, v) in rot.iter().enumerate() {
            for c in 0..3 {
                modes[3 + r][3 * k + c] = v[c];
            }
        }
    }
    modes
}

/// A tetrahedron with volume ≥ 2% of its diameter cubed.
fn tetrahedron() -> impl Strategy<Value = [[f64; 3]; 4]> {
    prop::array::uniform4(prop::array::uniform3(-2.0..2.0f64)).prop_filter("non-degenerate", |x| {
        let Some((_, v)) = tet::gradients(*x) else { return false };
        let d = (0..4)
            .flat_map(|i| (0..4).map(move |j| (i, j)))
            .map(|(i, j)| (0..3).map(|c| (x[i][c] - x[j][c]).powi(2)).sum::<f64>().sqrt())
            .fold(0.0, f64::max);
        v.abs() >= 0.02 * d.powi(3) && d > 0.1
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// (P.1) The tetrahedron's K_e is symmetric positive semidefinite with exactly the six rigid
    /// modes in its kernel (round-off: 1e-11 of the largest entry), and the strain of a linear
    /// field u = G x is sym(G) on every tetrahedron (1e-12: exact for P1 up to round-off).
    #[test]
    fn p1_tetrahedron_stiffness_is_psd_with_the_rigid_kernel(x in tetrahedron(), g in prop::array::uniform9(-1.0..1.0f64)) {
        let ke = tet::operator_matrix(x, &material().elasticity_3d()).expect("non-degenerate");
        let scale = ke.amax();
        prop_assert!((ke - ke.transpose()).amax() <= 1e-13 * scale, "not symmetric");
        for mode in rigid_modes(&x) {
            let m = SMatrix::<f64, 12, 1>::from_column_slice(&mode);
            prop_assert!((ke * m).amax() <= 1e-11 * scale * (1.0 + m.amax()), "a rigid mode is not in the kernel");
        }
        let mut eig: Vec<f64> = SymmetricEigen::new(ke).eigenvalues.iter().copied().collect();
        eig.sort_by(f64::total_cmp);
        prop_assert!(eig[..6].iter().all(|e| e.abs() <= 1e-10 * scale), "kernel larger than the rigid modes: {eig:?}");
        prop_assert!(eig[6] >= 1e-8 * scale, "a deformation mode has no energy: {eig:?}");

        let (grad, _) = tet::gradients(x).expect("non-degenerate");
        let mut u = SMatrix::<f64, 12, 1>::zeros();
        for (k, p) in x.iter().enumerate() {
            for r in 0..3 {
                u[3 * k + r] = (0..3).map(|c| g[3 * r + c] * p[c]).sum();
            }
        }
        let eps = tet::strain_matrix(&grad) * u;
        let gm = |r: usize, c: usize| g[3 * r + c];
        let want = [gm(0, 0), gm(1, 1), gm(2, 2), gm(1, 2) + gm(2, 1), gm(0, 2) + gm(2, 0), gm(0, 1) + gm(1, 0)];
        for (a, b) in eps.iter().zip(want) {
            prop_assert!((a - b).abs() <= 1e-12 * 8.0, "strain {a} against {b}");
        }
    }

    /// (P.2) The tetrahedron's consistent and lumped masses carry ρ|T| per component
    /// (1e-14 relative: twelve-term sums).
    #[test]
    fn p2_tetrahedron_masses_sum_to_rho_volume(x in tetrahedron()) {
        let (_, v) = tet::gradients(x).expect("non-degenerate");
        let m = tet::consistent_mass(v.abs(), 1.3);
        for c in 0..3 {
            let total: f64 = (0..4).flat_map(|i| (0..4).map(move |j| (i, j))).map(|(i, j)| m[(3 * i + c, 3 * j + c)]).sum();
            prop_assert!((total - 1.3 * v.abs()).abs() <= 1e-14 * 1.3 * v.abs());
        }
        prop_assert!((4.0 * tet::vertex_mass(v.abs(), 1.3) - 1.3 * v.abs()).abs() <= 1e-15 * v.abs());
    }

    /// (N.3) in 3-D, the disk: F_t = 0 at t = S v̂ for any slip v ≠ 0 and at any ‖t‖ ≤ S when
    /// v = 0, and F_t ≠ 0 when t turns away from v̂ while slipping (round-off: 1e-12 of the
    /// velocity scale).
    #[test]
    fn n3_disk_residual_vanishes_exactly_on_the_friction_law(v in prop::array::uniform2(-1.0..1.0f64), s in 0.1..2.0f64, rho in 0.1..10.0f64, turn in 0.1..3.0f64) {
        use dyncontact::step::newton::friction_residual_disk;
        let nv = v[0].hypot(v[1]);
        prop_assume!(nv > 1e-3);
        let t = [s * v[0] / nv, s * v[1] / nv];
        let f = friction_residual_disk(t, v, s, rho, 0.5);
        prop_assert!(f[0].hypot(f[1]) <= 1e-12 * (1.0 + nv), "slip on the law: {f:?}");
        let inside = [0.5 * s * v[1] / nv, -0.3 * s * v[0] / nv];
        let f = friction_residual_disk(inside, [0.0, 0.0], s, rho, 0.5);
        prop_assert!(f[0].hypot(f[1]) <= 1e-15, "stick inside the disk: {f:?}");
        let (c, sn) = (turn.cos(), turn.sin());
        let turned = [c * t[0] - sn * t[1], sn * t[0] + c * t[1]];
        let f = friction_residual_disk(turned, v, s, rho, 0.5);
        prop_assert!(f[0].hypot(f[1]) > 1e-6 * s / rho, "a force turned by {turn} from the slip gives no residual");
    }

    /// Contact frames in 3-D: (τ_1, τ_2, ν) orthonormal and right-handed for every unit normal
    /// (1e-14: a few products of unit vectors).
    #[test]
    fn spatial_frames_are_orthonormal_and_right_handed(n in prop::array::uniform3(-1.0..1.0f64)) {
        let norm = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        prop_assume!(norm > 1e-3);
        let f = Frame::spatial(n.map(|c| c / norm));
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let [t1, t2] = f.tangents;
        for (a, b, want) in [(t1, t1, 1.0), (t2, t2, 1.0), (f.normal, f.normal, 1.0), (t1, t2, 0.0), (t1, f.normal, 0.0), (t2, f.normal, 0.0)] {
            prop_assert!((dot(a, b) - want).abs() <= 1e-14);
        }
        let cross = [t1[1] * t2[2] - t1[2] * t2[1], t1[2] * t2[0] - t1[0] * t2[2], t1[0] * t2[1] - t1[1] * t2[0]];
        prop_assert!((dot(cross, f.normal) - 1.0).abs() <= 1e-14, "not right-handed");
    }
}

/// The box generator: 6 positive tetrahedra per cell tiling the box (volume to 1e-13), every
/// interior face shared by two tetrahedra (conforming), the six sides with two faces per cell
/// face, their areas and outward normals exact, and `check` passes.
#[test]
fn box_of_tetrahedra_tiles_the_box_with_six_sides() {
    let (l, n) = ([1.0, 0.75, 0.5], [4, 3, 2]);
    let mesh = SolidMesh::cuboid(l, n);
    mesh.check().expect("the box is a valid mesh");
    assert_eq!(mesh.nodes.len(), 5 * 4 * 3);
    assert_eq!(mesh.cells.len(), 6 * 4 * 3 * 2);
    assert!((0..mesh.cells.len()).all(|t| mesh.signed_measure(t) > 0.0));
    let vol = l[0] * l[1] * l[2];
    assert!((mesh.measure() - vol).abs() <= 1e-13 * vol, "volume {} against {vol}", mesh.measure());
    let faces = mesh.boundary_faces().len();
    assert_eq!(faces, 2 * 2 * (n[0] * n[1] + n[1] * n[2] + n[0] * n[2]), "boundary faces (conformity)");
    let expect = [
        ("left", [-1.0, 0.0, 0.0], l[1] * l[2], n[1] * n[2]),
        ("right", [1.0, 0.0, 0.0], l[1] * l[2], n[1] * n[2]),
        ("front", [0.0, -1.0, 0.0], l[0] * l[2], n[0] * n[2]),
        ("back", [0.0, 1.0, 0.0], l[0] * l[2], n[0] * n[2]),
        ("bottom", [0.0, 0.0, -1.0], l[0] * l[1], n[0] * n[1]),
        ("top", [0.0, 0.0, 1.0], l[0] * l[1], n[0] * n[1]),
    ];
    for (name, normal, area, cells) in expect {
        let side = mesh.side(name).expect(name);
        assert_eq!(side.facets.len(), 2 * cells, "{name}: faces");
        let geo = mesh.facet_geometry(side).expect("boundary faces");
        let total: f64 = geo.iter().map(|g| g.1).sum();
        assert!((total - area).abs() <= 1e-14 * area * cells as f64, "{name}: area {total} against {area}");
        for (nrm, _) in &geo {
            assert!((0..3).all(|c| (nrm[c] - normal[c]).abs() <= 1e-15), "{name}: normal {nrm:?}");
        }
        // the stored orientation is outward too: (x1 − x0) × (x2 − x0) along the normal
        for f in &side.facets {
            let [p, q, r] = f.map(|v| mesh.nodes[v]);
            let c = [
                (q[1] - p[1]) * (r[2] - p[2]) - (q[2] - p[2]) * (r[1] - p[1]),
                (q[2] - p[2]) * (r[0] - p[0]) - (q[0] - p[0]) * (r[2] - p[2]),
                (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]),
            ];
            assert!(c[0] * normal[0] + c[1] * normal[1] + c[2] * normal[2] > 0.0, "{name}: face {f:?} is not outward");
        }
    }
}

/// Nodal data on Γ3 = bottom of a box, and with the left side clamped: normals (0, 0, −1)
/// exactly, weights ω_i = Σ |F|/3 summing to the bottom's area (15 terms: 1e-15 × 15), and the
/// nodes on x = 0 left out when clamped.
#[test]
fn surface_nodes_of_a_box_side() {
    let mesh = SolidMesh::cuboid([2.0, 1.0, 0.5], [4, 2, 1]);
    let clamped = mesh.nodes_on(&["left".to_string()]).expect("left");
    let all = mesh.side_nodes(&["bottom".to_string()], &[]).expect("bottom");
    assert_eq!(all.nodes.len(), 5 * 3);
    let total: f64 = all.omega.iter().sum();
    assert!((total - 2.0).abs() <= 1e-15 * 15.0, "Σ ω = {total} against the area 2");
    assert!(all.normals.iter().all(|n| n == &[0.0, 0.0, -1.0]), "bottom normals");
    let free = mesh.side_nodes(&["bottom".to_string()], &clamped).expect("bottom");
    assert_eq!(free.nodes.len(), 4 * 3, "the x = 0 row is clamped");
    assert!(free.nodes.iter().all(|&v| mesh.nodes[v][0] > 0.0 && mesh.nodes[v][2] == 0.0));
}

/// (P.2) The assembled operators of a box: rigid motions in the kernel of K and C (1e-11 of
/// ‖K‖ times the mode's size), K and C symmetric, and M carrying ρ·volume per component for
/// the consistent and the lumped mass (1e-13: sums over 1,152 entries).
#[test]
fn p2_box_operators_have_rigid_kernel_and_total_mass() {
    let mesh = SolidMesh::cuboid([1.0, 0.5, 0.5], [4, 2, 2]);
    let mat = material();
    for mass in [MassKind::Consistent, MassKind::Lumped] {
        let (m, k, c) = assemble_solid(&mesh, &mat, mass).expect("assembly");
        for a in [&k, &c] {
            let scale = linalg::triplets(a).iter().fold(0.0f64, |s, t| s.max(t.2.abs()));
            for mode in rigid_modes(&mesh.nodes) {
                let r = linalg::mul(a, &mode);
                let size = linalg::norm_inf(&mode);
                assert!(
                    linalg::norm_inf(&r) <= 1e-11 * scale * size,
                    "{mass:?}: a rigid mode is not in the kernel: {:.3e}",
                    linalg::norm_inf(&r) / scale
                );
            }
            let asym = linalg::triplets(a)
                .iter()
                .map(|&(i, j, v)| {
                    (v - linalg::triplets(a).iter().find(|t| t.0 == j && t.1 == i).map(|t| t.2).unwrap_or(0.0)).abs()
                })
                .fold(0.0, f64::max);
            assert!(asym <= 1e-13 * scale, "not symmetric: {asym:.3e}");
        }
        let vol = 0.25;
        for comp in 0..3 {
            let ones: Vec<f64> = (0..3 * mesh.nodes.len()).map(|i| if i % 3 == comp { 1.0 } else { 0.0 }).collect();
            let total = linalg::quad(&m, &ones, &ones);
            assert!((total - 1.3 * vol).abs() <= 1e-13 * 1.3 * vol, "{mass:?}: component {comp} mass {total}");
        }
    }
}

/// Mesh errors name what is wrong: an inverted tetrahedron ("negative (inverted)"), a flat one
/// ("zero (degenerate)"), and a contact surface whose edge is shared by four faces (two
/// tetrahedra meeting along an edge only: "not a manifold").
#[test]
fn solid_mesh_errors_name_the_defect() {
    let mut mesh = SolidMesh::cuboid([1.0, 1.0, 1.0], [1, 1, 1]);
    mesh.cells[3].swap(0, 1);
    let e = mesh.check().expect_err("inverted").to_string();
    assert!(e.contains("tetrahedron 3") && e.contains("negative (inverted)"), "{e}");

    let mut flat = SolidMesh::cuboid([1.0, 1.0, 1.0], [1, 1, 1]);
    let t = flat.cells[0];
    flat.nodes.push([0.5, 0.5, 0.0]);
    flat.nodes.push([0.25, 0.25, 0.0]);
    let (p, q) = (flat.nodes.len() - 2, flat.nodes.len() - 1);
    flat.cells.push([t[0], t[1], p, q]);
    let e = flat.check().expect_err("degenerate").to_string();
    assert!(e.contains("zero (degenerate)"), "{e}");

    // two tetrahedra sharing only the edge (0, 1)
    let nodes =
        vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]];
    let mut bowtie = SolidMesh {
        nodes,
        cells: vec![[0, 1, 2, 3], [0, 1, 4, 5]],
        sides: Vec::new(),
        source: "bowtie".into(),
        tags: None,
    };
    let faces: Vec<[usize; 3]> =
        bowtie.boundary_faces().into_iter().filter(|f| f.contains(&0) && f.contains(&1)).collect();
    assert_eq!(faces.len(), 4);
    bowtie.sides.push(Side { name: "contact".into(), facets: faces });
    bowtie.check().expect("each tetrahedron is valid");
    let e = bowtie.side_nodes(&["contact".to_string()], &[]).expect_err("non-manifold").to_string();
    assert!(e.contains("the edge between node 0 and node 1") && e.contains("not a manifold"), "{e}");
}

/// The degree-5 tetrahedron rule of the 3-D error norms integrates every monomial
/// λ1^a λ2^b λ3^c λ0^d of degree ≤ 5 exactly: 3! a! b! c! d! / (a + b + c + d + 3)! of the volume
/// (to 1e-14, round-off of 64 products).
#[test]
fn tet_rule_is_exact_to_degree_five() {
    let rule = dyncontact::fem::norms::tet_rule();
    let fact = |n: u32| (1..=n).map(f64::from).product::<f64>();
    let mut worst = 0.0f64;
    for a in 0..=5u32 {
        for b in 0..=5 - a {
            for c in 0..=5 - a - b {
                for d in 0..=5 - a - b - c {
                    let q: f64 = rule
                        .iter()
                        .map(|(l, w)| {
                            w * l[1].powi(a as i32) * l[2].powi(b as i32) * l[3].powi(c as i32) * l[0].powi(d as i32)
                        })
                        .sum();
                    let exact = 6.0 * fact(a) * fact(b) * fact(c) * fact(d) / fact(a + b + c + d + 3);
                    worst = worst.max((q - exact).abs() / exact);
                }
            }
        }
    }
    println!("tet rule: worst relative error over monomials of degree ≤ 5: {worst:.2e}");
    assert!(worst <= 1e-14, "{worst:.3e}");
}
