//! The ASZ as the spec (§3) defines it and the paper's code computes it: one
//! arrival field per robot, each a second-order Fast Marching distance over
//! the free cells; the target's cells are those it reaches strictly before
//! every captor; a second march from the target, kept inside those cells,
//! leaves the part it reaches without crossing a captor-first cell.
//!
//! Per-robot fields keep open the narrow gaps between two captors' regions
//! that a single labelled march (`FastMarching::asz_cells`) closes, which
//! is where that march's |ASZ| and the reference's part (near capture).
//! They also make reuse possible: a field depends only on the map and its
//! robot's cell, so a robot that has not moved keeps its field, and the
//! planner's four candidate moves of one captor recompute only that
//! captor's field (`AszFields::with_moved_captor`).
//!
//! The update is the upwind second-order one of scikit-fmm (the reference's
//! library): along each axis the smaller settled neighbour v1, and where
//! the next cell beyond it is settled with v2 <= v1, the two-point
//! difference (3 d - 4 v1 + v2) / 2h; otherwise first order. A field's
//! distances are in metres from its robot's cell centre (where the
//! reference starts its march at zero), and a robot's arrival time is its
//! distance over its speed.

use super::{Lattice, Source};
use std::cmp::Ordering;
use std::collections::BinaryHeap;

const FAR: u8 = 0;
const TRIAL: u8 = 1;
const FROZEN: u8 = 2;
const WALL: u8 = 3;

/// A settled-or-not distance per padded cell; cells the march never
/// touched read infinite.
#[derive(Default)]
pub struct DistanceField {
    lattice_id: u64,
    stride: usize,
    /// The cell an unconfined march started from (padded index).
    origin: Option<usize>,
    distance: Vec<f64>,
    state: Vec<u8>,
    touched: Vec<u32>,
    heap: BinaryHeap<Entry>,
}

/// A heap entry: smaller distance first, then smaller cell, so the march
/// is the same whatever the heap's internal order.
#[derive(Clone, Copy, PartialEq)]
struct Entry {
    distance: f64,
    cell: u32,
}

impl Eq for Entry {}

impl Ord for Entry {
    fn cmp(&self, other: &Self) -> Ordering {
        other
            .distance
            .total_cmp(&self.distance)
            .then(other.cell.cmp(&self.cell))
    }
}

impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

/// 9/4: the weight of a two-point (second-order) difference.
const SECOND_ORDER: f64 = 2.25;

impl DistanceField {
    pub fn new() -> DistanceField {
        DistanceField::default()
    }

    /// Distance (m) at padded cell `cell`; infinite where the march did not
    /// reach.
    #[inline]
    pub fn at(&self, cell: usize) -> f64 {
        if self.state[cell] == FROZEN {
            self.distance[cell]
        } else {
            f64::INFINITY
        }
    }

