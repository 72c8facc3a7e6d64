//! The charts `run` writes into plots/: forces, contact status map, normal
//! stress profiles and the deformed mesh; well-formed SVG with the series each one claims.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use dyncontact::output::contact_charts::{self, Along, Category, FlatSurface};
use dyncontact::output::{ChartRow, plots};
use dyncontact::problem::Problem;
use dyncontact::run::{RunOptions, run};
use dyncontact::scene::Scene;
use dyncontact::simulation::NodeRecord;
use dyncontact::step::NodeStatus;

const CONTACT_CHARTS: [&str; 3] = ["forces.svg", "contact_status.svg", "normal_stress.svg"];

/// What the shortened impact_friction run produced.
struct Fixture {
    out: PathBuf,
    triangles: usize,
    contact_nodes: usize,
}

fn scene_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fixtures/scenes")
}

/// Run a fixture scene (optionally shortened) into a fresh folder under the target tmpdir, named
/// by the calling test's `tag` too (two tests running one scene differently at once must not
/// share a folder).
fn run_scene(tag: &str, name: &str, end: Option<f64>, every: i64) -> (PathBuf, Problem) {
    let mut scene = Scene::from_file(&scene_dir().join(format!("{name}.toml"))).expect("scene");
    if let Some(end) = end {
        scene.time.end = end;
    }
    scene.output.every = every;
    let problem = Problem::from_scene(&scene, &scene_dir()).expect("problem");
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("charts_{tag}_{name}"));
    let _ = std::fs::remove_dir_all(&out);
    run(&problem, &RunOptions { out: out.clone(), progress: false, ..RunOptions::default() }).expect("run");
    (out, problem)
}

/// impact_friction to t = 0.1 with a frame every 10 steps, run once for all tests.
fn impact() -> &'static Fixture {
    static RUN: OnceLock<Fixture> = OnceLock::new();
    RUN.get_or_init(|| {
        let (out, problem) = run_scene("shared", "impact_friction", Some(0.1), 10);
        let contact_nodes = problem.contact.as_ref().expect("contact").n();
        Fixture { out, triangles: problem.mesh.plane().expect("a 2-D mesh").cells.len(), contact_nodes }
    })
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Well-formedness: every `<...>` token is balanced (open/close names match, one root), with
/// `<?xml ...?>`, comments and declarations ignored, and `&` only as an entity.
fn check_xml(text: &str) -> Result<(), String> {
    let mut stack: Vec<&str> = Vec::new();
    let mut roots = 0;
    let mut rest = text;
    while let Some(start) = rest.find('<') {
        check_text(&rest[..start])?;
        if stack.is_empty() && !rest[..start].trim().is_empty() {
            return Err(format!("text outside the root: {:?}", &rest[..start.min(40)]));
        }
        let tail = &rest[start..];
        if let Some(body) = tail.strip_prefix("<!--") {
            let end = body.find("-->").ok_or("unterminated comment")?;
            rest = &body[end + 3..];
            continue;
        }
        // the end of the tag, skipping '>' inside quoted attribute values
        let mut quote = None;
        let end = tail
            .char_indices()
            .skip(1)
            .find(|&(_, ch)| match (quote, ch) {
                (None, '"' | '\'') => {
                    quote = Some(ch);
                    false
                }
                (Some(q), c) if c == q => {
                    quote = None;
                    false
                }
                (None, '>') => true,
                _ => false,
            })
            .map(|(i, _)| i)
            .ok_or_else(|| format!("unterminated tag at {:?}", &tail[..tail.len().min(40)]))?;
        let tag = &tail[1..end];
        rest = &tail[end + 1..];
        if tag.starts_with('?') || tag.starts_with('!') {
            continue;
        }
        if let Some(name) = tag.strip_prefix('/') {
            let open = stack.pop().ok_or_else(|| format!("</{name}> closes nothing"))?;
            if open != name.trim() {
                return Err(format!("<{open}> closed by </{}>", name.trim()));
            }
            continue;
        }
        let name = tag.split(|c: char| c.is_whitespace() || c == '/').next().unwrap_or("");
        if name.is_empty() {
            return Err(format!("empty tag name in <{tag}>"));
        }
        if stack.is_empty() {
            roots += 1;
        }
        if !tag.ends_with('/') {
            stack.push(name);
        }
    }
    check_text(rest)?;
    if !stack.is_empty() {
        return Err(format!("unclosed tags: {stack:?}"));
    }
    if !rest.trim().is_empty() {
        return Err("text after the root".into());
    }
    if roots != 1 {
        return Err(format!("{roots} root elements"));
    }
    Ok(())
}

