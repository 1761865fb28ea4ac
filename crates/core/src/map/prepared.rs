//! Per-map precomputation, so that an environment step does no ray marching
//! over long distances: an obstacle-padded copy of the grid (patch lookups need
//! no bounds checks), the clearance of every cell (Euclidean distance
//! transform), and the cells where robots may be placed. The rule-based
//! robots' long wall rays (spec §7) are sampled per query; a table per ray
//! (`RaySteps`) lets them skip samples that cannot be in an obstacle.

use super::grid::{floor_isize, Grid, CELL_SIZE};
use super::ray_steps::{RaySteps, IN_OBSTACLE, MAX_STEP};
pub use super::rays::{ray_dirs, NUM_RAYS, WALL_RAY_STEP};
use std::sync::OnceLock;

/// Obstacle border around the grid in the padded copy; covers the corner of a
/// rotated 48x48 patch (24 * sqrt 2 < 34 cells) and short rays.
pub const PAD: usize = 40;
/// Dilation radius for placement (spec §4).
pub const PLACEMENT_CLEARANCE: f64 = 0.4;
/// Half the diagonal of a cell: how far a point can be from its cell centre.
const HALF_DIAG: f64 = CELL_SIZE * std::f64::consts::SQRT_2 / 2.0;
// A grid cell's squares moved up to the longest skip along a wall ray (2
// cells a sample), widened by a cell, stay inside the padding.
const _: () = assert!(MAX_STEP * 2 + 2 <= PAD);

pub struct PreparedMap {
    pub grid: Grid,
    /// Row stride of `obstacle`.
    pub stride: usize,
    /// (side + 2 PAD)^2 cells, 1 = obstacle; the grid sits at offset (PAD, PAD).
    pub obstacle: Vec<u8>,
    /// Per padded cell, like `obstacle`: its obstacle bit (bit 0) and how
    /// far around it every cell is of its kind (bits 1..=7,
    /// `reach::kind_and_reach`), so the patch fills runs without lookups.
    pub patch_cells: Vec<u8>,
    /// Per grid cell: distance (m) from its centre to the nearest obstacle cell centre.
    pub clearance: Vec<f32>,
    /// Grid indices of free cells whose centre is more than 0.4 m from any obstacle.
    pub spawn_cells: Vec<u32>,
    /// Per world ray and cell: how many wall-ray samples a ray may skip
    /// after a sample in the cell (`RaySteps`).
    ray_steps: RaySteps,
    /// Unique per prepared map, so reusable buffers know when the map changed.
    pub id: u64,
    /// Per coarse-map size n (index n, up to `MAX_COARSE`): the share of
    /// obstacle cells in each of n x n coarse cells, row-major from the
    /// grid's first row. Made on first use: the map is static, and most
    /// runs never ask.
    coarse_walls: [OnceLock<Box<[f32]>>; MAX_COARSE + 1],
}

/// The largest coarse map `coarse_walls` makes.
pub const MAX_COARSE: usize = 64;

static NEXT_MAP_ID: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

/// A new id from the counter prepared maps draw theirs from, for other
/// structures that reusable buffers key on (`asz::CoarseLattice`).
pub fn fresh_id() -> u64 {
    NEXT_MAP_ID.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}

impl PreparedMap {
    pub fn new(grid: Grid) -> PreparedMap {
        let side = grid.side();
        let stride = side + 2 * PAD;
        let mut obstacle = vec![1u8; stride * stride];
        for r in 0..side {
            for c in 0..side {
                if grid.is_free(r as isize, c as isize) {
                    obstacle[(r + PAD) * stride + c + PAD] = 0;
                }
            }
        }
        let edt = squared_edt(&obstacle, stride);
        let clearance: Vec<f32> = (0..side * side)
            .map(|i| {
                let (r, c) = (i / side, i % side);
                (edt[(r + PAD) * stride + c + PAD] as f64).sqrt() as f32 * CELL_SIZE as f32
            })
            .collect();
        let spawn_cells = (0..side * side)
            .filter(|&i| clearance[i] as f64 > PLACEMENT_CLEARANCE + 1e-9)
            .map(|i| i as u32)
            .collect();
        let ray_steps = RaySteps::new(&obstacle, stride, PAD);
        let patch_cells = super::reach::kind_and_reach(&obstacle, stride);
        PreparedMap {
            grid,
            stride,
            obstacle,
            patch_cells,
            clearance,
            spawn_cells,
            ray_steps,
            id: fresh_id(),
            coarse_walls: std::array::from_fn(|_| OnceLock::new()),
        }
    }

