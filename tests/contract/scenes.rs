//! The scene contract of the README, tested from the outside: malformed scenes are refused with
//! messages that name the key path, every shipped scene loads, and defaults are what the
//! contract says. `cargo test --test scenes -- --nocapture` prints the table of messages, which
//! doubles as documentation of what a user sees.

use std::path::Path;

use dyncontact::problem::Problem;
use dyncontact::scene::{
    Bound, DEFAULT_SCENE, DomainKind, EnforcementKind as Enforcement, FrictionBound, FrictionLaw, InnerSolver,
    MassKind, Plane, Scene, SchemeKind,
};

/// The valid base scene every malformed case is edited from.
const BASE: &str = DEFAULT_SCENE;

/// `BASE` with `from` replaced by `to`; `from` must occur exactly once (keeps the table honest).
fn edit(from: &str, to: &str) -> String {
    edit_in(BASE, from, to)
}

fn edit_in(text: &str, from: &str, to: &str) -> String {
    assert_eq!(text.matches(from).count(), 1, "the base scene must contain {from:?} exactly once");
    text.replacen(from, to, 1)
}

/// `BASE` with several replacements applied in order.
fn edits(pairs: &[(&str, &str)]) -> String {
    pairs.iter().fold(BASE.to_string(), |text, (from, to)| edit_in(&text, from, to))
}

/// `BASE` with `lines` inserted right after the section header `header` (e.g. "[contact.friction]").
fn after(header: &str, lines: &str) -> String {
    edit(&format!("{header}\n"), &format!("{header}\n{lines}\n"))
}

/// `BASE` with the text from `start` (inclusive) to `end` (exclusive) removed.
fn cut(start: &str, end: &str) -> String {
    cut_in(BASE, start, end)
}

fn cut_in(text: &str, start: &str, end: &str) -> String {
    assert_eq!(text.matches(start).count(), 1, "the base scene must contain {start:?} exactly once");
    let i = text.find(start).unwrap();
    let j = i + text[i..].find(end).expect("end marker after start marker");
    format!("{}{}", &text[..i], &text[j..])
}

/// The friction section of the base scene, to swap for another law.
const FRICTION: &str = "law = \"exponential\"\nstatic = 0.6\nkinetic = 0.3\ndecay = 20.0\n";

fn friction(lines: &str) -> String {
    edit(FRICTION, &format!("{lines}\n"))
}

/// Where a case must be refused.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Stage {
    /// `Scene::from_toml` (serde schema or `validate`).
    Scene,
    /// `Scene::from_toml` accepts; `Problem::new` (mesh-dependent checks) refuses.
    Problem,
}

/// A malformed scene: where it must be refused, with which key path and problem.
struct Malformed {
    what: &'static str,
    toml: String,
    stage: Stage,
    /// The exact key path; the message must contain `"{path}: "`.
    path: &'static str,
    /// A fragment naming the problem.
    problem: &'static str,
}

fn case(what: &'static str, toml: String, path: &'static str, problem: &'static str) -> Malformed {
    Malformed { what, toml, stage: Stage::Scene, path, problem }
}

fn mesh_case(what: &'static str, toml: String, path: &'static str, problem: &'static str) -> Malformed {
    Malformed { what, toml, stage: Stage::Problem, path, problem }
}

