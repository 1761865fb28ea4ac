//! Near-copy detection of maps: a compact fingerprint of a map's free space
//! and a similarity between a map and a fingerprint that does not change
//! when the map is mirrored, turned, transposed, padded or shifted, and
//! barely changes when a few pixels are edited.
//!
//! The fingerprint of a map is its free space cropped to the bounding box of
//! its free cells and downsampled to coarse cells of `COARSE` x `COARSE`
//! working cells (0.1 m), one bit per coarse cell (free when at least half
//! of its working cells are free), with the centroid of the free cells.
//!
//! A grid is compared with a fingerprint under each of the 8 symmetries of
//! the square, laid onto it centroid on centroid (a padding, a crop or a
//! shift moves both alike; a stray pixel barely moves a centroid). The
//! alignment is chosen by a quick overlap: each free coarse cell of the
//! fingerprint counts the fraction of free cells in the matching window of
//! the grid (a summed-area table), the best symmetry then nudged by a
//! working cell either way (rounding, resampling). At that alignment the
//! grid is downsampled as the fingerprint was and two numbers are taken:
//! the IoU of the free cells, and the agreement of the walls (F1 score of
//! the boundary cells matched within one coarse cell). Two different rooms
//! of one size overlap in most of their free space but not in their walls,
//! doors and furniture, so the similarity is the smaller of the two. Since
//! the IoU is at most the ratio of the two areas, pairs whose areas differ
//! too much are skipped without a look (`Probe::similarity_at_least`).

use super::Grid;

/// Working cells (0.05 m) per coarse cell side: 0.1 m.
pub const COARSE: usize = 2;
const WINDOW: f64 = (COARSE * COARSE) as f64;

/// The free space of a map at 0.1 m, cropped to its free cells.
#[derive(Clone, Debug, PartialEq)]
pub struct Fingerprint {
    pub name: String,
    /// Free cells of the working grid (0.05 m).
    pub free_cells: u32,
    /// Centroid (row, col) of the free cells, in working cells from the
    /// crop's top-left corner (cell (r, c) spans [r, r+1) x [c, c+1)).
    pub centroid: (f64, f64),
    /// Coarse rows and columns.
    pub rows: u16,
    pub cols: u16,
    /// Row-major, one bit per coarse cell (bit k of byte k/8, LSB first).
    pub bits: Vec<u8>,
}

/// The 8 symmetries of the square as signed permutations of (row, col):
/// `(swap, row sign, col sign)`: p' = (s_r * p[swap], s_c * p[1-swap]).
/// Names say how the grid compared is turned relative to the fingerprint's
/// map (rows grow downwards, so (r, c) -> (c, -r) turns it clockwise).
pub const SYMMETRIES: [(bool, f64, f64, &str); 8] = [
    (false, 1.0, 1.0, "as it is"),
    (true, 1.0, -1.0, "turned 90 degrees clockwise"),
    (false, -1.0, -1.0, "turned 180 degrees"),
    (true, -1.0, 1.0, "turned 90 degrees anticlockwise"),
    (false, 1.0, -1.0, "mirrored left-right"),
    (false, -1.0, 1.0, "mirrored top-bottom"),
    (
        true,
        1.0,
        1.0,
        "transposed (mirrored about the main diagonal)",
    ),
    (true, -1.0, -1.0, "mirrored about the anti-diagonal"),
];

#[cfg(test)]
fn apply(sym: usize, p: (f64, f64)) -> (f64, f64) {
    let (swap, sr, sc, _) = SYMMETRIES[sym];
    let (a, b) = if swap { (p.1, p.0) } else { (p.0, p.1) };
    (sr * a, sc * b)
}

