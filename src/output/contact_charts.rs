//! The contact and geometry charts of plots/: force histories with the
//! Coulomb→Tresca reference, the space–time contact-status map along Γ3, normal-stress
//! profiles along Γ3 and the deformed mesh.
//!
//! Every function returns the SVG text or a plotting error message; the caller names the file.
//! Odd data never fails a chart: non-finite values are skipped and empty data gives empty axes.

use plotters::prelude::*;

use super::ChartRow;
use super::plots::{self, Options, Series, SeriesLabelPosition};
use super::style::{self, font, status};
use super::units;
use crate::mesh::{PlaneMesh, SolidMesh};
use crate::model::contact::ContactModel;
use crate::model::kinds::Bound;
use crate::simulation::NodeRecord;
use crate::step::NodeStatus;

/// The frames the writer kept: (step, t, one record per contact node).
pub type ContactFrame = (usize, f64, Vec<NodeRecord>);

/// Status maps with more cells than this draw every k-th frame only (keeps the SVG small).
const MAX_CELLS: usize = 200_000;

/// p(g), when the bound is finite and the compliance law is not zero (else no reference line).
pub fn p_at_bound(c: &ContactModel) -> Option<f64> {
    match c.bound {
        Bound::Finite(g) if !c.compliance.is_zero() => Some(c.compliance.p(g)).filter(|p| p.is_finite() && *p > 0.0),
        _ => None,
    }
}

/// Where each contact node lies along Γ3: x when Γ3 is horizontal, else the arc length.
#[derive(Debug, Clone)]
pub struct Along {
    /// position of contact node i
    pub s: Vec<f64>,
    /// contact-node indices sorted by position
    pub order: Vec<usize>,
    /// axis description
    pub label: &'static str,
}

impl Along {
    /// Positions of the contact nodes of `c` on `mesh`; `sides` are the Γ3 side names.
    pub fn of(mesh: &PlaneMesh, c: &ContactModel, sides: &[String]) -> Along {
        let xy: Vec<[f64; 2]> = c.nodes.iter().map(|&v| mesh.nodes[v]).collect();
        let (ylo, yhi) = xy.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| (a.min(p[1]), b.max(p[1])));
        let horizontal = yhi - ylo <= 1e-9 * mesh.bbox_diameter().max(f64::MIN_POSITIVE);
        let (s, label) = if horizontal {
            (xy.iter().map(|p| p[0]).collect(), "x along Γ3 [m]")
        } else {
            (arc_length(mesh, sides, &c.nodes), "arc length along Γ3 [m]")
        };
        let mut order: Vec<usize> = (0..s.len()).collect();
        order.sort_by(|&a, &b| s[a].total_cmp(&s[b]));
        Along { s, order, label }
    }
}

/// Arc length of `nodes` along the chains formed by the edges of `sides` (each chain walked
/// from its leftmost end; chains laid end to end). Nodes on no edge fall back to x.
fn arc_length(mesh: &PlaneMesh, sides: &[String], nodes: &[usize]) -> Vec<f64> {
    let n = mesh.nodes.len();
    let mut adj: Vec<Vec<usize>> = vec![Vec::new(); n];
    for side in sides.iter().filter_map(|name| mesh.side(name)) {
        for &[a, b] in &side.facets {
            if a < n && b < n {
                adj[a].push(b);
                adj[b].push(a);
            }
        }
    }
    let key = |v: usize| (mesh.nodes[v][0], mesh.nodes[v][1]);
    let mut starts: Vec<usize> = (0..n).filter(|&v| !adj[v].is_empty()).collect();
    // chain ends first (degree ≠ 2), leftmost first; then any node of a closed loop
    starts.sort_by(|&a, &b| {
        (adj[a].len() == 2)
            .cmp(&(adj[b].len() == 2))
            .then(key(a).partial_cmp(&key(b)).unwrap_or(std::cmp::Ordering::Equal))
    });
    let mut arc = vec![f64::NAN; n];
    let mut total = 0.0;
    for start in starts {
        if !arc[start].is_nan() {
            continue;
        }
        let mut cur = start;
        arc[cur] = total;
        while let Some(&next) = adj[cur].iter().find(|&&w| arc[w].is_nan()) {
            let (p, q) = (mesh.nodes[cur], mesh.nodes[next]);
            total += (q[0] - p[0]).hypot(q[1] - p[1]);
            arc[next] = total;
            cur = next;
        }
    }
    nodes.iter().map(|&v| if arc[v].is_nan() { mesh.nodes[v][0] } else { arc[v] }).collect()
}

