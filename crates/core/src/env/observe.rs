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
    let Some(at) = PatchAt::of(map, pos, theta) else {
        out.fill(1);
        return;
    };
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: AVX2 is present; the lookups are the per-pixel loop's,
        // which stay inside the padded grid (see there).
        unsafe { patch_rows_avx2(&map.patch_cells, &at, out) };
        return;
    }
    patch_rows(&map.patch_cells, &at, out);
}

/// 16.16 fixed point.
const ONE: f64 = 65536.0;
const HALF: i32 = (PATCH / 2) as i32;
/// Rounds the 16.16 offsets to the nearest cell.
const ROUND: i32 = 1 << 15;
/// Pixels a run of one patch row holds; a run is filled at once when the
/// cells around its middle pixel are all of one kind.
const RUN: usize = 8;
const _: () = assert!(PATCH.is_multiple_of(RUN));
/// The reach that makes a block of `RUN` x `RUN` pixels one value, from
/// its middle pixel's cell (rows and pixels `RUN / 2` before it to
/// `RUN / 2 - 1` after): a pixel lies within (RUN / 2)(|sin| + |cos|) <=
/// 4 sqrt 2 < 5.7 cells of it along either axis, and flooring adds less
/// than a cell.
const BLOCK_REACH: usize = 6;

/// Where a patch samples the padded grid. The robot's cell (index `base`,
/// rows `stride` apart) is pixel (24, 24): the patch reaches 24 cells ahead
/// and to the left, 23 behind and to the right, like a crop [c-24, c+24) of
/// the grid, and axis-aligned headings give integer offsets (no ties).
/// Offsets (in cells) of a patch pixel from the robot's cell centre: with
/// right = b - 24 and forward = 24 - a,
///   column offset = right sin + forward cos, row offset = right cos - forward sin,
/// stepped along each patch row in 16.16 fixed point (`sf`, `cf`: sin and
/// cos; integer adds and shifts, the rounding error stays below 1e-3 cells
/// over a row).
struct PatchAt {
    base: isize,
    stride: isize,
    sf: i32,
    cf: i32,
}

impl PatchAt {
    /// The patch of a robot at `pos` heading `theta`; None off the map,
    /// where the whole patch is obstacle.
    fn of(map: &PreparedMap, pos: [f64; 2], theta: f64) -> Option<PatchAt> {
        let (r0, c0) = map.grid.cell_of(pos);
        let side = map.side() as isize;
        if r0 < 0 || c0 < 0 || r0 >= side || c0 >= side {
            return None;
        }
        Some(PatchAt {
            base: map.padded_index(r0, c0) as isize,
            stride: map.stride as isize,
            sf: (theta.sin() * ONE).round() as i32,
            cf: (theta.cos() * ONE).round() as i32,
        })
    }

    /// The 16.16 offsets (column, row) of pixel 0 of patch row `a`.
    #[inline(always)]
    fn row_start(&self, a: usize) -> (i32, i32) {
        let forward = HALF - a as i32;
        (
            -HALF * self.sf + forward * self.cf + ROUND,
            -HALF * self.cf - forward * self.sf + ROUND,
        )
    }

    /// Index in the padded grid of the cell at 16.16 offsets (dc, dr).
    #[inline(always)]
    fn index(&self, dc: i32, dr: i32) -> usize {
        (self.base + (dr >> 16) as isize * self.stride + (dc >> 16) as isize) as usize
    }
}

