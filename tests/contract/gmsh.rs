//! The Gmsh reader (src/mesh/gmsh.rs) on real Gmsh output and on malformed input, and a scene
//! with `kind = "gmsh"` run end to end.
//!
//! Fixtures (fixtures/meshes): `square_v41.msh` and `square_v22.msh` are one Gmsh 4.15 mesh of
//! the unit square (12 nodes, 14 triangles, 2 edges per side, a physical point "origin") written
//! in both formats; `half_disk.msh` (4.1) is the half disk r = 1, y ≥ 0, whose side "arc" is
//! two quarter circles of 6 chords each with nodes at the exact angles kπ/12, and whose side
//! "flat" is the diameter in 8 edges.

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use dyncontact::mesh::{PlaneMesh, gmsh};
use dyncontact::problem::Problem;
use dyncontact::run::{RunOptions, run};
use dyncontact::scene::Scene;

fn fixture(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures").join(rel)
}

fn load(name: &str) -> PlaneMesh {
    let path = fixture(&format!("meshes/{name}"));
    gmsh::read(&path).unwrap_or_else(|e| panic!("{name} should load: {e}"))
}

fn side_names(m: &PlaneMesh) -> Vec<String> {
    m.sides.iter().map(|s| s.name.clone()).collect()
}

fn dist(p: [f64; 2], q: [f64; 2]) -> f64 {
    ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt()
}

// ---------------------------------------------------------------- the square, 2.2 and 4.1

/// The 2.2 and 4.1 readers give the same mesh (nodes, triangles, sides) for the same Gmsh mesh.
#[test]
fn v22_and_v41_give_the_same_mesh() {
    let (a, b) = (load("square_v22.msh"), load("square_v41.msh"));
    // both files carry the same 16-digit decimal strings, so equality is exact
    assert_eq!(a.nodes, b.nodes);
    assert_eq!(a.cells, b.cells);
    assert_eq!(side_names(&a), side_names(&b));
    for (sa, sb) in a.sides.iter().zip(&b.sides) {
        assert_eq!(sa.facets, sb.facets, "side {}", sa.name);
    }
    assert_eq!(a.nodes.len(), 12);
    assert_eq!(a.cells.len(), 14);
}

/// The unit square mesh has area 1 up to round-off (|A − 1| ≤ 1e-14).
#[test]
fn square_area_is_one() {
    for name in ["square_v22.msh", "square_v41.msh"] {
        let m = load(name);
        // boundary nodes sit exactly on x, y ∈ {0, 1}, so the polygon is exactly the unit
        // square; 14 terms of size ~0.07 summed in double precision err by ~1e-16
        assert!((m.measure() - 1.0).abs() <= 1e-14, "{name}: area {}", m.measure());
    }
}

/// Every triangle the reader returns is counterclockwise.
#[test]
fn triangles_are_counterclockwise() {
    // the orientation is computed here from the coordinates, not by the library
    for name in ["square_v22.msh", "square_v41.msh", "half_disk.msh"] {
        let m = load(name);
        for (t, &[a, b, c]) in m.cells.iter().enumerate() {
            let (p, q, r) = (m.nodes[a], m.nodes[b], m.nodes[c]);
            let cross = (q[0] - p[0]) * (r[1] - p[1]) - (r[0] - p[0]) * (q[1] - p[1]);
            assert!(cross > 0.0, "{name}: triangle {t} {:?} is not counterclockwise", [a, b, c]);
        }
    }
}

/// A mesh whose triangles are all clockwise is flipped to counterclockwise, not rejected.
#[test]
fn all_clockwise_mesh_is_flipped() {
    let text = msh22(UNIT_NODES, &["1 2 0 1 5 2", "2 2 0 2 5 3", "3 2 0 3 5 4", "4 2 0 4 5 1"]);
    let m = gmsh::parse(&text, "cw.msh").expect("an all-clockwise mesh is valid");
    assert!((0..m.cells.len()).all(|t| m.signed_measure(t) > 0.0));
    assert!((m.measure() - 1.0).abs() <= 1e-15);
}