/// The contact-status categories of the status map: separated, or in contact through the
/// compliance alone or with the constraint active (λ > 0), in stick or slip under a friction law
/// and neither without one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Category {
    Separated,
    ComplianceStick,
    ComplianceSlip,
    ConstraintStick,
    ConstraintSlip,
    /// in contact through the compliance, no friction law
    Compliance,
    /// in contact with the constraint active, no friction law
    Constraint,
}

impl Category {
    pub const ALL: [Category; 7] = [
        Category::Separated,
        Category::ComplianceStick,
        Category::ComplianceSlip,
        Category::ConstraintStick,
        Category::ConstraintSlip,
        Category::Compliance,
        Category::Constraint,
    ];

    /// The categories a run can show: with a friction law (`friction`) separated and the four
    /// of compliance or constraint × stick or slip; without one separated, compliance and
    /// constraint.
    pub fn of_run(friction: bool) -> &'static [Category] {
        if friction { &Category::ALL[..5] } else { &[Category::Separated, Category::Compliance, Category::Constraint] }
    }

    /// The category of a node record: separated, else by the constraint (λ > 0) and the status.
    pub fn of(r: &NodeRecord) -> Category {
        match (r.status, r.lambda > 0.0) {
            (NodeStatus::Separated, _) => Category::Separated,
            (NodeStatus::Stick, false) => Category::ComplianceStick,
            (NodeStatus::Slip, false) => Category::ComplianceSlip,
            (NodeStatus::Stick, true) => Category::ConstraintStick,
            (NodeStatus::Slip, true) => Category::ConstraintSlip,
            (NodeStatus::Contact, false) => Category::Compliance,
            (NodeStatus::Contact, true) => Category::Constraint,
        }
    }

    /// The legend text.
    pub fn label(self) -> &'static str {
        match self {
            Category::Separated => "separated",
            Category::ComplianceStick => "compliance & stick",
            Category::ComplianceSlip => "compliance & slip",
            Category::ConstraintStick => "constraint (λ > 0) & stick",
            Category::ConstraintSlip => "constraint (λ > 0) & slip",
            Category::Compliance => "compliance, no friction",
            Category::Constraint => "constraint (λ > 0), no friction",
        }
    }

    fn color(self) -> RGBColor {
        match self {
            Category::Separated => status::SEPARATED,
            Category::ComplianceStick => status::COMPLIANCE_STICK,
            Category::ComplianceSlip => status::COMPLIANCE_SLIP,
            Category::ConstraintStick => status::CONSTRAINT_STICK,
            Category::ConstraintSlip => status::CONSTRAINT_SLIP,
            Category::Compliance => status::COMPLIANCE,
            Category::Constraint => status::CONSTRAINT,
        }
    }
}

/// Cell boundaries around sorted centres: midpoints inside, half a spacing beyond the ends.
fn cell_edges(centres: &[f64], lone_width: f64) -> Vec<f64> {
    match centres.len() {
        0 => Vec::new(),
        1 => vec![centres[0] - 0.5 * lone_width, centres[0] + 0.5 * lone_width],
        n => {
            let mut e = Vec::with_capacity(n + 1);
            e.push(centres[0] - 0.5 * (centres[1] - centres[0]));
            e.extend(centres.windows(2).map(|w| 0.5 * (w[0] + w[1])));
            e.push(centres[n - 1] + 0.5 * (centres[n - 1] - centres[n - 2]));
            e
        }
    }
}

/// Normal and tangential contact force against t, with p(g)·|Γ3|: above it the constraint
/// carries load and the friction bound is capped at μ p(g) (the Coulomb→Tresca switch). Forces
/// in the units of dimension `dim` (N/m per unit thickness in 2-D, N in 3-D).
///
/// Without a friction law (`friction` false) the tangential force is no line of the chart: it is
/// zero by definition, not a result.
pub fn forces(rows: &[ChartRow], reference: Option<f64>, dim: usize, friction: bool) -> Result<String, String> {
    let hist = |f: fn(&ChartRow) -> f64| rows.iter().map(|r| (r.t, f(r))).collect();
    let mut series = vec![Series { name: "normal force Σ ω (q + λ)".into(), points: hist(|r| r.normal_force) }];
    if friction {
        series.push(Series { name: "tangential force −Σ ω t".into(), points: hist(|r| r.tangential_force) });
    }
    let hlines: Vec<(String, f64)> = reference
        .filter(|r| r.is_finite())
        .map(|r| (format!("p(g)·|Γ3| = {} {}", plots::number(r), units::force(dim)), r))
        .into_iter()
        .collect();
    let title = match (hlines.is_empty(), friction) {
        (true, true) => "Contact forces on Γ3",
        (true, false) => "Normal contact force on Γ3 (no friction law)",
        (false, true) => {
            "Contact forces on Γ3 (above p(g)·|Γ3|: constraint active, friction capped at μ p(g): Coulomb→Tresca)"
        }
        (false, false) => "Normal contact force on Γ3 (no friction law; above p(g)·|Γ3|: constraint active)",
    };
    let opts = Options { markers: false, legend: SeriesLabelPosition::UpperRight, headroom: 0.3, ..Options::default() };
    plots::line_chart_with(title, "t [s]", &units::force_axis(dim), &series, &hlines, &opts)
}

