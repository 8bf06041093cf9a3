//! The report's plots, drawn as SVG with plotters: error against run time per scene, and key
//! metrics over past runs.

use aabench_renderer::{Counts, Reconstruction, Technique};
use plotters::coord::Shift;
use plotters::prelude::*;

/// The shape of a technique's points on the error-against-time plots.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shape {
    Square,
    Cross,
    /// A square with a cross inside.
    CrossedSquare,
    Triangle,
    Circle,
}

/// How a technique's points look on the plots: related techniques share a shape, filled for
/// the one that the hollow ones are measured against.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Marker {
    pub shape: Shape,
    pub filled: bool,
}

/// A technique's points on the plots: squares for the one-sample techniques (deferred shading
/// filled, SMAA hollow, TAA crossed), a cross for FXAA, triangles for the M×M grid (the
/// reference filled, MSAA hollow), discs for the paper's adaptive modes and circles for the
/// variants beyond it. One arm per technique, no catch-all: a new technique is asked for its
/// marker.
pub fn marker(technique: Technique) -> Marker {
    let (shape, filled) = match technique {
        Technique::Deferred => (Shape::Square, true),
        Technique::Fxaa => (Shape::Cross, false),
        Technique::Smaa => (Shape::Square, false),
        Technique::Taa => (Shape::CrossedSquare, false),
        Technique::Reference => (Shape::Triangle, true),
        Technique::Msaa => (Shape::Triangle, false),
        Technique::Adaptive(_, reconstruction, counts) => {
            (Shape::Circle, reconstruction == Reconstruction::Equal && counts == Counts::PerFrame)
        }
    };
    Marker { shape, filled }
}

/// One mode on the error-against-time plot.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    pub label: String,
    /// Its technique's ([`marker`]).
    pub marker: Marker,
    pub stalled: bool,
    /// Frame time median and its interval, ms.
    pub time: f64,
    pub time_low: f64,
    pub time_high: f64,
    /// The value the plot draws: its metric's (`report::ErrorPlot`), scaled to the axis.
    pub error: f64,
    /// On the scene's error-against-run-time front (run.json's `front`).
    pub on_front: bool,
}

/// The points on the front, fastest first: the line the plot draws through them.
fn front_line(points: &[&Point]) -> Vec<(f64, f64)> {
    let mut front: Vec<(f64, f64)> =
        points.iter().filter(|p| p.on_front).map(|p| (p.time, p.error)).collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    front
}

type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;

fn fail<E: std::fmt::Debug>(error: E) -> String {
    format!("plot: {error:?}")
}

/// A log range around `values`, padded so markers and labels stay inside.
fn log_range(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (low, high) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(low, high), v| (low.min(v), high.max(v)));
    if !low.is_finite() {
        return 0.1..10.0;
    }
    low / 1.6..high * 1.6
}

/// Renders `draw` into an SVG string of `size` pixels.
fn svg(size: (u32, u32), draw: impl FnOnce(&Area) -> Result<(), String>) -> Result<String, String> {
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
        root.fill(&WHITE).map_err(fail)?;
        draw(&root)?;
        root.present().map_err(fail)?;
    }
    // Inline SVG in HTML needs no namespace, and a page that must load nothing from the network
    // is easier to check without one.
    Ok(text.replacen(" xmlns=\"http://www.w3.org/2000/svg\"", "", 1))
}

/// Three significant digits at most, no trailing zeros beyond them: 1000, 250, 12.5, 0.125.
fn short_number(v: f64) -> String {
    let digits = if v.abs() >= 100.0 {
        0
    } else if v.abs() >= 10.0 {
        1
    } else if v.abs() >= 1.0 {
        2
    } else if v.abs() >= 0.01 || v == 0.0 {
        3
    } else {
        // Instability and FLIP run to 10⁻⁵: three decimals would print them all as 0.000.
        return format!("{v:.1e}");
    };
    format!("{v:.digits$}")
}

