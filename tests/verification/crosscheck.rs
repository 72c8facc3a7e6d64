//! Our assembly against scikit-fem's, without Python: fixtures/reference holds the matrices
//! and load vectors that `cargo xtask crosscheck` computed with scikit-fem 12.0.2 on the
//! crosscheck_* scenes (same mesh, same DOF numbering 2·node + component, nothing eliminated).
//! Loads are linear in x, y so both quadratures are exact; the comparison is to round-off.

use crate::common;

use std::collections::HashMap;

use common::{fixture, problem};
use dyncontact::fem::assemble::{Dofs, assemble_full};
use dyncontact::linalg;

fn reference(name: &str) -> std::path::PathBuf {
    std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fixtures/reference").join(name)
}

/// A Matrix Market file as a map (row, col) → value (missing entries are zero).
fn read_mtx(name: &str) -> (usize, HashMap<(usize, usize), f64>) {
    let text = std::fs::read_to_string(reference(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
    let mut lines = text.lines().filter(|l| !l.starts_with('%'));
    let head: Vec<usize> =
        lines.next().expect("size line").split_whitespace().map(|w| w.parse().expect("size")).collect();
    let mut m = HashMap::new();
    for l in lines {
        let w: Vec<&str> = l.split_whitespace().collect();
        if w.len() == 3 {
            m.insert(
                (w[0].parse::<usize>().expect("row") - 1, w[1].parse::<usize>().expect("col") - 1),
                w[2].parse::<f64>().expect("value"),
            );
        }
    }
    (head[0], m)
}

/// max |A − B| / max |B| over the union of the patterns.
fn rel_diff(ours: &linalg::SpMat, theirs: &HashMap<(usize, usize), f64>) -> f64 {
    let mut a: HashMap<(usize, usize), f64> = HashMap::new();
    for (i, j, v) in linalg::triplets(ours) {
        *a.entry((i, j)).or_insert(0.0) += v;
    }
    let scale = theirs.values().fold(0.0f64, |m, v| m.max(v.abs())).max(a.values().fold(0.0f64, |m, v| m.max(v.abs())));
    if scale == 0.0 {
        return 0.0;
    }
    let mut keys: Vec<&(usize, usize)> = a.keys().chain(theirs.keys()).collect();
    keys.dedup();
    keys.iter()
        .map(|k| (a.get(k).copied().unwrap_or(0.0) - theirs.get(k).copied().unwrap_or(0.0)).abs())
        .fold(0.0, f64::max)
        / scale
}

/// (P.1) (P.2) (P.4) M, K, C and f(0) equal scikit-fem's entry by entry to 1e-12 relative
/// (measured ~2e-15: scikit-fem's quadrature sums are the larger part of the round-off).
#[test]
fn p1_p2_p4_operators_match_scikit_fem() {
    for name in ["crosscheck_strain", "crosscheck_stress", "crosscheck_elastic", "crosscheck_gmsh"] {
        let p = problem(fixture(name));
        let (m, k, c) =
            assemble_full(p.mesh.plane().expect("a 2-D mesh"), &p.material, p.model.solver.mass).expect("assembly");
        let n = 2 * p.mesh.plane().expect("a 2-D mesh").nodes.len();
        let mut report = Vec::new();
        for (label, ours) in [("M", &m), ("K", &k), ("C", &c)] {
            let (size, theirs) = read_mtx(&format!("{name}_{label}.mtx"));
            assert_eq!(size, n, "{name} {label}: size");
            let d = rel_diff(ours, &theirs);
            report.push(format!("{label} {d:.2e}"));
            assert!(d <= 1e-12, "{name}: {label} differs from scikit-fem by {d:.3e}");
        }
        let all = Dofs::with_dim(
            p.mesh.plane().expect("a 2-D mesh").nodes.len(),
            &vec![false; p.mesh.plane().expect("a 2-D mesh").nodes.len()],
            2,
        );
        let f = dyncontact::problem::build_loads(&p.model, &p.mesh, &all).expect("loads").at(0.0);
        let text = std::fs::read_to_string(reference(&format!("{name}_f.txt"))).expect("f");
        let theirs: Vec<f64> = text
            .lines()
            .filter(|l| !l.starts_with('%') && !l.trim().is_empty())
            .map(|l| l.trim().parse().expect("value"))
            .collect();
        assert_eq!(theirs.len(), n);
        let scale = theirs.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let d = f.iter().zip(&theirs).fold(0.0f64, |m, (a, b)| m.max((a - b).abs())) / scale;
        report.push(format!("f {d:.2e}"));
        assert!(d <= 1e-12, "{name}: f differs from scikit-fem by {d:.3e}");
        println!("{name}: {}", report.join(", "));
    }
}

/// M (consistent and lumped), K and C of a tetrahedral mesh (E = 1000, ν = 0.3, θ = 2, ζ = 1.5,
/// ρ = 1.3) against scikit-fem's `<prefix>_{consistent_M,lumped_M,K,C}.mtx`, each to 1e-12
/// relative; `test` names the measurements.
fn solid_operators_match(mesh: &dyncontact::mesh::solid::SolidMesh, prefix: &str, test: &str) {
    use dyncontact::fem::assemble::assemble_solid;
    use dyncontact::model::MaterialParams;
    use dyncontact::model::material::Material;
    use dyncontact::scene::{MassKind, Plane};
    let mat = Material::new(
        &MaterialParams { density: 1.3, young: 1000.0, poisson: 0.3, theta: 2.0, zeta: 1.5 },
        Plane::Strain,
    );
    let n = 3 * mesh.nodes.len();
    let mut report = Vec::new();
    for (mass, label) in [(MassKind::Consistent, "consistent"), (MassKind::Lumped, "lumped")] {
        let (m, k, c) = assemble_solid(mesh, &mat, mass).expect("assembly");
        for (name, ours) in [(format!("{label}_M"), &m), ("K".to_string(), &k), ("C".to_string(), &c)] {
            let (size, theirs) = read_mtx(&format!("{prefix}_{name}.mtx"));
            assert_eq!(size, n, "{name}: size");
            let d = rel_diff(ours, &theirs);
            report.push(format!("{name} {d:.2e}"));
            common::measured(test, &format!("{name} relative difference"), d, "≤ 1e-12");
            assert!(d <= 1e-12, "{prefix}: {name} differs from scikit-fem by {d:.3e}");
        }
    }
    println!("{prefix}: {}", report.join(", "));
}

/// (P.1) (P.2) in three dimensions on an unstructured Gmsh mesh (fixtures/meshes/holed_block.msh:
/// a block with a cylindrical hole, 329 nodes, 1,016 tetrahedra, read by our reader in 4.1 and
/// 2.2 — the same mesh both ways): M, K, C equal scikit-fem's (the mesh read by meshio) entry by
/// entry to 1e-12 relative, as on the box.
#[test]
fn p1_p2_gmsh_solid_operators_match_scikit_fem() {
    use dyncontact::mesh::gmsh;
    let meshes = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fixtures/meshes");
    let read = |f: &str| match gmsh::read_any(&meshes.join(f)).expect("the mesh reads") {
        dyncontact::mesh::Geometry::Solid(m) => m,
        dyncontact::mesh::Geometry::Plane(_) => panic!("{f}: expected tetrahedra"),
    };
    let (mesh, mesh22) = (read("holed_block.msh"), read("holed_block_22.msh"));
    assert_eq!((mesh.nodes.len(), mesh.cells.len()), (329, 1016));
    assert_eq!(mesh.nodes, mesh22.nodes, "2.2 and 4.1 give the same nodes");
    assert_eq!(mesh.cells, mesh22.cells, "2.2 and 4.1 give the same tetrahedra");
    let names: Vec<&str> = mesh.sides.iter().map(|s| s.name.as_str()).collect();
    for side in ["left", "right", "front", "back", "bottom", "top", "hole"] {
        assert!(names.contains(&side), "side {side} missing: {names:?}");
    }
    solid_operators_match(&mesh, "holed_block", "p1_p2_gmsh_solid_operators_match_scikit_fem");
}

/// (P.1) (P.2) in three dimensions: M (consistent and lumped), K and C of the Kuhn box
/// [0, 1] × [0, 0.5] × [0, 0.5], 4 × 2 × 2 cells (E = 1000, ν = 0.3, θ = 2, ζ = 1.5, ρ = 1.3),
/// equal scikit-fem's (ElementVector(ElementTetP1()), written by
/// xtask/crosscheck/solid_operators.py with its own subdivision) entry by entry to 1e-12
/// relative: every integrand is integrated exactly, so only round-off separates them.
#[test]
fn p1_p2_solid_operators_match_scikit_fem() {
    let mesh = dyncontact::mesh::solid::SolidMesh::cuboid([1.0, 0.5, 0.5], [4, 2, 2]);
    solid_operators_match(&mesh, "box3d", "p1_p2_solid_operators_match_scikit_fem");
}
