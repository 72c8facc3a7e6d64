//! The sweep's Snakemake path, checked by `cargo xtask crosscheck` (so by `verify`) with the
//! Snakemake pinned in `xtask/crosscheck/requirements.txt` (installed into the cross-check's venv):
//!
//! 1. `dyncontact sweep fixtures/sweeps/six_points.toml` runs its 6 points in-process (2 jobs);
//! 2. the same sweep with `--plan-only` in another folder, planned by a copy of the binary in a
//!    folder whose name holds a quote, `$(touch PWNED)` and spaces, then the generated Snakefile
//!    with `snakemake --cores 2`, whose last job is `dyncontact sweep collect .`: the path
//!    reaches the shell quoted (no PWNED file appears);
//! 3. the two sweep.csv files must be equal, figure for figure (the wall times aside);
//! 4. one point's marker and sweep.csv removed (as a Snakemake run leaves them when a point was
//!    interrupted or killed: no marker, so no collect): `snakemake -n` lists exactly one `point`
//!    job to run again;
//! 5. `snakemake -n` on the stability map's sweeps (fixtures/sweeps/stability_*.toml, planned
//!    with `--plan-only`) must list one `point` job per point of the plan.

use std::fmt::Write as _;
use std::path::Path;
use std::process::Command;

use crate::process::{fresh_dir, spawn};

/// The checks above; Ok((all passed, the report lines)), Err when a program could not start.
pub fn check(root: &Path, bin: &Path, python: &Path, out_root: &Path) -> Result<(bool, String), String> {
    let snakemake = python.with_file_name(if cfg!(windows) { "snakemake.exe" } else { "snakemake" });
    let mut report = String::new();
    let mut ok = true;
    let sweep = root.join("fixtures/sweeps/six_points.toml");
    let inproc = fresh_dir(&out_root.join("sweep-inprocess"))?;
    let snake = fresh_dir(&out_root.join("sweep-snakemake"))?;
    let run = |cmd: &mut Command| -> Result<String, String> {
        match spawn(cmd)? {
            (true, text) => Ok(text),
            (false, text) => Err(text),
        }
    };
    let version = run(Command::new(&snakemake).arg("--version")).map(|v| v.trim().to_string()).unwrap_or_else(|e| e);
    let _ = writeln!(report, "snakemake {version}");
    run(Command::new(bin).current_dir(root).arg("sweep").arg(&sweep).arg("--out").arg(&inproc).args(["--jobs", "2"]))?;
    let odd = fresh_dir(&out_root.join("we\"ird $(touch PWNED) dir"))?;
    let odd_bin = odd.join(bin.file_name().unwrap_or_default());
    std::fs::copy(bin, &odd_bin).map_err(|e| format!("copy {} to {}: {e}", bin.display(), odd_bin.display()))?;
    run(Command::new(&odd_bin).current_dir(root).arg("sweep").arg(&sweep).arg("--out").arg(&snake).arg("--plan-only"))?;
    run(Command::new(&snakemake).current_dir(&snake).args(["--cores", "2", "--quiet", "all"]))?;
    let pwned: Vec<_> = [&snake, &odd, out_root, root].iter().map(|d| d.join("PWNED")).filter(|p| p.exists()).collect();
    if pwned.is_empty() {
        let _ = writeln!(
            report,
            "the binary at a path holding a quote and `$(touch PWNED)` ran every point; nothing ran from its name"
        );
    } else {
        ok = false;
        let _ = writeln!(report, "FAILED: the binary's path ran as code: {pwned:?}");
    }
    let (a, b) = (read(&inproc.join("sweep.csv"))?, read(&snake.join("sweep.csv"))?);
    match compare(&a, &b) {
        Ok(n) => {
            let _ = writeln!(
                report,
                "six-point sweep: in-process and Snakemake (--cores 2) give the same sweep.csv ({n} rows, every figure equal; wall times aside)"
            );
        }
        Err(e) => {
            ok = false;
            let _ = writeln!(report, "FAILED: six-point sweep, in-process vs Snakemake: {e}");
        }
    }
    for f in [snake.join("points").join("p002.done"), snake.join("sweep.csv")] {
        std::fs::remove_file(&f).map_err(|e| format!("{}: {e}", f.display()))?;
    }
    let dry = run(Command::new(&snakemake).current_dir(&snake).args(["-n", "all"]))?;
    if job_count(&dry, "point") == Some(1) {
        let _ = writeln!(
            report,
            "a point without its marker (interrupted or killed): `snakemake -n` runs it again, and only it"
        );
    } else {
        ok = false;
        let _ = writeln!(
            report,
            "FAILED: after removing one marker `snakemake -n` lists {:?} point jobs, not 1",
            job_count(&dry, "point")
        );
    }
    for name in ["stability_academic", "stability_impact"] {
        let dir = fresh_dir(&out_root.join(format!("plan-{name}")))?;
        run(Command::new(bin)
            .current_dir(root)
            .arg("sweep")
            .arg(root.join(format!("fixtures/sweeps/{name}.toml")))
            .arg("--out")
            .arg(&dir)
            .arg("--plan-only"))?;
        let points = std::fs::read_dir(dir.join("points")).map_err(|e| format!("{}: {e}", dir.display()))?.count();
        let dry = run(Command::new(&snakemake).current_dir(&dir).args(["-n", "all"]))?;
        let jobs = job_count(&dry, "point");
        if jobs == Some(points) {
            let _ = writeln!(report, "{name}: `snakemake -n` lists {points} point jobs, one per point of the plan");
        } else {
            ok = false;
            let _ = writeln!(report, "FAILED: {name}: `snakemake -n` lists {jobs:?} point jobs for {points} points");
        }
    }
    Ok((ok, report))
}

fn read(p: &Path) -> Result<String, String> {
    std::fs::read_to_string(p).map_err(|e| format!("{}: {e}", p.display()))
}

/// Two sweep.csv texts equal but for their `wall_time_s` column: Ok(rows) or what differs.
fn compare(a: &str, b: &str) -> Result<usize, String> {
    let (la, lb): (Vec<&str>, Vec<&str>) = (a.lines().collect(), b.lines().collect());
    if la.len() != lb.len() {
        return Err(format!("{} lines against {}", la.len(), lb.len()));
    }
    let header: Vec<&str> = la.first().ok_or("an empty sweep.csv")?.split(',').collect();
    let skip = header.iter().position(|c| *c == "wall_time_s");
    for (i, (x, y)) in la.iter().zip(&lb).enumerate() {
        let keep = |l: &str| {
            l.split(',').enumerate().filter(|(j, _)| Some(*j) != skip).map(|(_, f)| f.to_string()).collect::<Vec<_>>()
        };
        if keep(x) != keep(y) {
            return Err(format!("line {}:\n  {x}\n  {y}", i + 1));
        }
    }
    Ok(la.len() - 1)
}

/// The count of `rule` in the job table that `snakemake -n` prints (`point     132`).
fn job_count(text: &str, rule: &str) -> Option<usize> {
    text.lines().find_map(|l| {
        let mut it = l.split_whitespace();
        (it.next() == Some(rule)).then(|| it.next()?.parse().ok()).flatten()
    })
}
