//! Project tasks: `cargo xtask verify | crosscheck | trace | bench | stability | bound-at`.
//!
//! `verify` is the project's test command. It
//! 1. checks the formatting (`cargo fmt --all --check`, rustfmt.toml);
//! 2. builds every test target (`cargo test -p dyncontact -p dyncontact-studies --no-run`) and
//!    checks the lints in the same build: cargo runs the workspace's crates through clippy's
//!    driver (lints.rs) and adds xtask's targets (`-p xtask --all-targets`, criterion included),
//!    so the lints of what `cargo clippy --workspace --all-targets` checks are reported — the
//!    Python crate's by the wheel's build (step 5), wrapped alike — each a warning that fails
//!    verify without stopping it (`-D warnings` as a check); without a clippy-driver that passes
//!    the canary, or without the cross-check, `cargo clippy` checks what the builds did not.
//!    Meanwhile a thread prepares the cross-check's Python (venv, pip, GetFEM), which waits
//!    mostly on the network;
//! 3. runs each test binary directly, as many at a time as the machine has cores, recording which
//!    test passed (so a test is tied to its file: a grouped binary's modules are its files);
//! 4. checks the equation trace (spec/equations.toml): every `implemented` ID names code anchors
//!    that exist — `file.rs::function` or `file.rs::Type::method`, found exactly once, whose doc
//!    comment starts with `/// (ID)` — and at least one test that exists and passed in this run;
//!    every ID cited in a doc comment under src/ or tests/ is in the spec; every ID is defined in
//!    the index of spec/model.md; and no module cycle (cycles.rs);
//! 5. runs the Python cross-check (`crosscheck`) and the Snakemake check (`workflow`);
//! 6. writes target/verify/trace.md and report.md and exits non-zero on any failure (all of them
//!    listed).

mod crosscheck;
mod cycles;
mod lints;
mod process;
mod python;
mod source;
mod workflow;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode, Stdio};
use std::sync::Mutex;
use std::time::Instant;

use serde::Deserialize;

#[derive(Debug, Deserialize)]
struct Spec {
    equation: Vec<Equation>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Equation {
    id: String,
    statement: String,
    provenance: String,
    status: String,
    #[serde(default)]
    code: Vec<String>,
    #[serde(default)]
    tests: Vec<String>,
    #[serde(default)]
    notes: String,
}

fn root() -> PathBuf {
    let here = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    here.parent().map(Path::to_path_buf).unwrap_or(here)
}

/// Cargo's target directory as cargo itself resolves it (CARGO_TARGET_DIR, `build.target-dir`,
/// or `<root>/target`): where the tests write their measurements and verify its reports.
fn target_dir(root: &Path) -> Result<PathBuf, String> {
    let out = Command::new(env!("CARGO"))
        .args(["metadata", "--format-version", "1", "--no-deps"])
        .current_dir(root)
        .stderr(Stdio::inherit())
        .output()
        .map_err(|e| format!("cannot run cargo metadata: {e}"))?;
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).map_err(|e| format!("cargo metadata: {e}"))?;
    v["target_directory"].as_str().map(PathBuf::from).ok_or_else(|| "cargo metadata names no target_directory".into())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let root = root();
    let target = match target_dir(&root) {
        Ok(t) => t,
        Err(e) => {
            eprintln!("xtask: {e}");
            return ExitCode::FAILURE;
        }
    };
    let result = match args.first().map(String::as_str) {
        Some("verify") => verify(&root, &target, args.iter().any(|a| a == "--no-crosscheck")),
        Some("crosscheck") => crosscheck_only(&root, &target),
        Some("trace") => trace_only(&root),
        Some("bench") => study(&root, &target, "bench", &args[1..]),
        Some("stability") => study(&root, &target, "stability", &args[1..]),
        Some("bound-at") => study(&root, &target, "bound-at", &args[1..]),
        _ => Err(
            "usage: cargo xtask <verify [--no-crosscheck] | crosscheck | trace | bench [--quick] | stability [--quick] | bound-at [--quick]>"
                .to_string(),
        ),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("xtask: {e}");
            ExitCode::FAILURE
        }
    }
}