const UNSTALLED: RGBColor = RGBColor(31, 119, 180);
const STALLED: RGBColor = RGBColor(214, 96, 39);

/// Error against the truth over frame time, log-log: one point per mode with its time
/// interval, stalled and unstalled as two series, each with its Pareto front dashed. `axes`
/// names x and y.
pub fn error_against_time(title: &str, axes: [&str; 2], points: &[Point]) -> Result<String, String> {
    let [x_desc, y_desc] = axes;
    svg((820, 520), |root| {
        let x = log_range(points.iter().flat_map(|p| [p.time_low, p.time_high]));
        let y = log_range(points.iter().map(|p| p.error));
        let mut chart = ChartBuilder::on(root)
            .caption(title, ("sans-serif", 18))
            .margin(14)
            .x_label_area_size(44)
            .y_label_area_size(64)
            .build_cartesian_2d(x.log_scale(), y.log_scale())
            .map_err(fail)?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(y_desc)
            .x_label_formatter(&|v| short_number(*v))
            .y_label_formatter(&|v| short_number(*v))
            .light_line_style(WHITE.mix(0.0))
            .draw()
            .map_err(fail)?;
        for (stalled, colour, name) in [(false, UNSTALLED, "unstalled"), (true, STALLED, "stalled")] {
            let series: Vec<&Point> = points.iter().filter(|p| p.stalled == stalled).collect();
            if series.is_empty() {
                continue;
            }
            let style = ShapeStyle::from(&colour).filled();
            chart
                .draw_series(series.iter().map(|p| {
                    ErrorBar::new_horizontal(
                        p.error,
                        p.time_low,
                        p.time,
                        p.time_high,
                        colour.stroke_width(1),
                        6,
                    )
                }))
                .map_err(fail)?;
            chart
                .draw_series(DashedLineSeries::new(front_line(&series), 6, 4, colour.stroke_width(1)))
                .map_err(fail)?
                .label(if series.iter().any(|p| p.on_front) {
                    format!("{name} (dashed: the front)")
                } else {
                    name.to_string()
                })
                .legend(move |(x, y)| Circle::new((x, y), 4, style));
            let markers = series.iter().flat_map(|p| {
                let at = (p.time, p.error);
                marker_shapes(p.marker, colour).into_iter().map(move |shape| EmptyElement::at(at) + shape)
            });
            chart.draw_series(markers).map_err(fail)?;
            let font = ("sans-serif", 11).into_font().color(&colour);
            chart
                .draw_series(series.iter().map(|p| {
                    EmptyElement::at((p.time, p.error)) + Text::new(p.label.clone(), (6, -13), font.clone())
                }))
                .map_err(fail)?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.4))
            .draw()
            .map_err(fail)
    })
}

/// The shapes of a technique's marker, around the point: filled, or drawn in outline.
fn marker_shapes<DB: DrawingBackend>(
    marker: Marker,
    colour: RGBColor,
) -> Vec<DynElement<'static, DB, (i32, i32)>> {
    let style = if marker.filled { ShapeStyle::from(&colour).filled() } else { colour.stroke_width(2) };
    match marker.shape {
        Shape::Square => vec![Rectangle::new([(-4, -4), (4, 4)], style).into_dyn()],
        Shape::Cross => vec![Cross::new((0, 0), 5, colour.stroke_width(2)).into_dyn()],
        Shape::CrossedSquare => vec![
            Rectangle::new([(-5, -5), (5, 5)], colour.stroke_width(1)).into_dyn(),
            Cross::new((0, 0), 4, colour.stroke_width(1)).into_dyn(),
        ],
        Shape::Triangle => vec![TriangleMarker::new((0, 0), 6, style).into_dyn()],
        Shape::Circle => vec![Circle::new((0, 0), 4, style).into_dyn()],
    }
}