/// Each physical curve becomes one side with its edges: the square has 4 sides of 2 edges each.
#[test]
fn square_sides_have_the_right_edges() {
    // in file order, every edge on its line of the square; the physical point "origin" and the
    // physical surface "domain" are not sides
    let m = load("square_v41.msh");
    assert_eq!(side_names(&m), ["bottom", "right", "top", "left"]);
    // (coordinate index, value) of the line each side lies on; exact: Gmsh writes 0 and 1
    let lines = [("bottom", 1, 0.0), ("right", 0, 1.0), ("top", 1, 1.0), ("left", 0, 0.0)];
    for (name, k, v) in lines {
        let side = m.side(name).unwrap_or_else(|| panic!("no side {name}"));
        assert_eq!(side.facets.len(), 2, "side {name}");
        let mut length = 0.0;
        for &[a, b] in &side.facets {
            assert_eq!(m.nodes[a][k], v, "side {name}: node {a}");
            assert_eq!(m.nodes[b][k], v, "side {name}: node {b}");
            length += dist(m.nodes[a], m.nodes[b]);
        }
        assert!((length - 1.0).abs() <= 1e-15, "side {name} has length {length}");
        // every side edge is a boundary edge (one owning triangle), else this errors
        m.facet_geometry(side).unwrap_or_else(|e| panic!("side {name}: {e}"));
    }
}

/// A physical curve without a $PhysicalNames entry becomes a side named by its tag number.
#[test]
fn unnamed_physical_curve_is_named_by_its_tag() {
    let text = msh22(UNIT_NODES, &[&UNIT_TRIANGLES[..], &["5 1 2 7 1 1 2"]].concat());
    let m = gmsh::parse(&text, "unnamed.msh").expect("valid");
    assert_eq!(side_names(&m), ["7"]);
    assert_eq!(m.sides[0].facets, [[0, 1]]);
}

/// Physical names may contain spaces, and physical tag 0 (Gmsh's "no group") makes no side.
#[test]
fn physical_names_with_spaces_and_tag_zero() {
    // runs of blanks between the fields; tag 0 is what 2.2 files written with Mesh.SaveAll carry
    let text = msh22(UNIT_NODES, &[&UNIT_TRIANGLES[..], &["5 1 2 1 1 1 2", "6 1 2 0 0 2 3"]].concat())
        .replace("1 1 \"bottom\"", "1  1   \"bottom side\"");
    let m = gmsh::parse(&text, "names.msh").expect("valid");
    assert_eq!(side_names(&m), ["bottom side"]);
    assert_eq!(m.sides[0].facets, [[0, 1]]);
}

// ---------------------------------------------------------------- the half disk

/// Arc nodes of half_disk.msh in order of angle, with their angles.
fn arc_nodes(m: &PlaneMesh) -> Vec<(usize, f64)> {
    let arc = m.side("arc").expect("side arc");
    let mut v: Vec<usize> = arc.facets.iter().flatten().copied().collect();
    v.sort_unstable();
    v.dedup();
    let mut out: Vec<(usize, f64)> = v.into_iter().map(|i| (i, m.nodes[i][1].atan2(m.nodes[i][0]))).collect();
    out.sort_by(|a, b| a.1.total_cmp(&b.1));
    out
}

/// The half disk fixture reads as 12 arc + 8 flat edges with area 6 sin(π/12) (the inscribed 12-gon).
#[test]
fn half_disk_geometry() {
    // arc nodes on the unit circle at the angles kπ/12; area to round-off (1e-14)
    let m = load("half_disk.msh");
    assert_eq!(side_names(&m), ["arc", "flat"]);
    assert_eq!(m.side("arc").map(|s| s.facets.len()), Some(12));
    assert_eq!(m.side("flat").map(|s| s.facets.len()), Some(8));
    let arc = arc_nodes(&m);
    assert_eq!(arc.len(), 13);
    for (k, &(i, th)) in arc.iter().enumerate() {
        // coordinates are cos/sin of kπ/12 printed with 16 significant digits: ~1e-16 off
        assert!((dist(m.nodes[i], [0.0, 0.0]) - 1.0).abs() <= 1e-15, "node {i} is off the circle");
        assert!((th - k as f64 * PI / 12.0).abs() <= 1e-15, "node {i} at angle {th}");
    }
    // the mesh fills the 12-gon inscribed in the half circle exactly (the flat side is straight)
    let polygon = 6.0 * (PI / 12.0).sin();
    assert!((m.measure() - polygon).abs() <= 1e-14, "area {} vs {polygon}", m.measure());
}