/// Bounding box (r0, r1, c0, c1), half-open, of a grid's free cells.
fn free_bbox(grid: &Grid) -> Option<(usize, usize, usize, usize)> {
    let n = grid.side();
    let mask = grid.free_mask();
    let (mut r0, mut r1, mut c0, mut c1) = (usize::MAX, 0, usize::MAX, 0);
    for r in 0..n {
        let row = &mask[r * n..(r + 1) * n];
        let Some(first) = row.iter().position(|&f| f) else {
            continue;
        };
        let last = row.iter().rposition(|&f| f).unwrap();
        r0 = r0.min(r);
        r1 = r + 1;
        c0 = c0.min(first);
        c1 = c1.max(last + 1);
    }
    (r0 != usize::MAX).then_some((r0, r1, c0, c1))
}

/// A grid's free cells cropped to their bounding box, as a summed-area
/// table, with their count and centroid: everything a comparison needs.
pub struct CroppedFree {
    rows: usize,
    cols: usize,
    /// Free cells of every window of `COARSE` x `COARSE` cells that
    /// overlaps the crop, by its top-left cell (r, c), r in
    /// [1 - COARSE, rows), c in [1 - COARSE, cols): row-major over
    /// (rows + COARSE - 1) x (cols + COARSE - 1), cells outside the crop
    /// counting as obstacle. One read per window: comparisons look up
    /// windows by the hundred thousand.
    windows: Vec<u8>,
    pub free_cells: u32,
    pub centroid: (f64, f64),
}

const PAD: usize = COARSE - 1;

impl CroppedFree {
    pub fn of(grid: &Grid) -> CroppedFree {
        let Some((r0, r1, c0, c1)) = free_bbox(grid) else {
            return CroppedFree {
                rows: 0,
                cols: 0,
                windows: Vec::new(),
                free_cells: 0,
                centroid: (0.0, 0.0),
            };
        };
        let (rows, cols) = (r1 - r0, c1 - c0);
        let (wr, wc) = (rows + PAD, cols + PAD);
        let mut windows = vec![0u8; wr * wc];
        let (mut sr, mut sc, mut n) = (0f64, 0f64, 0u32);
        for r in 0..rows {
            for c in 0..cols {
                if grid.is_free((r0 + r) as isize, (c0 + c) as isize) {
                    n += 1;
                    sr += r as f64 + 0.5;
                    sc += c as f64 + 0.5;
                    // Every window holding (r, c): top-left (r - dr, c - dc),
                    // at index (r - dr + PAD, c - dc + PAD).
                    for dr in 0..COARSE {
                        for dc in 0..COARSE {
                            windows[(r + PAD - dr) * wc + (c + PAD - dc)] += 1;
                        }
                    }
                }
            }
        }
        CroppedFree {
            rows,
            cols,
            windows,
            free_cells: n,
            centroid: if n > 0 {
                (sr / n as f64, sc / n as f64)
            } else {
                (0.0, 0.0)
            },
        }
    }

    /// Free cells in rows [r, r + COARSE) and columns [c, c + COARSE), the
    /// window clipped to the crop.
    #[inline]
    fn window(&self, r: i64, c: i64) -> u32 {
        let (r, c) = (r + PAD as i64, c + PAD as i64);
        let (wr, wc) = ((self.rows + PAD) as i64, (self.cols + PAD) as i64);
        if r < 0 || c < 0 || r >= wr || c >= wc {
            return 0;
        }
        self.windows[(r * wc + c) as usize] as u32
    }

    /// The fingerprint of this free space.
    pub fn fingerprint(&self, name: &str) -> Fingerprint {
        let rows = self.rows.div_ceil(COARSE);
        let cols = self.cols.div_ceil(COARSE);
        let mut bits = vec![0u8; (rows * cols).div_ceil(8)];
        for i in 0..rows {
            for j in 0..cols {
                let free = self.window((i * COARSE) as i64, (j * COARSE) as i64);
                if 2 * free >= (COARSE * COARSE) as u32 {
                    let k = i * cols + j;
                    bits[k / 8] |= 1 << (k % 8);
                }
            }
        }
        Fingerprint {
            name: name.to_string(),
            free_cells: self.free_cells,
            centroid: self.centroid,
            rows: rows as u16,
            cols: cols as u16,
            bits,
        }
    }
}

