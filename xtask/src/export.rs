//! `cargo xtask export --scene SCENE --solver SOLVER --out SOLVED.glb [--ff BACKEND]
//! [--until RULES]`: writes the solved scene as binary glTF 2.0, its radiosity as vertex
//! colours, for any glTF viewer (DESIGN §7).
//!
//! What is written, and why:
//! - One node, one mesh, one primitive of triangles. Every patch gets vertices of its own
//!   (3 for a triangle, 4 for a quad), so neighbouring patches share no vertex and creases
//!   between objects or walls stay sharp; the colour at each corner is the smoothed radiosity
//!   of `shading::vertex_radiosity`, so a wall meshed into a grid still shades smoothly. A
//!   quad is cut into the triangles `(0, 1, 2)` and `(0, 2, 3)`, the fan of
//!   `Patch::triangles`; patches are planar and convex, so the fan covers them exactly. The
//!   vertex order makes the triangles counter-clockwise seen from the patch normal, the front
//!   face in glTF.
//! - Attributes, each in its own buffer view, in this order in the BIN chunk: `POSITION`
//!   (f32 vec3, in the scene's units, with the `min`/`max` glTF requires), `NORMAL` (f32 vec3,
//!   the patch normal at each of its corners), `COLOR_0` (f32 vec3, linear RGB in `[0, 1]`),
//!   then the indices (u32 scalars, three per triangle). Vertices come patch after patch, in
//!   the scene's patch order.
//! - One material: base colour white, `doubleSided` false, and `KHR_materials_unlit` (listed
//!   in `extensionsUsed`, not required), so a viewer shows the vertex colours as they are
//!   instead of lighting the scene a second time. A viewer without the extension falls back
//!   to a lit white material tinted by the colours.
//! - Tone mapping is linear: colour = radiosity / exposure, clamped to `[0, 1]` per channel,
//!   where the exposure is the 99th percentile (nearest rank) of the vertex luminance
//!   `0.2126 R + 0.7152 G + 0.0722 B`. So the brightest 1% of vertices, usually the lights,
//!   saturate, and the rest keep their proportions. The exposure is stored twice, so the
//!   radiosity can be recovered as colour × exposure wherever nothing was clamped: in
//!   `asset.extras.radiosity_exposure` (with the scene, solver and backend) and in the node's
//!   name.
//!
//! The file is written by `gltf::binary::Glb`: header, JSON chunk, BIN chunk, each 4-byte
//! aligned. Only `.glb` is written; a `.gltf` output is refused with a message saying so.

use crate::experiment::{Experiment, SolveArgs, check_output_file};
use crate::scene_report::{prepare, print_warnings};
use anyhow::{Context, Result, bail};
use gltf::json;
use json::validation::Checked::Valid;
use json::validation::USize64;
use radiosity_core::{Real, Scene};
use std::borrow::Cow;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The fraction of vertices whose luminance maps below 1.
const EXPOSURE_PERCENTILE: Real = 0.99;

/// Arguments of `export`.
#[derive(Debug, clap::Args)]
pub struct Args {
    #[command(flatten)]
    run: SolveArgs,
    /// The binary glTF file to write (.glb).
    #[arg(long, value_name = "SOLVED.glb")]
    out: PathBuf,
}

/// Runs `export`.
pub fn run(args: &Args) -> Result<()> {
    // Every argument is checked before any geometry is built, so a typo fails at once.
    check_output(&args.out)?;
    check_output_file(&args.out)?;
    let (spec, _) = args.run.check()?;
    let prepared = prepare(&args.run.scene)?;
    print_warnings(&prepared.report());
    let experiment = Experiment::new(&prepared, spec)?;
    let rgb = experiment.radiosity_rgb(&args.run.solver, &args.run.until)?;
    if let Some(i) = rgb.iter().position(|b| b.iter().any(|c| !c.is_finite())) {
        bail!("{} left a radiosity that is not finite at patch {i}, so there is nothing to export", args.run.solver);
    }
    let scene = &prepared.loaded.scene;
    let mesh = PatchMesh::new(scene, &rgb)?;
    let about = About { scene: &args.run.scene, solver: &args.run.solver, ff: experiment.spec.canonical() };
    let bytes = mesh.to_glb(&about)?;
    std::fs::write(&args.out, bytes).with_context(|| format!("cannot write {}", args.out.display()))?;
    println!(
        "{}: {} patches, {} vertices, {} triangles, exposure {:.6e} (radiosity = colour × exposure)",
        args.out.display(),
        scene.len(),
        mesh.positions.len(),
        mesh.indices.len() / 3,
        mesh.exposure
    );
    Ok(())
}

