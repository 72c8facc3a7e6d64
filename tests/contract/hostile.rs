//! Hostile probes of the run folder contract (README, "Outputs" and "Exit codes"): names that
//! carry code, folders reused by other runs, killed runs, edited and foreign checkpoints,
//! changed meshes, corrupted sweep points, locked folders, a full disk, physics that breaks.
//! Each test reproduces a defect that a reliability review found, and holds the contract:
//! a run folder always tells the truth about what is in it, and nothing a user writes runs as
//! code.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_dyncontact");

fn tmp(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("hostile").join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("tmp dir");
    d
}

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fixtures/scenes").join(format!("{name}.toml"))
}

/// The default scene on 8 × 4 cells for 0.1 s (200 steps): a run of a fraction of a second.
const SMALL: [&str; 4] = ["--set", "domain.cells=[8,4]", "--set", "time.end=0.1"];

fn cli(args: &[&str]) -> Output {
    Command::new(BIN).args(args).output().expect("the dyncontact binary runs")
}

fn run_into(out: &Path, args: &[&str]) -> Output {
    Command::new(BIN).arg("run").args(args).arg("--out").arg(out).output().expect("run")
}

fn err(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn summary_status(out: &Path) -> Option<String> {
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).ok()?).ok()?;
    v["status"].as_str().map(str::to_string)
}

fn summary(out: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).expect("summary.json")).expect("json")
}

/// Every file below `dir` with its bytes (for "nothing changed").
fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    crate::common::files_below(dir, "run.lock").into_iter().map(|(p, b)| (dir.join(p), b)).collect()
}

/// The rows of history.csv as their step numbers; panics on a row that is not whole.
fn history_steps(out: &Path) -> Vec<usize> {
    let text = std::fs::read_to_string(out.join("history.csv")).expect("history.csv");
    let mut lines = text.lines();
    let width = lines.next().expect("header").split(',').count();
    lines
        .map(|l| {
            assert_eq!(l.split(',').count(), width, "a history.csv row is not whole: {l:?}");
            l.split(',').next().and_then(|s| s.parse().ok()).expect("a step number")
        })
        .collect()
}

/// Wait until `file` has more than `lines` lines (a run under way), at most 60 s.
fn wait_for_lines(child: &mut Child, file: &Path, lines: usize) {
    let start = Instant::now();
    loop {
        if std::fs::read_to_string(file).is_ok_and(|t| t.lines().count() > lines) {
            return;
        }
        assert!(child.try_wait().expect("try_wait").is_none(), "the run ended before it could be interrupted");
        assert!(start.elapsed() < Duration::from_secs(60), "{} did not grow", file.display());
        std::thread::sleep(Duration::from_millis(5));
    }
}

fn signal(child: &Child, sig: &str) {
    let st = Command::new("kill").args(["-s", sig, &child.id().to_string()]).status().expect("kill");
    assert!(st.success());
}

// ---- 1. nothing a user writes runs as code ----------------------------------------------

/// (issue 22, defect 1) A sweep name carrying Python for the Snakefile is refused before any
/// file is written (exit 1, the message names `name`), and nothing runs.
#[test]
fn a_sweep_name_with_code_is_refused_before_any_file() {
    let dir = tmp("sweep_name_code");
    let sweep = dir.join("evil.toml");
    std::fs::write(&sweep, "name = \"x\\nimport os; os.system('touch PWNED')\\n#\"\nbase = \"default\"\n[[axis]]\nkey = \"time.end\"\nvalues = [0.1]\n").expect("write");
    let out = dir.join("out");
    let o = cli(&["sweep", sweep.to_str().expect("path"), "--plan-only", "--out", out.to_str().expect("path")]);
    assert_eq!(o.status.code(), Some(1), "{}", err(&o));
    assert!(err(&o).contains("name: must be 1 to 100 letters"), "{}", err(&o));
    assert!(!out.exists(), "a folder was written for a refused sweep");
    assert!(!dir.join("PWNED").exists() && !Path::new("PWNED").exists());
}

/// (issue 22, defect 1) A scene name with a newline (it names the output folder) is refused;
/// no folder with a newline in its name appears.
#[test]
fn a_scene_name_with_a_newline_is_refused() {
    let dir = tmp("scene_name_newline");
    let o =
        Command::new(BIN).current_dir(&dir).args(["run", "--set", "name=\"a\\nb\""]).args(SMALL).output().expect("run");
    assert_eq!(o.status.code(), Some(1), "{}", err(&o));
    assert!(err(&o).contains("name: must be"), "{}", err(&o));
    assert!(!dir.join("out").exists(), "an output folder was made");
}