impl Fingerprint {
    pub fn of(grid: &Grid) -> Fingerprint {
        CroppedFree::of(grid).fingerprint(&grid.name)
    }

    pub fn is_free(&self, i: usize, j: usize) -> bool {
        let k = i * self.cols as usize + j;
        self.bits[k / 8] >> (k % 8) & 1 == 1
    }

    /// The coarse free cells, (row, col).
    pub fn free_coarse(&self) -> Vec<(u16, u16)> {
        let mut out = Vec::new();
        for i in 0..self.rows as usize {
            for j in 0..self.cols as usize {
                if self.is_free(i, j) {
                    out.push((i as u16, j as u16));
                }
            }
        }
        out
    }
}

/// How well a grid matches a fingerprint, at the best symmetry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Match {
    /// min(free_iou, walls): both must be high for a copy.
    pub similarity: f64,
    /// IoU of the free cells at 0.1 m.
    pub free_iou: f64,
    /// Agreement of the walls: the F1 score of the boundary cells (free
    /// cells beside an obstacle, at 0.1 m) matched within one cell. Two
    /// different rooms of the same size and shape overlap in most of their
    /// free space, but not in their walls, doors and furniture.
    pub walls: f64,
    /// An index into `SYMMETRIES`.
    pub symmetry: usize,
}

/// `Probe::placement`: coarse cell (i, j) of a fingerprint lands on the
/// window of a grid's crop whose top-left working cell is `at(i, j)`.
struct Placement {
    r0: i64,
    c0: i64,
    swap: bool,
    /// Signed working cells per coarse cell along the image's rows / columns.
    sr: i64,
    sc: i64,
}

impl Placement {
    #[inline]
    fn at(&self, i: i64, j: i64) -> (i64, i64) {
        let (u, v) = if self.swap { (j, i) } else { (i, j) };
        (self.r0 + self.sr * u, self.c0 + self.sc * v)
    }
}

/// A fingerprint ready for comparisons: its free cells listed once, and
/// every fourth of them (even rows and columns) for choosing alignments.
pub struct Probe {
    pub fingerprint: Fingerprint,
    free: Vec<(u16, u16)>,
    sample: Vec<(u16, u16)>,
}

/// Free cells with an obstacle (or the outside) among their 4 neighbours.
fn boundary(bits: &[bool], rows: usize, cols: usize) -> Vec<bool> {
    let at = |r: isize, c: isize| {
        r >= 0
            && c >= 0
            && (r as usize) < rows
            && (c as usize) < cols
            && bits[r as usize * cols + c as usize]
    };
    let mut out = vec![false; rows * cols];
    for r in 0..rows as isize {
        for c in 0..cols as isize {
            out[r as usize * cols + c as usize] =
                at(r, c) && !(at(r - 1, c) && at(r + 1, c) && at(r, c - 1) && at(r, c + 1));
        }
    }
    out
}

/// Cells within one cell (8-neighbourhood) of a set cell.
fn dilate(bits: &[bool], rows: usize, cols: usize) -> Vec<bool> {
    let mut out = vec![false; rows * cols];
    for r in 0..rows {
        for c in 0..cols {
            if bits[r * cols + c] {
                for rr in r.saturating_sub(1)..(r + 2).min(rows) {
                    for cc in c.saturating_sub(1)..(c + 2).min(cols) {
                        out[rr * cols + cc] = true;
                    }
                }
            }
        }
    }
    out
}

impl Probe {
    pub fn new(fingerprint: Fingerprint) -> Probe {
        let free = fingerprint.free_coarse();
        let sample = free
            .iter()
            .copied()
            .filter(|&(i, j)| i % 2 == 0 && j % 2 == 0)
            .collect();
        Probe {
            fingerprint,
            free,
            sample,
        }
    }

