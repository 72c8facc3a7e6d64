//! `--set KEY=VALUE` overrides and sweeps (SCENES.md, "Overrides and sweeps"): overrides read
//! exactly like a file (errors name the key), a sweep's points are validated before anything
//! runs, run in parallel into their folders, skipped when completed with the same scene, and a
//! failing point is recorded while the others complete; sweep.csv's figures are those of
//! separate `run`s of the same scenes.

use std::path::{Path, PathBuf};
use std::process::Command;

use dyncontact::overrides::Override;
use dyncontact::scene::{DEFAULT_SCENE, FrictionLaw, Scene};
use dyncontact::sweep::Plan;
use dyncontact::sweep::collect::{self, FIGURES};
use dyncontact::sweep::runner::{Outcome, RunnerOptions, run_points};

const BIN: &str = env!("CARGO_BIN_EXE_dyncontact");

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn tmp(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("tmp dir");
    d
}

fn with(sets: &[&str]) -> Result<Scene, dyncontact::Error> {
    let ovs = sets.iter().map(|s| Override::parse(s)).collect::<Result<Vec<_>, _>>()?;
    Scene::from_toml_with(DEFAULT_SCENE, "academic.toml", &ovs)
}

/// `--set` reaches nested keys, arrays (whole and by index), arrays of tables, inline tables
/// and strings (quoted, or bare where the value is not TOML).
#[test]
fn set_overrides_nested_keys_arrays_and_strings() {
    let s = with(&[
        "contact.friction.law=constant",
        "contact.friction.coefficient=0.4",
        "contact.friction.static=0.5",
        "domain.cells=[8, 4]",
        "domain.cells[1]=6",
        "loads.traction[0].value=[\"0\", \"-10\"]",
        "material.viscosity={ theta = 1.0, zeta = 0.5 }",
        "name=\"renamed\"",
        "description=a bare string",
        "time.end=0.05",
    ])
    .expect("valid overrides");
    let c = s.contact.as_ref().expect("contact");
    assert_eq!(c.friction.law, FrictionLaw::Constant);
    assert_eq!(c.friction.coefficient, Some(0.4));
    assert_eq!(s.domain.cells, Some(vec![8, 6]));
    assert_eq!(s.loads.traction[0].value, vec!["0".to_string(), "-10".to_string()]);
    assert_eq!((s.material.viscosity.theta, s.material.viscosity.zeta), (1.0, 0.5));
    assert_eq!((s.name.as_str(), s.description.as_str(), s.time.end), ("renamed", "a bare string", 0.05));
}

/// A wrong `--set` is refused with its key named: an unknown key and a wrong type as in a
/// file (the same key-path errors), an index out of range, a path through a value that is not
/// a table, and an argument without `=`.
#[test]
fn set_errors_name_the_key() {
    let cases: [(&[&str], &str, &str); 5] = [
        (&["contact.penaltyy=1e-5"], "contact.penaltyy", "unknown field `penaltyy`"),
        (&["domain.cells=3"], "domain.cells", "invalid type"),
        (&["domain.cells[4]=2"], "domain.cells[4]", "out of range"),
        (&["name.x=1"], "name.x", "`name` is a string, not a table"),
        (&["contact.penalty"], "--set", "is not KEY=VALUE"),
    ];
    for (sets, key, what) in cases {
        let e = with(sets).expect_err("refused").to_string();
        println!("{sets:?}: {e}");
        assert!(e.contains(key) && e.contains(what), "{sets:?}: expected {key} / {what}, got {e}");
    }
    // the same key-path message as the same mistake in a file
    let in_file = Scene::from_toml(
        &DEFAULT_SCENE.replace("penetration_bound = 0.02", "penetration_bound = 0.02\npenaltyy = 1e-5"),
        "f",
    )
    .expect_err("refused")
    .to_string();
    let by_set = with(&["contact.penaltyy=1e-5"]).expect_err("refused").to_string();
    // (the file's names its line there; --set's says where the value came from instead)
    let what =
        |m: &str| m.split_once("unknown field").map(|(_, w)| w.split(" (the value").next().unwrap_or(w).to_string());
    assert!(in_file.contains("contact.penaltyy: ") && by_set.contains("contact.penaltyy: "), "{in_file}\n{by_set}");
    assert_eq!(what(&in_file), what(&by_set), "file: {in_file}\n--set: {by_set}");
    assert!(by_set.contains("(the value came from --set contact.penaltyy="), "{by_set}");
    // a value that passes reading but not validation is refused by `validate`, naming the key
    let e = with(&["contact.friction.decay=-3"]).expect("reads").validate().expect_err("refused").to_string();
    assert!(e.starts_with("contact.friction.decay:"), "{e}");
}

/// The CLI: `run --set` runs the overridden scene (the number of steps follows time.end), and
/// `check --set` with a bad key exits 1 naming it.
#[test]
fn cli_run_and_check_take_set() {
    let out = tmp("set_run");
    let o = Command::new(BIN)
        .args(["run", "--set", "time.end=0.01", "--set", "domain.cells=[8,4]", "--set", "output.every=100", "--out"])
        .arg(&out)
        .output()
        .expect("spawn");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let history = std::fs::read_to_string(out.join("history.csv")).expect("history");
    assert_eq!(history.lines().count(), 1 + 1 + 20, "header, t = 0 and 20 steps of 5e-4");
    let o = Command::new(BIN)
        .args(["check"])
        .arg(root().join("fixtures/scenes/academic.toml"))
        .args(["--set", "contact.friction.decayy=3"])
        .output()
        .expect("spawn");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("contact.friction.decayy") && err.contains("from --set"), "{err}");
}

fn six_points() -> PathBuf {
    root().join("fixtures/sweeps/six_points.toml")
}

