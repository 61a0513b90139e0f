//! Convergence plots: SVG with the solvers' names and what e_rms is, PNG of the right size
//! with lines drawn and the legend beside the data, one style per solver name whatever else
//! is plotted, axes that start where the data starts, standard errors as bands named in the
//! legend that stay light where they overlap, a power law straight on log–log axes beside its
//! named reference slope, notes wrapped under the plot, and a clear error when nothing can go
//! on a log scale.

use radiosity_eval::EvalError;
use radiosity_eval::Rgb8;
use radiosity_eval::{
    AxisScale, BOUND_LABEL, Curve, MONTE_CARLO_SLOPE, Marker, PlotSpec, Variant, Y_LABEL, Y_LABEL_SHORT, slope_label,
    style_of, write_png, write_svg,
};
use std::collections::HashSet;

fn decay(rate: f64) -> Vec<(f64, f64)> {
    (0..=100).map(|s| (s as f64, (-rate * s as f64).exp())).collect()
}

fn curves() -> Vec<Curve> {
    vec![
        Curve { label: "pr".into(), spread: Vec::new(), points: decay(0.05) },
        Curve { label: "xu-g30-m480".into(), spread: Vec::new(), points: decay(0.12) },
    ]
}

fn spec() -> PlotSpec {
    PlotSpec { size: (480, 320), ..PlotSpec::new("multi-cubes", "shooting steps") }
}

fn png(curves: &[Curve], spec: &PlotSpec) -> Rgb8 {
    let mut out = Vec::new();
    write_png(curves, spec, &mut out).unwrap();
    Rgb8::decode(&out).unwrap()
}

#[test]
fn svg_names_every_solver_and_the_axes() {
    let mut out = Vec::new();
    write_svg(&curves(), &spec(), &mut out).unwrap();
    let svg = String::from_utf8(out).unwrap();
    for text in ["<svg", "pr", "xu-g30-m480", "shooting steps", "multi-cubes", "1e-5", "e_rms"] {
        assert!(svg.contains(text), "missing {text}");
    }
    // The full y label on a plot of the size `compare` draws, the short one on a small plot.
    assert!(svg.contains(Y_LABEL_SHORT) && !svg.contains(Y_LABEL), "the long label does not fit 320 pixels");
    let mut out = Vec::new();
    write_svg(&curves(), &PlotSpec { size: (800, 500), ..spec() }, &mut out).unwrap();
    assert!(String::from_utf8(out).unwrap().contains(Y_LABEL));
    assert!(Y_LABEL.contains("e_rms") && Y_LABEL.contains("area-weighted relative RMS error"));
    // A plot of certified bounds says so, not e_rms.
    let mut out = Vec::new();
    write_svg(&curves(), &PlotSpec { size: (800, 500), certified_bound: true, ..spec() }, &mut out).unwrap();
    let svg = String::from_utf8(out).unwrap();
    assert!(svg.contains(BOUND_LABEL) && !svg.contains("e_rms"), "the bound's label");
}

#[test]
fn a_node_shooter_takes_its_point_methods_colour_and_each_kind_of_group_a_marker() {
    for method in ["pr", "xu", "southwell", "jacobi", "gauss-seidel"] {
        let (point, node) = (style_of(method), style_of(&format!("h-{method}")));
        assert_eq!((node.colour, node.variant), (point.colour, Variant::Hierarchy), "h-{method}");
    }
    let names = ["h-xu", "h-xu:groups=clusters", "h-xu:groups=spatial", "h-xu:groups=unshot"];
    let grey: HashSet<_> = names.iter().map(|n| style_of(n)).map(|s| (s.marker, s.filled)).collect();
    assert_eq!(grey.len(), names.len(), "{names:?}");
    let dashes: HashSet<_> = [Variant::Point, Variant::GroupAccelerated, Variant::Group, Variant::Hierarchy]
        .iter()
        .map(|v| v.dashes())
        .collect();
    assert_eq!(dashes.len(), 4);
}

#[test]
fn png_has_the_size_and_draws_in_colour() {
    let img = png(&curves(), &spec());
    assert_eq!((img.width, img.height), (480, 320));
    // Lines and text: some pixels are neither white nor grey.
    let coloured = img.enumerate().filter(|(_, _, p)| p.iter().max().unwrap() - p.iter().min().unwrap() > 60).count();
    assert!(coloured > 200, "{coloured} coloured pixels");
}

