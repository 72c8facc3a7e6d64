//! `cargo xtask bound-at`: where the friction bound is evaluated (S.5, Co.2). For normal
//! compliances c_ν = 1e3 … 1e8, on the academic scene (coarse) and on the pulled block of B.3,
//! each evaluation point — the predictor û = u_ν^n + (k/2) v_ν^n and u_ν^{n+½} of the iterate —
//! is run at three steps k0, k0/2, k0/4 and compared with one fine reference (k0/16, the bound at
//! the iterate): the relative L² error of the tangential impulses over windows of k0 (the
//! midpoint rule's force chatter averages out within a window) and its observed order.
//! Then the block with each compliance against its limit c_ν → ∞, Signorini–Coulomb (compliance
//! 0, g = 0, the total bound), at the same step. Writes bound_at.csv, signorini_limit.csv,
//! bound_at.svg and report.txt.

use std::path::Path;
use std::time::Instant;

use dyncontact::error::{Error, Result};
use dyncontact::model::kinds::{self, BoundAt, FrictionBound};
use dyncontact::problem::Problem;
use dyncontact::scene::{NumOrStr, Scene};

use crate::convergence::{Trajectory, relative_l2, simulate, step_ratio, steps_in, window_means};
use dyncontact::output::csv::csv_table;
use dyncontact::output::loglog::{self, LogSeries, loglog_slope};
use dyncontact::output::write_files;

/// The compliances of the study.
pub const COMPLIANCES: [f64; 6] = [1e3, 1e4, 1e5, 1e6, 1e7, 1e8];

/// Options of the study.
#[derive(Debug, Clone, Default)]
pub struct BoundAtOptions {
    /// two compliances and two levels only (for tests)
    pub quick: bool,
}

/// One scene family of the study.
#[derive(Debug, Clone, Copy)]
struct SceneFamily {
    name: &'static str,
    /// the coarsest step and the horizon
    k0: f64,
    t_end: f64,
}

const CASES: [SceneFamily; 2] =
    [SceneFamily { name: "academic", k0: 1e-3, t_end: 0.4 }, SceneFamily { name: "block", k0: 1e-3, t_end: 0.2 }];

/// One row of bound_at.csv.
#[derive(Debug, Clone)]
pub struct BoundAtRow {
    pub case: &'static str,
    pub compliance: f64,
    pub at: BoundAt,
    pub k: f64,
    /// relative L² error of the tangential impulses over windows of k0
    pub error_tangential: f64,
    pub wall_time_s: f64,
}

const BLOCK_SCENE: &str = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/../fixtures/scenes/sliding_block.toml"));

/// The scene of a case with compliance c, step k and evaluation point `at`.
fn scene(case: &SceneFamily, c: f64, k: f64, at: BoundAt) -> Result<Scene> {
    let mut s = match case.name {
        "academic" => {
            let mut s = Scene::default_scene();
            s.domain.cells = Some([16, 8].to_vec());
            s
        }
        _ => Scene::from_toml(BLOCK_SCENE, "fixtures/scenes/sliding_block.toml")?,
    };
    s.time.end = case.t_end;
    s.time.step = k;
    let contact = s.contact.as_mut().ok_or_else(|| Error::scene("contact", "the study needs a contact section"))?;
    contact.compliance = c;
    if case.name == "block" {
        contact.penetration_bound = NumOrStr::Str("inf".into());
    }
    contact.friction_bound_at = at;
    Ok(s)
}

/// Run one configuration to its end and return its trajectory and wall time.
fn trajectory(case: &SceneFamily, c: f64, k: f64, at: BoundAt) -> Result<(Trajectory, f64)> {
    let clock = Instant::now();
    let p = Problem::from_scene(&scene(case, c, k, at)?, Path::new("."))?;
    let (traj, _) = simulate(&p, &[])?;
    Ok((traj, clock.elapsed().as_secs_f64()))
}

