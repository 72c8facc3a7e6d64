//! The contact solve against the number of contact nodes (`cargo xtask bench`, part 4):
//! strips [n, 16] of the academic material and loads (contact on the bottom, n + 1 contact
//! nodes), each run with the dense and the sparse Delassus operator, the dense one only up to
//! where its m³ factorizations stay affordable. Per step: the contact solve, the whole step, and
//! the floor (two A_k solve pairs) for scale; per run: the Delassus setup. The 3-D points: the
//! academic3d box at several resolutions (friction on the disk, the contact solve `auto`).

use std::fmt::Write as _;
use std::path::Path;

use dyncontact::error::Result;
use dyncontact::model::kinds::ContactSolve;
use dyncontact::problem::Problem;
use dyncontact::scene::Scene;

use crate::convergence::simulate;
use dyncontact::output::csv::csv_table;
use dyncontact::output::loglog::{self, LogSeries, loglog_slope};

/// What the scaling part runs.
#[derive(Debug, Clone)]
pub struct ScalingPlan {
    /// cells along the strip (n + 1 contact nodes)
    pub ns: Vec<i64>,
    /// the dense form runs up to this n
    pub dense_max: i64,
    pub k: f64,
    pub steps: usize,
    /// the 3-D points: the academic3d box at these cells, `steps_3d` steps of its own k = 5e-4
    /// (pressing, half the nodes slipping outward, then shaken from 0.2 s), contact solve `auto`
    pub boxes: Vec<[i64; 3]>,
    pub steps_3d: usize,
}

impl ScalingPlan {
    /// 65 to 8,193 contact nodes, 40 steps of 5e-4 (the load presses the strip on; the dense
    /// form up to 1,025 nodes, where one run already costs ~25 s); 3-D boxes with 36 to 528
    /// contact nodes over 0.3 s (600 steps: pressing, then shaking).
    pub fn full() -> ScalingPlan {
        ScalingPlan {
            ns: vec![64, 128, 256, 512, 1024, 2048, 4096, 8192],
            dense_max: 1024,
            k: 5e-4,
            steps: 40,
            boxes: vec![[8, 4, 4], [16, 8, 4], [24, 12, 8], [32, 16, 8]],
            steps_3d: 600,
        }
    }
    pub fn quick() -> ScalingPlan {
        ScalingPlan { ns: vec![64, 128], dense_max: 128, k: 5e-4, steps: 5, boxes: vec![[8, 4, 4]], steps_3d: 5 }
    }
}

/// One strip run.
pub struct ScalingRow {
    pub contact_nodes: usize,
    pub form: &'static str,
    pub steps: usize,
    pub contact_per_step: f64,
    pub step_time: f64,
    pub floor: f64,
    pub delassus_setup: f64,
    pub factorizations: usize,
}

/// The strip [n, 16] of size [n/16, 1]: h = 1/16 as in the academic scene.
fn strip(n: i64, plan: &ScalingPlan, form: ContactSolve) -> Scene {
    let mut s = Scene::default_scene();
    s.name = format!("strip_{n}");
    s.domain.size = Some([n as f64 / 16.0, 1.0].to_vec());
    s.domain.cells = Some([n, 16].to_vec());
    s.time.step = plan.k;
    s.time.end = plan.k * plan.steps as f64;
    s.solver.contact_solve = form;
    s
}

/// One run of `scene`, as a row labelled `form`.
fn measure(scene: &Scene, form: &'static str) -> Result<ScalingRow> {
    let p = Problem::from_scene(scene, Path::new("."))?;
    let (_, st) = simulate(&p, &[])?;
    let steps = st.steps as f64;
    Ok(ScalingRow {
        contact_nodes: p.contact.as_ref().map_or(0, |c| c.n()),
        form,
        steps: st.steps,
        contact_per_step: st.contact_time_s / steps,
        step_time: st.step_time_s / steps,
        floor: st.floor_s,
        delassus_setup: st.setup_delassus_s,
        factorizations: st.factorizations,
    })
}

/// The academic3d box at `cells`, `steps` steps.
fn box3d(cells: [i64; 3], steps: usize) -> Result<Scene> {
    let mut s = Scene::from_toml(include_str!("../../fixtures/scenes/academic3d.toml"), "academic3d.toml")?;
    s.name = format!("box_{}x{}x{}", cells[0], cells[1], cells[2]);
    s.domain.cells = Some(cells.to_vec());
    s.time.end = s.time.step * steps as f64;
    Ok(s)
}

