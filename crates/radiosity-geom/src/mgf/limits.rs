//! Bounds on what one MGF file may make, and the survey that checks them before anything is
//! instantiated.
//!
//! A few lines of MGF can ask for unbounded work: arrays multiply (three nested `xf -a 1000000`
//! are 10^18 instances), includes multiply (ten lines `i next.mgf` in each of ten files are
//! 10^10 runs of the last one), and every curved primitive is hundreds of facets. So before a
//! file is run, a survey walks its entities and those of its includes once each (an included
//! file once, however often it is included), multiplying the counts of arrays and includes with
//! saturating arithmetic, and refuses the file at the first line where the totals exceed the
//! [`Limits`]: the error names the file, the line and the count. What the survey
//! cannot see (the number of patches `size` cuts the faces into; names whose creation costs
//! their length) is counted when it happens, before the memory is allocated.
//!
//! The limits, [`Limits::DEFAULT`]:
//!
//! - **Instances** ([`MAX_INSTANCES`], 10^6): the copies that `xf -a` arrays make, counting the
//!   innermost copies of nested arrays (two nested arrays of 1000 make 10^6), through includes.
//!   The product of the counts of nested arrays is checked before the first copy is made.
//! - **Patches** ([`MAX_PATCHES`], 2^22 = 4 194 304): each face and each facet of a curved
//!   primitive is at least one patch unless it is degenerate, so their count is checked by the
//!   survey; the exact count, after splitting faces and cutting them to `size`, is checked before
//!   the patches are built. 330 times the largest real scene (`office.mgf`, 12 626 patches).
//! - **Work** ([`MAX_WORK`], 2^27 units): the bytes of the entities run, counting each repetition
//!   by arrays and includes, plus a third of the cube of the vertex count of every face of
//!   more than four vertices (the corner tests of ear clipping at worst: each of the `k − 3`
//!   ears clipped may test every corner against every other), the facets of curved primitives,
//!   and the matrix products of `xf -i` (so one face of more than about 730 vertices is
//!   refused on its own). The limit is about a second of loading (measured in
//!   `docs/scenes.md`), far beyond the largest real scene (`classroom.mgf`, 1.1 MB). The names of objects
//!   and materials, whose creation costs their length, are counted as they are created.
//! - **Include depth** ([`MAX_INCLUDE_DEPTH`], 32 files including one another): the reader
//!   recurses into each include, so the depth bounds its stack.
//! - **Arguments** ([`MAX_WORDS`], 1024 words to an entity, MGF's reference parser's
//!   `MG_MAXARGC`): the reference parser reads no more. The real scenes have at most 41.
//!
//! The five real scenes in `shared/scenes/mgf/` load within a 64th of each limit (a test checks
//! it), so the limits refuse only files that ask for far more than any of them.

use super::{At, Loader, Source, matching_end, parse_xf};
use crate::error::GeomError;
use std::ops::Range;
use std::path::Path;
use std::rc::Rc;

/// The most instances `xf -a` arrays may make in one file, counting innermost copies.
pub const MAX_INSTANCES: u64 = 1_000_000;
/// The most patches one file may make.
pub const MAX_PATCHES: u64 = 1 << 22;
/// The most units of work (bytes of entities run, and the other costs in the module
/// documentation) one file may take.
pub const MAX_WORK: u64 = 1 << 27;
/// The most files that may include one another in a chain below the file loaded.
pub const MAX_INCLUDE_DEPTH: usize = 32;
/// The most words an entity may have, its name included: MGF's reference parser's
/// `MG_MAXARGC` (`MG_MAXLINE / 4`).
pub const MAX_WORDS: usize = 1024;

/// What one file may make; [`Limits::DEFAULT`] for files, smaller ones for fuzzing, where a
/// file at the default limits would take longer than the fuzzer's timeout.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// The most instances arrays may make.
    pub instances: u64,
    /// The most patches.
    pub patches: u64,
    /// The most units of work.
    pub work: u64,
    /// The most files in a chain of includes below the file loaded.
    pub include_depth: usize,
}

impl Limits {
    /// The limits files are loaded with: [`MAX_INSTANCES`], [`MAX_PATCHES`], [`MAX_WORK`],
    /// [`MAX_INCLUDE_DEPTH`].
    pub const DEFAULT: Limits =
        Limits { instances: MAX_INSTANCES, patches: MAX_PATCHES, work: MAX_WORK, include_depth: MAX_INCLUDE_DEPTH };
}

impl Default for Limits {
    fn default() -> Self {
        Limits::DEFAULT
    }
}

/// What a range of entities makes when it is run once.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Tally {
    /// Innermost instances made by arrays.
    instances: u64,
    /// Faces and facets, each at least one patch unless degenerate.
    faces: u64,
    /// Units of work.
    pub(super) work: u64,
    /// How deep the includes below it nest.
    depth: usize,
}

