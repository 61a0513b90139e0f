//! glTF 2.0 input: the triangles of a `.gltf` or `.glb` file as patches, with diffuse
//! materials read from the PBR factors or from the radiosity `extras` of a solved export.
//!
//! What is read, and how it maps to a [`Scene`](radiosity_core::Scene):
//!
//! - **Geometry.** The meshes reached from the default scene (the `scene` property, else the
//!   first scene; a file without scenes uses all its root nodes), through the whole node
//!   hierarchy. Node transforms (`matrix` or translation, rotation, scale) are composed
//!   parent × child in `f64`; a rotation quaternion is renormalised in `f64` first, so a 90°
//!   turn written in `f32` gives coordinates exact to `f64` rounding rather than to `1e-7`.
//!   Meshes that no node of that scene reaches are ignored, as are cameras, lights, skins and
//!   morph targets.
//! - **Primitives.** `TRIANGLES` with or without indices, and `TRIANGLE_STRIP` and
//!   `TRIANGLE_FAN`, which are converted to triangles in the winding the glTF specification
//!   gives them. Points and lines have no area and are refused with an error naming the mesh.
//! - **Quads.** A `TRIANGLES` primitive marked with the extension `FB_ngon_encoding` (what
//!   `radiosity-eval`'s glTF export writes) lists each polygon as a fan of consecutive
//!   triangles sharing their first vertex index, and consecutive polygons never share it. Two
//!   such triangles `(a, b, c)`, `(a, c, d)` are read back as the quad `a b c d`, one patch,
//!   when it is planar to the precision of the file's `f32` coordinates (each vertex within
//!   `8 ε_f32` of the largest coordinate magnitude from the mean plane; the vertices are then
//!   projected onto that plane) and convex. Anything else, polygons of five or more vertices
//!   included, stays one patch per triangle, as without the extension.
//! - **Orientation.** Patches are one-sided, and their front is glTF's front face: the side
//!   from which the vertices run counter-clockwise. A node whose world transform mirrors
//!   space (negative determinant) has its triangles' winding reversed, as glTF requires, so
//!   the front stays on the same side of the surface.
//! - **Materials.** `baseColorFactor` (red, green, blue) is the diffuse reflectivity and
//!   `emissiveFactor` times `KHR_materials_emissive_strength` (default 1) the emission, unless
//!   the material's `extras` say otherwise: an object `extras` with
//!   `"radiosity_reflectivity": [r, g, b]` gives the reflectivity and one with
//!   `"radiosity_emission": [r, g, b]` the emission, each in preference to the PBR factor.
//!   This is how `radiosity-eval`'s glTF export keeps a solved scene's physics while its
//!   base colour stays white, for viewers showing vertex colours unlit. Extras that are not
//!   an object, and other keys, are someone else's and ignored; either key holding anything
//!   but three numbers is an error naming the material. Each glTF material actually used
//!   becomes one scene material with its name (or `material N`). A primitive without a
//!   material gets glTF's default material, whose base colour is white: reflectivity 1 makes
//!   the radiosity system singular, so that is an error saying so, as is any material with a
//!   reflectivity of 1 or more in a channel. Textures are ignored (one warning counts the
//!   materials whose base colour texture is dropped, unless their reflectivity comes from the
//!   extras): radiosity needs one reflectivity per patch, and averaging a texture is a choice
//!   the user should make.
//! - **Objects.** One object per node with a mesh, named after the node, else the mesh, else
//!   `node N`.
//! - **Meshing.** Each triangle is one patch, unless the parameter `size` is positive: then
//!   triangles are cut into similar triangles whose edges are at most `size` times the scene's
//!   bounding-box diagonal. A fraction of the diagonal rather than a length makes the same
//!   argument mean the same refinement in a file modelled in millimetres or in metres.
//! - **Degenerate triangles** (zero area, collinear vertices) are common in real exports and
//!   carry no light; they are dropped and counted in one warning.
//!
//! Everything that cannot be loaded is an error of one sentence naming the file and, where it
//! applies, the mesh, node or material: a missing or unreadable file, truncated or corrupt
//! data, extensions the file requires that we do not support, NaN or infinite positions,
//! missing `POSITION` data, indices past the vertices, a node hierarchy that is not a set of
//! disjoint trees (a cycle, or a node reached twice), and a scene without any usable
//! triangle. The gltf crate's reader indexes slices and asserts sizes as it goes, so accessor
//! layouts and byte ranges are checked here before anything is read: a malformed file must
//! not panic.

use crate::LoadedScene;
use crate::error::GeomError;
use crate::mesh::SceneBuilder;
use crate::spec::{KeyValueParams, ParamDoc};
use glam::{DMat4, DQuat};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;
use gltf::{Accessor, Document, Gltf, Node, Primitive, Semantic};
use radiosity_core::math::bounding_diagonal;
use radiosity_core::{CoreError, Material, MaterialId, ObjectId, Patch, Real, Spectrum, Vec3};
use std::collections::HashMap;
use std::path::Path;