fn run_sweep(plan: &Plan, dir: &Path, jobs: usize) -> Vec<Outcome> {
    // each point's numerics sequential, as `dyncontact`'s main sets them (the runner sets no global state)
    faer::set_global_parallelism(faer::Par::Seq);
    let done = plan.write(dir, &dyncontact::sweep::snakemake::this_executable()).expect("the folder");
    run_points(plan, dir, &done, &RunnerOptions { jobs, progress: false, interrupt: None }).expect("run")
}

/// (sweep, Python) The command a sweep's Snakefile runs `dyncontact` with: one word (the CLI's
/// binary) is written as a JSON string, several (the Python package's `[python, "-m",
/// "dyncontact"]`) as a JSON list that decodes to those words exactly — a word with a quote,
/// `$(…)` and a space among them — which Snakemake's `:q` quotes word by word.
#[test]
fn the_snakefile_command_is_the_launcher_given() {
    let plan = Plan::from_file(&six_points(), &[]).expect("plan");
    let dir = tmp("sweep_launcher");
    let words = |dir: &Path| {
        let config = std::fs::read_to_string(dir.join("config.yaml")).expect("config.yaml");
        let line = config.lines().find_map(|l| l.strip_prefix("dyncontact: ")).expect("the command's line").to_string();
        serde_json::from_str::<serde_json::Value>(&line).expect("JSON")
    };
    plan.write(&dir.join("cli"), &["/opt/dyncontact".to_string()]).expect("the folder");
    assert_eq!(words(&dir.join("cli")), serde_json::json!("/opt/dyncontact"));
    let python = ["/v env/bin/py\"thon $(id)".to_string(), "-m".to_string(), "dyncontact".to_string()];
    plan.write(&dir.join("py"), &python).expect("the folder");
    assert_eq!(words(&dir.join("py")), serde_json::json!(python));
    let snakefile = std::fs::read_to_string(dir.join("py").join("Snakefile")).expect("Snakefile");
    assert!(snakefile.contains("{config[dyncontact]:q} sweep point"), "{snakefile}");
}

/// A 6-point sweep (3 penalties × 2 steps) run in-process with 2 jobs gives sweep.csv with one
/// row per point in the plan's order, its axis columns, status completed and every figure; each
/// point's history.csv equals, byte for byte, a separate `dyncontact run --set …` of the same
/// scene, and its figures equal those read from that run. Run again, every point is skipped
/// (completed with the same scene: its files untouched); with one point's summary removed, only
/// that point runs.
#[test]
fn six_point_sweep_matches_separate_runs_and_resumes() {
    let dir = tmp("sweep_six");
    let plan = Plan::from_file(&six_points(), &[]).expect("the plan");
    assert_eq!(plan.points.len(), 6);
    let outcomes = run_sweep(&plan, &dir, 2);
    assert!(outcomes.iter().all(|o| *o == Outcome::Completed), "{outcomes:?}");
    let (_, rows) = collect::collect(&dir).expect("collect");
    let csv = std::fs::read_to_string(dir.join("sweep.csv")).expect("sweep.csv");
    let header: Vec<&str> = csv.lines().next().expect("header").split(',').collect();
    assert_eq!(&header[..5], &["point", "contact.penalty", "time.step", "status", "wall_time_s"]);
    assert!(FIGURES.iter().all(|f| header.contains(f)) && header.ends_with(&["reason", "warnings"]), "{header:?}");
    assert_eq!(csv.lines().count(), 7);
    let expected = [
        ("0.001", "0.001"),
        ("0.001", "0.0005"),
        ("0.0001", "0.001"),
        ("0.0001", "0.0005"),
        ("0.00001", "0.001"),
        ("0.00001", "0.0005"),
    ];
    for (r, (pen, k)) in rows.iter().zip(expected) {
        assert_eq!((r.axes[0].as_str(), r.axes[1].as_str(), r.status.as_str()), (pen, k, "completed"), "{}", r.point);
        assert!(r.figures.iter().all(|f| !f.is_empty()), "{}: a figure is missing", r.point);
    }
    // separate runs of the same scenes through the CLI
    for (r, (pen, k)) in rows.iter().zip(expected) {
        let out = dir.join("separate").join(&r.point);
        let sets = ["contact.enforcement=\"penalty\"", "domain.cells=[16, 8]", "time.end=0.3", "output.every=100"];
        let mut cmd = Command::new(BIN);
        cmd.arg("run");
        for s in sets.iter().map(|s| s.to_string()).chain([format!("contact.penalty={pen}"), format!("time.step={k}")])
        {
            cmd.args(["--set", &s]);
        }
        let o = cmd.arg("--out").arg(&out).output().expect("spawn");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let a = std::fs::read(out.join("history.csv")).expect("separate history");
        let b = std::fs::read(dir.join("points").join(&r.point).join("history.csv")).expect("point history");
        assert!(a == b, "{}: history.csv differs from a separate run", r.point);
        let h = collect::History::read(&out.join("history.csv")).expect("history");
        let last = |c: &str| h.rows.last().expect("rows")[h.column(c).expect("column")].clone();
        assert_eq!(r.figures[FIGURES.iter().position(|f| *f == "final_kinetic").expect("figure")], last("kinetic"));
        let peak = h.numbers("normal_force").expect("column").into_iter().fold(f64::NEG_INFINITY, f64::max);
        assert_eq!(r.figure("max_normal_force"), Some(peak));
    }
    println!("6 points: sweep.csv rows and figures equal separate runs");
    // the iteration totals' means per step, right after the figures that were there before them
    let at = |name: &str| header.iter().position(|c| *c == name).unwrap_or_else(|| panic!("no {name} column"));
    assert_eq!(
        (at("newton_iterations_per_step"), at("fixed_point_iterations_per_step")),
        (at("final_time") + 1, at("final_time") + 2)
    );
    for r in &rows {
        let steps = r.figure("steps_completed").expect("steps_completed");
        for (mean, total) in [
            ("newton_iterations_per_step", "newton_iterations"),
            ("fixed_point_iterations_per_step", "fixed_point_iterations"),
        ] {
            let (m, t) = (r.figure(mean).expect(mean), r.figure(total).expect(total));
            println!("{}: {total} {t}, {mean} {m}", r.point);
            assert_eq!(m, t / steps, "{}: {mean}", r.point);
        }
    }
    // the charts draw the mean per step, not the total: the default figures and this sweep's
    let chart = std::fs::read_to_string(dir.join("plots/time.step.svg")).expect("plots/time.step.svg");
    assert!(chart.contains("newton_iterations_per_step"), "the time.step chart has no per-step iterations");
    let defaults = dyncontact::sweep::PlotSpec::default().figures;
    assert!(defaults.iter().any(|f| f == "newton_iterations_per_step"), "{defaults:?}");
    assert!(!defaults.iter().any(|f| f == "newton_iterations" || f == "fixed_point_iterations"), "{defaults:?}");
    // resume: nothing runs again
    let stamp = |id: &str| {
        std::fs::metadata(dir.join("points").join(id).join("history.csv")).and_then(|m| m.modified()).expect("mtime")
    };
    let before = stamp("p003");
    let again = run_sweep(&plan, &dir, 2);
    assert!(again.iter().all(|o| *o == Outcome::Skipped), "{again:?}");
    assert_eq!(stamp("p003"), before, "a skipped point's files were rewritten");
    std::fs::remove_file(dir.join("points/p002/summary.json")).expect("remove");
    let partial = run_sweep(&plan, &dir, 2);
    let ran: Vec<usize> =
        partial.iter().enumerate().filter(|(_, o)| **o == Outcome::Completed).map(|(i, _)| i).collect();
    assert_eq!(ran, vec![2], "{partial:?}");
    let (_, again_rows) = collect::collect(&dir).expect("collect");
    assert_eq!(
        again_rows.iter().map(|r| &r.figures).collect::<Vec<_>>(),
        rows.iter().map(|r| &r.figures).collect::<Vec<_>>(),
        "the rerun point's figures changed"
    );
    // the cluster files: a rule per point, one collector, a resource entry per point
    let snakefile = std::fs::read_to_string(dir.join("Snakefile")).expect("Snakefile");
    assert!(
        snakefile.contains("rule point:")
            && snakefile.contains("rule collect:")
            && snakefile.contains("sweep collect .")
    );
    let config = std::fs::read_to_string(dir.join("config.yaml")).expect("config.yaml");
    assert_eq!(config.lines().filter(|l| l.trim_start().starts_with('p') && l.contains("mem_mb")).count(), 6);
}

