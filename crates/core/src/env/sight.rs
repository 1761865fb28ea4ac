//! Sight: observation options beyond the spec's inputs (not in the paper).
//!
//! The spec's learner sees a 2.4 m obstacle patch and the other robots'
//! positions, while the rule-based robots cast 12 wall rays across the
//! whole 16 m map. `Sight` gives a learner what the rule-based robots
//! read: wall distances along rays in the robot's own frame, out to the
//! map's extent. They are appended to the agent vector, after the spec's
//! 5 + 5N numbers, so a vector with sight is `5 + 5N + wall_rays` long.
//! Off (0 rays) is the spec's observation, byte for byte.

use super::physics::Robot;
use crate::error::ConfigError;
use crate::map::PreparedMap;
use serde::{Deserialize, Serialize};

/// The most rays a robot may cast (every 5 degrees).
pub const MAX_WALL_RAYS: usize = 72;

/// Which extra inputs a robot's observation carries.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Sight {
    /// Wall rays in the robot's frame, evenly spaced from straight ahead
    /// turning left (counter-clockwise); each reads the exact distance to
    /// the first obstacle cell divided by the map's extent (16 m), so 1.0
    /// is "no wall on this map". 0: off; the rule-based robots cast 12.
    pub wall_rays: usize,
}

impl Sight {
    pub const OFF: Sight = Sight { wall_rays: 0 };

    pub fn is_off(&self) -> bool {
        *self == Sight::OFF
    }

    /// Numbers appended to one robot's vector.
    pub fn len(&self) -> usize {
        self.wall_rays
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

    /// A short name for tables and logs: "spec" when off, else "rays12".
    pub fn label(&self) -> String {
        if self.is_off() {
            "spec".into()
        } else {
            format!("rays{}", self.wall_rays)
        }
    }

    /// Writes robot `me`'s sight into `out` (`self.len()` numbers).
    pub fn write(&self, map: &PreparedMap, me: &Robot, out: &mut [f32]) {
        debug_assert_eq!(out.len(), self.len());
        write_wall_rays(map, me.pos, me.theta, out);
    }
}

/// `out.len()` wall distances from `pos`, ray m at heading `theta + 2 pi m /
/// out.len()`, each divided by the map's extent and capped at 1.
pub fn write_wall_rays(map: &PreparedMap, pos: [f64; 2], theta: f64, out: &mut [f32]) {
    let reach = map.long_ray_max();
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
    use crate::map::{Grid, PreparedMap};

    /// A robot in a corridor along x, facing +x: the ray ahead reaches the
    /// far wall, the one to its left (ray n/4) the corridor's side, and the
    /// readings turn with the robot.
    #[test]
    fn rays_read_walls_in_the_robots_frame() {
        // Free cells rows 150..170 (1 m wide), columns 20..300 (14 m long).
        let g = Grid::with_free_rects("corridor", 320, &[(150..170, 20..300)]);
        let map = PreparedMap::new(g);
        let extent = map.long_ray_max();
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

    #[test]
    fn ray_counts_outside_the_range_are_refused_by_name() {
        for bad in [1, 3, MAX_WALL_RAYS + 1] {
            let err = Sight { wall_rays: bad }.validate().unwrap_err().to_string();
            assert!(err.contains("sight.wall_rays"), "{err}");
        }
        for good in [0, 4, 12, MAX_WALL_RAYS] {
            assert!(Sight { wall_rays: good }.validate().is_ok());
        }
    }
}
