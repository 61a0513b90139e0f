//! `office`: the paper's third scene, a furnished room lit by ceiling panels (few occlusions,
//! small patches).
//!
//! Rousselle & Renaud describe it only as "an office", 10991 patches, mean reflectivity 0.43,
//! whose patches are "very small as compared to the scene dimensions" and which "does not
//! include a large number of occlusions". Our reconstruction, in metres, y up:
//!
//! - **Room** `[0, 7.2] × [0, 2.7] × [0, 6.0]`, closed: floor, ceiling and four walls, facing
//!   inwards. The ceiling is a suspended grid of 12 × 10 tiles of 0.6 m; 8 of them (columns 1,
//!   4, 7, 10 of rows 2 and 7) are the **light panels**, emission `light` (default 1),
//!   reflectivity 0 (sources reflect little, as the paper notes in §4). A light is a ceiling
//!   tile with another material, so lights and ceiling never overlap.
//! - **Desks** (`desks`, default 9): a 3 × 3 array filled row by row from the front, each a 1.6 × 0.8 laminate top 30 mm thick
//!   at 0.74 m on four 50 mm metal legs, with a monitor (base, neck, screen) on it and a chair
//!   (seat on four legs, backrest standing on the seat) in front of it.
//! - **Bookcases**: three adjacent ones against the back wall (z = 6), each two side panels, a
//!   back panel, a plinth, four boards and a top, with rows of books on the boards.
//! - **Filing cabinets**: two against the right wall, a **whiteboard** on the front wall and a
//!   **door** on the left wall (each a thin box standing proud of its wall).
//!
//! All furniture is built of axis-aligned boxes whose faces face outwards. Coordinates are
//! whole millimetres, so contacts are exact: the boxes never interpenetrate, and where a box
//! face rests on the floor, stands against a wall or touches another box, the touching part of
//! both faces is left out (a face is cut into the rectangles that remain free). So no patch
//! lies inside a solid or coincides with another patch. Every rectangle is then cut into
//! patches of edge at most `size` (default 0.186 m, which gives the paper's patch count).
//!
//! Palette (RGB reflectivities, plausible for the materials): carpet (0.13, 0.15, 0.18),
//! wall paint (0.5, 0.472, 0.42), ceiling tiles (0.8, 0.8, 0.78), desk laminate (0.62, 0.5,
//! 0.36), metal (0.35, 0.36, 0.38), chair fabric (0.12, 0.16, 0.32), monitor plastic (0.06,
//! 0.06, 0.07), bookcase wood (0.5, 0.36, 0.22), books red/green/blue/cream, filing cabinets
//! (0.45, 0.46, 0.48), whiteboard (0.85, 0.85, 0.83), door (0.35, 0.24, 0.15).
//!
//! Default: 10 990 patches (128 of them light), area-weighted mean reflectivity 0.4300 (the
//! palette was tuned to it: dark carpet and a warm grey paint offset the white ceiling).
//!
//! **Storeys** (`floors`, default 1, 1 to 64): the furnished room repeated one above the
//! other, for scenes of many millions of patches (11 storeys at `size=0.0158` give
//! 10 519 509 patches). Storey `s` (0-based) is storey 0 moved up by `s` storey heights of
//! 3.0 m: the room's 2.7 m plus a 0.3 m concrete slab, whose lower face is the ceiling of the
//! storey below and whose upper face is the floor of the storey above. Each storey is thus a
//! closed room of its own and no light passes between storeys; the slab's edges, outside every
//! room, are not modelled. Every storey has exactly the patches of storey 0 (so `floors=N`
//! has N times the patches of `floors=1`), in the same order, with the same materials. The
//! first storey is the single room, unchanged (same patches, order and object names); the
//! objects of storey `s + 1` for `s ≥ 1` are named `storey {s + 1} ` followed by the name in
//! the first storey (`storey 2 desk 3`, `storey 2 floor`), and come after all objects of the
//! storey below.

