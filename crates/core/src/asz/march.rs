//! The square lattices a march runs on (`Lattice`: the map's own cells or
//! coarser ones) and the one-pass first-order Fast Marching with labelled
//! fronts (`FastMarching`): the geodesic distance the planner falls back
//! on, and the one-pass |ASZ| kept as the baseline and for `greedy:K`.

use crate::map::{PreparedMap, CELL_AREA, CELL_SIZE};

/// The square lattice a march runs on: the map's own 0.05 m cells
/// (`PreparedMap`, the spec's ASZ) or a coarser one (`CoarseLattice`, for
/// controllers that march many times per step).
pub trait Lattice {
    /// Unique per lattice, so the march's buffers know when it changed.
    fn lattice_id(&self) -> u64;
    /// Row stride of `obstacle`.
    fn stride(&self) -> usize;
    /// 1 = obstacle, padded so that every free cell's four neighbours exist.
    fn obstacle(&self) -> &[u8];
    /// Side of a cell in metres.
    fn cell_size(&self) -> f64;
    /// The free cell holding `p` (padded index) and its centre; None when
    /// no front can start there.
    fn locate(&self, p: [f64; 2]) -> Option<(usize, [f64; 2])>;
    /// The cells a front from `p` starts in, each at its straight-line time
    /// from `p`: by default the one cell holding it.
    fn seeds(&self, p: [f64; 2]) -> Seeds {
        let mut seeds = Seeds::default();
        if let Some(s) = self.locate(p) {
            seeds.push(s);
        }
        seeds
    }
    /// The geodesic distance (m) to `p` after `fm.distance_field` on this
    /// lattice: by default that of the cell holding `p` (the spec's rule).
    fn distance_at(&self, fm: &FastMarching, p: [f64; 2]) -> f64 {
        match self.locate(p) {
            Some((cell, _)) => fm.time(cell) as f64,
            None => f64::INFINITY,
        }
    }
}

/// Up to four start cells of a front (padded index, centre).
#[derive(Clone, Copy, Debug, Default)]
pub struct Seeds {
    cells: [(usize, [f64; 2]); 4],
    len: usize,
}

impl Seeds {
    pub fn push(&mut self, seed: (usize, [f64; 2])) {
        self.cells[self.len] = seed;
        self.len += 1;
    }

    pub fn as_slice(&self) -> &[(usize, [f64; 2])] {
        &self.cells[..self.len]
    }
}

impl Lattice for PreparedMap {
    fn lattice_id(&self) -> u64 {
        self.id
    }
    fn stride(&self) -> usize {
        self.stride
    }
    fn obstacle(&self) -> &[u8] {
        &self.obstacle
    }
    fn cell_size(&self) -> f64 {
        CELL_SIZE
    }
    /// The spec's rule: a source on an obstacle cell starts no front.
    fn locate(&self, p: [f64; 2]) -> Option<(usize, [f64; 2])> {
        let (r, c) = self.grid.cell_of(p);
        self.grid.is_free(r, c).then(|| {
            (
                self.padded_index(r, c),
                self.grid.cell_center(r as usize, c as usize),
            )
        })
    }
}

/// A robot seen by the march: where it is and how fast it can go (m/s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Source {
    pub pos: [f64; 2],
    pub speed: f64,
}

/// No front has reached the cell (or it is an obstacle).
pub const NO_LABEL: u8 = u8::MAX;

const FAR: u8 = 0;
const TRIAL: u8 = 1;
const FROZEN: u8 = 2;

/// |ASZ| at or below which the strict capture rule fires: pi (1.5 r / 0.05)^2 cells.
pub fn strict_capture_cells(robot_radius: f64) -> f64 {
    std::f64::consts::PI * (1.5 * robot_radius / CELL_SIZE).powi(2)
}

/// The march's priority queue. Every time it is offered lies within one
/// step cost (h / v) of the last time it settled, so a ring of buckets, each
/// 1/32 of the largest step cost wide, holds the whole front. Ring buckets
/// hold cell indices only: a cell whose time improves within the bucket it
/// already sits in needs no new entry (its time is read when the bucket
/// comes up), so no stale entries are ever popped. The bucket being settled
/// (a handful of cells) is sorted, so the order is the exact FMM order. Keys
/// are the time's bits (non-negative f32 bits order like the floats) above
/// the label and cell, so at equal times the lower label (a captor) settles
/// first. (32 buckets per step measured fastest on Graceville against 16,
/// 64 and 128; a binary heap per bucket was 4% slower than sorting.)
#[derive(Default)]
struct BucketQueue {
    width: f32,
    inv_width: f32,
    /// Absolute index of the bucket in `current`.
    cur: usize,
    ring: Vec<Vec<u32>>,
    ring_len: usize,
    /// The bucket being settled, sorted with the smallest key last.
    current: Vec<u64>,
}

const RING: usize = 64;
const BUCKETS_PER_STEP: f32 = 32.0;

#[inline]
fn queue_key(time: f32, label: u8, cell: usize) -> u64 {
    ((time.to_bits() as u64) << 32) | ((label as u64) << 24) | cell as u64
}