/// `&` in text must start an entity.
fn check_text(s: &str) -> Result<(), String> {
    for (i, _) in s.match_indices('&') {
        let ent = s[i + 1..].split(';').next().unwrap_or("");
        let ok =
            matches!(ent, "amp" | "lt" | "gt" | "quot" | "apos") || ent.starts_with('#') && s[i + 1..].contains(';');
        if !ok {
            return Err(format!("bare & in {:?}", &s[i..s.len().min(i + 20)]));
        }
    }
    Ok(())
}

/// The `points` of every polyline, as point counts.
fn polylines(svg: &str) -> Vec<usize> {
    svg.split("<polyline")
        .skip(1)
        .map(|t| {
            t.split("points=\"").nth(1).and_then(|p| p.split('"').next()).map_or(0, |p| p.split_whitespace().count())
        })
        .collect()
}

/// Long horizontal black 2-point polylines (x axis, reference lines): their y in pixels.
fn horizontal_rules(svg: &str) -> Vec<f64> {
    svg.split("<polyline")
        .skip(1)
        .filter(|t| t.contains("stroke=\"#000000\""))
        .filter_map(|t| {
            let pts: Vec<(f64, f64)> = t
                .split("points=\"")
                .nth(1)?
                .split('"')
                .next()?
                .split_whitespace()
                .filter_map(|p| p.split_once(',').and_then(|(x, y)| Some((x.parse().ok()?, y.parse().ok()?))))
                .collect();
            (pts.len() == 2 && pts[0].1 == pts[1].1 && (pts[1].0 - pts[0].0).abs() > 400.0).then_some(pts[0].1)
        })
        .collect()
}

/// A reference line: a long horizontal rule above the x axis (the lowest rule).
fn has_reference_line(svg: &str) -> bool {
    let rules = horizontal_rules(svg);
    let axis = rules.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    rules.iter().any(|&y| y < axis)
}

/// The text contents of the `<text>` elements (entities unescaped).
fn texts(svg: &str) -> Vec<String> {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| t.split_once('>').and_then(|(_, b)| b.split("</text>").next()))
        .map(|s| {
            s.trim()
                .replace("&lt;", "<")
                .replace("&gt;", ">")
                .replace("&quot;", "\"")
                .replace("&apos;", "'")
                .replace("&amp;", "&")
        })
        .collect()
}

fn svg(out: &Path, name: &str) -> String {
    let text = read(&out.join("plots").join(name));
    if let Err(e) = check_xml(&text) {
        panic!("plots/{name} is not well-formed: {e}");
    }
    text
}

/// contact.csv rows: (step, category) per node row, from the status and λ columns.
fn contact_categories(out: &Path) -> (BTreeSet<usize>, Vec<&'static str>) {
    let text = read(&out.join("contact.csv"));
    let mut steps = BTreeSet::new();
    let mut cats = Vec::new();
    for line in text.lines().skip(1) {
        let c: Vec<&str> = line.split(',').collect();
        steps.insert(c[0].parse::<usize>().expect("step"));
        let lambda: f64 = c[9].parse().expect("lambda");
        let status = NodeStatus::from_name(c[11]).unwrap_or_else(|| panic!("unknown status {:?}", c[11]));
        let rec = NodeRecord {
            u_n: 0.0,
            u_t: 0.0,
            v_t: 0.0,
            p: 0.0,
            lambda,
            friction: 0.0,
            bound: 0.0,
            status,
            v_t_vec: [0.0; 3],
            friction_vec: [0.0; 3],
        };
        cats.push(Category::of(&rec).label());
    }
    (steps, cats)
}

/// The well-formedness check accepts plotters' SVG and rejects unbalanced or mismatched tags
/// and bare ampersands.
#[test]
fn xml_check_rejects_malformed_documents() {
    assert!(
        check_xml("<?xml version=\"1.0\"?><!-- c --><svg a=\"x>y\"><g><rect/></g><text>a &amp; b</text></svg>").is_ok()
    );
    assert!(check_xml("<svg><g></svg>").is_err());
    assert!(check_xml("<svg><g></g>").is_err());
    assert!(check_xml("<svg></svg><svg></svg>").is_err());
    assert!(check_xml("<svg><text>a & b</text></svg>").is_err());
}