/// The most elements an accessor without a buffer view may declare. Such an accessor is
/// zeros except for its sparse elements, so its `count` is not bounded by the file: a 900-byte
/// file declaring two billion positions would otherwise make the loader allocate 48 GB and
/// abort. 2^24 vertices is far beyond any scene radiosity can solve.
const MAX_UNSTORED_ELEMENTS: usize = 1 << 24;

/// Parameters a glTF file takes after its path.
pub const PARAMS: &[ParamDoc] = &[ParamDoc {
    key: "size",
    default: "0",
    doc: "largest patch edge as a fraction of the scene's bounding-box diagonal; 0 keeps each triangle as one patch",
}];

/// The key of a material's `extras` that holds its diffuse reflectivity, three numbers in
/// `[0, 1)`, read in preference to `baseColorFactor`.
pub const REFLECTIVITY_EXTRA: &str = "radiosity_reflectivity";

/// The key of a material's `extras` that holds its emission, three finite numbers at least 0,
/// read in preference to `emissiveFactor` (and its strength).
pub const EMISSION_EXTRA: &str = "radiosity_emission";

/// The primitive extension marking triangle lists whose consecutive triangles sharing their
/// first index are fans of one polygon (Facebook's vendor extension, no data of its own).
pub const NGON_ENCODING: &str = "FB_ngon_encoding";

/// How far from their mean plane (in units of `f32::EPSILON` times the largest coordinate
/// magnitude) the corners of a fan-encoded quad may lie and still be read as one planar patch:
/// rounding each coordinate to `f32` moves a corner by at most `√3 ε/2` of that magnitude.
const NGON_PLANARITY_ULPS: Real = 8.0;

/// Extensions a file may list in `extensionsRequired` and still be loaded.
const SUPPORTED_REQUIRED_EXTENSIONS: &[&str] = &["KHR_materials_emissive_strength"];

/// Loads the triangles of a glTF 2.0 file (`.gltf` with embedded or external buffers, or
/// binary `.glb`) as a scene; see the module documentation for the mapping.
pub fn load(path: &Path, params: &KeyValueParams) -> Result<LoadedScene, GeomError> {
    let size = size(params)?;
    let bytes = std::fs::read(path).map_err(|e| GeomError::Io { path: path.to_path_buf(), message: e.to_string() })?;
    load_bytes(&bytes, path, Some(path.parent().unwrap_or(Path::new(""))), size, params)
}

/// Loads glTF 2.0 held in memory, text or binary (told apart by the `glTF` magic of binary
/// glTF, not by `name`), exactly as [`load`] loads a file with these bytes. `name` stands for
/// the file in error messages and in the scene's name. There is no directory to resolve
/// relative URIs against, so a buffer stored in an external file is an error; buffers must be
/// data URIs or the binary chunk.
pub fn load_slice(bytes: &[u8], name: &Path, params: &KeyValueParams) -> Result<LoadedScene, GeomError> {
    load_bytes(bytes, name, None, size(params)?, params)
}

/// The `size` parameter.
fn size(params: &KeyValueParams) -> Result<Real, GeomError> {
    params.real("size", 0.0, |v| v >= 0.0, "a fraction of the bounding-box diagonal, at least 0")
}

/// Loads glTF from `bytes`, which were read from `path` (a name for messages when `base` is
/// `None`), meshed at `size`; external buffers are read relative to `base`, and refused
/// without one.
fn load_bytes(
    bytes: &[u8],
    path: &Path,
    base: Option<&Path>,
    size: Real,
    params: &KeyValueParams,
) -> Result<LoadedScene, GeomError> {
    let (document, buffers) = open(bytes, path, base)?;
    let name = std::iter::once(path.display().to_string())
        .chain(params.given().map(|(k, v)| format!(":{k}={v}")))
        .collect::<String>();
    let mut loader = Loader {
        path,
        buffers: &buffers,
        builder: SceneBuilder::new(name),
        materials: HashMap::new(),
        textured: 0,
        faces: Vec::new(),
        read: 0,
        degenerate: 0,
        meshes: 0,
    };
    let mut reached = vec![Reached::No; document.nodes().len()];
    for node in Loader::roots(&document) {
        loader.visit(node, &mut reached)?;
    }
    loader.finish(size)
}

/// Parses and validates the bytes of `path` and loads its buffers (images are never read).
fn open(bytes: &[u8], path: &Path, base: Option<&Path>) -> Result<(Document, Vec<Vec<u8>>), GeomError> {
    let fail = |message: String| GeomError::Gltf { path: path.to_path_buf(), message };
    if bytes.is_empty() {
        return Err(GeomError::EmptyFile { path: path.to_path_buf(), detail: "; the file is empty".into() });
    }
    check_glb_header(bytes).map_err(fail)?;
    let Gltf { document, blob } =
        Gltf::from_slice_without_validation(bytes).map_err(|e| fail(describe_gltf_error(&e, bytes)))?;
    let unsupported: Vec<&str> =
        document.extensions_required().filter(|e| !SUPPORTED_REQUIRED_EXTENSIONS.contains(e)).collect();
    if !unsupported.is_empty() {
        let (noun, pronoun) = if unsupported.len() == 1 { ("extension", "it") } else { ("extensions", "them") };
        return Err(fail(format!(
            "it requires the {noun} {}, and this loader does not support {pronoun} (it supports {})",
            unsupported.join(", "),
            SUPPORTED_REQUIRED_EXTENSIONS.join(", ")
        )));
    }
    let document = validate(document).map_err(fail)?;
    let buffers = read_buffers(&document, base, blob).map_err(fail)?;
    Ok((document, buffers))
}

