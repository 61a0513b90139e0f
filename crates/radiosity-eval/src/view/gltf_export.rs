//! Binary glTF 2.0 of a solved scene: its patches with their radiosity as vertex colours, for
//! any glTF viewer, and with their materials, so that the file loads back as the same
//! radiosity system (docs/design.md §7, docs/cli.md `export`).
//!
//! What is written, and why:
//!
//! - **One node, one mesh, one primitive of triangles per material** the scene uses, in the
//!   order of the scene's materials; within a primitive, patches come in the scene's order
//!   ([`Glb::patch_order`] lists the scene patch of every exported patch, which is also the
//!   order in which [`radiosity_geom::load_scene`] reads them back). Every patch gets vertices
//!   of its own (3 for a triangle, 4 for a quad), so neighbouring patches share no vertex and
//!   creases between objects or walls stay sharp; the colour at each corner is the smoothed
//!   radiosity of [`vertex_radiosity`], so a wall meshed into a grid still shades smoothly. A
//!   quad is cut into the triangles `(0, 1, 2)` and `(0, 2, 3)`, the fan of
//!   `Patch::triangles`; patches are planar and convex, so the fan covers them exactly. The
//!   vertex order makes the triangles counter-clockwise seen from the patch normal, the front
//!   face in glTF.
//! - **Quads stay quads.** Each primitive is marked with `FB_ngon_encoding` (listed in
//!   `extensionsUsed`, not required): the triangles of one patch are consecutive and share
//!   their first vertex index, and consecutive patches never do (they share no vertex at all),
//!   so a reader that knows the extension rebuilds the patches, and one that does not sees
//!   ordinary triangles.
//! - **Attributes**, each in its own buffer view, primitive after primitive in the BIN chunk,
//!   in this order: `POSITION` (f32 vec3, in the scene's units, with the `min`/`max` glTF
//!   requires), `NORMAL` (f32 vec3, the patch normal at each of its corners), `COLOR_0` (f32
//!   vec3, linear RGB in `[0, 1]`), then the indices (u32 scalars, three per triangle, local
//!   to the primitive).
//! - **Materials.** One glTF material per scene material used, with its name: base colour
//!   white, `doubleSided` false, and `KHR_materials_unlit` (listed in `extensionsUsed`, not
//!   required), so a viewer shows the vertex colours as they are instead of lighting the scene
//!   a second time (a viewer without the extension falls back to a lit white material tinted
//!   by the colours). The physics goes in the material's `extras`:
//!   `{"radiosity_reflectivity": [r, g, b], "radiosity_emission": [r, g, b]}`, written as
//!   JSON numbers that read back to the same `f64`. The glTF loader of `radiosity-geom` takes
//!   these in preference to `baseColorFactor` and `emissiveFactor`, so loading the file gives
//!   the same patches (areas and normals to `f32` precision, the glTF vertex type) with the
//!   same reflectivity and emission each.
//! - **Tone mapping** is linear: colour = radiosity / exposure, clamped to `[0, 1]` per
//!   channel, where the exposure ([`exposure`]) is the 99th percentile (nearest rank) of the
//!   vertex luminance `0.2126 R + 0.7152 G + 0.0722 B`. So the brightest 1% of vertices,
//!   usually the lights, saturate, and the rest keep their proportions. The exposure is stored
//!   twice, so the radiosity can be recovered as colour × exposure wherever nothing was
//!   clamped: in `asset.extras.radiosity_exposure` (with the scene, solver and backend of
//!   [`ExportInfo`]) and in the node's name.
//!
//! The container is written by `gltf::binary::Glb`: header, JSON chunk, BIN chunk, each
//! 4-byte aligned.
//!
//! ## References
//!
//! - Khronos, *glTF 2.0 Specification*, §3.7 (meshes), §3.9 (materials), §4.4 (GLB).
//! - Khronos, `KHR_materials_unlit`; Facebook, `FB_ngon_encoding` (vendor extension draft).

use crate::error::EvalError;
use crate::view::shading::vertex_radiosity;
use gltf::json;
use json::validation::Checked::Valid;
use json::validation::USize64;
use radiosity_core::{Real, Scene};
use radiosity_geom::gltf_input::{EMISSION_EXTRA, NGON_ENCODING, REFLECTIVITY_EXTRA};
use std::borrow::Cow;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::Path;

