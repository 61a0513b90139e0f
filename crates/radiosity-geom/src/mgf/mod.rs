//! MGF input (Materials and Geometry Format 2.0, Greg Ward, LBL): the classic radiosity test
//! scenes as patches, with diffuse materials.
//!
//! What is read, and how it maps to a [`Scene`](radiosity_core::Scene):
//!
//! - **Syntax.** One entity per line, words separated by white space; a line ending in `\`
//!   continues on the next; lines starting with `#` are comments.
//! - **Contexts.** Colours (`c`), materials (`m`) and vertices (`v`) are named contexts:
//!   `c name =` defines `name` afresh and makes it current, `c name = other` defines it as a
//!   copy of `other`, `c name` makes an existing one current, and `c` alone makes a fresh
//!   unnamed one current. Entities that follow modify the current context (and the named
//!   one it is): `cxy`, `cspec`, `cct`, `cmix` for colours; `rd`, `ed` for materials; `p`,
//!   `n` for vertices. Names are global to the scene, across includes.
//! - **Materials.** `rd` (diffuse reflectance) and `ed` (diffuse emission) each take the
//!   current colour at the moment they are given; the RGB values are the colour's linear RGB
//!   with luminance the given value (see [`colour`]). A reflectivity that reaches 1 in a
//!   channel after conversion is clamped to 0.999 (the radiosity system needs ρ < 1), with a
//!   warning naming the materials. Specular and transmission attributes (`rs`, `ts`, `td`,
//!   `sides`, `ir`) and `ies` luminaires are ignored with one warning counting them: patches
//!   are diffuse reflectors and emitters.
//! - **Geometry.** `f` faces are split into triangles and quads by `polygon` (non-convex
//!   faces and holes joined by seam edges are ear-clipped); `fh` faces with holes are joined
//!   into one outline by seam edges first. Curved primitives (`cyl`, `cone`, `sph`, `ring`,
//!   `torus`) are tessellated and `prism` extruded by `shapes`, with `div` divisions per
//!   quarter circle (RenderPark's default 4). Vertex normals (`n`) are used only for the axes
//!   of `ring` and `torus`. Faces with no area are dropped and counted in one warning.
//! - **Orientation.** Patches are one-sided; a face's front is the side from which its
//!   vertices run counter-clockwise (MGF's right-hand rule).
//! - **Transforms.** `xf` pushes a transform (`-t x y z`, `-rx`/`-ry`/`-rz` degrees,
//!   `-s f`, `-mx`/`-my`/`-mz` mirrors), applied in the order written, and `xf` alone pops it.
//!   `-i N` applies the transforms after it `N` times; `-a N` makes an array: the enclosed
//!   entities (up to the matching `xf`, or the end of the file) are instantiated `N` times,
//!   the `k`-th with the transforms after `-a` applied `k` times (`k = 0 … N − 1`); several
//!   `-a` give every combination. Transforms apply to geometry when it is instantiated, so a
//!   vertex defined outside an `xf` block is transformed inside it. A transform that mirrors
//!   space reverses the winding of faces, so their front stays on the same side.
//! - **Includes.** `i file [xf arguments]` reads `file` relative to the including file, under
//!   its own transform (arrays included). A file that includes itself, directly or not, is an
//!   error naming the line, as is a file that cannot be read.
//! - **Objects.** `o name` opens an object and `o` closes it; patches belong to the object
//!   path of open objects joined by `/` (the file's name outside any object).
//! - **Meshing.** Each piece of a face is one patch, unless `size` is positive: then pieces are
//!   cut into patches whose edges are at most `size` times the bounding-box diagonal of the
//!   scene, as for glTF.
//!
//! - **Unknown entities** are ignored, as the reference parser does ("If an old version of the
//!   MGF parser encounters new entities it does not recognize, the default action is to ignore
//!   them, printing a warning message", MGF 2.0, Notes): one warning counts them per name and
//!   names the file and line of the first.
//! - **Lines whose first word is not a name** (MGF names begin with a letter: a vertex line
//!   that lost its `p`, a file path a converter left in the file) are skipped, as the
//!   reference parser hands them to its handler of unknown entities and RenderPark's warns
//!   and goes on: one warning counts them and names the file and line of the first.
//! - **Chromaticities with `y ≤ 0`** (`cxy 0.4 0`) are taken as black, as RenderPark does
//!   ("invalid color specification (Y<=0) … setting to black"): one warning counts them and
//!   names the first.
//! - **Faces and holes with fewer than three vertices** enclose nothing and are skipped, as
//!   RenderPark's reader does ("too few vertices in face", and it goes on): one warning counts
//!   them and names the first. Their vertices must still be defined.
//! - **An `o` closing no object** changes no geometry and is ignored with one warning (both
//!   readers stop there).
//! - **Vertices** without `p` are at the origin, the default vertex (`v id =`, MGF 2.0).
//!
//! Everything else is an error of one sentence naming the file and line, as it is for the
//! reference parser: wrong arguments or numbers out of range, an undefined vertex, material or
//! colour, a bare `xf` with nothing to end, an include that cannot be read; and a file with no
//! usable face, or one holding binary data (a NUL byte, or bytes that are not UTF-8).
//!
//! - **Limits.** Before a file is run, it is surveyed with its includes, and refused at the
//!   line where its arrays would make more than 10^6 instances (the product of nested counts
//!   is checked before the first copy), its entities more than 2^22 faces, or its reading more
//!   than 2^27 units of work; entities longer than MGF's reference parser reads (1024 words)
//!   and chains of more than 32 includes are refused too, and the exact patch count after
//!   cutting to `size` is checked before the patches are made. Each refusal is one sentence
//!   with the file, the line and the count; the limits and why they are what they are are in
//!   [`limits`].
//! - **Memory.** [`load_slice`] loads MGF held in memory, with the files it includes given in a
//!   map, through the same code as [`load`]: nothing is read from the disk.
//!
//! ## References
//!
//! - G. Ward, *The Materials and Geometry Format*, version 2.0, Lawrence Berkeley National
//!   Laboratory (the entity pages `v.html`, `f.html` and `notes.html` of the specification).
//! - The reference parser, `mgf_parser.c` and `mgf_context.c` in Radiance's `src/common/`
//!   (NREL/Radiance): unknown entities go to `mg_uhand`, which warns once and goes on; bad
//!   counts, numbers and undefined names stop the parse.
//! - RenderPark's reader, `src/io/mgf/readmgf.cpp` in rpkCpp (OscarChavarro/rpkCpp): the
//!   warnings it prints and goes on after (unknown entities, too few vertices in a face,
//!   degenerate faces, chromaticities with `Y ≤ 0` set to black).

