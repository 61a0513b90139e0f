//! Convergence plots: e_rms on a log scale against steps, columns, rays or seconds, one line
//! per solver, as SVG and PNG, in the style of the paper's figures 1–3, readable in grey.
//!
//! ## Standard errors
//!
//! A solver whose answer is an estimate with a standard error ([`Curve::spread`]: the spread
//! of its replicates, summarised as e_rms is) is drawn over a **shaded band** in its colour,
//! from the bottom of the plot up to **twice its standard error**. The two summaries have the
//! same form (the squared standard error estimates the expected squared e_rms of an unbiased
//! mean), so an unbiased run's e_rms curve runs inside its band, near its middle on the log
//! scale; a curve above the band is off by more than its noise says (a bias, or an optimistic
//! bar). The legend says so (`shaded: up to 2 standard errors`). Bands overlap, and solvers of
//! one method share a colour: so each band is filled faintly and its top drawn as a thin line
//! in its colour, and every band stays readable where two cross.
//!
//! ## Power laws
//!
//! The x axis is linear or logarithmic ([`AxisScale`]). On a logarithmic one the plot is
//! log–log, where a power law is a straight line: the caller asks for it where one is expected
//! (a Monte Carlo estimate's error falls as `1/√rays`), with a **reference slope**
//! ([`PlotSpec::slope`], [`MONTE_CARLO_SLOPE`]). That slope is drawn as a dashed grey line
//! across the data, below the lowest curve's end, named in the legend (`slope −½`), so that a
//! curve parallel to it converges at that rate, and one steeper or flatter than it does not.
//! Points at x = 0 have no place on a logarithmic axis and are left out.
//!
//! ## Styles
//!
//! Every solver is drawn the same way in every plot, whatever else is plotted beside it:
//! its [`Style`] is a function of its name alone ([`style_of`]), never of its place in the
//! list. A name is read as a **base method** and a **variant**:
//!
//! - the base method (`pr`, `xu`, `feda`, `shao`, `relax`, `southwell`, `gauss-seidel`,
//!   `jacobi`, `sor`, …; `gs` is `gauss-seidel`, and a trailing number such as the `1.2` of
//!   `sor-1.2` is a parameter, not a method) picks the colour, from the colour-blind-safe
//!   palette of Okabe & Ito without its yellow (too pale on white), and the marker shape;
//! - the variant picks the dash pattern: point methods are solid, group-accelerated `S-gM`
//!   dashed, its memory variant `S-gM-mK` dotted, and group methods `group-S-gM` (shooting
//!   and gathering) dash-dotted, and node shooters on the hierarchy `h-S` short-dashed in the
//!   colour of their point method `S`. Parameters after a `:` (`pr-g30:f=auto`) swap the
//!   marker between filled and hollow; a node shooter's groups (`groups=clusters`, `spatial`,
//!   `unshot`) each move its marker one further along the list of markers.
//!
//! So colour tells the methods apart on screen, and marker and dash tell them apart in grey
//! or for readers who do not see the colours. Methods the table does not list get their
//! colour and marker from a stable hash (FNV-1a) of their name. Group and memory sizes do not
//! enter the style (`pr-g30` looks like `pr-g50`).
//!
//! ## Layout
//!
//! The legend sits to the right of the data area (below it when the labels are too long to
//! fit in 40% of the width), so it never covers a curve. The axes start where the data
//! starts: x runs from the smallest to the largest x plotted, and y, on a log scale, from the
//! smallest to the largest e_rms, widened by 3% of its span in decades so that the extreme
//! points do not lie on the frame. A log axis is labelled at 1, 2 and 5 times each power of
//! ten, with grid lines at the other whole multiples; a long one at every decade (or every
//! 2nd, 5th, … decade) so that its labels do not run together, a short one at every whole
//! multiple (or tenth) it spans. The y axis says what e_rms is, the area-weighted relative
//! RMS error of docs/design.md §6.1 ([`Y_LABEL`]), or just `e_rms (log scale)` ([`Y_LABEL_SHORT`])
//! (for certified bounds, [`BOUND_LABEL`] and [`BOUND_LABEL_SHORT`])
//! on a plot too short for the long label. Notes ([`PlotSpec::notes`]: who is left out of the
//! plot, and why) are written under it, wrapped to its width.
//!
//! Drawn with plotters; text uses the DejaVu Sans font embedded in the binary (the `dejavu`
//! crate), so the PNG looks the same on a machine without fonts. Both formats go to any
//! [`std::io::Write`]; opening files is the caller's business.
//!
//! ## References
//!
//! - M. Okabe and K. Ito, *Color Universal Design (CUD): how to make figures and
//!   presentations that are friendly to colorblind people*, 2008.

use crate::error::EvalError;
use plotters::coord::Shift;
use plotters::coord::ranged1d::ValueFormatter;
use plotters::prelude::*;
use radiosity_core::Real;
use std::io::Write;
use std::sync::Once;

