//! `watch` in a real browser: headless Chromium (SwiftShader's WebGL2) loads the live page of
//! a small comparison, waits for the run's end as the page reports it, and its pixels, its
//! final e_rms and the kept page are checked against `render`, `compare` and each other.
//!
//! Needs Chromium (`/usr/bin/chromium`, or the path in `RADIOSITY_CHROMIUM`) and the feature
//! `browser`, which `.ci/run` turns on after installing Debian's `chromium`.

use super::{cache_dir, xtask};
use std::io::{BufRead, BufReader, Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

const SCENE: &str = "cornell:res=4";
const SOLVERS: &str = "pr,xu,xu-g30";
const UNTIL: &str = "columns=2n";
const WINDOW: (u32, u32) = (1000, 900);
/// How far a byte of the page's pixel may be from `render`'s: the page's exposure is set by
/// 160 × 120 pixel centres, `render`'s by its own, which may differ by a percent; an exposure
/// off by 5% moves a mid-tone byte by 5 and fails.
const TOLERANCE: u8 = 3;

fn chromium() -> PathBuf {
    let path = std::env::var_os("RADIOSITY_CHROMIUM").map_or_else(|| PathBuf::from("/usr/bin/chromium"), PathBuf::from);
    assert!(path.exists(), "the browser tests need Chromium at {} (or RADIOSITY_CHROMIUM)", path.display());
    path
}

/// Headless Chromium on `url`, with `what` (`--screenshot=…` or `--dump-dom`); its stdout.
fn browse(dir: &Path, url: &str, what: &str) -> String {
    let profile = dir.join(format!("profile-{}", what.len()));
    let output = Command::new(chromium())
        .args([
            "--headless",
            "--no-sandbox",
            "--use-angle=swiftshader",
            "--enable-unsafe-swiftshader",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--no-first-run",
            "--hide-scrollbars",
            "--force-device-scale-factor=1",
            &format!("--window-size={},{}", WINDOW.0, WINDOW.1),
            &format!("--user-data-dir={}", profile.display()),
            what,
            url,
        ])
        .output()
        .unwrap();
    assert!(output.status.success(), "chromium failed: {}", String::from_utf8_lossy(&output.stderr));
    String::from_utf8(output.stdout).unwrap()
}

/// A running `watch`, killed when dropped.
struct Watch(Child);

impl Drop for Watch {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// `xtask watch ARGS`, started; its stdout's lines after the first, and the page's address,
/// which the first gives.
fn start(args: &[&str]) -> (Watch, std::io::Lines<BufReader<std::process::ChildStdout>>, String) {
    let mut child = Command::new(assert_cmd::cargo::cargo_bin("xtask"))
        .arg("watch")
        .args(args)
        .env("RADIOSITY_CACHE_DIR", cache_dir())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
    let watch = Watch(child);
    let first = lines.next().unwrap().unwrap();
    let url = first.strip_prefix("watch the comparison at ").unwrap_or_else(|| panic!("{first}")).to_string();
    (watch, lines, url)
}

/// The 8-bit RGB pixels of the PNG at `path`, with its width.
fn pixels(path: &Path) -> (usize, Vec<[u8; 3]>) {
    let image = radiosity_eval::Rgb8::decode(&std::fs::read(path).unwrap()).unwrap();
    let width = image.width as usize;
    (width, image.enumerate().map(|(_, _, p)| p).collect())
}

/// The value of `attribute` on the element with id `id` in `dom`.
fn attribute(dom: &str, id: &str, attribute: &str) -> String {
    let at = dom.find(&format!("id=\"{id}\"")).unwrap_or_else(|| panic!("no element {id} in the page"));
    let tag = &dom[dom[..at].rfind('<').unwrap()..at + dom[at..].find('>').unwrap()];
    let key = format!("{attribute}=\"");
    let start = tag.find(&key).unwrap_or_else(|| panic!("no {attribute} on {id}: {tag}")) + key.len();
    tag[start..start + tag[start..].find('"').unwrap()].replace("&quot;", "\"")
}

/// The body of `GET path` from the server at `url`.
fn get(url: &str, path: &str) -> String {
    let address = url.trim_start_matches("http://").trim_end_matches('/');
    let mut stream = std::net::TcpStream::connect(address).unwrap();
    write!(stream, "GET {path} HTTP/1.1\r\nHost: {address}\r\nConnection: close\r\n\r\n").unwrap();
    let mut text = String::new();
    stream.read_to_string(&mut text).unwrap();
    text.split_once("\r\n\r\n").unwrap().1.to_string()
}

#[test]
#[cfg_attr(not(feature = "browser"), ignore = "needs Chromium: cargo test --features browser (.ci/run installs it)")]
fn the_live_page_shows_the_comparison_as_render_and_compare_do() {
    let dir = std::env::temp_dir().join(format!("radiosity-watch-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let kept = dir.join("page.html");
    let results = dir.join("results");
    let (watch, mut lines, url) = start(
        &[
            &["--scene", SCENE, "--solvers", SOLVERS, "--until", UNTIL, "--port", "0"][..],
            &["--results", results.to_str().unwrap(), "--out", kept.to_str().unwrap()],
        ]
        .concat(),
    );

    // The page holds its load event until it has drawn the comparison's end, so both wait.
    let live = dir.join("live.png");
    browse(&dir, &format!("{url}?hold"), &format!("--screenshot={}", live.display()));
    let dom = browse(&dir, &format!("{url}?hold"), "--dump-dom");
    assert!(dom.contains("data-done=\"true\""), "the page never said the run ended");
    let meta: serde_json::Value = serde_json::from_str(&get(&url, "/meta")).unwrap();

    // Once the comparison has ended, watch says so and keeps serving.
    assert!(lines.by_ref().map_while(Result::ok).any(|l| l.starts_with("the comparison has ended")));
    // Ctrl-C ends the server cleanly once the run is over.
    let mut watch = watch;
    Command::new("kill").args(["-INT", &watch.0.id().to_string()]).status().unwrap();
    assert!(watch.0.wait().unwrap().success(), "watch did not end cleanly on Ctrl-C");
    assert!(dir.join("results/report.md").exists() && dir.join("results/convergence.csv").exists());

    // The page's final e_rms of each solver is compare's, run on its own.
    let out = dir.join("compare");
    let assert =
        xtask(&["compare", "--scene", SCENE, "--solvers", SOLVERS, "--until", UNTIL, "--out", out.to_str().unwrap()]);
    let table = String::from_utf8(assert.success().get_output().stdout.clone()).unwrap();
    for (index, solver) in SOLVERS.split(',').enumerate() {
        let row = table.lines().find(|l| l.split_whitespace().next() == Some(solver)).unwrap();
        // solver, steps, columns, e_rms @n, e_rms end, …
        let printed = row.split_whitespace().nth(4).unwrap();
        let page: f64 = attribute(&dom, &format!("metric-{index}"), "data-value").parse().unwrap();
        assert_eq!(radiosity_eval::round_significant(page, 3), printed, "{solver}: the page's e_rms {page}");
    }

    // The first view (pr) against `render` of the same solve through the same camera.
    let viewports: serde_json::Value = serde_json::from_str(&attribute(&dom, "views", "data-viewports")).unwrap();
    let rect: Vec<f64> = serde_json::from_str(&attribute(&dom, "views", "data-rect")).unwrap();
    let view = &viewports[0];
    let (vx, vy, w, h) = ["x", "y", "w", "h"].map(|k| view[k].as_u64().unwrap() as usize).into();
    let (cx, cy) = (rect[0].round() as usize + vx, rect[1].round() as usize + vy);
    let camera = &meta["camera"];
    let coordinates =
        |key: &str| camera[key].as_array().unwrap().iter().map(|v| v.to_string()).collect::<Vec<_>>().join(",");
    let rendered = dir.join("render.png");
    xtask(&[
        "render",
        "--scene",
        SCENE,
        "--solver",
        "pr",
        "--until",
        UNTIL,
        "--width",
        &w.to_string(),
        "--height",
        &h.to_string(),
        "--camera",
        &format!("{}:{}:{}", coordinates("eye"), coordinates("target"), camera["fov"]),
        "--out",
        rendered.to_str().unwrap(),
    ])
    .success();
    let (rw, truth) = pixels(&rendered);
    let (sw, shot) = pixels(&live);
    let at = |x: usize, y: usize| shot[(cy + y) * sw + cx + x];
    // Not blank: most of the view is lit, in many colours.
    let view: Vec<[u8; 3]> = (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).map(|(x, y)| at(x, y)).collect();
    let lit = view.iter().filter(|p| p.iter().any(|&c| c > 20)).count();
    let colours: std::collections::HashSet<_> = view.iter().collect();
    assert!(
        lit * 2 > view.len() && colours.len() > 200,
        "a blank view: {lit} of {} lit, {} colours",
        view.len(),
        colours.len()
    );
    // Two pixels inside patches (their 5 × 5 neighbourhood uniform in the rendered image), as
    // far apart in colour as can be found, match the rendered picture.
    let uniform = |x: usize, y: usize| {
        let p = truth[y * rw + x];
        // Neither clipped nor near black, where a wrong exposure would not show.
        if p.iter().any(|&c| !(24..=232).contains(&c)) {
            return false;
        }
        (y - 2..=y + 2)
            .all(|j| (x - 2..=x + 2).all(|i| truth[j * rw + i].iter().zip(p).all(|(a, b)| a.abs_diff(b) <= 2)))
    };
    let candidates: Vec<(usize, usize)> = (3..h - 3)
        .step_by(5)
        .flat_map(|y| (3..w - 3).step_by(5).map(move |x| (x, y)))
        .filter(|&(x, y)| uniform(x, y))
        .collect();
    let distance = |a: (usize, usize), b: (usize, usize)| {
        let (p, q) = (truth[a.1 * rw + a.0], truth[b.1 * rw + b.0]);
        p.iter().zip(q).map(|(x, y)| (i32::from(*x) - i32::from(y)).pow(2)).sum::<i32>()
    };
    let pair = candidates
        .iter()
        .flat_map(|&a| candidates.iter().map(move |&b| (a, b)))
        .max_by_key(|&(a, b)| distance(a, b))
        .unwrap();
    for (x, y) in [pair.0, pair.1] {
        let (page, cpu) = (at(x, y), truth[y * rw + x]);
        eprintln!("at ({x}, {y}): page {page:?}, render {cpu:?}");
        assert!(
            page.iter().zip(cpu).all(|(a, b)| a.abs_diff(b) <= TOLERANCE),
            "at ({x}, {y}) of the view the page shows {page:?}, render {cpu:?}"
        );
    }

    // The kept page, opened from disk, shows the same views.
    let from_disk = dir.join("kept.png");
    browse(&dir, &format!("file://{}", kept.display()), &format!("--screenshot={}", from_disk.display()));
    let (_, disk) = pixels(&from_disk);
    let differ = (0..h)
        .flat_map(|y| (0..w).map(move |x| (cy + y) * sw + cx + x))
        .filter(|&i| disk[i].iter().zip(shot[i]).any(|(a, b)| a.abs_diff(b) > 1))
        .count();
    assert!(differ == 0, "the kept page differs from the live one at {differ} pixels of the first view");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn watch_refuses_bad_input_before_any_work() {
    let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let port = taken.local_addr().unwrap().port().to_string();
    let e = super::failure(&["watch", "--scene", "cornell:res=2", "--solvers", "pr", "--port", &port]);
    assert!(e.contains(&format!("127.0.0.1:{port}")) && e.contains("in use") && e.contains("--port"), "{e}");
    let e = super::failure(&["watch", "--scene", "cornell:res=2", "--solvers", "pr,xyz"]);
    assert!(e.contains("xyz"), "{e}");
    let e = super::failure(&["watch", "--scene", "cornel", "--solvers", "pr"]);
    assert!(e.contains("cornel") && e.contains("cornell"), "{e}");
    let e = super::failure(&["watch", "--scene", "cornell:res=2", "--solvers", "pr", "--out", "page.png"]);
    assert!(e.contains(".html"), "{e}");
}

#[test]
fn ctrl_c_during_the_run_stops_it_and_writes_what_ran() {
    let dir = std::env::temp_dir().join(format!("radiosity-watch-stop-{}", std::process::id()));
    let results = dir.join("results");
    // A run far longer than the test: Ctrl-C ends it.
    let (watch, lines, url) = start(&[
        "--scene",
        "cornell:res=4",
        "--solvers",
        "pr,xu",
        "--until",
        "columns=1000n",
        "--results",
        results.to_str().unwrap(),
    ]);
    // Once the page's events say pr runs, Ctrl-C.
    let address = url.trim_start_matches("http://").trim_end_matches('/').to_string();
    let mut events = std::net::TcpStream::connect(&address).unwrap();
    write!(events, "GET /events HTTP/1.1\r\nHost: {address}\r\n\r\n").unwrap();
    let mut seen = BufReader::new(events).lines();
    assert!(seen.by_ref().map_while(Result::ok).any(|l| l == "event: points"), "no points were streamed");
    let mut watch = watch;
    Command::new("kill").args(["-INT", &watch.0.id().to_string()]).status().unwrap();
    let status = watch.0.wait().unwrap();
    assert_eq!(status.code(), Some(130), "watch did not stop with code 130");
    let printed: Vec<String> = lines.map_while(Result::ok).collect();
    assert!(printed.iter().any(|l| l == "stopped by Ctrl-C"), "{printed:?}");
    let report = std::fs::read_to_string(results.join("report.md")).unwrap();
    assert!(report.contains("stopped during pr's run; not run: xu"), "{report}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn compare_html_writes_a_page_that_needs_nothing_else() {
    let dir = std::env::temp_dir().join(format!("radiosity-watch-html-{}", std::process::id()));
    let out = dir.to_str().unwrap();
    // A family a cost unit: columns, products over the hierarchy, rays, node rounds (links).
    let (solvers, until) = ("pr,gmres-30,stochastic-jacobi,h-pr", "steps=40,rays=1e5");
    let args = ["compare", "--scene", "cornell:res=2", "--ff", "hierarchical", "--solvers", solvers, "--until", until];
    let args = [&args[..], &["--html", "--out", out]].concat();
    let stdout = String::from_utf8(xtask(&args).success().get_output().stdout.clone()).unwrap();
    assert!(stdout.contains("page.html"), "{stdout}");
    let page = std::fs::read_to_string(dir.join("page.html")).unwrap();
    // Nothing fetched: no address, no source or link outside the file.
    for outside in ["http:", "https:", "src=", "href=", "@import"] {
        assert!(!page.contains(outside), "the kept page refers to something outside it ({outside})");
    }
    let start = page.find("<script id=\"data\" type=\"application/json\">").unwrap();
    let json = &page[start..];
    let json = &json[json.find('>').unwrap() + 1..json.find("</script>").unwrap()];
    let data: serde_json::Value = serde_json::from_str(json).unwrap();
    // The geometry once, each run's points and the radiosity at its kept moments.
    let patches = data["meta"]["patches"].as_u64().unwrap() as usize;
    let channels = data["meta"]["channels"].as_u64().unwrap() as usize;
    let geometry = data["geometry"].as_str().unwrap();
    assert_eq!(geometry.len(), data["meta"]["geometry_bytes"].as_u64().unwrap().div_ceil(3) as usize * 4);
    assert_eq!(data["runs"].as_array().unwrap().len(), 4);
    for run in data["runs"].as_array().unwrap() {
        let kept = run["kept"].as_array().unwrap();
        assert!(kept.len() > 3, "too few moments kept for a slider: {}", kept.len());
        let last = kept.last().unwrap();
        assert_eq!(last["values"].as_str().unwrap().len(), (patches * channels * 4).div_ceil(3) * 4);
        assert_eq!(last["point"], run["end"]["last"], "the last moment kept is not the run's end");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn pages_that_come_and_go_change_nothing_in_the_run() {
    let dir = std::env::temp_dir().join(format!("radiosity-watch-leave-{}", std::process::id()));
    let args = ["--scene", "cornell:res=4", "--solvers", "pr,xu", "--until", "columns=2n"];
    let watched = dir.join("watched");
    let (mut watch, mut lines, url) = start(&[&args[..], &["--results", watched.to_str().unwrap()]].concat());
    let address = url.trim_start_matches("http://").trim_end_matches('/').to_string();
    // Clients that read a little of the events and leave, again and again, while it runs.
    let leaving = std::thread::spawn(move || {
        for _ in 0..20 {
            if let Ok(mut s) = std::net::TcpStream::connect(&address) {
                let _ = write!(s, "GET /events HTTP/1.1\r\nHost: {address}\r\n\r\n");
                let _ = s.read(&mut [0u8; 4096]);
            }
            std::thread::sleep(std::time::Duration::from_millis(50));
        }
    });
    let printed: Vec<String> = lines
        .by_ref()
        .map_while(Result::ok)
        .skip_while(|l| !l.starts_with("solver "))
        .take_while(|l| !l.starts_with("seconds"))
        .collect();
    leaving.join().unwrap();
    // Interrupted once the comparison has ended and the page waits: an interrupt before that
    // stops the run, with code 130, and a loaded machine can still be writing the results.
    assert!(lines.by_ref().map_while(Result::ok).any(|l| l.starts_with("the comparison has ended")));
    Command::new("kill").args(["-INT", &watch.0.id().to_string()]).status().unwrap();
    assert!(watch.0.wait().unwrap().success());
    // The table watch printed is compare's, but for the seconds.
    let out = dir.join("compared");
    let stdout = xtask(&[&["compare"][..], &args, &["--out", out.to_str().unwrap()]].concat())
        .success()
        .get_output()
        .stdout
        .clone();
    let compared: Vec<String> =
        String::from_utf8(stdout).unwrap().lines().take(printed.len()).map(String::from).collect();
    let without_seconds = |l: &String| l.rsplit_once(' ').map_or(l.clone(), |(a, _)| a.trim_end().to_string());
    assert_eq!(
        printed.iter().map(without_seconds).collect::<Vec<_>>(),
        compared.iter().map(without_seconds).collect::<Vec<_>>()
    );
    let _ = std::fs::remove_dir_all(&dir);
}
