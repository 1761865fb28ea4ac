//! How far each cell's kind (obstacle or free) reaches: the obstacle patch
//! fills a run of pixels with one value, without looking each pixel up,
//! when every cell the run can touch is provably of the same kind.

/// The largest reach stored; farther counts as this far.
pub const MAX_REACH: u8 = 127;

/// Per cell of an obstacle grid (`obstacle`, `stride` cells a row, 1 =
/// obstacle): bit 0 the cell's own obstacle bit, bits 1..=7 its reach r,
/// the largest r <= `MAX_REACH` such that every cell of the grid within
/// Chebyshev distance r (|row offset| <= r and |column offset| <= r) is of
/// the cell's kind. Cells beyond the grid's edge do not limit it.
pub fn kind_and_reach(obstacle: &[u8], stride: usize) -> Vec<u8> {
    let to_obstacle = chessboard_distance(obstacle, stride, |o| o != 0);
    let to_free = chessboard_distance(obstacle, stride, |o| o == 0);
    obstacle
        .iter()
        .zip(to_obstacle.iter().zip(&to_free))
        .map(|(&o, (&d_obstacle, &d_free))| {
            // The nearest cell of the other kind is at distance d, so
            // every cell closer than d is of this kind.
            let d = if o != 0 { d_free } else { d_obstacle };
            let reach = (d - 1).min(MAX_REACH as u16) as u8;
            (o != 0) as u8 | reach << 1
        })
        .collect()
}

/// Chebyshev distance from every cell to the nearest cell where `is_source`
/// holds (0 on those), saturating at `u16::MAX`: the two raster passes over
/// the 3 x 3 neighbourhood, exact for this metric.
fn chessboard_distance(cells: &[u8], stride: usize, is_source: impl Fn(u8) -> bool) -> Vec<u16> {
    let rows = cells.len() / stride;
    let mut d: Vec<u16> = cells
        .iter()
        .map(|&c| if is_source(c) { 0 } else { u16::MAX })
        .collect();
    let at = |r: usize, c: usize| r * stride + c;
    for r in 0..rows {
        for c in 0..stride {
            let mut best = d[at(r, c)];
            let mut relax = |n: u16| best = best.min(n.saturating_add(1));
            if c > 0 {
                relax(d[at(r, c - 1)]);
            }
            if r > 0 {
                relax(d[at(r - 1, c)]);
                if c > 0 {
                    relax(d[at(r - 1, c - 1)]);
                }
                if c + 1 < stride {
                    relax(d[at(r - 1, c + 1)]);
                }
            }
            d[at(r, c)] = best;
        }
    }
    for r in (0..rows).rev() {
        for c in (0..stride).rev() {
            let mut best = d[at(r, c)];
            let mut relax = |n: u16| best = best.min(n.saturating_add(1));
            if c + 1 < stride {
                relax(d[at(r, c + 1)]);
            }
            if r + 1 < rows {
                relax(d[at(r + 1, c)]);
                if c > 0 {
                    relax(d[at(r + 1, c - 1)]);
                }
                if c + 1 < stride {
                    relax(d[at(r + 1, c + 1)]);
                }
            }
            d[at(r, c)] = best;
        }
    }
    d
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
