//! `dyncontact-studies bench --quick`: the benchmark runs end to end and writes its CSV and SVG
//! files with the documented columns and one row per run.

use studies::bench::{self, BenchOptions};

const WORK_COLUMNS: [&str; 14] = [
    "scheme",
    "inner",
    "mass",
    "cells",
    "k",
    "steps",
    "wall_time_s",
    "time_per_step_s",
    "floor_s",
    "ratio_to_floor",
    "error_force",
    "error_disp",
    "newton_iterations",
    "fixed_point_iterations",
];

const RACE_COLUMNS: [&str; 6] =
    ["case", "method", "time_per_step_s", "newton_iterations_per_step", "unfrozen_steps", "fallback_steps"];

/// The rows of a CSV file as maps from column name to field.
fn read_csv(path: &std::path::Path) -> (Vec<String>, Vec<std::collections::HashMap<String, String>>) {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().expect("a header").split(',').map(str::to_string).collect();
    let rows = lines
        .map(|l| {
            let fields: Vec<&str> = l.split(',').collect();
            assert_eq!(fields.len(), header.len(), "{}: row {l:?} does not match the header", path.display());
            header.iter().cloned().zip(fields.into_iter().map(str::to_string)).collect()
        })
        .collect();
    (header, rows)
}

fn number(row: &std::collections::HashMap<String, String>, col: &str) -> f64 {
    row[col].parse().unwrap_or_else(|e| panic!("{col} = {:?}: {e}", row[col]))
}