/// Normal stress q + λ along Γ3 at about five frames spread over the contact phase, with p(g),
/// to show where the constraint lifts the stress above the compliance bound.
pub fn normal_stress(frames: &[ContactFrame], along: &Along, p_g: Option<f64>) -> Result<String, String> {
    // frames whose largest q + λ is at least 1% of the run's largest: a frame just touching
    // (1e-5 Pa against 70) would draw a flat line at 0
    let peak = |f: &ContactFrame| f.2.iter().map(|r| r.p + r.lambda).fold(0.0, f64::max);
    let top = frames.iter().map(peak).fold(0.0, f64::max);
    let loaded: Vec<&ContactFrame> = frames.iter().filter(|f| top > 0.0 && peak(f) >= 0.01 * top).collect();
    let pool: Vec<&ContactFrame> = if loaded.len() >= 5 { loaded } else { frames.iter().collect() };
    let mut picks: Vec<usize> =
        (0..5).map(|j| (j * pool.len().saturating_sub(1) + 2) / 4).filter(|&k| k < pool.len()).collect();
    picks.dedup();
    let series: Vec<Series> = picks
        .iter()
        .map(|&k| {
            let (_, t, recs) = pool[k];
            let points =
                along.order.iter().filter_map(|&i| Some((along.s[i], recs.get(i).map(|r| r.p + r.lambda)?))).collect();
            Series { name: format!("t = {} s", plots::number(*t)), points }
        })
        .collect();
    let hlines: Vec<(String, f64)> =
        p_g.map(|p| (format!("p(g) = {} Pa (compliance bound)", plots::number(p)), p)).into_iter().collect();
    let opts = Options { markers: true, legend: SeriesLabelPosition::UpperRight, headroom: 0.35, ..Options::default() };
    plots::line_chart_with(
        "Normal stress q + λ along Γ3 (frames with contact load)",
        along.label,
        "q + λ [Pa]",
        &series,
        &hlines,
        &opts,
    )
}

/// The colour key of the status map with the number of cells of each category.
/// `shown`: the categories of the run ([`Category::of_run`]).
fn draw_status_legend(
    area: &DrawingArea<SVGBackend, plotters::coord::Shift>,
    shown: &[Category],
    counts: &[usize; Category::ALL.len()],
    nodes: usize,
    frames: usize,
) -> Result<(), DrawingAreaErrorKind<std::io::Error>> {
    let font = font(style::LEGEND);
    area.draw(&Text::new("status (cells)", (10, 60), font))?;
    for (k, cat) in shown.iter().enumerate() {
        let y = 90 + 26 * k as i32;
        area.draw(&Rectangle::new([(10, y), (28, y + 16)], cat.color().filled()))?;
        area.draw(&Rectangle::new([(10, y), (28, y + 16)], BLACK.stroke_width(1)))?;
        area.draw(&Text::new(format!("{} ({})", cat.label(), counts[*cat as usize]), (36, y + 2), font))?;
    }
    let y = 90 + 26 * shown.len() as i32 + 10;
    area.draw(&Text::new(format!("{nodes} nodes × {frames} frames"), (10, y), font))
}