impl BucketQueue {
    fn reset(&mut self, max_step_cost: f32) {
        self.width = max_step_cost / BUCKETS_PER_STEP;
        self.inv_width = 1.0 / self.width;
        self.cur = 0;
        self.ring_len = 0;
        self.current.clear();
        self.ring.resize_with(RING, Vec::new);
        for b in &mut self.ring {
            b.clear();
        }
    }

    /// The smallest time a push may carry.
    #[inline]
    fn floor(&self) -> f32 {
        self.cur as f32 * self.width
    }

    #[inline]
    fn bucket(&self, time: f32) -> usize {
        // Offers lie within one step cost of the settled front; the clamp
        // only guards against rounding.
        let scaled = time * self.inv_width;
        debug_assert!(scaled.is_finite() && scaled >= 0.0 && scaled < u32::MAX as f32);
        // SAFETY: offered times are finite, non-negative and below a few
        // hundred seconds, so the scaled time fits a u32 (checked in debug).
        let b = unsafe { scaled.to_int_unchecked::<u32>() } as usize;
        b.min(self.cur + RING - 1)
    }

    /// Queues `cell` at `time`; `old` is the cell as it was before this offer.
    #[inline]
    fn push(&mut self, cell: usize, time: f32, label: u8, old: Cell) {
        let b = self.bucket(time);
        if b <= self.cur {
            // Rare: offers usually land tens of buckets ahead.
            let key = queue_key(time, label, cell);
            let at = self.current.partition_point(|&k| k > key);
            self.current.insert(at, key);
        } else if !(old.state == TRIAL && self.bucket(old.time) == b) {
            self.ring[b % RING].push(cell as u32);
            self.ring_len += 1;
        }
    }

    /// The next (time, label, cell) in FMM order; entries may be stale.
    #[inline]
    fn pop(&mut self, cells: &[Cell]) -> Option<(f32, u8, usize)> {
        loop {
            if let Some(key) = self.current.pop() {
                let t = f32::from_bits((key >> 32) as u32);
                return Some((t, (key >> 24) as u8, (key & 0xFF_FFFF) as usize));
            }
            if self.ring_len == 0 {
                return None;
            }
            self.cur += 1;
            let slot = self.cur % RING;
            let mut bucket = std::mem::take(&mut self.ring[slot]);
            self.ring_len -= bucket.len();
            for &cell in &bucket {
                let c = cells[cell as usize];
                if c.state == TRIAL && self.bucket(c.time) <= self.cur {
                    self.current.push(queue_key(c.time, c.label, cell as usize));
                }
            }
            self.current.sort_unstable_by(|a, b| b.cmp(a));
            bucket.clear();
            self.ring[slot] = bucket; // keep the allocation
        }
    }
}

/// One cell of the march, packed so that reading a neighbour is one load.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(8))]
struct Cell {
    time: f32,
    label: u8,
    state: u8,
}

const BLOCKED: u8 = 3;

impl Cell {
    const FAR: Cell = Cell {
        time: f32::INFINITY,
        label: NO_LABEL,
        state: FAR,
    };
    const WALL: Cell = Cell {
        time: f32::INFINITY,
        label: NO_LABEL,
        state: BLOCKED,
    };
}

/// Reusable buffers of a multi-label fast march over one map. Only the cells
/// touched by the last march are reset, so small marches stay cheap.
#[derive(Default)]
pub struct FastMarching {
    map_id: u64,
    stride: usize,
    cells: Vec<Cell>,
    touched: Vec<u32>,
    queue: BucketQueue,
}

impl FastMarching {
    pub fn new() -> FastMarching {
        FastMarching::default()
    }

    fn prepare<L: Lattice + ?Sized>(&mut self, map: &L) {
        let n = map.stride() * map.stride();
        assert!(n < (1 << 24), "map too large for the march's queue keys");
        if self.map_id != map.lattice_id() {
            self.map_id = map.lattice_id();
            self.stride = map.stride();
            self.cells.clear();
            self.cells.extend(map.obstacle().iter().map(|&o| {
                if o != 0 {
                    Cell::WALL
                } else {
                    Cell::FAR
                }
            }));
        } else {
            for &c in &self.touched {
                self.cells[c as usize] = Cell::FAR;
            }
        }
        self.touched.clear();
    }

    /// Arrival time (s) at padded cell `cell` from the front that claimed it.
    #[inline]
    pub fn time(&self, cell: usize) -> f32 {
        let c = self.cells[cell];
        if c.state == FROZEN {
            c.time
        } else {
            f32::INFINITY
        }
    }

    /// Index of the source that reaches padded cell `cell` first, or NO_LABEL.
    #[inline]
    pub fn label(&self, cell: usize) -> u8 {
        let c = self.cells[cell];
        if c.state == FROZEN {
            c.label
        } else {
            NO_LABEL
        }
    }

