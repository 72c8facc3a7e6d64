//! What the studies share: CSV fields, least-squares log–log slopes, chart ranges and errors,
//! and writing a study's files.

use std::path::Path;

use crate::error::{Error, Result};
use crate::output::write_atomic;

/// Least-squares slope of log10(y) against log10(x) over the positive pairs (NaN with fewer
/// than two).
pub fn loglog_slope(x: &[f64], y: &[f64]) -> f64 {
    let pts: Vec<(f64, f64)> = x.iter().zip(y).filter(|(a, b)| **a > 0.0 && **b > 0.0).map(|(a, b)| (a.log10(), b.log10())).collect();
    let n = pts.len() as f64;
    if pts.len() < 2 {
        return f64::NAN;
    }
    let (mx, my) = (pts.iter().map(|p| p.0).sum::<f64>() / n, pts.iter().map(|p| p.1).sum::<f64>() / n);
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    sxy / sxx
}

/// A CSV field: one line, quoted (RFC 4180) when it holds a comma or a quote.
pub fn csv_field(s: &str) -> String {
    let one_line = s.replace(['\n', '\r'], " ");
    if one_line.contains([',', '"']) { format!("\"{}\"", one_line.replace('"', "\"\"")) } else { one_line }
}

/// A CSV table: the header line, then one line per row of already formatted fields.
pub fn csv_table(header: &str, rows: impl IntoIterator<Item = Vec<String>>) -> String {
    let mut s = format!("{header}\n");
    for r in rows {
        s.push_str(&r.join(","));
        s.push('\n');
    }
    s
}

/// The error of a chart named `file`.
pub fn chart_error(file: &'static str) -> impl Fn(&dyn std::fmt::Display) -> Error {
    move |e| Error::Output(format!("{file}: {e}"))
}

/// A padded log-scale range of the positive finite values (a decade when there are none).
pub fn log_range(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = vals.filter(|v| v.is_finite() && *v > 0.0).fold((f64::INFINITY, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
    if lo.is_finite() { (lo / 1.6, hi * 1.6) } else { (0.1, 1.0) }
}

/// Write a study's files into `dir` (created), each atomically.
pub fn write_files(dir: &Path, files: &[(&str, &[u8])]) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    for (name, bytes) in files {
        write_atomic(&dir.join(name), bytes)?;
    }
    Ok(())
}
