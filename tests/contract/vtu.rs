//! The VTU frames as VTK reads them: vectors of 3 components named x, y, z; the (P.1) stress as
//! VTK's symmetric tensor (XX, YY, ZZ, XY, YZ, XZ, with `ComponentName0..5`); friction as the
//! vector −t in global components. (The cross-check reads a frame back with VTK's own reader.)

use std::collections::BTreeMap;
use std::path::PathBuf;

use base64::Engine as _;
use dyncontact::model::kinds::Plane;
use dyncontact::output::vtu::{self, NodeContact, Snapshot};
use dyncontact::problem::Problem;
use dyncontact::run::{RunOptions, run};

use crate::common::{fixture, problem};

/// The attributes of the DataArray `name` and its Float64 values (inline binary, UInt64 header).
fn data_array(doc: &str, name: &str) -> (BTreeMap<String, String>, Vec<f64>) {
    let start = doc.find(&format!("Name=\"{name}\"")).unwrap_or_else(|| panic!("no DataArray {name}"));
    let open = doc[..start].rfind("<DataArray").expect("tag start");
    let tag_end = start + doc[start..].find('>').expect("tag end");
    let mut attrs = BTreeMap::new();
    let mut rest = &doc[open + "<DataArray".len()..tag_end];
    while let Some(eq) = rest.find("=\"") {
        let key = rest[..eq].trim().to_string();
        let close = eq + 2 + rest[eq + 2..].find('"').expect("closing quote");
        attrs.insert(key, rest[eq + 2..close].to_string());
        rest = &rest[close + 1..];
    }
    let body = &doc[tag_end + 1..tag_end + doc[tag_end..].find("</DataArray>").expect("array end")];
    let bytes = base64::engine::general_purpose::STANDARD.decode(body.trim()).expect("base64");
    let len = u64::from_le_bytes(bytes[..8].try_into().expect("header")) as usize;
    assert_eq!(len, bytes.len() - 8, "{name}: the UInt64 header counts the bytes that follow");
    let values = if attrs.get("type").map(String::as_str) == Some("Float64") {
        bytes[8..].chunks_exact(8).map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes"))).collect()
    } else {
        Vec::new()
    };
    (attrs, values)
}

/// The component names and count of a DataArray.
fn components(attrs: &BTreeMap<String, String>) -> (usize, Vec<String>) {
    let n: usize = attrs["NumberOfComponents"].parse().expect("NumberOfComponents");
    (n, (0..n).filter_map(|k| attrs.get(&format!("ComponentName{k}")).cloned()).collect())
}

/// u = E x and v = F x on every node: a uniform strain ε = sym E, rate sym F in every cell.
fn linear_fields(p: &Problem, e: [[f64; 3]; 3], f: [[f64; 3]; 3]) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
    let apply = |m: [[f64; 3]; 3], x: [f64; 3]| std::array::from_fn(|i| (0..3).map(|j| m[i][j] * x[j]).sum());
    let pts: Vec<[f64; 3]> = (0..p.mesh.n_nodes()).map(|i| p.mesh.point(i)).collect();
    (pts.iter().map(|&x| apply(e, x)).collect(), pts.iter().map(|&x| apply(f, x)).collect())
}

fn assert_close(got: &[f64], want: &[f64], what: &str) {
    let scale = want.iter().fold(1.0_f64, |m, x| m.max(x.abs()));
    for (g, w) in got.iter().zip(want) {
        assert!((g - w).abs() <= 1e-10 * scale, "{what}: got {got:?}, expected {want:?}");
    }
}