/// One solver's curve: `(x, e_rms)` points in order of `x`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Curve {
    /// The legend label (the solver's name), which also sets the curve's [`Style`].
    pub label: String,
    /// The points; those with a non-positive or non-finite error are left out (log scale).
    pub points: Vec<(Real, Real)>,
    /// `(x, standard error)` points in order of `x`, for a solver with a standard error
    /// (module doc: drawn as a band up to twice it); empty for the others. Points with a
    /// non-positive or non-finite standard error are left out.
    pub spread: Vec<(Real, Real)>,
}

impl Curve {
    /// The curve `label` through `points`, without a standard error.
    pub fn new(label: impl Into<String>, points: Vec<(Real, Real)>) -> Curve {
        Curve { label: label.into(), points, spread: Vec::new() }
    }
}

/// The multiple of the standard error a band reaches (module doc).
pub const BAND_STANDARD_ERRORS: Real = 2.0;

/// The legend's entry for the bands.
pub const BAND_LABEL: &str = "shaded: up to 2 standard errors";

/// Opacity of a band's fill: faint, so that overlapping bands stay apart (module doc).
const BAND_OPACITY: f64 = 0.08;

/// Opacity of the thin line along a band's top.
const BAND_EDGE_OPACITY: f64 = 0.6;

/// The slope of a Monte Carlo estimate's error against its samples on log–log axes: it falls
/// as one over their square root.
pub const MONTE_CARLO_SLOPE: Real = -0.5;

/// The colour of the reference slope's line.
const GUIDE_COLOUR: RGBColor = RGBColor(110, 110, 110);

/// The dash pattern of the reference slope's line, unlike any solver's ([`Variant::dashes`]).
const GUIDE_DASHES: [u32; 2] = [7, 5];

/// How far below the lowest curve's end the reference slope runs, as a factor.
const GUIDE_BELOW: Real = 2.0;

/// How an axis is scaled.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AxisScale {
    /// Linear: steps, columns, seconds.
    #[default]
    Linear,
    /// Logarithmic: with the log y axis a power law is a straight line (module doc).
    Log,
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
    /// Whether the values are certified bounds on the relative L1 error (a comparison without
    /// a reference) rather than e_rms: the y axis says which ([`BOUND_LABEL`]).
    pub certified_bound: bool,
    /// The scale of the x axis (the y axis is always logarithmic).
    pub x_scale: AxisScale,
    /// The slope of a dashed reference line (module doc, "Power laws"), drawn only on a
    /// logarithmic x axis and named in the legend ([`slope_label`]).
    pub slope: Option<Real>,
    /// Sentences written under the plot: who is left out of it, and why.
    pub notes: Vec<String>,
}

impl PlotSpec {
    /// A plot of e_rms titled `title` against `x_label` on a linear axis, 800 × 500 pixels,
    /// without a reference slope or notes.
    pub fn new(title: impl Into<String>, x_label: impl Into<String>) -> PlotSpec {
        PlotSpec {
            title: title.into(),
            x_label: x_label.into(),
            size: (800, 500),
            certified_bound: false,
            x_scale: AxisScale::Linear,
            slope: None,
            notes: Vec::new(),
        }
    }
}

/// The legend's entry for a reference slope: `slope −½`; a half as `½`, a whole number as
/// it is, any other to two decimals, with a true minus sign.
pub fn slope_label(slope: Real) -> String {
    let magnitude = match slope.abs() {
        0.5 => "½".to_string(),
        m if m.fract() == 0.0 => format!("{m:.0}"),
        m => format!("{m:.2}"),
    };
    let sign = if slope < 0.0 { "−" } else { "" };
    format!("slope {sign}{magnitude}")
}

/// The label of the y axis.
pub const Y_LABEL: &str = "e_rms: area-weighted relative RMS error (log scale)";
/// The label of the y axis of a plot too short for [`Y_LABEL`].
pub const Y_LABEL_SHORT: &str = "e_rms (log scale)";
/// The label of the y axis of a plot of certified bounds ([`PlotSpec::certified_bound`]).
pub const BOUND_LABEL: &str = "certified bound on the relative L1 error (log scale)";
/// The label of the y axis of a plot of certified bounds too short for [`BOUND_LABEL`].
pub const BOUND_LABEL_SHORT: &str = "bound (log scale)";

/// The shape drawn at a few points of a curve and in its legend entry.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Marker {
    /// A disc.
    Circle,
    /// An upward triangle.
    Triangle,
    /// A square.
    Square,
    /// A square standing on a corner.
    Diamond,
    /// A diagonal cross.
    Cross,
    /// An upright cross.
    Plus,
}

/// How a family of solvers varies the point method: it sets the dash pattern.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Variant {
    /// A point method (`pr`, `xu`, `gauss-seidel`): solid.
    Point,
    /// Group-accelerated with `M = m` (`pr-g30`): dashed.
    GroupAccelerated,
    /// Group-accelerated with a larger memory (`pr-g30-m480`): dotted.
    GroupAcceleratedMemory,
    /// Group shooting or gathering (`group-pr-g30`, `group-gs-g30`): dash-dotted.
    Group,
    /// Shooting on the hierarchy (`h-pr`, `h-xu:groups=spatial`): short dashes.
    Hierarchy,
}