/// (issue 22, defect 1) The binary's path reaches config.yaml as a JSON string that decodes to
/// the path exactly, and the Snakefile quotes it for the shell (`:q`) instead of pasting it —
/// here a copy of the binary in a folder named with quotes, `$(…)`, a backtick and spaces.
#[test]
fn a_hostile_binary_path_is_quoted_in_generated_files() {
    let dir = tmp("binary_path");
    let odd = dir.join("we\"ird $(touch PWNED) `id` dir");
    std::fs::create_dir_all(&odd).expect("odd dir");
    let bin = odd.join("dyncontact");
    // a hard link, not a copy: a copy's write descriptor, inherited by a child that another
    // test thread is starting, makes running it fail with "Text file busy" until that child
    // executes; a link never opens the file for writing (a copy only where linking fails, and
    // then its run is retried while busy)
    if std::fs::hard_link(BIN, &bin).is_err() {
        std::fs::copy(BIN, &bin).expect("copy the binary");
    }
    let out = dir.join("sweep");
    let sweep = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fixtures/sweeps/six_points.toml");
    let run = || Command::new(&bin).arg("sweep").arg(&sweep).arg("--plan-only").arg("--out").arg(&out).output();
    const ETXTBSY: i32 = 26;
    let mut o = run();
    for _ in 0..50 {
        if !matches!(&o, Err(e) if e.raw_os_error() == Some(ETXTBSY)) {
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
        o = run();
    }
    let o = o.expect("sweep");
    assert!(o.status.success(), "{}", err(&o));
    let config = std::fs::read_to_string(out.join("config.yaml")).expect("config.yaml");
    let line = config.lines().find_map(|l| l.strip_prefix("dyncontact: ")).expect("the binary's line");
    let decoded: String = serde_json::from_str(line).expect("a JSON string");
    assert_eq!(Path::new(&decoded), bin.as_path());
    let snakefile = std::fs::read_to_string(out.join("Snakefile")).expect("Snakefile");
    assert!(snakefile.contains("{config[dyncontact]:q}") && !snakefile.contains("PWNED"), "{snakefile}");
    assert!(!dir.join("PWNED").exists());
}

// ---- 2. resume proves that its files belong together ------------------------------------

/// (issue 22, defect 2) A fresh run removes an earlier run's checkpoint: after a completed run
/// with checkpoints and a second run into the same folder that fails at step 1, `--resume`
/// finds nothing to resume (exit 4) instead of appending the first run's steps to the second's.
#[test]
fn a_fresh_run_removes_the_old_checkpoint() {
    let dir = tmp("stale_checkpoint");
    let out = dir.join("out");
    let o = run_into(&out, &[&["--checkpoint-every", "50"][..], &SMALL[..]].concat());
    assert!(o.status.success(), "{}", err(&o));
    assert!(out.join("checkpoint.json").exists());
    let failing = Command::new(BIN)
        .arg("run")
        .arg(fixture("impact_friction"))
        .args(["--set", "solver.max_newton_iterations=1", "--out"])
        .arg(&out)
        .output()
        .expect("run");
    assert_eq!(failing.status.code(), Some(2), "{}", err(&failing));
    assert!(!out.join("checkpoint.json").exists(), "the first run's checkpoint survived the second run");
    let before = snapshot(&out);
    let o = cli(&[&["run", "--resume", out.to_str().expect("path")][..], &SMALL[..]].concat());
    assert_eq!(o.status.code(), Some(4), "{}", err(&o));
    assert!(err(&o).contains("checkpoint.json") && err(&o).contains("nothing to resume"), "{}", err(&o));
    assert_eq!(snapshot(&out), before, "a refused resume changed the folder");
}

/// (issue 22, defect 2) A checkpoint whose step was edited is refused by its checksum (exit 4),
/// and the folder is left as it was.
#[test]
fn an_edited_checkpoint_is_refused() {
    let dir = tmp("edited_checkpoint");
    let out = dir.join("out");
    let o = run_into(&out, &[&["--stop-after", "100"][..], &SMALL[..]].concat());
    assert_eq!(o.status.code(), Some(130), "{}", err(&o));
    let cp = std::fs::read_to_string(out.join("checkpoint.json")).expect("checkpoint");
    assert!(cp.contains("\"step\":100"));
    std::fs::write(out.join("checkpoint.json"), cp.replace("\"step\":100", "\"step\":40")).expect("edit");
    let before = snapshot(&out);
    let o = cli(&[&["run", "--resume", out.to_str().expect("path")][..], &SMALL[..]].concat());
    assert_eq!(o.status.code(), Some(4), "{}", err(&o));
    assert!(err(&o).contains("checksum"), "{}", err(&o));
    assert_eq!(snapshot(&out), before);
}

/// (issue 22, defect 2) A checkpoint from another folder is refused: first because it belongs
/// to another run (its run id is not summary.json's); with that run's summary.json copied too,
/// because history.csv does not reach its step (the rows are missing) — never resumed into a
/// history with a gap.
#[test]
fn a_foreign_checkpoint_is_refused() {
    let dir = tmp("foreign_checkpoint");
    let (a, b) = (dir.join("a"), dir.join("b"));
    assert_eq!(run_into(&a, &[&["--stop-after", "60"][..], &SMALL[..]].concat()).status.code(), Some(130));
    assert_eq!(run_into(&b, &[&["--stop-after", "150"][..], &SMALL[..]].concat()).status.code(), Some(130));
    std::fs::copy(b.join("checkpoint.json"), a.join("checkpoint.json")).expect("copy");
    let resume = || cli(&[&["run", "--resume", a.to_str().expect("path")][..], &SMALL[..]].concat());
    let o = resume();
    assert_eq!(o.status.code(), Some(4), "{}", err(&o));
    assert!(err(&o).contains("belongs to another run"), "{}", err(&o));
    std::fs::copy(b.join("summary.json"), a.join("summary.json")).expect("copy");
    let o = resume();
    assert_eq!(o.status.code(), Some(4), "{}", err(&o));
    assert!(err(&o).contains("history.csv") && err(&o).contains("0..60 only"), "{}", err(&o));
    assert_eq!(history_steps(&a), (0..=60).collect::<Vec<_>>());
}

// ---- 3. every input fingerprinted ----------------------------------------------------------

/// A copy of the Gmsh fixture scene and its mesh in `dir` (so the mesh can be edited).
fn gmsh_copy(dir: &Path) -> (PathBuf, PathBuf) {
    let scene = std::fs::read_to_string(fixture("gmsh_square")).expect("scene");
    let file = scene
        .lines()
        .find_map(|l| l.trim().strip_prefix("file = \""))
        .and_then(|r| r.split('"').next())
        .expect("file")
        .to_string();
    let mesh = fixture("gmsh_square").parent().expect("dir").join(&file);
    std::fs::copy(&mesh, dir.join("mesh.msh")).expect("copy mesh");
    let scene = scene.replace(&file, "mesh.msh");
    std::fs::write(dir.join("scene.toml"), scene).expect("scene");
    (dir.join("scene.toml"), dir.join("mesh.msh"))
}

/// Move the first node that is not at a corner by 1e-9 in x: a change no scene text shows.
fn nudge_a_node(mesh: &Path) {
    let text = std::fs::read_to_string(mesh).expect("mesh");
    let mut out = Vec::new();
    let mut in_nodes = false;
    let mut done = false;
    for l in text.lines() {
        let mut line = l.to_string();
        if l.trim() == "$Nodes" {
            in_nodes = true;
        } else if l.trim() == "$EndNodes" {
            in_nodes = false;
        } else if in_nodes && !done {
            let f: Vec<&str> = l.split_whitespace().collect();
            if (f.len() == 3 || f.len() == 4)
                && let Ok(x) = f[f.len() - 3].parse::<f64>()
                && x > 0.0
                && x < 1.0
            {
                let mut g: Vec<String> = f.iter().map(|s| s.to_string()).collect();
                let i = g.len() - 3;
                g[i] = format!("{}", x + 1e-9);
                line = g.join(" ");
                done = true;
            }
        }
        out.push(line);
    }
    assert!(done, "no interior node to move");
    std::fs::write(mesh, out.join("\n") + "\n").expect("write mesh");
}

/// (issue 22, defect 3) After one node of the Gmsh mesh moves by 1e-9, `--resume` refuses the
/// checkpoint (its inputs are not these), exit 4 — it would have mixed two meshes.
#[test]
fn resume_refuses_a_changed_mesh() {
    let dir = tmp("changed_mesh");
    let (scene, mesh) = gmsh_copy(&dir);
    let out = dir.join("out");
    let o =
        Command::new(BIN).arg("run").arg(&scene).args(["--stop-after", "12", "--out"]).arg(&out).output().expect("run");
    assert_eq!(o.status.code(), Some(130), "{}", err(&o));
    nudge_a_node(&mesh);
    let o = Command::new(BIN).arg("run").arg(&scene).arg("--resume").arg(&out).output().expect("resume");
    assert_eq!(o.status.code(), Some(4), "{}", err(&o));
    assert!(err(&o).contains("other inputs"), "{}", err(&o));
}

/// (issue 22, defect 3) A sweep on that mesh: after the node moves, `sweep collect` reports its
/// completed points as corrupt (their inputs changed; exit 4) and the sweep runs them again
/// instead of reporting the old figures as completed.
#[test]
fn a_sweep_reruns_points_whose_mesh_changed() {
    let dir = tmp("sweep_changed_mesh");
    let (_, mesh) = gmsh_copy(&dir);
    let sweep = dir.join("sweep.toml");
    std::fs::write(
        &sweep,
        "name = \"mesh-sweep\"\nbase = \"scene.toml\"\n[[axis]]\nkey = \"time.end\"\nvalues = [0.01, 0.02]\n",
    )
    .expect("write");
    let out = dir.join("out");
    let args = ["sweep", sweep.to_str().expect("path"), "--jobs", "1", "--out", out.to_str().expect("path")];
    let o = cli(&args);
    assert!(o.status.success(), "{}", err(&o));
    assert!(
        String::from_utf8_lossy(&o.stdout).contains("2 points: 2 completed"),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    let first = std::fs::read_to_string(out.join("points/p000/summary.json")).expect("summary");
    nudge_a_node(&mesh);
    let o = cli(&["sweep", "collect", out.to_str().expect("path")]);
    assert_eq!(o.status.code(), Some(4), "{}", err(&o));
    let csv = std::fs::read_to_string(out.join("sweep.csv")).expect("sweep.csv");
    assert_eq!(csv.matches(",corrupt,").count(), 2, "{csv}");
    assert!(csv.contains("inputs changed"), "{csv}");
    let o = cli(&args);
    assert!(o.status.success(), "{}", err(&o));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("(0 already completed)") && stdout.contains("2 points: 2 completed"), "{stdout}");
    assert_ne!(
        std::fs::read_to_string(out.join("points/p000/summary.json")).expect("summary"),
        first,
        "the point did not run again"
    );
}

// ---- 4. a run owns its folder ---------------------------------------------------------------

/// (issue 22, defect 4) A rerun into a completed folder, killed with SIGKILL mid-run, leaves a
/// summary.json that says `running` (never the earlier `completed`) beside a history.csv of the
/// new run's steps only, whole rows, 0, 1, 2, … without a gap.
#[test]
fn a_killed_rerun_never_reads_completed() {
    let dir = tmp("killed_rerun");
    let out = dir.join("out");
    assert!(run_into(&out, &SMALL).status.success());
    assert_eq!(summary(&out)["status"], "completed");
    let mut child = Command::new(BIN).args(["run", "--set", "time.end=5.0", "--out"]).arg(&out).spawn().expect("spawn");
    // the new run has taken the folder (its summary says so) and written 250 rows (a header and
    // more than 250 lines): more than the earlier run's history.csv has (201), so the file waited
    // on is the new run's; the kill may land right after the 250th row
    let start = Instant::now();
    while summary_status(&out).as_deref() != Some("running") {
        assert!(child.try_wait().expect("try_wait").is_none() && start.elapsed() < Duration::from_secs(60));
        std::thread::sleep(Duration::from_millis(2));
    }
    wait_for_lines(&mut child, &out.join("history.csv"), 250);
    child.kill().expect("SIGKILL");
    let _ = child.wait();
    let s = summary(&out);
    assert_eq!(s["status"], "running", "a killed run's summary must not say how an earlier run ended");
    let steps = history_steps(&out);
    assert!(
        steps.len() >= 250 && steps.iter().enumerate().all(|(i, s)| i == *s),
        "history.csv is not the new run's steps 0, 1, …"
    );
}

/// (issue 22, defect 4) A run that cannot start changes nothing in a folder holding an earlier
/// run: a scene naming a side the mesh lacks (exit 1), and a folder with a file that is not a
/// run's (exit 4, the file named) — every file byte for byte as before.
#[test]
fn a_run_that_cannot_start_changes_nothing() {
    let dir = tmp("cannot_start");
    let out = dir.join("out");
    assert!(run_into(&out, &SMALL).status.success());
    let before = snapshot(&out);
    let o = run_into(&out, &[&SMALL[..], &["--set", "boundary.contact=[\"nowhere\"]"][..]].concat());
    assert_eq!(o.status.code(), Some(1), "{}", err(&o));
    assert_eq!(snapshot(&out), before, "a refused scene changed the folder");
    std::fs::write(out.join("notes.txt"), "mine").expect("write");
    let before = snapshot(&out);
    let o = run_into(&out, &SMALL);
    assert_eq!(o.status.code(), Some(4), "{}", err(&o));
    assert!(err(&o).contains("notes.txt") && err(&o).contains("not a dyncontact run's"), "{}", err(&o));
    assert_eq!(snapshot(&out), before, "a refused folder was changed");
}

/// (issue 22, defect 4) A 3-D run into a folder of a 2-D run with a checkpoint, a trajectory and
/// 2-D charts replaces all of it: the folder then holds exactly what a fresh 3-D run writes
/// (its own checkpoint.json, no trajectory.f64, the 3-D charts only, its frames only).
#[test]
fn a_3d_run_replaces_a_2d_folder_entirely() {
    let dir = tmp("replace_2d");
    let (mixed, fresh) = (dir.join("mixed"), dir.join("fresh"));
    let o =
        run_into(&mixed, &[&["--checkpoint-every", "50", "--set", "output.trajectory=true"][..], &SMALL[..]].concat());
    assert!(o.status.success(), "{}", err(&o));
    assert!(
        mixed.join("checkpoint.json").exists()
            && mixed.join("trajectory.f64").exists()
            && mixed.join("plots/deformed.svg").exists()
    );
    let cantilever = fixture("cantilever3d");
    let three_d = ["run", cantilever.to_str().expect("path"), "--set", "time.end=0.02", "--out"];
    for out in [&mixed, &fresh] {
        let o = Command::new(BIN).args(three_d).arg(out).output().expect("run");
        assert!(o.status.success(), "{}", err(&o));
    }
    let names = |d: &Path| -> Vec<PathBuf> {
        snapshot(d).into_iter().map(|(p, _)| p.strip_prefix(d).expect("below").to_path_buf()).collect()
    };
    assert_eq!(names(&mixed), names(&fresh), "the 2-D run's files are still there");
    assert_eq!(
        std::fs::read(mixed.join("history.csv")).expect("a"),
        std::fs::read(fresh.join("history.csv")).expect("b")
    );
}

// ---- 5. sweep collect checks every point ---------------------------------------------------

/// (issue 22, defect 5) `sweep collect` checks each point's files: a truncated history.csv, a
/// NaN in a row, a missing history.csv, a summary.json that is not JSON and an unknown status
/// each make that point `corrupt` with its reason and no figures, and collect exits 4; the
/// untouched point stays completed.
#[test]
fn collect_marks_corrupt_points_and_exits_4() {
    let dir = tmp("corrupt_points");
    let out = dir.join("out");
    let sweep = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fixtures/sweeps/six_points.toml");
    let o = cli(&["sweep", sweep.to_str().expect("path"), "--jobs", "2", "--out", out.to_str().expect("path")]);
    assert!(o.status.success(), "{}", err(&o));
    let p = |id: &str, f: &str| out.join("points").join(id).join(f);
    let h = std::fs::read_to_string(p("p000", "history.csv")).expect("history");
    let keep: Vec<&str> = h.lines().take(h.lines().count() - 50).collect();
    std::fs::write(p("p000", "history.csv"), keep.join("\n") + "\n").expect("truncate");
    let h = std::fs::read_to_string(p("p001", "history.csv")).expect("history");
    let mut lines: Vec<String> = h.lines().map(str::to_string).collect();
    let fields: Vec<&str> = lines[10].split(',').collect();
    lines[10] = std::iter::once(fields[0])
        .chain(std::iter::once(fields[1]))
        .chain(std::iter::once("NaN"))
        .chain(fields[3..].iter().copied())
        .collect::<Vec<_>>()
        .join(",");
    std::fs::write(p("p001", "history.csv"), lines.join("\n") + "\n").expect("nan");
    std::fs::remove_file(p("p002", "history.csv")).expect("remove");
    std::fs::write(p("p003", "summary.json"), "{ not json").expect("garbage");
    let s = std::fs::read_to_string(p("p004", "summary.json")).expect("summary");
    std::fs::write(p("p004", "summary.json"), s.replace("\"completed\"", "\"weird\"")).expect("status");
    let o = cli(&["sweep", "collect", out.to_str().expect("path")]);
    assert_eq!(o.status.code(), Some(4), "{}", err(&o));
    let csv = std::fs::read_to_string(out.join("sweep.csv")).expect("sweep.csv");
    let rows: Vec<&str> = csv.lines().skip(1).collect();
    for (row, why) in rows.iter().zip([
        "rows of steps",
        "not a finite number",
        "history.csv is missing",
        "not readable JSON",
        "unknown status",
    ]) {
        assert!(row.contains(",corrupt,") && row.contains(why), "{row}");
        assert!(!row.contains(",completed,"));
    }
    assert!(rows[5].contains(",completed,"), "{}", rows[5]);
}

// ---- 6. locks, markers, jobs -------------------------------------------------------------

/// (issue 22, defect 6) A run folder and a sweep folder are written by one process at a time: while
/// a lock is held, `run` into the folder and `sweep collect` of it are refused (exit 4).
#[test]
fn locked_folders_are_refused() {
    let dir = tmp("locks");
    let out = dir.join("run");
    let _held = dyncontact::output::folder::lock_run(&out).expect("lock");
    let o = run_into(&out, &SMALL);
    assert_eq!(o.status.code(), Some(4), "{}", err(&o));
    assert!(err(&o).contains("another dyncontact process"), "{}", err(&o));
    let sweep = dir.join("sweep");
    let _held = dyncontact::sweep::lock(&sweep).expect("lock");
    let o = cli(&["sweep", "collect", sweep.to_str().expect("path")]);
    assert_eq!(o.status.code(), Some(4), "{}", err(&o));
}

/// (issue 22, defect 6) `--jobs` above the number of cores is refused without `--oversubscribe`
/// (it ran 100 points at once); with the flag the plan is made.
#[test]
fn jobs_above_the_cores_need_a_flag() {
    let dir = tmp("jobs");
    let sweep = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fixtures/sweeps/six_points.toml");
    let out = dir.join("out");
    let args =
        ["sweep", sweep.to_str().expect("path"), "--jobs", "1000", "--plan-only", "--out", out.to_str().expect("path")];
    let o = cli(&args);
    assert_eq!(o.status.code(), Some(1), "{}", err(&o));
    assert!(err(&o).contains("--jobs") && err(&o).contains("--oversubscribe"), "{}", err(&o));
    assert!(cli(&[&args[..], &["--oversubscribe"][..]].concat()).status.success());
}

/// (issue 22, defect 6; minor: SIGTERM) A sweep point stopped by SIGTERM exits 143 with its
/// summary `interrupted` and a checkpoint, and gets no marker `points/<id>.done` — the output
/// of the Snakefile's rule — so Snakemake runs it again; run again, it completes and gets it.
#[test]
fn an_interrupted_point_has_no_marker() {
    let dir = tmp("marker");
    let sweep = dir.join("long.toml");
    std::fs::write(&sweep, "name = \"long\"\nbase = \"default\"\n[[axis]]\nkey = \"time.end\"\nvalues = [5.0]\n")
        .expect("write");
    let out = dir.join("out");
    let o = cli(&["sweep", sweep.to_str().expect("path"), "--plan-only", "--out", out.to_str().expect("path")]);
    assert!(o.status.success(), "{}", err(&o));
    let snakefile = std::fs::read_to_string(out.join("Snakefile")).expect("Snakefile");
    assert!(
        snakefile.contains("\"points/{point}.done\"") && snakefile.contains("sweep point points/{wildcards.point}"),
        "{snakefile}"
    );
    let pd = out.join("points/p000");
    let mut child = Command::new(BIN).args(["sweep", "point"]).arg(&pd).spawn().expect("spawn");
    wait_for_lines(&mut child, &pd.join("history.csv"), 50);
    signal(&child, "TERM");
    let st = child.wait().expect("wait");
    assert_eq!(st.code(), Some(143));
    assert_eq!(summary(&pd)["status"], "interrupted");
    assert!(pd.join("checkpoint.json").exists());
    assert!(!out.join("points/p000.done").exists(), "an interrupted point has a marker");
    std::fs::write(
        pd.join("scene.toml"),
        std::fs::read_to_string(pd.join("scene.toml")).expect("scene").replace("end = 5.0", "end = 0.05"),
    )
    .expect("shorter");
    let o = cli(&["sweep", "point", pd.to_str().expect("path")]);
    assert!(o.status.success(), "{}", err(&o));
    assert!(out.join("points/p000.done").exists());
}

// ---- 7. a full disk -------------------------------------------------------------------------

/// Mount a tmpfs with `options` (its size) at `mnt`, created first; false where that is not
/// allowed (not root).
fn mount_tmpfs(mnt: &Path, options: &str) -> bool {
    std::fs::create_dir_all(mnt).expect("mnt");
    Command::new("mount")
        .args(["-t", "tmpfs", "-o", options, "tmpfs"])
        .arg(mnt)
        .output()
        .is_ok_and(|o| o.status.success())
}

/// (issue 22, defect 7) A disk that fills during a run (a 64 MiB tmpfs filled by another file
/// once the run is under way) ends it with exit 3 (an output could not be written, not "bad
/// input"): history.csv holds whole rows only, no temporary file is left, and summary.json says
/// `failed` with failure_kind `output`. Needs root to mount the tmpfs (CI runs as root); elsewhere
/// it says so and checks nothing.
#[test]
fn a_full_disk_fails_cleanly() {
    let dir = tmp("full_disk");
    let mnt = dir.join("mnt");
    if !mount_tmpfs(&mnt, "size=64m") {
        println!("skipped: mounting a tmpfs needs root");
        return;
    }
    let out = mnt.join("out");
    // 10,000 steps, 12 frames: about 7 MB of outputs, which fit until the filler takes the rest
    let mut child = Command::new(BIN)
        .args(["run", "--set", "time.end=5.0", "--set", "output.every=1000", "--out"])
        .arg(&out)
        .spawn()
        .expect("spawn");
    wait_for_lines(&mut child, &out.join("history.csv"), 20);
    // fill the file system
    {
        use std::io::Write;
        let mut f = std::fs::File::create(mnt.join("filler")).expect("filler");
        let block = vec![0u8; 1 << 20];
        while f.write_all(&block).is_ok() {}
        let _ = f.flush();
    }
    let st = child.wait().expect("wait");
    let result = std::panic::catch_unwind(|| {
        assert_eq!(st.code(), Some(3), "a full disk is not bad input");
        history_steps(&out);
        let tmp: Vec<_> = snapshot(&out).into_iter().filter(|(p, _)| p.to_string_lossy().ends_with(".tmp")).collect();
        assert!(tmp.is_empty(), "temporaries left: {:?}", tmp.iter().map(|t| &t.0).collect::<Vec<_>>());
        let s = summary(&out);
        assert_eq!((s["status"].as_str(), s["failure_kind"].as_str()), (Some("failed"), Some("output")), "{s}");
    });
    let _ = Command::new("umount").arg(&mnt).status();
    if let Err(p) = result {
        std::panic::resume_unwind(p);
    }
}

/// A disk that fills while the charts are written, after every step: exit 3, and summary.json
/// says `failed` (failure_kind `output`, the chart named), not `completed`. The tmpfs is sized
/// from the same run on a roomy disk: its files but the charts (4 KiB pages, and 4 more for the
/// temporaries of summary.json and checkpoint.json, written by rename; history.csv is appended)
/// plus half of the charts' pages. Needs root (as above).
#[test]
fn a_disk_full_of_charts_is_not_completed() {
    let dir = tmp("full_disk_charts");
    let args = ["--set", "domain.cells=[8,4]", "--set", "time.end=0.25", "--set", "output.every=0"];
    let roomy = dir.join("roomy");
    assert!(run_into(&roomy, &args).status.success());
    let pages = |p: &Path| std::fs::metadata(p).map_or(0, |m| m.len().div_ceil(4096));
    let (mut rest, mut charts) = (0u64, 0u64);
    for (p, _) in snapshot(&roomy) {
        if p.parent().is_some_and(|d| d.ends_with("plots")) {
            charts += pages(&p);
        } else {
            rest += pages(&p);
        }
    }
    assert!(charts >= 4, "the charts take {charts} pages");
    let mnt = dir.join("mnt");
    if !mount_tmpfs(&mnt, &format!("size={}k", 4 * (rest + 4 + charts / 2))) {
        println!("skipped: mounting a tmpfs needs root");
        return;
    }
    let out = mnt.join("out");
    let o = run_into(&out, &args);
    let result = std::panic::catch_unwind(|| {
        assert_eq!(o.status.code(), Some(3), "{}", err(&o));
        assert!(err(&o).contains("plots/"), "the disk filled before the charts: {}", err(&o));
        let s = summary(&out);
        assert_eq!((s["status"].as_str(), s["failure_kind"].as_str()), (Some("failed"), Some("output")), "{s}");
        assert!(s["failure"].as_str().is_some_and(|f| f.contains("every step completed")), "{s}");
    });
    let _ = Command::new("umount").arg(&mnt).status();
    if let Err(p) = result {
        std::panic::resume_unwind(p);
    }
}

// ---- 8. physics that breaks is not "completed" ------------------------------------------------

/// (issue 22, defect 8) (E.1) is a run-time guard of a midpoint run: with a limit that only an
/// exact balance meets (1e-300 of the energy scale) the run fails at the first step with a
/// round-off residual, naming the balance (exit 2), and summary.json says `failed`; with
/// `energy_residual_action = "warn"` it completes and counts exactly the steps of history.csv
/// whose residual exceeds the limit.
#[test]
fn the_energy_balance_guards_a_midpoint_run() {
    let dir = tmp("energy_guard");
    let fail = dir.join("fail");
    let o = run_into(&fail, &[&SMALL[..], &["--set", "solver.energy_residual_limit=1e-300"][..]].concat());
    assert_eq!(o.status.code(), Some(2), "{}", err(&o));
    assert!(err(&o).contains("energy balance (E.1)") && err(&o).contains("energy_residual_limit"), "{}", err(&o));
    assert_eq!(summary(&fail)["status"], "failed");
    let warn = dir.join("warn");
    let o = run_into(
        &warn,
        &[
            &SMALL[..],
            &["--set", "solver.energy_residual_limit=1e-300", "--set", "solver.energy_residual_action=\"warn\""][..],
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", err(&o));
    let s = summary(&warn);
    let text = std::fs::read_to_string(warn.join("history.csv")).expect("history");
    let cols: Vec<&str> = text.lines().next().expect("header").split(',').collect();
    let (r, e) = (
        cols.iter().position(|c| *c == "energy_residual").expect("col"),
        cols.iter().position(|c| *c == "energy_scale").expect("col"),
    );
    let over = text
        .lines()
        .skip(2)
        .filter(|l| {
            let f: Vec<f64> = l.split(',').map(|v| v.parse().expect("number")).collect();
            f[r].abs() / f[e] > 1e-300
        })
        .count();
    println!("{over} of 200 steps have a nonzero (E.1) residual");
    assert!(over > 100, "the residuals are round-off, so most steps exceed 1e-300");
    assert_eq!(s["energy_guard_exceeded_steps"].as_u64(), Some(over as u64));
    assert!(s["warnings"].to_string().contains("energy balance (E.1)"));
}

// ---- 10. the minor ones ------------------------------------------------------------------------

/// (issue 22, minor) A wrong command line exits 64, not 2 (the solver's code); --version 0.
#[test]
fn usage_errors_exit_64() {
    assert_eq!(cli(&["run", "--bogus"]).status.code(), Some(64));
    assert_eq!(cli(&["--version"]).status.code(), Some(0));
}

/// (issue 22, minor) SIGINT during the setup of a large scene (academic3d builds its contact
/// operator for ~1 s) is not lost: the run stops before its first step, exit 130, summary
/// `interrupted` at step 0 with a checkpoint.
#[test]
fn sigint_during_setup_stops_before_the_first_step() {
    let dir = tmp("sigint_setup");
    let out = dir.join("out");
    let mut child =
        Command::new(BIN).arg("run").arg(fixture("academic3d")).arg("--out").arg(&out).spawn().expect("spawn");
    let start = Instant::now();
    // the lock is taken after the problem is built, before the solver's setup
    while !out.join("run.lock").exists() {
        assert!(child.try_wait().expect("try_wait").is_none() && start.elapsed() < Duration::from_secs(60));
        std::thread::sleep(Duration::from_millis(2));
    }
    signal(&child, "INT");
    assert_eq!(child.wait().expect("wait").code(), Some(130));
    let s = summary(&out);
    assert_eq!((s["status"].as_str(), s["steps_completed"].as_u64()), (Some("interrupted"), Some(0)), "{s}");
    assert!(out.join("checkpoint.json").exists());
}

/// (issue 22, minor) Messages that said too little: an infinite size ("must be a finite
/// number > 0, got inf"), a multi-line --set value (refused instead of keeping its first line),
/// a junk mesh file (refused at its first line, without reading the rest), and the output
/// volume (`check` states it; `run` refuses 1e8 frames, naming output.every).
#[test]
fn minor_messages_say_what_is_wrong() {
    let o = cli(&["check", fixture("academic").to_str().expect("path"), "--set", "domain.size=[inf, 1.0]"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(err(&o).contains("domain.size[0]: must be a finite number > 0, got inf"), "{}", err(&o));
    let o = cli(&["check", fixture("academic").to_str().expect("path"), "--set", "time.end=0.1\nname=\"x\""]);
    assert_eq!(o.status.code(), Some(1));
    assert!(err(&o).contains("line break"), "{}", err(&o));
    let dir = tmp("minor");
    let junk = dir.join("junk.msh");
    std::fs::write(&junk, vec![b'x'; 50 << 20]).expect("junk");
    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        std::fs::read_to_string(fixture("gmsh_square"))
            .expect("scene")
            .lines()
            .map(|l| if l.trim_start().starts_with("file = ") { "file = \"junk.msh\"" } else { l })
            .collect::<Vec<_>>()
            .join("\n"),
    )
    .expect("scene");
    let t = Instant::now();
    let o = cli(&["check", scene.to_str().expect("path")]);
    assert_eq!(o.status.code(), Some(1));
    assert!(err(&o).contains("line 1: a Gmsh mesh starts with $MeshFormat"), "{}", err(&o));
    println!("a 50 MiB junk mesh refused in {:.3} s", t.elapsed().as_secs_f64());
    let o = cli(&["check", fixture("academic").to_str().expect("path")]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("outputs (est.)"));
    let o = run_into(&dir.join("huge"), &["--set", "time.step=1e-8", "--set", "output.every=1"]);
    assert_eq!(o.status.code(), Some(1), "{}", err(&o));
    assert!(err(&o).contains("output.every") && err(&o).contains("TiB"), "{}", err(&o));
    assert!(!dir.join("huge").exists(), "a refused run made its folder");
}

/// A checkpoint that does not fit the problem it is restored into is a folder whose files do not
/// belong together (failure_kind `folder`, exit 4), not an output fault.
#[test]
fn a_checkpoint_that_does_not_fit_is_a_folder_fault() {
    use dyncontact::error::{Error, FailureKind, exit};
    let scene = dyncontact::scene::Scene::from_file(&fixture("sliding_block")).expect("scene");
    let p = dyncontact::problem::Problem::from_scene(&scene, &fixture("sliding_block").with_file_name(""))
        .expect("problem");
    let mut sim = dyncontact::simulation::Simulation::new(&p).expect("setup");
    let mut wrong = sim.state.clone();
    wrong.u.push(0.0);
    let e = sim.restore(wrong).expect_err("a state of other sizes is refused");
    assert!(matches!(e, Error::Checkpoint(_)), "{e:?}");
    assert_eq!((e.kind(), e.exit_code()), (FailureKind::Folder, exit::FOLDER), "{e}");
    let mut late = sim.state.clone();
    late.n = p.steps + 1;
    let e = sim.restore(late).expect_err("a step beyond the scene's end is refused");
    assert!(e.to_string().contains("beyond the scene's"), "{e}");
}

/// A failed factorization keeps faer's error as a value (not only its text), says it in the
/// message it always gave, and exits 2 with failure_kind `linear_algebra`.
#[test]
fn a_failed_factorization_keeps_faers_error() {
    use dyncontact::error::{Error, FailureKind, LinearAlgebraFailure, exit};
    use faer::linalg::cholesky::llt::factor::LltError as Pivot;
    use faer::sparse::linalg::LltError;
    let a = dyncontact::linalg::from_triplets(1, 1, &[(0, 0, -1.0)]).expect("a 1 × 1 matrix");
    let e = dyncontact::linalg::Cholesky::new(&a, "M", None).err().expect("−1 is not positive definite");
    let Error::LinearAlgebra(LinearAlgebraFailure::Cholesky { matrix, cause }) = &e else { panic!("{e:?}") };
    assert_eq!(matrix, "M");
    assert!(matches!(cause, LltError::Numeric(Pivot::NonPositivePivot { .. })), "{cause:?}");
    assert_eq!(
        e.to_string(),
        format!(
            "linear algebra: Cholesky factorization of M failed ({cause:?}): the matrix is not positive definite \
             (check density > 0, the material constants and that the body is held or has mass)"
        )
    );
    assert_eq!((e.kind(), e.exit_code()), (FailureKind::LinearAlgebra, exit::SOLVER));
}

/// Each failure kind is stored under the name the README lists, and a defect of dyncontact (a
/// panic) is its own kind with its own exit code (70), not an output fault.
#[test]
fn failure_kinds_keep_their_names_and_a_defect_exits_70() {
    use dyncontact::error::{Error, FailureKind, exit};
    for (kind, name) in [
        (FailureKind::NonFinite, "non_finite"),
        (FailureKind::Solver, "solver"),
        (FailureKind::LinearAlgebra, "linear_algebra"),
        (FailureKind::Input, "input"),
        (FailureKind::Interrupted, "interrupted"),
        (FailureKind::Folder, "folder"),
        (FailureKind::Output, "output"),
        (FailureKind::Internal, "internal"),
    ] {
        assert_eq!(serde_json::to_value(kind).expect("json"), serde_json::json!(name));
        assert_eq!(serde_json::from_value::<FailureKind>(serde_json::json!(name)).expect("back"), kind);
    }
    let e = Error::Internal("the frame writer thread panicked".into());
    assert_eq!((e.kind(), e.exit_code()), (FailureKind::Internal, exit::INTERNAL));
    assert_eq!(exit::INTERNAL, 70);
    assert_eq!(Error::Study("the penalty study runs on 2-D scenes".into()).exit_code(), exit::INPUT);
}

/// A run that could not start writes its summary.json from the one `Summary` type: it reads back
/// as a `Summary` (failed, its kind, no step, no run details) with exactly the keys it always had.
#[test]
fn a_failed_starts_summary_reads_as_a_summary() {
    use dyncontact::error::FailureKind;
    use dyncontact::failure::RunStatus;
    let out = tmp("failed_start_summary");
    let e = dyncontact::scene::Scene::from_toml("time = [", "broken.toml").expect_err("not TOML");
    dyncontact::run::write_failed_start(&out, "broken", &e).expect("written");
    let text = std::fs::read_to_string(out.join("summary.json")).expect("summary.json");
    let s: dyncontact::output::Summary = serde_json::from_str(&text).expect("a Summary");
    assert_eq!((s.status, s.failure_kind, s.steps_completed), (RunStatus::Failed, Some(FailureKind::Input), 0));
    assert_eq!((s.scene.as_str(), s.failure), ("broken", Some(e.to_string())));
    assert!(s.run.is_none(), "a run that did not start has no run details");
    let v: serde_json::Value = serde_json::from_str(&text).expect("json");
    let mut keys: Vec<&str> = v.as_object().expect("an object").keys().map(String::as_str).collect();
    keys.sort_unstable();
    assert_eq!(keys, ["failure", "failure_kind", "scene", "status", "steps_completed", "version"]);
    assert_eq!((v["status"].as_str(), v["failure_kind"].as_str()), (Some("failed"), Some("input")));
}

/// A run's summary.json reads back as a `Summary` and writes the same JSON again: every key and
/// every value survives the type.
#[test]
fn a_runs_summary_round_trips_through_the_type() {
    let out = tmp("summary_round_trip");
    let o = run_into(&out, &SMALL);
    assert!(o.status.success(), "{}", err(&o));
    let text = std::fs::read_to_string(out.join("summary.json")).expect("summary.json");
    let s: dyncontact::output::Summary = serde_json::from_str(&text).expect("a Summary");
    assert_eq!(s.status, dyncontact::failure::RunStatus::Completed);
    assert!(s.run.as_ref().is_some_and(|d| !d.run_id.is_empty()), "a run that started has its details");
    let again: serde_json::Value = serde_json::from_str(&s.to_json().expect("json")).expect("json");
    assert_eq!(again, summary(&out));
}

/// (issue 24, item 9) Resume's own hint works: a run with `--set` overrides stopped after a
/// step says "continue with --resume DIR", and exactly that — no scene, no `--set` — continues
/// it from DIR/scene.toml (the effective scene) to the same history as an uninterrupted run.
#[test]
fn resume_needs_only_the_run_folder() {
    let dir = tmp("resume_folder_alone");
    let (a, b) = (dir.join("a"), dir.join("b"));
    assert_eq!(run_into(&a, &[&["--stop-after", "50"][..], &SMALL[..]].concat()).status.code(), Some(130));
    let summary = std::fs::read_to_string(a.join("summary.json")).expect("summary");
    assert!(summary.contains(&format!("continue with --resume {}", a.display())), "{summary}");
    // (issue 24, item 5) the summary says where the scene came from and what changed it
    let s: serde_json::Value = serde_json::from_str(&summary).expect("json");
    assert_eq!(s["scene_file"], "<embedded academic scene>");
    let given: Vec<&str> = SMALL.chunks(2).map(|p| p[1]).collect();
    assert_eq!(s["overrides"], serde_json::json!(given), "the --set arguments in order, as typed");
    assert_eq!(s["effective_scene"], "scene.toml");
    assert_eq!(s["version"], env!("CARGO_PKG_VERSION"));
    let o = cli(&["run", "--resume", a.to_str().expect("path")]);
    assert!(o.status.success(), "{}", err(&o));
    assert!(run_into(&b, &SMALL).status.success());
    let h = |d: &Path| std::fs::read(d.join("history.csv")).expect("history");
    assert_eq!(h(&a), h(&b), "the resumed run's history is the uninterrupted one's");
    // the summary's totals are the whole run's: the contact solve's counts continue too
    for key in [
        "newton_iterations_total",
        "fixed_point_iterations_total",
        "contact_factorizations",
        "contact_factor_reuses",
        "contact_pcg_solves",
        "contact_pcg_iterations",
    ] {
        assert_eq!(self::summary(&a)[key], self::summary(&b)[key], "{key}");
    }
}

/// (issue 24, item 9) A later time.end extends a finished run — a plain one, without
/// --checkpoint-every: "run --resume DIR needs nothing else" (its last step is always
/// checkpointed): history.csv, contact.csv, series.pvd and the frames equal a run to the later
/// end, except that an old end off the frame grid keeps its frame (and its contact.csv rows);
/// any other change is refused (exit 4), the folder unchanged.
#[test]
fn a_later_end_extends_a_finished_run() {
    let dir = tmp("resume_extend");
    let (a, b) = (dir.join("a"), dir.join("b"));
    assert!(run_into(&a, &SMALL).status.success());
    assert!(a.join("checkpoint.json").exists(), "a completed run checkpoints its last step");
    let before = snapshot(&a);
    let o = cli(&["run", "--resume", a.to_str().expect("path"), "--set", "time.step=1e-3"]);
    assert_eq!(o.status.code(), Some(4), "{}", err(&o));
    assert!(err(&o).contains("only a later time.end may differ"), "{}", err(&o));
    assert_eq!(snapshot(&a), before, "a refused extension changed the folder");
    let o = cli(&["run", "--resume", a.to_str().expect("path"), "--set", "time.end=0.2"]);
    assert!(o.status.success(), "{}", err(&o));
    let o = run_into(&b, &["--set", "domain.cells=[8,4]", "--set", "time.end=0.2"]);
    assert!(o.status.success(), "{}", err(&o));
    let h = |d: &Path| std::fs::read(d.join("history.csv")).expect("history");
    assert_eq!(h(&a), h(&b), "the extended run's history is that of a run to the later end");
    assert!(std::fs::read_to_string(a.join("scene.toml")).expect("scene.toml").contains("end = 0.2"));
    // the old end (step 200) is a multiple of output.every = 10: every other file is equal too
    for f in ["contact.csv", "series.pvd"] {
        assert_eq!(std::fs::read(a.join(f)).expect("a"), std::fs::read(b.join(f)).expect("b"), "{f}");
    }
    let frames = |d: &Path| {
        let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(d.join("frames"))
            .expect("frames")
            .flatten()
            .map(|e| (e.file_name().to_string_lossy().to_string(), std::fs::read(e.path()).expect("frame")))
            .collect();
        v.sort();
        v
    };
    assert_eq!(frames(&a), frames(&b), "the frames of the extended run");
    // an old end off the frame grid (step 205) keeps its frame: the only difference
    let (c, d) = (dir.join("c"), dir.join("d"));
    assert!(run_into(&c, &["--set", "domain.cells=[8,4]", "--set", "time.end=0.1025"]).status.success());
    let o = cli(&["run", "--resume", c.to_str().expect("path"), "--set", "time.end=0.2"]);
    assert!(o.status.success(), "{}", err(&o));
    assert!(run_into(&d, &["--set", "domain.cells=[8,4]", "--set", "time.end=0.2"]).status.success());
    assert_eq!(h(&c), h(&d));
    let without_205: String = std::fs::read_to_string(c.join("contact.csv"))
        .expect("contact")
        .lines()
        .filter(|l| !l.starts_with("205,"))
        .map(|l| format!("{l}\n"))
        .collect();
    assert_eq!(without_205, std::fs::read_to_string(d.join("contact.csv")).expect("contact"));
    let (fc, fd) = (frames(&c), frames(&d));
    assert_eq!(fc.iter().filter(|f| f.0 != "frame_00205.vtu").cloned().collect::<Vec<_>>(), fd);
    assert_eq!(fc.len(), fd.len() + 1, "the old end's frame is kept");
}

// ---- the audit of 2026-11-27: bad folders, overflowing inputs, the penalty study ----------

/// A run refused for a folder that is not a run's leaves it as it was: no run.lock either (the
/// lock the run took is removed again when it created it).
#[test]
fn a_refused_folder_gets_no_lock_file() {
    let dir = tmp("refused_no_lock");
    let out = dir.join("mine");
    std::fs::create_dir_all(&out).expect("mkdir");
    std::fs::write(out.join("notes.txt"), "mine").expect("write");
    let o = run_into(&out, &SMALL);
    assert_eq!(o.status.code(), Some(4), "{}", err(&o));
    let names: Vec<String> = std::fs::read_dir(&out)
        .expect("read_dir")
        .flatten()
        .map(|e| e.file_name().to_string_lossy().to_string())
        .collect();
    assert_eq!(names, ["notes.txt"], "the refused run left files behind");
}

/// `--out` naming a file, a device or a folder below a file is refused as a folder error
/// (exit 4) that names the path, before anything is built — not an I/O error "File exists".
#[test]
fn an_out_that_is_not_a_folder_is_refused_by_name() {
    let dir = tmp("out_not_folder");
    let file = dir.join("afile");
    std::fs::write(&file, "x").expect("write");
    for (out, says) in [
        (file.clone(), "is not a folder"),
        (PathBuf::from("/dev/null"), "is not a folder"),
        (file.join("sub"), "is a file"),
    ] {
        let o = run_into(&out, &SMALL);
        assert_eq!(o.status.code(), Some(4), "{}: {}", out.display(), err(&o));
        assert!(err(&o).contains(says), "{}: {}", out.display(), err(&o));
    }
    assert_eq!(std::fs::read(&file).expect("read"), b"x", "the file was changed");
}

/// Finite inputs whose energies overflow f64 never reach history.csv as inf or NaN: an initial
/// velocity of 1e300 is refused as input naming `initial.velocity` (exit 1), a body load of
/// 1e308 stops step 1 as a non-finite failure (exit 2, failure_kind non_finite), and every
/// number history.csv holds is finite.
#[test]
fn overflowing_energies_are_named_not_written() {
    let dir = tmp("overflow");
    let (a, b) = (dir.join("a"), dir.join("b"));
    let o = run_into(&a, &[&SMALL[..], &["--set", "initial.velocity=[\"1e300\",\"-1e300\"]"][..]].concat());
    assert_eq!(o.status.code(), Some(1), "{}", err(&o));
    assert!(err(&o).contains("initial.velocity") && err(&o).contains("kinetic energy"), "{}", err(&o));
    let o = run_into(&b, &[&SMALL[..], &["--set", "loads.body=[\"1e308\",\"-1e308\"]"][..]].concat());
    assert_eq!(o.status.code(), Some(2), "{}", err(&o));
    assert_eq!(summary(&b)["failure_kind"], "non_finite", "{}", err(&o));
    let history = std::fs::read_to_string(b.join("history.csv")).expect("history.csv");
    for line in history.lines().skip(1) {
        for v in line.split(',') {
            let x: f64 = v.parse().expect("a number");
            assert!(x.is_finite(), "history.csv holds {v}: {line}");
        }
    }
}

/// `plane` is a 2-D key: a Gmsh scene whose mesh is three-dimensional refuses it (exit 1,
/// naming `domain.plane`), as a box does.
#[test]
fn plane_is_refused_for_a_3d_gmsh_mesh() {
    let scene = fixture("gmsh_block3d");
    let o = cli(&["check", scene.to_str().expect("path"), "--set", "domain.plane=\"strain\""]);
    assert_eq!(o.status.code(), Some(1), "{}", err(&o));
    assert!(err(&o).contains("domain.plane") && err(&o).contains("three-dimensional"), "{}", err(&o));
}

/// `check` of a 2-D scene states its dimension, as of a 3-D one.
#[test]
fn check_states_the_dimension_in_2d() {
    let o = cli(&["check", fixture("academic").to_str().expect("path")]);
    assert!(o.status.success(), "{}", err(&o));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("dimension      : 2 (P1 triangles), plane strain"), "{text}");
}

/// Counts of 0 for --jobs and --checkpoint-every are usage errors (exit 64), not silently 1 or
/// "never".
#[test]
fn zero_jobs_and_checkpoints_are_refused() {
    let scene = fixture("academic");
    let o = cli(&["run", scene.to_str().expect("path"), "--checkpoint-every", "0"]);
    assert_eq!(o.status.code(), Some(64), "{}", err(&o));
    let o = cli(&["study", "penalty", scene.to_str().expect("path"), "--jobs", "0"]);
    assert_eq!(o.status.code(), Some(64), "{}", err(&o));
}

/// The penalty study runs on a scene that uses the penalty method itself (its exact reference
/// drops the scene's own ε), refuses an ε list without two different values (no NaN slope),
/// and its default folder, the scene's run folder's study/, does not stop the next `run`
/// there (a run keeps study/).
#[test]
fn the_penalty_study_takes_penalty_scenes_and_shares_the_run_folder() {
    let dir = tmp("penalty_study");
    let scene = dir.join("pen.toml");
    let text = std::fs::read_to_string(fixture("academic"))
        .expect("academic.toml")
        .replace("cells = [32, 16]", "cells = [8, 4]")
        .replace("end = 1.0", "end = 0.4")
        .replace("enforcement = \"exact\"", "enforcement = \"penalty\"\npenalty = 1.0e-3");
    assert!(text.contains("penalty = 1.0e-3") && text.contains("end = 0.4"), "the edit missed:\n{text}");
    std::fs::write(&scene, &text).expect("write");
    let s = scene.to_str().expect("path");
    for bad in ["1e-3", "1e-3,1e-3"] {
        let o = cli(&["study", "penalty", s, "--eps", bad]);
        assert_eq!(o.status.code(), Some(1), "--eps {bad}: {}", err(&o));
        assert!(err(&o).contains("--eps"), "{}", err(&o));
    }
    let out = dir.join("out");
    let o = run_into(&out, &[s]);
    assert!(o.status.success(), "{}", err(&o));
    let o = cli(&["study", "penalty", s, "--eps", "1e-2,1e-3", "--jobs", "1", "--out", out.to_str().expect("path")]);
    assert!(o.status.success(), "{}", err(&o));
    assert!(!String::from_utf8_lossy(&o.stdout).contains("NaN"), "{}", String::from_utf8_lossy(&o.stdout));
    assert!(out.join("study/penalty.csv").is_file());
    let o = run_into(&out, &[s]);
    assert!(o.status.success(), "a run after the study in its folder: {}", err(&o));
    assert!(out.join("study/penalty.csv").is_file(), "the run removed the study");
}

/// Requirement: `check` refuses a load that is finite at t = 0, at T and at every t_n but not
/// at a time a step samples it: with k = 5e-4 the midpoint step from t_1 = 0.0005 samples
/// f(0.00075), where 1/(t − 0.00075) divides by zero (0.0005 + 0.00025 is 0.00075 in f64).
/// `run` refuses it the same way before writing anything (it stopped at that step, after
/// writing the first); `check` said "valid" before.
#[test]
fn check_refuses_a_load_infinite_at_a_load_time_only() {
    let load = ["--set", "loads.body=[\"0\", \"1/(t-0.00075)\"]"];
    let scene = fixture("academic");
    let o = cli(&[&["check", scene.to_str().expect("path")][..], &SMALL, &load].concat());
    assert_eq!(o.status.code(), Some(1), "{}", String::from_utf8_lossy(&o.stdout));
    assert!(err(&o).contains("loads.body") && err(&o).contains("t = 0.00075"), "{}", err(&o));
    let dir = tmp("load_time");
    let o = run_into(&dir.join("run"), &[&SMALL[..], &load].concat());
    assert_eq!(o.status.code(), Some(1), "{}", err(&o));
    assert!(err(&o).contains("loads.body") && err(&o).contains("t = 0.00075"), "{}", err(&o));
    assert!(!dir.join("run").exists(), "a refused run made its folder");
    // a load that is finite at every load time: `check` says it scanned them
    let o = cli(&[&["check", scene.to_str().expect("path")][..], &SMALL].concat());
    assert_eq!(o.status.code(), Some(0), "{}", err(&o));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(out.contains("finite at each of the 200 times the steps sample them"), "{out}");
}

/// Requirement: a whole number beyond TOML's i64 at a key that takes one is refused with the
/// range named, whether `--set` read it as a float (`1e20`) or, out of TOML's integer range, as
/// a string; a fraction or `007` at such a key keeps serde's plain message (no range problem).
#[test]
fn a_whole_number_beyond_i64_names_the_range() {
    let scene = fixture("academic");
    for value in ["output.every=100000000000000000000", "output.every=1e20", "output.every=-9999999999999999999"] {
        let o = cli(&["check", scene.to_str().expect("path"), "--set", value]);
        assert_eq!(o.status.code(), Some(1), "{value}");
        assert!(err(&o).contains("output.every") && err(&o).contains("to 9223372036854775807"), "{value}: {}", err(&o));
    }
    // a fraction, and digits TOML reads as text for another reason (`007`), are no range problem
    for value in ["output.every=1.5", "output.every=007"] {
        let o = cli(&["check", scene.to_str().expect("path"), "--set", value]);
        assert_eq!(o.status.code(), Some(1));
        assert!(err(&o).contains("expected i64") && !err(&o).contains("to 9223372036854775807"), "{}", err(&o));
    }
}
