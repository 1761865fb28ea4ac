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
    let (sf, cf) = (
        (theta.sin() * ONE).round() as i32,
        (theta.cos() * ONE).round() as i32,
    );
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: AVX2 is present; the lookups are the scalar loop's, which
        // stay inside the padded grid (see there).
        unsafe { patch_rows_avx2(&map.obstacle, base, stride, sf, cf, out) };
        return;
    }
    patch_rows(&map.obstacle, base, stride, sf, cf, out);
}

const HALF: i32 = (PATCH / 2) as i32;
/// Rounds the 16.16 offsets to the nearest cell.
const ROUND: i32 = 1 << 15;

/// The patch's pixels one at a time.
fn patch_rows(obstacle: &[u8], base: isize, stride: isize, sf: i32, cf: i32, out: &mut [u8]) {
    for (a, row_out) in out.chunks_exact_mut(PATCH).enumerate() {
        let forward = HALF - a as i32;
        let mut dc = -HALF * sf + forward * cf + ROUND;
        let mut dr = -HALF * cf - forward * sf + ROUND;
        for px in row_out.iter_mut() {
            let idx = (base + (dr >> 16) as isize * stride + (dc >> 16) as isize) as usize;
            debug_assert!(idx < obstacle.len());
            // SAFETY: the robot's cell is inside the grid and every offset is
            // at most 24 sqrt 2 < 35 cells, inside the PAD = 40 obstacle border.
            *px = unsafe { *obstacle.get_unchecked(idx) };
            dc += sf;
            dr += cf;
        }
    }
}

/// The same pixels, eight at a time: the offsets in AVX2 lanes and one
/// gather per eight lookups (the patch was most of an env step with
/// observations). Integer arithmetic, so the bytes are the scalar loop's.
///
/// # Safety
/// The CPU has AVX2, and `base`, `stride` are those `write_patch` computes
/// for a robot inside the grid of the map `obstacle` belongs to.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn patch_rows_avx2(
    obstacle: &[u8],
    base: isize,
    stride: isize,
    sf: i32,
    cf: i32,
    out: &mut [u8],
) {
    use std::arch::x86_64::*;
    const _: () = assert!(PATCH % 8 == 0);
    // Every index fits an i32: the padded grid has fewer than 2^31 cells.
    debug_assert!(obstacle.len() < i32::MAX as usize);
    let lanes = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    let lane_dc = _mm256_mullo_epi32(lanes, _mm256_set1_epi32(sf));
    let lane_dr = _mm256_mullo_epi32(lanes, _mm256_set1_epi32(cf));
    let (step_dc, step_dr) = (_mm256_set1_epi32(8 * sf), _mm256_set1_epi32(8 * cf));
    let (vbase, vstride) = (
        _mm256_set1_epi32(base as i32),
        _mm256_set1_epi32(stride as i32),
    );
    // The low byte of each gathered dword, packed into the first 8 bytes.
    let low_bytes = _mm256_setr_epi8(
        0, 4, 8, 12, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, //
        0, 4, 8, 12, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1,
    );
    let join = _mm256_setr_epi32(0, 4, 1, 1, 1, 1, 1, 1);
    let ptr = obstacle.as_ptr() as *const i32;
    for (a, row_out) in out.chunks_exact_mut(PATCH).enumerate() {
        let forward = HALF - a as i32;
        let mut dc = _mm256_add_epi32(
            _mm256_set1_epi32(-HALF * sf + forward * cf + ROUND),
            lane_dc,
        );
        let mut dr = _mm256_add_epi32(
            _mm256_set1_epi32(-HALF * cf - forward * sf + ROUND),
            lane_dr,
        );
        for chunk in row_out.chunks_exact_mut(8) {
            let idx = _mm256_add_epi32(
                vbase,
                _mm256_add_epi32(
                    _mm256_mullo_epi32(_mm256_srai_epi32::<16>(dr), vstride),
                    _mm256_srai_epi32::<16>(dc),
                ),
            );
            // SAFETY: each index is one the scalar loop reads, and at least
            // 5 rows of padding follow it, so the 4 bytes read stay inside.
            let words = unsafe { _mm256_i32gather_epi32::<1>(ptr, idx) };
            let packed = _mm256_permutevar8x32_epi32(_mm256_shuffle_epi8(words, low_bytes), join);
            // SAFETY: `chunk` holds 8 bytes.
            unsafe {
                _mm_storel_epi64(
                    chunk.as_mut_ptr() as *mut __m128i,
                    _mm256_castsi256_si128(packed),
                )
            };
            dc = _mm256_add_epi32(dc, step_dc);
            dr = _mm256_add_epi32(dr, step_dr);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::{Grid, PreparedMap};
    use rand::{Rng, SeedableRng};

    /// The vectorised patch is the one-pixel-at-a-time patch, byte for byte,
    /// at any position and heading (this CPU's path against the scalar one).
    #[test]
    fn every_patch_path_writes_the_same_bytes() {
        let mut g = Grid::with_free_rects("rooms", 160, &[(10..150, 10..70), (40..60, 70..150)]);
        for (r, c) in [(30, 30), (31, 31), (100, 20), (50, 100)] {
            g.set_free(r, c, false);
        }
        let map = PreparedMap::new(g);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let (mut fast, mut slow) = (vec![0u8; PATCH_LEN], vec![0u8; PATCH_LEN]);
        let half = map.grid.extent() / 2.0;
        for n in 0..5000 {
            let pos = [rng.gen_range(-half..half), rng.gen_range(-half..half)];
            let theta = match n % 5 {
                0 => (n / 5 % 4) as f64 * std::f64::consts::FRAC_PI_2,
                _ => rng.gen_range(0.0..std::f64::consts::TAU),
            };
            write_patch(&map, pos, theta, &mut fast);
            let (r0, c0) = map.grid.cell_of(pos);
            let side = map.side() as isize;
            if r0 < 0 || c0 < 0 || r0 >= side || c0 >= side {
                assert!(fast.iter().all(|&b| b == 1));
                continue;
            }
            let base = map.padded_index(r0, c0) as isize;
            let (sf, cf) = (
                (theta.sin() * 65536.0).round() as i32,
                (theta.cos() * 65536.0).round() as i32,
            );
            patch_rows(&map.obstacle, base, map.stride as isize, sf, cf, &mut slow);
            assert_eq!(fast, slow, "pos {pos:?}, theta {theta}");
        }
    }
}
