//! The command line (the README's scene and output contract): `run` writes every output with the contract's columns,
//! `check` prints the model and (C.k), bad input exits 1 with a message naming the key.

use std::path::{Path, PathBuf};
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_dyncontact");

fn tmp(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn scene(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fixtures/scenes").join(format!("{name}.toml"))
}

fn header(path: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    text.lines().next().unwrap_or("").split(',').map(str::to_string).collect()
}

const HISTORY: &str = "step,t,kinetic,elastic,compliance,external_work,viscous_dissipation,friction_dissipation,constraint_dissipation,energy_residual,normal_force,tangential_force,max_penetration,contact_nodes,slip_nodes,stick_nodes,newton_iterations,fixed_point_iterations";
const CONTACT: &str = "step,t,node,x,y,u_n,u_t,v_t,p,lambda,friction,status";

/// `dyncontact run` with no scene runs the embedded academic scene and writes history.csv
/// (a row per step plus t = 0, the contract's columns in order), contact.csv, summary.json
/// ("completed", no warning but the (C.k) note), frames with a PVD listing exactly the frames
/// written, and plots/energy.svg with its eight series.
#[test]
fn cli_run_default_scene_writes_outputs() {
    let out = tmp("cli_default");
    let st = Command::new(BIN).args(["run", "--out"]).arg(&out).output().expect("run");
    assert!(st.status.success(), "run failed: {}", String::from_utf8_lossy(&st.stderr));
    let h = header(&out.join("history.csv"));
    let want: Vec<&str> = HISTORY.split(',').collect();
    assert_eq!(&h[..want.len()], want.as_slice(), "history.csv columns");
    let rows = std::fs::read_to_string(out.join("history.csv")).expect("history").lines().count();
    assert_eq!(rows, 1 + 2001, "header + t = 0 + 2000 steps");
    let c = header(&out.join("contact.csv"));
    let want_c: Vec<&str> = CONTACT.split(',').collect();
    assert_eq!(&c[..want_c.len()], want_c.as_slice(), "contact.csv columns");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).expect("summary")).expect("json");
    assert_eq!(summary["status"], "completed");
    assert_eq!(summary["scene"], "academic");
    assert_eq!(summary["steps_completed"], 2000);
    assert!(summary["max_relative_energy_residual"].as_f64().expect("residual") <= 1e-9);
    assert_eq!(summary["fixed_point_cap_hits"], 0);
    // no warning: k = 5e-4 exceeds (C.k)'s corner limit (decision 6), but (Ck.1) holds, and the
    // setup says so instead of warning
    let warnings = summary["warnings"].as_array().expect("warnings");
    assert!(warnings.is_empty(), "unexpected warnings: {warnings:?}");
    assert_eq!(summary["model"]["ck_sharp"], true);
    // (issue 24, item 10) the README's figures of this run are this run's: "(E.1) defect 2e-16",
    // "5.7 convex solves per step … (15 at most" (rounded as printed there)
    let readme = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md")).expect("README");
    let steps = summary["steps_completed"].as_f64().expect("steps");
    let per_step = summary["fixed_point_iterations_total"].as_f64().expect("total") / steps;
    let quoted = format!(
        "(E.1) defect {:.0e} of the energy scale, {per_step:.1} convex\nsolves per step in the fixed point on average ({} at most",
        summary["max_relative_energy_residual"].as_f64().expect("residual"),
        summary["fixed_point_iterations_max"]
    );
    assert!(readme.contains(&quoted), "the README's academic figures are not this run's: {quoted}");
    let pvd = std::fs::read_to_string(out.join("series.pvd")).expect("pvd");
    let listed: Vec<&str> =
        pvd.lines().filter_map(|l| l.split("file=\"").nth(1)).map(|s| s.trim_end_matches("\"/>")).collect();
    assert_eq!(listed.len(), 201, "frames every 10 steps, t = 0 included");
    for f in &listed {
        assert!(out.join(f).exists(), "{f} listed but missing");
    }
    let frames = std::fs::read_dir(out.join("frames")).expect("frames").count();
    assert_eq!(frames, listed.len(), "frames on disk that the PVD does not list");
    let svg = std::fs::read_to_string(out.join("plots/energy.svg")).expect("energy.svg");
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    assert!(svg.matches("<polyline").count() >= 8, "energy chart has fewer than 8 series");
}