pub mod colour;
pub mod limits;
pub(crate) mod polygon;
pub(crate) mod shapes;

use crate::LoadedScene;
use crate::error::GeomError;
use crate::mesh::SceneBuilder;
use crate::mesh::divisions;
use crate::spec::{KeyValueParams, ParamDoc};
use colour::Colour;
use glam::{DMat4, DVec3};
pub use limits::Limits;
use radiosity_core::math::bounding_diagonal;
use radiosity_core::{Material, MaterialId, ObjectId, Patch, Real, Spectrum, Vec3};
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::ops::Range;
use std::path::{Component, Path, PathBuf};
use std::rc::Rc;

/// Parameters an MGF file takes after its path.
pub const PARAMS: &[ParamDoc] = &[
    ParamDoc {
        key: "size",
        default: "0",
        doc: "largest patch edge as a fraction of the scene's bounding-box diagonal; 0 keeps each face piece as one patch",
    },
    ParamDoc {
        key: "div",
        default: "4",
        doc: "divisions per quarter circle of curved primitives (cyl, cone, sph, ring, torus), as RenderPark's default 4",
    },
];

/// The largest reflectivity a converted colour keeps.
const MAX_REFLECTIVITY: Real = 0.999;

/// Loads an MGF file as a scene; see the module documentation for the mapping. Includes are
/// read from the disk, relative to the including file.
pub fn load(path: &Path, params: &KeyValueParams) -> Result<LoadedScene, GeomError> {
    let options = Options::parse(path, params)?;
    let bytes = std::fs::read(path).map_err(|e| GeomError::Io { path: path.to_path_buf(), message: e.to_string() })?;
    let key = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
    load_from(bytes, path, key, Files::Disk, options, &Limits::DEFAULT)
}

/// Loads MGF held in memory exactly as [`load`] loads a file with these bytes. `name` stands
/// for the file in error messages and in the scene's name, and `includes` holds the files it
/// may include, by their paths relative to the directory of `name` (an include `i part.mgf`
/// in `room/scene.mgf` reads `room/part.mgf`; paths are compared after removing `.` and
/// resolving `..`). The disk is never read.
pub fn load_slice(
    bytes: &[u8],
    name: &Path,
    includes: &BTreeMap<PathBuf, Vec<u8>>,
    params: &KeyValueParams,
) -> Result<LoadedScene, GeomError> {
    load_slice_limited(bytes, name, includes, params, &Limits::DEFAULT)
}

/// [`load_slice`] with other limits than [`Limits::DEFAULT`] (the fuzzer's, smaller).
pub fn load_slice_limited(
    bytes: &[u8],
    name: &Path,
    includes: &BTreeMap<PathBuf, Vec<u8>>,
    params: &KeyValueParams,
    limits: &Limits,
) -> Result<LoadedScene, GeomError> {
    let options = Options::parse(name, params)?;
    let files = includes.iter().map(|(path, bytes)| (normalised(path), bytes.as_slice())).collect();
    load_from(bytes.to_vec(), name, normalised(name), Files::Memory(files), options, limits)
}

/// The parameters of a load.
struct Options {
    size: Real,
    div: usize,
    /// The scene's name: the path and the parameters given.
    name: String,
}

impl Options {
    fn parse(path: &Path, params: &KeyValueParams) -> Result<Options, GeomError> {
        let size = params.real("size", 0.0, |v| v >= 0.0, "a fraction of the bounding-box diagonal, at least 0")?;
        let div = params.count("div", 4, 1, 64)?;
        let name = std::iter::once(path.display().to_string())
            .chain(params.given().map(|(k, v)| format!(":{k}={v}")))
            .collect::<String>();
        Ok(Options { size, div, name })
    }
}

/// Loads the MGF `bytes` read from `path` (identified by `key` among `files`, for include
/// cycles): surveys it against `limits`, runs it, meshes it.
fn load_from(
    bytes: Vec<u8>,
    path: &Path,
    key: PathBuf,
    files: Files<'_>,
    options: Options,
    limits: &Limits,
) -> Result<LoadedScene, GeomError> {
    let text = text_of(path, bytes)?;
    let root = Rc::new(parse(path, &text));
    let mut loader = Loader::new(path, options.div, options.name, files, *limits);
    loader.include_stack.push(key);
    let tally = loader.survey(&root, 0..root.entities.len(), 1)?;
    loader.work = tally.work;
    loader.run(&root, 0..root.entities.len(), 1)?;
    loader.finish(options.size)
}

/// Where included files come from.
enum Files<'a> {
    /// The file system, relative to the including file.
    Disk,
    /// Files held in memory, by their normalised paths.
    Memory(BTreeMap<PathBuf, &'a [u8]>),
}

impl Files<'_> {
    /// What identifies the file at `path`, for include cycles and for reading it once: its
    /// canonical path on disk, its normalised path in memory; an error message when there is
    /// no such file.
    fn key(&self, path: &Path) -> Result<PathBuf, String> {
        match self {
            Files::Disk => std::fs::canonicalize(path).map_err(|e| e.to_string()),
            Files::Memory(files) => {
                let key = normalised(path);
                if files.contains_key(&key) {
                    Ok(key)
                } else {
                    Err("no such file among the files given in memory".to_string())
                }
            }
        }
    }

    /// The bytes of the file at `path`, identified by `key`.
    fn read(&self, path: &Path, key: &Path) -> Result<Vec<u8>, String> {
        match self {
            Files::Disk => std::fs::read(path).map_err(|e| e.to_string()),
            Files::Memory(files) => {
                files.get(key).map(|b| b.to_vec()).ok_or_else(|| "no such file among the files given in memory".into())
            }
        }
    }
}

