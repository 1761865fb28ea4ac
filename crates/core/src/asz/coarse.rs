//! A coarser lattice over a prepared map: cells of `factor` x `factor` map
//! cells. The ASZ-greedy captor marches 12 times per step for 3 captors;
//! on cells of 0.10 m (factor 2) a march settles a quarter of the cells.
//!
//! A coarse cell is free only when every map cell it covers is free, so a
//! wall one map cell thick stays a wall (no front leaks through it) and
//! openings narrow by less than one coarse cell on each side. Because that
//! thickens walls, a robot hugging one can sit in a blocked coarse cell; its
//! front then starts from the nearest free neighbour instead (`locate`).

use super::march::{FastMarching, Lattice, Seeds};
use crate::map::{PreparedMap, CELL_SIZE};

pub struct CoarseLattice {
    id: u64,
    /// The prepared map it was built from.
    source_id: u64,
    factor: usize,
    /// Coarse cells per side (the last row and column may overhang the map;
    /// what lies outside counts as obstacle).
    side: usize,
    /// side + 2: one ring of obstacle around the cells.
    stride: usize,
    /// Half the map's side in metres (the world origin is the map's centre).
    half_extent: f64,
    obstacle: Vec<u8>,
}

impl CoarseLattice {
    /// Cells of `factor` x `factor` map cells (factor >= 1).
    pub fn new(map: &PreparedMap, factor: usize) -> CoarseLattice {
        assert!(factor >= 1, "a coarse lattice needs a factor of at least 1");
        let fine = map.side();
        let side = fine.div_ceil(factor);
        let stride = side + 2;
        let mut obstacle = vec![1u8; stride * stride];
        for r in 0..side {
            for c in 0..side {
                let free = (r * factor..(r + 1) * factor).all(|fr| {
                    (c * factor..(c + 1) * factor)
                        .all(|fc| map.grid.is_free(fr as isize, fc as isize))
                });
                if free {
                    obstacle[(r + 1) * stride + c + 1] = 0;
                }
            }
        }
        CoarseLattice {
            id: crate::map::prepared::fresh_id(),
            source_id: map.id,
            factor,
            side,
            stride,
            half_extent: map.grid.extent() / 2.0,
            obstacle,
        }
    }

    /// Whether this lattice was built from `map` with `factor`.
    pub fn covers(&self, map: &PreparedMap, factor: usize) -> bool {
        self.source_id == map.id && self.factor == factor
    }

    fn is_free(&self, row: isize, col: isize) -> bool {
        row >= 0
            && col >= 0
            && (row as usize) < self.side
            && (col as usize) < self.side
            && self.obstacle[self.index(row as usize, col as usize)] == 0
    }

    fn index(&self, row: usize, col: usize) -> usize {
        (row + 1) * self.stride + col + 1
    }

    fn centre(&self, row: usize, col: usize) -> [f64; 2] {
        let h = self.cell_size();
        [
            (col as f64 + 0.5) * h - self.half_extent,
            self.half_extent - (row as f64 + 0.5) * h,
        ]
    }
}

