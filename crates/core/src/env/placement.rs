//! Initial placement (spec §4), drawn from the episode's seed with a bounded
//! number of tries.

use super::physics::{dist, Robot};
use crate::map::PreparedMap;
use rand::Rng;

pub const MIN_GAP: f64 = 1.0;
pub const CAPTOR_SPREAD: f64 = 4.0;
pub const TARGET_MAX_DIST: f64 = 10.0;
/// Attempts at a whole placement before giving up.
const RESTARTS: usize = 200;
/// Draws per robot within one attempt.
const DRAWS: usize = 200;

#[derive(Debug, thiserror::Error)]
#[error("map {map}: no valid initial placement for {captors} captors and a target after {RESTARTS} attempts ({reason})")]
pub struct PlacementError {
    pub map: String,
    pub captors: usize,
    pub reason: String,
}

/// Captors first, each at least 1 m from every robot already placed and all
/// within 4 m of each other; then the target, 1 m to 10 m from every captor.
/// Centres are cell centres of free cells that stay free after dilating the
/// obstacles by 0.4 m; headings uniform, velocities zero.
pub fn place<R: Rng>(
    map: &PreparedMap,
    num_captors: usize,
    rng: &mut R,
) -> Result<Vec<Robot>, PlacementError> {
    let fail = |reason: &str| PlacementError {
        map: map.grid.name.clone(),
        captors: num_captors,
        reason: reason.into(),
    };
    if map.spawn_cells.is_empty() {
        return Err(fail("no free cell is 0.4 m away from every obstacle"));
    }
    let side = map.side();
    let draw = |rng: &mut R| {
        let cell = map.spawn_cells[rng.gen_range(0..map.spawn_cells.len())] as usize;
        map.grid.cell_center(cell / side, cell % side)
    };
    let mut positions: Vec<[f64; 2]> = Vec::with_capacity(num_captors + 1);
    'attempt: for _ in 0..RESTARTS {
        positions.clear();
        for _ in 0..num_captors {
            let found = (0..DRAWS).map(|_| draw(rng)).find(|p| {
                positions.iter().all(|q| {
                    let d = dist(*p, *q);
                    (MIN_GAP..=CAPTOR_SPREAD).contains(&d)
                })
            });
            match found {
                Some(p) => positions.push(p),
                None => continue 'attempt,
            }
        }
        let target = (0..DRAWS).map(|_| draw(rng)).find(|p| {
            positions.iter().all(|q| {
                let d = dist(*p, *q);
                (MIN_GAP..=TARGET_MAX_DIST).contains(&d)
            })
        });
        if let Some(t) = target {
            positions.push(t);
            return Ok(positions
                .iter()
                .map(|&pos| Robot {
                    pos,
                    vel: [0.0, 0.0],
                    theta: rng.gen_range(0.0..std::f64::consts::TAU),
                    collided: false,
                })
                .collect());
        }
    }
    Err(fail(
        "the placeable area is too small or too fragmented for these distances",
    ))
}
