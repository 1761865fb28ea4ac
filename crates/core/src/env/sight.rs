//! Sight: observation options beyond the spec's inputs (not in the paper).
//!
//! The spec's learner sees a 2.4 m obstacle patch and the other robots'
//! positions, while the rule-based robots cast 12 wall rays across the
//! whole 16 m map. `Sight` gives a learner what the rule-based robots
//! read, and more:
//! - wall distances along rays in the robot's own frame, out to a fixed
//!   16 m (`wall_rays`, `WALL_RAY_RANGE_M`);
//! - a coarse north-up map of the whole map (`map_cells` across), with one
//!   channel each for walls, captors, the target and the robot itself, so
//!   a network can learn where rooms, loops and dead ends are.
//!
//! They are appended to the agent vector, after the spec's 5 + 5N numbers:
//! the rays first, then the map channel by channel, row by row (north
//! first). Off (no rays, no map) is the spec's observation, byte for byte.

use super::robot::Robot;
use crate::error::ConfigError;
use crate::map::PreparedMap;
use serde::{Deserialize, Serialize};

/// The most rays a robot may cast (every 5 degrees).
pub const MAX_WALL_RAYS: usize = 72;

/// How far a wall ray reads, in metres; a reading is the distance over this
/// and 1.0 past it. Fixed rather than each map's extent, so that one wall
/// distance reads the same number on every map: a learner trained on 16 m
/// generated maps is tested on Gibson maps of other extents. Checkpoints
/// record it (`wall_ray_range_m` in meta.json).
pub const WALL_RAY_RANGE_M: f64 = 16.0;

/// Coarse map sizes, in cells across the map: 8 (2 m cells on a 16 m map)
/// to 32 (0.5 m cells; 4 x 32 x 32 = 4096 numbers per robot).
pub const MAP_CELLS: std::ops::RangeInclusive<usize> = 8..=32;

/// Channels of the coarse map, in their order in the vector.
pub const MAP_CHANNELS: [&str; 4] = ["walls", "captors", "target", "self"];

/// Which extra inputs a robot's observation carries.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Sight {
    /// Wall rays in the robot's frame, evenly spaced from straight ahead
    /// turning left (counter-clockwise); each reads the exact distance to
    /// the first obstacle cell divided by `WALL_RAY_RANGE_M` (16 m) and
    /// capped at 1, so 1.0 is "no wall within 16 m". 0: off; the
    /// rule-based robots cast 12.
    pub wall_rays: usize,
    /// A north-up map of the whole map, `map_cells` x `map_cells` cells, in
    /// four channels (`MAP_CHANNELS`): the share of the cell that is
    /// obstacle; the number of captors in the cell; 1 where the target is;
    /// 1 where this robot is. 0: off. Left out of the stored config while
    /// 0, so sights written before it existed keep their hashes.
    #[serde(skip_serializing_if = "is_zero")]
    pub map_cells: usize,
}

fn is_zero(x: &usize) -> bool {
    *x == 0
}

impl Sight {
    pub const OFF: Sight = Sight {
        wall_rays: 0,
        map_cells: 0,
    };

    /// `n` wall rays and no map.
    pub const fn rays(n: usize) -> Sight {
        Sight {
            wall_rays: n,
            map_cells: 0,
        }
    }

    pub fn is_off(&self) -> bool {
        *self == Sight::OFF
    }

    /// Numbers appended to one robot's vector.
    pub fn len(&self) -> usize {
        self.wall_rays + self.map_len()
    }