/// `path` without `.` components and with each `..` removing the component before it (kept
/// when there is none), as a key for files held in memory.
fn normalised(path: &Path) -> PathBuf {
    let mut out: Vec<Component<'_>> = Vec::new();
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir if matches!(out.last(), Some(Component::Normal(_))) => {
                out.pop();
            }
            c => out.push(c),
        }
    }
    out.iter().collect()
}

/// The text of an MGF file; a file holding NUL bytes or bytes that are not UTF-8 is binary, not
/// MGF, and an error naming the first such byte.
fn text_of(path: &Path, bytes: Vec<u8>) -> Result<String, GeomError> {
    let binary = |offset: usize| GeomError::NotText { path: path.to_path_buf(), offset };
    if let Some(offset) = bytes.iter().position(|&b| b == 0) {
        return Err(binary(offset));
    }
    String::from_utf8(bytes).map_err(|e| binary(e.utf8_error().valid_up_to()))
}

/// One entity: its first line and its words.
#[derive(Debug)]
struct Entity {
    line: usize,
    words: Vec<String>,
}

/// A parsed file.
#[derive(Debug)]
struct Source {
    path: PathBuf,
    entities: Vec<Entity>,
}

/// Splits a file into entities: joins continued lines, drops comments and blank lines.
fn parse(path: &Path, text: &str) -> Source {
    let mut entities = Vec::new();
    let mut pending: Option<(usize, String)> = None;
    for (i, raw) in text.lines().enumerate() {
        let trimmed = raw.trim_end();
        let (body, continues) = match trimmed.strip_suffix('\\') {
            Some(body) => (body, true),
            None => (trimmed, false),
        };
        let (line, mut acc) = pending.take().unwrap_or((i + 1, String::new()));
        acc.push(' ');
        acc.push_str(body);
        if continues {
            pending = Some((line, acc));
            continue;
        }
        let words: Vec<String> = acc.split_whitespace().map(str::to_string).collect();
        if words.first().is_some_and(|w| !w.starts_with('#')) {
            entities.push(Entity { line, words });
        }
    }
    if let Some((line, acc)) = pending {
        let words: Vec<String> = acc.split_whitespace().map(str::to_string).collect();
        if words.first().is_some_and(|w| !w.starts_with('#')) {
            entities.push(Entity { line, words });
        }
    }
    Source { path: path.to_path_buf(), entities }
}

/// An MGF material as far as radiosity needs it.
#[derive(Clone, Debug, Default)]
struct Mat {
    rd: Real,
    rd_colour: Colour,
    ed: Real,
    ed_colour: Colour,
}

/// A vertex: position and (optional, zero if absent) normal.
#[derive(Clone, Debug, Default)]
struct Vertex {
    p: Vec3,
    n: Vec3,
}

/// A named context (colours, materials, vertices): the named values and the current one.
/// Names are stored once and values found by index, so that changing the current value of a
/// named context costs the same whatever the length of its name.
#[derive(Debug)]
struct Context<T> {
    kind: &'static str,
    /// The index in `values` and `names` of each name.
    index: HashMap<String, usize>,
    values: Vec<T>,
    names: Vec<String>,
    current: T,
    /// The index of the named value the current one is, if any.
    current_index: Option<usize>,
}

impl<T: Clone + Default> Context<T> {
    fn new(kind: &'static str) -> Self {
        Context {
            kind,
            index: HashMap::new(),
            values: Vec::new(),
            names: Vec::new(),
            current: T::default(),
            current_index: None,
        }
    }

    fn index_of(&self, name: &str, at: &At<'_>) -> Result<usize, GeomError> {
        self.index.get(name).copied().ok_or_else(|| at.undefined(self.kind, name))
    }

    fn get(&self, name: &str, at: &At<'_>) -> Result<&T, GeomError> {
        self.index_of(name, at).map(|i| &self.values[i])
    }

    /// Sets the value named `name`, defining it if new; its index.
    fn define(&mut self, name: &str, value: T) -> usize {
        match self.index.get(name) {
            Some(&i) => {
                self.values[i] = value;
                i
            }
            None => {
                let i = self.values.len();
                self.index.insert(name.to_string(), i);
                self.values.push(value);
                self.names.push(name.to_string());
                i
            }
        }
    }

    /// `c`, `c name`, `c name =`, `c name = template`.
    fn select(&mut self, words: &[String], at: &At<'_>) -> Result<(), GeomError> {
        match words {
            [_] => {
                self.current = T::default();
                self.current_index = None;
            }
            [_, name] => {
                let i = self.index_of(name, at)?;
                self.current = self.values[i].clone();
                self.current_index = Some(i);
            }
            [_, name, eq] if eq == "=" => {
                self.current = T::default();
                self.current_index = Some(self.define(name, T::default()));
            }
            [_, name, eq, template] if eq == "=" => {
                self.current = self.get(template, at)?.clone();
                self.current_index = Some(self.define(name, self.current.clone()));
            }
            _ => return Err(at.bad(format!("'{}' takes a name, 'name =' or 'name = template'", words[0]))),
        }
        Ok(())
    }

    /// Changes the current value (and the named one it is).
    fn modify(&mut self, f: impl FnOnce(&mut T)) {
        f(&mut self.current);
        if let Some(i) = self.current_index {
            self.values[i] = self.current.clone();
        }
    }

    /// The name of the current value, if it is a named one.
    fn current_name(&self) -> Option<&str> {
        self.current_index.map(|i| self.names[i].as_str())
    }
}

/// Where an entity is, for error messages.
struct At<'a> {
    path: &'a Path,
    line: usize,
}