    /// Coarse free cells of the fingerprint.
    pub fn area(&self) -> f64 {
        self.free.len() as f64
    }

    /// Where the coarse cells of the fingerprint land in `grid`'s crop
    /// under one symmetry, moved by `nudge` working cells. The grid is laid
    /// onto the fingerprint centroid on centroid: p in the fingerprint's
    /// crop goes to q = c_grid + S (p - c_fingerprint) in the grid's; the
    /// image of a coarse square is a square whose smallest corner is the
    /// smallest image coordinate, rounded to a working cell. The rounding
    /// is the same for every cell (they differ by whole cells), so it is
    /// done once here.
    fn placement(&self, grid: &CroppedFree, sym: usize, nudge: (i64, i64)) -> Placement {
        let (swap, sr, sc, _) = SYMMETRIES[sym];
        let ct = self.fingerprint.centroid;
        let (cu, cv) = if swap { (ct.1, ct.0) } else { (ct.0, ct.1) };
        let k = COARSE as f64;
        let low = |s: f64| if s < 0.0 { -k } else { 0.0 };
        Placement {
            r0: (grid.centroid.0 - sr * cu + low(sr) + 0.5).floor() as i64 + nudge.0,
            c0: (grid.centroid.1 - sc * cv + low(sc) + 0.5).floor() as i64 + nudge.1,
            swap,
            sr: sr as i64 * COARSE as i64,
            sc: sc as i64 * COARSE as i64,
        }
    }

    /// A quick IoU for choosing the alignment: each free cell of the
    /// fingerprint counts the fraction of free cells in the grid's window.
    /// With `sampled`, over every fourth cell only, each counting four.
    fn soft_iou(&self, grid: &CroppedFree, sym: usize, nudge: (i64, i64), sampled: bool) -> f64 {
        let (cells, weight) = if sampled {
            (
                &self.sample,
                self.free.len() as f64 / self.sample.len().max(1) as f64,
            )
        } else {
            (&self.free, 1.0)
        };
        let place = self.placement(grid, sym, nudge);
        let mut intersection = 0u64;
        for &(i, j) in cells {
            let (r, c) = place.at(i as i64, j as i64);
            intersection += grid.window(r, c) as u64;
        }
        let i = (intersection as f64 * weight / WINDOW).min(self.area());
        let union = grid.free_cells as f64 / WINDOW + self.area() - i;
        if union > 0.0 {
            i / union
        } else {
            0.0
        }
    }