    /// Numbers of the coarse map (all channels).
    pub fn map_len(&self) -> usize {
        MAP_CHANNELS.len() * self.map_cells * self.map_cells
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Checks the settings; the error names the field.
    pub fn validate(&self) -> Result<(), ConfigError> {
        // Fewer than 4 rays leave whole quadrants unseen: not sight.
        if self.wall_rays != 0 && !(4..=MAX_WALL_RAYS).contains(&self.wall_rays) {
            return Err(ConfigError::new(
                "sight.wall_rays",
                self.wall_rays,
                format!("must be 0 (off) or between 4 and {MAX_WALL_RAYS}"),
            ));
        }
        if self.map_cells != 0 && !MAP_CELLS.contains(&self.map_cells) {
            return Err(ConfigError::new(
                "sight.map_cells",
                self.map_cells,
                format!(
                    "must be 0 (off) or between {} and {} (cells across the map)",
                    MAP_CELLS.start(),
                    MAP_CELLS.end()
                ),
            ));
        }
        Ok(())
    }

    /// Refuses two sides' sights that differ where `why` says both read
    /// one env's observations; the error names both fields.
    pub fn check_shared(captors: Sight, target: Sight, why: &str) -> Result<(), ConfigError> {
        if captors == target {
            return Ok(());
        }
        Err(ConfigError::about(
            "captors.net.sight, target.net.sight",
            format!(
                "differ ({} against {}): {why}, so both sides see the same",
                captors.label(),
                target.label()
            ),
        ))
    }

    /// A short name for tables and logs: "spec" when off, else "rays12",
    /// "map16" or "rays12+map16".
    pub fn label(&self) -> String {
        let mut parts = Vec::new();
        if self.wall_rays > 0 {
            parts.push(format!("rays{}", self.wall_rays));
        }
        if self.map_cells > 0 {
            parts.push(format!("map{}", self.map_cells));
        }
        if parts.is_empty() {
            "spec".into()
        } else {
            parts.join("+")
        }
    }

    /// Writes robot `i`'s sight into `out` (`self.len()` numbers); robots
    /// before `target` are captors, `robots[target]` the target.
    pub fn write(
        &self,
        map: &PreparedMap,
        robots: &[Robot],
        i: usize,
        target: usize,
        out: &mut [f32],
    ) {
        debug_assert_eq!(out.len(), self.len());
        let (rays, coarse) = out.split_at_mut(self.wall_rays);
        let me = &robots[i];
        if !rays.is_empty() {
            write_wall_rays(map, me.pos, me.theta, rays);
        }
        if self.map_cells > 0 {
            write_coarse_map(map, robots, i, target, self.map_cells, coarse);
        }
    }
}

/// The coarse map of `write`: `n` x `n` cells over the whole grid, four
/// channels of n * n numbers each (`MAP_CHANNELS`), rows from the top of
/// the map (largest y) down, columns from the left (smallest x), as the
/// grid's own rows and columns.
pub fn write_coarse_map(
    map: &PreparedMap,
    robots: &[Robot],
    i: usize,
    target: usize,
    n: usize,
    out: &mut [f32],
) {
    let cells = n * n;
    debug_assert_eq!(out.len(), MAP_CHANNELS.len() * cells);
    let (walls, robots_out) = out.split_at_mut(cells);
    walls.copy_from_slice(map.coarse_walls(n));
    robots_out.fill(0.0);
    let (captors, rest) = robots_out.split_at_mut(cells);
    let (target_out, me_out) = rest.split_at_mut(cells);
    let side = map.side();
    let cell_of = |p: [f64; 2]| -> usize {
        let (row, col) = map.grid.cell_of(p);
        // Robots are always on the grid; a clamp keeps a rounding at the
        // edge in the border cell. The last coarse cell whose first grid
        // row (`PreparedMap::coarse_walls`: a * side / n) is at most k.
        let to_coarse = |k: isize| ((k.clamp(0, side as isize - 1) as usize + 1) * n - 1) / side;
        to_coarse(row) * n + to_coarse(col)
    };
    for (j, r) in robots.iter().enumerate() {
        let k = cell_of(r.pos);
        if j == target {
            target_out[k] = 1.0;
        } else {
            captors[k] += 1.0;
        }
        if j == i {
            me_out[k] = 1.0;
        }
    }
}

/// `out.len()` wall distances from `pos`, ray m at heading `theta + 2 pi m /
/// out.len()`, each divided by `WALL_RAY_RANGE_M` and capped at 1.
pub fn write_wall_rays(map: &PreparedMap, pos: [f64; 2], theta: f64, out: &mut [f32]) {
    let reach = WALL_RAY_RANGE_M;
    let n = out.len();
    for (m, o) in out.iter_mut().enumerate() {
        let a = theta + std::f64::consts::TAU * m as f64 / n as f64;
        let d = map.ray_distance(pos, [a.cos(), a.sin()], reach);
        *o = (d / reach) as f32;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::env::physics::Robot;
    use crate::map::{Grid, PreparedMap};

    /// A robot in a corridor along x, facing +x: the ray ahead reaches the
    /// far wall, the one to its left (ray n/4) the corridor's side, and the
    /// readings turn with the robot.
    #[test]
    fn rays_read_walls_in_the_robots_frame() {
        // Free cells rows 150..170 (1 m wide), columns 20..300 (14 m long).
        let g = Grid::with_free_rects("corridor", 320, &[(150..170, 20..300)]);
        let map = PreparedMap::new(g);
        let extent = WALL_RAY_RANGE_M;
        // The centre of row 160, column 100 in world coordinates.
        let pos = map.grid.cell_center(160, 100);
        let mut ahead = [0f32; 4];
        write_wall_rays(&map, pos, 0.0, &mut ahead);
        let ends = |k: usize, want: f64| {
            let got = ahead[k] as f64 * extent;
            assert!((got - want).abs() < 0.06, "ray {k}: {got} m, want {want} m");
        };
        // Ahead: columns 100.5 -> 300 is 199.5 cells; behind: to column 20.
        ends(0, 199.5 * 0.05);
        ends(2, 80.5 * 0.05);
        // Left (+y is up, row numbers fall): from row 160.5 to row 150.
        ends(1, 10.5 * 0.05);
        ends(3, 9.5 * 0.05);
        // Turned a quarter left, what was "left" is now "ahead".
        let mut turned = [0f32; 4];
        write_wall_rays(&map, pos, std::f64::consts::FRAC_PI_2, &mut turned);
        for k in 0..4 {
            assert!(
                (turned[k] - ahead[(k + 1) % 4]).abs() < 1e-5,
                "ray {k}: {turned:?} against {ahead:?}"
            );
        }
        assert!(ahead.iter().all(|&x| x > 0.0 && x <= 1.0));
    }

    /// The same wall reads the same number on a 16 m map and a 24 m one,
    /// and a ray with no wall within 16 m reads 1.0 even where a wall lies
    /// beyond: a reading is metres, not a share of the map.
    #[test]
    fn a_wall_ray_reads_metres_whatever_the_maps_extent() {
        // A room 4 m east of the robot's cell on both maps.
        let small = PreparedMap::new(Grid::with_free_rects("16m", 320, &[(100..220, 20..120)]));
        let large = PreparedMap::new(Grid::with_free_rects("24m", 480, &[(100..220, 20..120)]));
        assert!((large.long_ray_max() - 1.5 * small.long_ray_max()).abs() < 1e-9);
        let read = |map: &PreparedMap| {
            let mut rays = [0f32; 4];
            write_wall_rays(map, map.grid.cell_center(160, 40), 0.0, &mut rays);
            rays
        };
        let (a, b) = (read(&small), read(&large));
        for k in 0..4 {
            assert!(
                (a[k] - b[k]).abs() < 1e-6,
                "ray {k}: {a:?} on 16 m, {b:?} on 24 m"
            );
        }
        // East: from column 40.5 to 120 is 79.5 cells, 3.975 m.
        assert!(
            (a[0] as f64 * WALL_RAY_RANGE_M - 79.5 * 0.05).abs() < 0.06,
            "{a:?}"
        );
        // A corridor 20 m long: the ray east sees no wall within 16 m.
        let long = PreparedMap::new(Grid::with_free_rects(
            "corridor",
            480,
            &[(150..170, 10..470)],
        ));
        let mut rays = [0f32; 4];
        write_wall_rays(&long, long.grid.cell_center(160, 20), 0.0, &mut rays);
        assert_eq!(rays[0], 1.0, "{rays:?}");
        assert!(rays[1] < 0.05, "{rays:?}");
    }

    /// A 320-cell map (16 m) whose left half is blocked, on a 16 x 16
    /// coarse map: each coarse cell is 20 x 20 grid cells (1 m).
    #[test]
    fn the_coarse_map_marks_walls_captors_target_and_self_in_grid_order() {
        let g = Grid::with_free_rects("right-half", 320, &[(0..320, 170..320)]);
        let map = PreparedMap::new(g);
        let n = 16;
        let sight = Sight {
            wall_rays: 0,
            map_cells: n,
        };
        let at = |row: usize, col: usize| Robot {
            pos: map.grid.cell_center(row, col),
            ..Robot::default()
        };
        // Two captors share coarse cell (2, 10), a third at (15, 15); the
        // target at (0, 12).
        let robots = [at(45, 205), at(50, 210), at(310, 310), at(5, 245)];
        let mut out = vec![0f32; sight.len()];
        sight.write(&map, &robots, 1, 3, &mut out);
        let cells = n * n;
        let (walls, rest) = out.split_at(cells);
        let (captors, rest) = rest.split_at(cells);
        let (target, me) = rest.split_at(cells);
        // Columns 0..160 (coarse 0..8) are walls, 160..170 half (coarse 8),
        // 170.. free.
        for a in 0..n {
            assert_eq!(walls[a * n + 7], 1.0);
            assert_eq!(walls[a * n + 8], 0.5);
            assert_eq!(walls[a * n + 9], 0.0);
        }
        assert_eq!(captors[2 * n + 10], 2.0);
        assert_eq!(captors[15 * n + 15], 1.0);
        assert_eq!(captors.iter().sum::<f32>(), 3.0);
        assert_eq!(target[12], 1.0);
        assert_eq!(target.iter().sum::<f32>(), 1.0);
        assert_eq!(me[2 * n + 10], 1.0);
        assert_eq!(me.iter().sum::<f32>(), 1.0);
        // The target's own view: "self" is where the target is.
        sight.write(&map, &robots, 3, 3, &mut out);
        assert_eq!(out[3 * cells + 12], 1.0);
        assert_eq!(sight.label(), "map16");
        assert_eq!(
            Sight {
                wall_rays: 12,
                ..sight
            }
            .label(),
            "rays12+map16"
        );
    }

    /// A side the coarse map does not divide: every grid cell belongs to
    /// exactly one coarse cell, and a robot lands in the cell whose walls
    /// it stands among.
    #[test]
    fn uneven_coarse_cells_cover_the_grid_once() {
        let g = Grid::with_free_rects("corner", 30, &[(0..30, 0..30)]);
        let map = PreparedMap::new(g);
        let n = 8;
        let walls = map.coarse_walls(n);
        assert!(walls.iter().all(|&w| w == 0.0));
        let sight = Sight {
            wall_rays: 0,
            map_cells: n,
        };
        let mut seen = vec![0usize; n];
        for k in 0..30 {
            let robots = [Robot {
                pos: map.grid.cell_center(k, k),
                ..Robot::default()
            }];
            let mut out = vec![0f32; sight.len()];
            sight.write(&map, &robots, 0, 0, &mut out);
            let cell = out[3 * n * n..].iter().position(|&x| x == 1.0).unwrap();
            let (a, b) = (cell / n, cell % n);
            assert_eq!(a, b);
            assert!(
                a * 30 / n <= k && k < (a + 1) * 30 / n,
                "row {k} in coarse {a}"
            );
            seen[a] += 1;
        }
        assert!(seen.iter().all(|&c| c >= 3), "{seen:?}");
    }

    #[test]
    fn ray_counts_outside_the_range_are_refused_by_name() {
        for bad in [1, 3, MAX_WALL_RAYS + 1] {
            let err = Sight::rays(bad).validate().unwrap_err().to_string();
            assert!(err.contains("sight.wall_rays"), "{err}");
        }
        for good in [0, 4, 12, MAX_WALL_RAYS] {
            assert!(Sight::rays(good).validate().is_ok());
        }
    }

    #[test]
    fn map_sizes_outside_the_range_are_refused_by_name() {
        for bad in [1, 7, 33] {
            let sight = Sight {
                map_cells: bad,
                ..Sight::OFF
            };
            let err = sight.validate().unwrap_err().to_string();
            assert!(err.contains("sight.map_cells"), "{err}");
        }
        for good in [0, 8, 16, 32] {
            let sight = Sight {
                map_cells: good,
                ..Sight::OFF
            };
            assert!(sight.validate().is_ok());
            assert_eq!(sight.len(), 4 * good * good);
        }
    }

    /// Sights stored before the map existed read as they were, and a
    /// sight without a map is stored as it was: a checkpoint's hash holds.
    #[test]
    fn a_sight_without_a_map_is_stored_as_before() {
        let old: Sight = serde_json::from_str(r#"{"wall_rays":12}"#).unwrap();
        assert_eq!(old, Sight::rays(12));
        assert_eq!(
            serde_json::to_string(&Sight::rays(12)).unwrap(),
            r#"{"wall_rays":12}"#
        );
    }
}