/// Space–time map of the contact status along Γ3 (one row per frame), so the spread of
/// separation, compliance, active constraint, stick and slip over the run is seen at once
/// (`friction`: the run has a friction law; without one the legend has no stick or slip).
pub fn contact_status(frames: &[ContactFrame], along: &Along, friction: bool) -> Result<String, String> {
    let n = along.order.len();
    let stride = (frames.len() * n).div_ceil(MAX_CELLS).max(1);
    let rows: Vec<&ContactFrame> = frames.iter().step_by(stride).filter(|f| f.1.is_finite()).collect();
    let s_sorted: Vec<f64> = along.order.iter().map(|&i| along.s[i]).collect();
    let ts: Vec<f64> = rows.iter().map(|f| f.1).collect();
    let xe = cell_edges(&s_sorted, 1.0);
    let te = cell_edges(&ts, 1.0);
    let span = |e: &[f64]| if e.len() >= 2 && e[0] < e[e.len() - 1] { (e[0], e[e.len() - 1]) } else { (0.0, 1.0) };
    let ((x0, x1), (t0, t1)) = (span(&xe), span(&te));
    let mut counts = [0usize; Category::ALL.len()];
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, style::STATUS_MAP).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let (left, legend) = root.split_horizontally(style::STATUS_MAP_WIDTH);
        let title = if stride > 1 {
            format!("Contact status along Γ3 (one frame in {stride})")
        } else {
            "Contact status along Γ3".to_string()
        };
        let mut chart = ChartBuilder::on(&left)
            .caption(title, font(style::CAPTION))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d(x0..x1, t0..t1)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc(along.label)
            .y_desc("t [s]")
            .x_label_formatter(&|v| plots::tick_label(*v, x0, x1))
            .y_label_formatter(&|v| plots::tick_label(*v, t0, t1))
            .draw()
            .map_err(|e| e.to_string())?;
        for cat in Category::ALL {
            let mut cells = Vec::new();
            for (row, (_, _, recs)) in rows.iter().enumerate() {
                for (col, &i) in along.order.iter().enumerate() {
                    if recs.get(i).is_some_and(|r| Category::of(r) == cat) {
                        cells.push(Rectangle::new(
                            [(xe[col], te[row]), (xe[col + 1], te[row + 1])],
                            cat.color().filled(),
                        ));
                    }
                }
            }
            counts[cat as usize] = cells.len();
            chart.draw_series(cells).map_err(|e| e.to_string())?;
        }
        draw_status_legend(&legend, Category::of_run(friction), &counts, n, rows.len()).map_err(|e| e.to_string())?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(svg)
}

type Chart2d<'a, 'b> = ChartContext<
    'a,
    SVGBackend<'b>,
    Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
>;

/// The axes of the deformed-mesh chart (built twice: once to measure the plotting area).
fn deformed_frame<'a, 'b>(
    area: &'a DrawingArea<SVGBackend<'b>, plotters::coord::Shift>,
    title: &str,
    x: std::ops::Range<f64>,
    y: std::ops::Range<f64>,
) -> Result<Chart2d<'a, 'b>, String> {
    ChartBuilder::on(area)
        .caption(title, font(style::SUBCAPTION))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(x, y)
        .map_err(|e| e.to_string())
}

/// A mesh edge (lower node id first).
type Edge = (usize, usize);

/// The edges of a triangulation, each once, and the boundary edges (those of one triangle).
fn mesh_edges(mesh: &PlaneMesh) -> (Vec<Edge>, Vec<Edge>) {
    let mut edges: Vec<Edge> = mesh
        .cells
        .iter()
        .flat_map(|t| (0..3).map(move |k| (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]))))
        .collect();
    edges.sort_unstable();
    let (mut unique, mut outline) = (Vec::with_capacity(edges.len() / 2 + 1), Vec::new());
    for (k, &e) in edges.iter().enumerate() {
        if k > 0 && edges[k - 1] == e {
            continue;
        }
        unique.push(e);
        if edges.get(k + 1) != Some(&e) {
            outline.push(e);
        }
    }
    (unique, outline)
}

/// The deformed mesh x + s·u at time `t` over the grey undeformed outline, s chosen so the
/// largest displacement is 10% of the domain size, to see the final shape at a glance.
/// Γ3's foundation for the deformed-mesh chart: the contact nodes in order along Γ3, where
/// the foundation lies (x + gap ν) and where the penetration bound lies (x + (gap + g) ν), both
/// drawn at the chart's displacement scale so that a node on the bound sits on its line.
pub struct Foundation {
    /// (node position x, outward normal ν, gap) per contact node, in order along Γ3
    pub nodes: Vec<([f64; 2], [f64; 2], f64)>,
    /// the penetration bound g (None: pure normal compliance)
    pub g: Option<f64>,
}

impl Foundation {
    /// The foundation of the contact model `c` on `mesh`, its nodes in the order of `along`.
    pub fn of(mesh: &PlaneMesh, c: &ContactModel, along: &Along) -> Foundation {
        let nodes = along
            .order
            .iter()
            .map(|&i| {
                let n = c.frames[i].normal;
                (mesh.nodes[c.nodes[i]], [n[0], n[1]], c.gap[i])
            })
            .collect();
        Foundation { nodes, g: c.constraint.filter(|g| g.is_finite()) }
    }
}

