//! `DIR/Snakefile` and `DIR/config.yaml`: the same points as Snakemake jobs, so a workstation
//! (`snakemake --cores N`) or a cluster (`snakemake --executor slurm --jobs 200`, README) runs the
//! sweep and `dyncontact sweep collect .` gathers the same sweep.csv. One rule runs one point
//! (`dyncontact sweep point points/<id>`, the in-process sweep's code), whose output is the
//! marker `points/<id>.done` that only a final outcome writes (completed, or a failure that a
//! rerun would repeat, recorded in the point's summary.json): an interrupted or killed point has
//! none, so Snakemake runs it again. One rule collects. config.yaml names the command that runs
//! `dyncontact` (the CLI's binary, or the Python package's `python -m dyncontact`) and each
//! point's resources: `mem_mb` from `check`'s memory estimate (×1.5 + 100 MB of headroom) and a
//! conservative `runtime` in minutes.
//!
//! No user text reaches the Snakefile but the sweep's name, which is a safe name (letters,
//! digits, `._-+`); the command is quoted for the shell by Snakemake (`:q`, word by word for a
//! list) and written in config.yaml as a JSON string or list of strings (valid YAML, every
//! character escaped).

use std::fmt::Write as _;
use std::path::Path;

use super::Plan;
use crate::error::Result;
use crate::output::write_atomic;

/// The Snakefile (the same for every sweep but its header).
pub fn snakefile(plan: &Plan) -> String {
    format!(
        r#"# Written by `dyncontact sweep` for the sweep "{name}" ({n} points): one job per point
# (`dyncontact run` into points/<id>), then `dyncontact sweep collect .` writes sweep.csv and plots/.
#   on this machine:  snakemake --cores 2
#   on a cluster:     snakemake --profile profiles/slurm   (executor: slurm; README, "Sweeps")
configfile: "config.yaml"

POINTS = list(config["points"])

# the collector and the target run where Snakemake runs, not as cluster jobs
localrules: all, collect


rule all:
    input:
        "sweep.csv",


rule point:
    input:
        "points/{{point}}/scene.toml",
    output:
        # written only by a final outcome (completed, or a failure a rerun would repeat)
        "points/{{point}}.done",
    log:
        "points/{{point}}.log",
    resources:
        mem_mb=lambda wildcards: config["points"][wildcards.point]["mem_mb"],
        runtime=lambda wildcards: config["points"][wildcards.point]["runtime"],
    shell:
        "{{config[dyncontact]:q}} sweep point points/{{wildcards.point}} > {{log:q}} 2>&1"


rule collect:
    input:
        expand("points/{{point}}.done", point=POINTS),
    output:
        "sweep.csv",
    shell:
        "{{config[dyncontact]:q}} sweep collect ."
"#,
        name = plan.name,
        n = plan.points.len()
    )
}

/// config.yaml: the command that runs `dyncontact` (the binary that wrote the sweep — edit it
/// where the cluster's copy lives — as a string; a command of several words, such as the Python
/// package's `[python, "-m", "dyncontact"]`, as a list, which Snakemake quotes word by word) and
/// each point's resources.
pub fn config(plan: &Plan, launcher: &[String]) -> String {
    let mut s =
        String::from("# written by `dyncontact sweep`: the command that runs a point, and each point's resources\n");
    s.push_str("# (mem_mb: the memory estimate of `dyncontact check`; runtime: minutes, a conservative bound)\n");
    // a JSON string is a YAML double-quoted scalar with every special character escaped
    let command = match launcher {
        // no command given: `dyncontact` on the PATH
        [] => serde_json::to_string("dyncontact"),
        [binary] => serde_json::to_string(binary),
        words => serde_json::to_string(words),
    };
    let _ = writeln!(s, "dyncontact: {}", command.unwrap_or_else(|_| "\"dyncontact\"".into()));
    s.push_str("points:\n");
    for p in &plan.points {
        let _ = writeln!(s, "  {}: {{mem_mb: {}, runtime: {}}}", p.id, p.mem_mb, p.runtime_min);
    }
    s
}

/// Write DIR/Snakefile and DIR/config.yaml; `launcher`: the command that runs `dyncontact`
/// ([`this_executable`] for the CLI).
pub fn write(plan: &Plan, dir: &Path, launcher: &[String]) -> Result<()> {
    write_atomic(&dir.join("Snakefile"), snakefile(plan).as_bytes())?;
    write_atomic(&dir.join("config.yaml"), config(plan, launcher).as_bytes())
}

/// This process's executable as the command that runs `dyncontact` — for a test binary
/// (target/<profile>/deps/…), the CLI built beside it when there is one. Not for a process that
/// is not the CLI (the Python interpreter): the Python package gives its own command.
pub fn this_executable() -> Vec<String> {
    let binary = std::env::current_exe().map(|p| p.display().to_string()).unwrap_or_else(|_| "dyncontact".into());
    vec![cli_beside(&binary).unwrap_or(binary)]
}

/// The `dyncontact` executable of the build a test binary (target/<profile>/deps/…) belongs to.
fn cli_beside(exe: &str) -> Option<String> {
    let p = Path::new(exe);
    if p.file_stem()?.to_str()? == "dyncontact" {
        return None;
    }
    let profile = p.parent()?.parent()?;
    let cli = profile.join(if cfg!(windows) { "dyncontact.exe" } else { "dyncontact" });
    cli.is_file().then(|| cli.display().to_string())
}