/// The pixels of `colour` right of the widest gap between columns holding that colour (the
/// legend sample, when one curve has the colour), relative to their top left corner.
fn legend_sample(img: &Rgb8, colour: [u8; 3]) -> HashSet<(u32, u32)> {
    let pixels: Vec<(u32, u32)> = img.enumerate().filter(|(_, _, p)| *p == colour).map(|(x, y, _)| (x, y)).collect();
    let mut columns: Vec<u32> = pixels.iter().map(|&(x, _)| x).collect();
    columns.sort_unstable();
    columns.dedup();
    let (_, at) = columns.windows(2).map(|w| (w[1] - w[0], w[1])).max().unwrap();
    let sample: Vec<(u32, u32)> = pixels.into_iter().filter(|&(x, _)| x >= at).collect();
    let (x0, y0) = (sample.iter().map(|p| p.0).min().unwrap(), sample.iter().map(|p| p.1).min().unwrap());
    sample.into_iter().map(|(x, y)| (x - x0, y - y0)).collect()
}

#[test]
fn a_name_has_the_same_style_whatever_else_is_plotted() {
    // pr drawn alone, and fourth after three others: its legend sample (colour, dashes and
    // marker) is drawn pixel for pixel the same.
    let alone = vec![Curve { label: "pr".into(), spread: Vec::new(), points: decay(0.05) }];
    let mut crowded: Vec<Curve> = ["xu", "feda", "xu-g30"]
        .iter()
        .map(|&l| Curve { label: l.into(), spread: Vec::new(), points: decay(0.2) })
        .collect();
    crowded.push(alone[0].clone());
    let pr = style_of("pr").colour;
    let (a, b) = (legend_sample(&png(&alone, &spec()), pr), legend_sample(&png(&crowded, &spec()), pr));
    assert!(a.len() > 40, "{} pixels", a.len());
    assert_eq!(a, b);
    // The others are drawn in other colours.
    for other in ["xu", "feda", "xu-g30"] {
        assert_ne!(style_of(other).colour, pr, "{other}");
    }
}

#[test]
fn the_default_and_the_paper_solvers_have_distinct_styles_in_grey_too() {
    for names in [
        &["pr", "xu", "pr-g30", "xu-g30", "pr-g30-m480", "xu-g30-m480"][..],
        &["pr-g50", "pr-g50-m500", "xu-g50", "xu-g50-m500"][..],
    ] {
        let styles: Vec<_> = names.iter().map(|n| style_of(n)).collect();
        assert_eq!(styles.iter().collect::<HashSet<_>>().len(), names.len(), "{names:?}");
        // Without colour: marker and dash pattern alone tell them apart.
        let grey: HashSet<_> = styles.iter().map(|s| (s.marker, s.filled, s.variant)).collect();
        assert_eq!(grey.len(), names.len(), "{names:?}");
    }
}

#[test]
fn the_method_picks_the_colour_and_marker_and_the_variant_the_dashes() {
    let pr = style_of("pr");
    for (name, variant) in [
        ("pr", Variant::Point),
        ("pr-g30", Variant::GroupAccelerated),
        ("pr-g50-m500", Variant::GroupAcceleratedMemory),
        ("group-pr-g30", Variant::Group),
    ] {
        let s = style_of(name);
        assert_eq!((s.colour, s.marker, s.filled, s.variant), (pr.colour, pr.marker, pr.filled, variant), "{name}");
    }
    let dashes: HashSet<_> =
        [Variant::Point, Variant::GroupAccelerated, Variant::GroupAcceleratedMemory, Variant::Group]
            .iter()
            .map(|v| v.dashes())
            .collect();
    assert_eq!(dashes.len(), 4);
    assert!(Variant::Point.dashes().is_empty());
    // gs is Gauss-Seidel; a numeric parameter is not a method; parameters after ':' swap the
    // marker's fill.
    assert_eq!(style_of("group-gs-g30").colour, style_of("gauss-seidel").colour);
    assert_eq!(style_of("group-gs-g30").marker, style_of("gauss-seidel").marker);
    assert_eq!(style_of("sor-1.2"), style_of("sor-1.8"));
    assert_eq!(style_of("relax-1.5").variant, Variant::Point);
    let tuned = style_of("pr-g30:f=auto");
    assert_eq!((tuned.colour, tuned.variant), (pr.colour, Variant::GroupAccelerated));
    assert_ne!(tuned.filled, pr.filled);
    assert_ne!(style_of("relax-1.5:x=1").marker, Marker::Cross);
}