use crate::LoadedScene;
use crate::error::GeomError;
use crate::mesh::{SceneBuilder, divisions};
use crate::scenes::camera::CameraPreset;
use crate::spec::{KeyValueParams, ParamDoc};
use radiosity_core::{Material, MaterialId, ObjectId, Real, Scene, Spectrum, Vec3};

/// One line for scene listings.
pub const SUMMARY: &str = "the paper's office: furnished room, ceiling light panels, few occlusions, small patches";

/// Parameters.
pub const PARAMS: &[ParamDoc] = &[
    ParamDoc {
        key: "size",
        default: "0.186",
        doc: "largest patch edge in metres, from 0.01 to 10 (0.0158 gives about a million patches)",
    },
    ParamDoc { key: "desks", default: "9", doc: "number of desks (each with monitor and chair), 0 to 9" },
    ParamDoc { key: "light", default: "1", doc: "emission of the ceiling panels, grey or r/g/b" },
    ParamDoc {
        key: "floors",
        default: "1",
        doc: "storeys stacked one above the other, 1 to 64, each a furnished room closed by 0.3 m slabs \
              (for large scenes: 11 at size=0.0158 give about 10.5 million patches)",
    },
];

/// Coordinates in whole millimetres: exact contacts between boxes.
type Mm = i32;

/// Room extent in millimetres along x, y (up) and z.
const ROOM: [Mm; 3] = [7200, 2700, 6000];
/// Storey height: the room's height plus a slab of 300 mm between storeys.
const STOREY: Mm = ROOM[1] + 300;
/// Side of a ceiling tile.
const TILE: Mm = 600;
/// Ceiling tile columns (along x) and rows (along z) that are light panels.
const LIGHT_COLUMNS: [Mm; 4] = [1, 4, 7, 10];
const LIGHT_ROWS: [Mm; 2] = [2, 7];

/// A rectangle `[u0, u1] × [v0, v1]` in the plane of a face.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Rect {
    u0: Mm,
    u1: Mm,
    v0: Mm,
    v1: Mm,
}

impl Rect {
    /// The overlap of two rectangles, if it has positive area.
    fn intersect(&self, o: &Rect) -> Option<Rect> {
        let r = Rect { u0: self.u0.max(o.u0), u1: self.u1.min(o.u1), v0: self.v0.max(o.v0), v1: self.v1.min(o.v1) };
        (r.u0 < r.u1 && r.v0 < r.v1).then_some(r)
    }
}

/// The two in-plane axes of a face normal to axis `k`, in cyclic order so that
/// `e_u × e_v = e_k`.
fn plane_axes(k: usize) -> (usize, usize) {
    ((k + 1) % 3, (k + 2) % 3)
}

/// An axis-aligned solid box of furniture.
#[derive(Clone, Copy, Debug)]
struct Part {
    lo: [Mm; 3],
    hi: [Mm; 3],
    material: MaterialId,
    object: ObjectId,
}

impl Part {
    /// The box's extent across axis `k`, as a rectangle in that plane's axes.
    fn section(&self, k: usize) -> Rect {
        let (u, v) = plane_axes(k);
        Rect { u0: self.lo[u], u1: self.hi[u], v0: self.lo[v], v1: self.hi[v] }
    }

    /// Whether the open interiors of two boxes overlap.
    fn overlaps(&self, o: &Part) -> bool {
        (0..3).all(|k| self.lo[k] < o.hi[k] && o.lo[k] < self.hi[k])
    }
}