impl Variant {
    /// The dash pattern in pixels, alternately drawn and skipped; empty for a solid line.
    pub fn dashes(self) -> &'static [u32] {
        match self {
            Variant::Point => &[],
            Variant::GroupAccelerated => &[11, 6],
            Variant::GroupAcceleratedMemory => &[3, 4],
            Variant::Group => &[12, 4, 3, 4],
            Variant::Hierarchy => &[5, 3],
        }
    }
}

/// How one solver's curve is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Style {
    /// Line and marker colour, sRGB.
    pub colour: [u8; 3],
    /// The marker's shape.
    pub marker: Marker,
    /// Whether the marker is drawn filled (else as an outline).
    pub filled: bool,
    /// The variant, which sets the dash pattern ([`Variant::dashes`]).
    pub variant: Variant,
}

/// The Okabe–Ito palette without yellow: blue, vermillion, bluish green, reddish purple,
/// orange, sky blue, black.
const PALETTE: [[u8; 3]; 7] =
    [[0, 114, 178], [213, 94, 0], [0, 158, 115], [204, 121, 167], [230, 159, 0], [86, 180, 233], [0, 0, 0]];

/// Marker shapes with their fill, in the order methods take them. Seven colours and nine
/// markers: the first 63 methods get distinct pairs.
const MARKERS: [(Marker, bool); 9] = [
    (Marker::Circle, true),
    (Marker::Triangle, true),
    (Marker::Square, true),
    (Marker::Diamond, true),
    (Marker::Cross, true),
    (Marker::Circle, false),
    (Marker::Triangle, false),
    (Marker::Square, false),
    (Marker::Diamond, false),
];

/// Base methods with a fixed place in the palette, in order.
const METHODS: [&str; 14] = [
    "pr",
    "xu",
    "feda",
    "shao",
    "relax",
    "southwell",
    "gauss-seidel",
    "jacobi",
    "sor",
    "xu-direct",
    "xu-ambient",
    "cg",
    "gmres",
    "bicgstab",
];

/// The style of the solver called `name`; see the module documentation for the rule.
pub fn style_of(name: &str) -> Style {
    let (base, params) = name.split_once(':').map_or((name, ""), |(b, p)| (b, p));
    let base = base.trim();
    // A node shooter on the hierarchy (`h-xu`): its point method's colour, its own dash, and
    // a marker of its own for each kind of group.
    let (method, variant, shift) = match base.strip_prefix("h-") {
        Some(method) => {
            let kinds = ["groups=clusters", "groups=spatial", "groups=unshot"];
            let shift = kinds.iter().position(|k| params.split(':').any(|p| p == *k)).map_or(0, |k| k + 1);
            (method, Variant::Hierarchy, shift)
        }
        None => {
            let (method, variant) = method_and_variant(base);
            (method, variant, 0)
        }
    };
    let method = if method == "gs" { "gauss-seidel" } else { method };
    let index = METHODS.iter().position(|m| *m == method).unwrap_or_else(|| {
        // Past the table, so an unknown method does not take a listed one's place by default.
        METHODS.len() + (fnv1a(method) % (PALETTE.len() * MARKERS.len()) as u64) as usize
    });
    let (marker, filled) = MARKERS[(index + shift) % MARKERS.len()];
    let (marker, filled) = match (params.trim().is_empty(), marker) {
        (true, _) => (marker, filled),
        // A cross has no inside to leave empty: tuned, it stands upright.
        (false, Marker::Cross) => (Marker::Plus, true),
        (false, _) => (marker, !filled),
    };
    Style { colour: PALETTE[index % PALETTE.len()], marker, filled, variant }
}

/// The base method and the variant of a solver name without parameters.
fn method_and_variant(base: &str) -> (&str, Variant) {
    // Whether `s` is `prefix` followed by digits (`g30`, `m480`).
    let sized = |s: &str, prefix: char| {
        s.strip_prefix(prefix).is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
    };
    // `s` without a trailing `-gM`, if it has one.
    let without_group = |s: &str| -> Option<usize> {
        let (rest, last) = s.rsplit_once('-')?;
        sized(last, 'g').then_some(rest.len())
    };
    if let Some(rest) = base.strip_prefix("group-") {
        return (without_group(rest).map_or(rest, |end| &rest[..end]), Variant::Group);
    }
    if let Some((rest, last)) = base.rsplit_once('-') {
        if let Some(end) = without_group(rest).filter(|_| sized(last, 'm')) {
            return (&rest[..end], Variant::GroupAcceleratedMemory);
        }
    }
    if let Some(end) = without_group(base) {
        return (&base[..end], Variant::GroupAccelerated);
    }
    // A point method, perhaps with a numeric parameter (`sor-1.2`, `relax-1.5`, `gmres-30`).
    match base.rsplit_once('-') {
        Some((method, last)) if !method.is_empty() && last.parse::<Real>().is_ok() => (method, Variant::Point),
        _ => (base, Variant::Point),
    }
}