/// Checks the fixed-size header of binary glTF, whose length field the gltf crate would
/// otherwise underflow on.
fn check_glb_header(bytes: &[u8]) -> Result<(), String> {
    if !bytes.starts_with(b"glTF") {
        return Ok(());
    }
    if bytes.len() < 12 {
        return Err(format!(
            "it is truncated: binary glTF needs a 12-byte header, but the file has {} bytes",
            bytes.len()
        ));
    }
    let length = u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize;
    if length < 12 {
        return Err(format!("its binary glTF header declares a total length of {length} bytes, less than the header"));
    }
    if length > bytes.len() {
        return Err(format!(
            "it is truncated: its binary glTF header declares {length} bytes, but the file has {}",
            bytes.len()
        ));
    }
    Ok(())
}

/// A readable sentence for an error of the gltf crate met while parsing.
fn describe_gltf_error(error: &gltf::Error, bytes: &[u8]) -> String {
    use gltf::binary::Error as Glb;
    match error {
        gltf::Error::Deserialize(e) if bytes.starts_with(b"glTF") => format!("its JSON chunk is invalid: {e}"),
        gltf::Error::Deserialize(e) => format!("it is not glTF JSON, or its JSON is truncated or invalid: {e}"),
        gltf::Error::Binary(Glb::Version(v)) => format!("it is binary glTF version {v}; only version 2 is supported"),
        gltf::Error::Binary(Glb::ChunkLength { length, length_read, .. }) => {
            format!("it is truncated: a binary glTF chunk declares {length} bytes, but only {length_read} follow")
        }
        gltf::Error::Binary(Glb::Length { length, length_read }) => {
            format!("it is truncated: its binary glTF header declares {length} bytes, but only {length_read} follow")
        }
        gltf::Error::Binary(e) => format!("its binary glTF container is corrupt ({e})"),
        e => e.to_string(),
    }
}

/// Validates the document with the gltf crate, tolerating only missing `POSITION` min/max:
/// the specification requires them, but hand-written files often leave them out and nothing
/// here reads them.
fn validate(document: Document) -> Result<Document, String> {
    use gltf::json::validation::Error as Invalid;
    let json = document.into_json();
    // The gltf crate's own validation indexes the POSITION accessor without a bounds check.
    let position = gltf::json::validation::Checked::Valid(Semantic::Positions);
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let accessor = primitive.attributes.get(&position).map_or(0, |a| a.value());
            if accessor >= json.accessors.len() {
                let label = mesh.name.as_deref().map_or_else(|| format!("mesh {m}"), |n| format!("mesh '{n}'"));
                return Err(format!(
                    "{label} primitive {p} reads POSITION from accessor {accessor}, but there are only {} accessors",
                    json.accessors.len()
                ));
            }
        }
    }
    match Document::from_json(json.clone()) {
        Ok(document) => Ok(document),
        Err(gltf::Error::Validation(errors)) => {
            let mut fatal = Vec::new();
            for (path, error) in &errors {
                let path = path.as_str();
                if *error == Invalid::Missing
                    && (path.ends_with("[\"POSITION\"].min") || path.ends_with("[\"POSITION\"].max"))
                {
                    continue;
                }
                if let Some((mesh, primitive)) = missing_positions(path).filter(|_| *error == Invalid::Missing) {
                    let name = json.meshes.get(mesh).and_then(|m| m.name.as_deref());
                    let label = name.map_or_else(|| format!("mesh {mesh}"), |n| format!("mesh '{n}'"));
                    return Err(format!("{label} primitive {primitive} has no POSITION attribute"));
                }
                fatal.push(format!("{path}: {}", error.to_string().to_lowercase()));
            }
            if fatal.is_empty() {
                Ok(Document::from_json_without_validation(json))
            } else {
                Err(format!("it fails glTF validation ({})", fatal.join("; ")))
            }
        }
        Err(e) => Err(e.to_string()),
    }
}

/// The mesh and primitive indices of a validation path `meshes[M].primitives[P].attributes["POSITION"]`.
fn missing_positions(path: &str) -> Option<(usize, usize)> {
    let rest = path.strip_prefix("meshes[")?;
    let (mesh, rest) = rest.split_once(']')?;
    let rest = rest.strip_prefix(".primitives[")?;
    let (primitive, rest) = rest.split_once(']')?;
    (rest == ".attributes[\"POSITION\"]").then_some((mesh.parse().ok()?, primitive.parse().ok()?))
}