/// The parts of `r` not covered by any of `holes`, as disjoint rectangles.
///
/// The rectangle is cut into slabs at every hole edge along u; each slab keeps the v intervals
/// no hole covers, and neighbouring slabs with the same intervals are merged back.
fn free_rects(r: Rect, holes: &[Rect]) -> Vec<Rect> {
    let holes: Vec<Rect> = holes.iter().filter_map(|h| h.intersect(&r)).collect();
    if holes.is_empty() {
        return vec![r];
    }
    let mut cuts: Vec<Mm> = vec![r.u0, r.u1];
    cuts.extend(holes.iter().flat_map(|h| [h.u0, h.u1]));
    cuts.sort_unstable();
    cuts.dedup();
    let mut out = Vec::new();
    let mut flush = |start: Mm, end: Mm, free: &[(Mm, Mm)]| {
        out.extend(free.iter().map(|&(v0, v1)| Rect { u0: start, u1: end, v0, v1 }));
    };
    let mut run: Option<(Mm, Vec<(Mm, Mm)>)> = None;
    for w in cuts.windows(2) {
        let (ua, ub) = (w[0], w[1]);
        let mut cover: Vec<(Mm, Mm)> =
            holes.iter().filter(|h| h.u0 <= ua && h.u1 >= ub).map(|h| (h.v0, h.v1)).collect();
        cover.sort_unstable();
        let mut free = Vec::new();
        let mut v = r.v0;
        for (c0, c1) in cover {
            if c0 > v {
                free.push((v, c0));
            }
            v = v.max(c1);
        }
        if v < r.v1 {
            free.push((v, r.v1));
        }
        match &run {
            Some((_, f)) if *f == free => {}
            _ => {
                if let Some((start, f)) = run.take() {
                    flush(start, ua, &f);
                }
                run = Some((ua, free));
            }
        }
    }
    if let Some((start, f)) = run {
        flush(start, r.u1, &f);
    }
    out
}

/// Metres from millimetres.
fn metres(x: Mm) -> Real {
    Real::from(x) / 1000.0
}

/// The point `i / n` of the way from `a` to `b`, exact at both ends.
fn lerp(a: Real, b: Real, i: usize, n: usize) -> Real {
    if i == n { b } else { a + (b - a) * (i as Real / n as Real) }
}

/// Adds the rectangle `r` of the plane `x_k = w`, facing `+k` when `positive`, cut into
/// patches of edge at most `size`, each moved up by `lift` metres.
///
/// The patches are cut in the storey's own frame and moved afterwards, so every storey is cut
/// alike and its vertices are the first storey's plus `lift` in y.
#[allow(clippy::too_many_arguments)]
fn emit_rect(
    b: &mut SceneBuilder,
    lift: Real,
    k: usize,
    w: Mm,
    positive: bool,
    r: Rect,
    size: Real,
    material: MaterialId,
    object: ObjectId,
) -> Result<(), GeomError> {
    let (ku, kv) = plane_axes(k);
    let (u0, u1, v0, v1) = (metres(r.u0), metres(r.u1), metres(r.v0), metres(r.v1));
    let (nu, nv) = (divisions(u1 - u0, size), divisions(v1 - v0, size));
    let point = |u: Real, v: Real| {
        let mut p = [0.0; 3];
        p[k] = metres(w);
        p[ku] = u;
        p[kv] = v;
        p[1] += lift;
        Vec3::from_array(p)
    };
    for j in 0..nv {
        let (va, vb) = (lerp(v0, v1, j, nv), lerp(v0, v1, j + 1, nv));
        for i in 0..nu {
            let (ua, ub) = (lerp(u0, u1, i, nu), lerp(u0, u1, i + 1, nu));
            let q = [point(ua, va), point(ub, va), point(ub, vb), point(ua, vb)];
            let q = if positive { q } else { [q[0], q[3], q[2], q[1]] };
            b.polygon(&q, material, object)?;
        }
    }
    Ok(())
}

/// The materials of the office.
struct Palette {
    carpet: MaterialId,
    paint: MaterialId,
    ceiling: MaterialId,
    light: MaterialId,
    laminate: MaterialId,
    metal: MaterialId,
    fabric: MaterialId,
    plastic: MaterialId,
    wood: MaterialId,
    books: [MaterialId; 4],
    cabinet: MaterialId,
    whiteboard: MaterialId,
    door: MaterialId,
}