#[test]
fn unknown_names_get_a_stable_style_of_their_own() {
    // The hash is FNV-1a, fixed: the same name gives the same style on every machine.
    let mine = style_of("chebyshev-jacobi");
    assert_eq!(style_of("chebyshev-jacobi"), mine);
    assert_eq!(style_of("chebyshev-jacobi-g30").colour, mine.colour);
    let others: HashSet<_> =
        ["chebyshev", "my-solver", "jacobi-chebyshev", "krylov"].iter().map(|n| style_of(n)).collect();
    assert!(others.len() >= 3, "{others:?}");
}

#[test]
fn the_legend_sits_right_of_the_data_and_covers_none_of_it() {
    // A solid curve that runs across the whole data area near its top, where a legend inside
    // the plot would go.
    let flat = vec![Curve {
        label: "xu".into(),
        spread: Vec::new(),
        points: (0..=50).map(|s| (s as f64, 1.0 - 1e-3 * s as f64)).collect(),
    }];
    let img = png(&flat, &spec());
    let xu = style_of("xu").colour;
    let mut columns: Vec<u32> = img.enumerate().filter(|(_, _, p)| *p == xu).map(|(x, _, _)| x).collect();
    columns.sort_unstable();
    columns.dedup();
    // Two groups of columns in xu's colour: the curve, and right of a gap the legend's sample.
    let (gap, at) = columns.windows(2).map(|w| (w[1] - w[0], w[1])).max().unwrap();
    assert!(gap > 10, "no gap between the data and the legend: {columns:?}");
    let (data, legend): (Vec<u32>, Vec<u32>) = columns.iter().partition(|&&x| x < at);
    let (first, last) = (data[0], data[data.len() - 1]);
    assert!(last - first > 250, "the curve spans {first}..{last}");
    // Every column of the curve holds some of it: nothing covers it.
    assert_eq!(data.len() as u32, last - first + 1, "the curve is hidden in places");
    // The legend sample is short, and entirely right of the data.
    assert!(legend.len() <= 48 && legend[0] > last, "{legend:?}");
    let rows: Vec<u32> = img.enumerate().filter(|(x, _, p)| *p == xu && *x >= at).map(|(_, y, _)| y).collect();
    assert!(rows.iter().max().unwrap() - rows.iter().min().unwrap() <= 10, "the legend sample is one row");
}

#[test]
fn a_legend_too_wide_for_the_side_goes_below_the_data() {
    let label = "xu with a label far too long to sit beside a plot of this width".to_string();
    let xu = style_of(&label).colour;
    let curve = vec![Curve {
        label,
        spread: Vec::new(),
        points: (0..=50).map(|s| (s as f64, 1.0 - 1e-3 * s as f64)).collect(),
    }];
    let img = png(&curve, &spec());
    // The curve in the data area, and below a gap the legend sample, one row near the bottom.
    let mut rows: Vec<u32> = img.enumerate().filter(|(_, _, p)| *p == xu).map(|(_, y, _)| y).collect();
    rows.sort_unstable();
    rows.dedup();
    let (gap, at) = rows.windows(2).map(|w| (w[1] - w[0], w[1])).max().unwrap();
    assert!(gap > 20, "no gap between the data and the legend: {rows:?}");
    let legend: Vec<u32> = rows.iter().copied().filter(|&y| y >= at).collect();
    assert!(legend[0] > 320 * 4 / 5 && legend[legend.len() - 1] - legend[0] <= 10, "{legend:?}");
}

/// The texts of an SVG, trimmed.
fn svg_texts(svg: &str) -> Vec<String> {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| Some(t.split_once('>')?.1.split_once("</text>")?.0.trim().to_string()))
        .collect()
}

#[test]
fn the_axes_start_where_the_data_starts() {
    // x from 1000 to 2000 and e_rms from 1e-3 to 1e-2: with the axis at 0 or at whole decades
    // beyond the data, the labels would show 0 or 1e-4.
    let curve = vec![Curve {
        label: "pr".into(),
        spread: Vec::new(),
        points: (0..=10).map(|k| (1000.0 + 100.0 * k as f64, 1e-2 * 10f64.powf(-0.1 * k as f64))).collect(),
    }];
    let mut out = Vec::new();
    write_svg(&curve, &spec(), &mut out).unwrap();
    let texts = svg_texts(&String::from_utf8(out).unwrap());
    let has = |t: &str| texts.iter().any(|x| x == t);
    assert!(has("1000") && has("2000"), "x labels: {texts:?}");
    assert!(!has("0") && !has("1e-4") && !has("1e-1") && !has("3000"), "the axes reach beyond the data: {texts:?}");
    assert!(has("1e-2") && has("1e-3") && has("5e-3"), "y labels: {texts:?}");
}