/// Loads every buffer (data URI, external file in `base`, or the `.glb` binary chunk),
/// checking each holds the bytes it declares.
fn read_buffers(document: &Document, base: Option<&Path>, mut blob: Option<Vec<u8>>) -> Result<Vec<Vec<u8>>, String> {
    let mut buffers = Vec::new();
    for buffer in document.buffers() {
        let i = buffer.index();
        let source = match buffer.source() {
            gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => "its data URI".to_string(),
            gltf::buffer::Source::Uri(uri) => format!("'{uri}'"),
            gltf::buffer::Source::Bin => "the binary chunk".to_string(),
        };
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => {
                blob.take().ok_or_else(|| format!("buffer {i} refers to the binary chunk, but there is none"))?
            }
            gltf::buffer::Source::Uri(uri) => read_uri(uri, base).map_err(|why| format!("buffer {i} {why}"))?,
        };
        if data.len() < buffer.length() {
            return Err(format!(
                "buffer {i} is truncated: it declares {} bytes, but {source} holds {}",
                buffer.length(),
                data.len()
            ));
        }
        buffers.push(data);
    }
    Ok(buffers)
}

/// The bytes a buffer URI names, as glTF 2.0 allows them (§3.6.1.2): a base64 data URI
/// (`data:[<media type>];base64,<data>`), or a path relative to the file's folder
/// (percent-encoded, RFC 3986), or a `file:` URI. Files loaded from memory have no folder.
fn read_uri(uri: &str, base: Option<&Path>) -> Result<Vec<u8>, String> {
    use base64::Engine as _;
    if let Some(rest) = uri.strip_prefix("data:") {
        let (_, data) = rest.split_once(";base64,").unwrap_or(("", rest));
        return base64::engine::general_purpose::STANDARD
            .decode(data)
            .map_err(|e| format!("has an invalid base64 data URI ({e})"));
    }
    let path = match uri.strip_prefix("file://").or_else(|| uri.strip_prefix("file:")) {
        Some(path) => std::path::PathBuf::from(path),
        None if uri.contains(':') => return Err(format!("has a URI scheme that is not supported ('{uri}')")),
        None => {
            let decoded = percent_encoding::percent_decode_str(uri)
                .decode_utf8()
                .map_err(|_| format!("has a URI that does not decode to UTF-8 ('{uri}')"))?;
            match base {
                Some(base) => base.join(&*decoded),
                None => {
                    return Err(format!("is stored in '{uri}', and glTF loaded from memory cannot read other files"));
                }
            }
        }
    };
    if base.is_none() {
        return Err(format!("is stored in '{uri}', and glTF loaded from memory cannot read other files"));
    }
    std::fs::read(&path).map_err(|e| format!("cannot be read from '{}': {e}", path.display()))
}

/// A triangle or quad ready to become patches, in world space and front-side
/// counter-clockwise.
struct Face {
    /// The corners; only the first `corners` are used.
    v: [Vec3; 4],
    /// 3 or 4.
    corners: usize,
    material: MaterialId,
    object: ObjectId,
}

impl Face {
    fn vertices(&self) -> &[Vec3] {
        &self.v[..self.corners]
    }
}

/// A material's reflectivity and emission as its `extras` give them, each `None` where they
/// give none ([`REFLECTIVITY_EXTRA`], [`EMISSION_EXTRA`]).
#[derive(Clone, Copy, Debug, Default)]
struct MaterialExtras {
    reflectivity: Option<[Real; 3]>,
    emission: Option<[Real; 3]>,
}

/// A polygon of a primitive, in the mesh's own space and the primitive's winding.
#[derive(Clone, Copy, Debug)]
enum Polygon {
    Triangle([Vec3; 3]),
    Quad([Vec3; 4]),
}

/// How far the walk of the node hierarchy has gone through a node.
#[derive(Clone, Copy)]
enum Reached {
    /// Not yet.
    No,
    /// It is being visited: it is an ancestor of the nodes visited now.
    OnPath,
    /// It and all its descendants have been visited.
    Done,
}

/// The state of one load: materials and objects so far, the faces kept and counters for
/// warnings and for explaining an empty result.
struct Loader<'a> {
    path: &'a Path,
    buffers: &'a [Vec<u8>],
    builder: SceneBuilder,
    /// Scene material of each glTF material used (`None`: the default material).
    materials: HashMap<Option<usize>, MaterialId>,
    /// Materials used whose base colour texture is ignored.
    textured: usize,
    faces: Vec<Face>,
    /// Triangles read, degenerate or not.
    read: usize,
    degenerate: usize,
    /// Mesh instances reached from the scene.
    meshes: usize,
}

impl<'a> Loader<'a> {
    fn error(&self, message: String) -> GeomError {
        GeomError::Gltf { path: self.path.to_path_buf(), message }
    }

