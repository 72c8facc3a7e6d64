//! The one chart style of plots/, the ε-study and the developer studies: colours (series and
//! contact statuses), fonts, page sizes and the tick rules (how an axis reads its numbers).
//! Every chart takes these from here, so two charts showing the same thing look the same.

use plotters::style::RGBColor;

/// The font family of every chart.
pub const FONT: &str = "sans-serif";
/// Font size of a page's caption.
pub const CAPTION: i32 = 20;
/// Font size of a sub-chart's caption (a stacked panel, the deformed mesh).
pub const SUBCAPTION: i32 = 18;
/// Font size of a small panel's caption (one map of a grid).
pub const PANEL_CAPTION: i32 = 16;
/// Font size of a hand-drawn legend's text.
pub const LEGEND: i32 = 14;
/// Font size of dense labels (bar names).
pub const SMALL: i32 = 12;
/// Font size of the densest labels (rotated bar names).
pub const TINY: i32 = 11;

/// The chart font at `size` (one of the sizes above).
pub const fn font(size: i32) -> (&'static str, i32) {
    (FONT, size)
}

/// A line chart's page (one panel).
pub const LINE_CHART: (u32, u32) = (960, 540);
/// The height of a page of two stacked panels.
pub const TWO_PANELS_HEIGHT: u32 = 720;
/// The height per panel of a page of three or more stacked panels.
pub const PANEL_HEIGHT: u32 = 260;
/// A log–log chart's plotting page (its legend is added below).
pub const LOGLOG_CHART: (u32, u32) = (900, 560);
/// The status map's page: the map's width, then the legend column beside it.
pub const STATUS_MAP: (u32, u32) = (1100, 600);
/// The width of the map part of a status map's page (the rest is the legend).
pub const STATUS_MAP_WIDTH: u32 = 800;
/// The deformed mesh's page width (its height follows the mesh's aspect).
pub const DEFORMED_WIDTH: u32 = 960;
/// The height of one line of a hand-drawn legend.
pub const LEGEND_ROW: i32 = 22;

/// The colours of successive series (matplotlib's tab10).
pub const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

/// tab10's olive (the ninth colour), for a ninth category.
pub const OLIVE: RGBColor = RGBColor(188, 189, 34);
/// The undeformed outline and other context lines.
pub const OUTLINE: RGBColor = RGBColor(160, 160, 160);

/// The contact-status colours (light enough for a cell, dark enough for a line on white); the
/// status map, the 3-D maps and the status fractions use these, so a status has one colour.
pub mod status {
    use plotters::style::RGBColor;
    /// separated
    pub const SEPARATED: RGBColor = RGBColor(200, 200, 200);
    /// compliance & stick
    pub const COMPLIANCE_STICK: RGBColor = RGBColor(158, 202, 225);
    /// compliance & slip
    pub const COMPLIANCE_SLIP: RGBColor = RGBColor(33, 113, 181);
    /// constraint (λ > 0) & stick
    pub const CONSTRAINT_STICK: RGBColor = RGBColor(253, 174, 107);
    /// constraint (λ > 0) & slip
    pub const CONSTRAINT_SLIP: RGBColor = RGBColor(217, 72, 1);
    /// compliance, no friction law
    pub const COMPLIANCE: RGBColor = RGBColor(116, 196, 118);
    /// constraint (λ > 0), no friction law
    pub const CONSTRAINT: RGBColor = RGBColor(0, 109, 44);
}

/// A padded range of the finite values (0..1 when there are none; a span that would overflow
/// is left unpadded and clamped so the chart still draws).
pub fn range(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in vals.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    if hi - lo <= 1e-300 + 1e-12 * hi.abs() {
        let pad = if hi.abs() > 0.0 { 0.1 * hi.abs() } else { 1.0 };
        return (lo - pad, hi + pad);
    }
    let pad = 0.05 * (hi - lo);
    if !pad.is_finite() || !(lo - pad).is_finite() || !(hi + pad).is_finite() {
        return (lo.max(-f64::MAX / 4.0), hi.min(f64::MAX / 4.0));
    }
    (lo - pad, hi + pad)
}

