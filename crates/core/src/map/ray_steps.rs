//! Per cell and world ray, how far a wall ray of the rule-based robots
//! (spec §7: a sample every 0.1 m) may skip: after a sample in a cell, the
//! samples before the step are provably in free cells, wherever in the
//! cell the sample was.

use super::grid::CELL_SIZE;
use super::rays::{ray_dirs, NUM_RAYS, WALL_RAY_STEP};
use std::ops::Range;

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
    /// the same block of offsets for every cell, and the blocks come in a
    /// few shapes (2 or 3 cells a side), so a table per shape says whether
    /// the block at each cell holds an obstacle; a cell's step is then the
    /// first i whose block, read from its shape's table, does (at most
    /// `MAX_STEP`). Obstacle cells need no step, so each row is built
    /// only between its first and last free cell.
    pub fn new(obstacle: &[u8], stride: usize, pad: usize) -> RaySteps {
        let cells = obstacle.len();
        assert!(pad >= 2 * MAX_STEP + 2, "padding {pad} too thin");
        let side = stride - 2 * pad;
        // Per block shape (rows, columns), whether the block whose first
        // cell is at each index holds an obstacle.
        let mut blocked_by_shape: Vec<((usize, usize), Vec<u8>)> = Vec::new();
        // Per ray and step i (index i - 1): the shape's place in
        // `blocked_by_shape` and the index offset of the block's first
        // cell from the cell the sample was in.
        let mut blocks = [[(0usize, 0isize); MAX_STEP - 1]; NUM_RAYS];
        for (m, ray_blocks) in blocks.iter_mut().enumerate() {
            for (i, block) in (1..MAX_STEP).zip(ray_blocks.iter_mut()) {
                let (rows, cols) = moved_block(m, i);
                let shape = (rows.clone().count(), cols.clone().count());
                let known = blocked_by_shape.iter().position(|(s, _)| *s == shape);
                let table = known.unwrap_or_else(|| {
                    let table = block_holds_obstacle(obstacle, stride, shape);
                    blocked_by_shape.push((shape, table));
                    blocked_by_shape.len() - 1
                });
                *block = (table, rows.start() * stride as isize + cols.start());
            }
        }
        // Per grid row with a free cell: the indices from its first free
        // cell to its last.
        let free_spans: Vec<Range<usize>> = (pad..pad + side)
            .filter_map(|r| {
                let start = r * stride + pad;
                let row = &obstacle[start..start + side];
                let first = row.iter().position(|&o| o == 0)?;
                let last = row.iter().rposition(|&o| o == 0)?;
                Some(start + first..start + last + 1)
            })
            .collect();
        let mut steps = vec![IN_OBSTACLE; NUM_RAYS * cells];
        for (table, ray_blocks) in steps.chunks_exact_mut(cells).zip(&blocks) {
            for span in &free_spans {
                let row_steps = &mut table[span.clone()];
                row_steps.fill(MAX_STEP as u8);
                // Longest first, so the shortest blocked step stays.
                for (i, &(shape, offset)) in (1..MAX_STEP).zip(ray_blocks).rev() {
                    let first = (span.start as isize + offset) as usize;
                    let blocked = &blocked_by_shape[shape].1[first..first + span.len()];
                    for (s, &b) in row_steps.iter_mut().zip(blocked) {
                        *s = if b != 0 { i as u8 } else { *s };
                    }
                }
                for (s, &o) in row_steps.iter_mut().zip(&obstacle[span.clone()]) {
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

/// Per cell index p of the grid (`stride` cells a row), whether the block
/// of `shape` (rows, columns) whose first cell is p holds an obstacle;
/// only for the indices whose block lies inside the grid. The rows of
/// each block first, then the columns of those.
fn block_holds_obstacle(obstacle: &[u8], stride: usize, shape: (usize, usize)) -> Vec<u8> {
    let (rows, cols) = shape;
    let mut along_row = obstacle[..obstacle.len() - (cols - 1)].to_vec();
    for k in 1..cols {
        for (a, &o) in along_row.iter_mut().zip(&obstacle[k..]) {
            *a |= o;
        }
    }
    let mut block = along_row[..along_row.len() - (rows - 1) * stride].to_vec();
    for k in 1..rows {
        for (b, &a) in block.iter_mut().zip(&along_row[k * stride..]) {
            *b |= a;
        }
    }
    block
}