    /// The padded cells this field settled.
    pub fn settled(&self) -> impl Iterator<Item = usize> + '_ {
        self.touched
            .iter()
            .map(|&c| c as usize)
            .filter(|&c| self.state[c] == FROZEN)
    }

    /// Whether the last march started at `cell` of `lattice` over every free
    /// cell: then this field can be kept as it is.
    pub fn is_from<L: Lattice + ?Sized>(&self, lattice: &L, cell: usize) -> bool {
        self.lattice_id == lattice.lattice_id() && self.origin == Some(cell)
    }

    fn prepare<L: Lattice + ?Sized>(&mut self, lattice: &L) {
        if self.lattice_id != lattice.lattice_id() {
            self.lattice_id = lattice.lattice_id();
            self.stride = lattice.stride();
            self.distance.clear();
            self.distance.resize(lattice.obstacle().len(), f64::INFINITY);
            self.state.clear();
            self.state
                .extend(lattice.obstacle().iter().map(|&o| if o == 0 { FAR } else { WALL }));
        } else {
            for &c in &self.touched {
                self.distance[c as usize] = f64::INFINITY;
                self.state[c as usize] = FAR;
            }
        }
        self.touched.clear();
        self.heap.clear();
        self.origin = None;
    }

    /// Marches from the free cell `start` (padded index) over every free
    /// cell, or over the cells `allowed` marks (indexed like the lattice's
    /// padded cells; `start` must be one of them).
    pub fn march<L: Lattice + ?Sized>(&mut self, lattice: &L, start: usize, allowed: Option<&[bool]>) {
        self.prepare(lattice);
        if self.state[start] == WALL || allowed.is_some_and(|a| !a[start]) {
            return;
        }
        self.origin = allowed.is_none().then_some(start);
        let h = lattice.cell_size();
        let s = self.stride;
        self.distance[start] = 0.0;
        self.state[start] = FROZEN;
        self.touched.push(start as u32);
        self.relax_around(start, h, allowed);
        while let Some(Entry { distance, cell }) = self.heap.pop() {
            let cell = cell as usize;
            if self.state[cell] != TRIAL || self.distance[cell] != distance {
                continue; // superseded by a later update
            }
            self.state[cell] = FROZEN;
            self.relax_around(cell, h, allowed);
            // A cell two steps away, across a settled neighbour, now has
            // this one as the far point of its two-point difference.
            for (near, far) in [
                (cell - 1, cell - 2),
                (cell + 1, cell + 2),
                (cell - s, cell - 2 * s),
                (cell + s, cell + 2 * s),
            ] {
                if self.state[near] == FROZEN && self.state[far] == TRIAL {
                    self.update(far, h);
                }
            }
        }
    }

    /// Offers the not-yet-settled neighbours of `cell` a new distance.
    #[inline]
    fn relax_around(&mut self, cell: usize, h: f64, allowed: Option<&[bool]>) {
        let s = self.stride;
        for nb in [cell - 1, cell + 1, cell - s, cell + s] {
            match self.state[nb] {
                FAR if allowed.is_none_or(|a| a[nb]) => {
                    if let Some(d) = self.solve(nb, h) {
                        self.state[nb] = TRIAL;
                        self.touched.push(nb as u32);
                        self.distance[nb] = d;
                        self.heap.push(Entry { distance: d, cell: nb as u32 });
                    }
                }
                TRIAL => self.update(nb, h),
                _ => {}
            }
        }
    }

    /// Recomputes a trial cell from its settled neighbours. The new value
    /// replaces the old one whichever is larger (a second-order stencil
    /// that gains its far point can raise it), as scikit-fmm does.
    #[inline]
    fn update(&mut self, cell: usize, h: f64) {
        if let Some(d) = self.solve(cell, h) {
            if d != self.distance[cell] {
                self.distance[cell] = d;
                self.heap.push(Entry { distance: d, cell: cell as u32 });
            }
        }
    }

    /// The upwind solution of |grad d| = 1 at `cell`: per axis, first order
    /// from the smaller settled neighbour, second order where the cell
    /// beyond it is settled and not larger. None where no real root exists.
    #[inline]
    fn solve(&self, cell: usize, h: f64) -> Option<f64> {
        let (mut a, mut b, mut c) = (0.0f64, 0.0f64, 0.0f64);
        for step in [1usize, self.stride] {
            let mut v1 = f64::INFINITY;
            let mut v2 = f64::INFINITY;
            // The two sides in the reference's order: backward, then forward.
            // v2 is kept from the backward side when the forward side wins
            // without a far point of its own, as the reference's loop does.
            for (near, far) in [(cell - step, cell - 2 * step), (cell + step, cell + 2 * step)] {
                if self.state[near] == FROZEN && self.distance[near] < v1 {
                    v1 = self.distance[near];
                    if self.state[far] == FROZEN && self.distance[far] <= v1 {
                        v2 = self.distance[far];
                    }
                }
            }
            if v2.is_finite() {
                let tp = (4.0 * v1 - v2) / 3.0;
                a += SECOND_ORDER;
                b -= 2.0 * SECOND_ORDER * tp;
                c += SECOND_ORDER * tp * tp;
            } else if v1.is_finite() {
                a += 1.0;
                b -= 2.0 * v1;
                c += v1 * v1;
            }
        }
        // In units of cells: a d^2 + b d + c = 1.
        let (b, c) = (b / h, c / (h * h) - 1.0);
        let det = b * b - 4.0 * a * c;
        (det > 0.0).then(|| (-b + det.sqrt()) / (2.0 * a) * h)
    }
}

/// Per-robot arrival fields and the ASZ they give, with their buffers. A
/// robot's field is kept while it stays in the same cell of the same map.
#[derive(Default)]
pub struct AszFields {
    /// Captor fields first, then the target's.
    fields: Vec<DistanceField>,
    /// A moved captor's field, for the planner's candidate moves.
    candidate: DistanceField,
    /// The target's second march, confined to its cells.
    confined: DistanceField,
    region: Vec<bool>,
    region_cells: Vec<u32>,
}