    /// The grid downsampled as the fingerprint was, in the fingerprint's
    /// frame, over a range that holds both: (IoU of the free cells, walls).
    fn compare(&self, grid: &CroppedFree, sym: usize, nudge: (i64, i64)) -> (f64, f64) {
        let fp = &self.fingerprint;
        let k = COARSE as f64;
        // The grid's crop corners in the fingerprint's frame (S^-1 = S^T).
        let (swap, sr, sc, _) = SYMMETRIES[sym];
        let back = |q: (f64, f64)| {
            let d = (q.0 - grid.centroid.0, q.1 - grid.centroid.1);
            let p = if swap {
                (sc * d.1, sr * d.0)
            } else {
                (sr * d.0, sc * d.1)
            };
            (fp.centroid.0 + p.0, fp.centroid.1 + p.1)
        };
        let (mut lo, mut hi) = ((0i64, 0i64), (fp.rows as i64, fp.cols as i64));
        for q in [
            (0.0, 0.0),
            (grid.rows as f64, 0.0),
            (0.0, grid.cols as f64),
            (grid.rows as f64, grid.cols as f64),
        ] {
            let p = back(q);
            lo = (
                lo.0.min((p.0 / k).floor() as i64 - 2),
                lo.1.min((p.1 / k).floor() as i64 - 2),
            );
            hi = (
                hi.0.max((p.0 / k).ceil() as i64 + 2),
                hi.1.max((p.1 / k).ceil() as i64 + 2),
            );
        }
        let (rows, cols) = ((hi.0 - lo.0) as usize, (hi.1 - lo.1) as usize);
        let mut mine = vec![false; rows * cols];
        let mut theirs = vec![false; rows * cols];
        let half = (COARSE * COARSE) as u32;
        let place = self.placement(grid, sym, nudge);
        for r in 0..rows {
            for c in 0..cols {
                let (i, j) = (r as i64 + lo.0, c as i64 + lo.1);
                let (wr, wc) = place.at(i, j);
                theirs[r * cols + c] = 2 * grid.window(wr, wc) >= half;
                mine[r * cols + c] = i >= 0
                    && j >= 0
                    && i < fp.rows as i64
                    && j < fp.cols as i64
                    && fp.is_free(i as usize, j as usize);
            }
        }
        let (mut both, mut either) = (0usize, 0usize);
        for (a, b) in mine.iter().zip(&theirs) {
            both += (*a && *b) as usize;
            either += (*a || *b) as usize;
        }
        let iou = if either > 0 {
            both as f64 / either as f64
        } else {
            0.0
        };
        let (bm, bt) = (boundary(&mine, rows, cols), boundary(&theirs, rows, cols));
        let (dm, dt) = (dilate(&bm, rows, cols), dilate(&bt, rows, cols));
        let count = |set: &[bool], near: &[bool]| {
            let n = set.iter().filter(|&&x| x).count();
            let hit = set.iter().zip(near).filter(|(&x, &y)| x && y).count();
            (hit, n)
        };
        let (hit_t, n_t) = count(&bt, &dm);
        let (hit_m, n_m) = count(&bm, &dt);
        let walls = if n_t > 0 && n_m > 0 {
            let precision = hit_t as f64 / n_t as f64;
            let recall = hit_m as f64 / n_m as f64;
            if precision + recall > 0.0 {
                2.0 * precision * recall / (precision + recall)
            } else {
                0.0
            }
        } else {
            0.0
        };
        (iou, walls)
    }

    /// The best match of `grid` with this fingerprint over the 8
    /// symmetries, or None without a look when the areas alone keep it
    /// below `floor` (their ratio bounds the IoU of the free cells, with a
    /// margin for the rounding of the downsampled cells), or when it stays
    /// below `floor`.
    pub fn similarity_at_least(&self, grid: &CroppedFree, floor: f64) -> Option<Match> {
        let a = grid.free_cells as f64 / WINDOW;
        let b = self.area();
        if a <= 0.0 || b <= 0.0 || a.min(b) / a.max(b) < 0.9 * floor {
            return None;
        }
        // The alignment, chosen on every fourth cell: the symmetries that
        // overlap (nearly) most, each nudged by a working cell either way
        // (rounding of centroids, resampling). A room symmetric by itself
        // overlaps alike under several; all of them are compared.
        let scores: Vec<f64> = (0..SYMMETRIES.len())
            .map(|sym| self.soft_iou(grid, sym, (0, 0), true))
            .collect();
        let top = scores.iter().copied().fold(f64::MIN, f64::max);
        // The quick overlap is a little below the IoU the comparison finds
        // (fractions against whole cells; copies score 0.9 and more): far
        // below the floor, no closer look. Most pairs end here.
        if top < floor - 0.15 {
            return None;
        }
        let mut best: Option<Match> = None;
        for sym in (0..SYMMETRIES.len()).filter(|&s| scores[s] >= top - 0.03) {
            let mut sampled = ((0i64, 0i64), scores[sym]);
            for dr in -1..=1 {
                for dc in -1..=1 {
                    if (dr, dc) != (0, 0) {
                        let s = self.soft_iou(grid, sym, (dr, dc), true);
                        if s > sampled.1 {
                            sampled = ((dr, dc), s);
                        }
                    }
                }
            }
            // The sample can prefer a neighbour of the true alignment: the
            // unmoved one and the sample's best, on every cell.
            let mut nudge = ((0i64, 0i64), self.soft_iou(grid, sym, (0, 0), false));
            if sampled.0 != (0, 0) {
                let s = self.soft_iou(grid, sym, sampled.0, false);
                if s > nudge.1 {
                    nudge = (sampled.0, s);
                }
            }
            if nudge.1 < floor - 0.1 {
                continue;
            }
            let (free_iou, walls) = self.compare(grid, sym, nudge.0);
            let m = Match {
                similarity: free_iou.min(walls),
                free_iou,
                walls,
                symmetry: sym,
            };
            if best.is_none_or(|b| m.similarity > b.similarity) {
                best = Some(m);
            }
        }
        best.filter(|m| m.similarity >= floor)
    }
}