/// The quick benchmark writes work_precision.csv/svg (3 schemes × 2 masses × 2 levels, newton
/// only, every run successful with finite positive errors and a floor below the step time) and
/// race.csv/svg (both methods on every case).
#[test]
fn quick_bench_writes_its_files() {
    let dir = std::env::temp_dir().join(format!("dyncontact-bench-smoke-{}", std::process::id()));
    let report =
        bench::run(&dir, &BenchOptions { quick: true, ..BenchOptions::default() }).expect("the quick benchmark runs");
    assert!(report.contains("work–precision") && report.contains("race"), "{report}");

    // the thick 3-D boxes: the three forms on every box, in velocity form (a near field keeping
    // a small share of W⁻¹ in the hierarchical and near-field rows, none in the node-block rows;
    // the hierarchical rows store less than the dense W⁻¹, the others nothing of the kind)
    let (_, rows) = read_csv(&dir.join("thick.csv"));
    assert_eq!(rows.len(), 2 * 3, "two boxes × three forms");
    for r in &rows {
        let density = number(r, "near_density");
        match r["form"].as_str() {
            "hierarchical" => {
                assert!(density > 0.0 && density < 0.5, "{r:?}");
                let share = number(r, "h_share");
                assert!(share > 0.0 && share <= 1.0, "{r:?}");
            }
            "near field" => assert!(density > 0.0 && density < 0.5 && r["h_share"].is_empty(), "{r:?}"),
            "node blocks" => assert!(density == 0.0 && r["h_share"].is_empty(), "{r:?}"),
            other => panic!("form {other}"),
        }
        assert!(number(r, "cg_iterations") > 0.0 && number(r, "contact_median_s") > 0.0, "{r:?}");
        // the run's peak and `check`'s estimate of it, side by side (not compared here: other
        // tests share this process's memory)
        assert!(number(r, "peak_mb") > 0.0 && number(r, "estimate_mb") > 0.0, "{r:?}");
        adjacent_pairs_are_ordered(r);
    }
    assert!(dir.join("thick.svg").is_file());

    // the shaking window: one row per run from the same state, at academic3d's step scaled
    // with the cell height (16×8×4: 5e-4, inside (C.k)); F.1 makes at least one convex solve per
    // frictional step, from the root (inside (C.k), 432 contact unknowns) usually exactly one;
    // N.4 none where it solved the step itself (a fallback to F.1 is counted and makes them again)
    let (_, rows) = read_csv(&dir.join("thick_shaking.csv"));
    let inners: Vec<&str> = rows.iter().map(|r| r["inner"].as_str()).collect();
    assert_eq!(inners, ["newton-predictor", "newton", "newton-unfrozen"], "one box × three runs");
    // the root start takes fewer convex solves than the predictor's (without it, the same path)
    assert!(number(&rows[1], "convex_solves") < number(&rows[0], "convex_solves"), "{rows:?}");
    for r in &rows {
        let steps = number(r, "steps");
        assert!(steps == 3.0 && number(r, "newton_iterations") >= steps, "{r:?}");
        assert_eq!(number(r, "step_s"), 5e-4, "{r:?}");
        assert!(number(r, "slip_nodes") + number(r, "stick_nodes") > 0.0, "the box is in contact: {r:?}");
        let (convex, fallbacks) = (number(r, "convex_solves"), number(r, "fallbacks"));
        match r["inner"].as_str() {
            "newton-predictor" => assert!(convex >= steps && fallbacks == 0.0, "{r:?}"),
            "newton" => assert!(convex >= steps && fallbacks == 0.0, "{r:?}"),
            _ => assert!((convex == 0.0) == (fallbacks == 0.0), "{r:?}"),
        }
        adjacent_pairs_are_ordered(r);
    }

    // the box run as a user runs it (academic3d's own k and solver, `auto`): one row, its 3
    // steps all pressing (the shaking starts at 0.2 s, so the shaken means are empty: NaN), the
    // issue's ratio being the two means' (printed to 3 decimals, ±5e-4, and recomputed here
    // from means printed to 7 digits, ≤ 1e-6 of the ratio: 1e-3 covers both)
    let (_, rows) = read_csv(&dir.join("thick_run.csv"));
    assert_eq!(rows.len(), 1, "one box");
    let r = &rows[0];
    assert!(number(r, "steps") == 3.0 && number(r, "step_s") == 5e-4, "{r:?}");
    let (free, contact) = (number(r, "free_mean_s"), number(r, "contact_mean_s"));
    assert!(free > 0.0 && contact > 0.0, "{r:?}");
    assert!((number(r, "contact_over_free") - contact / free).abs() <= 1e-3, "{r:?}");
    assert_eq!(number(r, "pressed_contact_mean_s"), contact, "every step is pressed: {r:?}");
    assert!(number(r, "shaken_contact_mean_s").is_nan(), "{r:?}");
    assert!(number(r, "newton_iterations") >= 3.0 && number(r, "convex_solves") >= 3.0, "{r:?}");
    assert!(number(r, "pair_median_s") > 0.0 && number(r, "peak_mb") > 0.0, "{r:?}");

    let (header, rows) = read_csv(&dir.join("work_precision.csv"));
    for c in WORK_COLUMNS {
        assert!(header.iter().any(|h| h == c), "work_precision.csv lacks column {c}");
    }
    assert_eq!(rows.len(), 3 * 2 * 2, "one row per run");
    for r in &rows {
        assert_eq!(r["inner"], "newton");
        assert_eq!(r["status"], "ok", "{r:?}");
        // timings are measured here, not asserted (two timings taken at different moments of a
        // loaded machine have no fixed ratio: 0.37 was seen against a floor of two solve pairs)
        for c in ["error_force", "error_disp", "wall_time_s", "floor_s", "ratio_to_floor"] {
            let v = number(r, c);
            assert!(v.is_finite() && v > 0.0, "{c} = {v} in {r:?}");
        }
        assert_eq!(number(r, "steps"), (0.05 / number(r, "k")).round());
    }

    let (header, rows) = read_csv(&dir.join("race.csv"));
    for c in RACE_COLUMNS {
        assert!(header.iter().any(|h| h == c), "race.csv lacks column {c}");
    }
    assert!(!rows.is_empty() && rows.len() % 2 == 0, "two methods per case");
    assert!(rows.iter().any(|r| r["method"] == "newton") && rows.iter().any(|r| r["method"] == "newton-unfrozen"));
    assert!(rows.iter().any(|r| r["inside_ck"] == "yes"), "a case inside (C.k)");

    let (header, rows) = read_csv(&dir.join("bookkeeping.csv"));
    assert!(header.iter().any(|h| h == "share_balance_output") && !rows.is_empty(), "bookkeeping.csv");
    for r in &rows {
        let share = number(r, "share_balance_output");
        assert!(share > 0.0 && share < 1.0, "a share of the step: {r:?}");
    }

    // the 3-D rows of part 2 and the 3-D points of part 4
    let (header, rows) = read_csv(&dir.join("floor3d.csv"));
    assert!(
        header.iter().any(|h| h == "ratio_to_floor") && header.iter().any(|h| h == "contact_nodes"),
        "floor3d.csv columns"
    );
    assert!(
        rows.iter().any(|r| r["scene"] == "academic3d") && rows.iter().any(|r| r["scene"] == "sliding_block3d"),
        "floor3d.csv rows"
    );
    let (_, rows) = read_csv(&dir.join("scaling.csv"));
    assert!(
        rows.iter().any(|r| r["form"] == "3-D" && number(r, "contact_per_step_s") > 0.0),
        "a 3-D point in scaling.csv"
    );

    for svg in ["work_precision.svg", "race.svg", "scaling.svg"] {
        let text = std::fs::read_to_string(dir.join(svg)).expect(svg);
        assert!(text.starts_with("<svg") && text.contains("</svg>"), "{svg} is not an SVG document");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A thick row's pairs timed after each step: a positive median pair, and the step-by-step
/// ratios of the contact solve to it ordered min ≤ median ≤ max, all positive.
fn adjacent_pairs_are_ordered(r: &std::collections::HashMap<String, String>) {
    assert!(number(r, "adjacent_pair_median_s") > 0.0, "{r:?}");
    let [min, median, max] = ["min", "median", "max"].map(|q| number(r, &format!("contact_over_adjacent_pair_{q}")));
    assert!(0.0 < min && min <= median && median <= max, "{r:?}");
}