/// Relative L² error of the tangential impulses over windows of `window`.
fn tangential_impulse_error(run: &Trajectory, reference: &Trajectory, window: f64) -> Result<f64> {
    step_ratio(run, reference)?;
    let (a, b) = (
        window_means(&run.forces, steps_in(window, run.k)?),
        window_means(&reference.forces, steps_in(window, reference.k)?),
    );
    Ok(relative_l2(&a, &b)[2])
}

/// The study's rows.
pub fn rows(opts: &BoundAtOptions) -> Result<Vec<BoundAtRow>> {
    let (compliances, levels): (Vec<f64>, usize) =
        if opts.quick { (vec![1e3, 1e7], 2) } else { (COMPLIANCES.to_vec(), 3) };
    let mut rows = Vec::new();
    for case in &CASES {
        for &c in &compliances {
            let (reference, _) = trajectory(case, c, case.k0 / 16.0, BoundAt::Midpoint)?;
            for at in [BoundAt::Predictor, BoundAt::Midpoint] {
                for l in 0..levels {
                    let k = case.k0 / f64::from(1u32 << l);
                    let (traj, wall_time_s) = trajectory(case, c, k, at)?;
                    let error_tangential = tangential_impulse_error(&traj, &reference, case.k0)?;
                    rows.push(BoundAtRow { case: case.name, compliance: c, at, k, error_tangential, wall_time_s });
                }
            }
        }
    }
    Ok(rows)
}

/// The block of B.3 with a stiff compliance against its limit, Signorini–Coulomb (compliance 0,
/// g = 0, the total bound), at the same step: the relative L² distance of the tangential impulses
/// per compliance and evaluation point (the compliance bound μ p(u_ν) tends to μ λ as c_ν → ∞).
#[derive(Debug, Clone)]
pub struct LimitRow {
    pub compliance: f64,
    pub at: BoundAt,
    pub k: f64,
    pub distance: f64,
}

/// The Signorini–Coulomb limit of the block at k0/4 (k0/2 in the quick study).
pub fn signorini_limit(opts: &BoundAtOptions) -> Result<Vec<LimitRow>> {
    let case = &CASES[1];
    let (compliances, k) =
        if opts.quick { (vec![1e3, 1e7], case.k0 / 2.0) } else { (COMPLIANCES.to_vec(), case.k0 / 4.0) };
    let mut limit_scene = scene(case, 0.0, k, BoundAt::Predictor)?;
    if let Some(c) = limit_scene.contact.as_mut() {
        c.penetration_bound = NumOrStr::Num(0.0);
        c.friction_bound = FrictionBound::Total;
    }
    let (limit, _) = simulate(&Problem::from_scene(&limit_scene, Path::new("."))?, &[])?;
    let mut rows = Vec::new();
    for &c in &compliances {
        for at in [BoundAt::Predictor, BoundAt::Midpoint] {
            let (traj, _) = trajectory(case, c, k, at)?;
            rows.push(LimitRow { compliance: c, at, k, distance: tangential_impulse_error(&traj, &limit, case.k0)? });
        }
    }
    Ok(rows)
}

/// bound_at.csv.
pub fn csv(rows: &[BoundAtRow]) -> String {
    csv_table(
        "case,compliance,bound_at,k,error_tangential_impulse,wall_time_s",
        rows.iter().map(|r| {
            vec![
                r.case.to_string(),
                format!("{:e}", r.compliance),
                kinds::name(&r.at),
                format!("{:e}", r.k),
                format!("{:.6e}", r.error_tangential),
                format!("{:.4}", r.wall_time_s),
            ]
        }),
    )
}

/// The rows of one (case, compliance, point) series, in order of k.
fn series<'a>(rows: &'a [BoundAtRow], case: &str, c: f64, at: BoundAt) -> Vec<&'a BoundAtRow> {
    rows.iter().filter(|r| r.case == case && r.compliance == c && r.at == at).collect()
}

/// The observed order in k of a series (least-squares log–log slope).
fn order(s: &[&BoundAtRow]) -> f64 {
    let k: Vec<f64> = s.iter().map(|r| r.k).collect();
    let e: Vec<f64> = s.iter().map(|r| r.error_tangential).collect();
    loglog_slope(&k, &e)
}