/// The 64-bit FNV-1a hash of `text`: stable across runs, platforms and compiler versions.
fn fnv1a(text: &str) -> u64 {
    text.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3))
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

/// Whether a point can go on a plot whose x axis is on `scale`: a logarithmic axis has no
/// place for x = 0.
fn drawable(scale: AxisScale) -> impl Fn(&(Real, Real)) -> bool {
    move |&(x, y)| x.is_finite() && y.is_finite() && y > 0.0 && (scale == AxisScale::Linear || x > 0.0)
}

/// The drawable points of a curve.
fn curve_points(curve: &Curve, scale: AxisScale) -> impl Iterator<Item = (Real, Real)> + '_ {
    curve.points.iter().copied().filter(drawable(scale))
}

/// The tops of a curve's band: `(x, 2 s)` for its drawable standard errors.
fn band_tops(curve: &Curve, scale: AxisScale) -> impl Iterator<Item = (Real, Real)> + '_ {
    curve.spread.iter().map(|&(x, s)| (x, BAND_STANDARD_ERRORS * s)).filter(drawable(scale))
}

/// Where a plot's data lies.
struct Frame {
    /// The x range.
    x: (Real, Real),
    /// The y range, padded.
    y: (Real, Real),
    /// The reference slope's line `y = c x^slope`, as `(slope, c)`, when one is drawn.
    guide: Option<(Real, Real)>,
}

/// The frame of the drawable points of `curves`, the tops of their bands and the reference
/// slope's lower end, or `None` when nothing can be drawn.
fn frame(curves: &[Curve], spec: &PlotSpec) -> Option<Frame> {
    let scale = spec.x_scale;
    let (mut x_min, mut x_max, mut y_min, mut y_max) = (Real::INFINITY, Real::NEG_INFINITY, Real::INFINITY, 0.0_f64);
    for (x, y) in curves.iter().flat_map(|c| curve_points(c, scale).chain(band_tops(c, scale))) {
        x_min = x_min.min(x);
        x_max = x_max.max(x);
        y_min = y_min.min(y);
        y_max = y_max.max(y);
    }
    if y_max <= 0.0 {
        return None;
    }
    if x_max <= x_min {
        x_max = match scale {
            AxisScale::Linear => x_min + 1.0,
            AxisScale::Log => x_min * 10.0,
        };
    }
    // The power law of the reference slope through the lowest of the curves' ends, lowered.
    let guide = spec.slope.filter(|_| scale == AxisScale::Log).and_then(|slope| {
        let c = curves
            .iter()
            .filter_map(|c| curve_points(c, scale).last())
            .map(|(x, y)| y * x.powf(-slope))
            .fold(Real::INFINITY, Real::min);
        (c.is_finite() && c > 0.0).then_some((slope, c / GUIDE_BELOW))
    });
    if let Some((slope, c)) = guide {
        y_min = y_min.min(c * x_min.powf(slope)).min(c * x_max.powf(slope));
    }
    // 3% of the span in decades, or a tenth of a decade around a single value.
    let decades = (y_max / y_min).log10();
    let pad = 10f64.powf(if decades > 0.0 { 0.03 * decades } else { 0.1 });
    Some(Frame { x: (x_min, x_max), y: (y_min / pad, y_max * pad), guide })
}

/// The ends of the line `y = c x^slope` inside the box `x` × `y` (all positive), or `None`
/// where it misses the box.
fn guide_ends((slope, c): (Real, Real), (x0, x1): (Real, Real), (lo, hi): (Real, Real)) -> Option<[(Real, Real); 2]> {
    let (mut a, mut b) = (x0, x1);
    if slope != 0.0 {
        // Where it crosses the bottom and the top.
        let (p, q) = ((lo / c).powf(1.0 / slope), (hi / c).powf(1.0 / slope));
        (a, b) = (a.max(p.min(q)), b.min(p.max(q)));
    } else if !(lo..=hi).contains(&c) {
        return None;
    }
    (a < b).then(|| [(a, c * a.powf(slope)), (b, c * b.powf(slope))])
}

/// The ticks of a log axis from `lo` to `hi` (positive) with at most `most` labels: those
/// labelled, and the grid lines between them (module doc, "Layout").
fn log_ticks(lo: Real, hi: Real, most: usize) -> (Vec<Real>, Vec<Real>) {
    // Every mantissa of `mantissas` times every `every`-th power of ten, inside the axis.
    let at = |mantissas: &[Real], every: i32| -> Vec<Real> {
        let (first, last) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
        (first..=last)
            .filter(|k| k.rem_euclid(every) == 0)
            .flat_map(|k| mantissas.iter().map(move |m| m * 10f64.powi(k)))
            .filter(|v| (lo..=hi).contains(v))
            .collect()
    };
    let digits: Vec<Real> = (1..=9).map(Real::from).collect();
    let tenths: Vec<Real> = (10..100).map(|m| Real::from(m) / 10.0).collect();
    let one_two_five = at(&[1.0, 2.0, 5.0], 1);
    let bold = if one_two_five.len() >= 2 {
        // Fewer labels on a long axis: every decade, then every 2nd, 5th, 10th, … decade.
        let sparser = [1, 2, 5, 10, 20, 50, 100, 200, 500].map(|every| at(&[1.0], every));
        std::iter::once(one_two_five).chain(sparser).find(|t| t.len() <= most).unwrap_or_default()
    } else {
        // A short axis: every whole mantissa, or every tenth, as many as fit.
        let finer = if at(&digits, 1).len() >= 2 { at(&digits, 1) } else { at(&tenths, 1) };
        let step = finer.len().div_ceil(most.max(1)).max(1);
        finer.into_iter().step_by(step).collect()
    };
    // Grid lines at the whole mantissas, or at the decades, while they are not too dense.
    let light = [at(&digits, 1), at(&[1.0], 1)]
        .into_iter()
        .find(|t| t.len() <= 8 * most)
        .unwrap_or_default()
        .into_iter()
        .filter(|v| !bold.contains(v))
        .collect();
    (bold, light)
}

