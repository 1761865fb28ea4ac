//! Per cell and world ray, how far a wall ray of the rule-based robots
//! (spec §7: a sample every 0.1 m) may skip: after a sample in a cell, the
//! samples before the step are provably in free cells, wherever in the
//! cell the sample was.

use super::grid::CELL_SIZE;
use super::rays::{ray_dirs, NUM_RAYS, WALL_RAY_STEP};

/// A step's mark of a sample in an obstacle cell.
pub const IN_OBSTACLE: u8 = u8::MAX;
/// The longest step stored (a shorter step is as exact; the table costs
/// one pass over the grid per step length).
pub const MAX_STEP: usize = 16;
/// Widening of a moved cell square, in cells, against the rounding of the
/// samples' coordinates.
const EPS: f64 = 1e-6;

/// The steps of every world ray, built for all cells at once.
pub struct RaySteps {
    /// Per ray m, per padded cell (`cells` a ray): the step to the next sample that could lie in an obstacle
    /// cell (1..=MAX_STEP), or `IN_OBSTACLE`.
    steps: Vec<u8>,
    cells: usize,
}

impl RaySteps {
    /// The steps over a padded obstacle grid (`stride` cells a row, 1 =
    /// obstacle; every cell within `pad` of its edge is an obstacle, and
    /// `pad` is at least 2 `MAX_STEP` + 2, so that the blocks below of
    /// every cell inside the padding lie inside the padded grid).
    ///
    /// Sample k + i of a ray lies in the square of sample k's cell moved i
    /// steps (2i cells) along the ray, wherever in the square sample k was;
    /// when every cell that moved square touches (closed, widened by `EPS`)
    /// is free, sample k + i lies in a free cell. The cells it touches are
    /// the same block of offsets for every cell, so each step length is one
    /// pass over the grid: a cell's step is the first i whose block holds
    /// an obstacle (at most `MAX_STEP`).
    pub fn new(obstacle: &[u8], stride: usize, pad: usize) -> RaySteps {
        let cells = obstacle.len();
        assert!(pad >= 2 * MAX_STEP + 2, "padding {pad} too thin");
        let side = stride - 2 * pad;
        let mut steps = vec![IN_OBSTACLE; NUM_RAYS * cells];
        let mut hit = vec![0u8; side];
        for (m, table) in steps.chunks_exact_mut(cells).enumerate() {
            for r in pad..pad + side {
                let row = r * stride + pad;
                table[row..row + side].fill(MAX_STEP as u8);
                // Longest first, so the shortest blocked step stays.
                for i in (1..MAX_STEP).rev() {
                    let (rows, cols) = moved_block(m, i);
                    hit.fill(0);
                    for dr in rows {
                        for dc in cols.clone() {
                            let from = (row as isize + dr * stride as isize + dc) as usize;
                            for (h, &o) in hit.iter_mut().zip(&obstacle[from..from + side]) {
                                *h |= o;
                            }
                        }
                    }
                    for (s, &h) in table[row..row + side].iter_mut().zip(&hit) {
                        *s = if h != 0 { i as u8 } else { *s };
                    }
                }
                for (s, &o) in table[row..row + side]
                    .iter_mut()
                    .zip(&obstacle[row..row + side])
                {
                    *s = if o != 0 { IN_OBSTACLE } else { *s };
                }
            }
        }
        RaySteps { steps, cells }
    }

    /// The step of ray m after a sample in padded cell `index`.
    #[inline(always)]
    pub fn step(&self, m: usize, index: usize) -> u8 {
        self.steps[m * self.cells + index]
    }
}

/// The offsets (rows, columns) of the cells that a cell's square, moved i
/// steps along world ray m and widened by `EPS`, touches.
fn moved_block(
    m: usize,
    i: usize,
) -> (
    std::ops::RangeInclusive<isize>,
    std::ops::RangeInclusive<isize>,
) {
    let cells_per_step = WALL_RAY_STEP / CELL_SIZE;
    // Grid columns grow with x, rows with -y.
    let dir = ray_dirs()[m];
    let (dc, dr) = (
        i as f64 * dir[0] * cells_per_step,
        -(i as f64) * dir[1] * cells_per_step,
    );
    let span = |d: f64| (d - EPS).floor() as isize..=(d + 1.0 + EPS).floor() as isize;
    (span(dr), span(dc))
}