impl At<'_> {
    fn bad(&self, message: String) -> GeomError {
        GeomError::MgfBadEntity { path: self.path.to_path_buf(), line: self.line, message }
    }

    fn undefined(&self, kind: &'static str, name: &str) -> GeomError {
        GeomError::MgfUndefined { path: self.path.to_path_buf(), line: self.line, kind, name: name.to_string() }
    }

    fn real(&self, entity: &str, word: &str) -> Result<Real, GeomError> {
        word.parse::<Real>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| self.bad(format!("'{entity}' expects a number, found '{word}'")))
    }

    fn reals<const N: usize>(&self, words: &[String]) -> Result<[Real; N], GeomError> {
        if words.len() != N + 1 {
            return Err(self.bad(format!("'{}' takes {N} numbers, found {}", words[0], words.len() - 1)));
        }
        let mut out = [0.0; N];
        for (o, w) in out.iter_mut().zip(&words[1..]) {
            *o = self.real(&words[0], w)?;
        }
        Ok(out)
    }
}

/// How a group of `xf` arguments repeats.
enum Repeat {
    Once,
    Iterate(usize),
    Array(usize),
}

/// The groups of an `xf` argument list: how each repeats, and its transform.
fn parse_xf(words: &[String], at: &At<'_>) -> Result<Vec<(Repeat, DMat4)>, GeomError> {
    let mut groups: Vec<(Repeat, DMat4)> = vec![(Repeat::Once, DMat4::IDENTITY)];
    let mut i = 0;
    let number = |i: usize| -> Result<Real, GeomError> {
        let w = words.get(i).ok_or_else(|| at.bad(format!("'xf {}' is missing a number", words[i - 1])))?;
        at.real("xf", w)
    };
    while i < words.len() {
        let flag = words[i].as_str();
        let m = match flag {
            "-t" => {
                let v = DVec3::new(number(i + 1)?, number(i + 2)?, number(i + 3)?);
                i += 3;
                DMat4::from_translation(v)
            }
            "-rx" | "-ry" | "-rz" => {
                let a = number(i + 1)?.to_radians();
                i += 1;
                match flag {
                    "-rx" => DMat4::from_rotation_x(a),
                    "-ry" => DMat4::from_rotation_y(a),
                    _ => DMat4::from_rotation_z(a),
                }
            }
            "-s" => {
                let s = number(i + 1)?;
                if s == 0.0 {
                    return Err(at.bad("'xf -s' must not scale by 0".into()));
                }
                i += 1;
                DMat4::from_scale(DVec3::splat(s))
            }
            "-mx" => DMat4::from_scale(DVec3::new(-1.0, 1.0, 1.0)),
            "-my" => DMat4::from_scale(DVec3::new(1.0, -1.0, 1.0)),
            "-mz" => DMat4::from_scale(DVec3::new(1.0, 1.0, -1.0)),
            "-i" | "-a" => {
                let n = number(i + 1)?;
                if !(n >= 1.0 && n.fract() == 0.0 && n <= 1e6) {
                    return Err(at.bad(format!("'xf {flag}' needs a positive whole count, found {n}")));
                }
                i += 2;
                let repeat = if flag == "-i" { Repeat::Iterate(n as usize) } else { Repeat::Array(n as usize) };
                groups.push((repeat, DMat4::IDENTITY));
                continue;
            }
            _ => return Err(at.bad(format!("'xf' has no option '{flag}'"))),
        };
        i += 1;
        let last = groups.last_mut().expect("groups start non-empty");
        last.1 = m * last.1;
    }
    Ok(groups)
}

/// The instances of an `xf` argument list: one matrix per array element (one if no `-a`).
/// More instances than `limit` are an error, found before any is made.
fn transforms(words: &[String], at: &At<'_>, limit: u64) -> Result<Vec<DMat4>, GeomError> {
    let groups = parse_xf(words, at)?;
    let count = groups.iter().fold(1u64, |count, (repeat, _)| match repeat {
        Repeat::Array(n) => count.saturating_mul(*n as u64),
        _ => count,
    });
    if count > limit {
        return Err(Limits { instances: limit, ..Limits::DEFAULT }.nested(at, count, false));
    }
    let mut instances = vec![DMat4::IDENTITY];
    for (repeat, m) in groups {
        instances = match repeat {
            Repeat::Once => instances.into_iter().map(|t| m * t).collect(),
            Repeat::Iterate(n) => {
                let p = (0..n).fold(DMat4::IDENTITY, |acc, _| m * acc);
                instances.into_iter().map(|t| p * t).collect()
            }
            Repeat::Array(n) => {
                let mut out = Vec::with_capacity(instances.len() * n);
                let mut p = DMat4::IDENTITY;
                for _ in 0..n {
                    out.extend(instances.iter().map(|t| p * *t));
                    p = m * p;
                }
                out
            }
        };
    }
    Ok(instances)
}

/// A face ready for meshing.
struct Face {
    points: Vec<Vec3>,
    material: MaterialId,
    object: ObjectId,
}

/// An object opened by `o`, as a node of the tree of open objects.
struct ObjectNode {
    /// The names of the open objects down to this one, joined by `/`.
    path: String,
    /// The scene object, once a face has been made in it.
    id: Option<ObjectId>,
}

struct Loader<'a> {
    root: PathBuf,
    div: usize,
    files: Files<'a>,
    limits: Limits,
    /// Units of work: the survey's, then names as they are created.
    work: u64,
    /// The survey of each included file, by key.
    tallies: HashMap<PathBuf, limits::Tally>,
    builder: SceneBuilder,
    colours: Context<Colour>,
    materials: Context<Mat>,
    vertices: Context<Vertex>,
    /// Cumulative transforms; the last is current.
    xf: Vec<DMat4>,
    /// The open objects, innermost last, as indices in `object_nodes`.
    objects: Vec<usize>,
    object_nodes: Vec<ObjectNode>,
    /// The node of each name under each parent node.
    object_children: HashMap<(Option<usize>, String), usize>,
    /// The scene object of faces outside any object.
    top_object: Option<ObjectId>,
    include_stack: Vec<PathBuf>,
    sources: HashMap<PathBuf, Rc<Source>>,
    faces: Vec<Face>,
    /// Scene materials by MGF material (its index, or `None` if unnamed) and values.
    material_ids: HashMap<(Option<usize>, [u64; 6]), MaterialId>,
    object_ids: HashMap<String, ObjectId>,
    ignored: BTreeMap<String, usize>,
    /// Entities this loader does not know, by name, with how often they were met.
    unknown: BTreeMap<String, usize>,
    /// Where the first unknown entity was met, as `file:line`.
    first_unknown: Option<String>,
    /// Lines skipped because their first word is not an entity name.
    not_names: Skipped,
    /// Chromaticities with `y ≤ 0`, taken as black.
    black: Skipped,
    /// Faces and holes with fewer than three vertices, which enclose no area.
    short: Skipped,
    /// `o` lines closing an object when none is open.
    unmatched: Skipped,
    clamped: BTreeSet<String>,
    degenerate: usize,
    read: usize,
}

