//! `cargo xtask watch [compare's arguments] [--port P] [--open] [--out PAGE.html] [--results
//! DIR]`: runs a comparison as `compare` does and serves a page on `127.0.0.1` that shows it
//! as it runs ([`radiosity_eval::Server`]): the scene in 3D, a view per solver coloured by its
//! current radiosity or its error against the reference, and the curves as they grow.
//!
//! Every argument, the output paths and the port are checked before any geometry is built.
//! The page is served once the lab is set up (a browser that comes earlier waits); when the
//! comparison ends, its results are written as `compare` writes them and the page stays
//! served until Ctrl-C. Ctrl-C during the run ends the solver running at its next point,
//! leaves the rest unrun, writes the results of what ran, and exits with code 130; a second
//! Ctrl-C exits at once. Closing the page changes nothing in the run.

use crate::compare::ComparisonArgs;
use crate::experiment::{check_out_dir, check_output_file, default_out};
use crate::ranks::Ranks;
use anyhow::{Result, bail};
use radiosity_eval::{FeedWatch, Server};
use std::io::Write;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// Arguments of `watch`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    run: ComparisonArgs,
    /// The port to serve the page on, on 127.0.0.1 (default: a free one; printed).
    #[arg(long, default_value_t = 0)]
    port: u16,
    /// Opens the page in the system's browser.
    #[arg(long)]
    open: bool,
    /// Also writes the page as one self-contained file when the comparison ends.
    #[arg(long, value_name = "PAGE.html")]
    out: Option<PathBuf>,
    /// The results folder (default `results/<scene>-<date-time>/`), as `compare --out`.
    #[arg(long, value_name = "DIR")]
    results: Option<PathBuf>,
}

/// Runs `watch`.
pub fn run(args: &Args) -> Result<()> {
    let plan = args.run.plan(&Ranks::default())?;
    if let Some(page) = &args.out {
        if !page.extension().is_some_and(|e| e.eq_ignore_ascii_case("html")) {
            bail!("the page must be an .html file, not '{}'", page.display());
        }
        check_output_file(page)?;
    }
    let results = args.results.clone().unwrap_or_else(|| default_out(&args.run.scene));
    check_out_dir(&results)?;
    let server = Server::bind(args.port)?;
    let url = server.url();
    let stop = Arc::new(AtomicBool::new(false));
    let flag = stop.clone();
    ctrlc::set_handler(move || {
        if flag.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
    })?;
    println!("watch the comparison at {url}");
    std::io::stdout().flush()?;
    let mut server = Some(server);
    let (scene, until) = (args.run.scene.clone(), args.run.until.clone());
    let started = Instant::now();
    let (comparison, watch) = plan.execute_with(&results, |prepared, lab, solvers| {
        let feed = crate::page::feed(&scene, &until, prepared, lab, solvers)?;
        if let Some(server) = server.take() {
            server.serve(feed.clone());
        }
        if args.open {
            open(&url);
        }
        Ok(FeedWatch::new(feed, stop.clone()))
    })?;
    let feed = watch.feed();
    crate::page::finish(&feed, &comparison, &results);
    if let Some(page) = &args.out {
        crate::page::write_kept(&feed, &comparison, &results, page)?;
    }
    print!("{}", comparison.summary());
    println!("{}: {}", comparison.clock.seconds_label(), comparison.seconds_phrase());
    println!("wrote {} (report.md, convergence.csv and plots)", results.display());
    if let Some(page) = &args.out {
        println!("wrote {}: the page as one file", page.display());
    }
    let sent = feed.sent();
    let seconds = started.elapsed().as_secs_f64();
    match sent.updates {
        0 => println!("page: no radiosity update was sent (no page was open)"),
        k => println!(
            "page: {k} radiosity updates sent, {} bytes each on average, {:.1} a second over {seconds:.1} s",
            sent.bytes / k,
            k as f64 / seconds
        ),
    }
    if stop.load(Ordering::SeqCst) {
        println!("stopped by Ctrl-C");
        std::io::stdout().flush()?;
        feed.close();
        std::process::exit(130);
    }
    println!("the comparison has ended; the page stays at {url} until Ctrl-C");
    std::io::stdout().flush()?;
    while !stop.load(Ordering::SeqCst) {
        std::thread::sleep(Duration::from_millis(100));
    }
    feed.close();
    Ok(())
}

/// Opens `url` in the system's browser, or says why not.
fn open(url: &str) {
    let opener = if cfg!(target_os = "macos") {
        ("open", vec![url])
    } else if cfg!(windows) {
        ("cmd", vec!["/C", "start", url])
    } else {
        ("xdg-open", vec![url])
    };
    if let Err(e) = std::process::Command::new(opener.0).args(&opener.1).spawn() {
        eprintln!("warning: cannot open a browser ({}: {e}); open {url} yourself", opener.0);
    }
}