/// Run every strip with both forms (the dense one up to `dense_max`), then the 3-D boxes.
pub fn run(plan: &ScalingPlan, progress: &dyn Fn(&str)) -> Result<Vec<ScalingRow>> {
    let mut rows = Vec::new();
    for &cells in &plan.boxes {
        progress(&format!("scaling: 3-D box {}x{}x{}", cells[0], cells[1], cells[2]));
        rows.push(measure(&box3d(cells, plan.steps_3d)?, "3-D")?);
    }
    for &n in &plan.ns {
        for (form, name) in [(ContactSolve::Dense, "dense"), (ContactSolve::Sparse, "sparse")] {
            if form == ContactSolve::Dense && n > plan.dense_max {
                continue;
            }
            progress(&format!("scaling: {} contact nodes, {name}", n + 1));
            rows.push(measure(&strip(n, plan, form), name)?);
        }
    }
    Ok(rows)
}

/// scaling.csv.
pub fn csv(rows: &[ScalingRow]) -> String {
    csv_table(
        "contact_nodes,form,steps,contact_per_step_s,step_time_s,floor_s,contact_over_free,delassus_setup_s,factorizations",
        rows.iter().map(|r| {
            vec![
                r.contact_nodes.to_string(),
                r.form.to_string(),
                r.steps.to_string(),
                format!("{:.6e}", r.contact_per_step),
                format!("{:.6e}", r.step_time),
                format!("{:.6e}", r.floor),
                format!("{:.3}", r.contact_per_step / (0.5 * r.floor)),
                format!("{:.6e}", r.delassus_setup),
                r.factorizations.to_string(),
            ]
        }),
    )
}

fn points(rows: &[ScalingRow], form: &str, value: fn(&ScalingRow) -> f64) -> Vec<(f64, f64)> {
    rows.iter().filter(|r| r.form == form).map(|r| (r.contact_nodes as f64, value(r))).collect()
}

/// The log–log slope of the sparse contact solve per step against n_c, over the whole range and
/// from 513 contact nodes on.
pub fn sparse_slopes(rows: &[ScalingRow]) -> (f64, f64) {
    let pts = points(rows, "sparse", |r| r.contact_per_step);
    let fit = |p: &[(f64, f64)]| {
        let (x, y): (Vec<f64>, Vec<f64>) = p.iter().copied().unzip();
        if x.len() >= 2 { loglog_slope(&x, &y) } else { f64::NAN }
    };
    let large: Vec<(f64, f64)> = pts.iter().copied().filter(|p| p.0 >= 513.0).collect();
    (fit(&pts), fit(&large))
}

/// scaling.svg: contact solve per step for both forms, the free solve (half the floor) for scale.
pub fn svg(rows: &[ScalingRow], plan: &ScalingPlan) -> Result<String> {
    let series = vec![
        LogSeries { name: "contact solve, dense W".into(), points: points(rows, "dense", |r| r.contact_per_step) },
        LogSeries { name: "contact solve, sparse W".into(), points: points(rows, "sparse", |r| r.contact_per_step) },
        LogSeries { name: "one A_k solve pair (free solve)".into(), points: points(rows, "sparse", |r| 0.5 * r.floor) },
        LogSeries {
            name: format!("contact solve, 3-D box (friction on the disk, {} steps)", plan.steps_3d),
            points: points(rows, "3-D", |r| r.contact_per_step),
        },
        LogSeries { name: "3-D: one A_k solve pair".into(), points: points(rows, "3-D", |r| 0.5 * r.floor) },
    ];
    let title = format!("contact solve per step, strips [n, 16] ({} steps of {}) and 3-D boxes", plan.steps, plan.k);
    loglog::loglog_chart("scaling.svg", &title, ("contact nodes n_c", "seconds per step"), &series, (1.3, 2.0))
}

/// The printed lines of the scaling part.
pub fn report(rows: &[ScalingRow]) -> String {
    let mut s = String::from(
        "scaling: strips [n, 16] and 3-D boxes (form \"3-D\"), contact solve per step against the contact nodes\n",
    );
    let _ = writeln!(
        s,
        "{:>8} {:<7} {:>12} {:>12} {:>14} {:>12} {:>8}",
        "n_c", "form", "contact[ms]", "free[ms]", "contact/free", "W setup[s]", "factors"
    );
    for r in rows {
        let _ = writeln!(
            s,
            "{:>8} {:<7} {:>12.3} {:>12.3} {:>14.2} {:>12.3} {:>8}",
            r.contact_nodes,
            r.form,
            1e3 * r.contact_per_step,
            1e3 * 0.5 * r.floor,
            r.contact_per_step / (0.5 * r.floor),
            r.delassus_setup,
            r.factorizations
        );
    }
    let (all, large) = sparse_slopes(rows);
    let _ = writeln!(
        s,
        "sparse contact solve per step: log–log slope {all:.2} over the range, {large:.2} from 513 contact nodes on"
    );
    s
}
