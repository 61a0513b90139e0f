//! The live page's feed for a comparison (`watch`, `compare --html`), seen from the camera
//! `render` starts from, and the page kept as a file at the end.

use crate::experiment::start_camera;
use anyhow::{Context, Result};
use radiosity_eval::{Comparison, Feed, Lab, LiveScene};
use radiosity_geom::PreparedScene;
use serde_json::json;
use std::path::Path;
use std::sync::Arc;

/// An empty feed for the comparison of `solvers` on `lab` under the stop rules `rules`, over
/// `prepared` (the scene argument `scene`), seen first through `render`'s default camera.
pub fn feed(
    scene: &str,
    rules: &str,
    prepared: &PreparedScene,
    lab: &Lab<'_>,
    solvers: Vec<String>,
) -> Result<Arc<Feed>> {
    let (camera, _, _) = start_camera(scene, prepared, None, 4.0 / 3.0)?;
    let live = LiveScene::of_lab(lab, &camera, rules, solvers)?;
    let runs = live.runs();
    Ok(Feed::new(live, runs))
}

/// Marks `feed` done with `comparison`'s notes and the results folder `out`.
pub fn finish(feed: &Feed, comparison: &Comparison, out: &Path) {
    feed.finish(json!({"notes": comparison.notes, "out": out.display().to_string()}));
}

/// Marks `feed` done and writes its page to `file`.
pub fn write_kept(feed: &Feed, comparison: &Comparison, out: &Path, file: &Path) -> Result<()> {
    finish(feed, comparison, out);
    let mut writer = std::io::BufWriter::new(
        std::fs::File::create(file).with_context(|| format!("cannot write {}", file.display()))?,
    );
    radiosity_eval::write_page(&mut writer, feed)?;
    Ok(())
}