/// 3-D: a uniform strain with three different shears gives in every tetrahedron the (P.1)
/// stress σ = λ tr ε I + 2μ ε + θ tr ε̇ I + 2ζ ε̇, written XX, YY, ZZ, XY, YZ, XZ.
#[test]
fn solid_stress_is_vtks_symmetric_tensor() {
    let p = problem(fixture("sliding_block3d"));
    let e = [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [7.0, 8.0, 9.0]].map(|r| r.map(|x| 1e-3 * x));
    let f = [[-2.0, 1.0, 0.5], [3.0, 1.0, -1.0], [0.0, 4.0, 2.0]].map(|r| r.map(|x| 1e-2 * x));
    let (u, v) = linear_fields(&p, e, f);
    let contact = vec![NodeContact::OFF; p.mesh.n_nodes()];
    let doc =
        vtu::vtu(&Snapshot { mesh: &p.mesh, material: &p.material, u: &u, v: &v, contact: &contact, eps_zz: &[] });
    let (attrs, stress) = data_array(&doc, "stress");
    assert_eq!(components(&attrs), (6, ["XX", "YY", "ZZ", "XY", "YZ", "XZ"].map(String::from).to_vec()));
    let m = &p.material;
    let sigma = |g: [[f64; 3]; 3], lambda: f64, mu: f64| {
        let eps = |i: usize, j: usize| 0.5 * (g[i][j] + g[j][i]);
        let tr = eps(0, 0) + eps(1, 1) + eps(2, 2);
        [(0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2)]
            .map(|(i, j)| 2.0 * mu * eps(i, j) + if i == j { lambda * tr } else { 0.0 })
    };
    let (se, sv) = (sigma(e, m.lambda_3d, m.mu_lame), sigma(f, m.theta_3d, m.zeta));
    let want: Vec<f64> = (0..6).map(|k| se[k] + sv[k]).collect();
    println!("uniform strain: stress (XX, YY, ZZ, XY, YZ, XZ) = {want:?}");
    assert_eq!(stress.len(), 6 * p.mesh.n_cells());
    for (c, cell) in stress.chunks_exact(6).enumerate() {
        assert_close(cell, &want, &format!("tetrahedron {c}"));
    }
}

/// 2-D: the stress is the same 6-component tensor, σ_zz the out-of-plane stress of plane
/// strain (0 in plane stress), σ_yz = σ_xz = 0; vectors have 3 components named x, y, z.
#[test]
fn plane_stress_and_vectors_follow_vtk() {
    for name in ["academic", "crosscheck_stress"] {
        let p = problem(fixture(name));
        let e = [[1.0, 2.0, 0.0], [-3.0, 0.5, 0.0], [0.0; 3]].map(|r| r.map(|x| 1e-3 * x));
        let f = [[0.5, 1.0, 0.0], [2.0, -1.0, 0.0], [0.0; 3]].map(|r| r.map(|x| 1e-2 * x));
        let (u, v) = linear_fields(&p, e, f);
        let contact = vec![NodeContact::OFF; p.mesh.n_nodes()];
        let doc =
            vtu::vtu(&Snapshot { mesh: &p.mesh, material: &p.material, u: &u, v: &v, contact: &contact, eps_zz: &[] });
        let (attrs, stress) = data_array(&doc, "stress");
        assert_eq!(components(&attrs), (6, ["XX", "YY", "ZZ", "XY", "YZ", "XZ"].map(String::from).to_vec()));
        let voigt = |g: [[f64; 3]; 3]| [g[0][0], g[1][1], g[0][1] + g[1][0]];
        let [sxx, syy, sxy, szz] = p.material.stress(voigt(e), voigt(f), 0.0);
        assert_eq!(szz == 0.0, p.material.plane == Plane::Stress, "{name}: σ_zz {szz}");
        for (c, cell) in stress.chunks_exact(6).enumerate() {
            assert_close(cell, &[sxx, syy, szz, sxy, 0.0, 0.0], &format!("{name}: triangle {c}"));
        }
        for vector in ["displacement", "velocity", "friction"] {
            let (attrs, values) = data_array(&doc, vector);
            assert_eq!(components(&attrs), (3, ["x", "y", "z"].map(String::from).to_vec()), "{name}: {vector}");
            assert_eq!(values.len(), 3 * p.mesh.n_nodes());
        }
    }
}