    /// The share of obstacle cells in each of `n` x `n` coarse cells over
    /// the grid, row-major from the grid's first row; coarse cell (a, b)
    /// holds grid rows `a * side / n .. (a + 1) * side / n` (and likewise
    /// columns), so a side that n does not divide is still covered once.
    pub fn coarse_walls(&self, n: usize) -> &[f32] {
        assert!(
            (1..=MAX_COARSE).contains(&n),
            "coarse map of {n} cells (1..={MAX_COARSE})"
        );
        self.coarse_walls[n].get_or_init(|| {
            let side = self.side();
            let bound = |k: usize| k * side / n;
            let mut out = vec![0f32; n * n];
            for a in 0..n {
                for b in 0..n {
                    let (rows, cols) = (bound(a)..bound(a + 1), bound(b)..bound(b + 1));
                    let total = rows.len() * cols.len();
                    let blocked = rows
                        .flat_map(|r| cols.clone().map(move |c| (r, c)))
                        .filter(|&(r, c)| !self.grid.is_free(r as isize, c as isize))
                        .count();
                    out[a * n + b] = if total == 0 {
                        1.0
                    } else {
                        blocked as f32 / total as f32
                    };
                }
            }
            out.into_boxed_slice()
        })
    }

    pub fn side(&self) -> usize {
        self.grid.side()
    }

    /// How far the rule-based robots' wall rays search: the map's side D in
    /// metres (spec §7; 16 m on a 320-cell grid).
    pub fn long_ray_max(&self) -> f64 {
        self.grid.extent()
    }

    /// Index into `obstacle` of grid cell (row, col); valid for rows and
    /// columns within PAD of the grid.
    #[inline]
    pub fn padded_index(&self, row: isize, col: isize) -> usize {
        ((row + PAD as isize) as usize) * self.stride + (col + PAD as isize) as usize
    }

    #[inline]
    fn blocked(&self, row: isize, col: isize) -> bool {
        let lim = (self.side() + PAD) as isize;
        if row < -(PAD as isize) || col < -(PAD as isize) || row >= lim || col >= lim {
            return true;
        }
        self.obstacle[self.padded_index(row, col)] != 0
    }

    /// Clearance (m) of the cell holding `p`; zero outside the grid.
    #[inline]
    pub fn clearance_at(&self, p: [f64; 2]) -> f64 {
        let (r, c) = self.grid.cell_of(p);
        let side = self.side() as isize;
        if r < 0 || c < 0 || r >= side || c >= side {
            return 0.0;
        }
        self.clearance[r as usize * self.side() + c as usize] as f64
    }

    /// Does a disc of radius `radius` at `p` touch an obstacle cell (or leave
    /// the grid)? Exact test of the whole disc against the cell squares.
    pub fn disc_touches_obstacle(&self, p: [f64; 2], radius: f64) -> bool {
        if self.clearance_at(p) >= radius + 2.0 * HALF_DIAG {
            return false;
        }
        let (x, y) = self.grid.to_cell_coords(p);
        let rr = radius / CELL_SIZE;
        let (r0, r1) = (floor_isize(y - rr), floor_isize(y + rr));
        let (c0, c1) = (floor_isize(x - rr), floor_isize(x + rr));
        for row in r0..=r1 {
            let dy = (row as f64 - y).max(0.0).max(y - (row + 1) as f64);
            for col in c0..=c1 {
                if !self.blocked(row, col) {
                    continue;
                }
                let dx = (col as f64 - x).max(0.0).max(x - (col + 1) as f64);
                if dx * dx + dy * dy < rr * rr {
                    return true;
                }
            }
        }
        false
    }

