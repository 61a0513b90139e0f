//! `labyrinth`: the paper's second scene, maze walls on a floor (high reflectivity).
//!
//! Rousselle & Renaud describe it only as a labyrinth of 3362 patches with mean reflectivity
//! 0.59. Our reconstruction, in metres, y up:
//!
//! - **Maze**: a perfect maze (exactly one path between any two cells) on `cells × cells`
//!   square cells of 2 m, made by a randomised depth-first search from cell (0, 0) driven by
//!   `ChaCha8Rng` seeded with `seed`, so each seed gives one fixed layout ([`passages`]).
//! - **Walls**: solid limestone slabs 0.2 m thick and 2.5 m high on the grid lines between
//!   cells that have no passage, and all around the boundary. Square posts (0.2 × 0.2) stand at
//!   every grid vertex; a wall runs between two posts, so walls and posts only touch and never
//!   overlap. Faces that touch (a wall's ends against its posts, a post's side where a wall
//!   meets it, every bottom standing on the floor) are left out, and so are the faces turned
//!   away from the maze on the boundary, which nothing could see or light. Wall sides, tops and
//!   post faces face out of their solid.
//! - **Floor** at y = 0, facing up, only where nothing stands: each cell's 1.8 × 1.8 square and
//!   the 1.8 × 0.2 strip of each passage between two cells.
//! - **Lights**: `lights` (default 6) square lamps of 1.2 m hang 0.3 m below the wall tops over
//!   distinct cells picked by the same random sequence, facing down, one-sided, emission
//!   `light` (default 1) and reflectivity 0 (sources reflect little, as the paper notes in §4).
//!   The maze is open to the sky: light that leaves upwards is lost, so each lamp lights its
//!   own corridor directly and the rest of the maze only through bounces round the corners.
//!
//! Every surface is cut into patches of edge at most `size` (default 1 m): a wall side into
//! 2 × 3 patches, a cell floor into 2 × 2, a lamp into 2 × 2, the rest one patch across.
//!
//! Palette: limestone walls and posts (0.68, 0.63, 0.575), sandstone paving (0.55, 0.5, 0.42).
//!
//! Default (11 × 11 cells): 3364 patches (24 of them lamp; the paper has 3362) whatever the
//! seed, since a perfect maze on `n²` cells always has `n² − 1` passages, so the same number of
//! walls and exposed post faces; area-weighted mean reflectivity 0.5902, also for every seed.