/// Outward nodal normals on a chord-discretized circle are radial at equidistant nodes (round-off).
#[test]
fn arc_nodal_normals_are_radial_where_nodes_are_equidistant() {
    // Claim: the nodal normal is at the exact angle θ_i + (Δ₊ − Δ₋)/2 (Δ± the angles to the
    // neighbours on the side, 0 at a side end): radial to round-off (1e-14) at the equidistant
    // interior nodes, off by exactly Δ/2 at the two ends.
    //
    // Derivation. Neighbours at θ−Δ₋ and θ+Δ₊ on the unit circle; chord j has length
    // 2 sin(Δⱼ/2) and outward normal at angle θ ∓ Δⱼ/2. The ω-weighted sum of the chord normals
    // (weights = half-lengths) has, along the radial and tangent directions at θ,
    //   radial  = ½(sin Δ₋ + sin Δ₊),   tangent = sin²(Δ₊/2) − sin²(Δ₋/2) = ½(cos Δ₋ − cos Δ₊),
    // and (cos a − cos b)/(sin a + sin b) = tan((b − a)/2): the nodal normal sits at exactly
    // θ + (Δ₊ − Δ₋)/2. So the error is zero for equidistant neighbours, O(h²) only where the
    // spacing varies smoothly (Δ₊ − Δ₋ = O(h²)), and O(h) (= Δ/2) at a side end or where the
    // spacing jumps — "O(h²)" is not a property of nodal normals in general.
    let m = load("half_disk.msh");
    let arc = arc_nodes(&m);
    let sn = m.side_nodes(&["arc".to_string()], &[]).expect("side_nodes(arc)");
    assert_eq!(sn.nodes.len(), arc.len());
    let n_of = |i: usize| sn.normals[sn.nodes.iter().position(|&v| v == i).expect("arc node in side_nodes")];
    let last = arc.len() - 1;
    for (k, &(i, th)) in arc.iter().enumerate() {
        let dm = if k == 0 { 0.0 } else { th - arc[k - 1].1 };
        let dp = if k == last { 0.0 } else { arc[k + 1].1 - th };
        let n = n_of(i);
        assert!((n[0].hypot(n[1]) - 1.0).abs() <= 1e-15, "normal at node {i} is not unit");
        // inputs carry ~1e-16 relative error; a few dozen flops: 1e-14 is a round-off bound
        let predicted = th + 0.5 * (dp - dm);
        let angle = n[1].atan2(n[0]);
        assert!((angle - predicted).abs() <= 1e-14, "node {i}: normal at {angle}, predicted {predicted}");
        let radial = [th.cos(), th.sin()];
        let err = dist(n, radial);
        if k == 0 || k == last {
            // a side end sees one chord: |ν − r| = 2 sin(Δ/4) with Δ = π/12
            assert!((err - 2.0 * (PI / 48.0).sin()).abs() <= 1e-14, "end node {i}: |ν − r| = {err}");
        } else {
            assert!(err <= 1e-14, "interior node {i}: |ν − r| = {err}");
        }
    }
}

/// The weights ω_i over a curved side sum to the length of its chord polygon.
#[test]
fn arc_weights_sum_to_the_polygon_length() {
    // to round-off (1e-14); the polygon is shorter than the half circle π by at most π³/(24 N²)
    let m = load("half_disk.msh");
    let sn = m.side_nodes(&["arc".to_string()], &[]).expect("side_nodes(arc)");
    let arc = m.side("arc").expect("side arc");
    let chords: f64 = arc.facets.iter().map(|&[a, b]| dist(m.nodes[a], m.nodes[b])).sum();
    let omega: f64 = sn.omega.iter().sum();
    assert!((omega - chords).abs() <= 1e-14, "Σω = {omega}, chord polygon {chords}");
    let n = 12.0;
    assert!((chords - 2.0 * n * (PI / (2.0 * n)).sin()).abs() <= 1e-14);
    // π − 2N sin(π/2N) = π³/(24N²) − O(N⁻⁴) > 0: the P1 boundary is O(h²) short of the circle
    let gap = PI - omega;
    assert!(gap > 0.0 && gap <= PI.powi(3) / (24.0 * n * n), "π − Σω = {gap}");
    // each interior arc node carries one chord (two halves), each end half a chord
    let chord = 2.0 * (PI / 24.0).sin();
    for (&v, &w) in sn.nodes.iter().zip(&sn.omega) {
        let on_axis = m.nodes[v][1] == 0.0;
        let expect = if on_axis { 0.5 * chord } else { chord };
        assert!((w - expect).abs() <= 1e-15, "ω at node {v} = {w}, expected {expect}");
    }
}

