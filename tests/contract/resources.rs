//! Memory known before it is spent: `check` prints the estimated peak memory and the cost per
//! step without building a large problem, and `run` refuses a scene whose estimate exceeds the
//! memory available, naming the estimate and suggesting a coarser mesh (exit 1).
//!
//! The estimate is calibrated against the measured peak resident memory of `run` (summary.json
//! `peak_memory_mb`, VmHWM): eleven runs from 12 MB to 1 GB, estimate ÷ peak 0.91–1.17
//! (src/resources.rs); three of them are checked here, each in a process of its own.

use std::path::Path;
use std::process::Command;

use dyncontact::resources::{check_fits, estimate};
use dyncontact::scene::Scene;

const BIN: &str = env!("CARGO_BIN_EXE_dyncontact");

fn rectangle(cells: [i64; 2]) -> Scene {
    let text = format!(
        "name = \"size\"\n[domain]\nkind = \"rectangle\"\nsize = [1.0, 1.0]\ncells = [{}, {}]\n[boundary]\ndirichlet = [\"left\"]\n\
         [material]\ndensity = 1.0\nyoung = 1.0\npoisson = 0.3\n[time]\nend = 1.0\nstep = 0.5\n",
        cells[0], cells[1]
    );
    Scene::from_toml(&text, "size.toml").expect("scene")
}

/// A 4096 × 4096 mesh (33.6 million unknowns) is estimated above 24 GiB and refused with the
/// estimate in the message; the academic scene's estimate is a few MiB and fits.
#[test]
fn oversize_scene_is_refused_with_its_estimate() {
    let twenty_four_gib = 24.0 * 1024f64.powi(3);
    let huge = estimate(&rectangle([4096, 4096]).validate().expect("valid"), Path::new(".")).expect("estimate");
    println!("4096x4096: {}", huge.lines().join("; "));
    assert_eq!(huge.unknowns, 2 * 4097 * 4097);
    let e = check_fits(&huge, Some(twenty_four_gib)).expect_err("refused").to_string();
    println!("{e}");
    assert!(
        e.starts_with("domain: the run would need about") && e.contains("GiB") && e.contains("use a coarser mesh"),
        "{e}"
    );
    let academic = estimate(&Scene::default_scene().validate().expect("valid"), Path::new(".")).expect("estimate");
    assert!(academic.total() < 16.0 * 1024f64.powi(2), "academic estimated at {} bytes", academic.total());
    check_fits(&academic, Some(twenty_four_gib)).expect("the academic scene fits");
}

/// Through the CLI: `run` refuses the oversize scene with exit 1 before building it, and `check`
/// answers (exit 0) with the estimate and a warning that `run` would refuse it. (This machine
/// family has 24 GiB; the scene needs ~95 GiB.)
#[test]
fn cli_refuses_oversize_scene_before_building_it() {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("resources");
    std::fs::create_dir_all(&dir).expect("dir");
    let scene = dir.join("huge.toml");
    let text = "name = \"huge\"\n[domain]\nkind = \"rectangle\"\nsize = [1.0, 1.0]\ncells = [4096, 4096]\n[boundary]\ndirichlet = [\"left\"]\n\
                [material]\ndensity = 1.0\nyoung = 1.0\npoisson = 0.3\n[time]\nend = 1.0\nstep = 0.5\n";
    std::fs::write(&scene, text).expect("write");
    let run = Command::new(BIN).arg("run").arg(&scene).arg("--out").arg(dir.join("out")).output().expect("run");
    let err = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{err}");
    assert!(err.contains("the run would need about") && err.contains("use a coarser mesh"), "{err}");
    let check = Command::new(BIN).arg("check").arg(&scene).output().expect("check");
    let (out, err) = (String::from_utf8_lossy(&check.stdout), String::from_utf8_lossy(&check.stderr));
    assert!(check.status.success(), "{err}");
    assert!(out.contains("memory (est.)") && out.contains("GiB"), "{out}");
    assert!(err.contains("`run` would refuse it"), "{err}");
}

