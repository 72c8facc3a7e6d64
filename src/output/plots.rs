//! SVG charts (plotters, SVG backend only): line charts with an optional secondary axis.

use plotters::prelude::*;

pub use plotters::prelude::SeriesLabelPosition;

/// One line of a chart.
pub struct Series {
    pub name: String,
    pub points: Vec<(f64, f64)>,
    /// drawn against the right-hand axis
    pub secondary: bool,
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
}

impl Default for Options {
    fn default() -> Options {
        Options { markers: false, legend: SeriesLabelPosition::UpperLeft, headroom: 0.0 }
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

/// A line chart as an SVG document. `hlines` are labelled horizontal reference lines on the
/// primary axis.
pub fn line_chart(
    title: &str,
    x_desc: &str,
    y_desc: &str,
    y2_desc: Option<&str>,
    series: &[Series],
    hlines: &[(String, f64)],
) -> Result<String, String> {
    line_chart_with(title, x_desc, y_desc, y2_desc, series, hlines, &Options::default())
}

/// [`line_chart`] with presentation [`Options`] (point markers, legend position).
pub fn line_chart_with(
    title: &str,
    x_desc: &str,
    y_desc: &str,
    y2_desc: Option<&str>,
    series: &[Series],
    hlines: &[(String, f64)],
    opts: &Options,
) -> Result<String, String> {
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (960, 540)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let prim = series.iter().filter(|s| !s.secondary);
        let (x0, x1) = range(series.iter().flat_map(|s| s.points.iter().map(|p| p.0)));
        let (y0, mut y1) = range(prim.flat_map(|s| s.points.iter().map(|p| p.1)).chain(hlines.iter().map(|h| h.1)));
        if opts.headroom > 0.0 && (y1 + opts.headroom * (y1 - y0)).is_finite() {
            y1 += opts.headroom * (y1 - y0);
        }
        let (z0, z1) = range(series.iter().filter(|s| s.secondary).flat_map(|s| s.points.iter().map(|p| p.1)));
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(80)
            .right_y_label_area_size(if y2_desc.is_some() { 80 } else { 0 })
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|e| e.to_string())?
            .set_secondary_coord(x0..x1, z0..z1);
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(y_desc)
            .y_label_formatter(&|v| format!("{v:.3e}"))
            .draw()
            .map_err(|e| e.to_string())?;
        if let Some(d) = y2_desc {
            chart
                .configure_secondary_axes()
                .y_desc(d)
                .y_label_formatter(&|v| format!("{v:.1e}"))
                .draw()
                .map_err(|e| e.to_string())?;
        }
        for (k, s) in series.iter().enumerate() {
            let color = PALETTE[k % PALETTE.len()];
            let style = ShapeStyle::from(&color).stroke_width(2);
            let pts = s.points.iter().copied().filter(|p| p.0.is_finite() && p.1.is_finite());
            if opts.markers {
                let dots = pts.clone().map(|p| Circle::new(p, 3, color.filled()));
                if s.secondary {
                    chart.draw_secondary_series(dots).map_err(|e| e.to_string())?;
                } else {
                    chart.draw_series(dots).map_err(|e| e.to_string())?;
                }
            }
            if s.secondary {
                chart
                    .draw_secondary_series(LineSeries::new(pts, style))
                    .map_err(|e| e.to_string())?
                    .label(format!("{} (right axis)", s.name))
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
            } else {
                chart
                    .draw_series(LineSeries::new(pts, style))
                    .map_err(|e| e.to_string())?
                    .label(s.name.clone())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
            }
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
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(svg)
}