/// `dyncontact check` prints the model and the (C.k) limit (3.4722e-4 at the corner node of
/// the academic mesh, decision 6) and warns on stderr that k = 5e-4 exceeds it.
#[test]
fn check_prints_the_ck_limit_and_warns() {
    let st = Command::new(BIN).arg("check").arg(scene("academic")).output().expect("check");
    assert!(st.status.success());
    let out = String::from_utf8_lossy(&st.stdout);
    let err = String::from_utf8_lossy(&st.stderr);
    println!("{out}{err}");
    assert!(out.contains("(C.k)") && out.contains("3.4722e-4"), "no (C.k) limit in: {out}");
    assert!(err.contains("warning: time.step = 0.0005 exceeds the (C.k) limit"), "no warning on stderr: {err}");
    assert!(out.contains("32 contact nodes") && out.contains("32 multipliers"));
}

/// (Ck.1) summary.json says what the run's setup found of the sharp (C.k) and where F.1 started:
/// academic3d at 12×8×4 (324 contact unknowns, an "auto" start) at k = 1.2e-3, beyond (C.k)'s
/// 1.04e-3 but inside (Ck.1): `model.ck_sharp` true, the contact solve "started at the root …:
/// (Ck.1) holds", no (C.k) warning; at k = 2e-3, outside both: false, "started at the predictor",
/// the warning; `check` (no W) says a run will test it. The default scene (64 contact unknowns,
/// the predictor's start) at its k = 5e-4, 1.44× its (C.k) limit, is inside (Ck.1): true and no
/// warning, its start unchanged; at k = 1e-3 outside: false and the warning. With the sparse W
/// at 1.2e-3 the test does not run (null), F.1 starts at the predictor and the words say why.
#[test]
fn summary_reports_the_sharp_ck() {
    let dir = tmp("cli_sharp_ck");
    let box_12x8x4 = |k: &str| {
        let end = format!("time.end={}", 4.0 * k.parse::<f64>().expect("k"));
        let mut args = vec!["--set".to_string(), "domain.cells=[12, 8, 4]".into(), "--set".into()];
        args.extend([format!("time.step={k}"), "--set".into(), end]);
        args
    };
    for (k, sharp) in [("1.2e-3", true), ("2e-3", false)] {
        let (summary, err) = run_for_summary(Some(&scene("academic3d")), &box_12x8x4(k), &dir.join(k));
        let model = &summary["model"];
        let words = model["contact_solve"].as_str().expect("contact_solve");
        println!("k = {k}: {words}");
        assert_eq!(model["ck_sharp"], serde_json::Value::Bool(sharp), "k = {k}");
        if sharp {
            assert!(words.contains("started at the root of the unfrozen Newton (N.4): (Ck.1) holds"), "{words}");
        } else {
            assert!(words.contains("started at the predictor: (Ck.1) does not hold"), "{words}");
        }
        let warned = summary["warnings"].to_string().contains("exceeds the (C.k) limit");
        assert_eq!(warned, !sharp, "the (C.k) warning only where (Ck.1) does not show convexity");
        assert_eq!(err.contains("exceeds the (C.k) limit"), !sharp, "{err}");
        assert!(summary["timing"]["sharp_convexity_s"].as_f64().expect("timing") > 0.0);
    }
    let st = Command::new(BIN)
        .arg("check")
        .arg(scene("academic3d"))
        .args(["--set", "domain.cells=[12, 8, 4]", "--set", "time.step=1.2e-3", "--set", "time.end=0.6"])
        .output()
        .expect("check");
    let (out, err) = (String::from_utf8_lossy(&st.stdout), String::from_utf8_lossy(&st.stderr));
    assert!(
        st.status.success() && out.contains("if (Ck.1), the sharp (C.k) through W, holds (tested at setup)"),
        "{out}"
    );
    assert!(err.contains("a run with a dense W tests the sharper (Ck.1) at setup"), "{err}");
    let mut sparse = box_12x8x4("1.2e-3");
    sparse.extend(["--set".to_string(), "solver.contact_solve=\"sparse\"".into()]);
    let (summary, _) = run_for_summary(Some(&scene("academic3d")), &sparse, &dir.join("sparse"));
    assert_eq!(summary["contact_solve"], "sparse");
    assert_eq!(summary["model"]["ck_sharp"], serde_json::Value::Null, "no test without the dense W");
    let words = summary["model"]["contact_solve"].as_str().expect("words");
    assert!(words.contains("started at the predictor: (Ck.1) not tested (it needs the dense W)"), "{words}");
    for (k, sharp) in [("5e-4", true), ("1e-3", false)] {
        let args = ["--set".to_string(), format!("time.step={k}"), "--set".into(), "time.end=0.005".into()];
        let (summary, err) = run_for_summary(None, &args, &dir.join(format!("default_{k}")));
        assert_eq!(summary["model"]["ck_sharp"], serde_json::Value::Bool(sharp), "default scene at k = {k}");
        assert!(!summary["model"]["contact_solve"].as_str().expect("words").contains("root"), "the predictor's start");
        assert_eq!(err.contains("exceeds the (C.k) limit"), !sharp, "default scene at k = {k}: {err}");
    }
}