/// The fraction of vertices whose luminance maps below 1.
const EXPOSURE_PERCENTILE: Real = 0.99;
/// The glTF extension that shows colours without lighting.
const UNLIT: &str = "KHR_materials_unlit";

/// What the file says about where its colours came from, in `asset.extras`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ExportInfo {
    /// The scene argument, also the mesh's and the glTF scene's name.
    pub scene: String,
    /// The solver that produced the radiosity.
    pub solver: String,
    /// The form-factor backend, in its canonical form.
    pub ff: String,
}

/// A binary glTF file in memory, with what went into it.
#[derive(Clone, Debug, PartialEq)]
pub struct Glb {
    /// The file: header, JSON chunk, BIN chunk.
    pub bytes: Vec<u8>,
    /// Radiosity = colour × exposure, wherever no channel was clamped.
    pub exposure: Real,
    /// Vertices written (every patch's own corners).
    pub vertices: usize,
    /// Triangles written (one per triangle patch, two per quad).
    pub triangles: usize,
    /// The scene patch of each exported patch, in file order (material by material).
    pub patch_order: Vec<usize>,
}

impl Glb {
    /// Writes the file's bytes to `out`.
    pub fn write(&self, mut out: impl Write) -> Result<(), EvalError> {
        out.write_all(&self.bytes).map_err(|e| EvalError::Gltf(e.to_string()))
    }

    /// Writes the file to `path`, creating or replacing it.
    pub fn save(&self, path: &Path) -> Result<(), EvalError> {
        std::fs::write(path, &self.bytes)
            .map_err(|e| EvalError::Write { path: path.to_path_buf(), message: e.to_string() })
    }
}

/// The binary glTF of `scene` lit by the per-patch RGB radiosity `rgb`, as the module
/// documentation describes. Refused when `rgb` does not have one finite triple per patch, or
/// the scene is too large for glTF's 32-bit indices and lengths.
pub fn export_glb(scene: &Scene, rgb: &[[Real; 3]], about: &ExportInfo) -> Result<Glb, EvalError> {
    if let Some(patch) = rgb.iter().position(|b| b.iter().any(|c| !c.is_finite())) {
        return Err(EvalError::NonFiniteRadiosity { patch });
    }
    let corners = vertex_radiosity(scene, rgb)?;
    let vertex_count: usize = scene.patches().iter().map(|p| p.vertices().len()).sum();
    if u32::try_from(vertex_count).is_err() {
        return Err(EvalError::GltfTooLarge { what: "vertices", needed: vertex_count as u64, limit: u32::MAX.into() });
    }
    let exposure = exposure(corners.iter().flatten());
    // Patches material by material, each material's in scene order.
    let mut by_material: Vec<Vec<usize>> = vec![Vec::new(); scene.materials().len()];
    for (i, patch) in scene.patches().iter().enumerate() {
        by_material[patch.material.0 as usize].push(i);
    }
    let parts: Vec<Part> = by_material
        .iter()
        .enumerate()
        .filter(|(_, patches)| !patches.is_empty())
        .map(|(m, patches)| Part::new(scene, m, patches, &corners, exposure))
        .collect();
    let bytes = to_glb(scene, &parts, exposure, about)?;
    Ok(Glb {
        bytes,
        exposure,
        vertices: vertex_count,
        triangles: parts.iter().map(|p| p.indices.len() / 3).sum(),
        patch_order: parts.iter().flat_map(|p| p.patches.iter().copied()).collect(),
    })
}

/// The luminance mapped to 1: the 99th percentile (nearest rank) of the luminance
/// `0.2126 R + 0.7152 G + 0.0722 B` of `values`, or the largest if that is zero, or 1 if every
/// value is black (or there are none).
pub fn exposure<'a>(values: impl IntoIterator<Item = &'a [Real; 3]>) -> Real {
    let mut luminance: Vec<Real> = values.into_iter().map(|b| 0.2126 * b[0] + 0.7152 * b[1] + 0.0722 * b[2]).collect();
    if luminance.is_empty() {
        return 1.0;
    }
    luminance.sort_by(Real::total_cmp);
    let rank = ((EXPOSURE_PERCENTILE * luminance.len() as Real).ceil() as usize).clamp(1, luminance.len());
    [luminance[rank - 1], luminance[luminance.len() - 1]].into_iter().find(|&l| l > 0.0 && l.is_finite()).unwrap_or(1.0)
}