pub fn deformed(mesh: &PlaneMesh, u: &[[f64; 2]], t: f64, foundation: Option<&Foundation>) -> Result<String, String> {
    let (unique, outline) = mesh_edges(mesh);
    let finite = |d: &[f64; 2]| d[0].is_finite() && d[1].is_finite();
    let u_max = u.iter().filter(|d| finite(d)).map(|d| d[0].hypot(d[1])).fold(0.0, f64::max);
    let size = mesh.bbox_diameter();
    let scale = if u_max > 0.0 && size.is_finite() && size > 0.0 { 0.1 * size / u_max } else { 1.0 };
    let moved: Vec<Option<(f64, f64)>> = mesh
        .nodes
        .iter()
        .enumerate()
        .map(|(v, x)| {
            let d = u.get(v).copied().unwrap_or([0.0, 0.0]);
            let p = (x[0] + scale * d[0], x[1] + scale * d[1]);
            (p.0.is_finite() && p.1.is_finite()).then_some(p)
        })
        .collect();
    // the foundation and the bound at the displacement scale, x + scale (gap + offset) ν, where
    // that is near the body (within a fifth of its size: a curved foundation's far flanks, its
    // gap magnified with the displacements, would shrink the body to a dot)
    let line = |offset: f64| -> Vec<(f64, f64)> {
        foundation.map_or(Vec::new(), |f| {
            f.nodes
                .iter()
                .filter(|(_, _, gap)| (scale * (gap + offset)).abs() <= 0.2 * size)
                .map(|(x, n, gap)| (x[0] + scale * (gap + offset) * n[0], x[1] + scale * (gap + offset) * n[1]))
                .filter(|p| p.0.is_finite() && p.1.is_finite())
                .collect()
        })
    };
    let surface = line(0.0);
    let bound = foundation.and_then(|f| f.g).map(line).unwrap_or_default();
    let pts = mesh
        .nodes
        .iter()
        .map(|x| (x[0], x[1]))
        .chain(moved.iter().flatten().copied())
        .chain(surface.iter().copied())
        .chain(bound.iter().copied());
    let (xs, ys): (Vec<f64>, Vec<f64>) = pts.unzip();
    let ((mut x0, mut x1), (mut y0, mut y1)) = (plots::range(xs.into_iter()), plots::range(ys.into_iter()));
    // equal scales on both axes: widen the narrower range to the plotting area's aspect
    let w = style::DEFORMED_WIDTH;
    let h = ((f64::from(w) * (y1 - y0) / (x1 - x0)) as u32).clamp(360, 900);
    let title = format!(
        "Deformed mesh at t = {} s, displacement × {scale:.3} (largest |u| = {u_max:.3e} m); grey: undeformed outline",
        plots::number(t)
    );
    let (pw, ph) = {
        let mut scratch = String::new();
        let area = SVGBackend::with_string(&mut scratch, (w, h)).into_drawing_area();
        let dims = deformed_frame(&area, &title, 0.0..1.0, 0.0..1.0)?.plotting_area().dim_in_pixel();
        (f64::from(dims.0.max(1)), f64::from(dims.1.max(1)))
    };
    let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
    let per_px = ((x1 - x0) / pw).max((y1 - y0) / ph);
    if per_px.is_finite() && per_px > 0.0 {
        (x0, x1, y0, y1) =
            (cx - 0.5 * per_px * pw, cx + 0.5 * per_px * pw, cy - 0.5 * per_px * ph, cy + 0.5 * per_px * ph);
    }
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let mut chart = deformed_frame(&root, &title, x0..x1, y0..y1)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("x [m]")
            .y_desc("y [m]")
            .x_label_formatter(&|v| plots::tick_label(*v, x0, x1))
            .y_label_formatter(&|v| plots::tick_label(*v, y0, y1))
            .draw()
            .map_err(|e| e.to_string())?;
        let grey = style::OUTLINE.stroke_width(2);
        let node = |v: usize| (mesh.nodes[v][0], mesh.nodes[v][1]);
        chart
            .draw_series(outline.iter().map(|&(a, b)| PathElement::new(vec![node(a), node(b)], grey)))
            .map_err(|e| e.to_string())?;
        let blue = style::PALETTE[0].stroke_width(1);
        let drawn = unique.iter().filter_map(|&(a, b)| Some(PathElement::new(vec![moved[a]?, moved[b]?], blue)));
        chart.draw_series(drawn).map_err(|e| e.to_string())?;
        let mut legend = false;
        if surface.len() >= 2 {
            let black = BLACK.stroke_width(2);
            chart
                .draw_series([PathElement::new(surface, black)])
                .map_err(|e| e.to_string())?
                .label("foundation (gap × the displacement scale)")
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], black));
            legend = true;
        }
        if bound.len() >= 2 {
            let red = style::PALETTE[3].stroke_width(1);
            chart
                .draw_series([PathElement::new(bound, red)])
                .map_err(|e| e.to_string())?
                .label("penetration bound g (same scale)")
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], red));
        }
        if legend {
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .draw()
                .map_err(|e| e.to_string())?;
        }
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(svg)
}