impl AszFields {
    pub fn new() -> AszFields {
        AszFields::default()
    }

    /// |ASZ| in cells: the target's connected part of the free cells it
    /// reaches strictly before every captor. 0 when the target stands on no
    /// free cell; captors on no free cell reach nothing.
    pub fn asz_cells<L: Lattice + ?Sized>(&mut self, lattice: &L, target: Source, captors: &[Source]) -> usize {
        let k = captors.len();
        self.fields.resize_with(k + 1, DistanceField::new);
        let Some((target_cell, _)) = lattice.locate(target.pos) else {
            return 0;
        };
        for (i, src) in captors.iter().chain(std::iter::once(&target)).enumerate() {
            refresh(&mut self.fields[i], lattice, src.pos);
        }
        let (captor_fields, target_field) = self.fields.split_at(k);
        let speeds: Vec<f64> = captors.iter().map(|c| c.speed).collect();
        count(
            lattice,
            &target_field[0],
            target.speed,
            target_cell,
            |cell| earliest(captor_fields.iter().zip(&speeds), cell),
            &mut self.region,
            &mut self.region_cells,
            &mut self.confined,
        )
    }

    /// |ASZ| in cells with captor `moved` at `pos` instead: the other
    /// robots' fields are those of the last `asz_cells` call with the same
    /// robots (call it first), only the moved captor's is marched.
    pub fn with_moved_captor<L: Lattice + ?Sized>(
        &mut self,
        lattice: &L,
        target: Source,
        captors: &[Source],
        moved: usize,
        pos: [f64; 2],
    ) -> usize {
        let k = captors.len();
        debug_assert_eq!(self.fields.len(), k + 1, "call asz_cells first");
        let Some((target_cell, _)) = lattice.locate(target.pos) else {
            return 0;
        };
        refresh(&mut self.candidate, lattice, pos);
        let candidate = &self.candidate;
        let (captor_fields, target_field) = self.fields.split_at(k);
        count(
            lattice,
            &target_field[0],
            target.speed,
            target_cell,
            |cell| {
                let mut best = f64::INFINITY;
                for (i, (field, src)) in captor_fields.iter().zip(captors).enumerate() {
                    let field = if i == moved { candidate } else { field };
                    best = best.min(field.at(cell) / src.speed);
                }
                best
            },
            &mut self.region,
            &mut self.region_cells,
            &mut self.confined,
        )
    }
}

/// Re-marches `field` unless it already starts from `pos`'s cell.
fn refresh<L: Lattice + ?Sized>(field: &mut DistanceField, lattice: &L, pos: [f64; 2]) {
    match lattice.locate(pos) {
        Some((cell, _)) if field.is_from(lattice, cell) => {}
        Some((cell, _)) => field.march(lattice, cell, None),
        // A robot on no free cell reaches nothing: an empty field.
        None => field.prepare(lattice),
    }
}

fn earliest<'a>(fields: impl Iterator<Item = (&'a DistanceField, &'a f64)>, cell: usize) -> f64 {
    fields.fold(f64::INFINITY, |best, (f, &speed)| best.min(f.at(cell) / speed))
}

/// The target's cells (its time strictly below `captor_time`), then its
/// second march confined to them, counting the cells it still reaches
/// strictly first.
#[allow(clippy::too_many_arguments)]
fn count<L: Lattice + ?Sized>(
    lattice: &L,
    target_field: &DistanceField,
    target_speed: f64,
    target_cell: usize,
    captor_time: impl Fn(usize) -> f64,
    region: &mut Vec<bool>,
    region_cells: &mut Vec<u32>,
    confined: &mut DistanceField,
) -> usize {
    let n = lattice.stride() * lattice.stride();
    region.resize(n, false);
    for &c in region_cells.iter() {
        region[c as usize] = false;
    }
    region_cells.clear();
    for cell in target_field.settled() {
        if target_field.at(cell) / target_speed < captor_time(cell) {
            region[cell] = true;
            region_cells.push(cell as u32);
        }
    }
    if !region[target_cell] {
        return 0;
    }
    confined.march(lattice, target_cell, Some(region));
    region_cells
        .iter()
        .map(|&c| c as usize)
        .filter(|&c| confined.at(c) / target_speed < captor_time(c))
        .count()
}