/// `dyncontact run [SCENE] ARGS --out OUT`, which must succeed: its summary.json and stderr.
fn run_for_summary(scene: Option<&Path>, args: &[String], out: &Path) -> (serde_json::Value, String) {
    let st = Command::new(BIN).arg("run").args(scene).args(args).arg("--out").arg(out).output().expect("run");
    let err = String::from_utf8_lossy(&st.stderr).into_owned();
    assert!(st.status.success(), "{err}");
    let summary =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).expect("summary")).expect("json");
    (summary, err)
}

/// `check`'s friction line (summary.json `model.friction`) says what a step solves, true for every
/// friction bound: "one convex solve per step" only where S is known before the solve (μ
/// constant, bound at the predictor), and there every step does at most one F.1 iteration; the
/// total bound (the contact force, Coulomb) and the midpoint name the fixed point (F.1), and the
/// total bound's run iterates it; `newton-unfrozen` names (Co.3) or (N.4). impact_friction to
/// t = 0.1 with a constant μ = 0.3.
#[test]
fn friction_words_are_true_for_every_bound() {
    use dyncontact::output::ModelInfo;
    use dyncontact::problem::Problem;
    use dyncontact::scene::{BoundAt, FrictionBound, FrictionLaw, InnerSolver, Scene};
    use dyncontact::simulation::Simulation;
    let dir = scene("impact_friction").parent().expect("dir").to_path_buf();
    let cases = [
        (
            FrictionLaw::Constant,
            FrictionBound::Capped,
            BoundAt::Predictor,
            InnerSolver::Newton,
            "one convex solve per step",
        ),
        (
            FrictionLaw::Constant,
            FrictionBound::Uncapped,
            BoundAt::Predictor,
            InnerSolver::Newton,
            "one convex solve per step",
        ),
        (
            FrictionLaw::Constant,
            FrictionBound::Total,
            BoundAt::Predictor,
            InnerSolver::Newton,
            "fixed point on S (F.1)",
        ),
        (FrictionLaw::Constant, FrictionBound::Total, BoundAt::Predictor, InnerSolver::NewtonUnfrozen, "(Co.3)"),
        (
            FrictionLaw::Constant,
            FrictionBound::Capped,
            BoundAt::Midpoint,
            InnerSolver::Newton,
            "fixed point on S (F.1)",
        ),
        (
            FrictionLaw::Exponential,
            FrictionBound::Capped,
            BoundAt::Predictor,
            InnerSolver::Newton,
            "fixed point on S (F.1)",
        ),
        (FrictionLaw::Exponential, FrictionBound::Capped, BoundAt::Predictor, InnerSolver::NewtonUnfrozen, "(N.4)"),
    ];
    for (law, bound, at, inner, words) in cases {
        let mut s = Scene::from_file(&scene("impact_friction")).expect("scene");
        s.time.end = 0.1;
        let c = s.contact.as_mut().expect("contact");
        (c.friction_bound, c.friction_bound_at) = (bound, at);
        if law == FrictionLaw::Constant {
            c.friction = dyncontact::scene::Friction { law, coefficient: Some(0.3), ..Default::default() };
        }
        s.solver.inner = inner;
        let p = Problem::from_scene(&s, &dir).expect("problem");
        let friction = ModelInfo::of(&p).friction;
        println!("{law:?} {bound:?} {at:?} {inner:?}: {friction}");
        assert!(friction.contains(words), "{bound:?} {at:?} {inner:?}: {friction:?} does not say {words:?}");
        let one_solve = friction.contains("one convex solve");
        assert_eq!(one_solve, words == "one convex solve per step", "{friction:?}");
        if inner == InnerSolver::Newton && law == FrictionLaw::Constant {
            let mut sim = Simulation::new(&p).expect("setup");
            let most = sim.steps().map(|r| r.expect("step").report.fixed_point_iterations).max().unwrap_or(0);
            println!("  at most {most} F.1 iterations per step");
            assert!(if one_solve { most <= 1 } else { most > 1 }, "{friction:?}: at most {most} F.1 iterations");
        }
    }
}