/// One line of a history plot: a value per run (`None` where a run lacks it).
#[derive(Debug, Clone)]
pub struct Series {
    pub name: String,
    pub values: Vec<Option<f64>>,
}

const PALETTE: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 96, 39),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(127, 127, 127),
];

/// A metric over past runs: x is the run (labelled by `runs`), one line per series.
pub fn history(title: &str, y_label: &str, runs: &[String], series: &[Series]) -> Result<String, String> {
    svg((760, 340), |root| {
        let values = series.iter().flat_map(|s| s.values.iter().flatten().copied());
        let (low, high) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| (l.min(v), h.max(v)));
        let (low, high) = if low.is_finite() { (low, high) } else { (0.0, 1.0) };
        let pad = ((high - low) * 0.1).max(high.abs() * 0.02).max(1e-6);
        let last = runs.len().saturating_sub(1).max(1) as f64;
        let mut chart = ChartBuilder::on(root)
            .caption(title, ("sans-serif", 16))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(-0.2..last + 0.2, low - pad..high + pad)
            .map_err(fail)?;
        let label = |x: &f64| runs.get(x.round() as usize).cloned().unwrap_or_default();
        chart
            .configure_mesh()
            .x_desc("run")
            .y_desc(y_label)
            .x_labels(runs.len().clamp(2, 8))
            .x_label_formatter(&label)
            .light_line_style(WHITE.mix(0.0))
            .draw()
            .map_err(fail)?;
        for (line, colour) in series.iter().zip(PALETTE.iter().cycle()) {
            let points: Vec<(f64, f64)> =
                line.values.iter().enumerate().filter_map(|(i, v)| v.map(|v| (i as f64, v))).collect();
            let style = ShapeStyle::from(colour).filled();
            chart
                .draw_series(LineSeries::new(points.iter().copied(), colour.stroke_width(2)))
                .map_err(fail)?
                .label(line.name.clone())
                .legend(move |(x, y)| Circle::new((x, y), 4, style));
            chart.draw_series(points.iter().map(|&p| Circle::new(p, 3, style))).map_err(fail)?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerLeft)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK.mix(0.4))
            .draw()
            .map_err(fail)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(label: &str, time: f64, error: f64) -> Point {
        Point {
            label: label.into(),
            marker: Marker { shape: Shape::Circle, filled: true },
            stalled: false,
            time,
            time_low: time * 0.9,
            time_high: time * 1.1,
            error,
            on_front: true,
        }
    }

    #[test]
    fn the_front_line_joins_the_front_fastest_first() {
        let mut points = [point("a", 10.0, 5.0), point("b", 20.0, 6.0), point("c", 30.0, 1.0)];
        points[1].on_front = false;
        let refs: Vec<&Point> = points.iter().collect();
        assert_eq!(front_line(&refs), [(10.0, 5.0), (30.0, 1.0)]);
    }

    #[test]
    fn small_numbers_keep_their_digits() {
        assert_eq!(short_number(250.4), "250");
        assert_eq!(short_number(0.0312), "0.031");
        assert_eq!(short_number(0.0), "0.000");
        assert_eq!(short_number(0.000_097_3), "9.7e-5");
    }

    #[test]
    fn plots_are_svg_with_their_labels_and_no_namespace_url() {
        let points = [point("adaptive 2×2", 40.0, 2.0), point("reference 2×2", 60.0, 1.5)];
        let text = error_against_time("thin", ["ms", "MSE"], &points).unwrap();
        assert!(text.starts_with("<svg"), "{}", &text[..40]);
        assert!(text.contains("adaptive 2×2") && text.contains("reference 2×2"));
        assert!(!text.contains("http"));
        let series = [Series { name: "speed-up 2×2".into(), values: vec![Some(1.2), None, Some(1.4)] }];
        let text = history("thin", "×", &["a".into(), "b".into(), "c".into()], &series).unwrap();
        assert!(text.contains("speed-up 2×2"));
    }
}