fn cases() -> Vec<Malformed> {
    vec![
        // ---- schema: unknown keys, wrong types, unknown variants, missing keys (serde) ----
        case("unknown top-level key", format!("colour = \"red\"\n{BASE}"), "colour", "unknown field `colour`"),
        case(
            "unknown key in a section",
            after("[material]", "elasticity = 3.0"),
            "material.elasticity",
            "unknown field `elasticity`",
        ),
        case(
            "unknown nested key",
            after("[contact.friction]", "foo = 1.0"),
            "contact.friction.foo",
            "unknown field `foo`",
        ),
        case(
            "unknown key in an inline table",
            edit("zeta = 1.5 }", "zeta = 1.5, eta = 1.0 }"),
            "material.viscosity.eta",
            "unknown field `eta`",
        ),
        case(
            "unknown key in an array of tables",
            edit("side = \"top\"", "side = \"top\"\nsides = \"top\""),
            "loads.traction[0].sides",
            "unknown field `sides`",
        ),
        case(
            "string for a number",
            edit("density = 1.0", "density = \"heavy\""),
            "material.density",
            "invalid type: string",
        ),
        case(
            "string inside an integer pair",
            edit("cells = [32, 16]", "cells = [32, \"16\"]"),
            "domain.cells[1]",
            "invalid type",
        ),
        case("float for an integer", edit("every = 10", "every = 2.5"), "output.every", "invalid type"),
        case(
            "number for an expression string",
            edit("value = [\"0\", \"-40*min(t/0.2, 1)\"]", "value = [\"0\", -40]"),
            "loads.traction[0].value[1]",
            "invalid type",
        ),
        case(
            "rectangle size with three entries",
            edit("size = [2.0, 1.0]", "size = [2.0, 1.0, 3.0]"),
            "domain.size",
            "a rectangle needs 2 entries [Lx, Ly], got 3",
        ),
        case(
            "size with four entries",
            edit("size = [2.0, 1.0]", "size = [2.0, 1.0, 3.0, 4.0]"),
            "domain.size",
            "invalid length 4, expected 2 entries [a, b] (2-D) or 3 [a, b, c] (3-D)",
        ),
        case(
            "3-D expression in a 2-D scene",
            edit("value = [\"0\", \"-40*min(t/0.2, 1)\"]", "value = [\"0\", \"-40\", \"0\"]"),
            "loads.traction[0].value",
            "has 3 components; the 2-D domain (kind = \"rectangle\") needs 2",
        ),
        case(
            "expression pair with one entry",
            edit("value = [\"0\", \"-40*min(t/0.2, 1)\"]", "value = [\"-40\"]"),
            "loads.traction[0].value",
            "invalid length 1",
        ),
        case(
            "table point with three entries",
            friction("law = \"table\"\npoints = [[0.0, 0.6], [0.1, 0.35, 0.3]]"),
            "contact.friction.points[1]",
            "invalid length 3",
        ),
        case(
            "unknown time scheme",
            edit("scheme = \"midpoint\"", "scheme = \"rk4\""),
            "time.scheme",
            "unknown variant `rk4`, expected one of `midpoint`, `trapezoid`, `backward-euler`",
        ),
        case(
            "unknown domain kind",
            edit("kind = \"rectangle\"", "kind = \"circle\""),
            "domain.kind",
            "unknown variant `circle`",
        ),
        case(
            "unknown plane",
            edit("plane = \"strain\"", "plane = \"shell\""),
            "domain.plane",
            "unknown variant `shell`",
        ),
        case(
            "unknown inner solver",
            edit("inner = \"newton\"", "inner = \"cg\""),
            "solver.inner",
            "unknown variant `cg`",
        ),
        case(
            "unknown friction bound",
            edit("friction_bound = \"capped\"", "friction_bound = \"soft\""),
            "contact.friction_bound",
            "unknown variant `soft`",
        ),
        case(
            "unknown friction law",
            friction("law = \"coulomb\""),
            "contact.friction.law",
            "unknown variant `coulomb`",
        ),
        case("missing required key", edit("young = 1000.0\n", ""), "material.young", "missing field `young`"),
        case(
            "missing key in an inline table",
            edit("viscosity = { theta = 2.0, zeta = 1.5 }", "viscosity = { theta = 2.0 }"),
            "material.viscosity.zeta",
            "missing field `zeta`",
        ),
        case("missing required section", cut("[time]", "[solver]"), "time", "missing field `time`"),
        case(
            "boolean penetration bound",
            edit("penetration_bound = 0.02", "penetration_bound = true"),
            "contact.penetration_bound",
            "invalid type: boolean `true`, expected a number or a string",
        ),
        // ---- name and domain ----
        case("name with a slash", edit("name = \"academic\"", "name = \"a/b\""), "name", "letters, digits"),
        // names reach folders and generated files (issue 22): a newline would have put code in a Snakefile
        case("name with a newline", edit("name = \"academic\"", "name = \"a\\nb\""), "name", "letters, digits"),
        case(
            "name with a shell character",
            edit("name = \"academic\"", "name = \"a$(touch x)\""),
            "name",
            "letters, digits",
        ),
        case(
            "description with a control character",
            edit("description = \"Ex-A", "description = \"\\u0007Ex-A"),
            "description",
            "control character",
        ),
        // friction coefficients bounded (a coefficient of 1e300 completed with (E.1) off by 1.0)
        case("static friction 1e300", edit("static = 0.6", "static = 1e300"), "contact.friction.static", "at most 100"),
        case(
            "energy residual limit 0",
            edit("[solver]", "[solver]\nenergy_residual_limit = 0"),
            "solver.energy_residual_limit",
            "must be a finite number > 0",
        ),
        case("missing rectangle size", edit("size = [2.0, 1.0]\n", ""), "domain.size", "missing"),
        case("missing rectangle cells", edit("cells = [32, 16]\n", ""), "domain.cells", "missing"),
        case(
            "zero length",
            edit("size = [2.0, 1.0]", "size = [2.0, 0.0]"),
            "domain.size[1]",
            "must be a finite number > 0",
        ),
        case("zero cells", edit("cells = [32, 16]", "cells = [0, 16]"), "domain.cells[0]", "must be >= 1"),
        case(
            "gmsh without file",
            edits(&[
                ("kind = \"rectangle\"", "kind = \"gmsh\""),
                ("size = [2.0, 1.0]\n", ""),
                ("cells = [32, 16]\n", ""),
            ]),
            "domain.file",
            "missing",
        ),
        // ---- material ----
        case(
            "negative density",
            edit("density = 1.0", "density = -1.0"),
            "material.density",
            "must be a finite number > 0, got -1",
        ),
        case(
            "NaN density",
            edit("density = 1.0", "density = nan"),
            "material.density",
            "must be a finite number > 0, got NaN",
        ),
        case(
            "zero Young modulus",
            edit("young = 1000.0", "young = 0.0"),
            "material.young",
            "must be a finite number > 0, got 0",
        ),
        case(
            "Poisson ratio 0.5",
            edit("poisson = 0.3", "poisson = 0.5"),
            "material.poisson",
            "must be in (-1, 0.5), got 0.5",
        ),
        case(
            "Poisson ratio -1",
            edit("poisson = 0.3", "poisson = -1.0"),
            "material.poisson",
            "must be in (-1, 0.5), got -1",
        ),
        case(
            "negative viscosity",
            edit("theta = 2.0", "theta = -2.0"),
            "material.viscosity.theta",
            "must be >= 0, got -2",
        ),
        case("negative shear viscosity", edit("zeta = 1.5", "zeta = -0.1"), "material.viscosity.zeta", "must be >= 0"),
        // ---- boundary ----
        case(
            "side both clamped and in contact",
            edit("dirichlet = [\"left\"]", "dirichlet = [\"left\", \"bottom\"]"),
            "boundary.dirichlet[1]",
            "also a contact side",
        ),
        case(
            "side listed twice",
            edit("contact = [\"bottom\"]", "contact = [\"bottom\", \"bottom\"]"),
            "boundary.contact[1]",
            "listed twice",
        ),
        case("contact sides without [contact]", cut("[contact]\n", "[time]"), "contact", "missing section [contact]"),
        // ---- loads and initial data ----
        case(
            "unknown function in the body force",
            edit("body = [\"0\", \"0\"]", "body = [\"foo(x)\", \"0\"]"),
            "loads.body[0]",
            "unknown function `foo`",
        ),
        case(
            "syntax error in a traction",
            edit("\"-40*min(t/0.2, 1)\"", "\"-40*min(t/0.2, 1\""),
            "loads.traction[0].value[1]",
            "cannot parse",
        ),
        case("empty expression", edit("body = [\"0\", \"0\"]", "body = [\"0\", \"\"]"), "loads.body[1]", "empty"),
        case(
            "traction on a clamped side",
            edit("side = \"top\"", "side = \"left\""),
            "loads.traction[0].side",
            "Dirichlet side",
        ),
        case(
            "traction on a contact side",
            edit("side = \"top\"", "side = \"bottom\""),
            "loads.traction[0].side",
            "contact side",
        ),
        case(
            "two tractions on one side",
            edit("side = \"right\"", "side = \"top\""),
            "loads.traction[1].side",
            "already has a traction",
        ),
        case(
            "time in the initial displacement",
            edit("displacement = [\"0\", \"0\"]", "displacement = [\"t\", \"0\"]"),
            "initial.displacement[0]",
            "`t`",
        ),
        // ---- contact ----
        case("gap depending on time", edit("gap = \"0\"", "gap = \"0.01*t\""), "contact.gap", "`t`"),
        case("infinite numeric gap", edit("gap = \"0\"", "gap = inf"), "contact.gap", "must be finite"),
        case(
            "negative compliance",
            edit("compliance = 1000.0", "compliance = -1.0"),
            "contact.compliance",
            "must be >= 0",
        ),
        case(
            "penalty enforcement without penalty",
            edit("enforcement = \"exact\"", "enforcement = \"penalty\""),
            "contact.penalty",
            "missing",
        ),
        case(
            "zero penalty",
            edit("enforcement = \"exact\"", "enforcement = \"penalty\"\npenalty = 0.0"),
            "contact.penalty",
            "must be a finite number > 0",
        ),
        case(
            "penalty with an infinite bound",
            edits(&[
                ("enforcement = \"exact\"", "enforcement = \"penalty\"\npenalty = 1.0e-4"),
                ("penetration_bound = 0.02", "penetration_bound = \"inf\""),
            ]),
            "contact.enforcement",
            "needs a finite penetration_bound",
        ),
        case(
            "negative penetration bound",
            edit("penetration_bound = 0.02", "penetration_bound = -1.0"),
            "contact.penetration_bound",
            "must be >= 0 or \"inf\", got -1",
        ),
        case(
            "misspelled infinite bound",
            edit("penetration_bound = 0.02", "penetration_bound = \"infinity\""),
            "contact.penetration_bound",
            "the string \"inf\", got \"infinity\"",
        ),
        case(
            "no force at all",
            edits(&[
                ("compliance = 1000.0", "compliance = 0.0"),
                ("penetration_bound = 0.02", "penetration_bound = \"inf\""),
            ]),
            "contact.compliance",
            "no force",
        ),
        // ---- friction ----
        case(
            "exponential law without decay",
            friction("law = \"exponential\"\nstatic = 0.6\nkinetic = 0.3"),
            "contact.friction.decay",
            "missing: law = \"exponential\" needs it",
        ),
        case(
            "negative decay",
            friction("law = \"exponential\"\nstatic = 0.6\nkinetic = 0.3\ndecay = -3.0"),
            "contact.friction.decay",
            "must be >= 0, got -3",
        ),
        case(
            "constant law without coefficient",
            friction("law = \"constant\""),
            "contact.friction.coefficient",
            "missing",
        ),
        case("table without points", friction("law = \"table\""), "contact.friction.points", "missing"),
        case("empty table", friction("law = \"table\"\npoints = []"), "contact.friction.points", "is empty"),
        case(
            "unsorted table",
            friction("law = \"table\"\npoints = [[0.0, 0.6], [1.0, 0.3], [0.1, 0.35]]"),
            "contact.friction.points[2][0]",
            "must increase strictly",
        ),
        case(
            "table with a repeated slip rate",
            friction("law = \"table\"\npoints = [[0.0, 0.6], [0.1, 0.4], [0.1, 0.3]]"),
            "contact.friction.points[2][0]",
            "must increase strictly",
        ),
        case(
            "table with a negative mu",
            friction("law = \"table\"\npoints = [[0.0, 0.6], [0.1, -0.35]]"),
            "contact.friction.points[1][1]",
            "μ must be >= 0",
        ),
        case(
            "table not starting at 0",
            friction("law = \"table\"\npoints = [[0.1, 0.6], [1.0, 0.3]]"),
            "contact.friction.points[0][0]",
            "the first slip rate must be 0",
        ),
        // ---- time ----
        case("zero end time", edit("end = 1.0", "end = 0.0"), "time.end", "must be a finite number > 0"),
        case("negative step", edit("step = 5.0e-4", "step = -5.0e-4"), "time.step", "must be a finite number > 0"),
        case("step longer than the run", edit("step = 5.0e-4", "step = 2.0"), "time.step", "must be <= time.end"),
        case(
            "end not a whole number of steps",
            edit("step = 5.0e-4", "step = 0.3"),
            "time.step",
            "not a whole number of steps",
        ),
        case(
            "too many steps",
            edit("step = 5.0e-4", "step = 1.0e-9"),
            "time.step",
            "too many steps (1000000000), at most 100000000",
        ),
        case(
            "a step so small that N overflows",
            edit("step = 5.0e-4", "step = 1.0e-300"),
            "time.step",
            "too many steps (1.000e300), at most 100000000",
        ),
        // ---- solver and output ----
        case("relaxation 0", edit("relaxation = 1.0", "relaxation = 0.0"), "solver.relaxation", "must be in (0, 1]"),
        case(
            "relaxation above 1",
            edit("relaxation = 1.0", "relaxation = 1.5"),
            "solver.relaxation",
            "must be in (0, 1]",
        ),
        case(
            "Newton tolerance 2",
            edit("newton_tolerance = 1.0e-10", "newton_tolerance = 2.0"),
            "solver.newton_tolerance",
            "must be in (0, 1), got 2",
        ),
        case(
            "zero fixed-point tolerance",
            edit("fixed_point_tolerance = 1.0e-8", "fixed_point_tolerance = 0.0"),
            "solver.fixed_point_tolerance",
            "must be in (0, 1)",
        ),
        case(
            "zero Newton iterations",
            edit("max_newton_iterations = 50", "max_newton_iterations = 0"),
            "solver.max_newton_iterations",
            "must be in 1..=100000",
        ),
        case(
            "output every -1 steps",
            edit("every = 10", "every = -1"),
            "output.every",
            "must be >= 0 (0: no frames), got -1",
        ),
        // ---- checks against the mesh (Problem::new) ----
        mesh_case(
            "contact side the mesh lacks",
            edit("contact = [\"bottom\"]", "contact = [\"bottm\"]"),
            "boundary.contact[0]",
            "no side named \"bottm\"; the mesh has bottom, right, top, left",
        ),
        mesh_case(
            "clamped side the mesh lacks",
            edit("dirichlet = [\"left\"]", "dirichlet = [\"lft\"]"),
            "boundary.dirichlet[0]",
            "no side named \"lft\"",
        ),
        mesh_case(
            "traction side the mesh lacks",
            edit("side = \"top\"", "side = \"Top\""),
            "loads.traction[0].side",
            "no side named \"Top\"",
        ),
        mesh_case(
            "gmsh file that does not exist",
            edits(&[
                ("kind = \"rectangle\"", "kind = \"gmsh\"\nfile = \"no/such/mesh.msh\""),
                ("size = [2.0, 1.0]\n", ""),
                ("cells = [32, 16]\n", ""),
            ]),
            "domain.file",
            "does not exist",
        ),
        mesh_case(
            "initial displacement beyond the bound",
            edit("displacement = [\"0\", \"0\"]", "displacement = [\"0\", \"-0.05*x\"]"),
            "initial.displacement",
            "penetrates beyond the bound",
        ),
        mesh_case(
            "gap not finite on the contact side",
            edit("gap = \"0\"", "gap = \"sqrt(x - 1)\""),
            "contact.gap",
            "evaluates to NaN",
        ),
        mesh_case(
            "body force not finite on the mesh",
            edit("body = [\"0\", \"0\"]", "body = [\"0\", \"sqrt(x - 1)\"]"),
            "loads.body",
            "must be finite",
        ),
        mesh_case(
            "every node clamped",
            edit_in(
                &cut_in(
                    &edits(&[
                        ("cells = [32, 16]", "cells = [1, 1]"),
                        ("dirichlet = [\"left\"]", "dirichlet = [\"left\", \"right\"]"),
                    ]),
                    "[[loads.traction]]\nside = \"right\"",
                    "[initial]",
                ),
                "contact = [\"bottom\"]",
                "contact = []",
            ),
            "boundary.dirichlet",
            "clamps every node",
        ),
    ]
}