const MAGIC: &[u8; 8] = b"T2EFP\x01\0\0";

/// Fingerprints with a class byte each, as one little-endian file:
/// magic, count (u32), then per map: name length (u16), name (UTF-8),
/// class (u8: 0 small, 1 medium, 2 large, 255 none), free cells (u32),
/// centroid row and column (f64), coarse rows and columns (u16), bits.
pub fn encode(maps: &[(Fingerprint, Option<super::SizeClass>)]) -> Vec<u8> {
    let mut out = MAGIC.to_vec();
    out.extend((maps.len() as u32).to_le_bytes());
    for (fp, class) in maps {
        out.extend((fp.name.len() as u16).to_le_bytes());
        out.extend(fp.name.as_bytes());
        out.push(match class {
            Some(c) => super::SizeClass::ALL.iter().position(|x| x == c).unwrap() as u8,
            None => 255,
        });
        out.extend(fp.free_cells.to_le_bytes());
        out.extend(fp.centroid.0.to_le_bytes());
        out.extend(fp.centroid.1.to_le_bytes());
        out.extend(fp.rows.to_le_bytes());
        out.extend(fp.cols.to_le_bytes());
        out.extend(&fp.bits);
    }
    out
}

/// Why the embedded fingerprint bytes cannot be read.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum FingerprintError {
    #[error("fingerprints end at byte {at}, reading {what}")]
    Truncated { at: usize, what: &'static str },
    #[error("not a fingerprint file (bad magic)")]
    BadMagic,
    #[error("a name is not UTF-8")]
    NameNotUtf8,
    #[error("{name}: class byte {byte}")]
    BadClass { name: String, byte: u8 },
    #[error("{left} bytes left over after {count} fingerprints")]
    LeftOver { left: usize, count: u32 },
}

struct Cursor<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Cursor<'a> {
    fn take(&mut self, n: usize, what: &'static str) -> Result<&'a [u8], FingerprintError> {
        let s = self
            .bytes
            .get(self.at..self.at + n)
            .ok_or(FingerprintError::Truncated { at: self.at, what })?;
        self.at += n;
        Ok(s)
    }

    fn array<const N: usize>(&mut self, what: &'static str) -> Result<[u8; N], FingerprintError> {
        Ok(self.take(N, what)?.try_into().unwrap())
    }
}