/// Refuses an output that is not `.glb`.
fn check_output(out: &Path) -> Result<()> {
    let extension = out.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    match extension.as_deref() {
        Some("glb") => Ok(()),
        Some("gltf") => {
            bail!("export writes binary glTF only; name the output {} instead", out.with_extension("glb").display())
        }
        _ => bail!("the output {} must end in .glb (export writes binary glTF)", out.display()),
    }
}

/// What the file says about where its colours came from.
struct About<'a> {
    scene: &'a str,
    solver: &'a str,
    ff: String,
}

/// The exported mesh: every patch's own corners, with their tone-mapped colours.
struct PatchMesh {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    colours: Vec<[f32; 3]>,
    indices: Vec<u32>,
    /// Radiosity = colour × exposure, where no channel was clamped.
    exposure: Real,
}

impl PatchMesh {
    /// Builds the vertices, triangles and colours of `scene` for the patch radiosity `rgb`.
    fn new(scene: &Scene, rgb: &[[Real; 3]]) -> Result<PatchMesh> {
        let corners = crate::shading::vertex_radiosity(scene, rgb);
        let vertex_count: usize = scene.patches().iter().map(|p| p.vertices().len()).sum();
        if u32::try_from(vertex_count).is_err() {
            bail!("{vertex_count} vertices are more than glTF's u32 indices can address");
        }
        let exposure = exposure(corners.iter().flatten());
        let mut mesh = PatchMesh {
            positions: Vec::with_capacity(vertex_count),
            normals: Vec::with_capacity(vertex_count),
            colours: Vec::with_capacity(vertex_count),
            indices: Vec::new(),
            exposure,
        };
        for (patch, values) in scene.patches().iter().zip(&corners) {
            let first = mesh.positions.len() as u32;
            let n = patch.normal().as_vec3().to_array();
            for (v, b) in patch.vertices().iter().zip(values) {
                mesh.positions.push(v.as_vec3().to_array());
                mesh.normals.push(n);
                mesh.colours.push(b.map(|c| (c / exposure).clamp(0.0, 1.0) as f32));
            }
            // The fan of `Patch::triangles`: (0, i, i + 1).
            for i in 1..patch.vertices().len() as u32 - 1 {
                mesh.indices.extend([first, first + i, first + i + 1]);
            }
        }
        Ok(mesh)
    }

