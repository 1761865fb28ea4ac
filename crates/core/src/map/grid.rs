//! The working occupancy grid: 0.05 m cells, row 0 at the top (+y), and the
//! world frame of spec §1 (metres, origin at the grid centre, x right, y up).

use serde::{Deserialize, Serialize};
use std::fmt;

/// Side of one working-grid cell in metres.
pub const CELL_SIZE: f64 = 0.05;
/// Side of one source-PNG pixel in metres.
pub const PIXEL_SIZE: f64 = 0.01;
/// Source pixels per working cell (0.05 / 0.01).
pub const PIXELS_PER_CELL: u32 = 5;
/// Source maps smaller than this are padded with obstacle to this side.
pub const MIN_SIDE_PX: u32 = 1600;
/// Area of one working cell in m^2.
pub const CELL_AREA: f64 = CELL_SIZE * CELL_SIZE;

/// The paper's evaluation split by traversable area.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SizeClass {
    Small,
    Medium,
    Large,
}

impl SizeClass {
    pub const ALL: [SizeClass; 3] = [SizeClass::Small, SizeClass::Medium, SizeClass::Large];

    /// small < 40 m^2, medium 40–60 m^2, large > 60 m^2 (spec §1).
    pub fn from_area(area_m2: f64) -> SizeClass {
        if area_m2 < 40.0 {
            SizeClass::Small
        } else if area_m2 <= 60.0 {
            SizeClass::Medium
        } else {
            SizeClass::Large
        }
    }

    /// The range of traversable area (m^2) the class stands for, as used by the generator.
    pub fn area_range(self) -> (f64, f64) {
        match self {
            SizeClass::Small => (15.0, 40.0),
            SizeClass::Medium => (40.0, 60.0),
            SizeClass::Large => (60.0, 80.0),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            SizeClass::Small => "small",
            SizeClass::Medium => "medium",
            SizeClass::Large => "large",
        }
    }
}

impl fmt::Display for SizeClass {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A size class's name that is none of small, medium or large.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown size class '{0}' (expected small, medium or large)")]
pub struct UnknownSizeClass(pub String);

impl std::str::FromStr for SizeClass {
    type Err = UnknownSizeClass;
    fn from_str(s: &str) -> Result<Self, UnknownSizeClass> {
        match s.trim().to_ascii_lowercase().as_str() {
            "small" => Ok(SizeClass::Small),
            "medium" => Ok(SizeClass::Medium),
            "large" => Ok(SizeClass::Large),
            other => Err(UnknownSizeClass(other.to_string())),
        }
    }
}

/// A square occupancy grid of `side x side` cells.
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    pub name: String,
    side: usize,
    /// Row-major, row 0 at the top of the map (largest y).
    free: Vec<bool>,
}

impl Grid {
    pub fn new(name: impl Into<String>, side: usize, free: Vec<bool>) -> Grid {
        assert_eq!(free.len(), side * side, "grid data does not match its side");
        Grid {
            name: name.into(),
            side,
            free,
        }
    }

    /// A grid whose cells are all obstacle.
    pub fn blocked(name: impl Into<String>, side: usize) -> Grid {
        Grid::new(name, side, vec![false; side * side])
    }

    /// A `side x side` grid, obstacle except the given rectangles of free
    /// cells, each `(rows, cols)` as half-open ranges (synthetic maps, tests).
    pub fn with_free_rects(
        name: impl Into<String>,
        side: usize,
        rects: &[(std::ops::Range<usize>, std::ops::Range<usize>)],
    ) -> Grid {
        let mut g = Grid::blocked(name, side);
        for (rows, cols) in rects {
            for r in rows.clone() {
                for c in cols.clone() {
                    g.set_free(r, c, true);
                }
            }
        }
        g
    }

    /// Cells per side.
    pub fn side(&self) -> usize {
        self.side
    }

    /// Side of the world in metres.
    pub fn extent(&self) -> f64 {
        self.side as f64 * CELL_SIZE
    }

    /// Free cell? Outside the grid counts as obstacle.
    #[inline]
    pub fn is_free(&self, row: isize, col: isize) -> bool {
        row >= 0
            && col >= 0
            && (row as usize) < self.side
            && (col as usize) < self.side
            && self.free[row as usize * self.side + col as usize]
    }

    pub fn set_free(&mut self, row: usize, col: usize, free: bool) {
        self.free[row * self.side + col] = free;
    }

    pub fn free_mask(&self) -> &[bool] {
        &self.free
    }

    /// SHA-256 of the grid's content (side, then one byte per cell, 1 =
    /// free), hex: the same map however its file is named, placed or
    /// re-encoded. The test-map guard (`map::testset`) and eval's setting
    /// identity read it.
    pub fn content_hash(&self) -> String {
        use sha2::{Digest, Sha256};
        let mut h = Sha256::new();
        h.update((self.side as u64).to_le_bytes());
        let cells: Vec<u8> = self.free.iter().map(|&f| f as u8).collect();
        h.update(&cells);
        crate::util::hex(&h.finalize())
    }

    pub fn free_cells(&self) -> usize {
        self.free.iter().filter(|&&f| f).count()
    }

    /// Traversable area in m^2 (free cells of the working grid).
    pub fn area_m2(&self) -> f64 {
        self.free_cells() as f64 * CELL_AREA
    }

