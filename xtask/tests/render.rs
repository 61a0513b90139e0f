//! `render`: a picture of the solved Cornell box that looks like one, and clean failures on
//! bad arguments.

use super::{failure, xtask};

/// The 8-bit RGB pixels of `path`, with its width and height.
fn read_png(path: &std::path::Path) -> (u32, u32, Vec<[f64; 3]>) {
    let image = radiosity_eval::Rgb8::decode(&std::fs::read(path).unwrap()).unwrap();
    let pixels = image.enumerate().map(|(_, _, p)| p.map(f64::from)).collect();
    (image.width, image.height, pixels)
}

fn luminance(p: &[f64; 3]) -> f64 {
    0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]
}

fn mean(values: impl Iterator<Item = f64>) -> f64 {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    sum / n as f64
}

#[test]
fn render_shows_the_cornell_box() {
    let dir = std::env::temp_dir().join(format!("radiosity-render-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("cornell.png");
    let args = ["render", "--scene", "cornell:res=2", "--solver", "reference", "--width", "96", "--height", "72"];
    let stdout = xtask(&[&args[..], &["--out", out.to_str().unwrap()]].concat()).success().get_output().stdout.clone();
    let text = String::from_utf8(stdout).unwrap();
    assert!(text.contains("cornell.png") && text.contains("96 × 72") && text.contains("exposure"), "{text}");

    let (w, h, pixels) = read_png(&out);
    assert_eq!((w, h), (96, 72));
    let (w, h) = (w as usize, h as usize);
    let all = mean(pixels.iter().map(luminance));
    assert!(all > 10.0 && all < 245.0, "mean luminance {all}");
    // The ceiling light is at the top of the picture: the brightest pixels of the top quarter
    // outshine the bottom quarter (floor and blocks) on average.
    let rows = |from: usize, to: usize| pixels[from * w..to * w].iter().map(luminance);
    let top_max = rows(0, h / 4).fold(0.0, f64::max);
    let bottom_mean = mean(rows(h - h / 4, h));
    assert!(top_max > bottom_mean && top_max >= 250.0, "top max {top_max}, bottom mean {bottom_mean}");
    // The default camera stands in front of the open side (z < 0) looking towards +z, so the
    // image's right is −x: the red wall (x ≈ 556) is on the left, the green one (x = 0) on the
    // right, as in the published pictures.
    let redness = |from: usize, to: usize| {
        mean((0..h).flat_map(|y| (from..to).map(move |x| (x, y))).map(|(x, y)| {
            let p = pixels[y * w + x];
            p[0] - p[1]
        }))
    };
    let (left, right) = (redness(0, w / 3), redness(w - w / 3, w));
    assert!(left > right + 20.0, "left third red-green {left}, right third {right}");
    assert!(right < 0.0, "the right third is green: {right}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn render_refuses_bad_arguments_before_any_work() {
    let base = ["render", "--scene", "cornell:res=2", "--solver", "pr", "--out", "never.png"];
    let e = failure(&["render", "--scene", "cornell:res=2", "--solver", "xu-q30", "--out", "never.png"]);
    assert!(e.contains("unknown solver 'xu-q30'"), "{e}");
    let e = failure(&[&base[..], &["--camera", "1,2:3,4,5"]].concat());
    assert!(e.contains("invalid camera '1,2:3,4,5'") && e.contains("x,y,z:tx,ty,tz"), "{e}");
    let e = failure(&[&base[..], &["--camera", "1,2,3:3,4,5:180"]].concat());
    assert!(e.contains("field of view"), "{e}");
    let e = failure(&["render", "--scene", "cornell:res=2", "--solver", "pr", "--out", "picture.jpg"]);
    assert!(e.contains(".png") && e.contains("picture.jpg"), "{e}");
    let e = failure(&[&base[..], &["--width", "0"]].concat());
    assert!(e.contains("--width 0"), "{e}");
    let e = failure(&[&base[..], &["--until", "columns=abc"]].concat());
    assert!(e.contains("invalid stop rule 'columns=abc'"), "{e}");
    assert!(!std::path::Path::new("never.png").exists());
}
