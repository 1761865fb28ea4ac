//! The priority queue of a per-robot field's march (`fields.rs`): pops
//! (distance, cell) in the order a binary heap would, smallest distance
//! first and then smallest cell, at a fraction of its cost.
//!
//! Every distance offered lies within one cell size of the last one
//! settled (an upwind update adds at most h to a settled neighbour), so a
//! ring of buckets, each 1/32 of a cell wide, holds the whole front. Ring
//! buckets hold cell indices only; when a bucket comes up, the cells whose
//! current distance falls in it are sorted, so the order within it is
//! exact. An offer that lands in the bucket being settled (or below it, as
//! a second-order update can) is inserted in that sorted list. Entries
//! whose cell has since changed are skipped by the caller's check.

const RING: usize = 64;
const BUCKETS_PER_CELL: f64 = 32.0;

#[derive(Default)]
pub(super) struct FieldQueue {
    inv_width: f64,
    /// Absolute index of the bucket in `current`.
    cur: usize,
    ring: Vec<Vec<u32>>,
    ring_len: usize,
    /// The bucket being settled, sorted with the smallest entry last, as
    /// `key`s: integer comparisons in the sort.
    current: Vec<u128>,
}

impl FieldQueue {
    pub(super) fn reset(&mut self, cell_size: f64) {
        self.inv_width = BUCKETS_PER_CELL / cell_size;
        self.cur = 0;
        self.ring_len = 0;
        self.current.clear();
        self.ring.resize_with(RING, Vec::new);
        for b in &mut self.ring {
            b.clear();
        }
    }

    #[inline]
    fn bucket(&self, distance: f64) -> usize {
        // Distances are finite and non-negative; the cast saturates.
        ((distance * self.inv_width) as usize).min(self.cur + RING - 1)
    }

    #[inline(always)]
    pub(super) fn push(&mut self, cell: u32, distance: f64) {
        let b = self.bucket(distance);
        if b <= self.cur {
            let entry = key(distance, cell);
            let at = self.current.partition_point(|&e| e > entry);
            self.current.insert(at, entry);
        } else {
            self.ring[b % RING].push(cell);
            self.ring_len += 1;
        }
    }

    /// The next (distance, cell), left in the queue; `distance_of` gives a
    /// cell's current trial distance (None when it is no longer a trial
    /// cell), so a bucket takes only the cells whose distance still falls
    /// in it. A march stopped at a limit looks without taking, so the
    /// cell it stopped at is not pushed again.
    #[inline]
    pub(super) fn peek(&mut self, distance_of: impl Fn(u32) -> Option<f64>) -> Option<(f64, u32)> {
        loop {
            if let Some(&entry) = self.current.last() {
                return Some((f64::from_bits((entry >> 32) as u64), entry as u32));
            }
            if self.ring_len == 0 {
                return None;
            }
            self.cur += 1;
            let slot = self.cur % RING;
            let mut bucket = std::mem::take(&mut self.ring[slot]);
            self.ring_len -= bucket.len();
            for &cell in &bucket {
                if let Some(d) = distance_of(cell) {
                    if self.bucket(d) == self.cur {
                        self.current.push(key(d, cell));
                    }
                }
            }
            self.current.sort_unstable_by(|a, b| b.cmp(a));
            // A cell offered twice into this bucket appears twice.
            self.current.dedup();
            bucket.clear();
            self.ring[slot] = bucket;
        }
    }

    /// Removes the entry `peek` returned.
    #[inline]
    pub(super) fn take(&mut self) {
        self.current.pop();
    }
}

/// (distance, cell) as one integer in the queue's order: distance first,
/// then cell. Non-negative f64 bits order like the floats.
#[inline]
fn key(distance: f64, cell: u32) -> u128 {
    ((distance.to_bits() as u128) << 32) | cell as u128
}
