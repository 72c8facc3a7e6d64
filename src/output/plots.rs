//! SVG charts (plotters, SVG backend only): line charts, one panel or stacked panels sharing
//! the time axis, with tick labels written as plain numbers (60, 0.25) and in scientific
//! notation only where an axis spans values too large or too small for that.

use plotters::prelude::*;

pub use plotters::prelude::SeriesLabelPosition;

/// One line of a chart.
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
}

/// Presentation options of [`line_chart_with`] beyond the data; the default is the plain
/// line chart of [`line_chart`] (legend upper left, no markers).
#[derive(Debug, Clone)]
pub struct Options {
    /// a filled circle at every finite point (e.g. at the mesh nodes of a profile)
    pub markers: bool,
    pub legend: SeriesLabelPosition,
    /// extra room above the data, as a fraction of the primary range (keeps a legend placed
    /// at the top off the lines)
    pub headroom: f64,
    /// the colour of each series in order (empty: [`PALETTE`]); a chart whose series are
    /// categories drawn elsewhere too passes the categories' colours, so a status has one colour
    pub colors: Vec<RGBColor>,
}

impl Default for Options {
    fn default() -> Options {
        Options { markers: false, legend: SeriesLabelPosition::UpperLeft, headroom: 0.0, colors: Vec::new() }
    }
}

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

/// One panel of a chart: title, axis names, series and labelled horizontal lines, and which
/// axes are logarithmic (x, y: the values' log10 is drawn and the ticks read as powers of ten;
/// non-positive values are left out).
pub struct Panel<'a> {
    pub title: &'a str,
    pub x_desc: &'a str,
    pub y_desc: &'a str,
    pub series: &'a [Series],
    pub hlines: &'a [(String, f64)],
    pub log: (bool, bool),
}

/// A line chart as an SVG document. `hlines` are labelled horizontal reference lines.
pub fn line_chart(
    title: &str,
    x_desc: &str,
    y_desc: &str,
    series: &[Series],
    hlines: &[(String, f64)],
) -> Result<String, String> {
    line_chart_with(title, x_desc, y_desc, series, hlines, &Options::default())
}

/// [`line_chart`] with presentation [`Options`] (point markers, legend position).
pub fn line_chart_with(
    title: &str,
    x_desc: &str,
    y_desc: &str,
    series: &[Series],
    hlines: &[(String, f64)],
    opts: &Options,
) -> Result<String, String> {
    stacked_chart(&[(Panel { title, x_desc, y_desc, series, hlines, log: (false, false) }, 1.0)], opts)
}

/// Panels stacked top to bottom on one SVG page, each taking its share of the height (the
/// shares are relative weights); the same presentation options for all.
pub fn stacked_chart(panels: &[(Panel, f64)], opts: &Options) -> Result<String, String> {
    let mut svg = String::new();
    {
        let height = match panels.len() {
            0 | 1 => 540,
            2 => 720,
            n => 260 * n as u32,
        };
        let root = SVGBackend::with_string(&mut svg, (960, height)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let total: f64 = panels.iter().map(|p| p.1).sum();
        let mut rest = root;
        for (k, (panel, share)) in panels.iter().enumerate() {
            let area = if k + 1 == panels.len() {
                rest.clone()
            } else {
                let (top, bottom) = rest.split_vertically((f64::from(height) * share / total).round() as u32);
                rest = bottom;
                top
            };
            draw_panel(&area, panel, opts)?;
        }
        rest.present().map_err(|e| e.to_string())?;
    }
    Ok(svg)
}

/// Draw one panel on `area`.
fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    p: &Panel,
    opts: &Options,
) -> Result<(), String> {
    // on a logarithmic axis the values' log10 is drawn (NaN, so left out, for v ≤ 0)
    let axis = |log: bool| {
        move |v: f64| {
            if !log {
                v
            } else if v > 0.0 {
                v.log10()
            } else {
                f64::NAN
            }
        }
    };
    let (fx, fy) = (axis(p.log.0), axis(p.log.1));
    let drawn: Vec<Series> = p
        .series
        .iter()
        .map(|s| Series { name: s.name.clone(), points: s.points.iter().map(|q| (fx(q.0), fy(q.1))).collect() })
        .collect();
    let hlines: Vec<(String, f64)> = p.hlines.iter().map(|h| (h.0.clone(), fy(h.1))).collect();
    let (x0, x1) = range(drawn.iter().flat_map(|s| s.points.iter().map(|q| q.0)));
    let (mut y0, mut y1) =
        range(drawn.iter().flat_map(|s| s.points.iter().map(|q| q.1)).chain(hlines.iter().map(|h| h.1)));
    if opts.headroom > 0.0 && (y1 + opts.headroom * (y1 - y0)).is_finite() {
        y1 += opts.headroom * (y1 - y0);
    }
    if !p.log.1 {
        (y0, y1) = nice_bounds(y0, y1);
    }
    let mut chart = ChartBuilder::on(area)
        .caption(p.title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(80)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc(p.x_desc)
        .y_desc(p.y_desc)
        .x_label_formatter(&|v| if p.log.0 { format!("{:.0e}", 10f64.powf(*v)) } else { tick_label(*v, x0, x1) })
        .y_label_formatter(&|v| if p.log.1 { format!("{:.0e}", 10f64.powf(*v)) } else { tick_label(*v, y0, y1) })
        .draw()
        .map_err(|e| e.to_string())?;
    for (k, s) in drawn.iter().enumerate() {
        let color = opts.colors.get(k).copied().unwrap_or(PALETTE[k % PALETTE.len()]);
        let style = ShapeStyle::from(&color).stroke_width(2);
        let pts = s.points.iter().copied().filter(|q| q.0.is_finite() && q.1.is_finite());
        if opts.markers {
            chart.draw_series(pts.clone().map(|q| Circle::new(q, 3, color.filled()))).map_err(|e| e.to_string())?;
        }
        chart
            .draw_series(LineSeries::new(pts, style))
            .map_err(|e| e.to_string())?
            .label(s.name.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
    }
    for (label, y) in hlines.iter().filter(|h| h.1.is_finite()) {
        let style = ShapeStyle::from(&BLACK).stroke_width(1);
        chart
            .draw_series(LineSeries::new(vec![(x0, *y), (x1, *y)], style))
            .map_err(|e| e.to_string())?
            .label(label.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
    }
    chart
        .configure_series_labels()
        .position(opts.legend.clone())
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()
        .map_err(|e| e.to_string())?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Chart numbers read as written: labels without padding zeros, a round labelled tick below a
    /// negative minimum, an axis of non-negative data kept at 0, and a zero tick read as 0 (exact
    /// comparisons: every value here is a short decimal or a product of one).
    #[test]
    fn chart_numbers_read_as_written() {
        assert_eq!(number(39.375), "39.375");
        assert_eq!(number(20.0), "20");
        assert_eq!(number(39.166_666_666), "39.1667");
        assert_eq!(number(1e-5), "1.0e-5");
        assert_eq!(nice_bounds(-18.0, 103.0), (-20.0, 120.0));
        assert_eq!(nice_bounds(-0.1, 3.0).0, -0.1);
        assert_eq!(tick_label(-2.5e-32, -2e-16, 5e-17), "0");
    }
}