/// report.txt: per case and compliance, the errors at the finest k and the orders of both points;
/// then the block's distance to its Signorini–Coulomb limit.
pub fn report(rows: &[BoundAtRow], limit: &[LimitRow], wall_time_s: f64) -> String {
    let mut s = String::from(
        "friction_bound_at study: tangential impulse error against a k0/16 reference (bound at the iterate)\n",
    );
    s.push_str(&format!(
        "{:<9} {:>8} {:>14} {:>8} {:>14} {:>8}\n",
        "case", "c_nu", "predictor err", "order", "midpoint err", "order"
    ));
    for case in &CASES {
        let mut cs: Vec<f64> = rows.iter().filter(|r| r.case == case.name).map(|r| r.compliance).collect();
        cs.dedup();
        for c in cs {
            let (p, m) =
                (series(rows, case.name, c, BoundAt::Predictor), series(rows, case.name, c, BoundAt::Midpoint));
            let last = |v: &[&BoundAtRow]| v.last().map_or(f64::NAN, |r| r.error_tangential);
            s.push_str(&format!(
                "{:<9} {:>8.0e} {:>14.3e} {:>8.2} {:>14.3e} {:>8.2}\n",
                case.name,
                c,
                last(&p),
                order(&p),
                last(&m),
                order(&m)
            ));
        }
    }
    s.push_str("\nblock against Signorini–Coulomb (compliance 0, g = 0, friction_bound = total), same k:\n");
    s.push_str(&format!("{:>8} {:>12} {:>12}\n", "c_nu", "predictor", "midpoint"));
    let mut cs: Vec<f64> = limit.iter().map(|r| r.compliance).collect();
    cs.dedup();
    for c in cs {
        let d = |at: BoundAt| limit.iter().find(|r| r.compliance == c && r.at == at).map_or(f64::NAN, |r| r.distance);
        s.push_str(&format!("{:>8.0e} {:>12.3e} {:>12.3e}\n", c, d(BoundAt::Predictor), d(BoundAt::Midpoint)));
    }
    s.push_str(&format!("wall time {wall_time_s:.1} s\n"));
    s
}

/// bound_at.svg: the error at the finest k against c_ν, per case and evaluation point.
pub fn svg(rows: &[BoundAtRow]) -> Result<String> {
    let finest = |r: &&BoundAtRow| rows.iter().all(|o| o.case != r.case || o.k >= r.k);
    let mut series = Vec::new();
    for case in &CASES {
        for at in [BoundAt::Predictor, BoundAt::Midpoint] {
            series.push(LogSeries {
                name: format!("{}, {}", case.name, kinds::name(&at)),
                points: rows
                    .iter()
                    .filter(finest)
                    .filter(|r| r.case == case.name && r.at == at)
                    .map(|r| (r.compliance, r.error_tangential))
                    .collect(),
            });
        }
    }
    let title = "friction_bound_at: tangential impulse error at the finest k";
    loglog::loglog_chart("bound_at.svg", title, ("compliance c_ν", "relative error"), &series, (1.6, 1.6))
}

/// Run the study and write its files into `out`.
pub fn run(out: &Path, opts: &BoundAtOptions) -> Result<String> {
    let clock = Instant::now();
    let rows = rows(opts)?;
    let limit = signorini_limit(opts)?;
    let report = report(&rows, &limit, clock.elapsed().as_secs_f64());
    let svg = svg(&rows)?;
    let limit_csv = csv_table(
        "compliance,bound_at,k,distance_tangential_impulse",
        limit.iter().map(|r| {
            vec![format!("{:e}", r.compliance), kinds::name(&r.at), format!("{:e}", r.k), format!("{:.6e}", r.distance)]
        }),
    );
    write_files(
        out,
        &[
            ("bound_at.csv", csv(&rows).as_bytes()),
            ("signorini_limit.csv", limit_csv.as_bytes()),
            ("bound_at.svg", svg.as_bytes()),
            ("report.txt", report.as_bytes()),
        ],
    )?;
    Ok(report)
}