/// The share of Γ3's nodes in each status category against t, over the contact frames (any
/// dimension): the 3-D counterpart of the space–time map, which needs a 1-D Γ3; the categories
/// of the run's friction law (`friction`).
pub fn status_fractions(frames: &[ContactFrame], friction: bool) -> Result<String, String> {
    let colors = Category::of_run(friction).iter().map(|c| c.color()).collect();
    let series: Vec<plots::Series> = Category::of_run(friction)
        .iter()
        .map(|&cat| plots::Series {
            name: cat.label().to_string(),
            points: frames
                .iter()
                .filter(|f| !f.2.is_empty())
                .map(|(_, t, recs)| {
                    (*t, recs.iter().filter(|r| Category::of(r) == cat).count() as f64 / recs.len() as f64)
                })
                .collect(),
        })
        .collect();
    plots::line_chart_with(
        "Contact status on Γ3: share of the nodes (the status map's colours)",
        "t [s]",
        "share of the contact nodes",
        &series,
        &[],
        &plots::Options { colors, ..plots::Options::default() },
    )
}

/// A 2-D Γ3 (a surface of a 3-D body) laid flat for the status maps: each contact node's
/// in-plane position, Γ3's triangles in the same coordinates with the contact node (if any) at
/// each vertex, and the names of the two axes.
#[derive(Debug, Clone)]
pub struct FlatSurface {
    /// in-plane position of contact node i
    pub xy: Vec<[f64; 2]>,
    /// Γ3's faces: each vertex's in-plane position and its contact-node index (None: a vertex
    /// that is no contact node, e.g. on the Dirichlet boundary)
    pub faces: Vec<[([f64; 2], Option<usize>); 3]>,
    /// horizontal and vertical axis descriptions, with units
    pub axes: [String; 2],
}

impl FlatSurface {
    /// Γ3 of `c` on `mesh` (`sides`: the Γ3 side names) in the plane of its mean normal
    /// n̄ = Σ ω ν: when n̄ is a coordinate axis (a face with normal ±z, or a cap symmetric about
    /// z) the global coordinates (x horizontal, y vertical; for ±x or ±y the other two in order),
    /// else the tangents of n̄, the longer in-plane extent horizontal.
    pub fn of(mesh: &SolidMesh, c: &ContactModel, sides: &[String]) -> FlatSurface {
        let mut n = [0.0; 3];
        for (f, w) in c.frames.iter().zip(&c.omega) {
            (0..3).for_each(|k| n[k] += w * f.normal[k]);
        }
        let norm = n.iter().map(|v| v * v).sum::<f64>().sqrt();
        let dot = |x: [f64; 3], e: [f64; 3]| x[0] * e[0] + x[1] * e[1] + x[2] * e[2];
        let axis = (0..3).find(|&k| norm > 0.0 && n[k].abs() >= (1.0 - 1e-9) * norm);
        let names = ["x", "y", "z"];
        let (mut e, mut axes) = match axis {
            Some(k) => {
                let (a, b) = match k {
                    0 => (1, 2),
                    1 => (0, 2),
                    _ => (0, 1),
                };
                let unit = |i: usize| {
                    let mut u = [0.0; 3];
                    u[i] = 1.0;
                    u
                };
                ([unit(a), unit(b)], [format!("{} [m]", names[a]), format!("{} [m]", names[b])])
            }
            None => {
                let f = if norm > 0.0 {
                    crate::model::contact::Frame::spatial([n[0] / norm, n[1] / norm, n[2] / norm])
                } else {
                    c.frames.first().copied().unwrap_or(crate::model::contact::Frame::spatial([0.0, 0.0, 1.0]))
                };
                (f.tangents, ["along τ1 [m]".to_string(), "along τ2 [m]".to_string()])
            }
        };
        let extent = |e: [f64; 3]| {
            let v = c.nodes.iter().map(|&i| dot(mesh.nodes[i], e));
            let (lo, hi) = v.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(x), b.max(x)));
            hi - lo
        };
        if axis.is_none() && extent(e[1]) > extent(e[0]) {
            e.swap(0, 1);
            axes.swap(0, 1);
        }
        let flat = |x: [f64; 3]| [dot(x, e[0]), dot(x, e[1])];
        let xy = c.nodes.iter().map(|&v| flat(mesh.nodes[v])).collect();
        let mut index = vec![None; mesh.nodes.len()];
        for (i, &v) in c.nodes.iter().enumerate() {
            index[v] = Some(i);
        }
        let faces = sides
            .iter()
            .filter_map(|name| mesh.side(name))
            .flat_map(|side| side.facets.iter())
            .filter(|f| f.iter().all(|&v| v < mesh.nodes.len()))
            .map(|f| f.map(|v| (flat(mesh.nodes[v]), index[v])))
            .collect();
        FlatSurface { xy, faces, axes }
    }
}

