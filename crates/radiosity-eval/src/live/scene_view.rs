//! What a live page is sent once: geometry, the smoothing table, the reference and the
//! header that names the run ([`LiveScene`]).

use crate::error::{EvalError, LabError};
use crate::lab::setup::Lab;
use crate::reports::comparison::short_name;
use crate::reports::plot::style_of;
use crate::view::render::{Camera, ExposureProbe};
use crate::view::shading::CornerTable;
use radiosity_core::{Real, Scene};
use radiosity_geom::Visibility;
use radiosity_solvers::Unit;
use serde_json::{Value, json};

/// The width and height of the image whose pixel centres set each moment's exposure (4:3, as
/// `render`'s default 640 × 480, a quarter of its side).
pub const PROBE_SIZE: (u32, u32) = (160, 120);

/// What names a watched comparison: shown in the page's header and legend.
#[derive(Clone, Debug, PartialEq)]
pub struct LiveHeader {
    /// The scene's short name (`cornell`, `office.glb`).
    pub scene: String,
    /// The form-factor backend, as written.
    pub backend: String,
    /// The stop rules, as written.
    pub rules: String,
    /// The clock every run's seconds are counted on (`measured`, `charged`).
    pub clock: String,
    /// The solvers, in the order they run.
    pub solvers: Vec<String>,
    /// Why there is no error map, when there is no reference (`None` with one).
    pub no_reference: Option<String>,
}

/// The part of a live page sent once: the header as JSON, and the geometry, smoothing table
/// and reference as little-endian binary whose layout the JSON gives.
pub struct LiveScene {
    /// The header, the camera and the binary layout, as JSON.
    pub meta: Value,
    /// Positions, corner counts, areas, the smoothing table and the reference.
    pub geometry: Vec<u8>,
    pub(crate) probe: ExposureProbe,
    pub(crate) table: CornerTable,
    pub(crate) channels: usize,
    pub(crate) patches: usize,
}

impl LiveScene {
    /// The live scene of `scene` (whose BVH is `visibility`) seen first through `camera`, with
    /// `channels` radiosity channels per patch and, for the error map, the reference `star`
    /// (patch-major, `channels` a patch).
    pub fn new(
        scene: &Scene,
        visibility: &Visibility,
        camera: &Camera,
        channels: usize,
        star: Option<&[Real]>,
        header: &LiveHeader,
    ) -> Result<LiveScene, EvalError> {
        let n = scene.len();
        if let Some(star) = star
            && star.len() != n * channels
        {
            return Err(EvalError::SizeMismatch { what: "the reference", expected: n * channels, found: star.len() });
        }
        let probe = ExposureProbe::new(scene, visibility, camera, PROBE_SIZE.0, PROBE_SIZE.1)?;
        let table = CornerTable::new(scene);
        let mut bytes = Binary::default();
        let mut layout = serde_json::Map::new();
        let positions: Vec<f32> = scene
            .patches()
            .iter()
            .flat_map(|p| {
                let v = p.vertices();
                (0..4).flat_map(move |k| {
                    let c = v[k.min(v.len() - 1)];
                    [c.x as f32, c.y as f32, c.z as f32]
                })
            })
            .collect();
        layout.insert("positions".into(), bytes.f32s(&positions));
        let corners: Vec<u32> = scene.patches().iter().map(|p| p.vertices().len() as u32).collect();
        layout.insert("corners".into(), bytes.u32s(&corners));
        let areas: Vec<f32> = scene.patches().iter().map(|p| p.area() as f32).collect();
        layout.insert("areas".into(), bytes.f32s(&areas));
        layout.insert("starts".into(), bytes.u32s(&table.starts));
        layout.insert("neighbours".into(), bytes.u32s(&table.patches));
        let weights: Vec<f32> = table.areas.iter().map(|&a| a as f32).collect();
        layout.insert("weights".into(), bytes.f32s(&weights));
        if let Some(star) = star {
            let star: Vec<f32> = star.iter().map(|&b| b as f32).collect();
            layout.insert("reference".into(), bytes.f32s(&star));
        }
        let (lo, hi) = scene.bounds();
        let solvers: Vec<Value> = header
            .solvers
            .iter()
            .map(|name| {
                let style = style_of(name);
                let [r, g, b] = style.colour;
                json!({"name": name, "colour": format!("#{r:02x}{g:02x}{b:02x}"), "dashes": style.variant.dashes()})
            })
            .collect();
        let (e, t, u) = (camera.eye(), camera.target(), camera.up());
        let meta = json!({
            "scene": header.scene,
            "backend": header.backend,
            "rules": header.rules,
            "clock": header.clock,
            "patches": n,
            "channels": channels,
            "solvers": solvers,
            "reference": star.is_some(),
            "no_reference": header.no_reference,
            "camera": {"eye": [e.x, e.y, e.z], "target": [t.x, t.y, t.z], "up": [u.x, u.y, u.z], "fov": camera.fov()},
            "bounds": [[lo.x, lo.y, lo.z], [hi.x, hi.y, hi.z]],
            "layout": layout,
            "units": Unit::ALL.iter().map(|u| u.key()).collect::<Vec<_>>(),
            "geometry_bytes": bytes.0.len(),
        });
        Ok(LiveScene { meta, geometry: bytes.0, probe, table, channels, patches: n })
    }