/// (sweep) No point is refused while other threads of the process start child processes: a
/// child holds every descriptor of its parent between fork and exec, a point's folder lock
/// among them, and a released lock stayed held by that copy, so the point that released its
/// lock and took it again to run was refused ("another dyncontact process is writing this
/// folder", the folder left with run.lock and scene.toml: seen once in CI, where tests start
/// the binary beside in-process sweeps). Locks are now unlocked when released, and a point is
/// cleared and run under one lock. Five times, the six points run with 2 jobs into a new folder
/// while two threads start processes without pause; every point must complete (the code before
/// failed 8 of 41 runs of this test: a regression guard; the deterministic test is
/// `output::folder`'s).
#[test]
fn no_point_is_refused_while_other_threads_start_processes() {
    use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
    /// Stops the spawning threads however the sweeps end (a panic too: the scope would wait).
    struct Stop<'a>(&'a AtomicBool);
    impl Drop for Stop<'_> {
        fn drop(&mut self) {
            self.0.store(true, Ordering::SeqCst);
        }
    }
    let plan = Plan::from_file(&six_points(), &[]).expect("the plan");
    let (stop, spawned) = (AtomicBool::new(false), AtomicUsize::new(0));
    let outcomes = std::thread::scope(|s| {
        for _ in 0..2 {
            s.spawn(|| {
                while !stop.load(Ordering::SeqCst) {
                    // `true`: the quickest child, so the most fork–exec windows a second
                    if Command::new("true").status().is_ok() {
                        spawned.fetch_add(1, Ordering::SeqCst);
                    }
                }
            });
        }
        let _stop = Stop(&stop);
        (0..5).flat_map(|round| run_sweep(&plan, &tmp(&format!("sweep_spawning_{round}")), 2)).collect::<Vec<_>>()
    });
    assert!(spawned.load(Ordering::SeqCst) > 0, "no child process (`true`) was started beside the sweeps");
    assert!(outcomes.iter().all(|o| *o == Outcome::Completed), "{outcomes:?}");
}

/// (units) Every sweep figure with a unit has the unit of its history.csv column for the
/// dimension, counts and ratios have none, and refine's impulses (whole run and windows) are a
/// force times a time: N·s/m in 2-D, N·s in 3-D. The charts' axes read these.
#[test]
fn every_figure_has_the_unit_of_its_column() {
    use dyncontact::output::units::{Units, figure};
    for dim in [2, 3] {
        let u = Units::of(dim);
        for name in FIGURES {
            let column = name.trim_start_matches("final_").trim_start_matches("max_");
            let expected = match column {
                "abs_energy_residual" => u.history_unit("energy_residual"),
                "time" => u.history_unit("t"),
                _ => u.history_unit(name).or(u.history_unit(column)).filter(|unit| *unit != "1"),
            };
            assert_eq!(figure(name, dim).as_deref(), expected, "{name} in {dim}-D");
        }
        let impulse = if dim == 3 { "N·s" } else { "N·s/m" };
        for name in dyncontact::sweep::refine::impulse_figures(dim, 4) {
            assert_eq!(figure(&name, dim).as_deref(), Some(impulse), "{name} in {dim}-D");
        }
    }
}