/// On the flat side every outward nodal normal is (0, −1) and Σ ω = 2 (the diameter).
#[test]
fn flat_side_normal_points_down() {
    let m = load("half_disk.msh");
    let sn = m.side_nodes(&["flat".to_string()], &[]).expect("side_nodes(flat)");
    assert_eq!(sn.nodes.len(), 9);
    for (&v, n) in sn.nodes.iter().zip(&sn.normals) {
        assert_eq!(m.nodes[v][1], 0.0, "flat node {v} is off the axis");
        // the edges are exactly horizontal, so the normal is exact: no tolerance needed beyond 1e-15
        assert!(n[0].abs() <= 1e-15 && (n[1] + 1.0).abs() <= 1e-15, "normal at node {v}: {n:?}");
    }
    let omega: f64 = sn.omega.iter().sum();
    assert!((omega - 2.0).abs() <= 1e-14, "Σω = {omega}");
}

// ---------------------------------------------------------------- a gmsh scene end to end

/// A scene with kind = "gmsh" loads (mesh path relative to the scene file) and runs to its end.
#[test]
fn gmsh_scene_runs() {
    let path = fixture("scenes/gmsh_square.toml");
    let scene = Scene::from_file(&path).expect("gmsh_square.toml parses");
    let dir = path.parent().expect("scene dir");
    let problem = Problem::from_scene(&scene, dir).expect("gmsh_square.toml builds");
    assert_eq!(problem.mesh.plane().expect("a 2-D mesh").nodes.len(), 12);
    assert_eq!(problem.mesh.plane().expect("a 2-D mesh").cells.len(), 14);
    assert!(problem.contact.is_none());
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("gmsh_scene_runs");
    let _ = std::fs::remove_dir_all(&out);
    let summary = run(&problem, &RunOptions { out: out.clone(), progress: false, ..Default::default() })
        .expect("the run completes");
    assert_eq!(summary.status, dyncontact::failure::RunStatus::Completed);
    assert_eq!(summary.steps_completed, problem.steps);
    assert!(problem.steps > 0);
    assert!(out.join("summary.json").is_file());
    assert!(out.join("history.csv").is_file());
}

// ---------------------------------------------------------------- malformed input

/// The unit square with a centre node (tag 5): four counterclockwise triangles.
const UNIT_NODES: &[&str] = &["1 0 0 0", "2 1 0 0", "3 1 1 0", "4 0 1 0", "5 0.5 0.5 0"];
const UNIT_TRIANGLES: [&str; 4] = ["1 2 0 1 2 5", "2 2 0 2 3 5", "3 2 0 3 4 5", "4 2 0 4 1 5"];

/// A 2.2 file with the given node and element lines and two physical names.
fn msh22(nodes: &[&str], elements: &[&str]) -> String {
    format!(
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n2\n1 1 \"bottom\"\n1 3 \"inner\"\n$EndPhysicalNames\n\
         $Nodes\n{}\n{}\n$EndNodes\n$Elements\n{}\n{}\n$EndElements\n",
        nodes.len(),
        nodes.join("\n"),
        elements.len(),
        elements.join("\n")
    )
}

fn valid22() -> String {
    msh22(UNIT_NODES, &[&UNIT_TRIANGLES[..], &["5 1 2 1 1 1 2"]].concat())
}

/// The same unit square in 4.1 (one curve entity in physical 1), with the given node block\n/// header and $Elements body.
fn msh41(node_block_header: &str, elements: &str) -> String {
    format!(
        "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Entities\n0 1 1 0\n1 0 0 0 1 0 0 1 1 2 1 -2\n1 0 0 0 1 1 0 0 0\n$EndEntities\n\
         $Nodes\n1 5 1 5\n{node_block_header}\n1\n2\n3\n4\n5\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 0\n$EndNodes\n\
         $Elements\n{elements}$EndElements\n"
    )
}

const ELEMENTS41: &str = "2 6 1 6\n1 1 1 1\n5 1 2\n2 1 2 4\n1 1 2 5\n2 2 3 5\n3 3 4 5\n4 4 1 5\n";