/// `bench`, `stability`, `bound-at`: build the studies' binary in release (numerics at full
/// speed) and run that study, writing under target/<what>.
fn study(root: &Path, target: &Path, what: &str, extra: &[String]) -> Result<(), String> {
    let st = Command::new(env!("CARGO"))
        .args(["build", "--release", "-p", "dyncontact-studies", "--bin", "dyncontact-studies"])
        .current_dir(root)
        .status()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    if !st.success() {
        return Err("the release build failed".into());
    }
    let out = target.join(what.replace('-', "_"));
    let exe = target.join("release").join(format!("dyncontact-studies{}", std::env::consts::EXE_SUFFIX));
    let st = Command::new(exe)
        .args([what, "--out"])
        .arg(&out)
        .args(extra)
        .current_dir(root)
        .status()
        .map_err(|e| format!("cannot run dyncontact-studies: {e}"))?;
    if st.success() { Ok(()) } else { Err(format!("dyncontact-studies {what} failed")) }
}

/// A test binary built by cargo: the source file of its target and the executable.
struct TestBinary {
    src: String,
    exe: PathBuf,
}

/// What the test build (`cargo test -p dyncontact -p dyncontact-studies --no-run`) built: the
/// test binaries, and the `dyncontact` binary that the CLI tests run and the cross-check uses (the
/// one built with these tests, never an older one left in the target directory). `linted`: the
/// build went through clippy's driver (lints.rs) with xtask's targets added (`-p xtask
/// --all-targets`), so `warnings` holds every lint and compiler warning of dyncontact,
/// dyncontact-studies and xtask, each once (`code at file:line: message`).
struct Build {
    tests: Vec<TestBinary>,
    dyncontact: PathBuf,
    linted: bool,
    warnings: BTreeSet<String>,
}

fn build_tests(root: &Path, target: &Path) -> Result<Build, String> {
    let mut cargo = Command::new(env!("CARGO"));
    cargo.args(["test", "-p", "dyncontact", "-p", "dyncontact-studies", "--no-run"]);
    let linted = lints::through_clippy(&mut cargo, target);
    if linted {
        // xtask's targets for their lints: its binary, its test harness (run below) and its
        // bench (with criterion, built, not run); `--all-targets` applies to every package, so it
        // also builds the bins', benches' and examples' harnesses of the other two (not run)
        cargo.args(["-p", "xtask", "--all-targets"]);
    }
    // cargo's JSON, the diagnostics printed here as cargo would print them (rendered)
    let mut child = cargo
        .arg("--message-format=json")
        .current_dir(root)
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .map_err(|e| format!("cannot run cargo: {e}"))?;
    let stdout = child.stdout.take().ok_or("cargo's output")?;
    let (mut tests, mut dyncontact, mut warnings, mut errors) = (Vec::new(), None, BTreeSet::new(), Vec::new());
    for line in std::io::BufRead::lines(std::io::BufReader::new(stdout)) {
        let line = line.map_err(|e| format!("reading cargo's output: {e}"))?;
        let Ok(v) = serde_json::from_str::<serde_json::Value>(&line) else { continue };
        if v["reason"] == "compiler-message" {
            let m = &v["message"];
            eprint!("{}", m["rendered"].as_str().unwrap_or_default());
            let text = m["message"].as_str().unwrap_or_default();
            if summary(text) {
                continue;
            }
            let code = m["code"]["code"].as_str().unwrap_or("warning");
            let span = m["spans"].as_array().and_then(|s| s.iter().find(|s| s["is_primary"] == true));
            let at = match span {
                Some(span) => {
                    format!("{code} at {}:{}: {text}", span["file_name"].as_str().unwrap_or("?"), span["line_start"])
                }
                None => format!("{code} (no location): {text}"),
            };
            if m["level"] == "error" {
                errors.push(at);
            } else {
                warnings.insert(at);
            }
            continue;
        }
        if v["reason"] != "compiler-artifact" {
            continue;
        }
        let Some(exe) = v["executable"].as_str() else { continue };
        if v["profile"]["test"] != true {
            let is_bin = v["target"]["kind"].as_array().is_some_and(|k| k.iter().any(|k| k == "bin"));
            if is_bin && v["target"]["name"] == "dyncontact" {
                dyncontact = Some(PathBuf::from(exe));
            }
            continue;
        }
        // the test harnesses of targets that are tested (`test = true`: the libs, tests/ and,
        // built when linted, xtask's binary), not those `--all-targets` adds for the lints (bins
        // and examples with `test = false`, benches)
        if v["target"]["test"] != true {
            continue;
        }
        let Some(src) = v["target"]["src_path"].as_str() else { continue };
        let src = Path::new(src)
            .strip_prefix(root)
            .map(|p| p.to_string_lossy().to_string())
            .unwrap_or_else(|_| src.to_string());
        tests.push(TestBinary { src, exe: PathBuf::from(exe) });
    }
    let status = child.wait().map_err(|e| format!("cargo: {e}"))?;
    if !status.success() {
        let first = errors.iter().take(6).cloned().collect::<Vec<_>>().join("; ");
        let first = if first.is_empty() { "see the errors printed above".to_string() } else { first };
        return Err(format!("building the tests failed: {first}"));
    }
    if tests.is_empty() {
        return Err("the test build reported no test binary (cargo's `target.test` field?)".into());
    }
    let dyncontact = dyncontact.ok_or("the test build reported no `dyncontact` binary")?;
    Ok(Build { tests, dyncontact, linted, warnings })
}