    /// The padded cells the last march settled, with their labels.
    pub fn settled(&self) -> impl Iterator<Item = (usize, u8)> + '_ {
        self.touched
            .iter()
            .map(|&c| c as usize)
            .filter(|&c| self.cells[c].state == FROZEN)
            .map(|c| (c, self.cells[c].label))
    }

    /// Solves the first-order eikonal update at `cell` from the settled
    /// neighbours of the same label.
    #[inline(always)]
    fn update_value(&self, cell: usize, label: u8, cost: f32) -> f32 {
        let s = self.stride;
        let cells = &self.cells[cell - s..=cell + s];
        let val = |c: usize| {
            let c = cells[c];
            if c.state == FROZEN && c.label == label {
                c.time
            } else {
                f32::INFINITY
            }
        };
        let (cell, s) = (s, s); // the neighbourhood slice starts at cell - s
        let min = |x: f32, y: f32| if x < y { x } else { y };
        let a = min(val(cell - 1), val(cell + 1));
        let b = min(val(cell - s), val(cell + s));
        let (lo, hi) = if a < b { (a, b) } else { (b, a) };
        if hi - lo >= cost {
            lo + cost
        } else {
            let diff = hi - lo;
            0.5 * (lo + hi + (2.0 * cost * cost - diff * diff).sqrt())
        }
    }

    /// Marches from all `sources` at once; source i labels its cells i.
    /// With `stop_label`, stops as soon as no cell is pending for that label
    /// (its region is then complete). Returns the cells settled with `stop_label`
    /// (0 without one).
    pub fn march<L: Lattice + ?Sized>(
        &mut self,
        map: &L,
        sources: &[Source],
        stop_label: Option<u8>,
    ) -> usize {
        assert!(sources.len() < NO_LABEL as usize);
        self.prepare(map);
        let s = self.stride;
        let h = map.cell_size();
        let costs: Vec<f32> = sources.iter().map(|src| (h / src.speed) as f32).collect();
        self.queue
            .reset(costs.iter().copied().fold(h as f32, f32::max));
        let mut pending_stop = 0usize;
        let mut settled_stop = 0usize;
        for (i, src) in sources.iter().enumerate() {
            for &(cell, centre) in map.seeds(src.pos).as_slice() {
                let t = ((src.pos[0] - centre[0]).hypot(src.pos[1] - centre[1]) / src.speed) as f32;
                self.offer(cell, t, i as u8, stop_label, &mut pending_stop);
            }
        }
        // Every cell the march settles is free, and a lattice pads its free
        // cells with obstacle, so its four neighbours are valid indices.
        while let Some((t, label, cell)) = self.queue.pop(&self.cells) {
            if stop_label.is_some() && pending_stop == 0 {
                break;
            }
            let c = self.cells[cell];
            if c.state != TRIAL || c.label != label || c.time != t {
                continue; // stale entry
            }
            self.cells[cell].state = FROZEN;
            if Some(label) == stop_label {
                pending_stop -= 1;
                settled_stop += 1;
            }
            let cost = costs[label as usize];
            debug_assert!(cell >= s && cell + s < self.cells.len());
            for nb in [cell - 1, cell + 1, cell - s, cell + s] {
                if self.cells[nb].state >= FROZEN {
                    continue; // settled or an obstacle
                }
                let t = self.update_value(nb, label, cost);
                self.offer(nb, t, label, stop_label, &mut pending_stop);
            }
        }
        settled_stop
    }

    /// Proposes time `t` from front `label` for a cell not yet settled.
    #[inline(always)]
    fn offer(
        &mut self,
        cell: usize,
        t: f32,
        label: u8,
        stop_label: Option<u8>,
        pending_stop: &mut usize,
    ) {
        // Rounding can put a one-sided update a hair below the settled front.
        let t = t.max(self.queue.floor());
        let old = self.cells[cell];
        let better = t < old.time || (t == old.time && label < old.label);
        if !better {
            return;
        }
        if old.state == FAR {
            self.touched.push(cell as u32);
        } else if Some(old.label) == stop_label {
            *pending_stop -= 1;
        }
        if Some(label) == stop_label {
            *pending_stop += 1;
        }
        self.cells[cell] = Cell {
            time: t,
            label,
            state: TRIAL,
        };
        self.queue.push(cell, t, label, old);
    }

    /// Geodesic distance (m) from `from` to every free cell: one full march at
    /// unit speed. Read it with `time`.
    pub fn distance_field<L: Lattice + ?Sized>(&mut self, map: &L, from: [f64; 2]) {
        self.march(
            map,
            &[Source {
                pos: from,
                speed: 1.0,
            }],
            None,
        );
    }

    /// The one-pass |ASZ| in cells (the baseline `AszFields` is measured
    /// against): the free cells the target's front claims before every
    /// captor's, restricted to the part it reaches without crossing
    /// captor-first cells. Ties go to the captors; cells nobody reaches
    /// belong to nobody.
    pub fn asz_cells<L: Lattice + ?Sized>(
        &mut self,
        map: &L,
        target: Source,
        captors: &[Source],
    ) -> usize {
        let mut sources: Vec<Source> = captors.to_vec();
        sources.push(target);
        self.march(map, &sources, Some(captors.len() as u8))
    }
}

/// |ASZ| in m^2.
pub fn cells_to_m2(cells: usize) -> f64 {
    cells as f64 * CELL_AREA
}