/// A point that fails at run time (Newton capped at one iteration on the frictional impact) is
/// recorded — status failed and its reason in sweep.csv, summary.json saying why — and the other
/// points complete.
#[test]
fn a_failing_point_is_recorded_and_the_others_complete() {
    let dir = tmp("sweep_failing");
    let file = dir.join("failing.toml");
    std::fs::write(
        &file,
        r#"
name = "failing"
base = "../../../fixtures/scenes/impact_friction.toml"
[[axis]]
key = "solver.max_newton_iterations"
values = [50, 1, 40]
[set]
"time.end" = 0.05
"#,
    )
    .expect("write");
    // the base path is relative to the sweep file: resolve from the test's temporary folder
    let sweep_text = std::fs::read_to_string(&file)
        .expect("read")
        .replace("../../../fixtures", &root().join("fixtures").display().to_string());
    std::fs::write(&file, sweep_text).expect("write");
    let plan = Plan::from_file(&file, &[]).expect("plan");
    let outcomes = run_sweep(&plan, &dir.join("out"), 2);
    assert_eq!(outcomes[0], Outcome::Completed);
    assert!(matches!(&outcomes[1], Outcome::Failed(r) if r.contains("newton solver failed")), "{outcomes:?}");
    // shown in sweep.csv's words
    assert_eq!(outcomes[0].to_string(), "completed");
    assert!(
        outcomes[1].to_string().starts_with("failed: step ")
            && outcomes[1].to_string().contains("newton solver failed"),
        "{}",
        outcomes[1]
    );
    assert_eq!(outcomes[2], Outcome::Completed);
    let (_, rows) = collect::collect(&dir.join("out")).expect("collect");
    assert_eq!(rows.iter().map(|r| r.status.as_str()).collect::<Vec<_>>(), ["completed", "failed", "completed"]);
    assert!(rows[1].reason.contains("newton solver failed"), "{}", rows[1].reason);
    let csv = std::fs::read_to_string(dir.join("out/sweep.csv")).expect("csv");
    assert!(csv.lines().nth(2).is_some_and(|l| l.contains(",failed,") && l.contains("newton solver failed")), "{csv}");
}

/// Every point is validated before anything runs: one bad point refuses the sweep, naming the
/// key, the point and its axis values; a sweep file's own mistakes name their key path.
#[test]
fn a_bad_point_refuses_the_sweep_before_anything_runs() {
    let dir = tmp("sweep_refused");
    let bad = |name: &str, text: &str| {
        let f = dir.join(name);
        std::fs::write(&f, text).expect("write");
        Plan::from_file(&f, &[]).expect_err("refused").to_string()
    };
    let e = bad(
        "p.toml",
        "name = \"p\"\n[[axis]]\nkey = \"contact.penalty\"\nvalues = [1e-3, -1.0]\n[set]\n\"contact.enforcement\" = \"penalty\"\n",
    );
    println!("{e}");
    assert!(
        e.starts_with("contact.penalty: in sweep point p001 (contact.penalty = -1): must be a finite number > 0"),
        "{e}"
    );
    assert!(!dir.join("out").exists());
    let e = bad("k.toml", "name = \"k\"\n[[axis]]\nkey = \"time.stepp\"\nvalues = [1e-3]\n");
    assert!(e.contains("point p000 (time.stepp = 0.001)") && e.contains("unknown field `stepp`"), "{e}");
    let e = bad("u.toml", "name = \"u\"\nmodee = \"grid\"\n");
    assert!(e.contains("modee"), "{e}");
    let e = bad(
        "z.toml",
        "name = \"z\"\nmode = \"zip\"\n[[axis]]\nkey = \"time.step\"\nvalues = [1e-3, 5e-4]\n[[axis]]\nkey = \"contact.compliance\"\nvalues = [1.0]\n",
    );
    assert!(e.contains("\"zip\" needs axes of one length"), "{e}");
    let e =
        bad("s.toml", "name = \"s\"\n[[axis]]\nkey = \"time.step\"\nvalues = [1e-3]\n[set]\n\"time.step\" = 5e-4\n");
    assert!(e.contains("time.step and time.step of [set] set the same value"), "{e}");
    // two axes, or an axis and a key below it in [set], touching one value
    let e = bad(
        "a.toml",
        "name = \"a\"\n[[axis]]\nkey = \"time.step\"\nvalues = [1e-3]\n[[axis]]\nname = \"v\"\nsets = [{ \"time.step\" = 2e-3 }]\n",
    );
    assert!(e.contains("time.step and time.step of axis[0]"), "{e}");
    let e = bad(
        "f.toml",
        "name = \"f\"\n[[axis]]\nkey = \"contact.friction\"\nvalues = [{ decay = 5.0 }, { decay = 10.0 }]\n[set]\n\"contact.friction.decay\" = 5.0\n",
    );
    assert!(e.contains("contact.friction and contact.friction.decay of [set] set the same value"), "{e}");
    // name and labels go with `sets`; the columns of sweep.csv are taken; an empty set says nothing
    let e = bad("n.toml", "name = \"n\"\n[[axis]]\nkey = \"time.step\"\nname = \"k\"\nvalues = [1e-3]\n");
    assert!(e.contains("axis[0]") && e.contains("`name` and `labels` go with `sets`"), "{e}");
    let e = bad("r.toml", "name = \"r\"\n[[axis]]\nname = \"status\"\nsets = [{ \"time.step\" = 1e-3 }]\n");
    assert!(e.contains("\"status\" is a column of sweep.csv already"), "{e}");
    let e = bad("e.toml", "name = \"e\"\n[[axis]]\nname = \"x\"\nsets = [{}]\n");
    assert!(e.contains("axis[0].sets[0]") && e.contains("is empty"), "{e}");
    // the checks of building the problem: a gap below the body puts u^0 beyond the bound
    let e = bad("g.toml", "name = \"g\"\n[[axis]]\nkey = \"contact.gap\"\nvalues = [\"0\", \"-0.1\"]\n");
    assert!(e.contains("point p001 (contact.gap = -0.1)"), "{e}");
    // `--set` on a value an axis sets
    let f = dir.join("six.toml");
    std::fs::copy(six_points(), &f).expect("copy");
    let e =
        Plan::from_file(&f, &[Override::parse("time.step=1e-3").expect("override")]).expect_err("refused").to_string();
    assert!(e.contains("of --set set the same value"), "{e}");
    assert!(Override::parse("domain.cells[1=0").is_err(), "an unclosed index");
}

