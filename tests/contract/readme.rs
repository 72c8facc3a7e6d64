//! (issue 24, item 10) The README's output tables are the outputs: every history.csv and
//! contact.csv column is listed with the unit summary.json's `model.units` gives it in 2-D and
//! 3-D, every VTU array a frame holds is listed, and every key a run's summary.json has is named.
//! Read from README.md itself, so a column added without its row fails here.

use std::collections::BTreeSet;
use std::path::PathBuf;

use dyncontact::output::units::Units;
use dyncontact::output::{HISTORY, contact_columns};
use dyncontact::run::{RunOptions, run};

use crate::common::{fixture, problem, root};

/// The README's "Outputs" section.
fn outputs_section() -> String {
    let readme = std::fs::read_to_string(root().join("README.md")).expect("README.md");
    let start = readme.find("## Outputs").expect("an Outputs section");
    let end = start + readme[start..].find("### The run folder").expect("the run folder after it");
    readme[start..end].to_string()
}

/// The rows of the table that follows `title` (a bold line): each row's cells, trimmed.
fn table_after(section: &str, title: &str) -> Vec<Vec<String>> {
    let at = section.find(title).unwrap_or_else(|| panic!("no {title} in Outputs"));
    section[at..]
        .lines()
        .skip_while(|l| !l.starts_with('|'))
        .take_while(|l| l.starts_with('|'))
        .skip(2)
        .map(|l| l.trim_matches('|').split(" | ").map(|c| c.trim().to_string()).collect())
        .collect()
}

/// The backticked names of a cell: "`a`, `b`" → [a, b].
fn names(cell: &str) -> Vec<String> {
    cell.split('`').skip(1).step_by(2).map(str::to_string).collect()
}

/// Requirement: every history.csv column has exactly one row in the README's table, and its
/// 2-D and 3-D units are those of `Units::of(2)` and `Units::of(3)` ("1" for counts).
#[test]
fn history_table_lists_every_column_with_its_units() {
    let rows = table_after(&outputs_section(), "**history.csv**");
    let (u2, u3) = (Units::of(2), Units::of(3));
    for (name, _) in HISTORY {
        let hits: Vec<&Vec<String>> = rows.iter().filter(|r| names(&r[0]).iter().any(|n| n == name)).collect();
        assert_eq!(hits.len(), 1, "history.csv `{name}`: {} rows in the README's table", hits.len());
        let row = hits[0];
        assert_eq!(Some(row[1].as_str()), u2.history_unit(name), "`{name}` in 2-D");
        assert_eq!(Some(row[2].as_str()), u3.history_unit(name), "`{name}` in 3-D");
    }
    let listed: BTreeSet<String> = rows.iter().flat_map(|r| names(&r[0])).collect();
    let real: BTreeSet<String> = HISTORY.iter().map(|(n, _)| n.to_string()).collect();
    assert_eq!(listed, real, "the README lists columns history.csv does not have, or misses some");
}

/// Requirement: every contact.csv column of either dimension has one row with its unit ("—"
/// for `status`, a word), and the header lines quoted above the table are the files' headers.
#[test]
fn contact_table_lists_every_column_with_its_unit() {
    let section = outputs_section();
    let rows = table_after(&section, "**contact.csv**");
    for dim in [2, 3] {
        let units = Units::of(dim);
        assert!(section.contains(&format!("`{}`", contact_columns(dim))), "the {dim}-D header is quoted");
        for name in contact_columns(dim).split(',') {
            let hits: Vec<&Vec<String>> = rows.iter().filter(|r| names(&r[0]).iter().any(|n| n == name)).collect();
            assert_eq!(hits.len(), 1, "contact.csv `{name}`: {} rows", hits.len());
            let want = units.contact_unit(name).unwrap_or("—");
            assert_eq!(hits[0][1], want, "contact.csv `{name}` in {dim}-D");
        }
    }
}

/// Requirement: every array of a 3-D frame (with friction) is in the frames table with its
/// location (points or cells), and every top-level key of that run's summary.json is named in
/// the summary paragraph.
#[test]
fn frame_arrays_and_summary_keys_are_listed() {
    let mut scene = fixture("sliding_block3d");
    scene.time.end = 0.02;
    let p = problem(scene);
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("readme_outputs");
    let _ = std::fs::remove_dir_all(&out);
    run(&p, &RunOptions { out: out.clone(), progress: false, ..RunOptions::default() }).expect("run");
    let section = outputs_section();
    let rows = table_after(&section, "**Frames**");
    let frame = std::fs::read_to_string(out.join("frames/frame_00000.vtu")).expect("frame 0");
    for (data, place) in [("PointData", "points"), ("CellData", "cells")] {
        let open = frame.find(&format!("<{data}")).unwrap_or_else(|| panic!("{data}"));
        let close = frame.find(&format!("</{data}>")).expect("closed");
        for name in frame[open..close].split("Name=\"").skip(1).map(|s| &s[..s.find('"').expect("quote")]) {
            let row = rows.iter().find(|r| names(&r[0]) == [name]).unwrap_or_else(|| panic!("VTU `{name}` not listed"));
            assert_eq!(row[1], place, "VTU `{name}`");
        }
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).expect("summary")).expect("json");
    let para = &section[section.find("**summary.json**").expect("summary paragraph")..];
    let missing: Vec<&String> =
        summary.as_object().expect("an object").keys().filter(|k| !para.contains(&format!("`{k}`"))).collect();
    assert!(missing.is_empty(), "summary.json keys the README does not name: {missing:?}");
}
