//! Bench part 5: what a step costs beyond its solves on a large mesh without contact. The
//! default scene's body at 256 × 128 cells (66,306 unknowns), contact switched off, 200 steps
//! with its outputs (history.csv every step, a VTU frame every 10), run by `run` itself as the
//! CLI runs it; the shares come from summary.json's split: free solve, the operator products of
//! the new state (K u, K v, C v, M v — the next right-hand side reads them), the (E.1) terms and
//! records, and the outputs (what the time loop waits for; frames are encoded on a thread).

use std::fmt::Write as _;
use std::path::Path;

use dyncontact::error::Result;
use dyncontact::output::summary::Timing;
use dyncontact::problem::Problem;
use dyncontact::run::{RunOptions, run};
use dyncontact::scene::Scene;

/// Cells, horizon and repetitions of the part.
pub struct BookkeepingPlan {
    pub cells: [i64; 2],
    pub end: f64,
    pub repeats: usize,
}

impl BookkeepingPlan {
    pub fn full() -> BookkeepingPlan {
        BookkeepingPlan { cells: [256, 128], end: 0.1, repeats: 3 }
    }
    pub fn quick() -> BookkeepingPlan {
        BookkeepingPlan { cells: [32, 16], end: 0.01, repeats: 1 }
    }
}

/// One run's per-step split in seconds.
pub struct BookkeepingRow {
    pub unknowns: usize,
    pub steps: usize,
    pub timing: Timing,
}

impl BookkeepingRow {
    fn per_step(&self, x: f64) -> f64 {
        x / self.steps as f64
    }
    /// A step without setup.
    pub fn step(&self) -> f64 {
        self.per_step(self.timing.total_s - self.timing.setup_s)
    }
    /// (E.1) terms, records and outputs over the step.
    pub fn share(&self) -> f64 {
        self.per_step(self.timing.balance_s + self.timing.output_s) / self.step()
    }
    /// The same with the operator products counted as bookkeeping too.
    pub fn share_with_products(&self) -> f64 {
        self.per_step(self.timing.balance_s + self.timing.output_s + self.timing.products_s) / self.step()
    }
}

/// Run the part into `out`/bookkeeping-run (overwritten each repetition).
pub fn run_part(plan: &BookkeepingPlan, out: &Path) -> Result<Vec<BookkeepingRow>> {
    let mut scene = Scene::default_scene();
    scene.domain.cells = Some(plan.cells.to_vec());
    scene.boundary.contact = Vec::new();
    scene.contact = None;
    scene.time.end = plan.end;
    let p = Problem::from_scene(&scene, Path::new("."))?;
    let opts = RunOptions {
        out: out.join("bookkeeping-run"),
        progress: false,
        checkpoint_every: None,
        resume: false,
        scene_text: None,
        origin: Default::default(),
        stop_after: None,
        interrupt: None,
    };
    (0..plan.repeats)
        .map(|_| {
            let s = run(&p, &opts)?;
            Ok(BookkeepingRow { unknowns: p.dofs.n_free, steps: s.steps_completed, timing: s.timing() })
        })
        .collect()
}

pub fn csv(rows: &[BookkeepingRow]) -> String {
    let mut s = String::from(
        "run,unknowns,steps,step_s,free_solve_s,products_s,balance_s,output_s,share_balance_output,share_with_products\n",
    );
    for (i, r) in rows.iter().enumerate() {
        let t = &r.timing;
        let _ = writeln!(
            s,
            "{i},{},{},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.4},{:.4}",
            r.unknowns,
            r.steps,
            r.step(),
            r.per_step(t.free_solve_s),
            r.per_step(t.products_s),
            r.per_step(t.balance_s),
            r.per_step(t.output_s),
            r.share(),
            r.share_with_products()
        );
    }
    s
}

pub fn report(rows: &[BookkeepingRow]) -> String {
    let pick = |f: &dyn Fn(&BookkeepingRow) -> f64| {
        let mut v: Vec<f64> = rows.iter().map(f).collect();
        v.sort_by(f64::total_cmp);
        (v[0], v[v.len() / 2])
    };
    let (step_min, step_med) = pick(&|r| r.step());
    let (share_min, share_med) = pick(&|r| r.share());
    let (wp_min, wp_med) = pick(&|r| r.share_with_products());
    let (pr_min, pr_med) = pick(&|r| r.per_step(r.timing.products_s));
    let (out_min, out_med) = pick(&|r| r.per_step(r.timing.output_s));
    format!(
        "bookkeeping: {} unknowns without contact, {} steps with outputs, {} runs (min / median): step {:.2} / {:.2} ms; \
         (E.1) terms and outputs {:.1} / {:.1}% of it (outputs {:.3} / {:.3} ms); operator products {:.2} / {:.2} ms \
         (counted as bookkeeping too: {:.1} / {:.1}%)\n",
        rows[0].unknowns,
        rows[0].steps,
        rows.len(),
        1e3 * step_min,
        1e3 * step_med,
        100.0 * share_min,
        100.0 * share_med,
        1e3 * out_min,
        1e3 * out_med,
        1e3 * pr_min,
        1e3 * pr_med,
        100.0 * wp_min,
        100.0 * wp_med
    )
}