/// rustc's closing counts ("2 warnings emitted", "aborting due to 1 previous error"): every
/// diagnostic is reported on its own already.
fn summary(message: &str) -> bool {
    let counted = message.split_once(' ').is_some_and(|(n, rest)| {
        n.parse::<usize>().is_ok() && (rest.starts_with("warning") || rest.starts_with("error"))
    });
    counted || message.starts_with("aborting due to")
}

/// Outcome of every test: (source file of the target, libtest name) → passed.
type Outcomes = BTreeMap<(String, String), bool>;

/// One test binary run to its end: its output, whether it exited with 0, its wall time.
struct BinaryRun {
    stdout: String,
    ok: bool,
    seconds: f64,
}

fn run_binary(root: &Path, b: &TestBinary) -> Result<BinaryRun, String> {
    let t = Instant::now();
    let out = Command::new(&b.exe)
        .current_dir(root)
        .env("CI", "true")
        .stdin(Stdio::null())
        .output()
        .map_err(|e| format!("cannot run {}: {e}", b.exe.display()))?;
    let mut stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    stdout.push_str(&String::from_utf8_lossy(&out.stderr));
    Ok(BinaryRun { stdout, ok: out.status.success(), seconds: t.elapsed().as_secs_f64() })
}

/// Run every test binary, `jobs` at a time (each binary runs its own tests on its threads too);
/// a binary's output is printed whole when it ends. Returns every test's outcome and, when a
/// binary failed, what failed (verify goes on to report the trace and the other checks too).
fn run_tests(root: &Path, bins: &[TestBinary], jobs: usize) -> Result<(Outcomes, Option<String>), String> {
    let next = Mutex::new(0usize);
    let runs: Mutex<Vec<Option<Result<BinaryRun, String>>>> = Mutex::new((0..bins.len()).map(|_| None).collect());
    let print = Mutex::new(());
    std::thread::scope(|scope| {
        for _ in 0..jobs.max(1) {
            scope.spawn(|| {
                loop {
                    let i = {
                        let mut n = next.lock().unwrap_or_else(|e| e.into_inner());
                        let i = *n;
                        *n += 1;
                        i
                    };
                    let Some(b) = bins.get(i) else { break };
                    let run = run_binary(root, b);
                    if let Ok(r) = &run {
                        let _guard = print.lock().unwrap_or_else(|e| e.into_inner());
                        let name = b.exe.file_name().map(|f| f.to_string_lossy().to_string()).unwrap_or_default();
                        println!("== {} ({name}, {:.1} s)\n{}", b.src, r.seconds, r.stdout.trim_end());
                    }
                    runs.lock().unwrap_or_else(|e| e.into_inner())[i] = Some(run);
                }
            });
        }
    });
    let mut outcomes = Outcomes::new();
    let mut failed_bins = Vec::new();
    for (b, run) in bins.iter().zip(runs.into_inner().unwrap_or_else(|e| e.into_inner())) {
        let run = run.ok_or_else(|| format!("{} did not run", b.src))??;
        for line in run.stdout.lines() {
            // "test NAME ... ok" | "... FAILED" | "... ignored"
            let Some(rest) = line.strip_prefix("test ") else { continue };
            let Some((name, result)) = rest.rsplit_once(" ... ") else { continue };
            if result.trim() == "ok" || result.trim() == "FAILED" {
                outcomes.insert((b.src.clone(), name.trim().to_string()), result.trim() == "ok");
            }
        }
        if !run.ok {
            failed_bins.push(b.src.clone());
        }
    }
    let failure = (!failed_bins.is_empty()).then(|| {
        let failed: Vec<String> =
            outcomes.iter().filter(|(_, p)| !**p).map(|((f, n), _)| format!("{f}::{n}")).collect();
        format!("tests failed in {}: {}", failed_bins.join(", "), failed.join(", "))
    });
    Ok((outcomes, failure))
}

