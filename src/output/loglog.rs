//! Log–log helpers shared by the ε-study and the developer studies: least-squares slopes, padded
//! log ranges and the error charts (one line with markers per series).

use super::style::{self, font};
use crate::error::{Error, Result};

/// Least-squares slope of log10(y) against log10(x) over the positive pairs (NaN with fewer
/// than two).
pub fn loglog_slope(x: &[f64], y: &[f64]) -> f64 {
    let pts: Vec<(f64, f64)> =
        x.iter().zip(y).filter(|(a, b)| **a > 0.0 && **b > 0.0).map(|(a, b)| (a.log10(), b.log10())).collect();
    let n = pts.len() as f64;
    if pts.len() < 2 {
        return f64::NAN;
    }
    let (mx, my) = (pts.iter().map(|p| p.0).sum::<f64>() / n, pts.iter().map(|p| p.1).sum::<f64>() / n);
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    sxy / sxx
}

/// The error of a chart named `file`.
pub fn chart_error(file: &'static str) -> impl Fn(&dyn std::fmt::Display) -> Error {
    move |e| Error::Output(format!("{file}: {e}"))
}

/// A padded log-scale range of the positive finite values (a decade when there are none).
pub fn log_range(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) =
        vals.filter(|v| v.is_finite() && *v > 0.0).fold((f64::INFINITY, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
    if lo.is_finite() { (lo / 1.6, hi * 1.6) } else { (0.1, 1.0) }
}

/// One line of a log–log chart: its legend and its points (non-positive ones are left out).
pub struct LogSeries {
    pub name: String,
    pub points: Vec<(f64, f64)>,
}

/// A log–log line chart with markers (the studies' error charts), its legend below the axes so
/// it covers no line: `pad` widens the axes by that
/// factor on each side of the data. An error names `file` when no point is positive.
pub fn loglog_chart(
    file: &'static str,
    title: &str,
    (x_desc, y_desc): (&str, &str),
    series: &[LogSeries],
    pad: (f64, f64),
) -> Result<String> {
    use plotters::prelude::*;
    let err = chart_error(file);
    let pos = |p: &(f64, f64)| p.0.is_finite() && p.0 > 0.0 && p.1.is_finite() && p.1 > 0.0;
    let pts: Vec<(f64, f64)> = series.iter().flat_map(|s| s.points.iter().copied().filter(pos)).collect();
    let (x0, x1) = (pts.iter().map(|p| p.0).fold(f64::INFINITY, f64::min), pts.iter().map(|p| p.0).fold(0.0, f64::max));
    let (y0, y1) = (pts.iter().map(|p| p.1).fold(f64::INFINITY, f64::min), pts.iter().map(|p| p.1).fold(0.0, f64::max));
    if pts.is_empty() {
        return Err(Error::Output(format!("{file}: no positive values to plot")));
    }
    let mut svg = String::new();
    {
        // the legend below the plotting page, one row per series: inside, it hid lines (scaling.svg)
        let (w, h) = style::LOGLOG_CHART;
        let key_h = (style::LEGEND_ROW * series.len() as i32 + 16) as u32;
        let root = SVGBackend::with_string(&mut svg, (w, h + key_h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(&e))?;
        let (top, key) = root.split_vertically(h);
        let mut chart = ChartBuilder::on(&top)
            .caption(title, font(style::CAPTION))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(80)
            .build_cartesian_2d((x0 / pad.0..x1 * pad.0).log_scale(), (y0 / pad.1..y1 * pad.1).log_scale())
            .map_err(|e| err(&e))?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(y_desc)
            .x_label_formatter(&|v| style::log_tick_label(*v))
            .y_label_formatter(&|v| style::log_tick_label(*v))
            .draw()
            .map_err(|e| err(&e))?;
        for (k, s) in series.iter().enumerate() {
            let color = style::PALETTE[k % style::PALETTE.len()];
            let pts: Vec<(f64, f64)> = s.points.iter().copied().filter(pos).collect();
            chart
                .draw_series(LineSeries::new(pts.clone(), ShapeStyle::from(&color).stroke_width(2)))
                .map_err(|e| err(&e))?;
            chart.draw_series(pts.into_iter().map(|p| Circle::new(p, 4, color.filled()))).map_err(|e| err(&e))?;
            let y = 8 + style::LEGEND_ROW * k as i32 + style::LEGEND_ROW / 2;
            key.draw(&PathElement::new(vec![(92, y), (122, y)], ShapeStyle::from(&color).stroke_width(2)))
                .map_err(|e| err(&e))?;
            key.draw(&Circle::new((107, y), 4, color.filled())).map_err(|e| err(&e))?;
            key.draw(&Text::new(s.name.clone(), (132, y - style::LEGEND / 2 - 1), font(style::LEGEND)))
                .map_err(|e| err(&e))?;
        }
        root.present().map_err(|e| err(&e))?;
    }
    Ok(svg)
}