impl Palette {
    fn new(b: &mut SceneBuilder, light: Spectrum) -> Result<Palette, GeomError> {
        let mut m = |name: &str, r: Real, g: Real, bl: Real| {
            b.material(Material::new(name, Spectrum::rgb(r, g, bl), Spectrum::ZERO))
        };
        let carpet = m("carpet", 0.13, 0.15, 0.18)?;
        let paint = m("wall paint", 0.5, 0.472, 0.42)?;
        let ceiling = m("ceiling tile", 0.8, 0.8, 0.78)?;
        let laminate = m("desk laminate", 0.62, 0.5, 0.36)?;
        let metal = m("metal", 0.35, 0.36, 0.38)?;
        let fabric = m("chair fabric", 0.12, 0.16, 0.32)?;
        let plastic = m("monitor plastic", 0.06, 0.06, 0.07)?;
        let wood = m("bookcase wood", 0.5, 0.36, 0.22)?;
        let books = [
            m("red books", 0.55, 0.12, 0.1)?,
            m("green books", 0.15, 0.4, 0.2)?,
            m("blue books", 0.12, 0.2, 0.5)?,
            m("cream books", 0.75, 0.7, 0.55)?,
        ];
        let cabinet = m("filing cabinet", 0.45, 0.46, 0.48)?;
        let whiteboard = m("whiteboard", 0.85, 0.85, 0.83)?;
        let door = m("door", 0.35, 0.24, 0.15)?;
        let light = b.material(Material::new("light panel", Spectrum::ZERO, light))?;
        Ok(Palette {
            carpet,
            paint,
            ceiling,
            light,
            laminate,
            metal,
            fabric,
            plastic,
            wood,
            books,
            cabinet,
            whiteboard,
            door,
        })
    }
}

/// Collects the furniture boxes.
struct Furniture<'a> {
    b: &'a mut SceneBuilder,
    /// What the storey's object names start with: empty on the first storey.
    prefix: &'a str,
    parts: Vec<Part>,
}

impl Furniture<'_> {
    /// Adds an object of this storey.
    fn object(&mut self, name: &str) -> ObjectId {
        self.b.object(format!("{}{name}", self.prefix))
    }

    fn part(&mut self, lo: [Mm; 3], hi: [Mm; 3], material: MaterialId, object: ObjectId) {
        debug_assert!((0..3).all(|k| lo[k] < hi[k]), "empty box {lo:?} {hi:?}");
        self.parts.push(Part { lo, hi, material, object });
    }

    /// A desk with its top's corner at `(x, z)`, its monitor and, in front (towards −z), its
    /// chair.
    fn desk(&mut self, n: usize, x: Mm, z: Mm, p: &Palette) {
        const TOP: Mm = 740;
        const THICK: Mm = 30;
        let desk = self.object(&format!("desk {n}"));
        self.part([x, TOP - THICK, z], [x + 1600, TOP, z + 800], p.laminate, desk);
        for (lx, lz) in [(x + 50, z + 50), (x + 1500, z + 50), (x + 50, z + 700), (x + 1500, z + 700)] {
            self.part([lx, 0, lz], [lx + 50, TOP - THICK, lz + 50], p.metal, desk);
        }
        let monitor = self.object(&format!("monitor {n}"));
        let cx = x + 800;
        self.part([cx - 110, TOP, z + 500], [cx + 110, TOP + 20, z + 680], p.plastic, monitor);
        self.part([cx - 30, TOP + 20, z + 580], [cx + 30, TOP + 160, z + 620], p.metal, monitor);
        self.part([cx - 280, TOP + 160, z + 580], [cx + 280, TOP + 500, z + 620], p.plastic, monitor);
        let chair = self.object(&format!("chair {n}"));
        const SEAT: Mm = 420;
        let (sx, sz) = (cx - 225, z - 550);
        self.part([sx, SEAT, sz], [sx + 450, SEAT + 50, sz + 450], p.fabric, chair);
        for (lx, lz) in [(sx, sz), (sx + 400, sz), (sx, sz + 400), (sx + 400, sz + 400)] {
            self.part([lx, 0, lz], [lx + 50, SEAT, lz + 50], p.metal, chair);
        }
        self.part([sx, SEAT + 50, sz], [sx + 450, SEAT + 480, sz + 50], p.fabric, chair);
    }

    /// A bookcase 0.9 m wide, 0.35 m deep and 2 m high from `x` along x, its back against the
    /// back wall, with rows of books.
    fn bookcase(&mut self, n: usize, x: Mm, p: &Palette) {
        const SIDE: Mm = 20;
        const BACK: Mm = 10;
        const HEIGHT: Mm = 2000;
        let back = ROOM[2];
        let front = back - 350;
        let case = self.object(&format!("bookcase {n}"));
        let (inner0, inner1) = (x + SIDE, x + 900 - SIDE);
        self.part([x, 0, front], [inner0, HEIGHT, back], p.wood, case);
        self.part([inner1, 0, front], [x + 900, HEIGHT, back], p.wood, case);
        self.part([inner0, 0, back - BACK], [inner1, HEIGHT, back], p.wood, case);
        // Plinth, four boards and the top, each spanning between the sides.
        let boards: [(Mm, Mm); 6] = [(0, 80), (440, 460), (820, 840), (1200, 1220), (1580, 1600), (1980, 2000)];
        for &(y0, y1) in &boards {
            self.part([inner0, y0, front], [inner1, y1, back - BACK], p.wood, case);
        }
        // Rows of books on the plinth and on each board below the top.
        let books = self.object(&format!("books {n}"));
        const WIDTHS: [Mm; 5] = [260, 180, 320, 220, 280];
        const HEIGHTS: [Mm; 5] = [240, 300, 270, 220, 290];
        for (row, &(_, floor)) in boards[..5].iter().enumerate() {
            let mut bx = inner0 + 20;
            for i in 0.. {
                let k = (n * 7 + row * 3 + i) % 5;
                let (width, height) = (WIDTHS[k], HEIGHTS[(k + row) % 5]);
                if bx + width > inner1 - 20 {
                    break;
                }
                let colour = p.books[(n + row + i) % 4];
                self.part([bx, floor, front + 40], [bx + width, floor + height, back - BACK - 40], colour, books);
                bx += width + 30;
            }
        }
    }
}