/// A labelled tick of a log axis: `2e-5`, or `2.5e-5` off a whole mantissa.
fn tick_label(v: Real) -> String {
    let mantissa = v / 10f64.powf(v.log10().floor());
    if (mantissa - mantissa.round()).abs() < 1e-9 { format!("{v:.0e}") } else { format!("{v:.1e}") }
}

/// The most labels a log axis `pixels` long takes, `spacing` pixels apart.
fn most_labels(pixels: u32, spacing: u32) -> usize {
    (pixels / spacing).max(2) as usize
}

/// The text style of labels and the legend.
fn label_font() -> TextStyle<'static> {
    ("sans-serif", 13).into_font().color(&BLACK)
}

/// The text style of the notes under a plot.
fn note_font() -> TextStyle<'static> {
    ("sans-serif", 12).into_font().color(&RGBColor(60, 60, 60))
}

/// Where the legend goes.
enum LegendPlace {
    /// A column to the right, this many pixels wide.
    Right(u32),
    /// Rows below, this many pixels high, with this many entries per row.
    Below(u32, usize),
}

/// What a legend entry shows before its label.
enum Sample {
    /// A solver's line and marker.
    Curve(Style),
    /// The bands.
    Band,
    /// The reference slope.
    Guide,
}

/// Length of the line sample in a legend entry, and the gap before its label.
const SAMPLE: i32 = 40;
const SAMPLE_GAP: i32 = 8;
/// Height of one legend row.
const ROW: i32 = 20;
/// Height of one line of notes, and their left margin.
const NOTE_ROW: i32 = 16;
const NOTE_MARGIN: i32 = 12;

/// `texts` broken at spaces into lines at most `width` pixels wide in `font` (a longer word
/// on a line of its own).
fn wrap<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    texts: &[String],
    font: &TextStyle,
    width: u32,
) -> Result<Vec<String>, EvalError>
where
    DB::ErrorType: 'static,
{
    let mut lines = Vec::new();
    for text in texts {
        let mut line = String::new();
        for word in text.split_whitespace() {
            let longer = if line.is_empty() { word.to_string() } else { format!("{line} {word}") };
            if !line.is_empty() && area.estimate_text_size(&longer, font).map_err(plot_error)?.0 > width {
                lines.push(std::mem::replace(&mut line, word.to_string()));
            } else {
                line = longer;
            }
        }
        if !line.is_empty() {
            lines.push(line);
        }
    }
    Ok(lines)
}