    /// The live scene of a comparison on `lab`, run under the stop rules `rules` by `solvers`
    /// in order, seen first through `camera`: the header from the lab (the scene's short name,
    /// backend, clock, and why there is no error map when there is no reference), the lab's
    /// reference for the error map.
    pub fn of_lab(lab: &Lab<'_>, camera: &Camera, rules: &str, solvers: Vec<String>) -> Result<LiveScene, LabError> {
        let report = lab.report();
        let no_reference = lab.reference().is_none().then(|| match lab.chosen().why.as_str() {
            "" => "there is no reference (--reference none)".to_string(),
            why => format!("there is no reference ({why})"),
        });
        let header = LiveHeader {
            scene: short_name(&report.scene).to_string(),
            backend: lab.backend().to_string(),
            rules: rules.to_string(),
            clock: lab.clock().name().to_string(),
            solvers,
            no_reference,
        };
        let prepared = lab.prepared();
        let channels = lab.system().channels().count();
        let star = lab.reference().map(|r| r.values());
        Ok(LiveScene::new(
            &prepared.loaded.scene,
            &prepared.visibility_for("a live view")?,
            camera,
            channels,
            star,
            &header,
        )?)
    }

    /// The runs this scene's header names, in order.
    pub fn runs(&self) -> usize {
        self.meta["solvers"].as_array().map_or(0, Vec::len)
    }

    /// The exposure [`crate::render`] would choose at the start camera for the radiosity
    /// `values` (patch-major, the scene's channels a patch).
    pub fn exposure(&self, values: &[f32]) -> Real {
        let k = self.channels;
        let rgb: Vec<[Real; 3]> = values
            .chunks_exact(k)
            .map(|b| if k >= 3 { [b[0], b[1], b[2]].map(Real::from) } else { [Real::from(b[0]); 3] })
            .collect();
        if rgb.len() != self.patches {
            return 1.0;
        }
        self.probe.exposure(&|i, v| self.table.corner(i, v, &rgb))
    }
}

/// Little-endian arrays one after another, each at a 4-byte boundary.
#[derive(Default)]
struct Binary(Vec<u8>);

impl Binary {
    /// Appends `values`; their `[byte offset, count]`.
    fn f32s(&mut self, values: &[f32]) -> Value {
        let at = self.0.len();
        self.0.extend(values.iter().flat_map(|v| v.to_le_bytes()));
        json!([at, values.len()])
    }

    fn u32s(&mut self, values: &[u32]) -> Value {
        let at = self.0.len();
        self.0.extend(values.iter().flat_map(|v| v.to_le_bytes()));
        json!([at, values.len()])
    }
}