    pub fn size_class(&self) -> SizeClass {
        SizeClass::from_area(self.area_m2())
    }

    /// World position (m) of the centre of cell (row, col).
    #[inline]
    pub fn cell_center(&self, row: usize, col: usize) -> [f64; 2] {
        let half = self.extent() / 2.0;
        [
            (col as f64 + 0.5) * CELL_SIZE - half,
            half - (row as f64 + 0.5) * CELL_SIZE,
        ]
    }

    /// Continuous cell coordinates (col, row) of a world point: cell (r, c)
    /// spans [c, c+1) x [r, r+1).
    #[inline]
    pub fn to_cell_coords(&self, p: [f64; 2]) -> (f64, f64) {
        let half = self.extent() / 2.0;
        ((p[0] + half) / CELL_SIZE, (half - p[1]) / CELL_SIZE)
    }

    /// The cell (row, col) holding a world point, possibly outside the grid.
    #[inline]
    pub fn cell_of(&self, p: [f64; 2]) -> (isize, isize) {
        let (c, r) = self.to_cell_coords(p);
        (floor_isize(r), floor_isize(c))
    }

    /// Keeps only the largest 4-connected free component; returns how many
    /// free cells were closed.
    pub fn keep_largest_component(&mut self) -> usize {
        let n = self.side;
        let mut comp = vec![u32::MAX; n * n];
        let mut best = (0usize, u32::MAX);
        let mut stack = Vec::new();
        let mut id = 0u32;
        for start in 0..n * n {
            if !self.free[start] || comp[start] != u32::MAX {
                continue;
            }
            let mut size = 0;
            comp[start] = id;
            stack.push(start);
            while let Some(c) = stack.pop() {
                size += 1;
                let (r, col) = (c / n, c % n);
                let mut visit = |nb: usize| {
                    if self.free[nb] && comp[nb] == u32::MAX {
                        comp[nb] = id;
                        stack.push(nb);
                    }
                };
                if r > 0 {
                    visit(c - n);
                }
                if r + 1 < n {
                    visit(c + n);
                }
                if col > 0 {
                    visit(c - 1);
                }
                if col + 1 < n {
                    visit(c + 1);
                }
            }
            if size > best.0 {
                best = (size, id);
            }
            id += 1;
        }
        let mut closed = 0;
        for (f, &c) in self.free.iter_mut().zip(&comp) {
            if *f && c != best.1 {
                *f = false;
                closed += 1;
            }
        }
        closed
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cell_centres_round_trip_through_world_coordinates() {
        let g = Grid::blocked("t", 320);
        for &(r, c) in &[(0, 0), (319, 319), (160, 3), (7, 250)] {
            let p = g.cell_center(r, c);
            assert_eq!(g.cell_of(p), (r as isize, c as isize));
        }
        // Origin at the grid centre, y up.
        assert_eq!(g.cell_center(0, 0), [-8.0 + 0.025, 8.0 - 0.025]);
        assert_eq!(g.cell_of([0.01, 0.01]), (159, 160));
    }

    #[test]
    fn size_class_thresholds() {
        assert_eq!(SizeClass::from_area(39.9), SizeClass::Small);
        assert_eq!(SizeClass::from_area(40.0), SizeClass::Medium);
        assert_eq!(SizeClass::from_area(60.0), SizeClass::Medium);
        assert_eq!(SizeClass::from_area(60.1), SizeClass::Large);
        assert!("huge".parse::<SizeClass>().is_err());
    }

    #[test]
    fn largest_component_is_kept() {
        let mut g = Grid::blocked("t", 10);
        for c in 0..5 {
            g.set_free(1, c, true); // 5 cells
        }
        g.set_free(8, 8, true); // isolated cell
        assert_eq!(g.keep_largest_component(), 1);
        assert_eq!(g.free_cells(), 5);
        assert!(!g.is_free(8, 8));
    }
}

/// `x.floor() as isize`, to the bit, without the libm call that `floor`
/// costs on the baseline x86-64 target (no SSE4.1 `roundsd`): the rule-based
/// robots' wall rays spent a fifth of their time in it. NaN gives 0 and
/// out-of-range values saturate, as the cast does.
#[inline(always)]
pub fn floor_isize(x: f64) -> isize {
    let t = x as i64; // rounds towards zero, saturates, NaN -> 0
    t.saturating_sub(((t as f64) > x) as i64) as isize
}

#[cfg(test)]
mod floor_tests {
    use super::floor_isize;

    #[test]
    fn floor_isize_is_floor_as_isize_to_the_bit() {
        let mut xs = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            1.0 - 1e-16,
            -1e-300,
            2.5e15,
            -2.5e15,
            4503599627370495.5,
            -4503599627370495.5,
            9.3e18,
            -9.3e18,
            1e300,
            -1e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            f64::MIN_POSITIVE,
            -f64::MIN_POSITIVE,
        ];
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        for _ in 0..100_000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            // Cell coordinates of points near and far from the grid, and
            // values a hair either side of integers.
            let x = (state % 2_000_000) as f64 / 1000.0 - 1000.0;
            xs.extend([x, x.round(), x.round() + 1e-12, x.round() - 1e-12]);
        }
        for x in xs {
            assert_eq!(floor_isize(x), x.floor() as isize, "x = {x:e}");
        }
    }
}