fn draw<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, curves: &[Curve], spec: &PlotSpec) -> Result<(), EvalError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(plot_error)?;
    let Some(frame) = frame(curves, spec) else {
        return Err(EvalError::Plot("no positive e_rms to plot".into()));
    };
    let font = label_font();
    // The notes under everything else, across the whole width.
    let (width, height) = root.dim_in_pixel();
    let notes = wrap(&root, &spec.notes, &note_font(), width.saturating_sub(2 * NOTE_MARGIN as u32))?;
    let notes_height = if notes.is_empty() { 0 } else { notes.len() as u32 * NOTE_ROW as u32 + 8 };
    let (main, note_area) = root.split_vertically(height.saturating_sub(notes_height));
    let (width, height) = main.dim_in_pixel();
    let scale = spec.x_scale;
    // The legend's entries: every curve, then the bands' meaning when there is a band, then
    // the reference slope when it is drawn.
    let banded = curves.iter().any(|c| band_tops(c, scale).next().is_some());
    let guide_label = frame.guide.map(|(slope, _)| slope_label(slope));
    let entries: Vec<(Sample, &str)> = curves
        .iter()
        .map(|c| (Sample::Curve(style_of(&c.label)), c.label.as_str()))
        .chain(banded.then_some((Sample::Band, BAND_LABEL)))
        .chain(guide_label.as_deref().map(|label| (Sample::Guide, label)))
        .collect();
    let mut widest = 0;
    for (_, label) in &entries {
        widest = widest.max(main.estimate_text_size(label, &font).map_err(plot_error)?.0);
    }
    let entry = (SAMPLE + SAMPLE_GAP) as u32 + widest + 16;
    let place = if entry <= width * 2 / 5 {
        LegendPlace::Right(entry)
    } else {
        let per_row = (width / entry.min(width).max(1)).max(1) as usize;
        let rows = entries.len().div_ceil(per_row) as u32;
        LegendPlace::Below(rows * ROW as u32 + 12, per_row)
    };
    let (plot_area, legend_area) = match place {
        LegendPlace::Right(w) => main.split_horizontally(width.saturating_sub(w)),
        LegendPlace::Below(h, _) => main.split_vertically(height.saturating_sub(h)),
    };

    // The title at 20 pixels, smaller (down to 12) when it would not fit the plot's width.
    let title_size = (12..=20)
        .rev()
        .find(|&size| {
            let style: TextStyle = ("sans-serif", size).into_font().into();
            plot_area.estimate_text_size(&spec.title, &style).is_ok_and(|(w, _)| w + 24 <= plot_area.dim_in_pixel().0)
        })
        .unwrap_or(12);
    let mut builder = ChartBuilder::on(&plot_area);
    builder.caption(&spec.title, ("sans-serif", title_size)).margin(12).x_label_area_size(40).y_label_area_size(64);
    let ((x_min, x_max), (lo, hi)) = (frame.x, frame.y);
    // Log axes carry their own ticks: a label at least about every 28 pixels up the data (the
    // plot less its margins, title and x labels), every 50 across (labels such as `2e5`).
    let (plot_width, plot_height) = plot_area.dim_in_pixel();
    let (bold, light) = log_ticks(lo, hi, most_labels(plot_height.saturating_sub(100), 28));
    let y_axis = (lo..hi).log_scale().with_key_points(bold).with_light_points(light);
    match scale {
        AxisScale::Linear => {
            let chart = builder.build_cartesian_2d(x_min..x_max, y_axis).map_err(plot_error)?;
            draw_data(chart, &plot_area, curves, spec, &frame)?;
        }
        AxisScale::Log => {
            let (bold, light) = log_ticks(x_min, x_max, most_labels(plot_width.saturating_sub(100), 50));
            let x_axis = (x_min..x_max).log_scale().with_key_points(bold).with_light_points(light);
            let chart = builder.build_cartesian_2d(x_axis, y_axis).map_err(plot_error)?;
            draw_data(chart, &plot_area, curves, spec, &frame)?;
        }
    }

    // The legend: a framed list of samples and names, outside the data area.
    let (lx, ly) = match place {
        LegendPlace::Right(_) => (4, 40),
        LegendPlace::Below(..) => (64, 4),
    };
    let per_row = match place {
        LegendPlace::Right(_) => 1,
        LegendPlace::Below(_, n) => n,
    };
    let rows = entries.len().div_ceil(per_row) as i32;
    let columns = per_row.min(entries.len()) as i32;
    let frame = [(lx, ly), (lx + columns * entry as i32, ly + rows * ROW + 8)];
    legend_area.draw(&Rectangle::new(frame, BLACK.mix(0.6).stroke_width(1))).map_err(plot_error)?;
    let text = font.pos(plotters::style::text_anchor::Pos::new(
        plotters::style::text_anchor::HPos::Left,
        plotters::style::text_anchor::VPos::Center,
    ));
    for (k, (sample, label)) in entries.iter().enumerate() {
        let (row, column) = ((k / per_row) as i32, (k % per_row) as i32);
        let x = lx + 8 + column * entry as i32;
        let y = ly + 4 + row * ROW + ROW / 2;
        let line = [(Real::from(x), Real::from(y)), (Real::from(x + SAMPLE), Real::from(y))];
        match sample {
            Sample::Curve(style) => {
                draw_line(&legend_area, &line, *style)?;
                draw_marker(&legend_area, (x + SAMPLE / 2, y), *style)?;
            }
            Sample::Band => {
                let (top, bottom) = (y - ROW / 2 + 4, y + ROW / 2 - 4);
                let swatch = [(x, top), (x + SAMPLE, bottom)];
                legend_area.draw(&Rectangle::new(swatch, BLACK.mix(0.12).filled())).map_err(plot_error)?;
                let edge = [(Real::from(x), Real::from(top)), (Real::from(x + SAMPLE), Real::from(top))];
                draw_path(&legend_area, &edge, BLACK.mix(BAND_EDGE_OPACITY).stroke_width(1), &[])?;
            }
            Sample::Guide => draw_path(&legend_area, &line, GUIDE_COLOUR.stroke_width(2), &GUIDE_DASHES)?,
        }
        legend_area.draw_text(label, &text, (x + SAMPLE + SAMPLE_GAP, y)).map_err(plot_error)?;
    }
    let note = note_font().pos(plotters::style::text_anchor::Pos::new(
        plotters::style::text_anchor::HPos::Left,
        plotters::style::text_anchor::VPos::Top,
    ));
    for (k, line) in notes.iter().enumerate() {
        note_area.draw_text(line, &note, (NOTE_MARGIN, 4 + k as i32 * NOTE_ROW)).map_err(plot_error)?;
    }
    root.present().map_err(plot_error)
}

