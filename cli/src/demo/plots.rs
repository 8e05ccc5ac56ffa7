//! The demo's figures (SVG through plotters, so they need no font files): refinement
//! operations per camera, active polygons per camera, memory against the number of cameras,
//! and refinement time against the number of cameras — the CAVECLOD paper's Figures 10–14.

use std::path::Path;

use plotters::chart::DualCoordChartContext;
use plotters::coord::ranged1d::ValueFormatter;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

/// Colours of up to four series.
const COLOURS: [RGBColor; 4] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
];

/// One line of a chart.
pub struct Series<'a> {
    /// Legend label.
    pub label: String,
    /// Points.
    pub points: &'a [(f64, f64)],
    /// Dashed (drawn thinner and lighter) for a baseline.
    pub baseline: bool,
}

type PlotResult = Result<(), Box<dyn std::error::Error>>;

/// A second `y` axis on the right: the left axis's values times `scale`, described by `desc`
/// (the same data in another unit).
#[derive(Clone, Copy)]
pub struct SecondAxis<'a> {
    /// Right-axis value per left-axis unit.
    pub scale: f64,
    /// The right axis's label.
    pub desc: &'a str,
}

/// A line chart with axis labels and a legend; `log_y` for quantities over decades; `right`
/// for a second `y` axis in another unit.
/// The file is written through a temporary file and a rename.
pub fn lines(
    file: &Path,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    series: &[Series<'_>],
    log_y: bool,
    right: Option<SecondAxis<'_>>,
) -> PlotResult {
    let mut svg = String::new();
    draw_lines(&mut svg, title, x_desc, y_desc, series, log_y, right)?;
    caveclod_bake::baked::write_atomically(file, svg.as_bytes())?;
    Ok(())
}

/// The chart of [`lines`] as SVG text.
fn draw_lines(
    svg: &mut String,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    series: &[Series<'_>],
    log_y: bool,
    right: Option<SecondAxis<'_>>,
) -> PlotResult {
    let root = SVGBackend::with_string(svg, (1000, 600)).into_drawing_area();
    root.fill(&WHITE)?;
    let pts = || series.iter().flat_map(|s| s.points.iter());
    let x_max = pts().map(|p| p.0).fold(1.0f64, f64::max);
    // Room above the data for the legend: 15% on a linear axis, half a decade on a log one.
    let headroom = if log_y { 3.2 } else { 1.15 };
    let y_max = pts().map(|p| p.1).fold(1.0f64, f64::max) * headroom;
    // Counts (cameras) get a tick per whole number rather than halves.
    let whole_x = pts().all(|p| p.0.fract() == 0.0) && x_max <= 20.0;
    let x_labels = if whole_x { x_max as usize + 1 } else { 10 };
    let mut builder = ChartBuilder::on(&root);
    builder
        .caption(title, ("sans-serif", 22))
        .margin(14)
        .x_label_area_size(44)
        .y_label_area_size(84)
        .right_y_label_area_size(if right.is_some() { 84 } else { 0 });
    if log_y {
        let y_min = pts()
            .map(|p| p.1)
            .filter(|&y| y > 0.0)
            .fold(f64::INFINITY, f64::min)
            .clamp(0.1, 1.0);
        let chart = builder.build_cartesian_2d(0f64..x_max, (y_min..y_max).log_scale())?;
        let mut chart = match right {
            Some(r) => chart
                .set_secondary_coord(0f64..x_max, (y_min * r.scale..y_max * r.scale).log_scale()),
            None => chart.set_secondary_coord(0f64..x_max, (y_min..y_max).log_scale()),
        };
        draw_chart(&mut chart, (x_desc, y_desc, x_labels), right, series)?;
    } else {
        let chart = builder.build_cartesian_2d(0f64..x_max, 0f64..y_max)?;
        let scale = right.map_or(1.0, |r| r.scale);
        let mut chart = chart.set_secondary_coord(0f64..x_max, 0f64..y_max * scale);
        draw_chart(&mut chart, (x_desc, y_desc, x_labels), right, series)?;
    }
    root.present()?;
    Ok(())
}

/// The axes (and the right one, if any), then the series and their legend.
fn draw_chart<'a, DB: DrawingBackend + 'a, Y, Y2>(
    chart: &mut DualCoordChartContext<
        'a,
        DB,
        Cartesian2d<RangedCoordf64, Y>,
        Cartesian2d<RangedCoordf64, Y2>,
    >,
    (x_desc, y_desc, x_labels): (&str, &str, usize),
    right: Option<SecondAxis<'_>>,
    series: &[Series<'_>],
) -> PlotResult
where
    DB::ErrorType: 'static,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
    Y2: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .x_labels(x_labels)
        .x_label_formatter(&|v| short(*v))
        .y_label_formatter(&|v| short(*v))
        .draw()?;
    if let Some(r) = right {
        chart
            .configure_secondary_axes()
            .y_desc(r.desc)
            .y_label_formatter(&|v| short(*v))
            .draw()?;
    }
    draw_series(chart, series)
}

fn draw_series<'a, DB: DrawingBackend + 'a, X, Y, X2, Y2>(
    chart: &mut DualCoordChartContext<'a, DB, Cartesian2d<X, Y>, Cartesian2d<X2, Y2>>,
    series: &[Series<'_>],
) -> PlotResult
where
    DB::ErrorType: 'static,
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
    X2: Ranged,
    Y2: Ranged,
{
    for (i, s) in series.iter().enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        let style = if s.baseline {
            colour.mix(0.55).stroke_width(1)
        } else {
            colour.stroke_width(2)
        };
        chart
            .draw_series(LineSeries::new(s.points.iter().copied(), style))?
            .label(s.label.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 22, y)], style));
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

/// 12k, 3.4M, 250, 10, 0.25: short tick labels (whole numbers without decimals).
fn short(v: f64) -> String {
    let a = v.abs();
    if a >= 1e6 {
        format!("{:.1}M", v / 1e6)
    } else if a >= 1e4 {
        format!("{:.0}k", v / 1e3)
    } else if a >= 100.0 || (v - v.round()).abs() < 1e-9 {
        format!("{v:.0}")
    } else {
        format!("{v:.2}")
    }
}