/// The primitive of one material: its patches' own corners, with their tone-mapped colours.
struct Part {
    material: usize,
    patches: Vec<usize>,
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    colours: Vec<[f32; 3]>,
    indices: Vec<u32>,
}

impl Part {
    /// The vertices and triangles of `patches` (all of material `material`), with the corner
    /// radiosity `corners` divided by `exposure` as colours.
    fn new(scene: &Scene, material: usize, patches: &[usize], corners: &[Vec<[Real; 3]>], exposure: Real) -> Part {
        let mut part = Part {
            material,
            patches: patches.to_vec(),
            positions: Vec::new(),
            normals: Vec::new(),
            colours: Vec::new(),
            indices: Vec::new(),
        };
        for &i in patches {
            let patch = &scene.patches()[i];
            // The whole scene's vertex count fits in u32, so a part's does too.
            let first = part.positions.len() as u32;
            let n = patch.normal().as_vec3().to_array();
            for (v, b) in patch.vertices().iter().zip(&corners[i]) {
                part.positions.push(v.as_vec3().to_array());
                part.normals.push(n);
                part.colours.push(b.map(|c| (c / exposure).clamp(0.0, 1.0) as f32));
            }
            // The fan of `Patch::triangles`: (0, i, i + 1).
            for k in 1..patch.vertices().len() as u32 - 1 {
                part.indices.extend([first, first + k, first + k + 1]);
            }
        }
        part
    }
}

