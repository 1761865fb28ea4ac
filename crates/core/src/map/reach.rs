//! How far each cell's kind (obstacle or free) reaches: the obstacle patch
//! fills a run of pixels with one value, without looking each pixel up,
//! when every cell the run can touch is provably of the same kind.

use std::ops::Range;

/// The largest reach stored; farther counts as this far.
pub const MAX_REACH: u8 = 127;

/// Per cell of an obstacle grid (`obstacle`, `stride` cells a row, 1 =
/// obstacle): bit 0 the cell's own obstacle bit, bits 1..=7 its reach r,
/// the largest r <= `MAX_REACH` such that every cell of the grid within
/// Chebyshev distance r (|row offset| <= r and |column offset| <= r) is of
/// the cell's kind. Cells beyond the grid's edge do not limit it.
pub fn kind_and_reach(obstacle: &[u8], stride: usize) -> Vec<u8> {
    let to_other = distance_to_other_kind(obstacle, stride);
    obstacle
        .iter()
        .zip(&to_other)
        .map(|(&o, &d)| {
            // The nearest cell of the other kind is at distance d, so
            // every cell closer than d is of this kind.
            (o != 0) as u8 | (d - 1) << 1
        })
        .collect()
}

/// Farther than any reach stored: distances saturate here, which leaves
/// every reach below it exact (a saturated distance only feeds larger
/// ones).
const FAR: u8 = MAX_REACH + 1;

/// Per cell, the Chebyshev distance (saturating at `FAR`) to the nearest
/// cell of the other kind, for both kinds at once. That distance is 1 at
/// a border cell (one with a neighbour of the other kind) and otherwise 1
/// more than the distance to the nearest border cell: the cell next to
/// the nearest other-kind cell on a shortest path is a border cell, and
/// every border cell has the other kind within 1. So it is one distance
/// transform from the border cells: the two raster passes over the 3 x 3
/// neighbourhood, exact for this metric. Each pass takes a row's
/// neighbours in the adjacent row first, for the whole row at once, then
/// its horizontal neighbour in order.
fn distance_to_other_kind(kind: &[u8], stride: usize) -> Vec<u8> {
    let rows = kind.len() / stride;
    let row = |r: usize| r * stride..(r + 1) * stride;
    let mut d = vec![FAR; kind.len()];
    // The border cells.
    for r in 0..rows {
        for other in r.saturating_sub(1)..(r + 2).min(rows) {
            let (k_row, k_other) = (&kind[row(r)], &kind[row(other)]);
            for (from, to) in neighbour_columns(stride) {
                let cells = d[row(r)][to.clone()].iter_mut().zip(&k_row[to]);
                for ((d_c, &k_c), &k_n) in cells.zip(&k_other[from]) {
                    *d_c = if k_c != k_n { 1 } else { *d_c };
                }
            }
        }
    }
    for r in 0..rows {
        if r > 0 {
            let (above, rest) = d.split_at_mut(r * stride);
            relax_from_row(&mut rest[..stride], &above[row(r - 1)]);
        }
        relax_along_row(d[row(r)].iter_mut());
    }
    for r in (0..rows).rev() {
        if r + 1 < rows {
            let (head, below) = d.split_at_mut((r + 1) * stride);
            relax_from_row(&mut head[row(r)], &below[..stride]);
        }
        relax_along_row(d[row(r)].iter_mut().rev());
    }
    d
}

/// The pairs (columns read, columns written) that line each cell of a row
/// up with its neighbour straight across, to the left and to the right in
/// a row of `n` cells.
fn neighbour_columns(n: usize) -> [(Range<usize>, Range<usize>); 3] {
    [(0..n, 0..n), (0..n - 1, 1..n), (1..n, 0..n - 1)]
}

/// Relaxes every cell of a row, in the order given, through the cell
/// before it.
fn relax_along_row<'a>(cells: impl Iterator<Item = &'a mut u8>) {
    let mut before = FAR;
    for d_c in cells {
        before = (*d_c).min(before + 1);
        *d_c = before;
    }
}

/// Relaxes every cell of a row through its three neighbours in the
/// adjacent row `d_next`; each a pass over slices, which the compiler
/// vectorises. (Distances are at most `FAR`, so 1 more does not wrap.)
fn relax_from_row(d_row: &mut [u8], d_next: &[u8]) {
    for (from, to) in neighbour_columns(d_row.len()) {
        for (d_c, &d_n) in d_row[to].iter_mut().zip(&d_next[from]) {
            *d_c = (*d_c).min(d_n + 1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// Every reach is the largest square around the cell that holds only
    /// its kind (brute force on a random grid with rooms and specks).
    #[test]
    fn reach_is_the_largest_square_of_one_kind() {
        let (stride, rows) = (37, 29);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut grid = vec![0u8; stride * rows];
        for (i, o) in grid.iter_mut().enumerate() {
            let (r, c) = (i / stride, i % stride);
            *o = ((5..20).contains(&r) && (3..30).contains(&c)) as u8 ^ 1;
            if rng.gen_bool(0.03) {
                *o ^= 1;
            }
        }
        let packed = kind_and_reach(&grid, stride);
        for r in 0..rows as isize {
            for c in 0..stride as isize {
                let kind = grid[r as usize * stride + c as usize];
                let same_within = |k: isize| {
                    (r - k..=r + k).all(|rr| {
                        (c - k..=c + k).all(|cc| {
                            rr < 0
                                || cc < 0
                                || rr >= rows as isize
                                || cc >= stride as isize
                                || grid[rr as usize * stride + cc as usize] == kind
                        })
                    })
                };
                let want = (0..=MAX_REACH as isize)
                    .take_while(|&k| same_within(k))
                    .last()
                    .unwrap();
                let got = packed[r as usize * stride + c as usize];
                assert_eq!(got & 1, kind, "({r}, {c})");
                assert_eq!((got >> 1) as isize, want, "({r}, {c})");
            }
        }
    }
}