    /// Exact distance (m) from `p` along unit world direction `dir` to the
    /// first obstacle cell (grid traversal), capped at `max`.
    pub fn ray_distance(&self, p: [f64; 2], dir: [f64; 2], max: f64) -> f64 {
        let (x, y) = self.grid.to_cell_coords(p);
        let (dx, dy) = (dir[0], -dir[1]);
        let (mut col, mut row) = (floor_isize(x), floor_isize(y));
        if self.blocked(row, col) {
            return 0.0;
        }
        let axis = |pos: f64, cell: isize, d: f64| -> (isize, f64, f64) {
            if d > 0.0 {
                (1, ((cell + 1) as f64 - pos) / d, 1.0 / d)
            } else if d < 0.0 {
                (-1, (pos - cell as f64) / -d, -1.0 / d)
            } else {
                (0, f64::INFINITY, f64::INFINITY)
            }
        };
        let (step_c, mut t_c, dt_c) = axis(x, col, dx);
        let (step_r, mut t_r, dt_r) = axis(y, row, dy);
        let max_cells = max / CELL_SIZE;
        loop {
            let t = if t_c < t_r {
                col += step_c;
                t_c += dt_c;
                t_c - dt_c
            } else {
                row += step_r;
                t_r += dt_r;
                t_r - dt_r
            };
            if t >= max_cells {
                return max;
            }
            if self.blocked(row, col) {
                return t * CELL_SIZE;
            }
        }
    }

    /// The rule-based robots' wall distance d_m of spec §7 along world ray
    /// `m` (`ray_dirs()[m]`): sample `p + s dir` at s = 0.1, 0.2, ... m up to
    /// `max`; the first sample inside an obstacle cell (or outside the grid)
    /// gives d_m = s, and d_m = `max` if none is. Being sampled, it depends
    /// on `p` itself, not only on its cell, and can step over an obstacle
    /// corner thinner than the step: that is the definition the reference's
    /// robots follow, so it is kept exactly. Only samples that provably lie
    /// in free cells are skipped (`RaySteps`).
    pub fn stepped_wall_distance(&self, p: [f64; 2], m: usize, max: f64) -> f64 {
        let samples = wall_ray_samples(max);
        let mut k = 1;
        while k <= samples {
            match self.wall_ray_sample(p, m, k) {
                Some(step) => k += step,
                None => return k as f64 * WALL_RAY_STEP,
            }
        }
        max
    }

    /// `stepped_wall_distance` of every world ray (`ray_dirs()` order),
    /// the rays advanced in turn, one sample each: every sample waits on
    /// the table entry of its ray's last one, so one ray at a time would
    /// spend most of its time waiting, while twelve rays' samples do not
    /// wait on each other.
    pub fn stepped_wall_distances(&self, p: [f64; 2], max: f64) -> [f64; NUM_RAYS] {
        let samples = wall_ray_samples(max);
        let mut d = [max; NUM_RAYS];
        let mut k = [1; NUM_RAYS];
        let mut pending: u32 = (1 << NUM_RAYS) - 1;
        while pending != 0 {
            for m in 0..NUM_RAYS {
                if pending & 1 << m == 0 {
                    continue;
                }
                if k[m] > samples {
                    pending &= !(1 << m);
                    continue;
                }
                match self.wall_ray_sample(p, m, k[m]) {
                    Some(step) => k[m] += step,
                    None => {
                        d[m] = k[m] as f64 * WALL_RAY_STEP;
                        pending &= !(1 << m);
                    }
                }
            }
        }
        d
    }

    /// Sample k of wall ray m from `p`: None when it lies in an obstacle
    /// cell or outside the padded grid, else the step to the next sample
    /// that could lie in one.
    #[inline(always)]
    fn wall_ray_sample(&self, p: [f64; 2], m: usize, k: usize) -> Option<usize> {
        let dir = ray_dirs()[m];
        let s = k as f64 * WALL_RAY_STEP;
        let q = [p[0] + s * dir[0], p[1] + s * dir[1]];
        let (row, col) = self.grid.cell_of(q);
        let lim = (self.side() + PAD) as isize;
        if row < -(PAD as isize) || col < -(PAD as isize) || row >= lim || col >= lim {
            return None;
        }
        // One load says both whether the sample is in an obstacle and
        // which sample could be the next one in an obstacle.
        let step = self.ray_steps.step(m, self.padded_index(row, col));
        (step != IN_OBSTACLE).then_some(step as usize)
    }

