//! `dyncontact-studies`: the developer studies behind the README's charts, run by
//! `cargo xtask bench | stability | bound-at` (release build, outputs under target/).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use dyncontact::error::exit;
use studies::{bench, bound_at, stability};

#[derive(Parser)]
#[command(name = "dyncontact-studies", about = "dyncontact's developer studies (benchmarks, stability map, bound_at)")]
struct Cli {
    #[command(subcommand)]
    study: Study,
}

#[derive(Subcommand)]
enum Study {
    /// Work–precision benchmark: error against a fine reference vs wall time, for schemes ×
    /// inner solvers × masses × refinement levels; the linear-algebra floor; F.1 vs N.4; the
    /// scaling in n_c; the bookkeeping at 66k unknowns.
    Bench {
        /// output folder (default: target/bench)
        #[arg(long)]
        out: Option<PathBuf>,
        /// a small configuration (smoke test)
        #[arg(long)]
        quick: bool,
        /// only the floor part (time per step ÷ floor on the default scene; floor.csv)
        #[arg(long)]
        floor_only: bool,
        /// only the bookkeeping part (the (E.1) terms and outputs at 66k unknowns; bookkeeping.csv)
        #[arg(long)]
        bookkeeping_only: bool,
        /// only the thick 3-D boxes (thick.csv, thick.svg)
        #[arg(long)]
        thick_only: bool,
        /// the thick boxes also at 64×32×24 (158,400 unknowns: minutes of setup and GBs of memory)
        #[arg(long)]
        thick_largest: bool,
        /// the thick boxes also at 80×40×32 and 96×48×32, pressed in the hierarchical form only,
        /// and shaken (the slope past 2,112 contact nodes: up to 465,696 unknowns, ~18 GB, about
        /// an hour and a half)
        #[arg(long)]
        thick_beyond: bool,
    },
    /// Stability map: sweeps of k, ε, the friction decay, the impact speed and θ per scheme,
    /// each run classified (converged, fixed point failed, Newton failed, energy grew, error).
    Stability {
        /// output folder (default: target/stability); its sweeps run in OUT/sweeps/ (OUT/sweeps-quick/ with --quick)
        #[arg(long)]
        out: Option<PathBuf>,
        /// a small sweep (smoke test)
        #[arg(long)]
        quick: bool,
        /// runs at once (default: the number of cores)
        #[arg(long, value_name = "N")]
        jobs: Option<usize>,
    },
    /// Where the friction bound is evaluated: the predictor against u_ν^{n+½} of the iterate,
    /// convergence in k for c_ν = 1e3 … 1e8 on the academic scene and the pulled block.
    BoundAt {
        /// output folder (default: target/bound_at)
        #[arg(long)]
        out: Option<PathBuf>,
        /// two compliances and two levels (smoke test)
        #[arg(long)]
        quick: bool,
    },
}

fn main() -> ExitCode {
    // sequential numerics, as the solver's own command line sets them (its main says why)
    faer::set_global_parallelism(faer::Par::Seq);
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.print();
            return ExitCode::from(if e.use_stderr() { exit::USAGE } else { exit::OK });
        }
    };
    let out = |o: &Option<PathBuf>, default: &str| o.clone().unwrap_or_else(|| PathBuf::from(default));
    let report = match &cli.study {
        Study::Bench { out: o, quick, floor_only, bookkeeping_only, thick_only, thick_largest, thick_beyond } => {
            bench::run(
                &out(o, "target/bench"),
                &bench::BenchOptions {
                    quick: *quick,
                    floor_only: *floor_only,
                    bookkeeping_only: *bookkeeping_only,
                    thick_only: *thick_only,
                    thick_largest: *thick_largest,
                    thick_beyond: *thick_beyond,
                },
            )
        }
        Study::Stability { out: o, quick, jobs } => stability::run(
            &out(o, "target/stability"),
            &stability::StabilityOptions { quick: *quick, jobs: jobs.unwrap_or(0) },
        ),
        Study::BoundAt { out: o, quick } => {
            bound_at::run(&out(o, "target/bound_at"), &bound_at::BoundAtOptions { quick: *quick })
        }
    };
    match report {
        Ok(text) => {
            println!("{text}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}