impl<'a> Loader<'a> {
    fn new(root: &Path, div: usize, name: String, files: Files<'a>, limits: Limits) -> Self {
        Loader {
            root: root.to_path_buf(),
            div,
            files,
            limits,
            work: 0,
            tallies: HashMap::new(),
            builder: SceneBuilder::new(name),
            colours: Context::new("colour"),
            materials: Context::new("material"),
            vertices: Context::new("vertex"),
            xf: vec![DMat4::IDENTITY],
            objects: Vec::new(),
            object_nodes: Vec::new(),
            object_children: HashMap::new(),
            top_object: None,
            include_stack: Vec::new(),
            sources: HashMap::new(),
            faces: Vec::new(),
            material_ids: HashMap::new(),
            object_ids: HashMap::new(),
            ignored: BTreeMap::new(),
            unknown: BTreeMap::new(),
            first_unknown: None,
            not_names: Skipped::default(),
            black: Skipped::default(),
            short: Skipped::default(),
            unmatched: Skipped::default(),
            clamped: BTreeSet::new(),
            degenerate: 0,
            read: 0,
        }
    }

    /// Runs the entities `range` of `src`; a bare `xf` may not pop below `floor` transforms.
    fn run(&mut self, src: &Rc<Source>, range: Range<usize>, floor: usize) -> Result<(), GeomError> {
        let mut i = range.start;
        while i < range.end {
            let e = &src.entities[i];
            let at = At { path: &src.path, line: e.line };
            if e.words.len() > limits::MAX_WORDS {
                return Err(Limits::too_many_words(&at, &e.words));
            }
            if e.words[0] == "xf" {
                if e.words.len() == 1 {
                    if self.xf.len() <= floor {
                        return Err(at.bad("'xf' without arguments ends no transform".into()));
                    }
                    self.xf.pop();
                    i += 1;
                    continue;
                }
                let instances = transforms(&e.words[1..], &at, self.limits.instances)?;
                let current = *self.xf.last().expect("the identity is never popped");
                if instances.len() == 1 {
                    self.xf.push(current * instances[0]);
                    i += 1;
                    continue;
                }
                let end = matching_end(src, i, range.end);
                let depth = self.xf.len();
                for m in instances {
                    self.xf.push(current * m);
                    self.run(src, i + 1..end, depth + 1)?;
                    self.xf.truncate(depth);
                }
                i = end + 1;
                continue;
            }
            self.entity(&e.words, &at)?;
            i += 1;
        }
        Ok(())
    }

    fn entity(&mut self, words: &[String], at: &At<'_>) -> Result<(), GeomError> {
        let name = words[0].as_str();
        match name {
            "c" => self.colours.select(words, at)?,
            "cxy" => {
                let [x, y] = at.reals::<2>(words)?;
                let c = if y <= 0.0 && x.is_finite() {
                    // RenderPark: "invalid color specification (Y<=0) … setting to black".
                    self.black.note(at);
                    Colour::BLACK
                } else {
                    Colour::from_xy(x, y).ok_or_else(|| at.bad(format!("'cxy {x} {y}' is not a chromaticity")))?
                };
                self.colours.modify(|v| *v = c);
            }
            "cspec" => {
                if words.len() < 5 {
                    return Err(at.bad("'cspec' takes a wavelength range and at least two samples".into()));
                }
                let v: Vec<Real> = words[1..].iter().map(|w| at.real("cspec", w)).collect::<Result<_, _>>()?;
                let c = Colour::from_samples(v[0], v[1], &v[2..])
                    .ok_or_else(|| at.bad("'cspec' gives no visible light (or a bad wavelength range)".into()))?;
                self.colours.modify(|v| *v = c);
            }
            "cct" => {
                let [t] = at.reals::<1>(words)?;
                let c = Colour::black_body(t).ok_or_else(|| at.bad(format!("'cct {t}' is not a temperature")))?;
                self.colours.modify(|v| *v = c);
            }
            "cmix" => {
                if words.len() < 3 || words.len() % 2 == 0 {
                    return Err(at.bad("'cmix' takes pairs of weight and colour name".into()));
                }
                let mut parts = Vec::new();
                for pair in words[1..].chunks(2) {
                    parts.push((at.real("cmix", &pair[0])?, *self.colours.get(&pair[1], at)?));
                }
                let c = Colour::mix(&parts).ok_or_else(|| at.bad("'cmix' weights sum to no light".into()))?;
                self.colours.modify(|v| *v = c);
            }
            "m" => self.materials.select(words, at)?,
            "rd" | "ed" => {
                let [v] = at.reals::<1>(words)?;
                if v < 0.0 || (name == "rd" && v > 1.0) {
                    return Err(at.bad(format!("'{name} {v}' is out of range")));
                }
                let c = self.colours.current;
                self.materials.modify(|m| {
                    if name == "rd" {
                        (m.rd, m.rd_colour) = (v, c);
                    } else {
                        (m.ed, m.ed_colour) = (v, c);
                    }
                });
            }
            "rs" | "ts" | "td" | "sides" | "ir" | "ies" => *self.ignored.entry(name.to_string()).or_default() += 1,
            "v" => self.vertices.select(words, at)?,
            "p" | "n" => {
                let [x, y, z] = at.reals::<3>(words)?;
                let v = Vec3::new(x, y, z);
                self.vertices.modify(|vx| if name == "p" { vx.p = v } else { vx.n = v });
            }
            "o" => {
                if words.len() == 1 {
                    // The reference parser stops at a close with nothing open; it changes no
                    // geometry, so it is passed over with a warning.
                    if self.objects.pop().is_none() {
                        self.unmatched.note(at);
                    }
                } else {
                    let name = words[1..].join(" ");
                    let parent = self.objects.last().copied();
                    let next = self.object_nodes.len();
                    let node = *self.object_children.entry((parent, name.clone())).or_insert(next);
                    if node == next {
                        let path = match parent {
                            Some(p) => format!("{}/{name}", self.object_nodes[p].path),
                            None => name,
                        };
                        self.spend(path.len() as u64, at, "the name of the object opened here")?;
                        self.object_nodes.push(ObjectNode { path, id: None });
                    }
                    self.objects.push(node);
                }
            }
            "i" => self.include(words, at)?,
            // A face with fewer than three vertices encloses nothing: RenderPark's reader says
            // "too few vertices in face" and goes on. Its vertices must still be defined.
            "f" => {
                let points = self.points(&words[1..], at)?;
                match points.len() {
                    0..3 => self.short.note(at),
                    _ => self.emit(vec![points], at)?,
                }
            }
            "fh" => {
                if let Some(points) = self.face_with_holes(&words[1..], at)? {
                    self.emit(vec![points], at)?;
                }
            }
            "sph" | "cyl" | "cone" | "ring" | "torus" | "prism" => {
                let faces = self.shape(words, at)?;
                self.emit(faces, at)?;
            }
            // MGF names begin with a letter; anything else is not an entity at all.
            // A line whose first word is not a name (a vertex that lost its `p`, a file path a
            // converter left behind): MGF's reference parser hands it to its handler of unknown
            // entities, which RenderPark's warns about and skips.
            _ if !name.starts_with(|c: char| c.is_ascii_alphabetic()) => self.not_names.note(at),
            // The reference parser ignores entities it does not know, with a warning, so that
            // files written for later versions of the format still load (MGF 2.0, "Ignoring
            // new entities").
            _ => {
                *self.unknown.entry(name.to_string()).or_default() += 1;
                self.first_unknown.get_or_insert_with(|| format!("{}:{}", at.path.display(), at.line));
            }
        }
        Ok(())
    }