/// A bad point's error keeps the key path of what is wrong ([`dyncontact::Error::key`], the
/// Python package's `SceneError.key`): an unknown key on an axis, a bad value on an axis and an
/// unknown key in `[set]` are keyed by that dotted key, and the message names the point and its
/// axis values — not the point's scene.toml (never written for a refused sweep) nor a line of it.
#[test]
fn a_bad_point_is_keyed_by_its_key_path() {
    let dir = tmp("sweep_bad_key");
    let cases = [
        (
            "unknown",
            "[[axis]]\nkey = \"contact.penaltyy\"\nvalues = [1e-3]\n",
            "contact.penaltyy",
            "p000 (contact.penaltyy = 0.001)",
            "unknown field `penaltyy`",
        ),
        (
            "value",
            "[[axis]]\nkey = \"contact.compliance\"\nvalues = [1.0, -1.0]\n",
            "contact.compliance",
            "p001 (contact.compliance = -1)",
            "must be >= 0, got -1",
        ),
        (
            "set",
            "[[axis]]\nkey = \"time.step\"\nvalues = [1e-3]\n[set]\n\"contact.penaltyy\" = 1e-3\n",
            "contact.penaltyy",
            "p000 (time.step = 0.001)",
            "unknown field `penaltyy`",
        ),
    ];
    for (name, body, key, point, what) in cases {
        let f = dir.join(format!("{name}.toml"));
        std::fs::write(&f, format!("name = \"{name}\"\n{body}")).expect("write");
        let e = Plan::from_file(&f, &[]).expect_err("refused");
        let shown = e.to_string();
        println!("{name}: {shown}");
        assert_eq!(e.key(), Some(key), "{shown}");
        assert!(shown.starts_with(&format!("{key}: in sweep point {point}: ")) && shown.contains(what), "{shown}");
        assert!(!shown.contains("scene.toml") && !shown.contains("line "), "{shown}");
    }
    // a sweep refused from the command line writes nothing and exits 1
    let out = dir.join("out");
    let o = Command::new(BIN).arg("sweep").arg(dir.join("set.toml")).arg("--out").arg(&out).output().expect("spawn");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("contact.penaltyy: in sweep point p000"), "{stderr}");
    assert!(!out.join("sweep.json").exists(), "a refused sweep wrote its plan");
}

/// A table in `[set]` (an unquoted dotted key is one in TOML) is merged into the scene's table:
/// the base's other keys of that table stay.
#[test]
fn a_table_in_set_is_merged_into_the_scene() {
    let dir = tmp("sweep_merge");
    let f = dir.join("m.toml");
    std::fs::write(&f, "name = \"m\"\n[set]\nsolver.relaxation = 0.5\n").expect("write");
    let plan = Plan::from_file(&f, &[]).expect("plan");
    let scene = Scene::from_toml(&plan.points[0].scene_text, "point").expect("scene");
    assert_eq!(scene.solver.relaxation, 0.5);
    assert_eq!(scene.solver.mass, dyncontact::scene::MassKind::Lumped, "the base's other solver keys stay");
    assert!(plan.points[0].scene_text.contains("inner = \"newton\""), "{}", plan.points[0].scene_text);
}

/// A fresh folder `name` with the three-step sweep over k of [`steps_sweep`] run to completion
/// into its `out/`: the folder, `out` and the plan.
fn completed_steps_sweep(name: &str) -> (PathBuf, PathBuf, Plan) {
    let dir = tmp(name);
    let out = dir.join("out");
    let (_, plan) = steps_sweep(&dir, "k.toml", "[1e-3, 5e-4, 2.5e-4]", "");
    assert!(run_sweep(&plan, &out, 2).iter().all(|o| *o == Outcome::Completed));
    (dir, out, plan)
}

/// When the axes change, a point whose scene was run before keeps its run: its folder moves to
/// its new id with its marker (`points/<id>.done`, Snakemake's output) and only the new point
/// runs.
#[test]
fn points_moved_by_a_changed_axis_keep_their_runs() {
    let dir = tmp("sweep_moved");
    let write = |values: &str| {
        let f = dir.join("k.toml");
        std::fs::write(&f, format!("name = \"k\"\n[[axis]]\nkey = \"time.step\"\nvalues = {values}\n[set]\n\"domain.cells\" = [8, 4]\n\"time.end\" = 0.02\n")).expect("write");
        Plan::from_file(&f, &[]).expect("plan")
    };
    let out = dir.join("out");
    let first = write("[1e-3, 5e-4]");
    assert!(run_sweep(&first, &out, 2).iter().all(|o| *o == Outcome::Completed));
    let history = std::fs::read(out.join("points/p001/history.csv")).expect("history");
    let second = write("[2e-3, 1e-3, 5e-4]");
    // laid out only (as --plan-only): the moved runs keep their markers, so Snakemake runs only
    // the new point
    let done = second.write(&out, &dyncontact::sweep::snakemake::this_executable()).expect("the folder");
    assert_eq!(done, vec![false, true, true]);
    let markers: Vec<bool> =
        ["p000", "p001", "p002"].iter().map(|id| out.join(format!("points/{id}.done")).exists()).collect();
    assert_eq!(markers, vec![false, true, true], "the markers follow the moved points");
    let outcomes = run_sweep(&second, &out, 2);
    assert_eq!(outcomes, vec![Outcome::Completed, Outcome::Skipped, Outcome::Skipped]);
    assert_eq!(
        std::fs::read(out.join("points/p002/history.csv")).expect("moved history"),
        history,
        "k = 5e-4 moved from p001 to p002"
    );
}