    /// The nodes to start from: those of the default scene (or the first), else every root.
    fn roots(document: &Document) -> Vec<Node<'_>> {
        if let Some(scene) = document.default_scene().or_else(|| document.scenes().next()) {
            return scene.nodes().collect();
        }
        let mut is_child = vec![false; document.nodes().len()];
        for node in document.nodes() {
            for child in node.children() {
                is_child[child.index()] = true;
            }
        }
        document.nodes().filter(|n| !is_child[n.index()]).collect()
    }

    /// Adds the meshes of `root` and its descendants. `reached` holds how far each node of the
    /// document has been visited, so that a node met again is refused: on the current path it
    /// makes a cycle, elsewhere the hierarchy is not a set of disjoint trees (and a node shared
    /// by two parents at each of n levels would be visited 2^n times). The walk keeps its own
    /// stack, so a deep hierarchy cannot overflow the thread's.
    fn visit(&mut self, root: Node<'_>, reached: &mut [Reached]) -> Result<(), GeomError> {
        enum Step<'d> {
            /// Visit a node under the parent's world matrix.
            Enter(Node<'d>, DMat4),
            /// All descendants of this node are done.
            Leave(usize),
        }
        let mut stack = vec![Step::Enter(root, DMat4::IDENTITY)];
        while let Some(step) = stack.pop() {
            let (node, parent) = match step {
                Step::Leave(index) => {
                    reached[index] = Reached::Done;
                    continue;
                }
                Step::Enter(node, parent) => (node, parent),
            };
            match reached[node.index()] {
                Reached::No => {}
                Reached::OnPath => {
                    return Err(self
                        .error(format!("{} is its own ancestor (the node hierarchy has a cycle)", node_label(&node))));
                }
                Reached::Done => {
                    return Err(self.error(format!(
                        "{} is reached twice from its scene (it is listed twice, or has more than one parent), \
                         but glTF nodes must form disjoint trees",
                        node_label(&node)
                    )));
                }
            }
            reached[node.index()] = Reached::OnPath;
            let world = parent * self.local_transform(&node)?;
            if let Some(mesh) = node.mesh() {
                self.mesh(&node, &mesh, &world)?;
            }
            stack.push(Step::Leave(node.index()));
            // Reversed, so that children are visited in the order they are listed.
            let children: Vec<Node<'_>> = node.children().collect();
            stack.extend(children.into_iter().rev().map(|child| Step::Enter(child, world)));
        }
        Ok(())
    }

    /// The node's own transform in `f64`.
    fn local_transform(&self, node: &Node<'_>) -> Result<DMat4, GeomError> {
        Ok(match node.transform() {
            gltf::scene::Transform::Matrix { matrix } => DMat4::from_cols_array_2d(&matrix.map(|c| c.map(f64::from))),
            gltf::scene::Transform::Decomposed { translation, rotation, scale } => {
                let [x, y, z, w] = rotation.map(f64::from);
                let q = DQuat::from_xyzw(x, y, z, w);
                let length = q.length();
                if !(length > 0.0 && length.is_finite()) {
                    return Err(self.error(format!("{} has a zero rotation quaternion", node_label(node))));
                }
                DMat4::from_scale_rotation_translation(
                    Vec3::from_array(scale.map(f64::from)),
                    q / length,
                    Vec3::from_array(translation.map(f64::from)),
                )
            }
        })
    }

    /// Adds the triangles of one mesh instance.
    fn mesh(&mut self, node: &Node<'_>, mesh: &gltf::Mesh<'_>, world: &DMat4) -> Result<(), GeomError> {
        self.meshes += 1;
        let object_name = node.name().or(mesh.name()).map_or_else(|| format!("node {}", node.index()), str::to_string);
        let object = self.builder.object(object_name);
        let mesh_label = match mesh.name() {
            Some(name) => format!("mesh '{name}'"),
            None => format!("mesh {}", mesh.index()),
        };
        let mirrored = world.determinant() < 0.0;
        for primitive in mesh.primitives() {
            let context = format!("{mesh_label} primitive {}", primitive.index());
            let polygons = self.primitive_polygons(&primitive, &context)?;
            let material = self.material(&primitive, &context)?;
            for polygon in polygons {
                match polygon {
                    Polygon::Quad(v) => {
                        let [a, b, c, d] = v.map(|p| world.transform_point3(p));
                        let v = if mirrored { [a, d, c, b] } else { [a, b, c, d] };
                        if Patch::quad(v, material, object).is_ok() {
                            self.read += 2;
                            self.faces.push(Face { v, corners: 4, material, object });
                        } else {
                            // Not a patch in world space after all: its two triangles, as
                            // without the encoding.
                            for t in [[v[0], v[1], v[2]], [v[0], v[2], v[3]]] {
                                self.add_triangle(t, material, object, node, &context)?;
                            }
                        }
                    }
                    Polygon::Triangle(v) => {
                        let [a, b, c] = v.map(|p| world.transform_point3(p));
                        let v = if mirrored { [a, c, b] } else { [a, b, c] };
                        self.add_triangle(v, material, object, node, &context)?;
                    }
                }
            }
        }
        Ok(())
    }

    /// Keeps the world-space triangle `v`, front side counter-clockwise, as a face, or counts
    /// it as degenerate.
    fn add_triangle(
        &mut self,
        v: [Vec3; 3],
        material: MaterialId,
        object: ObjectId,
        node: &Node<'_>,
        context: &str,
    ) -> Result<(), GeomError> {
        self.read += 1;
        match Patch::triangle(v, material, object) {
            Ok(_) => {
                self.faces.push(Face { v: [v[0], v[1], v[2], Vec3::ZERO], corners: 3, material, object });
                Ok(())
            }
            Err(CoreError::DegeneratePatch { .. }) => {
                self.degenerate += 1;
                Ok(())
            }
            Err(CoreError::NonFiniteVertex) => Err(self.error(format!(
                "{} maps {context} to non-finite coordinates (its transform overflows)",
                node_label(node)
            ))),
            Err(e) => Err(GeomError::core(format!("{}: {context}", self.path.display()), e)),
        }
    }

    /// The scene material of a primitive's glTF material, created and checked on first use.
    fn material(&mut self, primitive: &Primitive<'_>, context: &str) -> Result<MaterialId, GeomError> {
        let gltf_material = primitive.material();
        let key = gltf_material.index();
        if let Some(&id) = self.materials.get(&key) {
            return Ok(id);
        }
        let name = match (key, gltf_material.name()) {
            (None, _) => "default material".to_string(),
            (Some(_), Some(name)) => name.to_string(),
            (Some(i), None) => format!("material {i}"),
        };
        let extras = self.material_extras(&gltf_material, &name)?;
        let pbr = gltf_material.pbr_metallic_roughness();
        let [r, g, b, _alpha] = pbr.base_color_factor().map(f64::from);
        let reflectivity = extras.reflectivity.unwrap_or([r, g, b]);
        let strength = f64::from(gltf_material.emissive_strength().unwrap_or(1.0));
        let emission =
            extras.emission.unwrap_or_else(|| gltf_material.emissive_factor().map(|e| f64::from(e) * strength));
        let material = Material::new(name, Spectrum(reflectivity), Spectrum(emission));
        if let Err(e) = material.validate() {
            let context = match key {
                None => format!(
                    "{}: {context} has no material, and glTF's default material is white (base colour 1, 1, 1)",
                    self.path.display()
                ),
                Some(_) => self.path.display().to_string(),
            };
            return Err(GeomError::core(context, e));
        }
        if pbr.base_color_texture().is_some() && extras.reflectivity.is_none() {
            self.textured += 1;
        }
        let id = self.builder.material(material)?;
        self.materials.insert(key, id);
        Ok(id)
    }

    /// What the `extras` of the material called `name` say about its physics.
    fn material_extras(&self, material: &gltf::Material<'_>, name: &str) -> Result<MaterialExtras, GeomError> {
        let Some(raw) = material.extras() else {
            return Ok(MaterialExtras::default());
        };
        // The gltf crate has checked that this is JSON; nesting too deep for serde_json is an
        // error of its own, not a panic.
        let value: serde_json::Value = serde_json::from_str(raw.get())
            .map_err(|e| self.error(format!("material '{name}' has extras that cannot be read ({e})")))?;
        let Some(object) = value.as_object() else {
            return Ok(MaterialExtras::default());
        };
        let read = |key: &str| -> Result<Option<[Real; 3]>, GeomError> {
            let Some(entry) = object.get(key) else {
                return Ok(None);
            };
            let numbers: Option<Vec<Real>> =
                entry.as_array().and_then(|a| a.iter().map(serde_json::Value::as_f64).collect());
            match numbers.as_deref() {
                Some(&[r, g, b]) => Ok(Some([r, g, b])),
                _ => Err(self.error(format!(
                    "material '{name}' has extras.{key} = {entry}, but it must be a list of three numbers (red, green, blue)"
                ))),
            }
        };
        Ok(MaterialExtras { reflectivity: read(REFLECTIVITY_EXTRA)?, emission: read(EMISSION_EXTRA)? })
    }

    /// The polygons of a primitive in the mesh's own space, in the primitive's winding: its
    /// triangles, with the fans of two triangles of an `FB_ngon_encoding` primitive that make a
    /// planar convex quad read as that quad (see the module documentation).
    fn primitive_polygons(&self, primitive: &Primitive<'_>, context: &str) -> Result<Vec<Polygon>, GeomError> {
        let (positions, corners) = self.primitive_triangles(primitive, context)?;
        let triangle = |t: [u32; 3]| Polygon::Triangle(t.map(|i| positions[i as usize]));
        let fans = primitive.mode() == Mode::Triangles && primitive.extension_value(NGON_ENCODING).is_some();
        if !fans {
            return Ok(corners.into_iter().map(triangle).collect());
        }
        let mut polygons = Vec::with_capacity(corners.len());
        let mut k = 0;
        while k < corners.len() {
            // The fan of one polygon: the triangles from k on that share its first index.
            let anchor = corners[k][0];
            let end = k + corners[k..].iter().take_while(|t| t[0] == anchor).count();
            let quad = match corners[k..end] {
                [[a, b, c], [_, c2, d]] if c2 == c => planar_quad([a, b, c, d].map(|i| positions[i as usize])),
                _ => None,
            };
            match quad {
                Some(v) => polygons.push(Polygon::Quad(v)),
                None => polygons.extend(corners[k..end].iter().copied().map(triangle)),
            }
            k = end;
        }
        Ok(polygons)
    }

    /// The positions of a primitive in the mesh's own space, and its triangles as indices into
    /// them, in the primitive's winding.
    fn primitive_triangles(
        &self,
        primitive: &Primitive<'_>,
        context: &str,
    ) -> Result<(Vec<Vec3>, Vec<[u32; 3]>), GeomError> {
        let mode = primitive.mode();
        if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
            return Err(self.error(format!(
                "{context} has mode {}; only surfaces (TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN) can be loaded",
                mode_name(mode)
            )));
        }
        let Some(position_accessor) = primitive.get(&Semantic::Positions) else {
            return Err(self.error(format!("{context} has no POSITION attribute")));
        };
        self.check_accessor(&position_accessor, "POSITION", context, |t, d| {
            (t == DataType::F32 && d == Dimensions::Vec3).then_some(()).ok_or("3-component floats")
        })?;
        if let Some(indices) = primitive.indices() {
            self.check_accessor(&indices, "index", context, |t, d| {
                (matches!(t, DataType::U8 | DataType::U16 | DataType::U32) && d == Dimensions::Scalar)
                    .then_some(())
                    .ok_or("unsigned integer scalars")
            })?;
        }
        let reader = primitive.reader(|b| self.buffers.get(b.index()).map(Vec::as_slice));
        let short = || self.error(format!("{context}: its data reaches past the end of its buffer"));
        let positions: Vec<Vec3> =
            reader.read_positions().ok_or_else(short)?.map(|p| Vec3::from_array(p.map(f64::from))).collect();
        if positions.len() != position_accessor.count() {
            return Err(short());
        }
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(self.error(format!("{context} has a NaN or infinite coordinate in its POSITION vertex {i}")));
        }
        let indices: Vec<u32> = match reader.read_indices() {
            Some(indices) => indices.into_u32().collect(),
            None if primitive.indices().is_some() => return Err(short()),
            None => (0..positions.len() as u32).collect(),
        };
        if let Some(&i) = indices.iter().find(|&&i| i as usize >= positions.len()) {
            return Err(self.error(format!(
                "{context} refers to vertex {i}, but its POSITION accessor has only {} vertices",
                positions.len()
            )));
        }
        let n = indices.len();
        let corners: Vec<[u32; 3]> = match mode {
            Mode::Triangles => {
                if n % 3 != 0 {
                    return Err(self
                        .error(format!("{context} is a triangle list of {n} vertices, which is not a multiple of 3")));
                }
                indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect()
            }
            // Triangle i of a strip is (v_i, v_{i+1+i%2}, v_{i+2-i%2}): the specification's
            // order, which keeps every triangle of the strip facing the same way.
            Mode::TriangleStrip => {
                (0..n.saturating_sub(2)).map(|i| [indices[i], indices[i + 1 + i % 2], indices[i + 2 - i % 2]]).collect()
            }
            // Triangle i of a fan is (v_{i+1}, v_{i+2}, v_0).
            _ => (0..n.saturating_sub(2)).map(|i| [indices[i + 1], indices[i + 2], indices[0]]).collect(),
        };
        Ok((positions, corners))
    }

    /// Checks an accessor's element type and that every byte it reads lies inside its buffer
    /// view and buffer, so the gltf crate's reader can neither panic nor come back short.
    fn check_accessor(
        &self,
        accessor: &Accessor<'_>,
        role: &str,
        context: &str,
        expected: impl Fn(DataType, Dimensions) -> Result<(), &'static str>,
    ) -> Result<(), GeomError> {
        let fail = |what: String| self.error(format!("{context}: its {role} accessor {} {what}", accessor.index()));
        if let Err(want) = expected(accessor.data_type(), accessor.dimensions()) {
            return Err(fail(format!(
                "holds {:?} {:?} elements, but {role} data must be {want}",
                accessor.dimensions(),
                accessor.data_type()
            )));
        }
        if accessor.count() == 0 {
            return Err(fail("is empty".to_string()));
        }
        let item = accessor.size();
        if let Some(view) = accessor.view() {
            self.check_range(&view, accessor.offset(), accessor.count(), item).map_err(fail)?;
        } else if accessor.count() > MAX_UNSTORED_ELEMENTS {
            return Err(fail(format!(
                "has no buffer view yet declares {} elements; elements not stored in the file are refused beyond \
                 {MAX_UNSTORED_ELEMENTS}",
                accessor.count()
            )));
        }
        if let Some(sparse) = accessor.sparse() {
            if sparse.count() == 0 {
                return Err(fail("has an empty sparse section".to_string()));
            }
            let indices = sparse.indices();
            self.check_range(&indices.view(), indices.offset(), sparse.count(), indices.index_type().size())
                .map_err(&fail)?;
            let values = sparse.values();
            self.check_range(&values.view(), values.offset(), sparse.count(), item).map_err(fail)?;
        }
        Ok(())
    }

    /// Checks that `count` elements of `item` bytes from `offset` in `view` (at its stride)
    /// lie inside the view, and the view inside its buffer.
    fn check_range(
        &self,
        view: &gltf::buffer::View<'_>,
        offset: usize,
        count: usize,
        item: usize,
    ) -> Result<(), String> {
        let stride = view.stride().unwrap_or(item);
        if stride < item {
            return Err(format!("has a byte stride of {stride}, smaller than its {item}-byte elements"));
        }
        let end = stride
            .checked_mul(count.saturating_sub(1))
            .and_then(|b| b.checked_add(item))
            .and_then(|b| b.checked_add(offset));
        if end.is_none_or(|end| end > view.length()) {
            return Err(format!("reads past the end of buffer view {}", view.index()));
        }
        let buffer = view.buffer().index();
        let view_end = view.offset().checked_add(view.length());
        if view_end.is_none_or(|end| end > self.buffers.get(buffer).map_or(0, Vec::len)) {
            return Err(format!(
                "reads through buffer view {}, which reaches past the end of buffer {buffer}",
                view.index()
            ));
        }
        Ok(())
    }

    /// Meshes the faces kept and builds the scene, with the warnings.
    fn finish(mut self, size: Real) -> Result<LoadedScene, GeomError> {
        if self.faces.is_empty() {
            let detail = if self.degenerate > 0 {
                format!("; all {} of its triangles are degenerate", self.degenerate)
            } else if self.meshes == 0 {
                "; no node of its scene has a mesh".to_string()
            } else {
                "; its meshes have no triangles".to_string()
            };
            return Err(GeomError::EmptyFile { path: self.path.to_path_buf(), detail });
        }
        let diagonal = bounding_diagonal(self.faces.iter().flat_map(|f| f.vertices().iter().copied()));
        let target = size * diagonal;
        for f in std::mem::take(&mut self.faces) {
            let added = match *f.vertices() {
                [a, b, c] if size > 0.0 => self.builder.triangle_sized([a, b, c], target, f.material, f.object),
                [a, b, c, d] if size > 0.0 => self.builder.quad_sized([a, b, c, d], target, f.material, f.object),
                _ => self.builder.polygon(f.vertices(), f.material, f.object),
            };
            added.map_err(|e| with_file(self.path, e))?;
        }
        let mut warnings = Vec::new();
        if self.degenerate > 0 {
            let s = if self.degenerate == 1 { "" } else { "s" };
            warnings.push(format!(
                "{}: dropped {} degenerate triangle{s} (zero area) of {} read",
                self.path.display(),
                self.degenerate,
                self.read
            ));
        }
        if self.textured > 0 {
            let (s, have) = if self.textured == 1 { ("", "has") } else { ("s", "have") };
            warnings.push(format!(
                "{}: {} material{s} used {have} a base colour texture, which is ignored: reflectivity comes from baseColorFactor only",
                self.path.display(),
                self.textured
            ));
        }
        let scene = self.builder.build().map_err(|e| with_file(self.path, e))?;
        Ok(LoadedScene { scene, warnings })
    }
}