/// The binary glTF file of `parts`: header, JSON chunk, BIN chunk.
fn to_glb(scene: &Scene, parts: &[Part], exposure: Real, about: &ExportInfo) -> Result<Vec<u8>, EvalError> {
    let mut bin = Vec::new();
    let mut root = json::Root::default();
    let buffer = root.push(json::Buffer {
        byte_length: USize64(0),
        name: None,
        uri: None,
        extensions: Default::default(),
        extras: Default::default(),
    });
    let mut accessor = |root: &mut json::Root,
                        data: &[u8],
                        count: usize,
                        component: json::accessor::ComponentType,
                        type_: json::accessor::Type,
                        target: json::buffer::Target,
                        bounds: Option<([f32; 3], [f32; 3])>| {
        let view = root.push(json::buffer::View {
            buffer,
            byte_length: USize64::from(data.len()),
            byte_offset: Some(USize64::from(bin.len())),
            byte_stride: None,
            name: None,
            target: Some(Valid(target)),
            extensions: Default::default(),
            extras: Default::default(),
        });
        // Every view is a whole number of 4-byte components, so the next one stays aligned.
        bin.extend_from_slice(data);
        root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64::from(count),
            component_type: Valid(json::accessor::GenericComponentType(component)),
            type_: Valid(type_),
            min: bounds.map(|(min, _)| json::Value::from(min.to_vec())),
            max: bounds.map(|(_, max)| json::Value::from(max.to_vec())),
            name: None,
            normalized: false,
            sparse: None,
            extensions: Default::default(),
            extras: Default::default(),
        })
    };
    use json::accessor::ComponentType::{F32, U32};
    use json::accessor::Type::{Scalar, Vec3};
    use json::buffer::Target::{ArrayBuffer, ElementArrayBuffer};
    let mut primitives = Vec::with_capacity(parts.len());
    for part in parts {
        let n = part.positions.len();
        let bounds = Some(bounds(&part.positions));
        let positions = accessor(&mut root, &vec3_bytes(&part.positions), n, F32, Vec3, ArrayBuffer, bounds);
        let normals = accessor(&mut root, &vec3_bytes(&part.normals), n, F32, Vec3, ArrayBuffer, None);
        let colours = accessor(&mut root, &vec3_bytes(&part.colours), n, F32, Vec3, ArrayBuffer, None);
        let index_bytes: Vec<u8> = part.indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        let indices = accessor(&mut root, &index_bytes, part.indices.len(), U32, Scalar, ElementArrayBuffer, None);
        let material = root.push(json::Material {
            name: Some(scene.materials()[part.material].name.clone()),
            pbr_metallic_roughness: json::material::PbrMetallicRoughness {
                base_color_factor: json::material::PbrBaseColorFactor([1.0; 4]),
                metallic_factor: json::material::StrengthFactor(0.0),
                roughness_factor: json::material::StrengthFactor(1.0),
                ..Default::default()
            },
            double_sided: false,
            ..Default::default()
        });
        primitives.push(json::mesh::Primitive {
            attributes: BTreeMap::from([
                (Valid(json::mesh::Semantic::Positions), positions),
                (Valid(json::mesh::Semantic::Normals), normals),
                (Valid(json::mesh::Semantic::Colors(0)), colours),
            ]),
            indices: Some(indices),
            material: Some(material),
            mode: Valid(json::mesh::Mode::Triangles),
            targets: None,
            extensions: Default::default(),
            extras: Default::default(),
        });
    }
    let Ok(byte_length) = u32::try_from(bin.len()) else {
        return Err(EvalError::GltfTooLarge { what: "bytes", needed: bin.len() as u64, limit: u32::MAX.into() });
    };
    root.buffers[0].byte_length = USize64::from(byte_length as usize);
    let mesh = root.push(json::Mesh {
        name: Some(about.scene.clone()),
        primitives,
        weights: None,
        extensions: Default::default(),
        extras: Default::default(),
    });
    let node = root.push(json::Node {
        mesh: Some(mesh),
        name: Some(format!("radiosity = COLOR_0 × {exposure:e}")),
        ..Default::default()
    });
    let gltf_scene = root.push(json::Scene {
        name: Some(about.scene.clone()),
        nodes: vec![node],
        extensions: Default::default(),
        extras: Default::default(),
    });
    root.scene = Some(gltf_scene);
    root.extensions_used = vec![UNLIT.to_string(), NGON_ENCODING.to_string()];
    root.asset.generator = Some(format!("radiosity-eval {}", env!("CARGO_PKG_VERSION")));

    // Extension objects and extras are added to the serialised JSON, which keeps them
    // independent of the gltf-json features that would type them.
    let serialise = |e: serde_json::Error| EvalError::Gltf(format!("cannot serialise the JSON ({e})"));
    let mut value = serde_json::to_value(&root).map_err(serialise)?;
    for (k, part) in parts.iter().enumerate() {
        let material = &scene.materials()[part.material];
        value["materials"][k]["extensions"] = serde_json::json!({ UNLIT: {} });
        value["materials"][k]["extras"] = serde_json::json!({
            REFLECTIVITY_EXTRA: material.reflectivity.0,
            EMISSION_EXTRA: material.emission.0,
        });
        value["meshes"][0]["primitives"][k]["extensions"] = serde_json::json!({ NGON_ENCODING: {} });
    }
    value["asset"]["extras"] = serde_json::json!({
        "radiosity_exposure": exposure,
        "tone_mapping": "COLOR_0 = clamp(radiosity / radiosity_exposure, 0, 1) per channel; \
                         radiosity_exposure is the 99th percentile of the vertex luminance \
                         0.2126 R + 0.7152 G + 0.0722 B",
        "materials": "each material's extras hold radiosity_reflectivity and radiosity_emission (linear RGB); \
                      its base colour is white so that the unlit COLOR_0 shows as is",
        "scene": about.scene,
        "solver": about.solver,
        "ff": about.ff,
    });
    let json = serde_json::to_vec(&value).map_err(serialise)?;
    let glb = gltf::binary::Glb {
        // `to_vec` works the length out itself.
        header: gltf::binary::Header { magic: *b"glTF", version: 2, length: 0 },
        json: Cow::Owned(json),
        bin: Some(Cow::Owned(bin)),
    };
    glb.to_vec().map_err(|e| EvalError::Gltf(e.to_string()))
}

/// The smallest and largest coordinates of `points`, as glTF wants them for `POSITION`.
fn bounds(points: &[[f32; 3]]) -> ([f32; 3], [f32; 3]) {
    points.iter().fold(([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]), |(lo, hi), p| {
        (std::array::from_fn(|k| lo[k].min(p[k])), std::array::from_fn(|k| hi[k].max(p[k])))
    })
}

/// Little-endian bytes of f32 triples.
fn vec3_bytes(values: &[[f32; 3]]) -> Vec<u8> {
    values.iter().flatten().flat_map(|x| x.to_le_bytes()).collect()
}