/// Builds the scene.
pub fn build(name: &str, params: &KeyValueParams) -> Result<LoadedScene, GeomError> {
    let size = params.real("size", 0.186, |v| (0.01..=10.0).contains(&v), "a patch size in metres from 0.01 to 10")?;
    let desks = params.count("desks", 9, 0, 9)?;
    let light = params.spectrum("light", Spectrum::grey(1.0), |v| v >= 0.0, "an emission >= 0")?;
    let floors = params.count("floors", 1, 1, 64)?;

    let mut b = SceneBuilder::new(name);
    let palette = Palette::new(&mut b, light)?;
    for storey in 0..floors {
        let prefix = if storey == 0 { String::new() } else { format!("storey {} ", storey + 1) };
        let lift = metres(STOREY * storey as Mm);
        build_storey(&mut b, &palette, &prefix, lift, size, desks)?;
    }
    Ok(LoadedScene { scene: b.build()?, warnings: Vec::new() })
}

/// Adds one furnished room, moved up by `lift` metres, its object names starting with
/// `prefix`.
fn build_storey(
    b: &mut SceneBuilder,
    p: &Palette,
    prefix: &str,
    lift: Real,
    size: Real,
    desks: usize,
) -> Result<(), GeomError> {
    // Room objects first, so their names come first.
    let mut f = Furniture { b, prefix, parts: Vec::new() };
    let floor = f.object("floor");
    let ceiling = f.object("ceiling");
    let walls = [f.object("left wall"), f.object("front wall"), f.object("right wall"), f.object("back wall")];

    for n in 0..desks {
        let (col, row) = (n % 3, n / 3);
        f.desk(n + 1, 600 + 2200 * col as Mm, 1000 + 1600 * row as Mm, p);
    }
    for n in 0..3 {
        f.bookcase(n + 1, 1200 + 900 * n as Mm, p);
    }
    for (n, z) in [4800, 5300].into_iter().enumerate() {
        let cabinet = f.object(&format!("filing cabinet {}", n + 1));
        f.part([ROOM[0] - 500, 0, z], [ROOM[0], 1300, z + 500], p.cabinet, cabinet);
    }
    let whiteboard = f.object("whiteboard");
    f.part([2400, 900, 0], [4800, 2100, 20], p.whiteboard, whiteboard);
    let door = f.object("door");
    f.part([0, 0, 600], [50, 2100, 1500], p.door, door);
    let Furniture { b, parts, .. } = f;

    debug_assert!(parts.iter().all(|q| (0..3).all(|k| 0 <= q.lo[k] && q.hi[k] <= ROOM[k])), "part outside the room");
    debug_assert!(
        parts.iter().enumerate().all(|(i, q)| parts[i + 1..].iter().all(|o| !q.overlaps(o))),
        "furniture boxes interpenetrate"
    );
    debug_assert!(parts.iter().all(|q| q.hi[1] < ROOM[1]), "furniture touches the ceiling");

    // Room surfaces, facing inwards, cut around the boxes that stand against them.
    let wall_of = [(0, false, walls[0]), (2, false, walls[1]), (0, true, walls[2]), (2, true, walls[3])];
    let room_faces = [(1, false, floor, p.carpet)].into_iter().chain(wall_of.map(|(k, far, o)| (k, far, o, p.paint)));
    for (k, far, object, material) in room_faces {
        let w = if far { ROOM[k] } else { 0 };
        let (u, v) = plane_axes(k);
        let whole = Rect { u0: 0, u1: ROOM[u], v0: 0, v1: ROOM[v] };
        let holes: Vec<Rect> =
            parts.iter().filter(|q| if far { q.hi[k] == w } else { q.lo[k] == 0 }).map(|q| q.section(k)).collect();
        for r in free_rects(whole, &holes) {
            emit_rect(b, lift, k, w, !far, r, size, material, object)?;
        }
    }
    // The ceiling: a grid of tiles, some of them light panels. Rows run along z, columns
    // along x; the ceiling's plane axes are (z, x).
    let mut lights = 0;
    for row in 0..ROOM[2] / TILE {
        for col in 0..ROOM[0] / TILE {
            let tile = Rect { u0: row * TILE, u1: (row + 1) * TILE, v0: col * TILE, v1: (col + 1) * TILE };
            let (material, object) = if LIGHT_ROWS.contains(&row) && LIGHT_COLUMNS.contains(&col) {
                lights += 1;
                (p.light, b.object(format!("{prefix}ceiling light {lights}")))
            } else {
                (p.ceiling, ceiling)
            };
            emit_rect(b, lift, 1, ROOM[1], false, tile, size, material, object)?;
        }
    }

    // Furniture: every face, less what rests on the floor, stands against a wall or touches
    // another box.
    for (i, q) in parts.iter().enumerate() {
        for (k, &extent) in ROOM.iter().enumerate() {
            for positive in [false, true] {
                let w = if positive { q.hi[k] } else { q.lo[k] };
                let against_room = if positive { w == extent } else { w == 0 };
                if against_room {
                    continue;
                }
                let holes: Vec<Rect> = parts
                    .iter()
                    .enumerate()
                    .filter(|&(j, o)| j != i && if positive { o.lo[k] == w } else { o.hi[k] == w })
                    .map(|(_, o)| o.section(k))
                    .collect();
                for r in free_rects(q.section(k), &holes) {
                    emit_rect(b, lift, k, w, positive, r, size, q.material, q.object)?;
                }
            }
        }
    }
    Ok(())
}

/// The camera preset: inside the room [0, 7.2] × [0, 2.7] × [0, 6], at eye height in the front
/// left corner, looking across the desks to the bookcases and filing cabinets.
pub fn camera(_scene: &Scene) -> CameraPreset {
    let v = Vec3::new;
    CameraPreset { eye: v(0.3, 1.7, 0.3), target: v(5.0, 0.9, 5.0), fov: 70.0 }
}