/// Malformed .msh input is rejected with a message that names the problem (and never panics).
#[test]
fn malformed_meshes_are_rejected_with_clear_messages() {
    let good = valid22();
    gmsh::parse(&good, "good.msh").expect("the base 2.2 case is valid");
    gmsh::parse(&msh41("2 1 0 5", ELEMENTS41), "good41.msh").expect("the base 4.1 case is valid");
    let with_tri = |extra: &[&str]| msh22(UNIT_NODES, &[&UNIT_TRIANGLES[..], extra].concat());
    let with_node = |node: &str| msh22(&[UNIT_NODES, &[node]].concat(), &UNIT_TRIANGLES);
    let cases: Vec<(&str, String, &str)> = vec![
        ("binary flag", good.replace("2.2 0 8", "2.2 1 8"), "binary .msh files are not supported"),
        ("unsupported version", good.replace("2.2 0 8", "3.0 0 8"), "format version 3.0 is not supported"),
        ("version 4.0", msh41("2 1 0 5", ELEMENTS41).replace("4.1 0 8", "4.0 0 8"), "version 4.0 is not supported"),
        ("quad element", with_tri(&["9 3 0 1 2 3 4"]), "element 9 is a quadrangle"),
        ("2nd-order triangle", with_tri(&["9 9 0 1 2 3 4 5 1"]), "element 9 is second order (type 9)"),
        ("2nd-order line", with_tri(&["9 8 1 1 1 2 5"]), "Mesh.ElementOrder = 1"),
        (
            "hexahedron",
            with_tri(&["9 5 0 1 2 3 4 5 1 2 3"]),
            "element 9 is a 3-D element of type 5 (hexahedron, prism or pyramid)",
        ),
        (
            "a flat tetrahedron among triangles",
            with_tri(&["9 4 0 1 2 3 5"]),
            "tetrahedron 9 (nodes 1, 2, 3, 5) has zero (degenerate) volume",
        ),
        ("unknown element type", with_tri(&["9 16 0 1 2 3 4 1 2 3 4"]), "element 9 has type 16"),
        ("too few nodes", with_tri(&["9 2 0 1 2"]), "element 9 lists 2 nodes, type 2 needs 3"),
        (
            "zero-area triangle",
            msh22(UNIT_NODES, &["1 2 0 1 2 3", "2 2 0 1 3 4", "3 2 0 1 5 3"]),
            "triangle 3 has zero area",
        ),
        (
            "inverted triangle in a ccw mesh",
            msh22(UNIT_NODES, &["1 2 0 1 2 5", "2 2 0 2 3 5", "3 2 0 3 4 5", "4 2 0 4 5 1"]),
            "triangle 4 is inverted",
        ),
        (
            "one ccw triangle in a cw mesh",
            msh22(UNIT_NODES, &["1 2 0 1 5 2", "2 2 0 2 5 3", "3 2 0 3 5 4", "4 2 0 4 1 5"]),
            "triangle 4 is inverted",
        ),
        ("duplicate node coordinates", with_node("6 1 1 0"), "nodes 3 and 6 are duplicates"),
        (
            "a triangle mesh off its plane",
            msh22(&[&UNIT_NODES[..4], &["5 0.5 0.5 0.5"]].concat(), &UNIT_TRIANGLES),
            "node 5 has z = 0.5 while node 1 has z = 0",
        ),
        ("near-duplicate node", with_node("6 0.99999999999999 1 0"), "nodes 3 and 6 are duplicates"),
        ("duplicate node tag", with_node("5 0.25 0.25 0"), "node tag 5 appears twice"),
        ("unreferenced node", with_node("6 2 2 0"), "node 6 is not a vertex of any triangle"),
        (
            "missing node",
            msh22(UNIT_NODES, &["1 2 0 1 2 5", "2 2 0 2 3 9"]),
            "triangle 2 refers to node 9, which is not in $Nodes",
        ),
        ("line on a missing node", with_tri(&["5 1 2 1 1 1 9"]), "line element 5 refers to node 9"),
        (
            "interior physical line",
            with_tri(&["5 1 2 3 3 1 5"]),
            "side \"inner\": line element 5 (nodes 1 5) is an interior edge",
        ),
        (
            "line that is no triangle edge",
            with_tri(&["5 1 2 1 1 1 3"]),
            "side \"bottom\": line element 5 (nodes 1 3) is not an edge of any triangle",
        ),
        ("truncated file", good[..good.find("$EndNodes").unwrap_or(0)].to_string(), "unexpected end of file in $Nodes"),
        ("missing $EndNodes", good.replace("$EndNodes\n", ""), "expected $EndNodes, found \"$Elements\""),
        ("truncated elements", good[..good.find("$EndElements").unwrap_or(0)].to_string(), "$EndElements is missing"),
        ("no triangles", msh22(UNIT_NODES, &["1 1 2 1 1 1 2"]), "contains no triangles"),
        ("no $MeshFormat", good[good.find("$PhysicalNames").unwrap_or(0)..].to_string(), "no $MeshFormat section"),
        ("empty file", String::new(), "no $MeshFormat section"),
        ("non-numeric coordinate", good.replace("5 0.5 0.5 0", "5 0.5 x 0"), "cannot read a node from \"x\""),
        ("non-finite coordinate", good.replace("5 0.5 0.5 0", "5 0.5 NaN 0"), "node 5 has non-finite coordinates"),
        ("negative ntags (2.2)", good.replace("5 1 2 1 1 1 2", "5 1 -2 1 1 1 2"), "element 5"),
        ("negative node count (4.1)", msh41("2 1 0 -5", ELEMENTS41), "node block"),
        ("huge node count (4.1)", msh41("2 1 0 99999999999999", ELEMENTS41), "more than the section header announces"),
        (
            "huge physical count (4.1)",
            msh41("2 1 0 5", ELEMENTS41).replace("0 1 1 2 1 -2", "0 1e300 1 2 1 -2"),
            "entity 1 (dim 1) lists 1e300 physical tags",
        ),
        ("stray text", format!("{good}hello\n"), "unexpected line \"hello\" outside a section"),
    ];
    assert!(cases.len() >= 12);
    let mut failures = Vec::new();
    for (what, text, fragment) in &cases {
        let outcome = std::panic::catch_unwind(|| gmsh::parse(text, "bad.msh"));
        match outcome {
            Err(_) => failures.push(format!("{what}: the reader panicked")),
            Ok(Ok(_)) => failures.push(format!("{what}: accepted")),
            Ok(Err(e)) => {
                let msg = e.to_string();
                if !msg.contains(fragment) {
                    failures.push(format!("{what}: message \"{msg}\" lacks \"{fragment}\""));
                } else if !msg.starts_with("mesh bad.msh: ") {
                    failures.push(format!("{what}: message \"{msg}\" does not name the file"));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{} of {} cases failed:\n{}", failures.len(), cases.len(), failures.join("\n"));
}

/// A binary .msh file (not valid UTF-8) read from disk is reported as binary, not as an I/O error.
#[test]
fn binary_file_on_disk_is_reported_as_binary() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("gmsh_binary");
    std::fs::create_dir_all(&dir).expect("tmp dir");
    let path = dir.join("binary.msh");
    let mut bytes = b"$MeshFormat\n4.1 1 8\n".to_vec();
    bytes.extend_from_slice(&[1, 0, 0, 0, 0xff, 0xfe, 0x80, b'\n']);
    bytes.extend_from_slice(b"$EndMeshFormat\n");
    std::fs::write(&path, bytes).expect("write binary.msh");
    let e = gmsh::read(&path).expect_err("binary files are rejected");
    assert!(e.to_string().contains("binary .msh files are not supported"), "{e}");
}

/// A missing mesh file is an error naming the path, from gmsh::read and from a scene.
#[test]
fn missing_mesh_file_is_reported() {
    let missing = fixture("meshes/no_such_mesh.msh");
    let e = gmsh::read(&missing).expect_err("missing file");
    assert!(e.to_string().contains("no_such_mesh.msh"), "{e}");
    let scene =
        Scene::from_toml(&scene_text("../meshes/no_such_mesh.msh", "left"), "missing.toml").expect("scene parses");
    let e = Problem::from_scene(&scene, &fixture("scenes")).err().expect("missing mesh file");
    let msg = e.to_string();
    assert!(msg.contains("domain.file") && msg.contains("no_such_mesh.msh") && msg.contains("does not exist"), "{msg}");
}

/// A scene naming a side the Gmsh mesh lacks fails with the key path and the available sides.
#[test]
fn scene_naming_an_unknown_side_lists_the_available_sides() {
    let scene =
        Scene::from_toml(&scene_text("../meshes/square_v41.msh", "west"), "unknown_side.toml").expect("scene parses");
    let e = Problem::from_scene(&scene, &fixture("scenes")).err().expect("unknown side");
    let msg = e.to_string();
    assert!(msg.contains("boundary.dirichlet[0]"), "{msg}");
    assert!(msg.contains("no side named \"west\"; the mesh has bottom, right, top, left"), "{msg}");
}

fn scene_text(file: &str, dirichlet: &str) -> String {
    format!(
        "[domain]\nkind = \"gmsh\"\nfile = \"{file}\"\n[boundary]\ndirichlet = [\"{dirichlet}\"]\n\
         [material]\ndensity = 1.0\nyoung = 1000.0\npoisson = 0.3\n[time]\nend = 0.01\nstep = 0.001\n"
    )
}

/// Two tetrahedra (element tags 11 and 12) on the shared face 1-2-3; `apex` is the second one's
/// fourth node (below the face: a consistent mesh; above it: folded through the face).
fn two_tets(apex: &str, swap_all: bool) -> String {
    let (t1, t2) = if swap_all { ("1 2 4 3", "1 2 3 5") } else { ("1 2 3 4", "1 3 2 5") };
    format!(
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 {apex}\n$EndNodes\n\
         $Elements\n2\n11 4 0 {t1}\n12 4 0 {t2}\n$EndElements\n"
    )
}

/// (issue 22) A 3-D mesh folded by one moved node — the second tetrahedron's apex pushed
/// through the shared face, so the two have opposite orientations — is refused naming the
/// inverted tetrahedron by its tag in the file, as the 2-D reader refuses a fold; the same mesh
/// unfolded is accepted in either consistent orientation (all clockwise is flipped, volume 1/3).
#[test]
fn folded_3d_mesh_is_refused_naming_the_tetrahedron() {
    use dyncontact::mesh::Geometry;
    use dyncontact::mesh::gmsh::parse_any;
    for swap_all in [false, true] {
        let Geometry::Solid(m) = parse_any(&two_tets("0 0 -1", swap_all), "two.msh").expect("a consistent mesh") else {
            panic!("3-D")
        };
        // every tetrahedron positive after reading; volume 1/6 + 1/6 (exact in binary: round-off only)
        assert!((0..2).all(|t| m.signed_measure(t) > 0.0));
        assert!((m.measure() - 1.0 / 3.0).abs() < 1e-15, "volume {}", m.measure());
    }
    let e = parse_any(&two_tets("0.2 0.2 0.5", false), "folded.msh").expect_err("a folded mesh is refused").to_string();
    println!("{e}");
    assert!(e.contains("folded.msh") && e.contains("tetrahedron 12 is inverted") && e.contains("folds"), "{e}");
}

/// (issue 22, minor) Mesh messages name nodes and cells by their tags in the file, not by the
/// reader's 0-based indices: a flat tetrahedron (its apex in the plane of its base) of a file
/// whose node tags start at 101 is reported as "tetrahedron 12 (nodes 101, 103, 102, 105)" (the file's element tag 9 was reported as "tetrahedron 0 (nodes [0, 1, 2, 4])" before).
#[test]
fn mesh_messages_name_the_file_tags() {
    let text = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n5\n101 0 0 0\n102 1 0 0\n103 0 1 0\n104 0 0 1\n105 0.3 0.3 0\n$EndNodes\n\
                $Elements\n2\n11 4 0 101 102 103 104\n12 4 0 101 103 102 105\n$EndElements\n";
    let e = dyncontact::mesh::gmsh::parse_any(text, "flat.msh").expect_err("a flat tetrahedron").to_string();
    println!("{e}");
    assert!(e.contains("tetrahedron 12 (nodes 101, 103, 102, 105) has zero (degenerate) volume"), "{e}");
}

/// (issue 22, minor) A mesh without physical groups has no named sides, and messages say so
/// ("the mesh has no named sides …") instead of ending in an empty list.
#[test]
fn a_mesh_without_physical_groups_says_it_has_no_named_sides() {
    let text = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n$EndNodes\n$Elements\n1\n1 2 0 1 2 3\n$EndElements\n";
    let g = dyncontact::mesh::gmsh::parse_any(text, "bare.msh").expect("a mesh");
    assert_eq!(g.side_list(), "no named sides (the mesh file defines no physical groups)");
}