/// Every malformed scene is refused with a message that names the exact key path.
#[test]
fn malformed_scenes_are_refused_with_the_key_path() {
    let cases = cases();
    assert!(cases.len() >= 25);
    let mut failures = Vec::new();
    for c in &cases {
        // the scene stage: the schema (from_toml) and the ranges (validate)
        let parsed = Scene::from_toml(&c.toml, "case.toml").and_then(|s| s.validate().map(|_| s));
        let refused = match (parsed, c.stage) {
            (Err(e), Stage::Scene) => Ok(e.to_string()),
            (Err(e), Stage::Problem) => Err(format!("refused too early (the scene should parse): {e}")),
            (Ok(_), Stage::Scene) => Err("accepted by Scene::from_toml and Scene::validate".to_string()),
            (Ok(scene), Stage::Problem) => match Problem::from_scene(&scene, Path::new(".")) {
                Err(e) => Ok(e.to_string()),
                Ok(_) => Err("accepted by Problem::new".to_string()),
            },
        };
        match refused {
            Ok(msg) => {
                println!("{:<42} {msg}", c.what);
                let key = format!("{}: ", c.path);
                let named = msg.starts_with(&key) || msg.contains(&format!(" {key}"));
                if !named || !msg.contains(c.problem) {
                    failures.push(format!("{}: expected `{key}` and {:?} in\n    {msg}", c.what, c.problem));
                }
                assert!(!msg.contains('\n'), "{}: the message must be one paragraph: {msg}", c.what);
            }
            Err(why) => failures.push(format!("{}: {why}", c.what)),
        }
    }
    assert!(failures.is_empty(), "{} of {} cases failed:\n  {}", failures.len(), cases.len(), failures.join("\n  "));
}