/// Reads what `encode` wrote; the error says where it stops making sense.
pub fn decode(
    bytes: &[u8],
) -> Result<Vec<(Fingerprint, Option<super::SizeClass>)>, FingerprintError> {
    let mut cur = Cursor { bytes, at: 0 };
    if cur.take(8, "the magic")? != MAGIC {
        return Err(FingerprintError::BadMagic);
    }
    let count = u32::from_le_bytes(cur.array("the count")?);
    let mut out = Vec::new();
    for _ in 0..count {
        let len = u16::from_le_bytes(cur.array("a name length")?) as usize;
        let name = String::from_utf8(cur.take(len, "a name")?.to_vec())
            .map_err(|_| FingerprintError::NameNotUtf8)?;
        let class = match cur.take(1, "a class")?[0] {
            255 => None,
            c => Some(*super::SizeClass::ALL.get(c as usize).ok_or(
                FingerprintError::BadClass {
                    name: name.clone(),
                    byte: c,
                },
            )?),
        };
        let free_cells = u32::from_le_bytes(cur.array("free cells")?);
        let r = f64::from_le_bytes(cur.array("a centroid")?);
        let c = f64::from_le_bytes(cur.array("a centroid")?);
        let rows = u16::from_le_bytes(cur.array("rows")?);
        let cols = u16::from_le_bytes(cur.array("columns")?);
        let bits = cur
            .take((rows as usize * cols as usize).div_ceil(8), "bits")?
            .to_vec();
        out.push((
            Fingerprint {
                name,
                free_cells,
                centroid: (r, c),
                rows,
                cols,
                bits,
            },
            class,
        ));
    }
    if cur.at != bytes.len() {
        return Err(FingerprintError::LeftOver {
            left: bytes.len() - cur.at,
            count,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An L-shaped room with a pillar: no symmetry of its own.
    fn l_room(side: usize, dr: usize, dc: usize) -> Grid {
        let mut g = Grid::with_free_rects(
            "l",
            side,
            &[
                (dr + 10..dr + 60, dc + 10..dc + 30),
                (dr + 40..dr + 60, dc + 30..dc + 100),
            ],
        );
        for r in dr + 15..dr + 20 {
            for c in dc + 15..dc + 18 {
                g.set_free(r, c, false);
            }
        }
        g
    }

    fn transformed(g: &Grid, sym: usize) -> Grid {
        let n = g.side();
        let mut out = Grid::blocked("t", n);
        let m = (n - 1) as f64;
        for r in 0..n {
            for c in 0..n {
                if g.is_free(r as isize, c as isize) {
                    // Map about the grid's centre so the result stays inside.
                    let (a, b) = apply(sym, (r as f64 - m / 2.0, c as f64 - m / 2.0));
                    out.set_free((a + m / 2.0) as usize, (b + m / 2.0) as usize, true);
                }
            }
        }
        out
    }

    #[test]
    fn every_symmetry_and_shift_of_a_map_matches_it_and_another_room_does_not() {
        let original = l_room(160, 0, 0);
        let probe = Probe::new(Fingerprint::of(&original));
        for (sym, symmetry) in SYMMETRIES.iter().enumerate() {
            let g = transformed(&l_room(160, 7, 3), sym);
            let m = probe
                .similarity_at_least(&CroppedFree::of(&g), 0.0)
                .unwrap();
            assert!(m.similarity > 0.97, "{}: {m:?}", symmetry.3);
            assert_eq!(m.symmetry, sym);
        }
        let other = Grid::with_free_rects("o", 160, &[(10..70, 10..60)]);
        let m = probe
            .similarity_at_least(&CroppedFree::of(&other), 0.0)
            .unwrap();
        assert!(m.similarity < 0.6, "{m:?}");
        // Areas too far apart are not even compared.
        let small = Grid::with_free_rects("s", 160, &[(10..20, 10..20)]);
        assert_eq!(
            probe.similarity_at_least(&CroppedFree::of(&small), 0.5),
            None
        );
    }

    #[test]
    fn fingerprints_round_trip_and_bad_bytes_are_named() {
        let fp = Fingerprint::of(&l_room(160, 0, 0));
        let bytes = encode(&[
            (fp.clone(), Some(super::super::SizeClass::Medium)),
            (fp.clone(), None),
        ]);
        let back = decode(&bytes).unwrap();
        assert_eq!(back[0], (fp.clone(), Some(super::super::SizeClass::Medium)));
        assert_eq!(back[1].1, None);
        assert!(decode(&bytes[..bytes.len() - 1])
            .unwrap_err()
            .to_string()
            .contains("bits"));
        assert_eq!(
            decode(b"nope"),
            Err(FingerprintError::Truncated {
                at: 0,
                what: "the magic"
            })
        );
        assert_eq!(decode(b"not-magic-bytes"), Err(FingerprintError::BadMagic));
    }
}