    /// `stepped_wall_distance` testing every sample (the definition itself,
    /// for tests and for checking the skipping).
    pub fn stepped_wall_distance_naive(&self, p: [f64; 2], m: usize, max: f64) -> f64 {
        let dir = ray_dirs()[m];
        let samples = wall_ray_samples(max);
        for k in 1..=samples {
            let s = k as f64 * WALL_RAY_STEP;
            let (row, col) = self.grid.cell_of([p[0] + s * dir[0], p[1] + s * dir[1]]);
            if self.blocked(row, col) {
                return s;
            }
        }
        max
    }
}

/// How many wall-ray samples lie within `max` metres.
fn wall_ray_samples(max: f64) -> usize {
    (max / WALL_RAY_STEP + 1e-9).floor() as usize
}

/// Squared Euclidean distance (in cells) from every cell centre to the nearest
/// obstacle cell centre (Felzenszwalb & Huttenlocher, two 1-D passes).
fn squared_edt(obstacle: &[u8], stride: usize) -> Vec<f32> {
    const INF: f32 = 1e20;
    let n = stride;
    let mut grid: Vec<f32> = obstacle
        .iter()
        .map(|&o| if o != 0 { 0.0 } else { INF })
        .collect();
    let mut f = vec![0f32; n];
    let mut d = vec![0f32; n];
    let mut v = vec![0usize; n];
    let mut z = vec![0f32; n + 1];
    let mut pass = |get: &mut dyn FnMut(usize) -> f32, f: &mut Vec<f32>, d: &mut Vec<f32>| {
        for (q, fq) in f.iter_mut().enumerate() {
            *fq = get(q);
        }
        let mut k = 0usize;
        v[0] = 0;
        z[0] = -INF;
        z[1] = INF;
        for q in 1..n {
            loop {
                let p = v[k];
                let s = ((f[q] + (q * q) as f32) - (f[p] + (p * p) as f32))
                    / (2.0 * q as f32 - 2.0 * p as f32);
                if s <= z[k] && k > 0 {
                    k -= 1;
                    continue;
                }
                if s <= z[k] {
                    // k == 0: the new parabola replaces the first one.
                    v[0] = q;
                    z[0] = -INF;
                    z[1] = INF;
                } else {
                    k += 1;
                    v[k] = q;
                    z[k] = s;
                    z[k + 1] = INF;
                }
                break;
            }
        }
        k = 0;
        for (q, dq) in d.iter_mut().enumerate() {
            while z[k + 1] < q as f32 {
                k += 1;
            }
            let p = v[k];
            *dq = (q as f32 - p as f32).powi(2) + f[p];
        }
    };
    for c in 0..n {
        pass(&mut |r| grid[r * n + c], &mut f, &mut d);
        for r in 0..n {
            grid[r * n + c] = d[r];
        }
    }
    for r in 0..n {
        pass(&mut |c| grid[r * n + c], &mut f, &mut d);
        grid[r * n..(r + 1) * n].copy_from_slice(&d);
    }
    grid
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Free rectangle rows r0..r1, cols c0..c1 of a 320-cell grid.
    fn room(r0: usize, r1: usize, c0: usize, c1: usize) -> Grid {
        Grid::with_free_rects("room", 320, &[(r0..r1, c0..c1)])
    }

    #[test]
    fn clearance_matches_brute_force() {
        let mut g = room(100, 140, 100, 160);
        g.set_free(120, 130, false);
        let m = PreparedMap::new(g.clone());
        for &(r, c) in &[
            (101usize, 101usize),
            (120, 131),
            (110, 150),
            (139, 159),
            (125, 125),
        ] {
            let mut best = f64::INFINITY;
            for rr in 0..320 {
                for cc in 0..320 {
                    if !g.is_free(rr, cc) {
                        let d = ((rr - r as isize).pow(2) + (cc - c as isize).pow(2)) as f64;
                        best = best.min(d.sqrt() * CELL_SIZE);
                    }
                }
            }
            let got = m.clearance[r * 320 + c] as f64;
            assert!((got - best).abs() < 1e-5, "({r},{c}): {got} vs {best}");
        }
    }

    #[test]
    fn rays_hit_walls_at_the_right_distance() {
        // Free rows 100..140, cols 100..160: the room spans x in [-3, 0], y in [1, 3].
        let m = PreparedMap::new(room(100, 140, 100, 160));
        let dirs = ray_dirs();
        let p = [-1.0, 2.0];
        let d = m.ray_distance(p, dirs[0], 16.0);
        assert!((d - 1.0).abs() < 1e-9);
        let d = m.ray_distance(p, dirs[3], 16.0); // straight up to y = 3
        assert!((d - 1.0).abs() < 1e-9);
        let d = m.ray_distance(p, dirs[1], 16.0); // 30 deg: x hits 0 at 1/cos30 = 1.1547, y at 3 after 2
        assert!((d - 1.0 / 30f64.to_radians().cos()).abs() < 1e-9);
        assert_eq!(m.ray_distance(p, dirs[0], 0.4), 0.4);
    }

    #[test]
    fn stepped_rays_take_the_first_sample_inside_an_obstacle() {
        // The room spans x in [-3, 0], y in [1, 3].
        let m = PreparedMap::new(room(100, 140, 100, 160));
        let dirs = ray_dirs();
        // East from x = -1.03: samples at -0.93, ..., -0.03 are free, 0.07 is not.
        let d = m.stepped_wall_distance([-1.03, 2.0], 0, 16.0);
        assert!((d - 1.1).abs() < 1e-12, "{d}");
        // The exact distance is 1.03; the stepped one rounds up to the next sample.
        assert!((m.ray_distance([-1.03, 2.0], dirs[0], 16.0) - 1.03).abs() < 1e-9);
        // Moving the robot 0.02 m inside its cell changes the answer: 1.01 -> 1.1, 0.99 -> 1.0.
        let d = m.stepped_wall_distance([-0.99, 2.0], 0, 16.0);
        assert!((d - 1.0).abs() < 1e-12, "{d}");
        // Nothing within the limit: D.
        assert_eq!(m.stepped_wall_distance([-1.03, 2.0], 0, 0.5), 0.5);
    }

    #[test]
    fn skipping_samples_never_changes_a_stepped_ray() {
        use rand::{Rng, SeedableRng};
        let mut g = room(40, 280, 40, 280);
        // Obstacles of every size, down to single cells a ray can step over.
        for (r, c) in [(100, 100), (150, 151), (200, 90), (61, 230)] {
            g.set_free(r, c, false);
        }
        for r in 120..180 {
            for c in 200..204 {
                g.set_free(r, c, false);
            }
        }
        // And scattered cells and short bars, so that rays graze corners
        // at every angle.
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for _ in 0..300 {
            let (r, c) = (rng.gen_range(40..280), rng.gen_range(40..280));
            for k in 0..rng.gen_range(1..4) {
                g.set_free(r, c + k, false);
            }
        }
        let m = PreparedMap::new(g);
        for _ in 0..40_000 {
            let p = [rng.gen_range(-6.0..6.0), rng.gen_range(-6.0..6.0)];
            let ray = rng.gen_range(0..NUM_RAYS);
            assert_eq!(
                m.stepped_wall_distance(p, ray, 16.0).to_bits(),
                m.stepped_wall_distance_naive(p, ray, 16.0).to_bits(),
                "{p:?} ray {ray}"
            );
        }
        // All rays at once, as the rule-based robots cast them.
        for _ in 0..5_000 {
            let p = [rng.gen_range(-6.0..6.0), rng.gen_range(-6.0..6.0)];
            let all = m.stepped_wall_distances(p, 16.0);
            for (ray, d) in all.iter().enumerate() {
                assert_eq!(
                    d.to_bits(),
                    m.stepped_wall_distance_naive(p, ray, 16.0).to_bits(),
                    "{p:?} ray {ray}"
                );
            }
        }
    }

    #[test]
    fn disc_test_is_exact_near_walls() {
        let m = PreparedMap::new(room(100, 140, 100, 160)); // x in [-3, 0]
        assert!(!m.disc_touches_obstacle([-0.2001, 2.0], 0.2));
        assert!(m.disc_touches_obstacle([-0.1999, 2.0], 0.2));
        // Near the inner corner (0, 3) both walls count.
        assert!(!m.disc_touches_obstacle([-0.21, 2.79], 0.2));
        assert!(m.disc_touches_obstacle([-0.19, 2.79], 0.2));
        assert!(m.disc_touches_obstacle([5.0, 5.0], 0.2));
    }
}