    fn vertex(&self, name: &str, at: &At<'_>) -> Result<&Vertex, GeomError> {
        self.vertices.get(name, at)
    }

    fn points(&self, names: &[String], at: &At<'_>) -> Result<Vec<Vec3>, GeomError> {
        names.iter().map(|n| self.vertex(n, at).map(|v| v.p)).collect()
    }

    /// `fh v… - h… - h…`: the outline with each hole joined to it by a seam between their
    /// closest vertices; `None` when the outline has fewer than three vertices. A hole with
    /// fewer than three vertices cuts nothing and is left out. Both are counted in `short`.
    fn face_with_holes(&mut self, words: &[String], at: &At<'_>) -> Result<Option<Vec<Vec3>>, GeomError> {
        let loops: Vec<&[String]> = words.split(|w| w == "-").collect();
        let mut outline = self.points(loops[0], at)?;
        let holes = loops[1..].iter().map(|h| self.points(h, at)).collect::<Result<Vec<_>, _>>()?;
        if outline.len() < 3 {
            self.short.note(at);
            return Ok(None);
        }
        for hole in holes {
            if hole.len() < 3 {
                self.short.note(at);
                continue;
            }
            let (mut best, mut oi, mut hi) = (Real::INFINITY, 0, 0);
            for (i, o) in outline.iter().enumerate() {
                for (j, h) in hole.iter().enumerate() {
                    let d = (*o - *h).length_squared();
                    if d < best {
                        (best, oi, hi) = (d, i, j);
                    }
                }
            }
            let mut joined = outline[..=oi].to_vec();
            joined.extend((0..=hole.len()).map(|k| hole[(hi + k) % hole.len()]));
            joined.extend_from_slice(&outline[oi..]);
            outline = joined;
        }
        Ok(Some(outline))
    }

    fn shape(&self, words: &[String], at: &At<'_>) -> Result<Vec<Vec<Vec3>>, GeomError> {
        let entity = words[0].as_str();
        let div = self.div;
        let args = &words[1..];
        let expect = |n: usize| {
            if args.len() == n {
                Ok(())
            } else {
                Err(at.bad(format!("'{entity}' takes {n} arguments, found {}", args.len())))
            }
        };
        let result = match entity {
            "sph" => {
                expect(2)?;
                shapes::sphere(self.vertex(&args[0], at)?.p, at.real(entity, &args[1])?, div)
            }
            "cyl" => {
                expect(3)?;
                let r = at.real(entity, &args[1])?;
                shapes::cone(self.vertex(&args[0], at)?.p, r, self.vertex(&args[2], at)?.p, r, div)
            }
            "cone" => {
                expect(4)?;
                let (r1, r2) = (at.real(entity, &args[1])?, at.real(entity, &args[3])?);
                shapes::cone(self.vertex(&args[0], at)?.p, r1, self.vertex(&args[2], at)?.p, r2, div)
            }
            "ring" | "torus" => {
                expect(3)?;
                let v = self.vertex(&args[0], at)?;
                let (r0, r1) = (at.real(entity, &args[1])?, at.real(entity, &args[2])?);
                if entity == "ring" {
                    shapes::ring(v.p, v.n, r0, r1, div)
                } else {
                    shapes::torus(v.p, v.n, r0, r1, div)
                }
            }
            _ => {
                if args.len() < 4 {
                    return Err(at.bad(format!("'prism' takes at least 3 vertices and a length, found {}", args.len())));
                }
                let base = self.points(&args[..args.len() - 1], at)?;
                shapes::prism(&base, at.real(entity, &args[args.len() - 1])?)
            }
        };
        result.map_err(|m| at.bad(format!("'{entity}': {m}")))
    }

    /// Transforms polygons by the current transform and queues them with the current material
    /// and object.
    fn emit(&mut self, polygons: Vec<Vec<Vec3>>, at: &At<'_>) -> Result<(), GeomError> {
        let m = *self.xf.last().expect("the identity is never popped");
        let mirrored = m.determinant() < 0.0;
        let material = self.material_id(at)?;
        let object = self.object_id(at)?;
        for polygon in polygons {
            let mut points: Vec<Vec3> = polygon.iter().map(|p| m.transform_point3(*p)).collect();
            if mirrored {
                points.reverse();
            }
            self.faces.push(Face { points, material, object });
        }
        Ok(())
    }