    /// The binary glTF file: header, JSON chunk, BIN chunk.
    fn to_glb(&self, about: &About<'_>) -> Result<Vec<u8>> {
        let (min, max) = bounds(&self.positions);
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
        let n = self.positions.len();
        let positions = accessor(&mut root, &vec3_bytes(&self.positions), n, F32, Vec3, ArrayBuffer, Some((min, max)));
        let normals = accessor(&mut root, &vec3_bytes(&self.normals), n, F32, Vec3, ArrayBuffer, None);
        let colours = accessor(&mut root, &vec3_bytes(&self.colours), n, F32, Vec3, ArrayBuffer, None);
        let index_bytes: Vec<u8> = self.indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        let indices = accessor(&mut root, &index_bytes, self.indices.len(), U32, Scalar, ElementArrayBuffer, None);
        let Ok(byte_length) = u32::try_from(bin.len()) else {
            bail!("the mesh takes {} bytes, more than a binary glTF file can hold", bin.len());
        };
        root.buffers[0].byte_length = USize64::from(byte_length as usize);

        let material = root.push(json::Material {
            name: Some("radiosity (unlit)".into()),
            pbr_metallic_roughness: json::material::PbrMetallicRoughness {
                base_color_factor: json::material::PbrBaseColorFactor([1.0; 4]),
                metallic_factor: json::material::StrengthFactor(0.0),
                roughness_factor: json::material::StrengthFactor(1.0),
                ..Default::default()
            },
            double_sided: false,
            ..Default::default()
        });
        let primitive = json::mesh::Primitive {
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
        };
        let mesh = root.push(json::Mesh {
            name: Some(about.scene.to_string()),
            primitives: vec![primitive],
            weights: None,
            extensions: Default::default(),
            extras: Default::default(),
        });
        let node = root.push(json::Node {
            mesh: Some(mesh),
            name: Some(format!("radiosity = COLOR_0 × {:e}", self.exposure)),
            ..Default::default()
        });
        let scene = root.push(json::Scene {
            name: Some(about.scene.to_string()),
            nodes: vec![node],
            extensions: Default::default(),
            extras: Default::default(),
        });
        root.scene = Some(scene);
        root.extensions_used = vec![UNLIT.to_string()];
        root.asset.generator = Some(format!("radiosity xtask export {}", env!("CARGO_PKG_VERSION")));

        // The unlit extension object and the asset's extras are added to the serialised JSON:
        // the workspace builds gltf-json without the features that would type them.
        let mut value = serde_json::to_value(&root).context("cannot serialise the glTF JSON")?;
        value["materials"][0]["extensions"] = serde_json::json!({ UNLIT: {} });
        value["asset"]["extras"] = serde_json::json!({
            "radiosity_exposure": self.exposure,
            "tone_mapping": "COLOR_0 = clamp(radiosity / radiosity_exposure, 0, 1) per channel; \
                             radiosity_exposure is the 99th percentile of the vertex luminance \
                             0.2126 R + 0.7152 G + 0.0722 B",
            "scene": about.scene,
            "solver": about.solver,
            "ff": about.ff,
        });
        let json = serde_json::to_vec(&value).context("cannot serialise the glTF JSON")?;
        let glb = gltf::binary::Glb {
            // `to_vec` works the length out itself.
            header: gltf::binary::Header { magic: *b"glTF", version: 2, length: 0 },
            json: Cow::Owned(json),
            bin: Some(Cow::Owned(bin)),
        };
        glb.to_vec().context("cannot write the binary glTF")
    }
}

/// The glTF extension that shows colours without lighting.
const UNLIT: &str = "KHR_materials_unlit";

/// The luminance mapped to 1: the 99th percentile (nearest rank) of the vertex luminance, or
/// the largest if that is zero, or 1 if every vertex is black.
fn exposure<'a>(values: impl Iterator<Item = &'a [Real; 3]>) -> Real {
    let mut luminance: Vec<Real> = values.map(|b| 0.2126 * b[0] + 0.7152 * b[1] + 0.0722 * b[2]).collect();
    if luminance.is_empty() {
        return 1.0;
    }
    luminance.sort_by(Real::total_cmp);
    let rank = ((EXPOSURE_PERCENTILE * luminance.len() as Real).ceil() as usize).clamp(1, luminance.len());
    [luminance[rank - 1], luminance[luminance.len() - 1]].into_iter().find(|&l| l > 0.0).unwrap_or(1.0)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exposure_is_the_99th_percentile_of_luminance() {
        // 200 grey vertices of luminance 1..=200: the 198th is the 99th percentile.
        let values: Vec<[Real; 3]> = (1..=200).map(|i| [i as Real; 3]).collect();
        assert!((exposure(values.iter()) - 198.0).abs() < 1e-9);
        // Mostly black: the brightest sets the exposure; all black: 1.
        let mut values = vec![[0.0; 3]; 200];
        values[7] = [0.0, 2.0, 0.0];
        assert!((exposure(values.iter()) - 1.4304).abs() < 1e-12);
        assert_eq!(exposure([[0.0; 3]; 5].iter()), 1.0);
    }

    #[test]
    fn outputs_other_than_glb_are_refused() {
        assert!(check_output(Path::new("a/b.GLB")).is_ok());
        let e = check_output(Path::new("a/b.gltf")).unwrap_err().to_string();
        assert!(e.contains("binary glTF only") && e.contains("b.glb"), "{e}");
        assert!(check_output(Path::new("b.png")).unwrap_err().to_string().contains(".glb"));
        assert!(check_output(Path::new("b")).is_err());
    }
}