/// The patch row by row. A run of `RUN` pixels is one value when the cell
/// of its middle pixel reaches far enough (`reach::kind_and_reach`): a
/// pixel j steps from it lies at most j cells away along either axis (|sin|
/// and |cos| are at most 1 in 16.16, and flooring adds less than a cell),
/// so the run's cells all lie within Chebyshev distance `RUN / 2` of it,
/// and a whole row's within 24 of its pixel 24. Other runs are looked up
/// pixel by pixel. Most of a patch lies inside rooms or inside walls, so
/// most runs need no lookup (on the Gibson maps, about 4 in 5).
fn patch_rows(cells: &[u8], at: &PatchAt, out: &mut [u8]) {
    let (sf, cf) = (at.sf, at.cf);
    // The kind of the cell at pixel j of a row, if every cell within
    // Chebyshev distance `reach` of it is of that kind.
    let uniform = |dc0: i32, dr0: i32, j: i32, reach: usize| {
        let cell = cells[at.index(dc0 + j * sf, dr0 + j * cf)];
        ((cell >> 1) as usize >= reach).then_some(cell & 1)
    };
    for (a, row_out) in out.chunks_exact_mut(PATCH).enumerate() {
        let (dc0, dr0) = at.row_start(a);
        if let Some(kind) = uniform(dc0, dr0, HALF, HALF as usize) {
            row_out.fill(kind);
            continue;
        }
        for (q, run) in row_out.chunks_exact_mut(RUN).enumerate() {
            let j0 = (q * RUN) as i32;
            match uniform(dc0, dr0, j0 + (RUN / 2) as i32, RUN / 2) {
                Some(kind) => run.fill(kind),
                None => lookup_run(cells, at, dc0 + j0 * sf, dr0 + j0 * cf, run),
            }
        }
    }
}

/// Looks up the pixels of `out` one at a time, the first at 16.16 offsets
/// (dc, dr), stepping along the patch row.
fn lookup_run(cells: &[u8], at: &PatchAt, mut dc: i32, mut dr: i32, out: &mut [u8]) {
    for px in out.iter_mut() {
        let idx = at.index(dc, dr);
        debug_assert!(idx < cells.len());
        // SAFETY: the robot's cell is inside the grid and every offset is
        // at most 24 sqrt 2 < 35 cells, inside the PAD = 40 obstacle border.
        *px = unsafe { *cells.get_unchecked(idx) } & 1;
        dc += at.sf;
        dr += at.cf;
    }
}

