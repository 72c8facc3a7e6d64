//! Solver failure, interruption and resume: a run that cannot continue stops with
//! exit code 2 and a message with the step, time, residuals and a suggestion; an interrupted
//! run exits 130; in both cases every file written so far is valid (history.csv complete up to
//! the last good step, series.pvd listing only frames on disk, summary.json saying why it
//! stopped); and a run resumed from its checkpoint equals an uninterrupted run bit for bit.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_dyncontact");

fn tmp(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("tmp dir");
    d
}

fn fixture_text(name: &str) -> String {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fixtures/scenes").join(format!("{name}.toml"));
    std::fs::read_to_string(p).expect("fixture")
}

fn run(args: &[&str], scene: &Path, out: &Path) -> Output {
    Command::new(BIN).arg("run").arg(scene).args(args).arg("--out").arg(out).output().expect("spawn")
}

fn summary(out: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).expect("summary.json")).expect("json")
}

/// The files of a stopped run are consistent: history.csv has t = 0 plus `steps` rows, every
/// frame listed by series.pvd exists and nothing else is in frames/.
fn check_files_valid(out: &Path, steps: usize) {
    let h = std::fs::read_to_string(out.join("history.csv")).expect("history");
    let rows: Vec<&str> = h.lines().skip(1).collect();
    assert_eq!(rows.len(), steps + 1, "history.csv rows");
    let last_step: usize =
        rows.last().and_then(|r| r.split(',').next()).and_then(|s| s.parse().ok()).expect("last step");
    assert_eq!(last_step, steps);
    let pvd = std::fs::read_to_string(out.join("series.pvd")).expect("series.pvd");
    assert!(pvd.trim_end().ends_with("</VTKFile>"), "series.pvd is not complete");
    let listed: Vec<String> =
        pvd.lines().filter_map(|l| l.split("file=\"").nth(1)).map(|s| s.trim_end_matches("\"/>").to_string()).collect();
    for f in &listed {
        assert!(out.join(f).exists(), "{f} listed but missing");
    }
    let on_disk = std::fs::read_dir(out.join("frames"))
        .expect("frames")
        .filter(|e| e.as_ref().is_ok_and(|e| e.path().extension().is_some_and(|x| x == "vtu")))
        .count();
    assert_eq!(on_disk, listed.len(), "frames on disk vs series.pvd");
}

/// A Newton capped at one iteration fails: exit code 2, the message names the step, the time,
/// the residual and a fix, and the files are valid up to the last good step.
#[test]
fn forced_newton_failure_exits_2_with_valid_files() {
    let dir = tmp("fail_newton");
    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        fixture_text("impact_friction").replace("[output]", "[solver]\nmax_newton_iterations = 1\n\n[output]"),
    )
    .expect("write");
    let out = dir.join("out");
    let o = run(&[], &scene, &out);
    let err = String::from_utf8_lossy(&o.stderr);
    println!("{err}");
    assert_eq!(o.status.code(), Some(2), "exit code");
    for want in ["step ", "t = ", "residual", "Suggestion"] {
        assert!(err.contains(want), "message lacks `{want}`: {err}");
    }
    let s = summary(&out);
    assert_eq!(s["status"], "failed");
    assert!(s["failure"].as_str().expect("failure").contains("newton"));
    let done = s["steps_completed"].as_u64().expect("steps") as usize;
    assert!(done < 600, "the run did not fail");
    check_files_valid(&out, done);
}

/// A load that becomes infinite mid-run (1/(t − 0.0105) at the midpoint of step 11) stops the
/// run at that step as bad input (exit 1) naming the load's key, the point and the time — it is
/// checked every step before anything is solved — and no non-finite value reaches a file. Over
/// 0.3 s `run` refuses the scene before its first step (the load at each of the 300 load times:
/// 768 quadrature points each); over 30 s that scan would take 30,000 × (768 + 10) = 2.3e7
/// evaluations, more than its budget of 2e7, so the run starts and the step meets the load.
#[test]
fn forced_non_finite_load_is_refused_naming_the_key() {
    let dir = tmp("fail_nan");
    let scene = dir.join("scene.toml");
    let text = fixture_text("impact_friction")
        .replace("body = [\"0\", \"-20\"]", "body = [\"0\", \"-20 + 1/(t - 0.0105)\"]")
        .replace("step = 5.0e-4", "step = 1.0e-3");
    std::fs::write(&scene, &text).expect("write");
    let refused = dir.join("refused");
    let o = run(&[], &scene, &refused);
    assert_eq!(o.status.code(), Some(1), "exit code");
    assert!(String::from_utf8_lossy(&o.stderr).contains("t = 0.0105") && !refused.exists());
    std::fs::write(&scene, text.replace("end = 0.3", "end = 30.0")).expect("write");
    let out = dir.join("out");
    let o = run(&[], &scene, &out);
    let err = String::from_utf8_lossy(&o.stderr);
    println!("{err}");
    assert_eq!(o.status.code(), Some(1), "exit code");
    assert!(err.contains("loads.body") && err.contains("t = 0.0105") && err.contains("inf"), "{err}");
    let s = summary(&out);
    assert_eq!(s["status"], "failed");
    assert_eq!(s["failure_kind"], "input");
    assert_eq!(s["steps_completed"], 10);
    check_files_valid(&out, 10);
    for f in ["history.csv", "contact.csv"] {
        let t = std::fs::read_to_string(out.join(f)).expect("csv").to_lowercase();
        assert!(!t.contains("nan") && !t.contains("inf"), "{f} contains a non-finite value");
    }
}

/// A run stopped after step 237 (exit 130, summary "interrupted", checkpoint written) and
/// resumed gives history.csv, contact.csv, series.pvd and every frame identical, byte for byte,
/// to an uninterrupted run.
#[test]
fn resume_equals_uninterrupted_run_bit_for_bit() {
    resume_case("resume", &fixture_text("impact_friction"), 237);
}

