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