use crate::LoadedScene;
use crate::error::GeomError;
use crate::mesh::{BoxFace, Facing, SceneBuilder};
use crate::scenes::camera::CameraPreset;
use crate::spec::{KeyValueParams, ParamDoc};
use radiosity_core::{Material, Real, Scene, Spectrum, Vec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// One line for scene listings.
pub const SUMMARY: &str = "the paper's labyrinth: a seeded perfect maze of stone walls on a floor, lamps, open sky";

/// Parameters.
pub const PARAMS: &[ParamDoc] = &[
    ParamDoc { key: "cells", default: "11", doc: "maze cells along each side, 1 to 100" },
    ParamDoc { key: "seed", default: "1998", doc: "seed of the maze layout and of the lamp positions" },
    ParamDoc { key: "size", default: "1", doc: "largest patch edge in metres, from 0.02 to 10" },
    ParamDoc {
        key: "lights",
        default: "6",
        doc: "number of lamps, each over its own cell, 1 to cells² (default at most cells²)",
    },
    ParamDoc { key: "light", default: "1", doc: "emission of the lamps, grey or r/g/b" },
];

/// Side of a cell, centre line to centre line of its walls.
const CELL: Real = 2.0;
/// Half the thickness of a wall (and half the side of a post).
const HALF: Real = 0.1;
/// Height of the walls.
const HEIGHT: Real = 2.5;
/// Side of a lamp.
const LAMP: Real = 1.2;
/// Height of the lamps, below the wall tops.
const LAMP_Y: Real = 2.2;
/// The default seed.
const SEED: u64 = 1998;

/// A perfect maze: which neighbouring cells are joined by a passage.
struct Maze {
    n: usize,
    /// `open_x[j * n + i]`: a passage between cells `(i, j)` and `(i + 1, j)`.
    open_x: Vec<bool>,
    /// `open_z[j * n + i]`: a passage between cells `(i, j)` and `(i, j + 1)`.
    open_z: Vec<bool>,
}

impl Maze {
    /// A randomised depth-first search from cell (0, 0).
    fn generate(n: usize, rng: &mut ChaCha8Rng) -> Maze {
        let mut maze = Maze { n, open_x: vec![false; n * n], open_z: vec![false; n * n] };
        let mut visited = vec![false; n * n];
        let mut stack = vec![(0, 0)];
        visited[0] = true;
        while let Some(&(i, j)) = stack.last() {
            let mut next = Vec::with_capacity(4);
            if i > 0 && !visited[j * n + i - 1] {
                next.push((i - 1, j));
            }
            if i + 1 < n && !visited[j * n + i + 1] {
                next.push((i + 1, j));
            }
            if j > 0 && !visited[(j - 1) * n + i] {
                next.push((i, j - 1));
            }
            if j + 1 < n && !visited[(j + 1) * n + i] {
                next.push((i, j + 1));
            }
            if next.is_empty() {
                stack.pop();
                continue;
            }
            let (a, b) = next[rng.random_range(0..next.len())];
            if a != i {
                maze.open_x[j * n + i.min(a)] = true;
            } else {
                maze.open_z[j.min(b) * n + i] = true;
            }
            visited[b * n + a] = true;
            stack.push((a, b));
        }
        maze
    }

    /// Whether the grid edge from vertex `(i, j)` to `(i + 1, j)` carries a wall.
    fn wall_along_x(&self, i: usize, j: usize) -> bool {
        j == 0 || j == self.n || !self.open_z[(j - 1) * self.n + i]
    }

    /// Whether the grid edge from vertex `(i, j)` to `(i, j + 1)` carries a wall.
    fn wall_along_z(&self, i: usize, j: usize) -> bool {
        i == 0 || i == self.n || !self.open_x[j * self.n + i - 1]
    }
}

/// The passages of the maze of `cells × cells` cells for `seed`, each as the pair of cells
/// `(i, j)` it joins (`i` along x, `j` along z), the lower cell first.
///
/// A perfect maze has exactly `cells² − 1` passages and joins every cell to every other.
pub fn passages(cells: usize, seed: u64) -> Vec<[(usize, usize); 2]> {
    let maze = Maze::generate(cells, &mut ChaCha8Rng::seed_from_u64(seed));
    let mut out = Vec::new();
    for j in 0..cells {
        for i in 0..cells {
            if maze.open_x[j * cells + i] {
                out.push([(i, j), (i + 1, j)]);
            }
            if maze.open_z[j * cells + i] {
                out.push([(i, j), (i, j + 1)]);
            }
        }
    }
    out
}

/// The coordinate of grid line `i`.
fn line(i: usize) -> Real {
    i as Real * CELL
}

/// Builds the scene.
pub fn build(name: &str, params: &KeyValueParams) -> Result<LoadedScene, GeomError> {
    let n = params.count("cells", 11, 1, 100)?;
    let seed = params.seed("seed", SEED)?;
    let size = params.real("size", 1.0, |v| (0.02..=10.0).contains(&v), "a patch size in metres from 0.02 to 10")?;
    let lights = params.count("lights", 6.min(n * n), 1, n * n)?;
    let light = params.spectrum("light", Spectrum::grey(1.0), |v| v >= 0.0, "an emission >= 0")?;

    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let maze = Maze::generate(n, &mut rng);
    // The lamps' cells: the first `lights` of a partial Fisher–Yates shuffle.
    let mut cells: Vec<usize> = (0..n * n).collect();
    for k in 0..lights {
        let pick = rng.random_range(k..cells.len());
        cells.swap(k, pick);
    }

    let mut b = SceneBuilder::new(name);
    let stone = b.material(Material::new("limestone", Spectrum::rgb(0.68, 0.63, 0.575), Spectrum::ZERO))?;
    let paving = b.material(Material::new("sandstone paving", Spectrum::rgb(0.55, 0.5, 0.42), Spectrum::ZERO))?;
    let lamp = b.material(Material::new("lamp", Spectrum::ZERO, light))?;
    let floor = b.object("floor");
    let outer = b.object("outer wall");
    let inner = b.object("inner walls");

    // Floor: each cell's free square, then the strip of each passage.
    let floor_rect = |b: &mut SceneBuilder, x0: Real, x1: Real, z0: Real, z1: Real| {
        let c = BoxFace::MaxY.corners(Vec3::new(x0, 0.0, z0), Vec3::new(x1, 0.0, z1));
        b.quad_sized(c, size, paving, floor)
    };
    for j in 0..n {
        for i in 0..n {
            floor_rect(&mut b, line(i) + HALF, line(i + 1) - HALF, line(j) + HALF, line(j + 1) - HALF)?;
        }
    }
    for j in 0..n {
        for i in 0..n {
            if i + 1 < n && maze.open_x[j * n + i] {
                floor_rect(&mut b, line(i + 1) - HALF, line(i + 1) + HALF, line(j) + HALF, line(j + 1) - HALF)?;
            }
            if j + 1 < n && maze.open_z[j * n + i] {
                floor_rect(&mut b, line(i) + HALF, line(i + 1) - HALF, line(j + 1) - HALF, line(j + 1) + HALF)?;
            }
        }
    }

    // Adds the listed faces of the box [lo, hi], facing out of it.
    let solid = |b: &mut SceneBuilder, lo: Vec3, hi: Vec3, faces: &[BoxFace], boundary: bool| {
        let object = if boundary { outer } else { inner };
        b.axis_box([lo, hi], faces, Facing::Outward, size, stone, object)
    };
    // Walls along x (on the line z = line(j)) and along z (on x = line(i)), between posts.
    for j in 0..=n {
        for i in 0..n {
            if maze.wall_along_x(i, j) {
                let lo = Vec3::new(line(i) + HALF, 0.0, line(j) - HALF);
                let hi = Vec3::new(line(i + 1) - HALF, HEIGHT, line(j) + HALF);
                let mut faces = vec![BoxFace::MaxY];
                faces.extend((j > 0).then_some(BoxFace::MinZ));
                faces.extend((j < n).then_some(BoxFace::MaxZ));
                solid(&mut b, lo, hi, &faces, j == 0 || j == n)?;
            }
        }
    }
    for i in 0..=n {
        for j in 0..n {
            if maze.wall_along_z(i, j) {
                let lo = Vec3::new(line(i) - HALF, 0.0, line(j) + HALF);
                let hi = Vec3::new(line(i) + HALF, HEIGHT, line(j + 1) - HALF);
                let mut faces = vec![BoxFace::MaxY];
                faces.extend((i > 0).then_some(BoxFace::MinX));
                faces.extend((i < n).then_some(BoxFace::MaxX));
                solid(&mut b, lo, hi, &faces, i == 0 || i == n)?;
            }
        }
    }
    // Posts at the grid vertices: the top, and each side facing into the maze with no wall.
    for j in 0..=n {
        for i in 0..=n {
            let lo = Vec3::new(line(i) - HALF, 0.0, line(j) - HALF);
            let hi = Vec3::new(line(i) + HALF, HEIGHT, line(j) + HALF);
            let mut faces = vec![BoxFace::MaxY];
            faces.extend((i > 0 && !maze.wall_along_x(i - 1, j)).then_some(BoxFace::MinX));
            faces.extend((i < n && !maze.wall_along_x(i, j)).then_some(BoxFace::MaxX));
            faces.extend((j > 0 && !maze.wall_along_z(i, j - 1)).then_some(BoxFace::MinZ));
            faces.extend((j < n && !maze.wall_along_z(i, j)).then_some(BoxFace::MaxZ));
            solid(&mut b, lo, hi, &faces, i == 0 || i == n || j == 0 || j == n)?;
        }
    }

    // Lamps: squares under the wall tops, centred over their cells, facing down.
    for (k, &cell) in cells[..lights].iter().enumerate() {
        let (i, j) = (cell % n, cell / n);
        let centre = Vec3::new(line(i) + 0.5 * CELL, LAMP_Y, line(j) + 0.5 * CELL);
        let half = Vec3::new(0.5 * LAMP, 0.0, 0.5 * LAMP);
        let object = b.object(format!("lamp {}", k + 1));
        b.quad_sized(BoxFace::MinY.corners(centre - half, centre + half), size, lamp, object)?;
    }
    Ok(LoadedScene { scene: b.build()?, warnings: Vec::new() })
}

/// The camera preset: the maze is open to the sky, so it is seen from above its front edge,
/// looking down at its middle (from the bounds of `scene`, whatever its size).
pub fn camera(scene: &Scene) -> CameraPreset {
    let v = Vec3::new;
    let (lo, hi) = scene.bounds();
    let (c, size) = ((lo + hi) * 0.5, (hi - lo).max_element());
    CameraPreset { eye: v(c.x, 0.8 * size, lo.z - 0.25 * size), target: v(c.x, 0.0, c.z), fov: 52.0 }
}