/// A small sweep on `time.step` (8×4 cells, to t = 0.02), its file written as `dir/<file>`.
fn steps_sweep(dir: &Path, file: &str, values: &str, extra: &str) -> (PathBuf, Plan) {
    let f = dir.join(file);
    std::fs::write(&f, format!("name = \"k\"\n[[axis]]\nkey = \"time.step\"\nvalues = {values}\n[set]\n\"domain.cells\" = [8, 4]\n\"time.end\" = 0.02\n{extra}")).expect("write");
    let plan = Plan::from_file(&f, &[]).expect("plan");
    (f, plan)
}

/// A folder's files (relative paths, sorted) with their bytes, but a sweep's lock (`sweep.lock`,
/// which every sweep of the folder takes).
fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    crate::common::files_below(dir, "sweep.lock").into_iter().map(|(p, b)| (p.display().to_string(), b)).collect()
}

/// Completed runs are never dropped: a sweep run again into its folder with fewer values, or
/// another sweep into that folder, would drop or overwrite completed points whose scene it does
/// not have, and is refused (exit 4) before anything is written, naming the folder, the points
/// with their axis values and the way on (another --out, or remove them by hand); once they are
/// removed by hand, the smaller sweep runs there, keeping the point it shares.
#[test]
fn completed_points_are_never_dropped() {
    let (dir, out, _) = completed_steps_sweep("sweep_never_dropped");
    let before = files(&out);
    let launcher = dyncontact::sweep::snakemake::this_executable();
    // fewer values: 5e-4 (p001) would be overwritten by 2.5e-4 moving there
    let (fewer_file, fewer) = steps_sweep(&dir, "fewer.toml", "[1e-3, 2.5e-4]", "");
    let e = fewer.write(&out, &launcher).expect_err("refused");
    println!("{e}");
    assert_eq!(e.exit_code(), 4, "{e}");
    let shown = e.to_string();
    assert!(shown.starts_with(&out.display().to_string()), "{shown}");
    assert!(shown.contains("points/p001 (time.step = 0.0005)") && shown.contains("--out"), "{shown}");
    assert!(!shown.contains("p000") && !shown.contains("p002"), "{shown}");
    // fewer values at the end: the dropped p002 is refused as well
    let (_, head) = steps_sweep(&dir, "head.toml", "[1e-3, 5e-4]", "");
    let shown = head.write(&out, &launcher).expect_err("refused").to_string();
    assert!(shown.contains("points/p002 (time.step = 0.00025)"), "{shown}");
    // another sweep (another base: every scene differs) into this sweep's folder
    let (_, other) = steps_sweep(&dir, "other.toml", "[1e-3, 5e-4, 2.5e-4]", "\"solver.relaxation\" = 0.5\n");
    let shown = other.write(&out, &launcher).expect_err("refused").to_string();
    assert!(shown.contains("3 completed points") && shown.contains("points/p000 (time.step = 0.001)"), "{shown}");
    // the command line: exit 4, and the folder as it was (but the sweep's lock)
    let o = Command::new(BIN)
        .arg("sweep")
        .arg(&fewer_file)
        .args(["--jobs", "1", "--out"])
        .arg(&out)
        .output()
        .expect("spawn");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(4), "{stderr}");
    assert!(stderr.contains("would drop or overwrite it"), "{stderr}");
    assert!(files(&out) == before, "a refused sweep changed the folder");
    // removed by hand, the smaller sweep runs: p000 stays, 2.5e-4 moves to p001
    let kept = std::fs::read(out.join("points/p002/history.csv")).expect("history");
    std::fs::remove_dir_all(out.join("points/p001")).expect("remove");
    std::fs::remove_file(out.join("points/p001.done")).expect("remove");
    assert_eq!(run_sweep(&fewer, &out, 2), vec![Outcome::Skipped, Outcome::Skipped]);
    assert_eq!(std::fs::read(out.join("points/p001/history.csv")).expect("moved"), kept);
    assert!(!out.join("points/p002").exists() && !out.join("points/p002.done").exists());
}