    fn material_id(&mut self, at: &At<'_>) -> Result<MaterialId, GeomError> {
        let mat = &self.materials.current;
        let mut reflectivity = mat.rd_colour.rgb(mat.rd);
        let emission = mat.ed_colour.rgb(mat.ed);
        let key = {
            let r = reflectivity.0;
            let e = emission.0;
            (self.materials.current_index, [r[0], r[1], r[2], e[0], e[1], e[2]].map(Real::to_bits))
        };
        if let Some(&id) = self.material_ids.get(&key) {
            return Ok(id);
        }
        let name = self.materials.current_name().unwrap_or("(unnamed material)").to_string();
        self.spend(name.len() as u64, at, "the material made here")?;
        if reflectivity.0.iter().any(|&r| r > MAX_REFLECTIVITY) {
            self.clamped.insert(name.clone());
            reflectivity = Spectrum(reflectivity.0.map(|r| r.min(MAX_REFLECTIVITY)));
        }
        let id = self
            .builder
            .material(Material::new(name.clone(), reflectivity, emission))
            .map_err(|e| at.bad(format!("material '{name}': {e}")))?;
        self.material_ids.insert(key, id);
        Ok(id)
    }

    /// The scene object of the open objects: their names joined by `/`, or the file's name
    /// outside any object.
    fn object_id(&mut self, at: &At<'_>) -> Result<ObjectId, GeomError> {
        let node = self.objects.last().copied();
        let known = match node {
            Some(n) => self.object_nodes[n].id,
            None => self.top_object,
        };
        if let Some(id) = known {
            return Ok(id);
        }
        let name = match node {
            None => self.root.file_name().map_or_else(|| "(top level)".into(), |n| n.to_string_lossy().into_owned()),
            Some(n) => self.object_nodes[n].path.clone(),
        };
        self.spend(name.len() as u64, at, "the name of the object of the face here")?;
        let id = match self.object_ids.get(&name) {
            Some(&id) => id,
            None => {
                let id = self.builder.object(name.clone());
                self.object_ids.insert(name, id);
                id
            }
        };
        match node {
            Some(n) => self.object_nodes[n].id = Some(id),
            None => self.top_object = Some(id),
        }
        Ok(id)
    }

    /// Counts `units` of work done at `at` for `what`, which must not take the file's work
    /// past the limit.
    fn spend(&mut self, units: u64, at: &At<'_>, what: &str) -> Result<(), GeomError> {
        self.work = self.work.saturating_add(units);
        if self.work > self.limits.work {
            return Err(GeomError::MgfLimit {
                path: at.path.to_path_buf(),
                line: Some(at.line),
                message: format!(
                    "{what} would take the file's work to {} units (bytes read and names made), more than the {} a \
                     file may take",
                    self.work, self.limits.work
                ),
            });
        }
        Ok(())
    }

    /// The parsed file at `path`, identified by `key`, read once: `Err` with a message when it
    /// cannot be read, `Ok(Err(_))` when it is not text.
    fn source(&mut self, path: &Path, key: &Path) -> Result<Result<Rc<Source>, GeomError>, String> {
        if let Some(s) = self.sources.get(key) {
            return Ok(Ok(Rc::clone(s)));
        }
        let bytes = self.files.read(path, key)?;
        Ok(text_of(path, bytes).map(|text| {
            let s = Rc::new(parse(path, &text));
            self.sources.insert(key.to_path_buf(), Rc::clone(&s));
            s
        }))
    }

    /// `i file [xf arguments]`.
    fn include(&mut self, words: &[String], at: &At<'_>) -> Result<(), GeomError> {
        let Some(file) = words.get(1) else {
            return Err(at.bad("'i' needs a file name".into()));
        };
        let include = at.path.parent().unwrap_or(Path::new(".")).join(file);
        let missing = |message: String| GeomError::MgfMissingInclude {
            path: at.path.to_path_buf(),
            line: at.line,
            include: include.clone(),
            message,
        };
        let key = self.files.key(&include).map_err(&missing)?;
        if self.include_stack.contains(&key) {
            return Err(GeomError::MgfIncludeCycle { path: at.path.to_path_buf(), line: at.line, include });
        }
        let source = self.source(&include, &key).map_err(&missing)??;
        let instances = transforms(&words[2..], at, self.limits.instances)?;
        let current = *self.xf.last().expect("the identity is never popped");
        let depth = self.xf.len();
        self.include_stack.push(key);
        for m in instances {
            self.xf.push(current * m);
            self.run(&source, 0..source.entities.len(), depth + 1)?;
            self.xf.truncate(depth);
        }
        self.include_stack.pop();
        Ok(())
    }

