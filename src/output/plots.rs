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
    /// the colour of each series in order (empty: [`style::PALETTE`]); a chart whose series are
    /// categories drawn elsewhere too passes the categories' colours, so a status has one colour
    pub colors: Vec<RGBColor>,
}

impl Default for Options {
    fn default() -> Options {
        Options { markers: false, legend: SeriesLabelPosition::UpperLeft, headroom: 0.0, colors: Vec::new() }
    }
}

use super::style::{self, font, log_tick_label};
pub use super::style::{PALETTE, nice_bounds, number, range, tick_label};

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
            0 | 1 => style::LINE_CHART.1,
            2 => style::TWO_PANELS_HEIGHT,
            n => style::PANEL_HEIGHT * n as u32,
        };
        let root = SVGBackend::with_string(&mut svg, (style::LINE_CHART.0, height)).into_drawing_area();
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
        .caption(p.title, font(style::CAPTION))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(80)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(|e| e.to_string())?;
    // plotters places the light grid lines of an axis near 1e-16 (the (E.1) residual) outside
    // the plotting area, across the caption: such an axis keeps its labelled lines only
    let tiny = y0.abs().max(y1.abs()) < 1e-10;
    chart
        .configure_mesh()
        .y_max_light_lines(if tiny { 0 } else { 10 })
        .x_desc(p.x_desc)
        .y_desc(p.y_desc)
        .x_label_formatter(&|v| if p.log.0 { log_tick_label(10f64.powf(*v)) } else { tick_label(*v, x0, x1) })
        .y_label_formatter(&|v| if p.log.1 { log_tick_label(10f64.powf(*v)) } else { tick_label(*v, y0, y1) })
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