/// The embedded default scene parses, validates and builds a problem.
#[test]
fn the_default_scene_is_valid() {
    let scene = Scene::from_toml(DEFAULT_SCENE, "<embedded>").expect("the embedded default scene is valid");
    scene.validate().expect("validate() agrees with from_toml");
    assert_eq!(scene.name, "academic");
    let again = Scene::default_scene();
    assert_eq!(again.name, scene.name);
    let problem = Problem::from_scene(&scene, Path::new(".")).expect("the default scene builds a problem");
    assert_eq!(problem.steps, 2000);
    assert!(problem.contact.is_some());
}

/// Every shipped scene in fixtures/scenes parses, validates and builds a problem.
#[test]
fn every_fixture_scene_loads() {
    let dir = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/fixtures/scenes"));
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .expect("fixtures/scenes exists")
        .map(|e| e.expect("readable directory entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    assert!(files.iter().any(|p| p.ends_with("academic.toml")), "fixtures/scenes/academic.toml is shipped");
    let mut failures = Vec::new();
    for path in &files {
        let loaded = Scene::from_file(path).and_then(|scene| Problem::from_scene(&scene, path.parent().unwrap_or(dir)));
        match loaded {
            Ok(p) => println!("ok   {} ({} steps)", path.display(), p.steps),
            Err(e) => failures.push(format!("{}: {e}", path.display())),
        }
    }
    assert!(failures.is_empty(), "fixture scenes that do not load:\n  {}", failures.join("\n  "));
}

/// A scene with only [domain], [material] and [time] gets the defaults the README documents.
#[test]
fn defaults_follow_the_contract() {
    let text = r#"
[domain]
kind = "rectangle"
size = [1.0, 1.0]
cells = [4, 4]

[material]
density = 1.0
young = 100.0
poisson = 0.25

[time]
end = 1
step = 0.1
"#;
    let s = Scene::from_toml(text, "minimal.toml").expect("a minimal scene is valid");
    assert_eq!(s.domain.kind, DomainKind::Rectangle);
    assert_eq!(s.domain.plane, None);
    assert_eq!(s.validate().expect("valid").plane.unwrap_or_default(), Plane::Strain);
    assert!(s.boundary.dirichlet.is_empty());
    assert!(s.boundary.contact.is_empty());
    assert!(s.contact.is_none());
    assert!(s.validate().expect("valid").contact.is_none());
    assert_eq!((s.material.viscosity.theta, s.material.viscosity.zeta), (0.0, 0.0));
    let m = s.validate().expect("valid");
    assert!(m.loads.body.is_zero() && m.loads.body.dim() == 2, "absent body force: zero with 2 components");
    assert!(s.loads.traction.is_empty());
    assert!(m.initial.displacement.is_zero() && m.initial.displacement.dim() == 2);
    assert!(m.initial.velocity.is_zero() && m.initial.velocity.dim() == 2);
    assert_eq!(s.time.scheme, SchemeKind::Midpoint);
    assert_eq!(s.validate().expect("valid").time.steps, 10);
    assert_eq!(s.solver.inner, InnerSolver::Newton);
    assert_eq!(s.solver.mass, MassKind::Lumped);
    assert_eq!(s.solver.newton_tolerance, 1e-10);
    assert_eq!(s.solver.fixed_point_tolerance, 1e-8);
    assert_eq!(s.solver.max_newton_iterations, 50);
    assert_eq!(s.solver.max_fixed_point_iterations, 50);
    assert_eq!(s.solver.relaxation, 1.0);
    assert_eq!(s.output.every, 10);
    // A free body is allowed ("May be empty for a free body"), with zero loads.
    let p = Problem::from_scene(&s, Path::new(".")).expect("a free body builds a problem");
    assert!(p.contact.is_none());
    assert!(p.u0.iter().chain(&p.v0).all(|&v| v == 0.0));

    // A minimal [contact] section: exact enforcement, capped friction bound, no friction, zero gap.
    let with_contact =
        format!("{text}\n[boundary]\ncontact = [\"bottom\"]\n\n[contact]\npenetration_bound = 0.1\ncompliance = 10\n");
    let s = Scene::from_toml(&with_contact, "minimal-contact.toml").expect("a minimal contact scene is valid");
    let c = s.contact.as_ref().expect("contact section");
    assert_eq!(c.enforcement, Enforcement::Exact);
    assert_eq!(c.friction_bound, FrictionBound::Capped);
    assert_eq!(c.friction.law, FrictionLaw::None);
    assert!(c.gap.is_none() && c.penalty.is_none());
    assert_eq!(Scene::bound_of(c).unwrap(), Bound::Finite(0.1));
    assert_eq!(c.compliance, 10.0, "an integer is accepted where a number is expected");
    let zero = with_contact.replace("penetration_bound = 0.1", "penetration_bound = 0");
    let s = Scene::from_toml(&zero, "zero.toml").expect("penetration_bound = 0 (integer) is valid");
    assert_eq!(Scene::bound_of(s.contact.as_ref().unwrap()).unwrap(), Bound::Finite(0.0));

    // "inf" means pure normal compliance.
    let inf = with_contact.replace("penetration_bound = 0.1", "penetration_bound = \"inf\"");
    let s = Scene::from_toml(&inf, "inf.toml").expect("penetration_bound = \"inf\" is valid");
    assert_eq!(Scene::bound_of(s.contact.as_ref().unwrap()).unwrap(), Bound::Infinite);
}

/// The README's scene template (the first TOML block of its "Scenes" section) with the comment
/// `#` of each line that shows an alternative kept.
fn readme_scene_template() -> String {
    let readme = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md")).expect("README.md");
    let scenes = &readme[readme.find("\n## Scenes").expect("a Scenes section")..];
    let start = scenes.find("```toml\n").expect("a TOML block in Scenes") + "```toml\n".len();
    let end = start + scenes[start..].find("\n```").expect("the block ends");
    scenes[start..end].to_string()
}

/// The README's scene template is the default scene, whole (it validates to the same model), and
/// it names every key of the scene schema (src/scene/schema.rs) and every value of the scene's
/// enumerations (src/model/kinds.rs), so it cannot fall behind the parser.
#[test]
fn the_readme_scene_template_is_the_default_scene_and_names_every_key() {
    let template = readme_scene_template();
    let model = Scene::from_toml(&template, "README.md").and_then(|s| s.validate()).expect("the template validates");
    let default = Scene::from_toml(dyncontact::scene::DEFAULT_SCENE, "academic.toml")
        .and_then(|s| s.validate())
        .expect("default");
    assert_eq!(format!("{model:?}"), format!("{default:?}"), "the template is not the default scene");

    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let schema = std::fs::read_to_string(root.join("src/scene/schema.rs")).expect("schema.rs");
    let mut missing = Vec::new();
    let mut rename: Option<String> = None;
    for line in schema.lines().map(str::trim) {
        if let Some(r) = line.strip_prefix("#[serde(rename = \"").and_then(|r| r.split('"').next()) {
            rename = Some(r.to_string());
        } else if let Some(field) = line.strip_prefix("pub ").and_then(|l| l.split_once(':')).map(|(f, _)| f) {
            if field.chars().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_') {
                let key = rename.take().unwrap_or_else(|| field.to_string());
                let named = template.lines().any(|l| {
                    let l = l.trim_start_matches(['#', ' ', '[']);
                    l.starts_with(&format!("{key} "))
                        || l.starts_with(&format!("{key}="))
                        || l.starts_with(&format!("{key}]"))
                        || l.contains(&format!("{{ {key} ="))
                        || l.contains(&format!(", {key} ="))
                        || l.contains(&format!("({key} ="))
                        || l.contains(&format!(".{key}]"))
                });
                if !named {
                    missing.push(format!("key `{key}`"));
                }
            }
        } else if !line.starts_with("#[") && !line.starts_with("///") {
            rename = None;
        }
    }

    let kinds = std::fs::read_to_string(root.join("src/model/kinds.rs")).expect("kinds.rs");
    let lines: Vec<&str> = kinds.lines().map(str::trim).collect();
    for (i, l) in lines.iter().enumerate() {
        let Some(case) = l.strip_prefix("#[serde(rename_all = \"").and_then(|r| r.split('"').next()) else { continue };
        let mut variant_rename: Option<String> = None;
        for v in lines[i + 1..].iter().skip_while(|v| !v.starts_with("pub enum")).skip(1) {
            if v.starts_with('}') {
                break;
            }
            if let Some(r) = v.strip_prefix("#[serde(rename = \"").and_then(|r| r.split('"').next()) {
                variant_rename = Some(r.to_string());
                continue;
            }
            let name: String = v.chars().take_while(|c| c.is_ascii_alphanumeric()).collect();
            if name.is_empty() || !name.starts_with(|c: char| c.is_ascii_uppercase()) {
                continue;
            }
            let value = variant_rename.take().unwrap_or_else(|| {
                let mut s = String::new();
                for (k, c) in name.chars().enumerate() {
                    if c.is_ascii_uppercase() && k > 0 && case == "kebab-case" {
                        s.push('-');
                    }
                    s.push(c.to_ascii_lowercase());
                }
                s
            });
            if !template.contains(&format!("\"{value}\"")) {
                missing.push(format!("value \"{value}\""));
            }
        }
    }
    assert!(missing.is_empty(), "the README's scene template does not name: {}", missing.join(", "));
}

/// Requirement: a key that the chosen options do not use is accepted, ignored and said by name
/// (the scene template gives `penalty` beside enforcement = "exact"; `--set
/// contact.friction.law=constant` leaves the exponential law's keys behind); the model is the one
/// without the key. A key no option knows is still refused (the cases above).
#[test]
fn unused_keys_are_ignored_and_said() {
    let ignored = [
        (edit("enforcement = \"exact\"", "enforcement = \"exact\"\npenalty = 1.0e-4"), "contact.penalty is not used"),
        (
            friction("law = \"constant\"\ncoefficient = 0.3\nstatic = 0.6"),
            "contact.friction.static is not used by law = \"constant\"",
        ),
        (friction("law = \"none\"\ncoefficient = 0.3"), "contact.friction.coefficient is not used by law = \"none\""),
        (after("[domain]", "file = \"m.msh\""), "domain.file is not used with kind = \"rectangle\""),
        (
            edit("kind = \"rectangle\"", "kind = \"gmsh\"\nfile = \"m.msh\""),
            "domain.size is not used with kind = \"gmsh\"",
        ),
    ];
    for (toml, said) in ignored {
        let model = Scene::from_toml(&toml, "case.toml").and_then(|s| s.validate()).expect("accepted");
        assert!(model.warnings.iter().any(|w| w.contains(said)), "{said:?} not in {:?}", model.warnings);
    }
    // ignored means ignored: the exact problem, whatever the penalty says
    let with = edit("enforcement = \"exact\"", "enforcement = \"exact\"\npenalty = -1.0");
    let model = Scene::from_toml(&with, "case.toml").and_then(|s| s.validate()).expect("accepted");
    let plain = Scene::from_toml(BASE, "case.toml").and_then(|s| s.validate()).expect("the base scene");
    let enforcement = |m: &dyncontact::model::Model| m.contact.as_ref().map(|c| c.enforcement);
    assert_eq!(enforcement(&model), Some(dyncontact::model::Enforcement::Exact));
    assert_eq!(enforcement(&model), enforcement(&plain));
}