impl Tally {
    /// Adds `other` run `count` times (an array or include of `count` instances).
    fn add_repeated(&mut self, other: Tally, count: u64) {
        let made = if count > 1 || other.instances > 0 { count.saturating_mul(other.instances.max(1)) } else { 0 };
        self.instances = self.instances.saturating_add(made);
        self.faces = self.faces.saturating_add(count.saturating_mul(other.faces));
        self.work = self.work.saturating_add(count.saturating_mul(other.work));
        self.depth = self.depth.max(other.depth);
    }
}

/// A count for a message: the number, or "more than 2^64 − 1" when it saturated.
fn count_text(n: u64) -> String {
    if n == u64::MAX { format!("more than {}", u64::MAX) } else { n.to_string() }
}

/// The faces (or facets) an entity makes, each at least one patch unless degenerate, with
/// `div` divisions per quarter circle.
fn faces_of(words: &[String], div: u64) -> u64 {
    let args = words.len() as u64 - 1;
    match words[0].as_str() {
        "f" | "fh" if args >= 3 => 1,
        "sph" => 8 * div * div,
        "torus" => 16 * div * div,
        "cyl" | "cone" | "ring" => 4 * div,
        "prism" if args >= 4 => args + 1,
        _ => 0,
    }
}

/// The work of running an entity once, `xf` repetitions aside: its bytes, a third of the cube
/// of the vertex count of a face (or prism base) of more than four vertices, and its facets.
fn work_of(words: &[String], faces: u64) -> u64 {
    let bytes: u64 = words.iter().map(|w| w.len() as u64 + 1).sum();
    let vertices = match words[0].as_str() {
        "f" | "fh" => words.len() as u64 - 1,
        "prism" => (words.len() as u64).saturating_sub(2),
        _ => 0,
    };
    let splitting = if vertices > 4 { vertices.pow(3) / 3 } else { 0 };
    bytes + splitting + faces
}

impl Limits {
    fn error(path: &Path, line: Option<usize>, message: String) -> GeomError {
        GeomError::MgfLimit { path: path.to_path_buf(), line, message }
    }

    /// The error for an entity with more than [`MAX_WORDS`] words.
    pub(super) fn too_many_words(at: &At<'_>, words: &[String]) -> GeomError {
        Limits::error(
            at.path,
            Some(at.line),
            format!(
                "'{}' has {} arguments, more than the {} MGF's reference parser reads in one entity",
                words[0],
                words.len() - 1,
                MAX_WORDS - 1
            ),
        )
    }

    /// The error for `xf -a` arrays whose counts multiply to `count` at one line.
    pub(super) fn nested(&self, at: &At<'_>, count: u64, nested: bool) -> GeomError {
        let what = if nested { "the nested `xf -a` arrays here" } else { "the `xf -a` arrays here" };
        Limits::error(
            at.path,
            Some(at.line),
            format!(
                "{what} would make {} instances, more than the {} a file may create",
                count_text(count),
                self.instances
            ),
        )
    }

    /// Checks the totals of a survey after the entity at `at`.
    fn check(&self, tally: &Tally, at: &At<'_>) -> Result<(), GeomError> {
        let message = if tally.instances > self.instances {
            format!(
                "the `xf -a` arrays up to here, through nesting and includes, would make {} instances, more than the {} \
                 a file may create",
                count_text(tally.instances),
                self.instances
            )
        } else if tally.faces > self.patches {
            format!(
                "the entities up to here, repeated by arrays and includes, would make {} faces, each at least one \
                 patch, more than the {} patches a file may create",
                count_text(tally.faces),
                self.patches
            )
        } else if tally.work > self.work {
            format!(
                "reading the file up to here, repeated by arrays and includes, would take {} units of work (bytes read \
                 and faces split), more than the {} a file may take",
                count_text(tally.work),
                self.work
            )
        } else {
            return Ok(());
        };
        Err(Limits::error(at.path, Some(at.line), message))
    }

    /// The error for a file whose faces, split and cut to `size`, make `count` patches.
    pub(super) fn too_many_patches(&self, path: &Path, size: f64, count: u64) -> GeomError {
        let meshed = if size > 0.0 { format!("cut to size={size}, ") } else { String::new() };
        Limits::error(
            path,
            None,
            format!(
                "{meshed}its faces would make {} patches, more than the {} a file may create",
                count_text(count),
                self.patches
            ),
        )
    }
}