    fn finish(mut self, size: Real) -> Result<LoadedScene, GeomError> {
        let path = self.root.clone();
        let with_file = |e: GeomError| match e {
            GeomError::Core { context, cause } => GeomError::core(format!("{}: {context}", path.display()), cause),
            e => e,
        };
        let mut pieces = Vec::new();
        for face in std::mem::take(&mut self.faces) {
            self.read += 1;
            match polygon::split(&face.points) {
                Ok(parts) => pieces.extend(parts.into_iter().map(|p| (p, face.material, face.object))),
                Err(polygon::Degenerate) => self.degenerate += 1,
            }
        }
        if pieces.is_empty() {
            let mut detail = if self.degenerate > 0 {
                format!("; all {} of its faces are degenerate", self.degenerate)
            } else {
                "; it has no faces".to_string()
            };
            for (skipped, kind) in self.skipped_kinds() {
                detail += &format!("; {}", skipped.phrase(&kind));
            }
            return Err(GeomError::EmptyFile { path, detail });
        }
        let target = size * bounding_diagonal(pieces.iter().flat_map(|(p, _, _)| p.iter().copied()));
        let patches = pieces.iter().fold(0u64, |n, (p, _, _)| n.saturating_add(patches_of(p, size > 0.0, target)));
        if patches > self.limits.patches {
            return Err(self.limits.too_many_patches(&path, size, patches));
        }
        for (p, material, object) in pieces {
            let added = match (size > 0.0, p.as_slice()) {
                (true, &[a, b, c]) => self.builder.triangle_sized([a, b, c], target, material, object),
                (true, &[a, b, c, d]) => self.builder.quad_sized([a, b, c, d], target, material, object),
                _ => self.builder.polygon(&p, material, object),
            };
            added.map_err(with_file)?;
        }
        let mut warnings = Vec::new();
        let file = path.display();
        if self.degenerate > 0 {
            let s = if self.degenerate == 1 { "" } else { "s" };
            warnings.push(format!(
                "{file}: dropped {} degenerate face{s} (zero area) of {} read",
                self.degenerate, self.read
            ));
        }
        if !self.ignored.is_empty() {
            let total: usize = self.ignored.values().sum();
            let list = self.ignored.iter().map(|(k, n)| format!("{k} ×{n}")).collect::<Vec<_>>().join(", ");
            warnings.push(format!(
                "{file}: ignored {total} non-diffuse attributes ({list}): patches are diffuse reflectors and emitters only"
            ));
        }
        if !self.unknown.is_empty() {
            let total: usize = self.unknown.values().sum();
            let list = self.unknown.iter().map(|(k, n)| format!("'{k}' ×{n}")).collect::<Vec<_>>().join(", ");
            let first = self.first_unknown.as_deref().unwrap_or_default();
            let s = if total == 1 { "y" } else { "ies" };
            warnings.push(format!(
                "{file}: ignored {total} unknown entit{s} ({list}; the first at {first}), as MGF's reference parser does"
            ));
        }
        for (skipped, kind) in self.skipped_kinds() {
            warnings.push(format!("{file}: {}, {}", skipped.phrase(&kind), kind.why));
        }
        if !self.clamped.is_empty() {
            let list = self.clamped.iter().map(|n| format!("'{n}'")).collect::<Vec<_>>().join(", ");
            warnings.push(format!(
                "{file}: reflectivity of {list} reaches 1 in a channel after colour conversion and is clamped to {MAX_REFLECTIVITY}"
            ));
        }
        let scene = self.builder.build().map_err(with_file)?;
        Ok(LoadedScene { scene, warnings })
    }
}

/// The patches `finish` makes of a piece (a triangle or a convex quad): one, or when cut to
/// edges of at most `target` (`sized`), as many as `SceneBuilder::triangle_sized` and
/// `quad_sized` make, counted before they are made.
fn patches_of(piece: &[Vec3], sized: bool, target: Real) -> u64 {
    let cuts = |a: Vec3, b: Vec3, c: Vec3, d: Vec3| divisions((b - a).length().max((c - d).length()), target) as u64;
    match (sized, piece) {
        (true, &[a, b, c]) => {
            let k = divisions((b - a).length().max((c - b).length()).max((a - c).length()), target) as u64;
            k.saturating_mul(k)
        }
        (true, &[a, b, c, d]) => {
            let (nu, nv) = (cuts(a, b, c, d), cuts(a, d, c, b));
            if Patch::quad([a, b, c, d], MaterialId(0), ObjectId(0)).is_ok() {
                nu.saturating_mul(nv)
            } else {
                let k = nu.max(nv);
                k.saturating_mul(k).saturating_mul(2)
            }
        }
        _ => 1,
    }
}

/// Lines of one kind passed over with a warning: how many, and where the first was.
#[derive(Default)]
struct Skipped {
    count: usize,
    first: Option<String>,
}

/// How the warning of one kind of skipped line reads.
struct SkippedKind {
    /// What was done, with `{n}` for the count: "skipped {n} line".
    verb: &'static str,
    /// The plural ending of the noun before `what`, and its singular one.
    endings: (&'static str, &'static str),
    /// What the lines were.
    what: &'static str,
    /// Why: the reader that does the same.
    why: &'static str,
}

impl Skipped {
    fn note(&mut self, at: &At<'_>) {
        self.count += 1;
        self.first.get_or_insert_with(|| format!("{}:{}", at.path.display(), at.line));
    }

    /// "skipped 2 lines whose first word is not an entity name (the first at f.mgf:12)".
    fn phrase(&self, kind: &SkippedKind) -> String {
        let ending = if self.count == 1 { kind.endings.1 } else { kind.endings.0 };
        let first = self.first.as_deref().unwrap_or_default();
        format!("{}{ending} {} (the first at {first})", kind.verb.replace("{n}", &self.count.to_string()), kind.what)
    }
}

impl Loader<'_> {
    /// The kinds of line passed over that were met, each with how its warning reads.
    fn skipped_kinds(&self) -> Vec<(&Skipped, SkippedKind)> {
        let kinds = [
            (
                &self.not_names,
                SkippedKind {
                    verb: "skipped {n} line",
                    endings: ("s", ""),
                    what: "whose first word is not an entity name",
                    why: "as MGF's reference parser does",
                },
            ),
            (
                &self.black,
                SkippedKind {
                    verb: "took {n} chromaticit",
                    endings: ("ies", "y"),
                    what: "with y ≤ 0 as black",
                    why: "as RenderPark does",
                },
            ),
            (
                &self.short,
                SkippedKind {
                    verb: "skipped {n} face",
                    endings: ("s or holes", " or hole"),
                    what: "with fewer than 3 vertices",
                    why: "as RenderPark does",
                },
            ),
            (
                &self.unmatched,
                SkippedKind {
                    verb: "ignored {n} 'o' line",
                    endings: ("s", ""),
                    what: "closing an object when none is open",
                    why: "since it changes no geometry",
                },
            ),
        ];
        kinds.into_iter().filter(|(s, _)| s.count > 0).collect()
    }
}

/// The index of the bare `xf` that ends the block opened at `start`, or `end` if none does.
fn matching_end(src: &Source, start: usize, end: usize) -> usize {
    let mut depth = 0usize;
    for j in start..end {
        let w = &src.entities[j].words;
        if w[0] == "xf" {
            if w.len() > 1 {
                depth += 1;
            } else {
                depth -= 1;
                if depth == 0 {
                    return j;
                }
            }
        }
    }
    end
}
