//! Seeded generator of indoor floor plans in the working-grid format: a
//! 320x320-cell (16 m x 16 m) grid holding one house.
//!
//! How a plan is made:
//! 1. A house footprint (a rectangle, sized from a target traversable area
//!    drawn inside the requested class) is split recursively (BSP) into rooms;
//!    the first splits of a big house may leave a corridor strip between the
//!    halves. One corner room may be cut away to give an L-shaped house.
//! 2. Rooms that share enough wall become door candidates; a random spanning
//!    tree of them (corridors preferred) makes every room reachable, and a few
//!    extra doors close loops, so the target cannot always be cornered in a
//!    dead end. Some doors are narrow passages (0.55–0.7 m by default).
//! 3. Furniture blobs (blocks along walls, free-standing blocks, round
//!    tables) go inside rooms, never in front of a door and never where they
//!    would cut the robots' free space in two: after every blob the set of
//!    cells a robot of `robot_clearance_m` fits on must stay one piece.
//! 4. Only the largest 4-connected free component is kept.
//!
//! Because furniture and walls eat an unpredictable share of the footprint,
//! the footprint is rescaled from the measured area until the result lands
//! near the target; a layout that does not converge is replaced by a fresh
//! one drawn from the same seed, so `generate` is a pure function of
//! (seed, class, config).

use super::grid::{Grid, SizeClass, CELL_AREA, CELL_SIZE};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Cells per side of generated maps (16 m at 0.05 m, like the padded Gibson maps).
pub const GENERATED_SIDE: usize = 320;

/// Footprint rescalings tried on one layout before a new layout is drawn.
const RESCALES_PER_LAYOUT: usize = 4;
/// First guess of traversable area / footprint area (walls and furniture take the rest).
const INITIAL_FILL_RATIO: f64 = 0.78;

/// Knobs of the floor-plan generator. Lengths are in metres, areas in m^2;
/// `(lo, hi)` pairs are ranges drawn uniformly per map, room or door.
#[derive(Clone, Debug)]
pub struct GeneratorConfig {
    /// Target traversable area per class, in the order of `SizeClass::ALL`
    /// (small, medium, large). Kept away from the class thresholds so that
    /// the result falls well inside its class.
    pub target_area_m2: [(f64, f64); 3],
    /// A plan is accepted once its traversable area is within this of the target.
    pub area_tolerance_m2: f64,
    /// Layouts x rescalings tried before the closest plan of the right class is returned.
    pub max_attempts: usize,
    /// Width / height of the house footprint before any corner is cut away.
    pub aspect_ratio: (f64, f64),
    /// Obstacle kept between the house and the grid border.
    pub border_margin_m: f64,
    /// Thickness of interior walls (and the least thickness of exterior ones).
    pub wall_thickness_m: f64,
    /// A room whose area exceeds a value drawn from this range is split again.
    pub room_area_m2: (f64, f64),
    /// No room side (wall centre to wall centre) is shorter than this.
    pub min_room_side_m: f64,
    /// Chance that one of the first two splits of a big enough house leaves a corridor.
    pub corridor_probability: f64,
    /// Corridors are only laid out in parts of the house at least this big.
    pub corridor_min_split_area_m2: f64,
    /// Corridor width, wall centre to wall centre.
    pub corridor_width_m: (f64, f64),
    /// Chance that a corner room is removed, making the house L-shaped.
    pub cutout_probability: f64,
    /// Width of an ordinary door opening.
    pub door_width_m: (f64, f64),
    /// Width of a narrow passage (door opening a robot of radius 0.2 m just fits through).
    pub narrow_passage_width_m: (f64, f64),
    /// Share of doors that are narrow passages; every plan with a door has at least one.
    pub narrow_passage_fraction: f64,
    /// Doors added beyond the spanning tree, closing loops (fewer if the layout has no room for them).
    pub extra_doors: (usize, usize),
    /// Doors keep this far from the corner of the wall they are cut into.
    pub door_corner_margin_m: f64,
    /// Depth of the furniture-free zone in front of each side of a door.
    pub door_clearance_m: f64,
    /// Furniture pieces tried per m^2 of room floor (corridors stay empty).
    pub furniture_density: f64,
    /// Furniture covers at most this share of a room's floor.
    pub furniture_max_cover: f64,
    /// Side lengths of free-standing blocks (tables, beds, sofas).
    pub block_size_m: (f64, f64),
    /// Length along the wall of blocks standing against a wall (shelves, counters).
    pub wall_block_length_m: (f64, f64),
    /// Depth from the wall of blocks standing against a wall.
    pub wall_block_depth_m: (f64, f64),
    /// Radius of round furniture (tables, plants).
    pub disc_radius_m: (f64, f64),
    /// The free space stays connected for a robot whose centre keeps this far
    /// from obstacle cell centres (0.25 m: a 0.2 m robot plus the cells' half diagonal).
    pub robot_clearance_m: f64,
}

