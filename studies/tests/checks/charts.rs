//! The studies' charts as a reader sees them: scaling.svg's legend covers none of its lines.

use studies::scaling::{self, ScalingPlan, ScalingRow};

/// A scaling row (the timings of a full `cargo xtask bench` run, rounded).
fn row(contact_nodes: usize, form: &'static str, contact_per_step: f64, floor: f64) -> ScalingRow {
    ScalingRow {
        contact_nodes,
        form,
        steps: 40,
        contact_per_step,
        step_time: 2.0 * contact_per_step,
        floor,
        delassus_setup: 0.0,
        factorizations: 1,
    }
}

/// The y coordinate of every `<text>` element whose content is `label`.
fn text_y(svg: &str, label: &str) -> Vec<f64> {
    svg.split("<text")
        .skip(1)
        .filter(|t| t.split_once('>').is_some_and(|(_, rest)| rest.trim_start().starts_with(label)))
        .filter_map(|t| t.split("y=\"").nth(1)?.split('"').next()?.parse().ok())
        .collect()
}

/// Requirement: scaling.svg's legend lies outside the axes (below the plotting page), so no
/// line of the chart is hidden under it.
#[test]
fn scaling_legend_is_outside_the_axes() {
    let mut rows = vec![row(36, "3-D", 2e-4, 6e-4), row(528, "3-D", 4e-3, 2e-2)];
    for (n, dense, sparse, floor) in
        [(65, 1e-4, 8e-5, 4e-4), (257, 2e-3, 3e-4, 2e-3), (1025, 9e-2, 1.5e-3, 9e-3), (8193, f64::NAN, 1.5e-2, 8e-2)]
    {
        if dense.is_finite() {
            rows.push(row(n, "dense", dense, floor));
        }
        rows.push(row(n, "sparse", sparse, floor));
    }
    let svg = scaling::svg(&rows, &ScalingPlan::full()).expect("scaling.svg");
    let out = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("scaling_check.svg");
    std::fs::write(&out, &svg).expect("write");
    let page = dyncontact::output::style::LOGLOG_CHART.1 as f64;
    for label in ["contact solve, dense W", "contact solve, sparse W", "one A_k solve pair", "3-D: one A_k"] {
        let ys = text_y(&svg, label);
        assert_eq!(ys.len(), 1, "{label}: one legend entry in {}", out.display());
        assert!(ys[0] > page, "{label}: legend at y = {} inside the plotting page (height {page})", ys[0]);
    }
}

/// A thick row of `form` whose median contact solve is `contact` seconds per step.
fn thick_row(cells: [i64; 3], contact_nodes: usize, form: &'static str, contact: f64) -> studies::thick::ThickRow {
    studies::thick::ThickRow {
        cells,
        unknowns: 0,
        contact_nodes,
        form,
        steps: 40,
        free: [contact, contact],
        contact: [contact, contact],
        recovery: [contact, contact],
        pair: contact,
        adjacent: studies::thick::Adjacent { pair: contact, ratio: [1.0; 3] },
        assembly: 0.0,
        factorization: 0.0,
        delassus: 0.0,
        route: "schur",
        delassus_solves: f64::NAN,
        newton_iterations: 0,
        cg_iterations: 0,
        near_density: 0.0,
        h_share: f64::NAN,
        peak_mb: 0.0,
        estimate_mb: 0.0,
        factor_entries: 0,
        fill_order: "nested dissection",
    }
}

/// Requirement: the thick part's slope is fitted over the family's boxes only (the boxes of
/// `--thick-beyond` have their own fit), and the segment slopes are those between neighbouring
/// boxes of one form. Costs n_c^1.5 on the family and n_c^2 past it: the fits return 1.5 and
/// 2 to round-off (1e-12: logarithms of exact powers), the segments the exponent of each.
#[test]
fn thick_slopes_are_fitted_over_the_boxes_they_name() {
    use studies::thick::{ThickPlan, segment_slopes, slope};
    let plan = ThickPlan::full(true).with_beyond();
    let nodes = [312usize, 544, 1200, 2112, 3280, 4704];
    let mut rows = Vec::new();
    for (i, (&cells, &n)) in plan.boxes.iter().chain(&plan.beyond).zip(&nodes).enumerate() {
        // family: 1e-6 n^1.5; beyond: continuous at 2,112, then n^2
        let t = if i < plan.boxes.len() {
            1e-6 * (n as f64).powf(1.5)
        } else {
            1e-6 * 2112f64.powf(1.5) * (n as f64 / 2112.0).powi(2)
        };
        rows.push(thick_row(cells, n, "hierarchical", t));
        if i < plan.boxes.len() {
            rows.push(thick_row(cells, n, "node blocks", 3.0 * t));
        }
    }
    assert!((slope(&rows, "hierarchical", &plan.boxes) - 1.5).abs() < 1e-12);
    assert!((slope(&rows, "node blocks", &plan.boxes) - 1.5).abs() < 1e-12);
    let past: Vec<[i64; 3]> = std::iter::once(plan.boxes[3]).chain(plan.beyond.iter().copied()).collect();
    assert!((slope(&rows, "hierarchical", &past) - 2.0).abs() < 1e-12);
    let seg = segment_slopes(&rows, "hierarchical");
    assert_eq!(seg.len(), 5);
    for (k, &(a, b, s)) in seg.iter().enumerate() {
        assert_eq!((a, b), (nodes[k], nodes[k + 1]));
        assert!((s - if k < 3 { 1.5 } else { 2.0 }).abs() < 1e-12, "segment {a} → {b}: {s}");
    }
}