impl Lattice for CoarseLattice {
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
        CELL_SIZE * self.factor as f64
    }
    fn locate(&self, p: [f64; 2]) -> Option<(usize, [f64; 2])> {
        let h = self.cell_size();
        let col = ((p[0] + self.half_extent) / h).floor() as isize;
        let row = ((self.half_extent - p[1]) / h).floor() as isize;
        let mut best: Option<(f64, usize, usize)> = None;
        for (dr, dc) in [
            (0, 0),
            (-1, 0),
            (1, 0),
            (0, -1),
            (0, 1),
            (-1, -1),
            (-1, 1),
            (1, -1),
            (1, 1),
        ] {
            let (r, c) = (row + dr, col + dc);
            if !self.is_free(r, c) {
                continue;
            }
            if (dr, dc) == (0, 0) {
                return Some((
                    self.index(r as usize, c as usize),
                    self.centre(r as usize, c as usize),
                ));
            }
            let q = self.centre(r as usize, c as usize);
            let d = (q[0] - p[0]).hypot(q[1] - p[1]);
            if best.is_none_or(|(bd, _, _)| d < bd) {
                best = Some((d, r as usize, c as usize));
            }
        }
        best.map(|(_, r, c)| (self.index(r, c), self.centre(r, c)))
    }

    /// The free cells among the 2 x 2 whose centres surround `p`, so that
    /// arrival times move smoothly with `p`. Started from the one cell
    /// holding it, a front's times would only see where `p` sits in that
    /// cell: moving towards the cell's centre would look best whatever the
    /// direction, and a greedy captor on cells wider than its step would
    /// hover at centres (measured: 3 of 20 captures on small maps at 0.10 m,
    /// against 9 of 12 on the map's own cells). Without a free cell there,
    /// the nearest free neighbour (`locate`).
    fn seeds(&self, p: [f64; 2]) -> Seeds {
        let h = self.cell_size();
        // Continuous cell coordinates, shifted so that floor() gives the
        // top-left cell of the surrounding 2 x 2.
        let x = (p[0] + self.half_extent) / h - 0.5;
        let y = (self.half_extent - p[1]) / h - 0.5;
        let (c0, r0) = (x.floor() as isize, y.floor() as isize);
        let mut seeds = Seeds::default();
        for (dr, dc) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
            let (r, c) = (r0 + dr, c0 + dc);
            if self.is_free(r, c) {
                seeds.push((
                    self.index(r as usize, c as usize),
                    self.centre(r as usize, c as usize),
                ));
            }
        }
        if seeds.as_slice().is_empty() {
            if let Some(s) = self.locate(p) {
                seeds.push(s);
            }
        }
        seeds
    }

    /// Through the start cells around `p`, so that points within one cell
    /// still differ (a greedy captor compares moves shorter than a cell).
    fn distance_at(&self, fm: &FastMarching, p: [f64; 2]) -> f64 {
        self.seeds(p)
            .as_slice()
            .iter()
            .map(|&(cell, c)| fm.time(cell) as f64 + (p[0] - c[0]).hypot(p[1] - c[1]))
            .fold(f64::INFINITY, f64::min)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::asz::Source;
    use crate::map::Grid;

    fn room_with_wall() -> PreparedMap {
        // Two rooms, rows 40..120 and 121..200 over cols 40..200, split by a
        // wall one map cell thick (row 120) with a door at cols 170..190.
        let mut g =
            Grid::with_free_rects("two rooms", 320, &[(40..120, 40..200), (121..200, 40..200)]);
        for c in 170..190 {
            g.set_free(120, c, true);
        }
        PreparedMap::new(g)
    }

    #[test]
    fn a_wall_one_map_cell_thick_stays_a_wall_and_the_door_stays_open() {
        let map = room_with_wall();
        for factor in [2, 3, 4] {
            let coarse = CoarseLattice::new(&map, factor);
            let mut fm = FastMarching::new();
            let a = map.grid.cell_center(60, 60);
            let b = map.grid.cell_center(180, 60);
            // Through the door: about 2 x hypot(60, 110) cells = 12.5 m,
            // where a leak through the wall would give 6 m.
            fm.distance_field(&coarse, a);
            let (cell, _) = coarse.locate(b).unwrap();
            let through_door = fm.time(cell) as f64;
            let straight = (a[1] - b[1]).abs();
            assert!(
                through_door > straight + 5.0,
                "factor {factor}: {through_door} m, the wall leaked (straight {straight} m)"
            );
            let mut fine = FastMarching::new();
            fine.distance_field(&map, a);
            let exact = fine.time(map.padded_index(180, 60)) as f64;
            // The door narrows by less than a coarse cell on each side, and
            // the path bends around thicker walls: a few percent and a
            // couple of coarse cells.
            let cell = coarse.cell_size();
            assert!(
                (through_door - exact).abs() < 0.03 * exact + 2.0 * cell,
                "factor {factor}: {through_door} m against {exact} m on the map's own cells"
            );
        }
    }

    #[test]
    fn coarse_asz_approximates_the_maps_own() {
        let map = PreparedMap::new(Grid::with_free_rects("room", 320, &[(60..260, 60..260)]));
        let captors: Vec<Source> = [(100, 100), (100, 220), (230, 160)]
            .iter()
            .map(|&(r, c)| Source {
                pos: map.grid.cell_center(r, c),
                speed: 1.0,
            })
            .collect();
        let target = Source {
            pos: map.grid.cell_center(150, 150),
            speed: 1.0,
        };
        let mut fm = FastMarching::new();
        let fine = fm.asz_cells(&map, target, &captors) as f64;
        for factor in [2, 3] {
            let coarse = CoarseLattice::new(&map, factor);
            let cells = fm.asz_cells(&coarse, target, &captors) as f64;
            let as_fine = cells * (factor * factor) as f64;
            assert!(
                (as_fine - fine).abs() < 0.05 * fine,
                "factor {factor}: {as_fine} map cells against {fine}"
            );
        }
    }

    #[test]
    fn a_source_in_a_blocked_coarse_cell_starts_from_its_nearest_free_neighbour() {
        let map = PreparedMap::new(Grid::with_free_rects("room", 320, &[(60..260, 61..260)]));
        let coarse = CoarseLattice::new(&map, 2);
        // Map column 61 is free, but coarse column 30 covers map columns 60
        // and 61 and is blocked.
        let p = map.grid.cell_center(101, 61);
        let (cell, centre) = coarse.locate(p).expect("a free neighbour");
        assert_eq!(coarse.obstacle[cell], 0);
        assert!((centre[0] - p[0]).abs() <= 0.1 + 1e-9 && (centre[1] - p[1]).abs() <= 0.1 + 1e-9);
        // Deep inside a wall there is nothing to start from.
        assert!(coarse.locate(map.grid.cell_center(10, 10)).is_none());
    }
}