/// Draws the axes, the bands, the reference slope and the curves on `chart`, whose x axis is
/// linear or logarithmic (`X`) and y axis logarithmic (`Y`).
fn draw_data<DB, X, Y>(
    mut chart: ChartContext<'_, DB, Cartesian2d<X, Y>>,
    plot_area: &DrawingArea<DB, Shift>,
    curves: &[Curve],
    spec: &PlotSpec,
    frame: &Frame,
) -> Result<(), EvalError>
where
    DB: DrawingBackend,
    DB::ErrorType: 'static,
    X: Ranged<ValueType = Real> + ValueFormatter<Real>,
    Y: Ranged<ValueType = Real> + ValueFormatter<Real>,
{
    let ((x_min, x_max), (_, hi)) = (frame.x, frame.y);
    let scale = spec.x_scale;
    let span = x_max - x_min;
    let font = label_font();
    let data_height = chart.plotting_area().dim_in_pixel().1;
    let (full, short) = if spec.certified_bound { (BOUND_LABEL, BOUND_LABEL_SHORT) } else { (Y_LABEL, Y_LABEL_SHORT) };
    let long = plot_area.estimate_text_size(full, &font).map_err(plot_error)?.0;
    let y_label = if long + 8 <= data_height { full } else { short };
    let x_format = |x: &Real| match scale {
        AxisScale::Linear if span >= 20.0 => format!("{x:.0}"),
        AxisScale::Linear => format!("{x:.2}"),
        AxisScale::Log => tick_label(*x),
    };
    let y_format = |y: &Real| tick_label(*y);
    chart
        .configure_mesh()
        .x_desc(spec.x_label.as_str())
        .y_desc(y_label)
        .axis_desc_style(("sans-serif", 13))
        // About one x label per 90 pixels, so that four-digit labels do not run together.
        .x_labels((plot_area.dim_in_pixel().0 / 90).max(2) as usize)
        .y_label_formatter(&y_format)
        .x_label_formatter(&x_format)
        .label_style(("sans-serif", 13))
        .draw()
        .map_err(plot_error)?;

    let area = chart.plotting_area().strip_coord_spec();
    let (bx, by) = area.get_base_pixel();
    let bottom = Real::from(area.dim_in_pixel().1);
    let pixel = |(x, y): (Real, Real)| {
        let (px, py) = chart.backend_coord(&(x, y));
        (Real::from(px - bx), Real::from(py - by))
    };
    // The bands first, under every line.
    for curve in curves {
        let tops: Vec<(Real, Real)> = band_tops(curve, scale).map(|(x, y)| pixel((x, y.min(hi)))).collect();
        draw_band(&area, &tops, bottom, style_of(&curve.label))?;
    }
    // The reference slope under the curves.
    if let Some(ends) = frame.guide.and_then(|guide| guide_ends(guide, frame.x, frame.y)) {
        draw_path(&area, &ends.map(pixel), GUIDE_COLOUR.stroke_width(2), &GUIDE_DASHES)?;
    }
    for curve in curves {
        let style = style_of(&curve.label);
        let points: Vec<(Real, Real)> = curve_points(curve, scale).map(pixel).collect();
        draw_line(&area, &points, style)?;
        // About seven markers per curve, evenly spaced along it as drawn (on a log axis the
        // points crowd to the right), from a place that depends on the name, so that curves
        // running together do not hide each other's markers.
        let phase = (fnv1a(&curve.label) % 1000) as Real / 1000.0;
        for (x, y) in marker_points(&points, phase) {
            draw_marker(&area, (x.round() as i32, y.round() as i32), style)?;
        }
    }
    Ok(())
}

/// Where the markers of the polyline `points` (pixels) go: at about seven of its points,
/// evenly spaced along its length, the first `phase` (a fraction of the spacing) along it.
fn marker_points(points: &[(Real, Real)], phase: Real) -> Vec<(Real, Real)> {
    let step = |a: (Real, Real), b: (Real, Real)| (b.0 - a.0).hypot(b.1 - a.1);
    let gap = points.windows(2).map(|w| step(w[0], w[1])).sum::<Real>() / 7.0;
    if gap <= 0.0 {
        return points.first().copied().into_iter().collect();
    }
    let (mut walked, mut next, mut marked) = (0.0, phase * gap, Vec::new());
    for (k, &p) in points.iter().enumerate() {
        if k > 0 {
            walked += step(points[k - 1], p);
        }
        if walked >= next {
            marked.push(p);
            while next <= walked {
                next += gap;
            }
        }
    }
    marked
}