impl Default for GeneratorConfig {
    fn default() -> Self {
        GeneratorConfig {
            target_area_m2: [(22.0, 36.0), (44.0, 56.0), (64.0, 76.0)],
            area_tolerance_m2: 2.5,
            max_attempts: 32,
            aspect_ratio: (1.0, 1.6),
            border_margin_m: 0.5,
            wall_thickness_m: 0.15,
            room_area_m2: (9.0, 18.0),
            min_room_side_m: 2.2,
            corridor_probability: 0.6,
            corridor_min_split_area_m2: 36.0,
            corridor_width_m: (1.1, 1.5),
            cutout_probability: 0.35,
            door_width_m: (0.8, 1.0),
            narrow_passage_width_m: (0.55, 0.7),
            narrow_passage_fraction: 0.2,
            extra_doors: (1, 3),
            door_corner_margin_m: 0.15,
            door_clearance_m: 0.7,
            furniture_density: 0.32,
            furniture_max_cover: 0.25,
            block_size_m: (0.5, 1.4),
            wall_block_length_m: (0.6, 1.8),
            wall_block_depth_m: (0.4, 0.7),
            disc_radius_m: (0.2, 0.45),
            robot_clearance_m: 0.25,
        }
    }
}

impl GeneratorConfig {
    /// The range the target area of `class` is drawn from.
    pub fn target_range(&self, class: SizeClass) -> (f64, f64) {
        let i = SizeClass::ALL.iter().position(|&c| c == class).unwrap();
        self.target_area_m2[i]
    }
}

/// A half-open rectangle of cells: rows `r0..r1`, columns `c0..c1`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CellRect {
    pub r0: usize,
    pub c0: usize,
    pub r1: usize,
    pub c1: usize,
}

impl CellRect {
    pub fn height(&self) -> usize {
        self.r1.saturating_sub(self.r0)
    }

    pub fn width(&self) -> usize {
        self.c1.saturating_sub(self.c0)
    }

    pub fn cells(&self) -> usize {
        self.height() * self.width()
    }

    pub fn contains(&self, row: usize, col: usize) -> bool {
        (self.r0..self.r1).contains(&row) && (self.c0..self.c1).contains(&col)
    }

    pub fn intersects(&self, other: &CellRect) -> bool {
        self.r0 < other.r1 && other.r0 < self.r1 && self.c0 < other.c1 && other.c0 < self.c1
    }

    /// Grown by `rows` above and below and `cols` left and right (clipped at 0).
    fn grown(&self, rows: usize, cols: usize) -> CellRect {
        CellRect {
            r0: self.r0.saturating_sub(rows),
            c0: self.c0.saturating_sub(cols),
            r1: self.r1 + rows,
            c1: self.c1 + cols,
        }
    }