/// A tick label for an axis spanning [lo, hi]: a plain number with the decimals that tell
/// ticks apart (60, 2.5, 0.125: four significant digits of the span, trailing zeros dropped),
/// or scientific notation when the axis reaches values ≥ 1e5 or lies entirely below 1e-3.
pub fn tick_label(v: f64, lo: f64, hi: f64) -> String {
    // a tick at zero computed as lo + k·step carries the rounding of the sum (−2.5e-32)
    if v.abs() <= 1e-9 * (hi - lo).abs() {
        return "0".into();
    }
    let big = lo.abs().max(hi.abs());
    if big >= 1e5 || (big < 1e-3 && big > 0.0) {
        return format!("{v:.1e}");
    }
    let span = (hi - lo).abs();
    let decimals = if span > 0.0 { (4.0 - span.log10().floor()).clamp(0.0, 10.0) as usize } else { 0 };
    let s = format!("{v:.decimals$}");
    let s = if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s };
    if s == "-0" { "0".into() } else { s }
}

/// A value in a legend with `digits` significant digits (as C's %g): plain when its decimal
/// exponent e, after rounding to those digits, has −3 ≤ e < min(digits, 5) (51.50798,
/// 0.3493750, 10.00000 for 9.9999999), scientific otherwise (6.022141e23, 1.27e-4, 1.00e5).
pub fn significant(v: f64, digits: usize) -> String {
    let digits = digits.max(1);
    if v == 0.0 {
        return "0".into();
    }
    let scientific = format!("{v:.prec$e}", prec = digits - 1);
    // the exponent of the value as rounded (9.9999999 to 7 digits is 1.000000e1)
    let e: i64 = match scientific.rsplit_once('e').map(|(_, e)| e.parse()) {
        Some(Ok(e)) => e,
        _ => return scientific, // inf, NaN
    };
    if e < -3 || e >= (digits as i64).min(5) {
        return scientific;
    }
    let decimals = (digits as i64 - 1 - e).max(0) as usize;
    format!("{v:.decimals$}")
}

/// A tick label on a logarithmic axis: the power of ten (1e-3, 1e2).
pub fn log_tick_label(v: f64) -> String {
    format!("{v:.0e}")
}

/// A linear axis range widened to whole multiples of a round step (1, 2 or 5 × 10^n, about an
/// eighth of the span), so both ends are labelled ticks — a force reaching −15 gets a −20 tick.
pub fn nice_bounds(lo: f64, hi: f64) -> (f64, f64) {
    let span = hi - lo;
    if !(span > 0.0) || !span.is_finite() {
        return (lo, hi);
    }
    let raw = span / 8.0;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0].iter().map(|m| m * mag).find(|s| *s >= raw).unwrap_or(10.0 * mag);
    let (mut a, mut b) = ((lo / step).floor() * step, (hi / step).ceil() * step);
    // an end that is only the 5% padding past zero stays where it is (non-negative data keep
    // their axis at 0, not at −step)
    if lo < 0.0 && lo >= -0.06 * span {
        a = lo;
    }
    if hi > 0.0 && hi <= 0.06 * span {
        b = hi;
    }
    if a.is_finite() && b.is_finite() { (a, b) } else { (lo, hi) }
}

/// A number in a chart's label: at most four decimals with trailing zeros dropped (39.375, 20,
/// 0.2, 39.1667), or scientific notation outside [1e-3, 1e5) (1.0e-5).
pub fn number(v: f64) -> String {
    let a = v.abs();
    if a != 0.0 && !(1e-3..1e5).contains(&a) {
        return format!("{v:.1e}");
    }
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.').to_string();
    if s == "-0" { "0".into() } else { s }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A legend's value keeps its significant digits, plain in the range people read plainly.
    #[test]
    fn significant_digits_are_kept() {
        assert_eq!(significant(51.5079812, 7), "51.50798");
        assert_eq!(significant(0.34937504, 7), "0.3493750");
        assert_eq!(significant(-2.8934, 5), "-2.8934");
        assert_eq!(significant(1.27e-4, 3), "1.27e-4");
        assert_eq!(significant(6.02214076e23, 4), "6.022e23");
        assert_eq!(significant(0.0, 7), "0");
        // rounding carries into the next power of ten before the form is chosen
        assert_eq!(significant(9.9999999, 7), "10.00000");
        assert_eq!(significant(99999.999999, 7), "1.000000e5");
        assert_eq!(significant(0.00099999, 3), "0.00100");
        // an integer part wider than the digits asked for is not printed plain
        assert_eq!(significant(99999.4, 3), "1.00e5");
        assert_eq!(significant(4321.0, 3), "4.32e3");
        assert_eq!(significant(f64::INFINITY, 3), "inf");
    }
}