/// (Ps.1) Plane stress with a viscosity not proportional to the elasticity (the academic
/// scene's θ = 2, ζ = 1.5): with ε_zz = s given per triangle, the frame's stress is the 3-D
/// (P.1) stress of (ε, s) with ṡ chosen so that σ_zz = 0 — derived here from the 3-D law, not
/// from the solver's formula — to 1e-10 of its largest component (round-off of a few products).
#[test]
fn plane_stress_with_the_thickness_variable_is_the_3d_stress_with_sigma_zz_zero() {
    let mut scene = fixture("academic");
    scene.domain.plane = Some(Plane::Stress);
    let p = problem(scene);
    assert!(p.material.thickness.is_some(), "θ/ζ = 1.33 against λ/μ = 1.5: ε_zz is a variable");
    let e = [[1.0, 2.0, 0.0], [-3.0, 0.5, 0.0], [0.0; 3]].map(|r| r.map(|x| 1e-3 * x));
    let f = [[0.5, 1.0, 0.0], [2.0, -1.0, 0.0], [0.0; 3]].map(|r| r.map(|x| 1e-2 * x));
    let (u, v) = linear_fields(&p, e, f);
    let contact = vec![NodeContact::OFF; p.mesh.n_nodes()];
    let eps_zz: Vec<f64> = (0..p.mesh.n_cells()).map(|t| 1e-4 * (t % 7) as f64 - 3e-4).collect();
    let doc =
        vtu::vtu(&Snapshot { mesh: &p.mesh, material: &p.material, u: &u, v: &v, contact: &contact, eps_zz: &eps_zz });
    let (_, stress) = data_array(&doc, "stress");
    let (young, poisson) = (1000.0, 0.3);
    let (lambda, mu) = (young * poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson)), young / (2.0 * (1.0 + poisson)));
    let (theta, zeta) = (2.0, 1.5);
    let (tr_e, tr_f) = (e[0][0] + e[1][1], f[0][0] + f[1][1]);
    for (t, cell) in stress.chunks_exact(6).enumerate() {
        let s = eps_zz[t];
        // σ_zz = λ(tr ε + s) + 2μ s + θ(tr ε̇ + ṡ) + 2ζ ṡ = 0
        let s_dot = -(lambda * (tr_e + s) + 2.0 * mu * s + theta * tr_f) / (theta + 2.0 * zeta);
        let trace = lambda * (tr_e + s) + theta * (tr_f + s_dot);
        let want = [
            trace + 2.0 * mu * e[0][0] + 2.0 * zeta * f[0][0],
            trace + 2.0 * mu * e[1][1] + 2.0 * zeta * f[1][1],
            0.0,
            mu * (e[0][1] + e[1][0]) + zeta * (f[0][1] + f[1][0]),
            0.0,
            0.0,
        ];
        assert_close(cell, &want, &format!("triangle {t}"));
    }
}

/// Friction is the vector −t in global components: at every contact node of a frame it equals
/// contact.csv's friction_x, friction_y, friction_z of that step (its length the `friction`
/// column); off Γ3 it is 0.
#[test]
fn friction_is_the_global_vector_of_contact_csv() {
    let mut scene = fixture("sliding_block3d");
    scene.time.end = 0.12;
    scene.output.every = 100;
    let p = problem(scene);
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("vtu_friction");
    let _ = std::fs::remove_dir_all(&out);
    run(&p, &RunOptions { out: out.clone(), progress: false, ..RunOptions::default() }).expect("run");
    let csv = std::fs::read_to_string(out.join("contact.csv")).expect("contact.csv");
    let header: Vec<&str> = csv.lines().next().expect("header").split(',').collect();
    let col = |name: &str| header.iter().position(|c| *c == name).unwrap_or_else(|| panic!("column {name}"));
    let (step, node, size) = (col("step"), col("node"), col("friction"));
    let xyz = [col("friction_x"), col("friction_y"), col("friction_z")];
    let rows: Vec<Vec<&str>> = csv.lines().skip(1).map(|l| l.split(',').collect()).collect();
    let last = rows.iter().map(|r| r[step].parse::<usize>().expect("step")).max().expect("rows");
    let doc = std::fs::read_to_string(out.join(format!("frames/frame_{last:05}.vtu"))).expect("last frame");
    let (attrs, friction) = data_array(&doc, "friction");
    assert_eq!(components(&attrs), (3, ["x", "y", "z"].map(String::from).to_vec()));
    let mut on_gamma3 = vec![false; p.mesh.n_nodes()];
    let mut loaded = 0;
    for r in rows.iter().filter(|r| r[step] == last.to_string()) {
        let i: usize = r[node].parse().expect("node");
        on_gamma3[i] = true;
        let want: Vec<f64> = xyz.iter().map(|&k| r[k].parse().expect("friction component")).collect();
        assert_eq!(&friction[3 * i..3 * i + 3], want.as_slice(), "node {i}");
        let norm = want.iter().map(|x| x * x).sum::<f64>().sqrt();
        let magnitude: f64 = r[size].parse().expect("friction");
        assert!((norm - magnitude).abs() <= 1e-12 * magnitude.max(1.0), "node {i}: |{want:?}| vs {magnitude}");
        loaded += usize::from(norm > 0.0);
    }
    println!("step {last}: {loaded} contact nodes with a friction force");
    assert!(loaded > 0, "the block is pulled: some node must carry friction");
    for (i, _) in on_gamma3.iter().enumerate().filter(|(_, on)| !**on) {
        assert_eq!(&friction[3 * i..3 * i + 3], &[0.0; 3], "node {i} off Γ3");
    }
}