    fn iter(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        (self.r0..self.r1).flat_map(move |r| (self.c0..self.c1).map(move |c| (r, c)))
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RoomKind {
    Room,
    Corridor,
}

/// One cell of the house partition.
#[derive(Clone, Debug)]
pub struct Room {
    /// The partition cell, measured between wall centre lines.
    pub bounds: CellRect,
    /// The floor: `bounds` minus half a wall on every side.
    pub interior: CellRect,
    pub kind: RoomKind,
}

/// An opening cut through the wall between two rooms.
#[derive(Clone, Debug)]
pub struct Door {
    /// The wall cells made free.
    pub cells: CellRect,
    /// Indices into `FloorPlan::rooms`.
    pub rooms: (usize, usize),
    /// Clear width of the opening in metres.
    pub width_m: f64,
    /// A narrow passage rather than an ordinary door.
    pub narrow: bool,
    /// Furniture-free zone on both sides of the opening.
    pub keep_clear: CellRect,
}

/// A piece of furniture: obstacle cells inside a room.
#[derive(Clone, Debug, PartialEq)]
pub enum Furniture {
    Block(CellRect),
    /// Centre (row, col) and radius in cells, continuous: a cell is covered
    /// when its centre lies within the radius.
    Disc {
        row: f64,
        col: f64,
        radius: f64,
    },
}

impl Furniture {
    /// The cells the piece covers (clipped to the grid).
    pub fn cells(&self) -> Vec<(usize, usize)> {
        match *self {
            Furniture::Block(r) => r.iter().collect(),
            Furniture::Disc { row, col, radius } => {
                let b = self.bounding_box();
                b.iter()
                    .filter(|&(r, c)| {
                        let (dr, dc) = (r as f64 + 0.5 - row, c as f64 + 0.5 - col);
                        dr * dr + dc * dc <= radius * radius
                    })
                    .collect()
            }
        }
    }

    pub fn bounding_box(&self) -> CellRect {
        match *self {
            Furniture::Block(r) => r,
            Furniture::Disc { row, col, radius } => CellRect {
                r0: (row - radius).floor().max(0.0) as usize,
                c0: (col - radius).floor().max(0.0) as usize,
                r1: ((row + radius).ceil() as usize + 1).min(GENERATED_SIDE),
                c1: ((col + radius).ceil() as usize + 1).min(GENERATED_SIDE),
            },
        }
    }
}

/// A generated map with the layout it was drawn from.
#[derive(Clone, Debug)]
pub struct FloorPlan {
    pub grid: Grid,
    pub rooms: Vec<Room>,
    pub doors: Vec<Door>,
    pub furniture: Vec<Furniture>,
    /// The area (m^2) the generator aimed at.
    pub target_area_m2: f64,
    /// The attempt (counting layouts x rescalings) that produced this plan; 1 = the first.
    pub attempts: usize,
}

/// Generates the floor plan of a map of `class`; see the module doc.
pub fn generate(seed: u64, class: SizeClass, cfg: &GeneratorConfig) -> Grid {
    generate_plan(seed, class, cfg).grid
}

/// Like [`generate`], keeping the rooms, doors and furniture of the plan.
pub fn generate_plan(seed: u64, class: SizeClass, cfg: &GeneratorConfig) -> FloorPlan {
    let name = format!("gen-{class}-{seed}");
    // The master stream draws the target and one seed per layout, so every
    // layout of a map is reproducible from (seed, class).
    let mut master = ChaCha8Rng::seed_from_u64(seed ^ class_salt(class));
    let target = uniform(&mut master, cfg.target_range(class));
    let mut best: Option<FloorPlan> = None;
    let mut attempts = 0;
    let mut fill_ratio = INITIAL_FILL_RATIO;
    let mut layout_seed = master.gen::<u64>();
    while attempts < cfg.max_attempts.max(1) {
        if attempts > 0 && attempts % RESCALES_PER_LAYOUT == 0 {
            layout_seed = master.gen::<u64>();
            fill_ratio = INITIAL_FILL_RATIO;
        }
        attempts += 1;
        let footprint_m2 = target / fill_ratio;
        let Some(mut plan) = build_plan(&name, layout_seed, footprint_m2, cfg) else {
            // This layout cannot be made valid at any scale: draw another.
            attempts = attempts.div_ceil(RESCALES_PER_LAYOUT) * RESCALES_PER_LAYOUT;
            continue;
        };
        plan.target_area_m2 = target;
        plan.attempts = attempts;
        let area = plan.grid.area_m2();
        if (area - target).abs() <= cfg.area_tolerance_m2 && plan.grid.size_class() == class {
            return plan;
        }
        fill_ratio = (area / footprint_m2).clamp(0.3, 1.0);
        let closer = |p: &FloorPlan| {
            let key = |q: &FloorPlan| {
                (
                    q.grid.size_class() != class,
                    ((q.grid.area_m2() - target).abs() * 1e3) as u64,
                )
            };
            best.as_ref().is_none_or(|b| key(p) < key(b))
        };
        if closer(&plan) {
            best = Some(plan);
        }
    }
    // Not within tolerance after every attempt: the closest plan, preferring
    // the right class (with the default config this does not happen).
    best.unwrap_or_else(|| {
        // Every layout was invalid: fall back to a single empty room.
        let side = ((target / INITIAL_FILL_RATIO).sqrt() / CELL_SIZE) as usize;
        let mut grid = Grid::blocked(name, GENERATED_SIDE);
        let r0 = (GENERATED_SIDE - side.min(GENERATED_SIDE - 2)) / 2;
        let room = CellRect {
            r0,
            c0: r0,
            r1: r0 + side,
            c1: r0 + side,
        };
        room.iter().for_each(|(r, c)| grid.set_free(r, c, true));
        FloorPlan {
            grid,
            rooms: vec![Room {
                bounds: room,
                interior: room,
                kind: RoomKind::Room,
            }],
            doors: Vec::new(),
            furniture: Vec::new(),
            target_area_m2: target,
            attempts,
        }
    })
}

/// Makes the streams of equal seeds in different classes independent.
fn class_salt(class: SizeClass) -> u64 {
    match class {
        SizeClass::Small => 0x5EED_0001_u64.wrapping_mul(0x9E37_79B9_7F4A_7C15),
        SizeClass::Medium => 0x5EED_0002_u64.wrapping_mul(0x9E37_79B9_7F4A_7C15),
        SizeClass::Large => 0x5EED_0003_u64.wrapping_mul(0x9E37_79B9_7F4A_7C15),
    }
}

fn uniform(rng: &mut ChaCha8Rng, (lo, hi): (f64, f64)) -> f64 {
    if hi > lo {
        rng.gen_range(lo..hi)
    } else {
        lo
    }
}

/// Metres to a whole number of cells.
fn cells(m: f64) -> usize {
    (m / CELL_SIZE).round().max(0.0) as usize
}

/// Builds one plan on a footprint of about `footprint_m2`; None when the
/// layout cannot be made connected for a robot.
fn build_plan(
    name: &str,
    layout_seed: u64,
    footprint_m2: f64,
    cfg: &GeneratorConfig,
) -> Option<FloorPlan> {
    let mut rng = ChaCha8Rng::seed_from_u64(layout_seed);
    let side = GENERATED_SIDE;
    let footprint = place_footprint(footprint_m2, cfg, &mut rng);

    // Walls straddle partition lines: `lo` cells before the line, `hi` after.
    let wall = cells(cfg.wall_thickness_m).max(1);
    let (lo, hi) = (wall / 2, wall - wall / 2);

    let mut parts = Vec::new();
    split_bsp(footprint, 0, &mut rng, cfg, &mut parts);
    let mut rooms: Vec<Room> = parts
        .into_iter()
        .map(|(bounds, kind)| Room {
            bounds,
            interior: CellRect {
                r0: bounds.r0 + hi,
                c0: bounds.c0 + hi,
                r1: bounds.r1 - lo,
                c1: bounds.c1 - lo,
            },
            kind,
        })
        .collect();

    let door_max = cells(cfg.door_width_m.1.max(cfg.narrow_passage_width_m.1)).max(1);
    let corner = hi + cells(cfg.door_corner_margin_m);
    let mut candidates = door_candidates(&rooms, door_max, corner);

    if rooms.len() > 2 && rng.gen_bool(cfg.cutout_probability.clamp(0.0, 1.0)) {
        cut_corner_room(&mut rooms, &mut candidates, &footprint, &mut rng);
    }

    let chosen = choose_doors(&rooms, &candidates, cfg, &mut rng)?;
    let doors = place_doors(&chosen, &candidates, (lo, hi), cfg, &mut rng);
    let mut grid = carve_grid(name, side, &rooms, &doors);

    let mut space = RobotSpace::new(
        &grid,
        cells(cfg.robot_clearance_m).max(1),
        footprint.grown(1, 1),
    );
    if !space.is_connected(&space.ok.clone()) {
        return None;
    }

    let mut furniture = Vec::new();
    for room in rooms.iter().filter(|r| r.kind == RoomKind::Room) {
        furnish_room(
            room,
            &doors,
            cfg,
            &mut rng,
            &mut grid,
            &mut space,
            &mut furniture,
        );
    }
    grid.keep_largest_component();
    Some(FloorPlan {
        grid,
        rooms,
        doors,
        furniture,
        target_area_m2: 0.0,
        attempts: 0,
    })
}

/// The footprint's size and place are the layout's first draws; apart so
/// `build_plan` reads as the sequence of stages.
fn place_footprint(footprint_m2: f64, cfg: &GeneratorConfig, rng: &mut ChaCha8Rng) -> CellRect {
    let side = GENERATED_SIDE;
    let margin = cells(cfg.border_margin_m).clamp(1, side / 4);
    let max_side = side - 2 * margin;

    // Footprint rectangle, placed anywhere inside the margin.
    let aspect = uniform(rng, cfg.aspect_ratio);
    let long_m = (footprint_m2 * aspect).sqrt();
    let (mut h, mut w) = (
        cells(footprint_m2 / long_m).clamp(1, max_side),
        cells(long_m).clamp(1, max_side),
    );
    if rng.gen_bool(0.5) {
        std::mem::swap(&mut h, &mut w);
    }
    let r0 = margin + rng.gen_range(0..=max_side - h);
    let c0 = margin + rng.gen_range(0..=max_side - w);
    CellRect {
        r0,
        c0,
        r1: r0 + h,
        c1: c0 + w,
    }
}

/// Which candidate doors open: a spanning tree plus a few loop doors; `None`
/// when the rooms cannot all be joined, so the caller tries another seed.
fn choose_doors(
    rooms: &[Room],
    candidates: &[DoorCandidate],
    cfg: &GeneratorConfig,
    rng: &mut ChaCha8Rng,
) -> Option<Vec<usize>> {
    // Spanning tree by Kruskal on random weights, corridors first.
    let mut weighted: Vec<(f64, usize)> = candidates
        .iter()
        .enumerate()
        .map(|(k, cand)| {
            let corridor = rooms[cand.a].kind == RoomKind::Corridor
                || rooms[cand.b].kind == RoomKind::Corridor;
            (rng.gen::<f64>() + if corridor { 0.0 } else { 0.7 }, k)
        })
        .collect();
    weighted.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
    let mut sets = UnionFind::new(rooms.len());
    let mut chosen = Vec::new();
    let mut spare = Vec::new();
    for &(_, k) in &weighted {
        if sets.union(candidates[k].a, candidates[k].b) {
            chosen.push(k);
        } else {
            spare.push(k);
        }
    }
    if (0..rooms.len()).any(|i| sets.find(i) != sets.find(0)) {
        return None;
    }
    let extra = rng.gen_range(cfg.extra_doors.0..=cfg.extra_doors.1.max(cfg.extra_doors.0));
    for _ in 0..extra.min(spare.len()) {
        let pick = rng.gen_range(0..spare.len());
        chosen.push(spare.swap_remove(pick));
    }
    Some(chosen)
}

/// Widths and positions of the chosen doors, with the clear zone each keeps;
/// apart from the choice of doors because it is geometry, not topology.
fn place_doors(
    chosen: &[usize],
    candidates: &[DoorCandidate],
    (lo, hi): (usize, usize),
    cfg: &GeneratorConfig,
    rng: &mut ChaCha8Rng,
) -> Vec<Door> {
    // Door widths: some narrow passages, at least one when there is a door,
    // preferably on a loop door so that no room hangs on it alone.
    let mut narrow: Vec<bool> = chosen
        .iter()
        .map(|_| rng.gen_bool(cfg.narrow_passage_fraction.clamp(0.0, 1.0)))
        .collect();
    if !narrow.is_empty() && !narrow.iter().any(|&n| n) {
        let n = narrow.len();
        narrow[n - 1] = true; // extra doors come last
    }
    let clearance = cells(cfg.door_clearance_m);
    let keep_side = cells(0.15);
    let mut doors = Vec::new();
    for (&k, &is_narrow) in chosen.iter().zip(&narrow) {
        let cand = &candidates[k];
        let width_range = if is_narrow {
            cfg.narrow_passage_width_m
        } else {
            cfg.door_width_m
        };
        let width = cells(uniform(rng, width_range)).clamp(1, cand.span.1 - cand.span.0);
        let start = cand.span.0 + rng.gen_range(0..=cand.span.1 - cand.span.0 - width);
        let (cells_rect, keep_clear) = if cand.vertical {
            let r = CellRect {
                r0: start,
                r1: start + width,
                c0: cand.line - lo,
                c1: cand.line + hi,
            };
            (r, r.grown(keep_side, clearance))
        } else {
            let r = CellRect {
                r0: cand.line - lo,
                r1: cand.line + hi,
                c0: start,
                c1: start + width,
            };
            (r, r.grown(clearance, keep_side))
        };
        doors.push(Door {
            cells: cells_rect,
            rooms: (cand.a, cand.b),
            width_m: width as f64 * CELL_SIZE,
            narrow: is_narrow,
            keep_clear,
        });
    }
    doors
}

/// The blocked grid with room interiors and door openings freed; no draws.
fn carve_grid(name: &str, side: usize, rooms: &[Room], doors: &[Door]) -> Grid {
    let mut grid = Grid::blocked(name, side);
    for room in rooms {
        room.interior
            .iter()
            .for_each(|(r, c)| grid.set_free(r, c, true));
    }
    for door in doors {
        door.cells
            .iter()
            .for_each(|(r, c)| grid.set_free(r, c, true));
    }
    grid
}

/// Recursive binary split of `rect` into rooms (and corridors).
fn split_bsp(
    rect: CellRect,
    depth: usize,
    rng: &mut ChaCha8Rng,
    cfg: &GeneratorConfig,
    out: &mut Vec<(CellRect, RoomKind)>,
) {
    let min_side = cells(cfg.min_room_side_m);
    let area_m2 = rect.cells() as f64 * CELL_AREA;
    let max_area = uniform(rng, cfg.room_area_m2);
    let (h, w) = (rect.height(), rect.width());
    let long = h.max(w);
    if area_m2 <= max_area || long < 2 * min_side {
        out.push((rect, RoomKind::Room));
        return;
    }
    // Cut across the longer side; near-square parts either way.
    let across_rows = if h * 5 > w * 6 {
        true
    } else if w * 5 > h * 6 {
        false
    } else {
        rng.gen_bool(0.5)
    };
    let len = if across_rows { h } else { w };
    if len < 2 * min_side {
        out.push((rect, RoomKind::Room));
        return;
    }
    // Pieces along the cut axis: (start offset, end offset, kind).
    let cut = |a: usize, b: usize| -> CellRect {
        if across_rows {
            CellRect {
                r0: rect.r0 + a,
                r1: rect.r0 + b,
                ..rect
            }
        } else {
            CellRect {
                c0: rect.c0 + a,
                c1: rect.c0 + b,
                ..rect
            }
        }
    };
    let corridor_w = cells(uniform(rng, cfg.corridor_width_m));
    let corridor_roll = rng.gen_bool(cfg.corridor_probability.clamp(0.0, 1.0));
    if depth <= 1
        && corridor_roll
        && area_m2 >= cfg.corridor_min_split_area_m2
        && len >= 2 * min_side + corridor_w
    {
        let at = rng.gen_range(min_side..=len - min_side - corridor_w);
        split_bsp(cut(0, at), depth + 1, rng, cfg, out);
        out.push((cut(at, at + corridor_w), RoomKind::Corridor));
        split_bsp(cut(at + corridor_w, len), depth + 1, rng, cfg, out);
    } else {
        let lo = ((len as f64 * 0.35) as usize).max(min_side);
        let hi = ((len as f64 * 0.65) as usize).min(len - min_side).max(lo);
        let at = rng.gen_range(lo..=hi);
        split_bsp(cut(0, at), depth + 1, rng, cfg, out);
        split_bsp(cut(at, len), depth + 1, rng, cfg, out);
    }
}

/// Two rooms sharing a wall long enough for a door.
#[derive(Clone, Debug)]
struct DoorCandidate {
    a: usize,
    b: usize,
    /// The wall's partition line is a column boundary (rooms side by side).
    vertical: bool,
    /// Row (horizontal wall) or column (vertical wall) of the partition line.
    line: usize,
    /// Range along the wall where the opening may lie.
    span: (usize, usize),
}

fn door_candidates(rooms: &[Room], door_max: usize, corner: usize) -> Vec<DoorCandidate> {
    let mut out = Vec::new();
    for a in 0..rooms.len() {
        for b in a + 1..rooms.len() {
            let (p, q) = (rooms[a].bounds, rooms[b].bounds);
            let shared = if p.c1 == q.c0 || q.c1 == p.c0 {
                let line = if p.c1 == q.c0 { p.c1 } else { p.c0 };
                Some((true, line, p.r0.max(q.r0), p.r1.min(q.r1)))
            } else if p.r1 == q.r0 || q.r1 == p.r0 {
                let line = if p.r1 == q.r0 { p.r1 } else { p.r0 };
                Some((false, line, p.c0.max(q.c0), p.c1.min(q.c1)))
            } else {
                None
            };
            if let Some((vertical, line, s0, s1)) = shared {
                if s1 >= s0 + 2 * corner + door_max {
                    out.push(DoorCandidate {
                        a,
                        b,
                        vertical,
                        line,
                        span: (s0 + corner, s1 - corner),
                    });
                }
            }
        }
    }
    out
}

/// Removes one non-corridor room that fills a corner of the footprint, if the
/// others stay connected without it; keeps indices of the rest consistent.
fn cut_corner_room(
    rooms: &mut Vec<Room>,
    candidates: &mut Vec<DoorCandidate>,
    footprint: &CellRect,
    rng: &mut ChaCha8Rng,
) {
    let total: usize = rooms.iter().map(|r| r.bounds.cells()).sum();
    let corner_rooms: Vec<usize> = (0..rooms.len())
        .filter(|&i| {
            let b = rooms[i].bounds;
            let at_row_edge = b.r0 == footprint.r0 || b.r1 == footprint.r1;
            let at_col_edge = b.c0 == footprint.c0 || b.c1 == footprint.c1;
            rooms[i].kind == RoomKind::Room && at_row_edge && at_col_edge && b.cells() * 4 <= total
        })
        .filter(|&i| {
            let mut sets = UnionFind::new(rooms.len());
            for c in candidates.iter().filter(|c| c.a != i && c.b != i) {
                sets.union(c.a, c.b);
            }
            let root = sets.find(if i == 0 { 1 } else { 0 });
            (0..rooms.len()).all(|k| k == i || sets.find(k) == root)
        })
        .collect();
    if corner_rooms.is_empty() {
        return;
    }
    let gone = corner_rooms[rng.gen_range(0..corner_rooms.len())];
    rooms.remove(gone);
    candidates.retain(|c| c.a != gone && c.b != gone);
    for c in candidates.iter_mut() {
        c.a -= (c.a > gone) as usize;
        c.b -= (c.b > gone) as usize;
    }
}

/// Places furniture in one room, piece by piece, rejecting pieces that touch
/// a door's clear zone, exceed the room's cover budget or disconnect the robots' space.
fn furnish_room(
    room: &Room,
    doors: &[Door],
    cfg: &GeneratorConfig,
    rng: &mut ChaCha8Rng,
    grid: &mut Grid,
    space: &mut RobotSpace,
    furniture: &mut Vec<Furniture>,
) {
    let floor = room.interior;
    let floor_m2 = floor.cells() as f64 * CELL_AREA;
    let wanted = (cfg.furniture_density * floor_m2 * uniform(rng, (0.6, 1.4))).round() as usize;
    let budget = (cfg.furniture_max_cover * floor.cells() as f64) as usize;
    let mut covered = 0;
    let mut placed = 0;
    for _ in 0..wanted * 6 {
        if placed >= wanted {
            break;
        }
        let Some(piece) = random_piece(&floor, cfg, rng) else {
            continue;
        };
        let bbox = piece.bounding_box();
        if doors.iter().any(|d| d.keep_clear.intersects(&bbox)) {
            continue;
        }
        let piece_cells: Vec<(usize, usize)> = piece
            .cells()
            .into_iter()
            .filter(|&(r, c)| grid.is_free(r as isize, c as isize))
            .collect();
        if piece_cells.is_empty() || covered + piece_cells.len() > budget {
            continue;
        }
        let trial = space.without(&piece_cells);
        if !space.is_connected(&trial) {
            continue;
        }
        space.ok = trial;
        for &(r, c) in &piece_cells {
            grid.set_free(r, c, false);
        }
        covered += piece_cells.len();
        placed += 1;
        furniture.push(piece);
    }
}

/// One random piece of furniture lying on `floor`, or None if it does not fit.
fn random_piece(
    floor: &CellRect,
    cfg: &GeneratorConfig,
    rng: &mut ChaCha8Rng,
) -> Option<Furniture> {
    let (fh, fw) = (floor.height(), floor.width());
    let roll = rng.gen::<f64>();
    if roll < 0.5 {
        // Against one of the four walls.
        let along = cells(uniform(rng, cfg.wall_block_length_m)).max(1);
        let depth = cells(uniform(rng, cfg.wall_block_depth_m)).max(1);
        let side = rng.gen_range(0..4);
        let horizontal_wall = side < 2;
        let (run, deep) = if horizontal_wall { (fw, fh) } else { (fh, fw) };
        // Leave at least half the room's depth free in front of it.
        if along >= run || depth * 2 > deep {
            return None;
        }
        let s = rng.gen_range(0..=run - along);
        Some(Furniture::Block(match side {
            0 => CellRect {
                r0: floor.r0,
                r1: floor.r0 + depth,
                c0: floor.c0 + s,
                c1: floor.c0 + s + along,
            },
            1 => CellRect {
                r0: floor.r1 - depth,
                r1: floor.r1,
                c0: floor.c0 + s,
                c1: floor.c0 + s + along,
            },
            2 => CellRect {
                r0: floor.r0 + s,
                r1: floor.r0 + s + along,
                c0: floor.c0,
                c1: floor.c0 + depth,
            },
            _ => CellRect {
                r0: floor.r0 + s,
                r1: floor.r0 + s + along,
                c0: floor.c1 - depth,
                c1: floor.c1,
            },
        }))
    } else if roll < 0.8 {
        // Free-standing block.
        let bh = cells(uniform(rng, cfg.block_size_m)).max(1);
        let bw = cells(uniform(rng, cfg.block_size_m)).max(1);
        if bh >= fh || bw >= fw {
            return None;
        }
        let r0 = floor.r0 + rng.gen_range(0..=fh - bh);
        let c0 = floor.c0 + rng.gen_range(0..=fw - bw);
        Some(Furniture::Block(CellRect {
            r0,
            c0,
            r1: r0 + bh,
            c1: c0 + bw,
        }))
    } else {
        let radius = uniform(rng, cfg.disc_radius_m) / CELL_SIZE;
        let d = (2.0 * radius).ceil() as usize + 1;
        if d >= fh || d >= fw {
            return None;
        }
        let row = floor.r0 as f64 + radius + rng.gen_range(0.0..(fh as f64 - 2.0 * radius));
        let col = floor.c0 as f64 + radius + rng.gen_range(0.0..(fw as f64 - 2.0 * radius));
        Some(Furniture::Disc { row, col, radius })
    }
}

/// The cells a robot's centre may occupy: free cells with no obstacle cell
/// centre closer than `radius` cells. Kept up to date as furniture is added,
/// to test that every piece leaves this space in one piece.
struct RobotSpace {
    ok: Vec<bool>,
    side: usize,
    /// Offsets (dr, dc) with dr^2 + dc^2 < radius^2.
    disc: Vec<(isize, isize)>,
    /// Flood fills stay in here (the house and its walls).
    bounds: CellRect,
}

impl RobotSpace {
    fn new(grid: &Grid, radius: usize, bounds: CellRect) -> RobotSpace {
        let rad = radius as isize;
        let disc = (-rad..=rad)
            .flat_map(|dr| (-rad..=rad).map(move |dc| (dr, dc)))
            .filter(|&(dr, dc)| dr * dr + dc * dc < rad * rad)
            .collect();
        let side = grid.side();
        let bounds = CellRect {
            r1: bounds.r1.min(side),
            c1: bounds.c1.min(side),
            ..bounds
        };
        let mut space = RobotSpace {
            ok: grid.free_mask().to_vec(),
            side,
            disc,
            bounds,
        };
        // Only obstacle cells next to free space can be the nearest obstacle.
        let edge: Vec<(usize, usize)> = bounds
            .iter()
            .filter(|&(r, c)| {
                let (r, c) = (r as isize, c as isize);
                !grid.is_free(r, c)
                    && [(0, 1), (0, -1), (1, 0), (-1, 0)]
                        .iter()
                        .any(|&(dr, dc)| grid.is_free(r + dr, c + dc))
            })
            .collect();
        let mut ok = std::mem::take(&mut space.ok);
        space.clear_around(&mut ok, &edge);
        space.ok = ok;
        space
    }

    fn clear_around(&self, ok: &mut [bool], cells: &[(usize, usize)]) {
        let n = self.side as isize;
        for &(r, c) in cells {
            for &(dr, dc) in &self.disc {
                let (rr, cc) = (r as isize + dr, c as isize + dc);
                if rr >= 0 && cc >= 0 && rr < n && cc < n {
                    ok[(rr * n + cc) as usize] = false;
                }
            }
        }
    }

    /// The space once `cells` become obstacle.
    fn without(&self, cells: &[(usize, usize)]) -> Vec<bool> {
        let mut ok = self.ok.clone();
        self.clear_around(&mut ok, cells);
        ok
    }

    /// Is `ok` (non-empty and) one 4-connected piece?
    fn is_connected(&self, ok: &[bool]) -> bool {
        let n = self.side;
        let b = self.bounds;
        let mut in_bounds = b.iter().filter(|&(r, c)| ok[r * n + c]);
        let Some((r, c)) = in_bounds.next() else {
            return false;
        };
        let total = 1 + in_bounds.count();
        let mut seen = vec![false; n * n];
        let mut stack = vec![r * n + c];
        seen[r * n + c] = true;
        let mut reached = 0;
        while let Some(i) = stack.pop() {
            reached += 1;
            let (r, c) = (i / n, i % n);
            let mut visit = |j: usize| {
                if ok[j] && !seen[j] {
                    seen[j] = true;
                    stack.push(j);
                }
            };
            if r > b.r0 {
                visit(i - n);
            }
            if r + 1 < b.r1 {
                visit(i + n);
            }
            if c > b.c0 {
                visit(i - 1);
            }
            if c + 1 < b.c1 {
                visit(i + 1);
            }
        }
        reached == total
    }
}

struct UnionFind {
    parent: Vec<usize>,
}

impl UnionFind {
    fn new(n: usize) -> UnionFind {
        UnionFind {
            parent: (0..n).collect(),
        }
    }

    fn find(&mut self, mut x: usize) -> usize {
        while self.parent[x] != x {
            self.parent[x] = self.parent[self.parent[x]];
            x = self.parent[x];
        }
        x
    }

    /// Joins the sets of a and b; false if they were already one.
    fn union(&mut self, a: usize, b: usize) -> bool {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra == rb {
            return false;
        }
        self.parent[ra] = rb;
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::PreparedMap;

    fn plan(seed: u64, class: SizeClass) -> FloorPlan {
        generate_plan(seed, class, &GeneratorConfig::default())
    }

    /// Number of 4-connected free components (flood fill from each unlabelled free cell).
    fn components(grid: &Grid) -> usize {
        let n = grid.side();
        let mut seen = vec![false; n * n];
        let mut count = 0;
        for start in 0..n * n {
            if seen[start] || !grid.free_mask()[start] {
                continue;
            }
            count += 1;
            seen[start] = true;
            let mut stack = vec![start];
            while let Some(i) = stack.pop() {
                let (r, c) = ((i / n) as isize, (i % n) as isize);
                for (rr, cc) in [(r - 1, c), (r + 1, c), (r, c - 1), (r, c + 1)] {
                    let j = rr * n as isize + cc;
                    if grid.is_free(rr, cc) && !seen[j as usize] {
                        seen[j as usize] = true;
                        stack.push(j as usize);
                    }
                }
            }
        }
        count
    }

    #[test]
    fn generated_maps_hit_their_class_and_target() {
        for class in SizeClass::ALL {
            let (lo, hi) = GeneratorConfig::default().target_range(class);
            for seed in 0..6 {
                let p = plan(seed, class);
                let area = p.grid.area_m2();
                assert_eq!(p.grid.size_class(), class, "seed {seed}: {area:.2} m^2");
                assert!(
                    area > lo - 3.0 && area < hi + 3.0,
                    "{class} seed {seed}: {area:.2} m^2 far from {lo}..{hi}"
                );
                assert_eq!(p.grid.name, format!("gen-{class}-{seed}"));
                assert_eq!(p.grid.side(), GENERATED_SIDE);
            }
        }
    }

    #[test]
    fn same_seed_same_map_other_seed_other_map() {
        let cfg = GeneratorConfig::default();
        for class in SizeClass::ALL {
            let a = generate(7, class, &cfg);
            assert_eq!(a, generate(7, class, &cfg));
            let b = generate(8, class, &cfg);
            assert_ne!(a.free_mask(), b.free_mask());
        }
        // Same seed, different class: different maps too.
        assert_ne!(
            generate(7, SizeClass::Small, &cfg).free_mask(),
            generate(7, SizeClass::Large, &cfg).free_mask()
        );
    }

    #[test]
    fn maps_are_one_component_with_room_to_spawn() {
        for class in SizeClass::ALL {
            for seed in [1, 2] {
                let g = generate(seed, class, &GeneratorConfig::default());
                assert_eq!(components(&g), 1, "{class} seed {seed}");
                let spawn = PreparedMap::new(g).spawn_cells.len();
                assert!(
                    spawn >= 500,
                    "{class} seed {seed}: only {spawn} spawn cells"
                );
            }
        }
    }

    #[test]
    fn components_counts_pieces() {
        let mut g = Grid::blocked("t", 20);
        g.set_free(1, 1, true);
        g.set_free(1, 2, true);
        g.set_free(5, 5, true);
        g.set_free(9, 9, true);
        assert_eq!(components(&g), 3);
    }

    #[test]
    fn rooms_hold_furniture_but_doors_stay_clear() {
        for class in SizeClass::ALL {
            for seed in 0..4 {
                let p = plan(seed, class);
                let g = &p.grid;
                assert!(!p.furniture.is_empty(), "{class} seed {seed}: no furniture");
                // Checked on the grid alone: obstacle cells on room floors
                // (strictly inside the walls) are furniture.
                let on_floors = p
                    .rooms
                    .iter()
                    .flat_map(|room| room.interior.iter())
                    .filter(|&(r, c)| !g.is_free(r as isize, c as isize))
                    .count();
                assert!(
                    on_floors >= 50,
                    "{class} seed {seed}: {on_floors} furniture cells"
                );
                for piece in &p.furniture {
                    let inside = p.rooms.iter().any(|room| {
                        room.kind == RoomKind::Room
                            && piece
                                .cells()
                                .iter()
                                .all(|&(r, c)| room.interior.contains(r, c))
                    });
                    assert!(
                        inside,
                        "{class} seed {seed}: {piece:?} is not on one room's floor"
                    );
                    assert!(p
                        .doors
                        .iter()
                        .all(|d| !d.keep_clear.intersects(&piece.bounding_box())));
                }
                for door in &p.doors {
                    assert!(
                        door.cells
                            .iter()
                            .all(|(r, c)| g.is_free(r as isize, c as isize)),
                        "{door:?} blocked"
                    );
                }
            }
        }
    }

    #[test]
    fn plans_have_doors_loops_and_narrow_passages() {
        let mut loops = 0;
        for class in SizeClass::ALL {
            for seed in 0..4 {
                let p = plan(seed, class);
                assert!(p.rooms.len() >= 2, "{class} seed {seed}: one room");
                assert!(p.doors.len() >= p.rooms.len() - 1);
                loops += (p.doors.len() >= p.rooms.len()) as usize;
                let narrow = p.doors.iter().filter(|d| d.narrow).collect::<Vec<_>>();
                assert!(!narrow.is_empty(), "{class} seed {seed}: no narrow passage");
                for d in narrow {
                    assert!((0.5..=0.75).contains(&d.width_m), "{d:?}");
                }
            }
        }
        assert!(loops >= 6, "only {loops} of 12 plans have a loop");
    }

    #[test]
    fn generator_never_panics_and_stays_in_class() {
        let cfg = GeneratorConfig::default();
        for class in SizeClass::ALL {
            for seed in 100..130 {
                let g = generate(seed, class, &cfg);
                assert_eq!(
                    g.size_class(),
                    class,
                    "{class} seed {seed}: {:.2} m^2",
                    g.area_m2()
                );
            }
        }
    }
}
