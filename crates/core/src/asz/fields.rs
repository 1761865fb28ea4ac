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

use super::field_queue::FieldQueue;
use super::march::{Lattice, Source};

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
    /// That cell's (row, column) in the padded grid.
    origin_at: [f64; 2],
    distance: Vec<f64>,
    state: Vec<u8>,
    touched: Vec<u32>,
    queue: FieldQueue,
    cell_size: f64,
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
            self.distance
                .resize(lattice.obstacle().len(), f64::INFINITY);
            self.state.clear();
            self.state.extend(
                lattice
                    .obstacle()
                    .iter()
                    .map(|&o| if o == 0 { FAR } else { WALL }),
            );
        } else {
            for &c in &self.touched {
                self.distance[c as usize] = f64::INFINITY;
                self.state[c as usize] = FAR;
            }
        }
        self.touched.clear();
        self.queue.reset(lattice.cell_size());
        self.origin = None;
    }

    /// Marches from the free cell `start` (padded index) over every free
    /// cell, or over the cells `allowed` marks (indexed like the lattice's
    /// padded cells; `start` must be one of them).
    pub fn march<L: Lattice + ?Sized>(
        &mut self,
        lattice: &L,
        start: usize,
        allowed: Option<&[bool]>,
    ) {
        self.start(lattice, start, allowed);
        while self.step(f64::INFINITY, allowed).is_some() {}
    }

    /// Starts a march from `start` and settles that cell alone; `step`
    /// settles the next ones. A march stopped part way has settled exactly
    /// the cells a whole march settles first, with the same distances.
    pub fn start<L: Lattice + ?Sized>(
        &mut self,
        lattice: &L,
        start: usize,
        allowed: Option<&[bool]>,
    ) {
        self.prepare(lattice);
        if self.state[start] == WALL || allowed.is_some_and(|a| !a[start]) {
            return;
        }
        self.origin = allowed.is_none().then_some(start);
        self.origin_at = grid_at(start, self.stride);
        self.cell_size = lattice.cell_size();
        self.distance[start] = 0.0;
        self.state[start] = FROZEN;
        self.touched.push(start as u32);
        self.relax_around(start, self.cell_size, allowed);
    }

    /// Settles the next cell if its distance is at most `limit`; returns it.
    pub fn step(&mut self, limit: f64, allowed: Option<&[bool]>) -> Option<usize> {
        let h = self.cell_size;
        let s = self.stride;
        loop {
            let (state, field) = (&self.state, &self.distance);
            let (distance, cell) = self
                .queue
                .peek(|c| (state[c as usize] == TRIAL).then(|| field[c as usize]))?;
            let cell = cell as usize;
            if self.state[cell] != TRIAL || self.distance[cell] != distance {
                self.queue.take();
                continue; // superseded by a later update
            }
            if distance > limit {
                return None;
            }
            self.queue.take();
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
            return Some(cell);
        }
    }

    /// Whether the cell at `at` (`grid_at`) lies so far from this field's
    /// origin in a straight line that its distance must exceed `limit`.
    #[inline]
    fn beyond(&self, at: [f64; 2], limit: f64) -> bool {
        if self.origin.is_none() {
            return false;
        }
        let dr = at[0] - self.origin_at[0];
        let dc = at[1] - self.origin_at[1];
        let reach = (limit / self.cell_size + 2.0) / 0.97;
        dr * dr + dc * dc > reach * reach
    }

    /// Settles every cell of distance at most `limit`.
    pub fn advance(&mut self, limit: f64) {
        while self.step(limit, None).is_some() {}
    }

    /// Offers the not-yet-settled neighbours of `cell` a new distance.
    #[inline]
    fn relax_around(&mut self, cell: usize, h: f64, allowed: Option<&[bool]>) {
        let s = self.stride;
        let nbs = [cell - 1, cell + 1, cell - s, cell + s];
        // Solving touches only settled cells, so the four solves are
        // independent: all four first, then their offers.
        let mut solved = [None; 4];
        for k in 0..4 {
            let nb = nbs[k];
            let open = match self.state[nb] {
                FAR => allowed.is_none_or(|a| a[nb]),
                TRIAL => true,
                _ => false,
            };
            if open {
                solved[k] = self.solve(nb, h);
            }
        }
        for k in 0..4 {
            let Some(d) = solved[k] else { continue };
            let nb = nbs[k];
            if self.state[nb] == FAR {
                self.state[nb] = TRIAL;
                self.touched.push(nb as u32);
                self.distance[nb] = d;
                self.queue.push(nb as u32, d);
            } else if d != self.distance[nb] {
                self.distance[nb] = d;
                self.queue.push(nb as u32, d);
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
                self.queue.push(cell as u32, d);
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
            for (near, far) in [
                (cell - step, cell - 2 * step),
                (cell + step, cell + 2 * step),
            ] {
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
///
/// Each field is marched only as far as the answer needs: the target's
/// cells are found in the order of its arrival time, each settled against
/// the captors' fields marched up to that time, and a march stopped part
/// way holds exactly the first cells of the whole march, with the same
/// distances. So the count is that of whole fields, at the cost of the
/// fields up to the time the target's region closes.
#[derive(Default)]
pub struct AszFields {
    /// Captor fields first, then the target's.
    fields: Vec<DistanceField>,
    /// A moved captor's field (`with_moved_captor`), apart from the one of
    /// its own cell.
    candidate: DistanceField,
    /// The target's second march, confined to its cells.
    confined: DistanceField,
    search: RegionSearch,
    /// The captors' speeds of the last call.
    captor_speeds: Vec<f64>,
    /// The counts made since the robots' own cells last changed: a count
    /// depends only on the robots' cells and speeds, and the planner's
    /// moves often land two robots' configurations on the same cells (a
    /// move that stays in its cell, two turns that end in one cell).
    counts: Vec<(CountKey, usize)>,
    /// The robots' own cells those counts were made beside.
    counts_base: Option<CountKey>,
}

/// The most counts kept beside one set of own cells: the planner's 12
/// moves (3 captors) and the state itself; a caller trying more moves
/// loses the oldest.
const COUNTS_KEPT: usize = 16;

/// The cells (None off the free cells) and speeds of the robots of one
/// count, captors first, on one lattice.
#[derive(Clone, PartialEq)]
struct CountKey {
    lattice: u64,
    robots: Vec<(Option<usize>, u64)>,
}

impl CountKey {
    fn new<L: Lattice + ?Sized>(lattice: &L, target: Source, captors: &[Source]) -> CountKey {
        CountKey {
            lattice: lattice.lattice_id(),
            robots: captors
                .iter()
                .chain(std::iter::once(&target))
                .map(|s| (lattice.locate(s.pos).map(|(c, _)| c), s.speed.to_bits()))
                .collect(),
        }
    }
}

/// The buffers of the search for the target's region.
#[derive(Default)]
struct RegionSearch {
    /// Per padded cell: in the target's region.
    region: Vec<bool>,
    region_cells: Vec<u32>,
    /// Per padded cell: offered to the search already.
    seen: Vec<bool>,
    seen_cells: Vec<u32>,
    /// Cells offered before the target's field settled them.
    waiting: Vec<bool>,
    waiting_count: usize,
    candidates: std::collections::BinaryHeap<Candidate>,
    /// The ASZ's cells of the last call.
    asz: Vec<u32>,
    /// The region the confined march last ran in, in the order the search
    /// found it (the order is a function of the region and the target's
    /// field): a planner's move that leaves the region as it was keeps
    /// that march.
    confined_region: Vec<u32>,
    confined_lattice: u64,
}

/// A cell to settle, smallest target time first, then smallest index.
#[derive(Clone, Copy, PartialEq)]
struct Candidate {
    distance: f64,
    cell: u32,
}

impl Eq for Candidate {}

impl Ord for Candidate {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        other
            .distance
            .total_cmp(&self.distance)
            .then(other.cell.cmp(&self.cell))
    }
}

impl PartialOrd for Candidate {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl AszFields {
    pub fn new() -> AszFields {
        AszFields::default()
    }

    /// |ASZ| in cells: the target's connected part of the free cells it
    /// reaches strictly before every captor, then only those its march
    /// inside that part still reaches first (the reference's second pass).
    /// 0 when the target stands on no free cell; a captor on no free cell
    /// reaches nothing.
    pub fn asz_cells<L: Lattice + ?Sized>(
        &mut self,
        lattice: &L,
        target: Source,
        captors: &[Source],
    ) -> usize {
        self.count(lattice, target, captors, None)
    }

    /// After `asz_cells`: every cell some robot's field settled, with the
    /// robot it belongs to: the target (label K) on the ASZ's cells,
    /// elsewhere the captor that arrives first (ties to the lower index).
    /// For drawing: the whole fields are marched first.
    pub fn regions(&mut self) -> Vec<(usize, u8)> {
        let k = self.captor_speeds.len();
        for field in &mut self.fields[..k] {
            field.advance(f64::INFINITY);
        }
        let asz = &self.search.asz;
        let mut out: Vec<(usize, u8)> = asz.iter().map(|&c| (c as usize, k as u8)).collect();
        let in_asz: std::collections::HashSet<u32> = asz.iter().copied().collect();
        let mut seen = std::collections::HashSet::new();
        for field in &self.fields[..k] {
            for cell in field.settled() {
                if in_asz.contains(&(cell as u32)) || !seen.insert(cell) {
                    continue;
                }
                let (mut best, mut label) = (f64::INFINITY, 0u8);
                for (i, (f, &v)) in self.fields[..k].iter().zip(&self.captor_speeds).enumerate() {
                    let t = f.at(cell) / v;
                    if t < best {
                        (best, label) = (t, i as u8);
                    }
                }
                out.push((cell, label));
            }
        }
        out
    }

    /// |ASZ| in cells with captor `moved` at `pos` instead. Its field is
    /// marched apart, so the fields of the robots' own cells are kept for
    /// the next call: the planner's four moves of one captor march one
    /// field each.
    pub fn with_moved_captor<L: Lattice + ?Sized>(
        &mut self,
        lattice: &L,
        target: Source,
        captors: &[Source],
        moved: usize,
        pos: [f64; 2],
    ) -> usize {
        assert!(
            moved < captors.len(),
            "with_moved_captor: captor {moved} of {}",
            captors.len()
        );
        self.count(lattice, target, captors, Some((moved, pos)))
    }

    /// |ASZ| in cells with the target at `pos` instead (the mirror of
    /// `with_moved_captor`): the captors' fields and the target's own are
    /// kept, the moved target's is marched apart.
    pub fn with_moved_target<L: Lattice + ?Sized>(
        &mut self,
        lattice: &L,
        target: Source,
        captors: &[Source],
        pos: [f64; 2],
    ) -> usize {
        self.count(lattice, target, captors, Some((captors.len(), pos)))
    }

    /// The count of a moved robot's configuration made already beside the
    /// same own cells, else `search`'s; a move that stays in its robot's
    /// cell is no move.
    fn count<L: Lattice + ?Sized>(
        &mut self,
        lattice: &L,
        target: Source,
        captors: &[Source],
        moved: Option<(usize, [f64; 2])>,
    ) -> usize {
        let base = CountKey::new(lattice, target, captors);
        if self.counts_base.as_ref() != Some(&base) {
            self.counts.clear();
            self.counts_base = Some(base.clone());
        }
        let mut key = base;
        let mut moved = moved;
        if let Some((m, pos)) = moved {
            let cell = lattice.locate(pos).map(|(c, _)| c);
            if cell == key.robots[m].0 {
                moved = None;
            } else {
                key.robots[m].0 = cell;
            }
        }
        if moved.is_some() {
            if let Some(&(_, n)) = self.counts.iter().find(|(k, _)| *k == key) {
                return n;
            }
        }
        let n = self.search(lattice, target, captors, moved);
        if !self.counts.iter().any(|(k, _)| *k == key) {
            if self.counts.len() == COUNTS_KEPT {
                self.counts.remove(0);
            }
            self.counts.push((key, n));
        }
        n
    }

    /// Brings every field to its robot's cell (kept where the robot stayed
    /// in it), the moved robot's (index K for the target) into `candidate`,
    /// then searches.
    fn search<L: Lattice + ?Sized>(
        &mut self,
        lattice: &L,
        target: Source,
        captors: &[Source],
        moved: Option<(usize, [f64; 2])>,
    ) -> usize {
        let k = captors.len();
        self.fields.resize_with(k + 1, DistanceField::new);
        self.captor_speeds.clear();
        self.captor_speeds.extend(captors.iter().map(|c| c.speed));
        self.search.asz.clear();
        let target_pos = match moved {
            Some((m, pos)) if m == k => pos,
            _ => target.pos,
        };
        let Some((target_cell, _)) = lattice.locate(target_pos) else {
            return 0;
        };
        for (i, src) in captors.iter().chain(std::iter::once(&target)).enumerate() {
            if moved.is_none_or(|(m, _)| m != i) {
                refresh(&mut self.fields[i], lattice, src.pos);
            }
        }
        if let Some((_, pos)) = moved {
            refresh(&mut self.candidate, lattice, pos);
        }
        let mut candidate = Some(&mut self.candidate);
        let mut fields: Vec<&mut DistanceField> = Vec::with_capacity(k + 1);
        for (i, field) in self.fields.iter_mut().enumerate() {
            fields.push(match moved {
                Some((m, _)) if m == i => candidate.take().expect("one moved robot"),
                _ => field,
            });
        }
        let target_field = fields.pop().expect("the target's field");
        self.search.run(
            lattice,
            target_field,
            target.speed,
            target_cell,
            &mut fields,
            &self.captor_speeds,
            &mut self.confined,
        )
    }
}

/// A padded cell's (row, column), as numbers to measure straight lines by.
#[inline]
fn grid_at(cell: usize, stride: usize) -> [f64; 2] {
    [(cell / stride) as f64, (cell % stride) as f64]
}

/// Keeps `field` if it already starts from `pos`'s cell (marched as far as
/// it was), else starts it there.
fn refresh<L: Lattice + ?Sized>(field: &mut DistanceField, lattice: &L, pos: [f64; 2]) {
    match lattice.locate(pos) {
        Some((cell, _)) if field.is_from(lattice, cell) => {}
        Some((cell, _)) => field.start(lattice, cell, None),
        // A robot on no free cell reaches nothing: an empty field.
        None => field.prepare(lattice),
    }
}

impl RegionSearch {
    fn reset(&mut self, n: usize) {
        for buffer in [&mut self.region, &mut self.seen, &mut self.waiting] {
            buffer.resize(n, false);
        }
        for &c in &self.region_cells {
            self.region[c as usize] = false;
        }
        for &c in &self.seen_cells {
            self.seen[c as usize] = false;
            self.waiting[c as usize] = false;
        }
        self.region_cells.clear();
        self.seen_cells.clear();
        self.waiting_count = 0;
        self.candidates.clear();
        self.asz.clear();
    }

    /// Whether some captor reaches `cell` no later than `time`, its field
    /// marched that far first (ties go to the captors). A captor too far
    /// from the cell in a straight line is not marched for it.
    fn captor_first(
        captors: &mut [&mut DistanceField],
        speeds: &[f64],
        stride: usize,
        cell: usize,
        time: f64,
    ) -> bool {
        let at = grid_at(cell, stride);
        captors.iter_mut().zip(speeds).any(|(field, &speed)| {
            let limit = time * speed;
            if field.beyond(at, limit) {
                return false;
            }
            field.advance(limit);
            field.at(cell) / speed <= time
        })
    }

    /// Moves the waiting cells the target's field settles before `bound`
    /// into the candidates; apart from `run` to keep its search loop short,
    /// inlined because it runs once per candidate.
    #[inline]
    fn release_waiting(&mut self, target: &mut DistanceField, bound: f64) {
        while self.waiting_count > 0 {
            let Some(cell) = target.step(bound, None) else {
                break;
            };
            if self.waiting[cell] {
                self.waiting[cell] = false;
                self.waiting_count -= 1;
                self.candidates.push(Candidate {
                    distance: target.at(cell),
                    cell: cell as u32,
                });
            }
        }
    }

    /// Offers a region cell's unseen free neighbours: as candidates when the
    /// target's field has reached them, else as waiting; inlined because it
    /// runs once per region cell.
    #[inline]
    fn offer_neighbours(
        &mut self,
        free: &[u8],
        stride: usize,
        cell: usize,
        target: &DistanceField,
    ) {
        for nb in [cell - 1, cell + 1, cell - stride, cell + stride] {
            if free[nb] != 0 || self.seen[nb] {
                continue;
            }
            self.seen[nb] = true;
            self.seen_cells.push(nb as u32);
            let d = target.at(nb);
            if d.is_finite() {
                self.candidates.push(Candidate {
                    distance: d,
                    cell: nb as u32,
                });
            } else {
                self.waiting[nb] = true;
                self.waiting_count += 1;
            }
        }
    }

    /// The target's region (its connected part of the cells it reaches
    /// strictly first), searched in the order of its arrival time; then the
    /// second march inside it. Fills `asz`; returns its size.
    #[allow(clippy::too_many_arguments)]
    fn run<L: Lattice + ?Sized>(
        &mut self,
        lattice: &L,
        target: &mut DistanceField,
        target_speed: f64,
        target_cell: usize,
        captors: &mut [&mut DistanceField],
        speeds: &[f64],
        confined: &mut DistanceField,
    ) -> usize {
        let stride = lattice.stride();
        let free = lattice.obstacle();
        self.reset(free.len());
        if target.at(target_cell) != 0.0 {
            return 0;
        }
        self.seen[target_cell] = true;
        self.seen_cells.push(target_cell as u32);
        self.candidates.push(Candidate {
            distance: 0.0,
            cell: target_cell as u32,
        });
        loop {
            // Cells offered before the target's field reached them join the
            // candidates once it settles them, before any later candidate.
            let bound = self.candidates.peek().map_or(f64::INFINITY, |c| c.distance);
            self.release_waiting(target, bound);
            let Some(Candidate { distance, cell }) = self.candidates.pop() else {
                break;
            };
            let cell = cell as usize;
            if Self::captor_first(captors, speeds, stride, cell, distance / target_speed) {
                continue;
            }
            self.region[cell] = true;
            self.region_cells.push(cell as u32);
            self.offer_neighbours(free, stride, cell, target);
        }
        if !self.region[target_cell] {
            return 0;
        }
        if self.confined_lattice != lattice.lattice_id()
            || self.confined_region != self.region_cells
        {
            confined.march(lattice, target_cell, Some(&self.region));
            self.confined_lattice = lattice.lattice_id();
            self.confined_region.clone_from(&self.region_cells);
        }
        for &c in &self.region_cells {
            let c = c as usize;
            if !Self::captor_first(captors, speeds, stride, c, confined.at(c) / target_speed) {
                self.asz.push(c as u32);
            }
        }
        self.asz.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::asz::CoarseLattice;
    use crate::map::{Grid, PreparedMap};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Two rooms joined by a door, on a 320-cell grid (16 m).
    fn two_rooms() -> PreparedMap {
        PreparedMap::new(Grid::with_free_rects(
            "two rooms",
            320,
            &[
                (40..280, 40..150),
                (40..280, 170..280),
                (150..175, 150..170),
            ],
        ))
    }

    /// Kept fields, a moved captor's and a moved target's, give every count a
    /// fresh set of fields gives, whatever the order of the calls.
    fn kept_fields_count_as_fresh_ones<L: Lattice + ?Sized>(lattice: &L, map: &PreparedMap) {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let free: Vec<[f64; 2]> = (0..map.grid.side())
            .flat_map(|r| (0..map.grid.side()).map(move |c| (r, c)))
            .filter(|&(r, c)| map.grid.is_free(r as isize, c as isize))
            .map(|(r, c)| map.grid.cell_center(r, c))
            .collect();
        let pick = |rng: &mut ChaCha8Rng| free[rng.gen_range(0..free.len())];
        let mut kept = AszFields::new();
        let mut told_apart = 0;
        for round in 0..24 {
            let captors: Vec<Source> = (0..3)
                .map(|_| Source {
                    pos: pick(&mut rng),
                    speed: 1.0,
                })
                .collect();
            let target = Source {
                pos: pick(&mut rng),
                speed: [1.0, 1.2][round % 2],
            };
            let fresh = |target: Source, captors: &[Source]| {
                AszFields::new().asz_cells(lattice, target, captors)
            };
            let now = fresh(target, &captors);
            // A call after a moved robot's counts the state itself again.
            let order = rng.gen_range(0..3);
            if order == 0 {
                assert_eq!(kept.asz_cells(lattice, target, &captors), now);
            }
            // A zero step stays in its cell; the last two repeat earlier
            // moves, so a count made already is looked up.
            let mut moves: Vec<(usize, [f64; 2])> =
                [[0.1, 0.0], [0.0, -0.15], [-0.1, 0.05], [0.0, 0.0]]
                    .into_iter()
                    .map(|step| (rng.gen_range(0..3), step))
                    .collect();
            moves.extend_from_within(..2);
            for (i, step) in moves {
                let pos = [captors[i].pos[0] + step[0], captors[i].pos[1] + step[1]];
                let mut moved = captors.clone();
                moved[i].pos = pos;
                let want = fresh(target, &moved);
                told_apart += usize::from(want != now);
                assert_eq!(
                    kept.with_moved_captor(lattice, target, &captors, i, pos),
                    want,
                    "round {round}: captor {i} moved to {pos:?}"
                );
                let pos = [target.pos[0] - step[1], target.pos[1] + step[0]];
                let want = fresh(Source { pos, ..target }, &captors);
                assert_eq!(
                    kept.with_moved_target(lattice, target, &captors, pos),
                    want,
                    "round {round}: target moved to {pos:?}"
                );
            }
            assert_eq!(
                kept.asz_cells(lattice, target, &captors),
                now,
                "round {round}"
            );
        }
        assert!(told_apart > 12, "the moves must change |ASZ|: {told_apart}");
    }

    /// The straight-line bound the search uses to leave a captor's field
    /// unmarched (`beyond`) holds on every settled cell of fields from
    /// many starts on generated floor plans: a field never reads below
    /// 0.97 of the straight line less two cells. Were it wrong, a count
    /// could miss a captor's cell.
    #[test]
    fn fields_never_read_below_the_straight_line_bound() {
        use crate::map::generate::{generate, GeneratorConfig};
        use crate::map::SizeClass;
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut checked = 0usize;
        for seed in 0..3 {
            let map = PreparedMap::new(generate(
                seed,
                SizeClass::ALL[seed as usize % 3],
                &GeneratorConfig::default(),
            ));
            let free: Vec<usize> = (0..map.obstacle.len())
                .filter(|&c| map.obstacle[c] == 0)
                .collect();
            let mut field = DistanceField::new();
            for _ in 0..6 {
                let start = free[rng.gen_range(0..free.len())];
                field.march(&map, start, None);
                for cell in field.settled() {
                    let d = field.at(cell);
                    let dr = (cell / map.stride) as f64 - (start / map.stride) as f64;
                    let dc = (cell % map.stride) as f64 - (start % map.stride) as f64;
                    let straight = dr.hypot(dc) * map.cell_size();
                    assert!(
                        !field.beyond(grid_at(cell, map.stride), d),
                        "cell {cell}: distance {d} m, straight line {straight} m"
                    );
                    checked += 1;
                }
            }
        }
        assert!(checked > 100_000, "{checked} cells checked");
    }

    /// More moves of one state than the counts kept: every count is still
    /// a fresh one's, the early moves' asked again after the oldest left.
    #[test]
    fn more_moves_than_the_counts_kept_count_as_fresh_ones() {
        let map = two_rooms();
        let at = |r: usize, c: usize| map.grid.cell_center(r, c);
        let captors: Vec<Source> = [(60, 60), (250, 90), (120, 230)]
            .map(|(r, c)| Source {
                pos: at(r, c),
                speed: 1.0,
            })
            .to_vec();
        let target = Source {
            pos: at(150, 110),
            speed: 1.0,
        };
        let moves: Vec<[f64; 2]> = (0..2 * COUNTS_KEPT + 3)
            .map(|k| at(60 + 4 * (k / 6), 60 + 4 * (k % 6)))
            .collect();
        let mut kept = AszFields::new();
        for pos in moves.iter().chain(&moves[..4]) {
            let mut moved = captors.clone();
            moved[0].pos = *pos;
            assert_eq!(
                kept.with_moved_captor(&map, target, &captors, 0, *pos),
                AszFields::new().asz_cells(&map, target, &moved),
                "captor 0 moved to {pos:?}"
            );
        }
        assert_eq!(kept.counts.len(), COUNTS_KEPT);
    }

    #[test]
    fn kept_fields_count_as_fresh_ones_on_map_cells() {
        let map = two_rooms();
        kept_fields_count_as_fresh_ones(&map, &map);
    }

    #[test]
    fn kept_fields_count_as_fresh_ones_on_coarse_cells() {
        let map = two_rooms();
        let coarse = CoarseLattice::new(&map, 4);
        kept_fields_count_as_fresh_ones(&coarse, &map);
    }
}
