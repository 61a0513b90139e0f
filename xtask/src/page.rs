//! The live page's scene and feed for a comparison (`watch`, `compare --html`): the camera
//! `render` starts from, the header, and the page kept as a file at the end.

use crate::experiment::start_camera;
use anyhow::{Context, Result};
use radiosity_eval::{Comparison, Feed, Lab, LiveHeader, LiveScene};
use radiosity_geom::PreparedScene;
use serde_json::json;
use std::path::Path;
use std::sync::Arc;

/// The short name of a scene argument: a built-in scene's name, or a file's name without its
/// folders (`office.glb`), with no parameters.
pub fn short_name(scene: &str) -> String {
    let path = scene.split(':').next().unwrap_or(scene);
    Path::new(path).file_name().map_or_else(|| path.to_string(), |f| f.to_string_lossy().into_owned())
}

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
    let no_reference = lab.reference().is_none().then(|| match lab.chosen().why.as_str() {
        "" => "there is no reference (--reference none)".to_string(),
        why => format!("there is no reference ({why})"),
    });
    let header = LiveHeader {
        scene: short_name(scene),
        backend: lab.backend().to_string(),
        rules: rules.to_string(),
        clock: lab.clock().name().to_string(),
        solvers: solvers.clone(),
        no_reference,
    };
    let channels = lab.system().channels().count();
    let star = lab.reference().map(|r| r.values());
    let live = LiveScene::new(&prepared.loaded.scene, &prepared.visibility, &camera, channels, star, &header)?;
    Ok(Feed::new(live, solvers.len()))
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
