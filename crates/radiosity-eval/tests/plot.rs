//! Convergence plots: SVG with the solvers' names, PNG of the right size with lines drawn,
//! and a clear error when nothing can go on a log scale.

use radiosity_eval::EvalError;
use radiosity_eval::plot::{Curve, PlotSpec, write_png, write_svg};

fn curves() -> Vec<Curve> {
    let decay = |rate: f64| (0..=100).map(|s| (s as f64, (-rate * s as f64).exp())).collect();
    vec![Curve { label: "pr".into(), points: decay(0.05) }, Curve { label: "xu-g30-m480".into(), points: decay(0.12) }]
}

fn spec() -> PlotSpec {
    PlotSpec { title: "multi-cubes".into(), x_label: "shooting steps".into(), size: (480, 320) }
}

#[test]
fn svg_names_every_solver_and_the_axes() {
    let mut out = Vec::new();
    write_svg(&curves(), &spec(), &mut out).unwrap();
    let svg = String::from_utf8(out).unwrap();
    for text in ["<svg", "pr", "xu-g30-m480", "shooting steps", "e_rms", "multi-cubes", "1e-5"] {
        assert!(svg.contains(text), "missing {text}");
    }
}

#[test]
fn png_has_the_size_and_draws_in_colour() {
    let mut out = Vec::new();
    write_png(&curves(), &spec(), &mut out).unwrap();
    let img = image::load_from_memory(&out).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (480, 320));
    // Lines and text: some pixels are neither white nor grey.
    let coloured = img.pixels().filter(|p| p.0.iter().max().unwrap() - p.0.iter().min().unwrap() > 60).count();
    assert!(coloured > 200, "{coloured} coloured pixels");
}

#[test]
fn nothing_positive_is_a_clear_error() {
    let flat = vec![Curve { label: "done".into(), points: vec![(0.0, 0.0), (1.0, f64::NAN)] }];
    let err = write_svg(&flat, &spec(), Vec::new()).unwrap_err();
    assert!(matches!(err, EvalError::Plot(_)) && err.to_string().contains("no positive e_rms"), "{err}");
}