#[test]
fn nothing_positive_is_a_clear_error() {
    let flat = vec![Curve { label: "done".into(), spread: Vec::new(), points: vec![(0.0, 0.0), (1.0, f64::NAN)] }];
    let err = write_svg(&flat, &spec(), Vec::new()).unwrap_err();
    assert!(matches!(err, EvalError::Plot(_)) && err.to_string().contains("no positive e_rms"), "{err}");
}

#[test]
fn a_standard_error_is_a_band_up_to_twice_it_named_in_the_legend() {
    // e_rms 1e-3 throughout, its standard error 1e-2: the band's top, 2e-2, sets the top of
    // the y axis, and the band is filled, lightly, in the curve's colour, under the line.
    let flat = |v: f64| (0..=10).map(|k| (k as f64, v)).collect::<Vec<_>>();
    let banded = vec![Curve { label: "stochastic-jacobi".into(), points: flat(1e-3), spread: flat(1e-2) }];
    let mut out = Vec::new();
    write_svg(&banded, &spec(), &mut out).unwrap();
    let texts = svg_texts(&String::from_utf8(out).unwrap());
    assert!(texts.iter().any(|t| t == radiosity_eval::BAND_LABEL), "{texts:?}");
    assert!(texts.iter().any(|t| t == "2e-2"), "the band's top is on the axis: {texts:?}");
    let colour = style_of("stochastic-jacobi").colour;
    // The colour at 8% over white, as the band is filled, give or take rounding.
    let blend = |c: usize| 255.0 - 0.08 * (255.0 - f64::from(colour[c]));
    let tint = |p: [u8; 3]| (0..3).all(|c| (f64::from(p[c]) - blend(c)).abs() <= 3.0);
    let img = png(&banded, &spec());
    let tinted = img.enumerate().filter(|(_, _, p)| tint(*p)).count();
    assert!(tinted > 5000, "{tinted} pixels of the band");
    // Without a standard error, no band and no legend entry for one.
    let plain = vec![Curve::new("stochastic-jacobi", flat(1e-3))];
    let mut out = Vec::new();
    write_svg(&plain, &spec(), &mut out).unwrap();
    assert!(!svg_texts(&String::from_utf8(out).unwrap()).iter().any(|t| t == radiosity_eval::BAND_LABEL));
    let tinted = png(&plain, &spec()).enumerate().filter(|(_, _, p)| tint(*p)).count();
    assert!(tinted < 500, "{tinted} pixels tinted without a band");
}

/// The points of every SVG polyline drawn in `stroke` (`#RRGGBB`), one list per polyline.
fn polylines(svg: &str, stroke: &str) -> Vec<Vec<(f64, f64)>> {
    svg.split("<polyline")
        .skip(1)
        .filter(|p| p.contains(&format!("stroke=\"{stroke}\"")))
        .filter_map(|p| {
            let points = p.split_once("points=\"")?.1.split_once('"')?.0;
            let pairs = points.split_whitespace().filter_map(|xy| {
                let (x, y) = xy.split_once(',')?;
                Some((x.parse().ok()?, y.parse().ok()?))
            });
            Some(pairs.collect())
        })
        .collect()
}

fn hex([r, g, b]: [u8; 3]) -> String {
    format!("#{r:02X}{g:02X}{b:02X}")
}

/// A Monte Carlo estimate's error, `1/√rays` from 1e3 to 1e7 rays, with its first point at 0.
fn monte_carlo() -> Vec<Curve> {
    let points = std::iter::once((0.0, 1.0)).chain((0..=40).map(|k| {
        let rays = 1e3 * 10f64.powf(k as f64 / 10.0);
        (rays, 1.0 / rays.sqrt())
    }));
    vec![Curve::new("stochastic-jacobi", points.collect())]
}

fn log_log() -> PlotSpec {
    PlotSpec {
        x_scale: AxisScale::Log,
        slope: Some(MONTE_CARLO_SLOPE),
        ..PlotSpec::new("classroom.mgf", "rays cast (log scale)")
    }
}