/// Bad input exits with code 1 and one message naming the key path; a missing file names it.
#[test]
fn cli_bad_input_exits_1_with_a_message() {
    let dir = tmp("cli_bad");
    std::fs::create_dir_all(&dir).expect("dir");
    let bad = dir.join("bad.toml");
    let text = std::fs::read_to_string(scene("academic")).expect("academic").replace("decay = 20.0", "decay = -3");
    std::fs::write(&bad, text).expect("write");
    let st = Command::new(BIN).arg("run").arg(&bad).arg("--out").arg(dir.join("out")).output().expect("run");
    assert_eq!(st.status.code(), Some(1));
    let err = String::from_utf8_lossy(&st.stderr);
    assert!(err.contains("contact.friction.decay: must be >= 0, got -3"), "{err}");
    let st = Command::new(BIN).args(["check", "/nonexistent/scene.toml"]).output().expect("check");
    assert_eq!(st.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&st.stderr).contains("/nonexistent/scene.toml"));
}

/// A scene without contact writes contact.csv with its header only and zeros in the contact
/// columns of history.csv.
#[test]
fn cli_run_without_contact() {
    let out = tmp("cli_no_contact");
    let st = Command::new(BIN).arg("run").arg(scene("gmsh_square")).arg("--out").arg(&out).output().expect("run");
    assert!(st.status.success(), "{}", String::from_utf8_lossy(&st.stderr));
    let c = std::fs::read_to_string(out.join("contact.csv")).expect("contact.csv");
    assert_eq!(c.lines().count(), 1);
    let text = std::fs::read_to_string(out.join("history.csv")).expect("history");
    for line in text.lines().skip(1) {
        let v: Vec<&str> = line.split(',').collect();
        for col in [10, 11, 12, 13, 14, 15] {
            assert_eq!(v[col].parse::<f64>().expect("number"), 0.0, "contact column {col} not zero");
        }
    }
}

/// (Co.1) Where the model switched on is less than the scene states, `run` says so on stderr
/// and in summary.json: a `[contact]` section with no contact side, on the crosscheck scene
/// (which has none).
#[test]
fn less_physics_than_stated_is_a_warning_on_stderr_and_in_the_summary() {
    let dir = tmp("warning");
    std::fs::create_dir_all(&dir).expect("dir");
    let text = std::fs::read_to_string(scene("crosscheck_strain")).expect("scene")
        + "\n[contact]\ncompliance = 10.0\npenetration_bound = 0.1\n";
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).expect("write");
    let st = Command::new(BIN).arg("run").arg(&path).arg("--out").arg(dir.join("out")).output().expect("run");
    let err = String::from_utf8_lossy(&st.stderr);
    assert!(st.status.success(), "{err}");
    let expected = "the [contact] section is not used: boundary.contact names no contact side";
    assert!(err.contains(&format!("warning: {expected}")), "stderr: {err}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out/summary.json")).expect("summary")).expect("json");
    let warnings = summary["warnings"].as_array().expect("warnings");
    assert!(warnings.iter().any(|w| w.as_str() == Some(expected)), "summary warnings: {warnings:?}");
}