/// Look up a test reference `file.rs::name`: a test binary's own file (its root), a module file
/// of a grouped binary (`tests/<group>/<module>.rs::name` is the test `<module>::name` of the
/// binary `tests/<group>/main.rs`), or `src/a/b.rs::tests::name` (unit tests: the lib target
/// with module path a::b::tests::name).
fn test_passed(outcomes: &Outcomes, reference: &str) -> Option<bool> {
    let (file, name) = reference.split_once("::")?;
    if file.starts_with("src/") && file != "src/main.rs" {
        let module =
            file.trim_start_matches("src/").trim_end_matches(".rs").trim_end_matches("/mod").replace('/', "::");
        let full = if module == "lib" { name.to_string() } else { format!("{module}::{name}") };
        return outcomes.get(&("src/lib.rs".to_string(), full)).copied();
    }
    let matches = |n: &str, name: &str| n == name || n.ends_with(&format!("::{name}"));
    if let Some(hit) = outcomes.iter().find(|((f, n), _)| f == file && matches(n, name)) {
        return Some(*hit.1);
    }
    // a module of a grouped binary: the nearest folder above `file` whose main.rs is a test binary
    let path = Path::new(file);
    for dir in path.ancestors().skip(1) {
        let root = dir.join("main.rs").to_string_lossy().to_string();
        if !outcomes.keys().any(|(f, _)| *f == root) {
            continue;
        }
        let module = path.strip_prefix(dir).ok()?.with_extension("").to_string_lossy().replace('/', "::");
        let module = module.trim_end_matches("::mod").to_string();
        return outcomes
            .iter()
            .find(|((f, n), _)| *f == root && n.starts_with(&format!("{module}::")) && matches(n, name))
            .map(|(_, p)| *p);
    }
    None
}

/// Does the anchor name exactly one function whose doc comment starts with `/// (ID)`? An anchor
/// is `file.rs::function` (a free function) or `file.rs::Type::method` (a function of an `impl`
/// or `trait` block of that type); a name found twice, or a method named without its type, fails
/// with what to write instead.
fn anchor_ok(root: &Path, anchor: &str, id: &str) -> Result<(), String> {
    let (file, item) = anchor
        .split_once(".rs::")
        .map(|(f, i)| (format!("{f}.rs"), i))
        .ok_or_else(|| format!("anchor `{anchor}` is not `file.rs::function` or `file.rs::Type::method`"))?;
    let (owner, name) = match item.split_once("::") {
        Some((t, m)) => (Some(t), m),
        None => (None, item),
    };
    let text = std::fs::read_to_string(root.join(&file))
        .map_err(|_| format!("anchor `{anchor}`: file {file} does not exist"))?;
    let defs = source::functions(&text);
    let hits: Vec<&source::FnDef> = defs.iter().filter(|d| d.name == name && d.owner.as_deref() == owner).collect();
    let hit = match hits.as_slice() {
        [one] => one,
        [] => {
            let others: Vec<String> = defs
                .iter()
                .filter(|d| d.name == name)
                .map(|d| d.owner.as_ref().map_or(format!("{file}::{name}"), |t| format!("{file}::{t}::{name}")))
                .collect();
            return Err(if others.is_empty() {
                format!("anchor `{anchor}`: no function `{name}` in {file}")
            } else {
                format!("anchor `{anchor}`: no such function; {file} has {}", others.join(", "))
            });
        }
        many => {
            let lines: Vec<String> = many.iter().map(|d| (d.line + 1).to_string()).collect();
            return Err(format!("anchor `{anchor}` is ambiguous: defined at lines {} of {file}", lines.join(", ")));
        }
    };
    // walk up over attributes to the start of the doc block
    let lines: Vec<&str> = text.lines().collect();
    let want = format!("/// ({id})");
    let mut j = hit.line;
    let mut first_doc: Option<&str> = None;
    while j > 0 {
        j -= 1;
        let p = lines[j].trim_start();
        if p.starts_with("#[") {
            continue;
        }
        if p.starts_with("///") {
            first_doc = Some(p);
            continue;
        }
        break;
    }
    if first_doc.is_some_and(|d| d.starts_with(&want)) {
        Ok(())
    } else {
        Err(format!("anchor `{anchor}`: the doc comment of `{item}` does not start with `{want}`"))
    }
}