impl Loader<'_> {
    /// Surveys the entities `range` of `src` as [`Loader::run`] would run them once, inside
    /// arrays of this file whose counts multiply to `enclosing`: what they make, or the error
    /// at the first line where that exceeds the limits. Included files are surveyed once and
    /// remembered. Lines that `run` will refuse for another reason (a malformed `xf`, an
    /// include that cannot be read or makes a cycle) count as plain lines, so that `run` gives
    /// its own error for them.
    pub(super) fn survey(&mut self, src: &Rc<Source>, range: Range<usize>, enclosing: u64) -> Result<Tally, GeomError> {
        let limits = self.limits;
        let div = self.div as u64;
        let mut tally = Tally::default();
        let mut i = range.start;
        while i < range.end {
            let e = &src.entities[i];
            let at = At { path: &src.path, line: e.line };
            let words = &e.words;
            if words.len() > MAX_WORDS {
                return Err(Limits::too_many_words(&at, words));
            }
            let faces = faces_of(words, div);
            tally.faces = tally.faces.saturating_add(faces);
            tally.work = tally.work.saturating_add(work_of(words, faces));
            match words[0].as_str() {
                "xf" if words.len() > 1 => {
                    let (count, iterations) = xf_counts(&words[1..], &at);
                    tally.work = tally.work.saturating_add(iterations);
                    if count > 1 {
                        let nest = enclosing.saturating_mul(count);
                        if nest > limits.instances {
                            return Err(limits.nested(&at, nest, enclosing > 1));
                        }
                        let end = matching_end(src, i, range.end);
                        let body = self.survey(src, i + 1..end, nest)?;
                        tally.add_repeated(body, count);
                        limits.check(&tally, &at)?;
                        i = end + 1;
                        continue;
                    }
                }
                "i" if words.len() > 1 => {
                    if let Some((file, included)) = self.survey_include(&words[1], &at)? {
                        let (count, iterations) = xf_counts(&words[2..], &at);
                        tally.work = tally.work.saturating_add(iterations);
                        let nest = enclosing.saturating_mul(count).saturating_mul(included.instances.max(1));
                        if nest > limits.instances {
                            return Err(Limits::error(
                                at.path,
                                Some(at.line),
                                format!(
                                    "the `xf -a` arrays around this include and in {file} would make {} instances, \
                                     more than the {} a file may create",
                                    count_text(nest),
                                    limits.instances
                                ),
                            ));
                        }
                        tally.add_repeated(included, count);
                        tally.depth = tally.depth.max(included.depth + 1);
                    }
                }
                _ => {}
            }
            limits.check(&tally, &at)?;
            i += 1;
        }
        Ok(tally)
    }

    /// The survey of the file `i file` at `at` names, from memory when it was surveyed before;
    /// `None` when it cannot be read or makes a cycle (which `run` reports). An include that
    /// nests deeper than the limit is an error.
    fn survey_include(&mut self, file: &str, at: &At<'_>) -> Result<Option<(String, Tally)>, GeomError> {
        let include = at.path.parent().unwrap_or(Path::new(".")).join(file);
        let Ok(key) = self.files.key(&include) else { return Ok(None) };
        if self.include_stack.contains(&key) {
            return Ok(None);
        }
        let depth = self.include_stack.len();
        let most = self.limits.include_depth;
        let deep = |below: usize| {
            Limits::error(
                at.path,
                Some(at.line),
                format!(
                    "including {} here nests includes {} deep, more than the {} a file may",
                    include.display(),
                    depth + below,
                    most
                ),
            )
        };
        let tally = match self.tallies.get(&key) {
            Some(&tally) => tally,
            None => {
                if depth > self.limits.include_depth {
                    return Err(deep(0));
                }
                let Ok(Ok(source)) = self.source(&include, &key) else { return Ok(None) };
                self.include_stack.push(key.clone());
                let tally = self.survey(&source, 0..source.entities.len(), 1);
                self.include_stack.pop();
                let tally = tally?;
                self.tallies.insert(key, tally);
                tally
            }
        };
        if depth + tally.depth > self.limits.include_depth {
            return Err(deep(tally.depth));
        }
        Ok(Some((include.display().to_string(), tally)))
    }
}

/// The instances (the product of the `-a` counts) and the matrix products of `-i` of an `xf`
/// argument list; an argument list `run` will refuse counts as one instance.
fn xf_counts(words: &[String], at: &At<'_>) -> (u64, u64) {
    match parse_xf(words, at) {
        Ok(groups) => groups.iter().fold((1u64, 0u64), |(count, iterations), group| match group.0 {
            super::Repeat::Array(n) => (count.saturating_mul(n as u64), iterations),
            super::Repeat::Iterate(n) => (count, iterations.saturating_add(n as u64)),
            super::Repeat::Once => (count, iterations),
        }),
        Err(_) => (1, 0),
    }
}