/// (issue 24, item 7) Every `--set` example and every sweep of the README runs as written: the
/// `--set …` spans of README.md (those with a concrete value) on `check` of the academic scene,
/// through the shell as a user types them; the sweep file under "Sweeps" with `--plan-only`
/// (its base `academic.toml` beside it); the `sets = […]` example that switches friction laws.
/// Read from README.md itself, so the test follows the README.
#[test]
fn the_readme_set_and_sweep_commands_run() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("README.md")).expect("README.md");
    // inline code spans (they may wrap a line): `…`
    let spans: Vec<String> = readme
        .split('`')
        .skip(1)
        .step_by(2)
        .map(|s| s.split_whitespace().collect::<Vec<_>>().join(" "))
        .filter(|s| !s.contains("```"))
        .collect();
    let sets: Vec<&String> = spans.iter().filter(|s| s.starts_with("--set ") && !s.contains("KEY=VALUE")).collect();
    assert!(sets.len() >= 6, "the README's --set examples: {sets:?}");
    for s in &sets {
        let cmd = format!("'{BIN}' check '{}' {s}", scene("academic").display());
        let o = Command::new("sh").arg("-c").arg(&cmd).output().expect("sh");
        assert!(o.status.success(), "README example `{s}` fails: {}", String::from_utf8_lossy(&o.stderr));
    }
    let dir = tmp("readme_sweeps");
    std::fs::create_dir_all(&dir).expect("dir");
    std::fs::copy(scene("academic"), dir.join("academic.toml")).expect("copy");
    let after = &readme[readme.find("## Sweeps").expect("a Sweeps section")..];
    let block = after.split("```toml\n").nth(1).and_then(|b| b.split("```").next()).expect("the sweep example");
    let sets_law =
        spans.iter().find(|s| s.starts_with("sets = ") && s.contains("law")).expect("the law-switching sets");
    let law_sweep = format!("name = \"laws\"\n[[axis]]\nname = \"law\"\n{sets_law}\n");
    for (name, text) in [("readme.toml", block.to_string()), ("laws.toml", law_sweep)] {
        std::fs::write(dir.join(name), text).expect("write");
        let o = Command::new(BIN)
            .arg("sweep")
            .arg(dir.join(name))
            .arg("--plan-only")
            .arg("--out")
            .arg(dir.join(format!("out-{name}")))
            .output()
            .expect("sweep");
        assert!(o.status.success(), "README sweep {name} fails: {}", String::from_utf8_lossy(&o.stderr));
    }
}

/// (issue 24, item 12) A TOML error keeps TOML's diagram as lines (the source line, a caret
/// under the place), the one-line message above it; a wrong value given by `--set` says it came
/// from `--set` rather than pointing at a line of a text nobody wrote; with `--set`, an error of
/// the file itself names its line in the file.
#[test]
fn toml_errors_keep_their_diagram_and_name_where_the_value_came_from() {
    let dir = tmp("toml_errors");
    std::fs::create_dir_all(&dir).expect("dir");
    let bad = dir.join("bad.toml");
    std::fs::write(&bad, "name = \"x\"\n[domain]\nkind = \"rectangle\"\nsize = [2.0, 1.0\n").expect("write");
    for extra in [&[][..], &["--set", "time.end=1"][..]] {
        let o = Command::new(BIN).arg("check").arg(&bad).args(extra).output().expect("check");
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{e}");
        let lines: Vec<&str> = e.lines().collect();
        assert!(lines[0].contains("line 4, column 17") && lines[0].contains("unclosed array"), "{e}");
        assert!(lines.iter().any(|l| l.trim_start().starts_with("4 | size = [2.0, 1.0")), "{e}");
        assert!(lines.iter().any(|l| l.trim_end().ends_with('^') && !l.contains("size")), "{e}");
    }
    let o =
        Command::new(BIN).arg("check").arg(scene("academic")).args(["--set", "time.end=abc"]).output().expect("check");
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("time.end: ") && e.contains("came from --set time.end=\"abc\""), "{e}");
    assert_eq!(e.lines().count(), 1, "no diagram of the overridden text: {e}");
}

