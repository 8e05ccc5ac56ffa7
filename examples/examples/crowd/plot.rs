//! The crowd's figure per camera path: polygons per frame against the budget, above the
//! controller's `T_bias` per frame.

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::flight::{CameraPath, Run};

/// The chart's error type.
type PlotError = Box<dyn std::error::Error>;

/// A colour per run: without control, and with the two caps.
const COLOURS: [RGBColor; 3] = [
    RGBColor(120, 120, 120),
    RGBColor(214, 39, 40),
    RGBColor(31, 119, 180),
];

/// The band the controller aims at, and its centre line.
const BUDGET_GREEN: RGBColor = RGBColor(44, 160, 44);

/// Writes the SVG figure of `path`'s runs to `file`.
pub fn plot(
    file: &Path,
    path: CameraPath,
    runs: &[Run],
    instances: usize,
    budget: u64,
    epsilon: u64,
) -> Result<(), PlotError> {
    let root = SVGBackend::new(file, (1100, 900)).into_drawing_area();
    root.fill(&WHITE)?;
    let (top, bottom) = root.split_vertically(600);
    let caption = format!(
        "Polygons per frame, {} path ({instances} instances, budget {budget}, ε = {epsilon})",
        path.name(),
    );
    polygons_chart(&top, &caption, runs, budget, epsilon)?;
    bias_chart(&bottom, runs)?;
    root.present()?;
    Ok(())
}

/// Frames of the runs (all have as many).
fn frame_count(runs: &[Run]) -> usize {
    runs.first().map_or(0, |r| r.polygons.len())
}

/// Polygons drawn per frame by each run, over the budget's `±ε` band and line.
fn polygons_chart(
    area: &DrawingArea<SVGBackend<'_>, Shift>,
    caption: &str,
    runs: &[Run],
    budget: u64,
    epsilon: u64,
) -> Result<(), PlotError> {
    let frames = frame_count(runs);
    let ymax = runs
        .iter()
        .flat_map(|r| r.polygons.iter().copied())
        .chain([budget + epsilon])
        .max()
        .unwrap_or(1) as f64
        * 1.08;
    let mut chart = ChartBuilder::on(area)
        .caption(caption, ("sans-serif", 22))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(80)
        .build_cartesian_2d(0..frames, 0f64..ymax)?;
    chart
        .configure_mesh()
        .x_desc("frame")
        .y_desc("polygons drawn")
        .y_label_formatter(&|v| format!("{:.0}k", v / 1000.0))
        .draw()?;
    chart
        .draw_series(std::iter::once(Rectangle::new(
            [
                (0usize, budget.saturating_sub(epsilon) as f64),
                (frames, (budget + epsilon) as f64),
            ],
            BUDGET_GREEN.mix(0.15).filled(),
        )))?
        .label("budget ± ε")
        .legend(|(x, y)| {
            Rectangle::new(
                [(x, y - 5), (x + 20, y + 5)],
                BUDGET_GREEN.mix(0.3).filled(),
            )
        });
    chart.draw_series(LineSeries::new(
        [(0usize, budget as f64), (frames, budget as f64)],
        BUDGET_GREEN.stroke_width(1),
    ))?;
    for (run, colour) in runs.iter().zip(COLOURS) {
        chart
            .draw_series(LineSeries::new(
                run.polygons.iter().enumerate().map(|(f, &q)| (f, q as f64)),
                colour.stroke_width(2),
            ))?
            .label(run.label)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
    }
    draw_legend(&mut chart)
}

/// The controlled runs' `T_bias` per frame.
fn bias_chart(area: &DrawingArea<SVGBackend<'_>, Shift>, runs: &[Run]) -> Result<(), PlotError> {
    let frames = frame_count(runs);
    let (lo, hi) = runs
        .iter()
        .flat_map(|r| r.bias.iter().copied())
        .fold((0f32, 0f32), |(lo, hi), b| (lo.min(b), hi.max(b)));
    let pad = ((hi - lo) * 0.1).max(0.01);
    let mut chart = ChartBuilder::on(area)
        .caption("T_bias per frame (controller output)", ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(80)
        .build_cartesian_2d(0..frames, (lo - pad)..(hi + pad))?;
    chart
        .configure_mesh()
        .x_desc("frame")
        .y_desc("T_bias")
        .draw()?;
    for (run, colour) in runs.iter().zip(COLOURS) {
        if run.cap.is_none() {
            continue;
        }
        chart
            .draw_series(LineSeries::new(
                run.bias.iter().enumerate().map(|(f, &b)| (f, b)),
                colour.stroke_width(2),
            ))?
            .label(run.label)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
    }
    draw_legend(&mut chart)
}

/// The series' legend, at the bottom middle of the chart.
fn draw_legend<'a, C: CoordTranslate>(
    chart: &mut ChartContext<'a, SVGBackend<'a>, C>,
) -> Result<(), PlotError> {
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerMiddle)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}