/// The IDs the model defines: the first cell of every row of spec/model.md's equation index,
/// written `| (ID) |`.
fn model_ids(root: &Path) -> Result<BTreeSet<String>, String> {
    let p = root.join("spec/model.md");
    let text = std::fs::read_to_string(&p)
        .map_err(|e| format!("{}: {e} (the model document must be in the repository)", p.display()))?;
    Ok(text
        .lines()
        .filter_map(|l| l.strip_prefix("| (")?.split_once(") |").map(|(id, _)| id.to_string()))
        .filter(|id| is_id(id))
        .collect())
}

/// IDs cited at the start of doc comments (`/// (ID)` or `//! (ID)`) under a folder.
fn cited_ids(dir: &Path, out: &mut BTreeMap<String, BTreeSet<String>>) {
    let Ok(rd) = std::fs::read_dir(dir) else { return };
    for e in rd.flatten() {
        let p = e.path();
        if p.is_dir() {
            cited_ids(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            let Ok(text) = std::fs::read_to_string(&p) else { continue };
            for l in text.lines() {
                let t = l.trim_start();
                let Some(rest) = t.strip_prefix("///").or_else(|| t.strip_prefix("//!")) else { continue };
                let rest = rest.trim_start();
                if let Some(inner) = rest.strip_prefix('(')
                    && let Some((id, _)) = inner.split_once(')')
                    && is_id(id)
                {
                    out.entry(id.to_string()).or_default().insert(p.display().to_string());
                }
            }
        }
    }
}

/// An equation ID: capital letter, optional lower-case letter, dot, digits/letters (P.1, Pe.5, C.k).
fn is_id(s: &str) -> bool {
    let Some((head, tail)) = s.split_once('.') else { return false };
    let mut h = head.chars();
    let first_ok = h.next().is_some_and(|c| c.is_ascii_uppercase());
    let rest_ok = head.len() <= 2 && h.all(|c| c.is_ascii_lowercase());
    first_ok && rest_ok && !tail.is_empty() && tail.len() <= 3 && tail.chars().all(|c| c.is_ascii_alphanumeric())
}

struct TraceResult {
    markdown: String,
    failures: Vec<String>,
    open: Vec<String>,
}

fn check_trace(root: &Path, outcomes: Option<&Outcomes>) -> Result<TraceResult, String> {
    let text =
        std::fs::read_to_string(root.join("spec/equations.toml")).map_err(|e| format!("spec/equations.toml: {e}"))?;
    let spec: Spec = toml::from_str(&text).map_err(|e| format!("spec/equations.toml: {e}"))?;
    let mut failures = Vec::new();
    let mut open = Vec::new();
    let mut md = String::from(
        "# Equation trace\n\n| ID | provenance | status | code | tests | result |\n|---|---|---|---|---|---|\n",
    );
    let mut ids = BTreeSet::new();
    for eq in &spec.equation {
        if !ids.insert(eq.id.clone()) {
            failures.push(format!("{}: listed twice in the spec", eq.id));
        }
        if eq.statement.trim().is_empty() {
            failures.push(format!("{}: empty statement", eq.id));
        }
        let mut problems = Vec::new();
        match eq.status.as_str() {
            "implemented" => {
                if eq.code.is_empty() {
                    problems.push("no code anchor".to_string());
                }
                for a in &eq.code {
                    if let Err(e) = anchor_ok(root, a, &eq.id) {
                        problems.push(e);
                    }
                }
                if eq.tests.is_empty() {
                    problems.push("no test".to_string());
                }
                if let Some(o) = outcomes {
                    let mut any_passed = false;
                    for t in &eq.tests {
                        match test_passed(o, t) {
                            Some(true) => any_passed = true,
                            Some(false) => problems.push(format!("test `{t}` failed")),
                            None => problems.push(format!("test `{t}` does not exist (or did not run)")),
                        }
                    }
                    if !any_passed && !eq.tests.is_empty() {
                        problems.push("no passing test".into());
                    }
                }
            }
            "planned" => {
                open.push(format!("{} — {}", eq.id, eq.notes));
                problems.push("still planned: every ID must be implemented and traced".into());
            }
            other => problems.push(format!("status must be implemented or planned, got `{other}`")),
        }
        let result = if problems.is_empty() {
            if eq.status == "planned" { "open".to_string() } else { "ok".to_string() }
        } else {
            failures.extend(problems.iter().map(|p| format!("{}: {p}", eq.id)));
            format!("FAIL: {}", problems.join("; "))
        };
        md.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} |\n",
            eq.id,
            eq.provenance,
            eq.status,
            eq.code.join("<br>"),
            eq.tests.join("<br>"),
            result
        ));
    }
    let mut cited = BTreeMap::new();
    cited_ids(&root.join("src"), &mut cited);
    cited_ids(&root.join("tests"), &mut cited);
    for (id, files) in &cited {
        if !ids.contains(id) {
            failures.push(format!(
                "{id} is cited in {} but is not in spec/equations.toml",
                files.iter().cloned().collect::<Vec<_>>().join(", ")
            ));
        }
    }
    // every ID of the spec and every cited ID is defined in the index of spec/model.md
    match model_ids(root) {
        Ok(defined) => {
            for id in ids.iter().chain(cited.keys()).collect::<BTreeSet<_>>() {
                if !defined.contains(id) {
                    failures.push(format!("{id}: not defined in spec/model.md (no index row `| ({id}) |`)"));
                }
            }
        }
        Err(e) => failures.push(e),
    }
    let module_cycles = cycles::check(root);
    md.push_str(&format!(
        "\n## Module cycles\n\n{}\n",
        if module_cycles.is_empty() {
            "none (every crate's modules, at every level)".to_string()
        } else {
            module_cycles.join("\n\n")
        }
    ));
    failures.extend(module_cycles);
    if !open.is_empty() {
        md.push_str("\n## Open (planned) IDs\n\n");
        for o in &open {
            md.push_str(&format!("- {o}\n"));
        }
    }
    Ok(TraceResult { markdown: md, failures, open })
}