/// A sweep writes only into a new or empty folder or a sweep's own (it has sweep.json): a folder
/// with a user's file, or a `run`'s folder, is refused (exit 4) naming what it holds, and left
/// as it was — no lock, no plan; `sweep collect` of it is refused alike.
#[test]
fn a_folder_that_is_not_a_sweeps_is_refused() {
    let dir = tmp("sweep_foreign_folder");
    let (f, _) = steps_sweep(&dir, "one.toml", "[1e-3]", "");
    let notes = dir.join("notes");
    std::fs::create_dir_all(&notes).expect("mkdir");
    std::fs::write(notes.join("notes.txt"), "my notes").expect("write");
    let run = dir.join("run");
    let o = Command::new(BIN)
        .args(["run", "--set", "time.end=0.01", "--set", "domain.cells=[8,4]", "--out"])
        .arg(&run)
        .output()
        .expect("spawn");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for (folder, holds) in [(&notes, "notes.txt"), (&run, "history.csv")] {
        let before = files(folder);
        for args in [vec!["sweep", f.to_str().expect("path"), "--plan-only", "--out"], vec!["sweep", "collect"]] {
            let o = Command::new(BIN).args(&args).arg(folder).output().expect("spawn");
            let stderr = String::from_utf8_lossy(&o.stderr);
            println!("{args:?}: {stderr}");
            assert_eq!(o.status.code(), Some(4), "{stderr}");
            assert!(stderr.contains("is not a sweep's folder") && stderr.contains(holds), "{stderr}");
            assert!(files(folder) == before, "{args:?} changed {}", folder.display());
            assert!(!folder.join("sweep.lock").exists(), "{args:?} left a lock in {}", folder.display());
        }
    }
    // the run's folder is still one `run` accepts
    let o = Command::new(BIN)
        .args(["run", "--set", "time.end=0.01", "--set", "domain.cells=[8,4]", "--out"])
        .arg(&run)
        .output()
        .expect("spawn");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // an empty folder is a sweep's to write
    let empty = dir.join("empty");
    std::fs::create_dir_all(&empty).expect("mkdir");
    let o = Command::new(BIN).arg("sweep").arg(&f).arg("--plan-only").arg("--out").arg(&empty).output().expect("spawn");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // and the library refuses the same folder
    let (_, plan) = steps_sweep(&dir, "one.toml", "[1e-3]", "");
    let e = plan.write(&notes, &[]).expect_err("refused");
    assert_eq!(e.exit_code(), 4, "{e}");
}

/// A point whose files do not agree (its history.csv cut short) is run again by the next sweep,
/// its marker removed when the sweep is laid out (so Snakemake runs it again too); the other
/// points are skipped.
#[test]
fn a_corrupt_point_runs_again() {
    let (_, out, plan) = completed_steps_sweep("sweep_corrupt_rerun");
    let history = out.join("points/p001/history.csv");
    let text = std::fs::read_to_string(&history).expect("history");
    let cut: String = text.lines().take(text.lines().count() - 1).map(|l| format!("{l}\n")).collect();
    std::fs::write(&history, cut).expect("truncate");
    let (_, rows) = collect::collect(&out).expect("collect");
    assert_eq!(rows[1].status.as_str(), "corrupt");
    let done = plan.write(&out, &dyncontact::sweep::snakemake::this_executable()).expect("the folder");
    assert_eq!(done, vec![true, false, true]);
    assert!(!out.join("points/p001.done").exists() && out.join("points/p000.done").exists());
    assert_eq!(run_sweep(&plan, &out, 2), vec![Outcome::Skipped, Outcome::Completed, Outcome::Skipped]);
    let (_, rows) = collect::collect(&out).expect("collect");
    assert!(rows.iter().all(|r| r.status.is_completed()), "{rows:?}");
    assert_eq!(std::fs::read_to_string(&history).expect("history"), text, "the rerun gives the same history");
    assert!(out.join("points/p001.done").exists());
}

/// A point too large for this machine's memory (2.6 TiB) passes the plan (`--plan-only`, for a
/// cluster's larger nodes; listed by `too_large_here`) but refuses a sweep run here before any
/// point runs, naming the key, the point and the estimate (exit 1).
#[test]
fn a_point_too_large_for_this_machine_refuses_the_run_before_anything_runs() {
    if dyncontact::resources::available_memory().is_none() {
        println!("skipped: this system does not say how much memory is available");
        return;
    }
    let dir = tmp("sweep_too_large");
    let f = dir.join("big.toml");
    std::fs::write(&f, "name = \"big\"\n[[axis]]\nkey = \"domain.cells\"\nvalues = [[8, 4], [20000, 20000]]\n[set]\n\"time.end\" = 0.02\n").expect("write");
    let plan = Plan::from_file(&f, &[]).expect("a plan: the point may be meant for a larger node");
    let out = dir.join("out");
    let large = dyncontact::sweep::runner::too_large_here(&plan, &out);
    assert_eq!(large.len(), 1, "{large:?}");
    assert_eq!(large[0].key(), Some("domain"));
    assert!(large[0].to_string().contains("in sweep point p001 (domain.cells = [20000, 20000])"), "{}", large[0]);
    let o = Command::new(BIN).arg("sweep").arg(&f).args(["--plan-only", "--out"]).arg(&out).output().expect("spawn");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = Command::new(BIN).arg("sweep").arg(&f).args(["--jobs", "1", "--out"]).arg(&out).output().expect("spawn");
    let stderr = String::from_utf8_lossy(&o.stderr);
    println!("{stderr}");
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("domain: in sweep point p001") && stderr.contains("TiB") && stderr.contains("No point ran"),
        "{stderr}"
    );
    assert!(!out.join("points/p000/summary.json").exists(), "a point ran");
    assert!(!out.join("points/p001.done").exists() && !out.join("points/p001/summary.json").exists());
}

/// `dyncontact sweep` from the command line: `--plan-only` writes the folder (a scene per point,
/// the Snakefile) without running; the run writes sweep.csv and a chart per numeric axis;
/// `sweep collect DIR` writes the same sweep.csv.
#[test]
fn cli_sweep_plan_run_and_collect() {
    let dir = tmp("sweep_cli");
    let o = Command::new(BIN)
        .arg("sweep")
        .arg(six_points())
        .arg("--out")
        .arg(&dir)
        .arg("--plan-only")
        .output()
        .expect("spawn");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        dir.join("points/p005/scene.toml").is_file()
            && dir.join("Snakefile").is_file()
            && !dir.join("sweep.csv").exists()
    );
    let o = Command::new(BIN)
        .arg("sweep")
        .arg(six_points())
        .arg("--out")
        .arg(&dir)
        .args(["--jobs", "2"])
        .output()
        .expect("spawn");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let first = std::fs::read_to_string(dir.join("sweep.csv")).expect("sweep.csv");
    for axis in ["contact.penalty", "time.step"] {
        let svg = std::fs::read_to_string(dir.join("plots").join(format!("{axis}.svg"))).expect("chart");
        assert!(svg.starts_with("<svg") && svg.contains("max_penetration"), "{axis}.svg");
        // the figures' axes in the points' (2-D) units; counts have none
        for label in ["max_penetration [m]", "friction_dissipation [J/m]"] {
            assert!(svg.contains(label), "{axis}.svg has no axis {label:?}");
        }
        assert!(!svg.contains("newton_iterations_per_step ["), "{axis}.svg gives a count a unit");
    }
    let o = Command::new(BIN).args(["sweep", "collect"]).arg(&dir).output().expect("spawn");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(std::fs::read_to_string(dir.join("sweep.csv")).expect("sweep.csv"), first);
}