/// The quad `v` (from `f32` coordinates) projected onto its mean plane, when its corners lie
/// within `f32` rounding of that plane ([`NGON_PLANARITY_ULPS`]); `None` when they do not, or
/// it has no area.
fn planar_quad(v: [Vec3; 4]) -> Option<[Vec3; 4]> {
    let mean = (v[0] + v[1] + v[2] + v[3]) * 0.25;
    // Newell's normal, relative to the first corner.
    let twice_area = (v[1] - v[0]).cross(v[2] - v[0]) + (v[2] - v[0]).cross(v[3] - v[0]);
    let normal = twice_area.normalize_or_zero();
    if normal == Vec3::ZERO {
        return None;
    }
    let magnitude = v.iter().map(|p| p.abs().max_element()).fold(0.0, Real::max);
    let tolerance = NGON_PLANARITY_ULPS * Real::from(f32::EPSILON) * magnitude;
    let offsets = v.map(|p| (p - mean).dot(normal));
    offsets.iter().all(|o| o.abs() <= tolerance).then(|| std::array::from_fn(|k| v[k] - normal * offsets[k]))
}

/// Adds the file to the context of a core error from the builder.
fn with_file(path: &Path, error: GeomError) -> GeomError {
    match error {
        GeomError::Core { context, cause } => GeomError::core(format!("{}: {context}", path.display()), cause),
        e => e,
    }
}

/// `node 'name'`, or `node N` when it has no name.
fn node_label(node: &Node<'_>) -> String {
    match node.name() {
        Some(name) => format!("node '{name}'"),
        None => format!("node {}", node.index()),
    }
}

/// The specification's name of a primitive mode.
fn mode_name(mode: Mode) -> &'static str {
    match mode {
        Mode::Points => "POINTS",
        Mode::Lines => "LINES",
        Mode::LineLoop => "LINE_LOOP",
        Mode::LineStrip => "LINE_STRIP",
        Mode::Triangles => "TRIANGLES",
        Mode::TriangleStrip => "TRIANGLE_STRIP",
        Mode::TriangleFan => "TRIANGLE_FAN",
    }
}