fn write_report(target: &Path, name: &str, text: &str) -> Result<PathBuf, String> {
    let dir = target.join("verify");
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let p = dir.join(name);
    std::fs::write(&p, text).map_err(|e| format!("{}: {e}", p.display()))?;
    Ok(p)
}

fn trace_only(root: &Path) -> Result<(), String> {
    let t = check_trace(root, None)?;
    println!("{}", t.markdown);
    if t.failures.is_empty() { Ok(()) } else { Err(t.failures.join("\n")) }
}

/// The measurements the tests recorded (<target>/verify/measurements.jsonl).
fn measurements(target: &Path) -> Vec<serde_json::Value> {
    std::fs::read_to_string(target.join("verify").join("measurements.jsonl"))
        .unwrap_or_default()
        .lines()
        .filter_map(|l| serde_json::from_str(l).ok())
        .collect()
}

/// target/verify/report.md: the trace, every measured number with its expectation, the largest
/// (E.1) residual, the twins' agreement and the snapshot status.
fn report(target: &Path, trace: &TraceResult, outcomes: &Outcomes, crosscheck: &str) -> String {
    let m = measurements(target);
    let mut r = String::from("# dyncontact verification report\n\n");
    let passed = outcomes.values().filter(|p| **p).count();
    r.push_str(&format!("{passed} tests passed, {} failed.\n\n", outcomes.len() - passed));
    let num = |v: &serde_json::Value| v["value"].as_f64().unwrap_or(f64::NAN);
    let worst_e1 = m
        .iter()
        .filter(|v| v["quantity"].as_str().unwrap_or("").starts_with("E.1 largest"))
        .map(num)
        .fold(0.0, f64::max);
    let twins: Vec<String> = m
        .iter()
        .filter(|v| v["quantity"].as_str().unwrap_or("").starts_with("twins"))
        .map(|v| format!("{}: {:.2e}", v["quantity"].as_str().unwrap_or(""), num(v)))
        .collect();
    let snapshots: Vec<String> = outcomes
        .iter()
        .filter(|((f, n), _)| f == "tests/solver/main.rs" && n.starts_with("snapshots::"))
        .map(|((_, n), p)| {
            format!("{}: {}", n.trim_start_matches("snapshots::"), if *p { "matches" } else { "CHANGED" })
        })
        .collect();
    r.push_str(&format!("- largest (E.1) residual, relative to the energy scale: {worst_e1:.2e}\n"));
    r.push_str(&format!("- twin solvers (newton vs conic), worst per-step difference: {}\n", twins.join("; ")));
    r.push_str(&format!(
        "- snapshots: {}\n\n",
        if snapshots.is_empty() { "not run".into() } else { snapshots.join("; ") }
    ));
    r.push_str("## Measured numbers\n\n| test | quantity | measured | expected |\n|---|---|---|---|\n");
    let cell = |v: &serde_json::Value| v.as_str().unwrap_or("").replace('|', "\\|");
    for v in &m {
        r.push_str(&format!(
            "| {} | {} | {:.4e} | {} |\n",
            cell(&v["test"]),
            cell(&v["quantity"]),
            num(v),
            cell(&v["expected"])
        ));
    }
    r.push_str("\n## Cross-check against scikit-fem\n\n```\n");
    r.push_str(crosscheck);
    r.push_str("\n```\n\n");
    r.push_str(&trace.markdown);
    r
}