/// forces.svg draws the normal and tangential force histories (one point per step) and the
/// labelled p(g)·|Γ3| reference line of the Coulomb→Tresca switch.
#[test]
fn forces_chart_has_both_histories_and_the_reference_line() {
    let f = impact();
    let svg = svg(&f.out, "forces.svg");
    let lines = polylines(&svg);
    let steps = read(&f.out.join("history.csv")).lines().count() - 1;
    let long = lines.iter().filter(|&&n| n >= steps).count();
    let labels = texts(&svg);
    let reference = labels.iter().find(|t| t.starts_with("p(g)·|Γ3|"));
    println!("forces.svg: {} polylines, {long} with ≥ {steps} points; reference label {reference:?}", lines.len());
    assert!(long >= 2, "expected the two force histories, polylines: {lines:?}");
    assert!(has_reference_line(&svg), "no reference line: rules at {:?}", horizontal_rules(&svg));
    // p(g)·|Γ3| = c_ν g · L = 2000 · 0.01 · 1.0
    let reference = reference.expect("reference line label");
    assert!(reference.contains("= 20 N/m"), "{reference}");
    assert!(
        labels.iter().any(|t| t.starts_with("normal force"))
            && labels.iter().any(|t| t.starts_with("tangential force"))
    );
}

/// Units follow the dimension: every chart of every 3-D fixture (a few steps each) is free of
/// the 2-D units per unit thickness (N/m, J/m) and reads N and J, and summary.json's
/// `model.units` says the same; the 2-D charts (impact_friction) read N/m and J/m.
#[test]
fn charts_use_the_units_of_the_dimension() {
    let charts = |out: &Path| -> Vec<(String, String)> {
        let mut v: Vec<(String, String)> = std::fs::read_dir(out.join("plots"))
            .expect("plots/")
            .map(|e| e.expect("entry").path())
            .filter(|p| p.extension().is_some_and(|e| e == "svg"))
            .map(|p| (p.file_name().unwrap().to_string_lossy().into_owned(), read(&p)))
            .collect();
        v.sort();
        v
    };
    for name in ["academic3d", "cantilever3d", "column_impact3d", "sliding_block3d", "hertz3d", "gmsh_block3d"] {
        let scene = Scene::from_file(&scene_dir().join(format!("{name}.toml"))).expect("scene");
        let (out, problem) = run_scene("units", name, Some(3.0 * scene.time.step), 1000);
        assert_eq!(problem.mesh.dim(), 3, "{name}");
        let all = charts(&out);
        for (chart, text) in &all {
            for unit in ["N/m", "J/m"] {
                assert!(!text.contains(unit), "{name}: plots/{chart} contains {unit:?}");
            }
        }
        let energy = &all.iter().find(|(c, _)| c == "energy.svg").expect("energy.svg").1;
        assert!(energy.contains("energy [J]") && energy.contains("residual [J]"), "{name}: energy.svg in J");
        if let Some((_, forces)) = all.iter().find(|(c, _)| c == "forces.svg") {
            assert!(forces.contains("force [N]"), "{name}: forces.svg in N");
        }
        let summary: serde_json::Value = serde_json::from_str(&read(&out.join("summary.json"))).expect("json");
        let units = &summary["model"]["units"];
        assert_eq!(units["history"]["force"]["unit"], "N", "{name}: {units}");
        assert_eq!(units["history"]["energy"]["unit"], "J", "{name}: {units}");
        println!("{name}: {} charts in N and J", all.len());
    }
    let all = charts(&impact().out);
    let joined: String = all.iter().map(|(_, t)| t.as_str()).collect();
    assert!(joined.contains("force per unit thickness [N/m]") && joined.contains("N/m"), "2-D forces in N/m");
    assert!(joined.contains("energy [J/m]"), "2-D energies in J/m");
    let summary: serde_json::Value = serde_json::from_str(&read(&impact().out.join("summary.json"))).expect("json");
    assert_eq!(summary["model"]["units"]["history"]["force"]["unit"], "N/m");
    assert_eq!(summary["model"]["units"]["history"]["energy"]["unit"], "J/m");
}