/// Each vertex's share of a triangle: for vertex k the quadrilateral (vertex, midpoint of the
/// edge to the next vertex, centroid, midpoint of the edge to the previous vertex). The three
/// tile the triangle without overlap, so over Γ3's faces a node's shares tile its own region
/// of the surface (whatever the mesh) and have a third of each face's area each.
pub fn node_regions(t: [[f64; 2]; 3]) -> [[[f64; 2]; 4]; 3] {
    let mid = |a: [f64; 2], b: [f64; 2]| [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
    let g = [(t[0][0] + t[1][0] + t[2][0]) / 3.0, (t[0][1] + t[1][1] + t[2][1]) / 3.0];
    std::array::from_fn(|k| {
        let (v, next, prev) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
        [v, mid(v, next), g, mid(v, prev)]
    })
}

/// The frames the 3-D status maps show (indices into `frames`): four spread over the frames
/// from the first where some node carries load (q + λ > 0) to the last such frame (a map of an
/// unloaded surface shows nothing); with no loaded frame, four spread over all frames with nodes.
pub fn map_frames(frames: &[ContactFrame]) -> Vec<usize> {
    let usable = |f: &ContactFrame| !f.2.is_empty() && f.1.is_finite();
    let loaded = |f: &ContactFrame| usable(f) && f.2.iter().any(|r| r.p + r.lambda > 0.0);
    let pool: Vec<usize> = match (frames.iter().position(loaded), frames.iter().rposition(loaded)) {
        (Some(a), Some(b)) => (a..=b).filter(|&i| usable(&frames[i])).collect(),
        _ => (0..frames.len()).filter(|&i| usable(&frames[i])).collect(),
    };
    let mut picks: Vec<usize> = match pool.len() {
        0 => Vec::new(),
        n => (0..4).map(|k| pool[k * (n - 1) / 3]).collect(),
    };
    picks.dedup();
    picks
}

/// The plotting area (width, height) in pixels of a map of a patch `span` = (width, height)
/// in metres, at equal scale on both axes, as large as fits in `room` pixels.
pub fn map_extent(span: (f64, f64), room: (f64, f64)) -> (f64, f64) {
    let (sx, sy) = span;
    if !(sx > 0.0 && sy > 0.0 && sx.is_finite() && sy.is_finite()) {
        return room;
    }
    let per_px = (sx / room.0).max(sy / room.1);
    (sx / per_px, sy / per_px)
}

/// The axes of one map (built twice: once to measure the room its labels take).
fn map_frame<'a, 'b>(
    area: &'a DrawingArea<SVGBackend<'b>, plotters::coord::Shift>,
    title: String,
    x: std::ops::Range<f64>,
    y: std::ops::Range<f64>,
) -> Result<Chart2d<'a, 'b>, String> {
    ChartBuilder::on(area)
        .caption(title, font(style::PANEL_CAPTION))
        .margin(8)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(x, y)
        .map_err(|e| e.to_string())
}

/// Maps of the contact status on a 2-D Γ3 (a surface of a 3-D body) at four frames of the
/// contact phase ([`map_frames`]): each node's own region of Γ3 ([`node_regions`] over the faces
/// of `surface`) coloured by its category (`friction`: the run has a friction law), each map at
/// the patch's aspect ratio (equal scales), axes in metres.
pub fn status_maps(frames: &[ContactFrame], surface: &FlatSurface, friction: bool) -> Result<String, String> {
    let picks: Vec<&ContactFrame> = map_frames(frames).into_iter().map(|i| &frames[i]).collect();
    let pts = surface.xy.iter().chain(surface.faces.iter().flat_map(|f| f.iter().map(|v| &v.0)));
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in pts.filter(|p| p[0].is_finite() && p[1].is_finite()) {
        (0..2).for_each(|c| (lo[c], hi[c]) = (lo[c].min(p[c]), hi[c].max(p[c])));
    }
    if !(lo[0] < hi[0]) || !(lo[1] < hi[1]) {
        // a single node or a degenerate patch: a unit square around it
        let c = [if lo[0].is_finite() { lo[0] } else { 0.0 }, if lo[1].is_finite() { lo[1] } else { 0.0 }];
        (lo, hi) = ([c[0] - 0.5, c[1] - 0.5], [c[0] + 0.5, c[1] + 0.5]);
    }
    // the square of a node when Γ3 has no faces: a share of the patch per node
    let side = (((hi[0] - lo[0]) * (hi[1] - lo[1])) / surface.xy.len().max(1) as f64).sqrt();
    let pad = if surface.faces.is_empty() { 0.5 * side } else { 0.03 * (hi[0] - lo[0]).max(hi[1] - lo[1]) };
    let (x0, x1, y0, y1) = (lo[0] - pad, hi[0] + pad, lo[1] - pad, hi[1] + pad);
    // one column of four maps for a long patch, else two by two
    let cols: u32 = if x1 - x0 > 2.0 * (y1 - y0) { 1 } else { 2 };
    let rows = 4 / cols;
    let cell_w = style::STATUS_MAP_WIDTH / cols;
    let caption = |t: f64| format!("Γ3 at t = {} s", plots::number(t));
    // the room the caption and axis labels take around the plotting area
    let (dx, dy) = {
        let mut scratch = String::new();
        let area = SVGBackend::with_string(&mut scratch, (cell_w, 400)).into_drawing_area();
        let d = map_frame(&area, caption(0.0), 0.0..1.0, 0.0..1.0)?.plotting_area().dim_in_pixel();
        (cell_w.saturating_sub(d.0), 400u32.saturating_sub(d.1))
    };
    let max_h = if cols == 1 { 200.0 } else { 420.0 };
    let (pw, ph) = map_extent((x1 - x0, y1 - y0), (f64::from(cell_w - dx), max_h));
    let (pw, ph) = ((pw.round() as u32).max(1), (ph.round() as u32).max(1));
    let cell_h = ph + dy;
    let height = (rows * cell_h).max(style::STATUS_MAP.1 / 2 + 100);
    // exactly equal scales after rounding the area to whole pixels
    let per_px = ((x1 - x0) / f64::from(pw)).max((y1 - y0) / f64::from(ph));
    let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
    let (hx, hy) = (0.5 * per_px * f64::from(pw), 0.5 * per_px * f64::from(ph));
    let (x0, x1, y0, y1) = (cx - hx, cx + hx, cy - hy, cy + hy);
    let mut counts = [0usize; Category::ALL.len()];
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (style::STATUS_MAP.0, height)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let (left, legend) = root.split_horizontally(style::STATUS_MAP_WIDTH);
        for (k, (_, t, recs)) in picks.iter().enumerate() {
            let (col, row) = (k as u32 % cols, k as u32 / cols);
            let (cw, ch) = (cell_w * col, cell_h * row);
            let panel = left.clone().shrink((cw, ch), (pw + dx, cell_h));
            let mut chart = map_frame(&panel, caption(*t), x0..x1, y0..y1)?;
            chart
                .configure_mesh()
                .disable_mesh()
                .x_desc(surface.axes[0].as_str())
                .y_desc(surface.axes[1].as_str())
                .x_label_formatter(&|v| plots::tick_label(*v, x0, x1))
                .y_label_formatter(&|v| plots::tick_label(*v, y0, y1))
                .draw()
                .map_err(|e| e.to_string())?;
            let cat = |i: usize| recs.get(i).map(Category::of);
            for c in recs.iter().map(Category::of) {
                counts[c as usize] += 1;
            }
            if surface.faces.is_empty() {
                let squares = surface.xy.iter().enumerate().filter_map(|(i, p)| {
                    let h = 0.45 * side;
                    Some(Rectangle::new([(p[0] - h, p[1] - h), (p[0] + h, p[1] + h)], cat(i)?.color().filled()))
                });
                chart.draw_series(squares.collect::<Vec<_>>()).map_err(|e| e.to_string())?;
            } else {
                let regions = surface.faces.iter().flat_map(|f| {
                    let quads = node_regions([f[0].0, f[1].0, f[2].0]);
                    (0..3).filter_map(move |k| {
                        let c = cat(f[k].1?)?;
                        Some(Polygon::new(
                            quads[k].iter().map(|p| (p[0], p[1])).collect::<Vec<_>>(),
                            c.color().filled(),
                        ))
                    })
                });
                chart.draw_series(regions.collect::<Vec<_>>()).map_err(|e| e.to_string())?;
            }
        }
        draw_status_legend(&legend, Category::of_run(friction), &counts, surface.xy.len(), picks.len())
            .map_err(|e| e.to_string())?;
        root.present().map_err(|e| e.to_string())?;
    }
    Ok(svg)
}