/// `[output] every = 0` writes no frames (and so no contact.csv rows, which are per frame): the
/// run completes with its full history.csv, its charts and no VTU file.
#[test]
fn output_every_zero_writes_no_frames() {
    let out = tmp("every_zero");
    let o = Command::new(BIN)
        .args(["run", "--set", "output.every=0", "--set", "time.end=0.05", "--out"])
        .arg(&out)
        .output()
        .expect("run");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let frames = std::fs::read_dir(out.join("frames")).map_or(0, |d| d.count());
    assert_eq!(frames, 0, "no frame is written");
    assert!(!out.join("series.pvd").exists(), "no series of frames");
    let history = std::fs::read_to_string(out.join("history.csv")).expect("history.csv");
    assert_eq!(history.lines().count(), 1 + 101, "a header and steps 0..=100");
    let contact = std::fs::read_to_string(out.join("contact.csv")).expect("contact.csv");
    assert_eq!(contact.lines().count(), 1, "contact.csv has its header only");
    for chart in ["forces.svg", "energy.svg", "contact_status.svg"] {
        let svg = std::fs::read_to_string(out.join("plots").join(chart)).expect(chart);
        assert!(!svg.contains("NaN"), "{chart} has a NaN");
    }
}

/// Requirement: the t = 0 row of a body that starts pressed into the foundation agrees with its
/// contact.csv rows: the academic block (bottom 2 m long) lowered by 0.015 m onto a foundation
/// 0.01 m below it penetrates u_ν = 0.005 m at every bottom node, so q = c_ν u_ν = 1000 · 0.005
/// = 5 N/m² there and the normal force is 5 · 2 = 10 N/m (round-off of Σ ω_i q_i: 1e-12). Every
/// node is in contact, in stick (the block starts at rest); λ and the friction force are not
/// solved for before the first step and are 0. The row said 0 N/m and 0 contact nodes, and
/// contact.csv `separated` beside p = 5.
#[test]
fn the_initial_row_of_a_pressed_body_has_its_contact_force() {
    let out = tmp("initially_pressed");
    let st = Command::new(BIN)
        .arg("run")
        .arg(scene("academic"))
        .args(["--set", "domain.cells=[8,4]", "--set", "time.end=0.005", "--set", "contact.gap=\"0.01\""])
        .args(["--set", "initial.displacement=[\"0\", \"-0.015\"]", "--set", "boundary.dirichlet=[]"])
        .arg("--out")
        .arg(&out)
        .output()
        .expect("run");
    assert!(st.status.success(), "{}", String::from_utf8_lossy(&st.stderr));
    let history = std::fs::read_to_string(out.join("history.csv")).expect("history");
    let cols: Vec<&str> = history.lines().next().expect("header").split(',').collect();
    let row0: Vec<&str> = history.lines().nth(1).expect("the t = 0 row").split(',').collect();
    let at = |name: &str| row0[cols.iter().position(|c| *c == name).expect(name)];
    let normal: f64 = at("normal_force").parse().expect("a number");
    assert!((normal - 10.0).abs() <= 1e-12, "normal_force at t = 0: {normal}");
    assert_eq!((at("contact_nodes"), at("stick_nodes"), at("slip_nodes")), ("9", "9", "0"));
    let contact = std::fs::read_to_string(out.join("contact.csv")).expect("contact");
    let ccols: Vec<&str> = contact.lines().next().expect("header").split(',').collect();
    let (p, status) =
        (ccols.iter().position(|c| *c == "p").expect("p"), ccols.iter().position(|c| *c == "status").expect("status"));
    let first: Vec<Vec<&str>> =
        contact.lines().skip(1).map(|l| l.split(',').collect::<Vec<_>>()).filter(|r| r[0] == "0").collect();
    assert_eq!(first.len(), 9, "the nine bottom nodes at t = 0");
    for r in &first {
        let q: f64 = r[p].parse().expect("p");
        assert!((q - 5.0).abs() <= 1e-12 && r[status] == "stick", "{r:?}");
    }
}