/// `cargo fmt --all --check`: the code is as rustfmt.toml formats it.
fn formatted(root: &Path) -> Result<(), String> {
    let out = Command::new(env!("CARGO"))
        .args(["fmt", "--all", "--check", "--", "--color", "never"])
        .current_dir(root)
        .output()
        .map_err(|e| format!("cannot run cargo fmt: {e}"))?;
    if out.status.success() {
        return Ok(());
    }
    let diff = String::from_utf8_lossy(&out.stdout);
    let files: BTreeSet<&str> =
        diff.lines().filter_map(|l| l.strip_prefix("Diff in ")).filter_map(|l| l.split(':').next()).collect();
    println!("{diff}");
    Err(format!(
        "formatting: {} file(s) differ from rustfmt.toml's format ({}); `cargo fmt --all` fixes them{}",
        files.len(),
        files.into_iter().collect::<Vec<_>>().join(", "),
        String::from_utf8_lossy(&out.stderr).lines().next().map(|l| format!(" ({l})")).unwrap_or_default()
    ))
}

/// No lint anywhere in the workspace (what `cargo clippy --workspace --all-targets -- -D
/// warnings` checks; the lints the crates allow are allowed in their roots, each with its
/// reason). A linted test build has checked dyncontact, dyncontact-studies and xtask: any warning
/// it reported fails here. The Python crate's lints are then checked by the wheel's build
/// (python.rs, wrapped alike), or here by `cargo clippy` when there is no cross-check.
fn lints(root: &Path, build: &Build, crosscheck: bool) -> Result<(), String> {
    let mut failed = Vec::new();
    if !build.warnings.is_empty() {
        let n = build.warnings.len();
        let first: Vec<&str> = build.warnings.iter().take(6).map(String::as_str).collect();
        failed.push(format!(
            "lints: the test build reported {n} warning(s) (rustc's and clippy's, -D warnings): {}",
            first.join("; ")
        ));
    }
    let rest = match (build.linted, crosscheck) {
        (true, true) => Ok(()),
        (true, false) => lints::clippy(root, &["-p", "dyncontact-python", "--all-targets"]),
        (false, _) => lints::clippy(root, &["--workspace", "--all-targets"]),
    };
    failed.extend(rest.err());
    if failed.is_empty() { Ok(()) } else { Err(failed.join("\n  ")) }
}