/// The VTU `contact_status` codes of a frame (Int32, inline binary).
fn vtu_status_codes(vtu: &str) -> Vec<i32> {
    use base64::Engine as _;
    let start = vtu.find("Name=\"contact_status\"").expect("a contact_status array");
    let body = &vtu[start..];
    let body = &body[body.find('>').expect("tag end") + 1..body.find("</DataArray>").expect("array end")];
    let bytes = base64::engine::general_purpose::STANDARD.decode(body.trim()).expect("base64");
    bytes[8..].chunks_exact(4).map(|b| i32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect()
}

/// Without a friction law a node in contact is neither stick nor slip (bar_impact: Signorini,
/// no friction): contact.csv says `contact`, history.csv counts it in contact_nodes with
/// slip_nodes = stick_nodes = 0, VTU gives it code 3, the status map and fractions name no stick
/// or slip, and forces.svg draws no tangential force. impact_friction (a friction law) still
/// says stick and slip.
#[test]
fn frictionless_contact_is_neither_stick_nor_slip() {
    let (out, _) = run_scene("bar", "bar_impact", None, 10);
    let (_, cats) = contact_categories(&out);
    let contact = read(&out.join("contact.csv"));
    let statuses: BTreeSet<&str> = contact.lines().skip(1).map(|l| l.split(',').nth(11).expect("status")).collect();
    println!("bar_impact: statuses {statuses:?}, categories {:?}", cats.iter().collect::<BTreeSet<_>>());
    assert!(statuses.contains("contact") && statuses.iter().all(|s| ["separated", "contact"].contains(s)));
    let history = read(&out.join("history.csv"));
    let header: Vec<&str> = history.lines().next().expect("header").split(',').collect();
    let col = |name: &str| header.iter().position(|c| *c == name).expect(name);
    let (c, sl, st) = (col("contact_nodes"), col("slip_nodes"), col("stick_nodes"));
    let rows: Vec<Vec<&str>> = history.lines().skip(1).map(|l| l.split(',').collect()).collect();
    assert!(rows.iter().any(|r| r[c] != "0"), "bar_impact never touches");
    assert!(rows.iter().all(|r| r[sl] == "0" && r[st] == "0"), "a frictionless run counts stick or slip");
    let mut codes = BTreeSet::new();
    for e in std::fs::read_dir(out.join("frames")).expect("frames/").flatten() {
        codes.extend(vtu_status_codes(&read(&e.path())));
    }
    assert!(codes.contains(&3) && codes.iter().all(|k| [-1, 0, 3].contains(k)), "VTU status codes {codes:?}");
    for chart in ["contact_status.svg", "status_fractions.svg"] {
        let labels = texts(&svg(&out, chart));
        assert!(labels.iter().any(|t| t.contains("no friction")), "{chart}: {labels:?}");
        assert!(!labels.iter().any(|t| t.contains("stick") || t.contains("slip")), "{chart}: {labels:?}");
    }
    let forces = texts(&svg(&out, "forces.svg"));
    assert!(forces.iter().any(|t| t.starts_with("normal force")), "{forces:?}");
    assert!(!forces.iter().any(|t| t.contains("tangential")), "{forces:?}");
    for status in NodeStatus::ALL {
        assert_eq!(NodeStatus::from_name(status.as_str()), Some(status));
    }
    assert_eq!(NodeStatus::ALL.map(NodeStatus::code), [0, 1, 2, 3]);
    // with a friction law: stick and slip, no `contact`
    let contact = read(&impact().out.join("contact.csv"));
    assert!(contact.lines().skip(1).all(|l| l.split(',').nth(11) != Some("contact")));
    assert!(texts(&svg(&impact().out, "forces.svg")).iter().any(|t| t.starts_with("tangential force")));
}

/// contact_status.svg has a filled cell per (frame, contact node) and a legend entry for each
/// status category present in contact.csv.
#[test]
fn status_map_has_a_cell_per_frame_and_node_and_a_legend() {
    let f = impact();
    let svg = svg(&f.out, "contact_status.svg");
    let (steps, cats) = contact_categories(&f.out);
    let rects = svg.matches("<rect").count();
    let present: BTreeSet<&str> = cats.iter().copied().collect();
    let labels = texts(&svg);
    println!(
        "contact_status.svg: {rects} rects for {} frames × {} nodes = {}; categories present {present:?}",
        steps.len(),
        f.contact_nodes,
        steps.len() * f.contact_nodes
    );
    for cat in Category::ALL {
        println!("  {:28} {} cells", cat.label(), cats.iter().filter(|&&c| c == cat.label()).count());
    }
    assert_eq!(cats.len(), steps.len() * f.contact_nodes, "contact.csv rows");
    assert!(rects >= steps.len() * f.contact_nodes, "{rects} rects");
    for cat in &present {
        let n = cats.iter().filter(|&c| c == cat).count();
        let want = format!("{cat} ({n})");
        assert!(labels.contains(&want), "no legend entry {want:?} in {labels:?}");
    }
    assert!(present.len() >= 3, "impact_friction should show several regimes by t = 0.1: {present:?}");
}

/// normal_stress.svg draws q + λ along Γ3 at five frames (a point per contact node each),
/// labelled with t, and the p(g) line.
#[test]
fn normal_stress_has_five_profiles_and_p_of_g() {
    let f = impact();
    let svg = svg(&f.out, "normal_stress.svg");
    let lines = polylines(&svg);
    let profiles = lines.iter().filter(|&&n| n >= f.contact_nodes).count();
    let labels = texts(&svg);
    let times: Vec<&String> = labels.iter().filter(|t| t.starts_with("t = ")).collect();
    println!(
        "normal_stress.svg: {} polylines, {profiles} with ≥ {} points; legend {times:?}",
        lines.len(),
        f.contact_nodes
    );
    assert!(profiles >= 5, "polylines: {lines:?}");
    assert_eq!(times.len(), 5);
    assert!(labels.iter().any(|t| t.starts_with("p(g) = 20 ")), "no p(g) line label");
    assert!(has_reference_line(&svg), "no p(g) line: rules at {:?}", horizontal_rules(&svg));
}

/// deformed.svg draws at least one edge per triangle of the deformed mesh, the grey undeformed
/// outline, the foundation and the penetration bound at the displacement scale, and says the
/// scale in the title.
#[test]
fn deformed_mesh_has_every_edge_and_the_outline() {
    let f = impact();
    let svg = svg(&f.out, "deformed.svg");
    let edges = svg.matches("<polyline").count() + svg.matches("<line").count();
    let deformed = svg.split("<polyline").filter(|t| t.contains("stroke=\"#1F77B4\"")).count();
    let outline = svg.split("<polyline").filter(|t| t.contains("stroke=\"#A0A0A0\"")).count();
    let title = texts(&svg).into_iter().find(|t| t.starts_with("Deformed mesh")).expect("title");
    println!(
        "deformed.svg: {edges} lines ({deformed} deformed, {outline} outline) for {} triangles; {title}",
        f.triangles
    );
    assert!(deformed >= f.triangles, "{deformed} deformed edges for {} triangles", f.triangles);
    // 16 × 8 cells: 48 boundary edges
    assert_eq!(outline, 48, "outline edges");
    assert!(title.contains("displacement ×"), "{title}");
    // the foundation under Γ3 (impact_friction: a bound g, so its line too), in the legend
    let labels = texts(&svg);
    assert!(labels.iter().any(|t| t.starts_with("foundation")), "no foundation line: {labels:?}");
    assert!(labels.iter().any(|t| t.starts_with("penetration bound g")), "no bound line: {labels:?}");
}

/// Every chart of the contact run is well-formed SVG, and energy.svg keeps its eight series.
#[test]
fn every_chart_is_well_formed() {
    let f = impact();
    for name in ["energy.svg", "deformed.svg"].into_iter().chain(CONTACT_CHARTS) {
        let text = svg(&f.out, name);
        println!(
            "{name}: {} bytes, {} polylines, {} rects, {} texts",
            text.len(),
            polylines(&text).len(),
            text.matches("<rect").count(),
            texts(&text).len()
        );
    }
    assert!(polylines(&read(&f.out.join("plots/energy.svg"))).len() >= 8);
}

/// A scene without contact writes energy.svg and deformed.svg and none of the contact charts.
#[test]
fn no_contact_scene_writes_only_energy_and_deformed() {
    let (out, problem) = run_scene("gmsh", "gmsh_square", None, 5);
    assert!(problem.contact.is_none());
    let energy = svg(&out, "energy.svg");
    let deformed = svg(&out, "deformed.svg");
    let edges = deformed.split("<polyline").filter(|t| t.contains("stroke=\"#1F77B4\"")).count();
    println!(
        "gmsh_square: energy.svg {} polylines, deformed.svg {edges} edges for {} triangles",
        polylines(&energy).len(),
        problem.mesh.plane().expect("a 2-D mesh").cells.len()
    );
    assert!(polylines(&energy).len() >= 8);
    assert!(edges >= problem.mesh.plane().expect("a 2-D mesh").cells.len());
    assert!(!texts(&deformed).iter().any(|t| t.starts_with("foundation")), "a foundation without contact");
    for name in CONTACT_CHARTS {
        assert!(!out.join("plots").join(name).exists(), "{name} written without contact");
    }
}

/// Odd data never fails a chart: empty histories and frames, non-finite or huge values and a
/// non-finite reference give valid SVG.
#[test]
fn charts_accept_empty_and_non_finite_data() {
    let nan = f64::NAN;
    let row = |t: f64, v: f64| ChartRow {
        t,
        kinetic: v,
        elastic: v,
        compliance: v,
        work: v,
        viscous: v,
        friction: v,
        constraint: v,
        residual: v,
        normal_force: v,
        tangential_force: v,
    };
    let along = Along { s: vec![0.0, 0.5, 1.0], order: vec![0, 1, 2], label: "x along Γ3 [m]" };
    let rec = |p: f64, lambda: f64, status| NodeRecord {
        u_n: 0.0,
        u_t: 0.0,
        v_t: 0.0,
        p,
        lambda,
        friction: 0.0,
        bound: 0.0,
        status,
        v_t_vec: [0.0; 3],
        friction_vec: [0.0; 3],
    };
    // three nodes on a unit triangle (one face, or none: squares), one of them at NaN
    let flat = |faces: bool| FlatSurface {
        xy: vec![[0.0, 0.0], [1.0, 0.0], [nan, 1.0]],
        faces: if faces { vec![[([0.0, 0.0], Some(0)), ([1.0, 0.0], Some(1)), ([0.0, 1.0], None)]] } else { vec![] },
        axes: ["x [m]".into(), "y [m]".into()],
    };
    let frames = vec![
        (
            0,
            0.0,
            vec![
                rec(nan, 0.0, NodeStatus::Separated),
                rec(1.0, nan, NodeStatus::Stick),
                rec(f64::INFINITY, 2.0, NodeStatus::Slip),
            ],
        ),
        // a short frame (fewer records than nodes)
        (1, 0.1, vec![rec(1.0, 0.0, NodeStatus::Slip)]),
    ];
    let outputs = [
        contact_charts::forces(&[], Some(nan), 2, true),
        contact_charts::forces(
            &[row(0.0, nan), row(nan, 1.0), row(0.1, f64::INFINITY), row(0.2, 1e308), row(0.3, -1e308)],
            Some(1.0),
            3,
            false,
        ),
        contact_charts::contact_status(&[], &along, true),
        contact_charts::contact_status(&frames, &along, false),
        contact_charts::normal_stress(&[], &along, None),
        contact_charts::normal_stress(&frames, &along, Some(nan)),
        plots::line_chart("empty", "x", "y", &[], &[]),
        contact_charts::status_maps(&frames, &flat(false), true),
        contact_charts::status_maps(&frames, &flat(true), false),
        contact_charts::status_maps(&[], &flat(true), false),
    ];
    for (k, o) in outputs.into_iter().enumerate() {
        let text = o.unwrap_or_else(|e| panic!("chart {k} failed: {e}"));
        check_xml(&text).unwrap_or_else(|e| panic!("chart {k}: {e}"));
    }
    let mesh = dyncontact::mesh::PlaneMesh::rectangle(1.0, 1.0, 2, 2);
    let u = vec![[nan, 0.0]; mesh.nodes.len()];
    let text = contact_charts::deformed(&mesh, &u, nan, None).expect("deformed with NaN displacement");
    check_xml(&text).expect("deformed");
    let text = contact_charts::deformed(&mesh, &[], 0.0, None).expect("deformed without displacement");
    check_xml(&text).expect("deformed");
}

/// On a Γ3 that is not horizontal the status and stress charts use the arc length along Γ3,
/// walked from its leftmost end (here bottom then right side of the 1 × 0.5 block).
#[test]
fn positions_follow_the_arc_length_on_a_bent_contact_boundary() {
    let mut scene = Scene::from_file(&scene_dir().join("impact_friction.toml")).expect("scene");
    scene.boundary.contact = vec!["bottom".into(), "right".into()];
    let problem = Problem::from_scene(&scene, &scene_dir()).expect("problem");
    let c = problem.contact.as_ref().expect("contact");
    let along = Along::of(problem.mesh.plane().expect("a 2-D mesh"), c, &problem.model.contact_sides);
    let at = |x: f64, y: f64| {
        let i =
            c.nodes.iter().position(|&v| problem.mesh.plane().expect("a 2-D mesh").nodes[v] == [x, y]).expect("node");
        along.s[i]
    };
    println!("{} nodes; s(0,0) = {}, s(1,0) = {}, s(1,0.5) = {}", c.n(), at(0.0, 0.0), at(1.0, 0.0), at(1.0, 0.5));
    assert_eq!(along.label, "arc length along Γ3 [m]");
    assert!((at(0.0, 0.0)).abs() < 1e-12 && (at(1.0, 0.0) - 1.0).abs() < 1e-12 && (at(1.0, 0.5) - 1.5).abs() < 1e-12);
    let sorted: Vec<f64> = along.order.iter().map(|&i| along.s[i]).collect();
    assert!(sorted.windows(2).all(|w| w[1] > w[0]), "positions not distinct: {sorted:?}");
}

/// Tick labels read at a glance: plain numbers with the decimals the tick spacing needs, and
/// scientific notation only where an axis reaches 1e5 or stays below 1e-3.
#[test]
fn tick_labels_are_plain_numbers_unless_the_axis_spans_decades() {
    use dyncontact::output::plots::tick_label;
    assert_eq!(tick_label(60.0, 0.0, 100.0), "60");
    assert_eq!(tick_label(0.25, 0.0, 1.0), "0.25");
    assert_eq!(tick_label(0.1 + 0.2, 0.0, 1.0), "0.3");
    assert_eq!(tick_label(2.5, 0.0, 2.6), "2.5");
    assert_eq!(tick_label(0.0, -1.0, 1.0), "0");
    assert_eq!(tick_label(2.0e-4, 0.0, 5.0e-4), "2.0e-4");
    assert_eq!(tick_label(3.0e6, 0.0, 1.0e7), "3.0e6");
}

/// A node record with contact stress p + λ and status.
fn record(p: f64, lambda: f64, status: NodeStatus) -> NodeRecord {
    NodeRecord {
        u_n: 0.0,
        u_t: 0.0,
        v_t: 0.0,
        p,
        lambda,
        friction: 0.0,
        bound: 0.0,
        status,
        v_t_vec: [0.0; 3],
        friction_vec: [0.0; 3],
    }
}

/// Requirement: each 3-D status map has the patch's aspect ratio (equal scales on both axes),
/// for wide, tall and square patches, in any room.
#[test]
fn status_maps_keep_the_patch_aspect_ratio() {
    for (span, room) in [((2.0, 1.0), (324.0, 420.0)), ((1.0, 3.0), (324.0, 420.0)), ((4.0, 4.0), (724.0, 200.0))] {
        let (w, h) = contact_charts::map_extent(span, room);
        // 1e-12 relative: one division and one multiplication of numbers near 1
        assert!(((w / h) / (span.0 / span.1) - 1.0).abs() < 1e-12, "{span:?} in {room:?}: {w} × {h}");
        assert!(w <= room.0 * (1.0 + 1e-12) && h <= room.1 * (1.0 + 1e-12), "{span:?}: {w} × {h} exceeds {room:?}");
        // one side fills the room (the map is as large as fits); same round-off as above
        assert!((w / room.0 - 1.0).abs() < 1e-12 || (h / room.1 - 1.0).abs() < 1e-12, "{span:?}: {w} × {h}");
    }
}

/// Requirement: the 3-D maps show frames with load from the first one on: an all-separated
/// t = 0 frame (and an unloaded t = 0.1) is skipped, the last loaded frame is the last map.
#[test]
fn status_maps_start_at_the_first_loaded_frame() {
    let sep = || vec![record(0.0, 0.0, NodeStatus::Separated); 3];
    let touching = || {
        vec![
            record(0.0, 0.0, NodeStatus::Separated),
            record(2.0, 0.0, NodeStatus::Stick),
            record(0.0, 0.0, NodeStatus::Separated),
        ]
    };
    let mut frames = vec![(0, 0.0, sep()), (1, 0.1, sep())];
    frames.extend((2..12).map(|k| (k, 0.1 * k as f64, touching())));
    frames.push((12, 1.2, sep()));
    let picks = contact_charts::map_frames(&frames);
    assert_eq!(picks, vec![2, 5, 8, 11], "frames shown");
    // nothing ever loaded: spread over all frames, as before
    assert_eq!(contact_charts::map_frames(&frames[..2]), vec![0, 1]);
}

/// Requirement: on the Gmsh 3-D mesh the nodes' regions of the maps tile Γ3 without overlap:
/// each face's three regions have a third of its area each and they sum to Γ3's area; the
/// axes are the global x and y in metres (Γ3 is the bottom face, normal −z), and the written
/// map's first panel is a frame with contact.
#[test]
fn status_map_regions_tile_the_gmsh_contact_surface() {
    let scene = Scene::from_file(&scene_dir().join("gmsh_block3d.toml")).expect("scene");
    let problem = Problem::from_scene(&scene, &scene_dir()).expect("problem");
    let c = problem.contact.as_ref().expect("contact");
    let solid = problem.mesh.solid().expect("a 3-D mesh");
    let surface = FlatSurface::of(solid, c, &problem.model.contact_sides);
    assert_eq!(surface.axes, ["x [m]".to_string(), "y [m]".to_string()]);
    let area = |p: &[[f64; 2]]| {
        0.5 * (0..p.len())
            .map(|k| {
                let (a, b) = (p[k], p[(k + 1) % p.len()]);
                a[0] * b[1] - a[1] * b[0]
            })
            .sum::<f64>()
    };
    let (mut faces_area, mut regions_area) = (0.0, 0.0);
    for f in &surface.faces {
        let t = [f[0].0, f[1].0, f[2].0];
        let a_t = area(&t).abs();
        assert!(a_t > 0.0, "a degenerate face in the plane of Γ3: {t:?}");
        faces_area += a_t;
        for q in contact_charts::node_regions(t) {
            let a_q = area(&q);
            // same orientation as the face, a third of it (1e-12 relative: a few products of
            // coordinates of size 1, summed)
            assert!(a_q * area(&t) > 0.0 && (a_q.abs() / (a_t / 3.0) - 1.0).abs() < 1e-12, "{q:?} in {t:?}");
            regions_area += a_q.abs();
        }
    }
    println!("Γ3: {} faces, area {faces_area}, regions {regions_area}", surface.faces.len());
    assert!(surface.faces.len() > 50, "Γ3 has its faces");
    // 1e-12 relative: the sum of a few hundred areas of size 1e-3 each exact to 1e-16 relative
    assert!((regions_area / faces_area - 1.0).abs() < 1e-12, "{regions_area} vs {faces_area}");
    // the bottom of the 1 × 0.5 block less its hole (the faces cover a box of that size)
    assert!(faces_area > 0.3 && faces_area <= 0.5 * (1.0 + 1e-12), "{faces_area}");

    let (out, _) = run_scene("status_map", "gmsh_block3d", None, 20);
    let map = svg(&out, "contact_status.svg");
    let labels = texts(&map);
    assert!(labels.iter().any(|t| t == "x [m]") && labels.iter().any(|t| t == "y [m]"), "axes in metres: {labels:?}");
    let first = labels.iter().find(|t| t.starts_with("Γ3 at t = ")).expect("a panel caption");
    assert_ne!(first, "Γ3 at t = 0 s", "the first map is a frame with contact");
    let contact = read(&out.join("contact.csv"));
    let header: Vec<&str> = contact.lines().next().expect("header").split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap_or_else(|| panic!("{name} in {header:?}"));
    let (t_col, p_col, l_col) = (col("t"), col("p"), col("lambda"));
    let t_first: f64 = first["Γ3 at t = ".len()..].trim_end_matches(" s").parse().expect("t");
    let loaded = contact.lines().skip(1).map(|l| l.split(',').collect::<Vec<_>>()).any(|f| {
        let v = |k: usize| f[k].parse::<f64>().expect("number");
        // 1e-9 relative: the caption prints t to four decimals; frame times are multiples of 0.01
        (v(t_col) - t_first).abs() <= 1e-9 * t_first.max(1.0) && v(p_col) + v(l_col) > 0.0
    });
    assert!(loaded, "a node carries load at t = {t_first}");
}

/// Requirement: every chart takes its font from style.rs: no literal font family in
/// src/output or studies/src outside style.rs.
#[test]
fn every_chart_uses_the_chart_style() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut offenders = Vec::new();
    for dir in ["src/output", "studies/src"] {
        for entry in std::fs::read_dir(root.join(dir)).expect("dir") {
            let path = entry.expect("entry").path();
            if path.extension().is_some_and(|e| e == "rs") && !path.ends_with("style.rs") {
                let text = read(&path);
                for family in ["\"sans-serif\"", "\"serif\"", "\"monospace\""] {
                    if text.contains(family) {
                        offenders.push(format!("{}: {family}", path.display()));
                    }
                }
            }
        }
    }
    assert!(offenders.is_empty(), "literal fonts outside style.rs: {offenders:?}");
}
