//! An observation as the learners' networks read it: the patch max-pooled,
//! and the vector turned into the robot's own frame. The learners pool
//! once per observation, outside the network (`pool_patch`); the
//! egocentric vector is computed inside their networks' first layer (the
//! batched `EgocentricVector` of crates/learners/src/nn/egocentric.rs),
//! and here for one robot, for Python's observation options. A test in
//! the learners crate holds the two equal.

use super::observe::PATCH;

/// Metres by which positions and distances are divided (half the 16 m map).
pub const POSITION_SCALE: f32 = 8.0;

/// Below this distance (m) a bearing is taken at this distance: robots
/// never overlap by that much, and it keeps the division finite.
pub const MIN_DISTANCE: f32 = 1e-3;

/// Max-pools a 48x48 patch by `pool` into `out` ((48 / pool)^2 bytes): a
/// pooled pixel is obstacle if any cell under it is.
pub fn pool_patch(patch: &[u8], pool: usize, out: &mut [u8]) {
    if pool == 1 {
        out.copy_from_slice(patch);
        return;
    }
    let side = PATCH / pool;
    for (r, row) in out.chunks_exact_mut(side).enumerate() {
        row.fill(0);
        for dr in 0..pool {
            let src = &patch[(r * pool + dr) * PATCH..(r * pool + dr + 1) * PATCH];
            for (c, o) in row.iter_mut().enumerate() {
                for &x in &src[c * pool..(c + 1) * pool] {
                    *o |= x;
                }
            }
        }
    }
}

/// Width of the egocentric vector of a robot that sees `others` robots.
pub fn egocentric_width(others: usize) -> usize {
    6 + 9 * others
}

/// One robot's spec vector (5 + 5N numbers: own velocity, position,
/// heading; the others' velocities, offsets, relative headings) in its own
/// frame, into `out` (6 + 9N numbers): own velocity as (forward, left),
/// position / 8 m, sine and cosine of the heading; then, grouped by
/// quantity over the N others: offsets forward / 8 m, offsets left / 8 m,
/// distances / 8 m, bearings' cosines, bearings' sines, velocities
/// forward, velocities left, sines and cosines of their headings relative
/// to ours.
pub fn egocentric_vector(vector: &[f32], out: &mut [f32]) {
    let n = (vector.len() - 5) / 5;
    assert_eq!(vector.len(), 5 + 5 * n, "a spec vector has 5 + 5N numbers");
    assert_eq!(out.len(), egocentric_width(n), "6 + 9N outputs");
    let (cos, sin) = (vector[4].cos(), vector[4].sin());
    // World axes to the robot's (forward, left): forward = (cos, sin), left = (-sin, cos).
    let turn = |x: f32, y: f32| (x * cos + y * sin, y * cos - x * sin);
    let (forward, left) = turn(vector[0], vector[1]);
    out[..6].copy_from_slice(&[
        forward,
        left,
        vector[2] / POSITION_SCALE,
        vector[3] / POSITION_SCALE,
        sin,
        cos,
    ]);
    for j in 0..n {
        let (vx, vy) = (vector[5 + 2 * j], vector[5 + 2 * j + 1]);
        let (ox, oy) = (vector[5 + 2 * n + 2 * j], vector[5 + 2 * n + 2 * j + 1]);
        let heading = vector[5 + 4 * n + j];
        let (off_forward, off_left) = turn(ox, oy);
        let distance = (off_forward * off_forward + off_left * off_left).sqrt();
        let reach = distance.max(MIN_DISTANCE);
        let (vel_forward, vel_left) = turn(vx, vy);
        let values = [
            off_forward / POSITION_SCALE,
            off_left / POSITION_SCALE,
            distance / POSITION_SCALE,
            off_forward / reach,
            off_left / reach,
            vel_forward,
            vel_left,
            heading.sin(),
            heading.cos(),
        ];
        for (q, value) in values.into_iter().enumerate() {
            out[6 + q * n + j] = value;
        }
    }
}