/// `patch_rows`' runs in AVX2 lanes (the patch was most of an env step
/// with observations): per patch row, one gather reads the middle cells of
/// its six runs and the row is written from their kinds; then each run
/// that was not uniform is one gather of its eight pixels. Deciding the
/// runs in lanes, not one branch per run (a run near a wall is not
/// predictable), and gathering the runs from a list leave one
/// mispredicted branch or so a patch. Integer arithmetic, so the bytes are
/// the scalar loop's.
///
/// # Safety
/// The CPU has AVX2, and `at` is what `write_patch` computes for a robot
/// inside the grid of the map `cells` belongs to.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
// Long on purpose: an AVX2 kernel, whose intrinsics read as one piece
// (load, shift, mask, store per run); helpers would each need
// `#[target_feature]` and `unsafe`, and the data flow would be lost.
unsafe fn patch_rows_avx2(cells: &[u8], at: &PatchAt, out: &mut [u8]) {
    use std::arch::x86_64::*;
    const RUNS: usize = PATCH / RUN;
    const _: () = assert!(RUN == 8 && RUNS == 6);
    // Every index fits an i32: the padded grid has fewer than 2^31 cells.
    debug_assert!(cells.len() < i32::MAX as usize);
    let (sf, cf) = (_mm256_set1_epi32(at.sf), _mm256_set1_epi32(at.cf));
    let (vbase, vstride) = (
        _mm256_set1_epi32(at.base as i32),
        _mm256_set1_epi32(at.stride as i32),
    );
    let index = |dc: __m256i, dr: __m256i| {
        _mm256_add_epi32(
            vbase,
            _mm256_add_epi32(
                _mm256_mullo_epi32(_mm256_srai_epi32::<16>(dr), vstride),
                _mm256_srai_epi32::<16>(dc),
            ),
        )
    };
    // Pixel j of a row in lane j (a run's pixels) and the middle pixel of
    // run l in lane l (lanes 6 and 7 repeat run 5's, so read valid cells).
    let pixels = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    let middles = _mm256_setr_epi32(4, 12, 20, 28, 36, 44, 44, 44);
    let (pixel_dc, pixel_dr) = (
        _mm256_mullo_epi32(pixels, sf),
        _mm256_mullo_epi32(pixels, cf),
    );
    let (middle_dc, middle_dr) = (
        _mm256_mullo_epi32(middles, sf),
        _mm256_mullo_epi32(middles, cf),
    );
    // The low byte of each gathered dword, packed into the first 8 bytes.
    let low_bytes = _mm256_setr_epi8(
        0, 4, 8, 12, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, //
        0, 4, 8, 12, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1,
    );
    let join = _mm256_setr_epi32(0, 4, 1, 1, 1, 1, 1, 1);
    let low_byte_of_each = |words: __m256i| {
        _mm256_castsi256_si128(_mm256_permutevar8x32_epi32(
            _mm256_shuffle_epi8(words, low_bytes),
            join,
        ))
    };
    // Each run's kind (byte l) spread over its eight bytes of the row.
    let spread = [
        _mm_setr_epi8(0, 0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 1, 1, 1, 1),
        _mm_setr_epi8(2, 2, 2, 2, 2, 2, 2, 2, 3, 3, 3, 3, 3, 3, 3, 3),
        _mm_setr_epi8(4, 4, 4, 4, 4, 4, 4, 4, 5, 5, 5, 5, 5, 5, 5, 5),
    ];
    // A cell byte is obstacle bit | reach << 1: reach >= RUN / 2 when the
    // byte is at least RUN, and reach >= BLOCK_REACH when it is at least
    // 2 BLOCK_REACH.
    let below_run = _mm256_set1_epi32(RUN as i32 - 1);
    let below_block = _mm256_set1_epi32(2 * BLOCK_REACH as i32 - 1);
    let (byte, obstacle_bit) = (_mm256_set1_epi32(0xff), _mm256_set1_epi32(1));
    let ptr = cells.as_ptr() as *const i32;
    // The cell bytes at the middle pixels of the runs of row a.
    let middles_of_row = |a: usize| {
        let (dc0, dr0) = at.row_start(a);
        let idx = index(
            _mm256_add_epi32(_mm256_set1_epi32(dc0), middle_dc),
            _mm256_add_epi32(_mm256_set1_epi32(dr0), middle_dr),
        );
        // SAFETY: each index is one the scalar loop reads, and at least
        // 5 rows of padding follow it, so the 4 bytes read stay inside.
        _mm256_and_si256(unsafe { _mm256_i32gather_epi32::<1>(ptr, idx) }, byte)
    };
    // Writes a row from the kinds of its runs (byte l: run l's).
    let write_row = |row_out: &mut [u8], kinds: __m128i| {
        for (k, spread) in spread.iter().enumerate() {
            // SAFETY: the row holds 48 bytes, 16 from 16 k.
            unsafe {
                _mm_storeu_si128(
                    row_out.as_mut_ptr().add(16 * k) as *mut __m128i,
                    _mm_shuffle_epi8(kinds, *spread),
                )
            };
        }
    };
    let all_runs = (1 << RUNS) - 1;
    // Per row, a bit per run to look up. The patch is first taken in
    // blocks of RUN x RUN pixels, whose middle pixels are the runs'
    // middle pixels of the block row's row RUN / 2: a block is one value
    // when that cell reaches `BLOCK_REACH`, and a row of blocks that are
    // all so is written without looking at its rows. In the other block
    // rows, each row's gathers come first, all of them: each row's mask
    // goes to a fixed place, so no store waits on a gather before the
    // next row's gather may start; a run inside a uniform block needs no
    // lookup (its middle pixel's kind is the block's).
    let mut to_look_up = [0u8; PATCH];
    for (b, block_row) in out.chunks_exact_mut(RUN * PATCH).enumerate() {
        let middle = middles_of_row(b * RUN + RUN / 2);
        let blocks_uniform =
            _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpgt_epi32(middle, below_block)))
                & all_runs;
        if blocks_uniform == all_runs {
            let kinds = low_byte_of_each(_mm256_and_si256(middle, obstacle_bit));
            for row_out in block_row.chunks_exact_mut(PATCH) {
                write_row(row_out, kinds);
            }
            continue;
        }
        for (k, row_out) in block_row.chunks_exact_mut(PATCH).enumerate() {
            let middle = middles_of_row(b * RUN + k);
            let uniform =
                _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpgt_epi32(middle, below_run)));
            write_row(
                row_out,
                low_byte_of_each(_mm256_and_si256(middle, obstacle_bit)),
            );
            to_look_up[b * RUN + k] = !(uniform | blocks_uniform) as u8 & all_runs as u8;
        }
    }
    // The runs to look up as a list (row * RUNS + run), so that their loop
    // branches once at its end, not once a row.
    let mut looked_up = [0u16; PATCH * RUNS];
    let mut count = 0;
    for (a, &runs) in to_look_up.iter().enumerate() {
        for run in 0..RUNS {
            looked_up[count] = (a * RUNS + run) as u16;
            count += (runs >> run) as usize & 1;
        }
    }
    for &row_run in &looked_up[..count] {
        let (a, run) = (row_run as usize / RUNS, row_run as usize % RUNS);
        let (dc0, dr0) = at.row_start(a);
        let first = (run * RUN) as i32;
        let idx = index(
            _mm256_add_epi32(_mm256_set1_epi32(dc0 + first * at.sf), pixel_dc),
            _mm256_add_epi32(_mm256_set1_epi32(dr0 + first * at.cf), pixel_dr),
        );
        // SAFETY: as above.
        let words = unsafe { _mm256_i32gather_epi32::<1>(ptr, idx) };
        let bits = _mm_and_si128(low_byte_of_each(words), _mm_set1_epi8(1));
        // SAFETY: `out` holds the patch; this run's 8 bytes start at
        // row a, pixel 8 run.
        unsafe {
            _mm_storel_epi64(
                out.as_mut_ptr().add(a * PATCH + RUN * run) as *mut __m128i,
                bits,
            )
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::{Grid, PreparedMap};
    use rand::{Rng, SeedableRng};

    /// The patch as defined: every pixel looked up in `obstacle` on its own.
    fn patch_by_pixel(map: &PreparedMap, pos: [f64; 2], theta: f64, out: &mut [u8]) {
        let Some(at) = PatchAt::of(map, pos, theta) else {
            out.fill(1);
            return;
        };
        for (a, row_out) in out.chunks_exact_mut(PATCH).enumerate() {
            let (mut dc, mut dr) = at.row_start(a);
            for px in row_out.iter_mut() {
                *px = map.obstacle[at.index(dc, dr)];
                dc += at.sf;
                dr += at.cf;
            }
        }
    }

    /// This CPU's patch and the scalar one (both filling uniform runs
    /// without lookups) are the one-pixel-at-a-time patch, byte for byte,
    /// at any position and heading, near walls, specks and the map's edge.
    #[test]
    fn every_patch_path_writes_the_same_bytes() {
        let mut g = Grid::with_free_rects("rooms", 160, &[(10..150, 10..70), (40..60, 70..150)]);
        for (r, c) in [(30, 30), (31, 31), (100, 20), (50, 100)] {
            g.set_free(r, c, false);
        }
        let map = PreparedMap::new(g);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let mut fast = vec![0u8; PATCH_LEN];
        let mut scalar = vec![0u8; PATCH_LEN];
        let mut want = vec![0u8; PATCH_LEN];
        let half = map.grid.extent() / 2.0;
        let mut uniform_runs = 0;
        for n in 0..5000 {
            let pos = [rng.gen_range(-half..half), rng.gen_range(-half..half)];
            let theta = match n % 5 {
                0 => (n / 5 % 4) as f64 * std::f64::consts::FRAC_PI_2,
                _ => rng.gen_range(0.0..std::f64::consts::TAU),
            };
            write_patch(&map, pos, theta, &mut fast);
            patch_by_pixel(&map, pos, theta, &mut want);
            assert_eq!(fast, want, "pos {pos:?}, theta {theta}");
            let Some(at) = PatchAt::of(&map, pos, theta) else {
                continue;
            };
            patch_rows(&map.patch_cells, &at, &mut scalar);
            assert_eq!(scalar, want, "pos {pos:?}, theta {theta}");
            // Count the runs that can be filled without lookups, so the
            // test shows that the shortcut is taken (and so checked).
            uniform_runs += (0..PATCH)
                .flat_map(|a| (0..PATCH / RUN).map(move |q| (a, q)))
                .filter(|&(a, q)| {
                    let (dc0, dr0) = at.row_start(a);
                    let j = (q * RUN + RUN / 2) as i32;
                    map.patch_cells[at.index(dc0 + j * at.sf, dr0 + j * at.cf)] >> 1 >= 4
                })
                .count();
        }
        assert!(uniform_runs > 5000 * PATCH_LEN / RUN / 4, "{uniform_runs}");
    }
}
