//! Convergence plots: e_rms on a log scale against steps, columns or seconds, one line per
//! solver, as SVG and PNG, in the style of the paper's figures 1–3.
//!
//! Drawn with plotters; text uses the DejaVu Sans font embedded in the binary (the `dejavu`
//! crate), so the PNG looks the same on a machine without fonts. Both formats go to any
//! [`std::io::Write`]; opening files is the caller's business.

use crate::error::EvalError;
use plotters::coord::Shift;
use plotters::prelude::*;
use radiosity_core::Real;
use std::io::Write;
use std::sync::Once;

/// One solver's curve: `(x, e_rms)` points in order of `x`.
#[derive(Clone, Debug, PartialEq)]
pub struct Curve {
    /// The legend label (the solver's name).
    pub label: String,
    /// The points; those with a non-positive or non-finite error are left out (log scale).
    pub points: Vec<(Real, Real)>,
}

/// What a plot shows.
#[derive(Clone, Debug, PartialEq)]
pub struct PlotSpec {
    /// The title above the plot.
    pub title: String,
    /// The label of the x axis.
    pub x_label: String,
    /// Width and height in pixels.
    pub size: (u32, u32),
}

/// Registers the embedded font once.
fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // Registration fails only for bytes that are not a font; these are DejaVu Sans.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular());
    });
}

fn plot_error(e: impl std::fmt::Display) -> EvalError {
    EvalError::Plot(e.to_string())
}

/// The drawable points of `curves` and the ranges of the axes, or `None` when nothing can be
/// drawn on a log scale.
fn ranges(curves: &[Curve]) -> Option<(Real, Real, Real)> {
    let points =
        curves.iter().flat_map(|c| c.points.iter()).filter(|(x, y)| x.is_finite() && y.is_finite() && *y > 0.0);
    let (mut x_max, mut y_min, mut y_max) = (0.0_f64, Real::INFINITY, 0.0_f64);
    for &(x, y) in points {
        x_max = x_max.max(x);
        y_min = y_min.min(y);
        y_max = y_max.max(y);
    }
    (y_max > 0.0).then(|| (x_max.max(Real::MIN_POSITIVE), y_min, y_max))
}

fn draw<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, curves: &[Curve], spec: &PlotSpec) -> Result<(), EvalError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(plot_error)?;
    let Some((x_max, y_min, y_max)) = ranges(curves) else {
        return Err(EvalError::Plot("no positive e_rms to plot".into()));
    };
    // Whole decades, so the log axis reads like the paper's.
    let (lo, hi) = (10f64.powf(y_min.log10().floor()), 10f64.powf(y_max.log10().ceil()));
    let mut chart = ChartBuilder::on(&root)
        .caption(&spec.title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(64)
        .build_cartesian_2d(0.0..x_max, (lo..hi).log_scale())
        .map_err(plot_error)?;
    chart
        .configure_mesh()
        .x_desc(spec.x_label.as_str())
        .y_desc("e_rms")
        .y_label_formatter(&|y| format!("{y:.0e}"))
        .x_label_formatter(&|x| if x_max >= 20.0 { format!("{x:.0}") } else { format!("{x:.2}") })
        .label_style(("sans-serif", 13))
        .draw()
        .map_err(plot_error)?;
    for (k, curve) in curves.iter().enumerate() {
        let color = Palette99::pick(k).to_rgba();
        let points = curve.points.iter().copied().filter(|(x, y)| x.is_finite() && y.is_finite() && *y > 0.0);
        chart
            .draw_series(LineSeries::new(points, color.stroke_width(2)))
            .map_err(plot_error)?
            .label(curve.label.as_str())
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], color.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 13))
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(plot_error)?;
    root.present().map_err(plot_error)
}

/// Writes the plot of `curves` as SVG.
pub fn write_svg(curves: &[Curve], spec: &PlotSpec, mut out: impl Write) -> Result<(), EvalError> {
    register_font();
    let mut svg = String::new();
    draw(SVGBackend::with_string(&mut svg, spec.size).into_drawing_area(), curves, spec)?;
    out.write_all(svg.as_bytes()).map_err(|e| EvalError::Plot(e.to_string()))
}

/// Writes the plot of `curves` as PNG.
pub fn write_png(curves: &[Curve], spec: &PlotSpec, out: impl Write) -> Result<(), EvalError> {
    register_font();
    let (w, h) = spec.size;
    let mut pixels = vec![0u8; (w * h * 3) as usize];
    draw(BitMapBackend::with_buffer(&mut pixels, spec.size).into_drawing_area(), curves, spec)?;
    let encoder = image::codecs::png::PngEncoder::new(out);
    image::ImageEncoder::write_image(encoder, &pixels, w, h, image::ExtendedColorType::Rgb8)
        .map_err(|e| EvalError::Plot(e.to_string()))
}