/// Fills the band under `tops` (pixels of `area`, in order of x) down to `bottom`, in the
/// style's colour, faintly, and draws its top as a thin line (module doc).
fn draw_band<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    tops: &[(Real, Real)],
    bottom: Real,
    style: Style,
) -> Result<(), EvalError>
where
    DB::ErrorType: 'static,
{
    let (Some(first), Some(last)) = (tops.first(), tops.last()) else { return Ok(()) };
    let mut outline: Vec<(i32, i32)> = tops.iter().map(|&(x, y)| (x.round() as i32, y.round() as i32)).collect();
    // A single point is a band one pixel wide either side.
    if tops.len() == 1 {
        outline = vec![
            (first.0.round() as i32 - 1, first.1.round() as i32),
            (first.0.round() as i32 + 1, first.1.round() as i32),
        ];
    }
    let (left, right) = (outline[0].0, outline[outline.len() - 1].0.max(last.0.round() as i32));
    outline.extend([(right, bottom.round() as i32), (left, bottom.round() as i32)]);
    let [r, g, b] = style.colour;
    area.draw(&Polygon::new(outline, RGBColor(r, g, b).mix(BAND_OPACITY).filled())).map_err(plot_error)?;
    draw_path(area, tops, RGBColor(r, g, b).mix(BAND_EDGE_OPACITY).stroke_width(1), &[])
}

/// Draws the polyline `points` (pixels of `area`) with the style's colour and dash pattern.
fn draw_line<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    points: &[(Real, Real)],
    style: Style,
) -> Result<(), EvalError>
where
    DB::ErrorType: 'static,
{
    let [r, g, b] = style.colour;
    draw_path(area, points, RGBColor(r, g, b).stroke_width(2), style.variant.dashes())
}

/// Draws the polyline `points` (pixels of `area`) with `stroke`, dashed by `pattern`
/// ([`dashes`]).
fn draw_path<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    points: &[(Real, Real)],
    stroke: ShapeStyle,
    pattern: &[u32],
) -> Result<(), EvalError>
where
    DB::ErrorType: 'static,
{
    for piece in dashes(points, pattern) {
        let piece: Vec<(i32, i32)> = piece.iter().map(|&(x, y)| (x.round() as i32, y.round() as i32)).collect();
        area.draw(&PathElement::new(piece, stroke)).map_err(plot_error)?;
    }
    Ok(())
}

/// The drawn pieces of the polyline `points` under the dash `pattern` (lengths in pixels,
/// alternately drawn and skipped, starting with a drawn one; empty: one solid piece).
fn dashes(points: &[(Real, Real)], pattern: &[u32]) -> Vec<Vec<(Real, Real)>> {
    if points.len() < 2 || pattern.is_empty() {
        return vec![points.to_vec()];
    }
    let mut pieces = Vec::new();
    let mut current = vec![points[0]];
    let (mut k, mut left) = (0, Real::from(pattern[0]));
    for pair in points.windows(2) {
        let (mut start, end) = (pair[0], pair[1]);
        let mut length = (end.0 - start.0).hypot(end.1 - start.1);
        while length > left {
            let f = left / length;
            let p = (start.0 + f * (end.0 - start.0), start.1 + f * (end.1 - start.1));
            if k % 2 == 0 {
                current.push(p);
                pieces.push(std::mem::take(&mut current));
            } else {
                current = vec![p];
            }
            length -= left;
            start = p;
            k = (k + 1) % pattern.len();
            left = Real::from(pattern[k]);
        }
        left -= length;
        if k % 2 == 0 {
            current.push(end);
        }
    }
    if current.len() > 1 {
        pieces.push(current);
    }
    pieces
}

/// Draws the style's marker centred on `(x, y)` (pixels of `area`).
fn draw_marker<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    (x, y): (i32, i32),
    style: Style,
) -> Result<(), EvalError>
where
    DB::ErrorType: 'static,
{
    const R: i32 = 4;
    let [r, g, b] = style.colour;
    let colour = RGBColor(r, g, b);
    let shape = if style.filled { colour.filled() } else { colour.stroke_width(2) };
    let outline = |corners: Vec<(i32, i32)>| -> Result<(), EvalError> {
        if style.filled {
            area.draw(&Polygon::new(corners, shape)).map_err(plot_error)
        } else {
            let mut closed = corners.clone();
            closed.push(corners[0]);
            area.draw(&PathElement::new(closed, shape)).map_err(plot_error)
        }
    };
    match style.marker {
        Marker::Circle => area.draw(&Circle::new((x, y), R, shape)).map_err(plot_error),
        Marker::Square => area.draw(&Rectangle::new([(x - R, y - R), (x + R, y + R)], shape)).map_err(plot_error),
        Marker::Triangle => outline(vec![(x, y - R - 1), (x + R + 1, y + R), (x - R - 1, y + R)]),
        Marker::Diamond => outline(vec![(x, y - R - 1), (x + R + 1, y), (x, y + R + 1), (x - R - 1, y)]),
        Marker::Cross | Marker::Plus => {
            let stroke = colour.stroke_width(2);
            let arms = if style.marker == Marker::Cross {
                [[(x - R, y - R), (x + R, y + R)], [(x - R, y + R), (x + R, y - R)]]
            } else {
                [[(x - R - 1, y), (x + R + 1, y)], [(x, y - R - 1), (x, y + R + 1)]]
            };
            for arm in arms {
                area.draw(&PathElement::new(arm.to_vec(), stroke)).map_err(plot_error)?;
            }
            Ok(())
        }
    }
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
    crate::view::png_image::write_rgb8(out, &pixels, w, h)
}