/// `cargo xtask crosscheck`: the test build (a no-op when verify has just built it) for the
/// solver binary, then the cross-check.
fn crosscheck_only(root: &Path, target: &Path) -> Result<(), String> {
    let prepared = crosscheck::prepare(root, target)?;
    let build = build_tests(root, target)?;
    crosscheck::run(root, target, &build.dyncontact, &prepared).map(|r| println!("{r}"))
}

fn verify(root: &Path, target: &Path, skip_crosscheck: bool) -> Result<(), String> {
    let start = Instant::now();
    std::thread::scope(|scope| {
        let prepared = (!skip_crosscheck).then(|| scope.spawn(|| crosscheck::prepare(root, target)));
        let mut failures = Vec::new();
        let t = Instant::now();
        if let Err(e) = formatted(root) {
            failures.push(e);
        }
        let build = build_tests(root, target)?;
        println!("== built in {:.1} s", start.elapsed().as_secs_f64());
        match lints(root, &build, !skip_crosscheck) {
            Ok(()) => println!(
                "== formatting and lints clean ({:.1} s; {})",
                t.elapsed().as_secs_f64(),
                match (build.linted, skip_crosscheck) {
                    (true, false) => "linted by the build; the Python crate to be by the wheel's",
                    (true, true) => "linted by the build; the Python crate by cargo clippy",
                    (false, _) => "cargo clippy: no clippy-driver that lints through the wrapper",
                }
            ),
            Err(e) => failures.push(e),
        }
        let _ = std::fs::remove_file(target.join("verify").join("measurements.jsonl"));
        let jobs = std::thread::available_parallelism().map_or(2, usize::from);
        let t = Instant::now();
        let (outcomes, tests_failed) = run_tests(root, &build.tests, jobs)?;
        failures.extend(tests_failed);
        let passed = outcomes.values().filter(|p| **p).count();
        println!(
            "\n== {passed} tests passed in {} binaries ({:.1} s, {jobs} at a time)",
            build.tests.len(),
            t.elapsed().as_secs_f64()
        );
        let trace = check_trace(root, Some(&outcomes))?;
        println!("\n{}", trace.markdown);
        let path = write_report(target, "trace.md", &trace.markdown)?;
        println!("trace written to {}", path.display());
        failures.extend(trace.failures.iter().cloned());
        let mut cross = String::from("skipped (--no-crosscheck)");
        match prepared.map(|h| h.join().unwrap_or_else(|_| Err("the cross-check's setup panicked".into()))) {
            None => println!("cross-check skipped (--no-crosscheck)"),
            Some(prepared) => {
                let t = Instant::now();
                match prepared.and_then(|p| crosscheck::run(root, target, &build.dyncontact, &p)) {
                    Ok(r) => {
                        println!("\n== cross-check ({:.1} s after the tests)\n{r}", t.elapsed().as_secs_f64());
                        cross = r;
                    }
                    Err(e) => {
                        cross = format!("FAILED: {e}");
                        failures.push(format!("cross-check: {e}"));
                    }
                }
            }
        }
        let rp = write_report(target, "report.md", &report(target, &trace, &outcomes, &cross))?;
        println!("report written to {}", rp.display());
        println!("\n{} open (planned) IDs", trace.open.len());
        println!("verify took {:.1} s", start.elapsed().as_secs_f64());
        if failures.is_empty() {
            println!("verify: OK");
            Ok(())
        } else {
            Err(format!("verify failed:\n  {}", failures.join("\n  ")))
        }
    })
}

#[cfg(test)]
mod tests {
    /// rustc's closing counts are not warnings of their own; every other diagnostic is (a
    /// warning with no location, such as an unknown lint named on the command line, included).
    #[test]
    fn only_rustcs_closing_counts_are_summaries() {
        for counts in ["1 warning emitted", "2 warnings emitted", "aborting due to 1 previous error", "3 errors"] {
            assert!(super::summary(counts), "{counts}");
        }
        for diagnostic in ["unneeded `return` statement", "unknown lint: `clippy::foo`", "10 is not a count here"] {
            assert!(!super::summary(diagnostic), "{diagnostic}");
        }
    }
}