/// What the allocator adds to a small run's peak at random: the same hertz run (68 MB on a quiet
/// machine) measured 67–99 MB on a loaded one — most likely a second thread's glibc arena (with
/// MALLOC_ARENA_MAX=1 the 12 runs stayed within 67–71 MB, against 67–74 MB without it at the
/// same load). Fixed, so it matters only for small runs: the defect this test guards (an
/// estimate half the peak, 145.6 against 306 MiB) still fails, by 37 MB.
const ALLOCATOR_NOISE_MB: f64 = 32.0;

/// (issue 22) The memory estimate is within ±30% of the peak a run measures (summary.json
/// `peak_memory_mb`, the process's VmHWM) on four scenes: 2-D with contact (128 × 64 cells),
/// 3-D with friction on the disk (academic3d at 16 × 8 × 6, and at its 24 × 12 × 8, where W comes
/// from the Schur complement) and the 2-D Hertz contact — it was
/// about half the peak before it counted the assembly's triplet lists and the process baseline
/// (145.6 MiB estimated against 306 MiB measured). ±30%: the calibration's own spread is
/// 0.91–1.17, and the allocator's behaviour varies between machines; on top of it a fixed
/// [`ALLOCATOR_NOISE_MB`].
#[test]
fn memory_estimate_is_within_30_percent_of_the_measured_peak() {
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("memory_estimate");
    let fixture = |n: &str| {
        std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fixtures/scenes").join(format!("{n}.toml"))
    };
    let cases: [(&str, &[&str]); 4] = [
        ("academic", &["domain.cells=[128,64]", "time.end=0.05"]),
        ("academic3d", &["domain.cells=[16,8,6]", "time.end=0.02"]),
        // 24×12×8 (936 contact unknowns): W from the Schur complement, a second factor at setup
        ("academic3d", &["time.end=0.01"]),
        ("hertz", &["time.end=0.01"]),
    ];
    for (name, sets) in cases {
        let overrides: Vec<dyncontact::overrides::Override> =
            sets.iter().map(|s| dyncontact::overrides::Override::parse(s).expect("override")).collect();
        let scene = Scene::from_file_with(&fixture(name), &overrides).expect("scene");
        let est = estimate(&scene.validate().expect("valid"), fixture(name).parent().expect("dir"))
            .expect("estimate")
            .total()
            / 1e6;
        let out = dir.join(format!("{name}-{}", sets.len()));
        let _ = std::fs::remove_dir_all(&out);
        let mut cmd = Command::new(BIN);
        cmd.arg("run").arg(fixture(name)).arg("--out").arg(&out);
        for s in sets {
            cmd.args(["--set", s]);
        }
        let o = cmd.output().expect("run");
        assert!(o.status.success(), "{name}: {}", String::from_utf8_lossy(&o.stderr));
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).expect("summary")).expect("json");
        let peak = summary["peak_memory_mb"].as_f64().expect("the peak is measured on Linux");
        println!("{name}: estimated {est:.1} MB, measured peak {peak:.1} MB, ratio {:.2}", est / peak);
        assert!(
            (est - peak).abs() <= 0.3 * peak + ALLOCATOR_NOISE_MB,
            "{name}: estimate {est:.1} MB against a measured peak of {peak:.1} MB"
        );
    }
}

