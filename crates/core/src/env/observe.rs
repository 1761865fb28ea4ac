//! Observations (spec §5): the agent-related vector and the 48x48 binary
//! obstacle patch, egocentric and rotated so the robot's heading points up.

use super::physics::Robot;
use crate::map::PreparedMap;

/// Side of the obstacle patch in cells (2.4 m).
pub const PATCH: usize = 48;
pub const PATCH_LEN: usize = PATCH * PATCH;

// A rotated patch reaches 24 sqrt 2 < 35 cells from the robot's cell.
const _: () = assert!(crate::map::prepared::PAD >= 35);

/// Writes robot `i`'s vector in the reference's layout: own velocity,
/// position, heading; then the velocities of the other robots (captors in
/// order, then the target; the target's is hidden as zeros), then their
/// positions relative to i, then their headings minus i's. For N other
/// robots: 5 + 2N + 2N + N numbers.
pub fn write_vector(robots: &[Robot], i: usize, target: usize, out: &mut [f32]) {
    let me = &robots[i];
    let others = robots.len() - 1;
    out[0] = me.vel[0] as f32;
    out[1] = me.vel[1] as f32;
    out[2] = me.pos[0] as f32;
    out[3] = me.pos[1] as f32;
    out[4] = me.theta as f32;
    let (vel, rest) = out[5..5 + 5 * others].split_at_mut(2 * others);
    let (rel, heading) = rest.split_at_mut(2 * others);
    let mut k = 0;
    for (j, other) in robots.iter().enumerate() {
        if j == i {
            continue;
        }
        if j != target {
            vel[2 * k] = other.vel[0] as f32;
            vel[2 * k + 1] = other.vel[1] as f32;
        } else {
            vel[2 * k] = 0.0;
            vel[2 * k + 1] = 0.0;
        }
        rel[2 * k] = (other.pos[0] - me.pos[0]) as f32;
        rel[2 * k + 1] = (other.pos[1] - me.pos[1]) as f32;
        heading[k] = (other.theta - me.theta) as f32;
        k += 1;
    }
}

/// Writes the 48x48 patch (1 = obstacle, row 0 ahead of the robot, column 0
/// to its left) centred on the robot's cell: nearest-cell lookup of the
/// rotated square, so it stays binary; outside the map is obstacle.
pub fn write_patch(map: &PreparedMap, pos: [f64; 2], theta: f64, out: &mut [u8]) {
    debug_assert_eq!(out.len(), PATCH_LEN);
    let (r0, c0) = map.grid.cell_of(pos);
    let side = map.side() as isize;
    if r0 < 0 || c0 < 0 || r0 >= side || c0 >= side {
        out.fill(1);
        return;
    }
    let base = map.padded_index(r0, c0) as isize;
    let stride = map.stride as isize;
    // The robot's cell is pixel (24, 24): the patch reaches 24 cells ahead
    // and to the left, 23 behind and to the right, like a crop [c-24, c+24)
    // of the grid, and axis-aligned headings give integer offsets (no ties).
    // Offsets (in cells) of a patch pixel from the robot's cell centre: with
    // right = b - 24 and forward = 24 - a,
    //   column offset = right sin + forward cos, row offset = right cos - forward sin,
    // stepped along each patch row in 16.16 fixed point (integer adds and
    // shifts; the sin/cos rounding error stays below 1e-3 cells over a row).
    const ONE: f64 = 65536.0;
    const ROUND: i32 = 1 << 15;
    let half = (PATCH / 2) as i32;
    let (sf, cf) = (
        (theta.sin() * ONE).round() as i32,
        (theta.cos() * ONE).round() as i32,
    );
    for (a, row_out) in out.chunks_exact_mut(PATCH).enumerate() {
        let forward = half - a as i32;
        let mut dc = -half * sf + forward * cf + ROUND;
        let mut dr = -half * cf - forward * sf + ROUND;
        for px in row_out.iter_mut() {
            let idx = (base + (dr >> 16) as isize * stride + (dc >> 16) as isize) as usize;
            debug_assert!(idx < map.obstacle.len());
            // SAFETY: the robot's cell is inside the grid and every offset is
            // at most 24 sqrt 2 < 35 cells, inside the PAD = 40 obstacle border.
            *px = unsafe { *map.obstacle.get_unchecked(idx) };
            dc += sf;
            dr += cf;
        }
    }
}