/// The same in 3-D with friction on the disk (sliding_block3d, stopped at step 900 while it
/// slides): from step 879 on the first Newton system of each step is solved by conjugate
/// gradients preconditioned with the kept factorization of the step before, which the
/// checkpoint carries (its key: U, D and the slip frames) and the resumed run rebuilds — without
/// it the resumed history differs (checked when this test was written).
#[test]
fn resume_equals_uninterrupted_run_bit_for_bit_in_3d() {
    resume_case("resume3d", &fixture_text("sliding_block3d"), 900);
}

/// The same in plane stress with the impact's viscosity θ = ζ = 0.5 (not proportional to the
/// elasticity): the checkpoint carries ε_zz per triangle (Ps.1), and the resumed run's files —
/// the frames' stress, which reads ε_zz, included — equal the uninterrupted run's byte for byte.
#[test]
fn resume_equals_uninterrupted_run_bit_for_bit_in_plane_stress() {
    let text = fixture_text("impact_friction").replace("[domain]\n", "[domain]\nplane = \"stress\"\n");
    assert!(text.contains("plane = \"stress\""));
    resume_case("resume_plane_stress", &text, 237);
}

fn resume_case(name: &str, text: &str, stop: usize) {
    let dir = tmp(name);
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, text).expect("write");
    let (a, b) = (dir.join("a"), dir.join("b"));
    assert!(run(&[], &scene, &a).status.success());
    let stop_text = stop.to_string();
    let o = run(&["--checkpoint-every", "100", "--stop-after", &stop_text], &scene, &b);
    assert_eq!(o.status.code(), Some(130), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(summary(&b)["status"], "interrupted");
    check_files_valid(&b, stop);
    let o = Command::new(BIN).arg("run").arg(&scene).arg("--resume").arg(&b).output().expect("spawn");
    assert!(o.status.success(), "resume failed: {}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(summary(&b)["status"], "completed");
    for f in ["history.csv", "contact.csv", "series.pvd"] {
        let (x, y) = (std::fs::read(a.join(f)).expect("a"), std::fs::read(b.join(f)).expect("b"));
        assert!(x == y, "{f} differs after resume");
    }
    let mut frames = 0;
    for e in std::fs::read_dir(a.join("frames")).expect("frames").flatten() {
        let name = e.file_name();
        let (x, y) =
            (std::fs::read(e.path()).expect("a"), std::fs::read(b.join("frames").join(&name)).expect("b frame"));
        assert!(x == y, "{name:?} differs after resume");
        frames += 1;
    }
    println!("resume: history, contact, pvd and {frames} frames identical");
    assert!(frames > 10);
}

/// A checkpoint resumes only the scene that wrote it: another scene is refused as a folder
/// error (exit 4) naming the inputs.
#[test]
fn resume_refuses_another_scene() {
    let dir = tmp("resume_other");
    let (s1, s2) = (dir.join("s1.toml"), dir.join("s2.toml"));
    std::fs::write(&s1, fixture_text("impact_friction")).expect("write");
    std::fs::write(&s2, fixture_text("impact_friction").replace("static = 0.5", "static = 0.55")).expect("write");
    let out = dir.join("out");
    assert_eq!(run(&["--stop-after", "20"], &s1, &out).status.code(), Some(130));
    let o = Command::new(BIN).arg("run").arg(&s2).arg("--resume").arg(&out).output().expect("spawn");
    assert_eq!(o.status.code(), Some(4));
    assert!(String::from_utf8_lossy(&o.stderr).contains("other inputs"), "{}", String::from_utf8_lossy(&o.stderr));
}

/// SIGINT stops the run at the end of the current step: exit 130, summary "interrupted" with
/// the step, and files consistent with it. The academic scene runs to t = 1000 s (2 million
/// steps, which no machine finishes first) and is interrupted once history.csv holds 50 rows,
/// mid-run on any machine (a fixed sleep before the signal let a fast run end first).
#[test]
fn sigint_leaves_valid_files() {
    let dir = tmp("sigint");
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, fixture_text("academic")).expect("write");
    let out = dir.join("out");
    /// Kills the run if the test fails before it ends (it would run for minutes).
    struct Run(std::process::Child);
    impl Drop for Run {
        fn drop(&mut self) {
            let _ = self.0.kill();
            let _ = self.0.wait();
        }
    }
    let mut run = Run(Command::new(BIN)
        .arg("run")
        .arg(&scene)
        .args(["--set", "time.end=1000.0", "--out"])
        .arg(&out)
        .spawn()
        .expect("spawn"));
    let child = &mut run.0;
    let start = std::time::Instant::now();
    while !std::fs::read_to_string(out.join("history.csv")).is_ok_and(|t| t.lines().count() > 50) {
        assert!(child.try_wait().expect("try_wait").is_none(), "the run ended before it could be interrupted");
        assert!(start.elapsed() < std::time::Duration::from_secs(60), "history.csv did not reach 50 steps in 60 s");
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let killed = Command::new("kill").args(["-INT", &child.id().to_string()]).status().expect("kill");
    assert!(killed.success());
    let status = child.wait().expect("wait");
    let s = summary(&out);
    assert_eq!(status.code(), Some(130));
    assert_eq!(s["status"], "interrupted");
    let done = s["steps_completed"].as_u64().expect("steps") as usize;
    // 51 lines: the header and steps 0 … 49 written; the step under way completes
    assert!(done >= 49, "interrupted at step {done}, before history.csv held 50 rows");
    println!("interrupted after step {done}: {}", s["failure"]);
    check_files_valid(&out, done);
    assert!(out.join("checkpoint.json").exists());
}
