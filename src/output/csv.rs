//! CSV text: fields quoted as RFC 4180 asks, tables of formatted rows (history.csv, sweep.csv and
//! the studies' tables all go through here).

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
