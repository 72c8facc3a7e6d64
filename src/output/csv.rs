//! CSV text: fields quoted as RFC 4180 asks, tables of formatted rows (history.csv, sweep.csv and
//! the studies' tables all go through here).

/// A real number as CSV text: the shortest form that reads back to the same f64 (Rust's
/// shortest round-trip digits), plain for 1e-5 ≤ |x| < 1e16 and with an exponent outside, so a
/// value like 4.7e-39 is 9 characters instead of 44 zeros (the rule of Python's `repr`).
/// Every CSV reader (Python's float, numpy, pandas, Rust's parse) reads both forms. A zero of
/// either sign is `0`: a force or slip that is exactly zero carries no direction, and `-0` in a
/// table reads as a sign that is not there.
pub fn real(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 {
        "0".into()
    } else if !x.is_finite() || (1e-5..1e16).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// The f64 that [`real`]'s text of x reads back as: x itself, but a zero without its sign
/// (−0.0 + 0.0 is +0.0 in IEEE arithmetic; every other x is unchanged). In-memory copies of the
/// tables (Python's `run(out=None)`) hold these, so they equal the files bit for bit.
pub fn as_written(x: f64) -> f64 {
    x + 0.0
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