/// The slope of the straight line through `points` (pixels, y down) by least squares, and
/// the largest distance in pixels of a point from it.
fn straight(points: &[(f64, f64)]) -> (f64, f64) {
    let n = points.len() as f64;
    let (mx, my) = (points.iter().map(|p| p.0).sum::<f64>() / n, points.iter().map(|p| p.1).sum::<f64>() / n);
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let slope = sxy / sxx;
    let off = points.iter().map(|p| (p.1 - my - slope * (p.0 - mx)).abs()).fold(0.0, f64::max);
    (slope, off)
}

#[test]
fn a_power_law_on_a_log_x_axis_is_a_straight_line_beside_its_named_reference_slope() {
    let curves = monte_carlo();
    let mut out = Vec::new();
    write_svg(&curves, &log_log(), &mut out).unwrap();
    let svg = String::from_utf8(out).unwrap();
    let texts = svg_texts(&svg);
    // The x axis in decades; the reference slope named in the legend.
    for label in ["1e4", "1e5", "1e6", "1e7", slope_label(MONTE_CARLO_SLOPE).as_str()] {
        assert!(texts.iter().any(|t| t == label), "{label} missing: {texts:?}");
    }
    assert_eq!(slope_label(MONTE_CARLO_SLOPE), "slope −½");
    // 1/√rays is a straight line (the point at 0 rays has no place on the axis) …
    let curve: Vec<(f64, f64)> =
        polylines(&svg, &hex(style_of("stochastic-jacobi").colour)).into_iter().max_by_key(|p| p.len()).unwrap();
    let (slope, off) = straight(&curve);
    assert!(off <= 1.5 && curve.len() >= 40, "{} points, {off} pixels off a line", curve.len());
    // … and the dashed reference runs parallel to it, below it.
    // Its dashes in the data; the legend's sample is level.
    let dashes: Vec<Vec<(f64, f64)>> =
        polylines(&svg, "#6E6E6E").into_iter().filter(|d| d[0].1 != d[d.len() - 1].1).collect();
    let guide: Vec<(f64, f64)> = dashes.iter().flatten().copied().collect();
    assert!(dashes.len() > 10, "{} dashes", dashes.len());
    let (guide_slope, guide_off) = straight(&guide);
    assert!(guide_off <= 1.5 && (guide_slope - slope).abs() < 0.02 * slope.abs(), "{guide_slope} against {slope}");
    let below = |x: f64| curve.iter().min_by(|a, b| (a.0 - x).abs().total_cmp(&(b.0 - x).abs())).unwrap().1;
    assert!(guide.iter().all(|&(x, y)| y > below(x)), "the reference runs below the curve");

    // On a linear axis the same curve bends, and no reference slope is drawn or named.
    let mut out = Vec::new();
    write_svg(&curves, &PlotSpec { x_scale: AxisScale::Linear, ..log_log() }, &mut out).unwrap();
    let svg = String::from_utf8(out).unwrap();
    let curve = polylines(&svg, &hex(style_of("stochastic-jacobi").colour)).into_iter().max_by_key(|p| p.len());
    assert!(straight(&curve.unwrap()).1 > 50.0, "a power law on a linear axis is no line");
    assert!(polylines(&svg, "#6E6E6E").is_empty() && !svg_texts(&svg).iter().any(|t| t.starts_with("slope")));
}

#[test]
fn notes_go_under_the_plot_wrapped_to_its_width() {
    let note = "Left out: stochastic-jacobi (no columns computed; its cost: 8,594,170 rays cast), \
                random-walk (no columns computed; its cost: 9,000,000 rays cast).";
    let spec = PlotSpec { notes: vec![note.into()], ..spec() };
    let mut out = Vec::new();
    write_svg(&curves(), &spec, &mut out).unwrap();
    let svg = String::from_utf8(out).unwrap();
    // Each line a text of its own, in order, the words as written; below the x axis's label.
    let lines: Vec<&str> = svg.split("<text").skip(1).collect();
    let at = |t: &str| -> (f64, String) {
        let y = t.split_once("y=\"").unwrap().1.split_once('"').unwrap().0.parse().unwrap();
        (y, t.split_once('>').unwrap().1.split_once("</text>").unwrap().0.trim().to_string())
    };
    let texts: Vec<(f64, String)> = lines.iter().map(|t| at(t)).collect();
    let first = texts.iter().position(|(_, t)| t.starts_with("Left out:")).unwrap();
    let wrapped: Vec<&(f64, String)> = texts[first..].iter().take_while(|(_, t)| !t.is_empty()).collect();
    let joined = wrapped.iter().map(|(_, t)| t.as_str()).collect::<Vec<_>>().join(" ");
    assert_eq!(joined.split_whitespace().collect::<Vec<_>>(), note.split_whitespace().collect::<Vec<_>>());
    assert!(wrapped.len() >= 2, "a note wider than 480 pixels is wrapped: {wrapped:?}");
    let axis = texts.iter().find(|(_, t)| t == "shooting steps").unwrap().0;
    assert!(wrapped.windows(2).all(|w| w[1].0 > w[0].0) && wrapped[0].0 > axis, "{wrapped:?} below {axis}");
}