/// (issue 24, item 7) A table value given whole replaces the table: `--set` switches the
/// friction law (the old law's keys go), and a `sets` axis of inline tables switches laws from
/// point to point, while a dotted key in `[set]` stays a leaf.
#[test]
fn a_table_given_whole_replaces_and_switches_the_friction_law() {
    let s = with(&["contact.friction={law=\"constant\", coefficient=0.3}"]).expect("the law switched");
    s.validate().expect("valid: the exponential law's static, kinetic and decay are gone");
    assert_eq!(s.contact.as_ref().expect("contact").friction.law, FrictionLaw::Constant);
    let leaf = with(&["contact.friction.law=constant"]).and_then(|s| s.validate().map(|_| ()));
    assert!(leaf.is_err(), "a dotted key changes one key: the other keys of the table stay");
    let dir = tmp("sweep_laws");
    let f = dir.join("laws.toml");
    std::fs::write(
        &f,
        "name = \"laws\"\n[[axis]]\nname = \"law\"\nsets = [{ \"contact.friction\" = { law = \"constant\", coefficient = 0.3 } }, { contact.friction = { law = \"none\" } }, { \"contact.friction.decay\" = 5.0 }]\nlabels = [\"constant\", \"none\", \"decay\"]\n[set]\nsolver.relaxation = 0.5\n",
    )
    .expect("write");
    let plan = Plan::from_file(&f, &[]).expect("a plan whose points switch laws");
    let laws: Vec<FrictionLaw> = plan
        .points
        .iter()
        .map(|p| Scene::from_toml(&p.scene_text, "point").expect("scene").contact.expect("contact").friction.law)
        .collect();
    assert_eq!(laws, vec![FrictionLaw::Constant, FrictionLaw::None, FrictionLaw::Exponential]);
    let third = Scene::from_toml(&plan.points[2].scene_text, "point").expect("scene");
    assert_eq!(third.solver.relaxation, 0.5);
    assert_eq!(third.solver.mass, dyncontact::scene::MassKind::Lumped, "a dotted key in [set] is a leaf");
}

/// (issue 24, item 8) A misspelled figure is refused when the sweep is read, naming the key and
/// the figures there are; a point's warnings (a step beyond (C.k)) reach sweep.csv's last
/// column, `warnings`, and one line on stderr names the points.
#[test]
fn sweeps_say_what_went_wrong() {
    let dir = tmp("sweep_says");
    let f = dir.join("typo.toml");
    std::fs::write(&f, "name = \"typo\"\n[plot]\nfigures = [\"max_penetraton\"]\n").expect("write");
    let e = Plan::from_file(&f, &[]).expect_err("refused").to_string();
    assert!(e.contains("plot.figures[0]") && e.contains("max_penetraton") && e.contains("max_penetration"), "{e}");
    let f = dir.join("ck.toml");
    std::fs::write(
        &f,
        "name = \"ck\"\n[[axis]]\nkey = \"time.step\"\nvalues = [1e-2, 5e-3]\n[set]\n\"domain.cells\" = [8, 4]\n\"time.end\" = 0.02\n",
    )
    .expect("write");
    let out = dir.join("out");
    let o = Command::new(BIN).arg("sweep").arg(&f).args(["--jobs", "1", "--out"]).arg(&out).output().expect("sweep");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    let csv = std::fs::read_to_string(out.join("sweep.csv")).expect("sweep.csv");
    assert!(csv.lines().next().is_some_and(|h| h.ends_with(",reason,warnings")), "{csv}");
    assert!(csv.lines().skip(1).all(|l| l.contains("(C.k)")), "{csv}");
    assert!(stderr.contains("2 of 2 points ran beyond (C.k): p000, p001"), "{stderr}");
}

/// Requirement: a sweep axis over a key its points do not use (`contact.penalty` on the exact
/// default scene: every point would be the same run) is refused before anything runs, naming the
/// key; with `[set] "contact.enforcement" = "penalty"` (the contract's example) it is a sweep.
#[test]
fn an_axis_over_an_unused_key_is_refused() {
    let dir = tmp("unused-axis");
    std::fs::create_dir_all(&dir).expect("dir");
    let file = dir.join("eps.toml");
    let body = "name = \"eps\"\nbase = \"default\"\n[[axis]]\nkey = \"contact.penalty\"\nvalues = [1e-3, 1e-4]\n";
    std::fs::write(&file, format!("{body}[set]\n\"time.end\" = 0.01\n")).expect("sweep file");
    let Err(e) = Plan::from_file(&file, &[]) else {
        panic!("an axis over contact.penalty without penalty enforcement was accepted")
    };
    assert_eq!(e.key(), Some("contact.penalty"), "{e}");
    assert!(e.to_string().contains("does not use"), "{e}");
    std::fs::write(&file, format!("{body}[set]\n\"time.end\" = 0.01\n\"contact.enforcement\" = \"penalty\"\n"))
        .expect("sweep file");
    assert_eq!(Plan::from_file(&file, &[]).expect("a sweep").points.len(), 2);
}