/// (issue 25) `check` states the contact solve's cost in the form the run takes: on academic3d
/// at 12×8×4 (3-D, ~350 contact unknowns: the velocity form, dense products, node blocks) about
/// VELOCITY_PRODUCTS dense products of 2m² flop per Newton iteration, not a dense Cholesky's
/// m³/3; at the fixture's 24×12×8 (~940 unknowns, from HMATRIX_FROM on: the hierarchical forms,
/// node blocks) and refined to 48×24×16 (3,600 unknowns, the near field too) at most that; on the
/// 2-D academic scene the Cholesky bound.
#[test]
fn check_states_the_velocity_form_cost() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let check_text = |sets: &[&str]| {
        let mut c = Command::new(BIN);
        c.arg("check").arg(root.join("fixtures/scenes/academic3d.toml"));
        for s in sets {
            c.args(["--set", s]);
        }
        String::from_utf8_lossy(&c.output().expect("check").stdout).to_string()
    };
    let cost_line = |sets: &[&str]| {
        let text = check_text(sets);
        text.lines()
            .find(|l| l.trim_start().starts_with("cost per step"))
            .unwrap_or_else(|| panic!("no cost line: {text}"))
            .to_string()
    };
    let coarse = dyncontact::overrides::Override::parse("domain.cells=[12,8,4]").expect("override");
    let scene = Scene::from_file_with(&root.join("fixtures/scenes/academic3d.toml"), &[coarse]).expect("scene");
    let e = estimate(&scene.validate().expect("valid"), &root.join("fixtures/scenes")).expect("estimate");
    let m = (3 * e.contact_nodes) as f64;
    assert!(m < dyncontact::defaults::HMATRIX_FROM as f64, "{m} unknowns: the dense products");
    let flops = dyncontact::resources::VELOCITY_PRODUCTS * 2.0 * m * m;
    assert_eq!(e.flops_per_step().1, flops, "the velocity form's work");
    let line = cost_line(&["domain.cells=[12,8,4]"]);
    assert!(line.contains("dense W or W⁻¹, node-block") && line.contains(&format!("about {flops:.2e} flop")), "{line}");
    let text = check_text(&[]);
    let line = cost_line(&[]);
    assert!(
        line.contains("at most")
            && line.contains("hierarchical W or W⁻¹ (0.3–0.6 of the dense values, measured), node-block"),
        "{line}"
    );
    let scene = Scene::from_file(&root.join("fixtures/scenes/academic3d.toml")).expect("scene");
    let e = estimate(&scene.validate().expect("valid"), &root.join("fixtures/scenes")).expect("estimate");
    // 936 contact unknowns, responses too large to keep: W from the Schur complement, and the
    // estimate counts its second factor
    assert!(e.schur_bytes > 0.0 && e.schur_setup_bytes() <= e.total(), "{e:?}");
    // the guard refuses by what the run needs without the Schur setup (taken only if it fits):
    // at 64×32×24 (estimated 7.0 GiB with it, 3.8 GiB without) a machine with memory between
    // the two runs it
    let set = dyncontact::overrides::Override::parse("domain.cells=[64,32,24]").expect("override");
    let big = Scene::from_file_with(&root.join("fixtures/scenes/academic3d.toml"), &[set]).expect("scene");
    let big = estimate(&big.validate().expect("valid"), &root.join("fixtures/scenes")).expect("estimate");
    assert!(big.required() < big.total(), "{big:?}");
    check_fits(&big, Some(0.5 * (big.required() + big.total()))).expect("fits without the Schur setup");
    assert!(check_fits(&big, Some(0.9 * big.required())).is_err(), "below what the solves need");
    assert!(text.lines().any(|l| l.contains("contact setup") && l.contains("Schur complement")), "{text}");
    // from HMATRIX_FROM contact unknowns on (48×24×16: 3,600) the products go through the
    // hierarchical W and W⁻¹, so the dense products' flop are a bound ("at most")
    let o = Command::new(BIN)
        .arg("check")
        .arg(root.join("fixtures/scenes/academic3d.toml"))
        .args(["--set", "domain.cells=[48,24,16]"])
        .output()
        .expect("check");
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.lines().any(|l| l.trim_start().starts_with("cost per step")
            && l.contains("at most")
            && l.contains("hierarchical W or W⁻¹")
            && l.contains("near-field factor")),
        "{text}"
    );
    let o = Command::new(BIN).arg("check").arg(root.join("fixtures/scenes/academic.toml")).output().expect("check");
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.lines().any(|l| l.trim_start().starts_with("cost per step")
            && l.contains("at most")
            && l.contains("dense Cholesky"))
    );
}