#[test]
fn overlapping_bands_stay_light_and_each_shows_its_top() {
    // Three solvers of one method (one colour) with the same band: where all three overlap the
    // fill is still light enough to read the lines over it, and each band's top is its own line.
    let flat = |v: f64| (0..=10).map(|k| (k as f64, v)).collect::<Vec<_>>();
    let names = ["stochastic-jacobi", "stochastic-jacobi:seq=sobol", "stochastic-jacobi:seq=halton"];
    let curves: Vec<Curve> = names
        .iter()
        .enumerate()
        .map(|(k, n)| Curve { label: n.to_string(), points: flat(1e-3), spread: flat(2e-3 * (k + 1) as f64) })
        .collect();
    let img = png(&curves, &PlotSpec { size: (800, 500), ..spec() });
    // A row 60 pixels above the curves at the data area's bottom (the x labels' 40 pixels
    // and the margin's 12 below it), across the middle of the data: under all three bands,
    // tinted but light.
    let y = 500 - 40 - 12 - 60;
    let row: Vec<[u8; 3]> =
        img.enumerate().filter(|&(x, py, _)| py == y && (150..400).contains(&x)).map(|p| p.2).collect();
    // The fill is the row's commonest colour (grid lines cross it here and there).
    let mut counts = std::collections::HashMap::new();
    for p in &row {
        *counts.entry(*p).or_insert(0) += 1;
    }
    let fill = counts.into_iter().max_by_key(|&(_, k)| k).unwrap().0;
    assert!(fill != [255, 255, 255] && fill.iter().all(|&c| c > 180), "{fill:?} under three bands");
    let mut out = Vec::new();
    write_svg(&curves, &spec(), &mut out).unwrap();
    let svg = String::from_utf8(out).unwrap();
    let colour = hex(style_of(names[0]).colour);
    // A band's top is a thin line at twice its standard error: three, at three heights.
    let tops: HashSet<i64> = svg
        .split("<polyline")
        .skip(1)
        .filter(|p| p.contains(&format!("stroke=\"{colour}\"")) && p.contains("stroke-width=\"1\""))
        .filter_map(|p| p.split_once("points=\"")?.1.split_once(',')?.1.split_whitespace().next()?.parse::<f64>().ok())
        .map(|y| y.round() as i64)
        .collect();
    assert_eq!(tops.len(), 3, "{tops:?}");
}

#[test]
fn markers_spread_along_a_curve_as_drawn_on_a_log_axis_too() {
    // Points evenly spaced in rays crowd to the right of a log axis: the markers still spread
    // along the curve, not after its points.
    let points: Vec<(f64, f64)> = (1..=2000).map(|k| (5e3 * k as f64, 1.0 / (5e3 * k as f64).sqrt())).collect();
    let mut out = Vec::new();
    write_svg(&[Curve::new("pr", points)], &log_log(), &mut out).unwrap();
    let svg = String::from_utf8(out).unwrap();
    let mut centres: Vec<f64> =
        svg.split("<circle").skip(1).filter_map(|c| c.split_once("cx=\"")?.1.split_once('"')?.0.parse().ok()).collect();
    centres.sort_by(f64::total_cmp);
    // The rightmost is the legend's; the data runs from the first to the last x label.
    centres.pop();
    let labels = svg_texts(&svg);
    assert!(labels.iter().any(|t| t == "1e4") && labels.iter().any(|t| t == "1e7"), "{labels:?}");
    let curve = polylines(&svg, &hex(style_of("pr").colour)).into_iter().max_by_key(|p| p.len()).unwrap();
    let (left, right) = (curve[0].0, curve[curve.len() - 1].0);
    assert!(centres.len() >= 6, "{centres:?}");
    assert!(centres[1] < left + 0.5 * (right - left), "markers crowd to the right: {centres:?} in {left}..{right}");
}
