//! Loading the Gibson traversability format (spec §1): square 8-bit grayscale
//! PNG, 0.01 m per pixel, 255 = free; padded to 1600 px; point-sampled to
//! 0.05 m cells at source pixel (5i+2, 5j+2).

use super::grid::{Grid, MIN_SIDE_PX, PIXELS_PER_CELL};
use image::GrayImage;
use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
#[error("map {}: {reason}", path.display())]
pub struct MapError {
    pub path: PathBuf,
    pub reason: String,
}

impl MapError {
    pub fn new(path: &Path, reason: impl Into<String>) -> MapError {
        MapError {
            path: path.to_path_buf(),
            reason: reason.into(),
        }
    }
}

/// The largest map side accepted, in pixels (40 m at 0.01 m per pixel; the
/// Gibson maps are at most 1800). Checked from the PNG header before
/// decoding, so a huge image is refused at once instead of filling memory.
pub const MAX_SIDE_PX: u32 = 4000;

/// Loads a traversability PNG into a working grid named after the file stem.
pub fn load_png(path: &Path) -> Result<Grid, MapError> {
    if !path.exists() {
        return Err(MapError::new(path, "not found"));
    }
    let bytes =
        std::fs::read(path).map_err(|e| MapError::new(path, format!("cannot read: {e}")))?;
    if !bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
        return Err(MapError::new(path, "not a PNG file (bad signature)"));
    }
    // IHDR is the first chunk: width and height, big-endian, at bytes 16..24.
    if bytes.len() >= 24 && &bytes[12..16] == b"IHDR" {
        let w = u32::from_be_bytes(bytes[16..20].try_into().unwrap());
        let h = u32::from_be_bytes(bytes[20..24].try_into().unwrap());
        if w > MAX_SIDE_PX || h > MAX_SIDE_PX {
            return Err(MapError::new(
                path,
                format!(
                    "{w}x{h} pixels: larger than the {MAX_SIDE_PX}x{MAX_SIDE_PX} maps accepted ({} m at 0.01 m per pixel)",
                    MAX_SIDE_PX / 100
                ),
            ));
        }
    }
    let img = image::load_from_memory_with_format(&bytes, image::ImageFormat::Png)
        .map_err(|e| MapError::new(path, format!("broken PNG: {e}")))?;
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "map".into());
    let gray = img.to_luma8();
    grid_from_pixels(&name, &gray).map_err(|reason| MapError::new(path, reason.to_string()))
}

/// Why an image cannot be a map.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum PixelsRefused {
    #[error("not square: {w}x{h} pixels")]
    NotSquare { w: u32, h: u32 },
    #[error("empty image")]
    Empty,
    #[error("{w}x{h} pixels: smaller than one 0.05 m cell ({PIXELS_PER_CELL} pixels at 0.01 m per pixel)")]
    SmallerThanACell { w: u32, h: u32 },
    #[error("no free cell: every sampled pixel is an obstacle (free pixels must be exactly 255)")]
    NoFreeCell,
}

/// Point-samples a traversability image into the 0.05 m working grid.
pub fn grid_from_pixels(name: &str, img: &GrayImage) -> Result<Grid, PixelsRefused> {
    let (w, h) = img.dimensions();
    if w != h {
        return Err(PixelsRefused::NotSquare { w, h });
    }
    if w == 0 {
        return Err(PixelsRefused::Empty);
    }
    if w <= PIXELS_PER_CELL / 2 {
        return Err(PixelsRefused::SmallerThanACell { w, h });
    }
    let side_px = w.max(MIN_SIDE_PX);
    let side = side_px.div_ceil(PIXELS_PER_CELL) as usize;
    let mut free = vec![false; side * side];
    let off = PIXELS_PER_CELL / 2;
    for i in 0..side {
        let py = i as u32 * PIXELS_PER_CELL + off;
        if py >= h {
            break;
        }
        for j in 0..side {
            let px = j as u32 * PIXELS_PER_CELL + off;
            if px >= w {
                break;
            }
            free[i * side + j] = img.get_pixel(px, py).0[0] == 255;
        }
    }
    let grid = Grid::new(name, side, free);
    if grid.free_cells() == 0 {
        return Err(PixelsRefused::NoFreeCell);
    }
    Ok(grid)
}

/// Writes a grid in the source format (0.01 m per pixel, 255 free, 0 obstacle),
/// so that `load_png` gives the same grid back.
pub fn save_png(grid: &Grid, path: &Path) -> Result<(), MapError> {
    let side_px = grid.side() as u32 * PIXELS_PER_CELL;
    let img = GrayImage::from_fn(side_px, side_px, |x, y| {
        let free = grid.is_free(
            (y / PIXELS_PER_CELL) as isize,
            (x / PIXELS_PER_CELL) as isize,
        );
        image::Luma([if free { 255 } else { 0 }])
    });
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir)
            .map_err(|e| MapError::new(path, format!("cannot create folder: {e}")))?;
    }
    // Encoded whole, then written to a temporary sibling and renamed: a
    // killed `maps generate` never leaves a truncated map under its name.
    let mut bytes = std::io::Cursor::new(Vec::new());
    img.write_to(&mut bytes, image::ImageFormat::Png)
        .map_err(|e| MapError::new(path, format!("cannot encode PNG: {e}")))?;
    crate::fs::write_file_atomically(path, bytes.get_ref())
        .map_err(|e| MapError::new(path, format!("cannot write PNG: {e:#}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }

    #[test]
    fn bad_inputs_name_the_file_and_the_problem() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("nope.png");
        let e = load_png(&missing).unwrap_err().to_string();
        assert!(e.contains("nope.png") && e.contains("not found"), "{e}");

        let text = write(dir.path(), "text.png", b"hello, not a png");
        let e = load_png(&text).unwrap_err().to_string();
        assert!(e.contains("text.png") && e.contains("not a PNG"), "{e}");

        let truncated = write(dir.path(), "cut.png", b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR");
        let e = load_png(&truncated).unwrap_err().to_string();
        assert!(e.contains("cut.png") && e.contains("broken PNG"), "{e}");

        let rect = dir.path().join("rect.png");
        GrayImage::from_pixel(100, 80, image::Luma([255]))
            .save(&rect)
            .unwrap();
        let e = load_png(&rect).unwrap_err().to_string();
        assert!(
            e.contains("rect.png") && e.contains("not square: 100x80"),
            "{e}"
        );

        let blocked = dir.path().join("blocked.png");
        GrayImage::from_pixel(50, 50, image::Luma([254]))
            .save(&blocked)
            .unwrap();
        let e = load_png(&blocked).unwrap_err().to_string();
        assert!(
            e.contains("blocked.png") && e.contains("no free cell"),
            "{e}"
        );
    }

    #[test]
    fn small_maps_are_padded_and_point_sampled() {
        // 20x20 px: free except pixel column 7 (sampled by cell column 1).
        let img = GrayImage::from_fn(20, 20, |x, _| image::Luma([if x == 7 { 0 } else { 255 }]));
        let g = grid_from_pixels("t", &img).unwrap();
        assert_eq!(g.side(), 320); // padded to 1600 px
        assert!(g.is_free(0, 0) && !g.is_free(0, 1) && g.is_free(3, 3));
        assert!(!g.is_free(0, 4) && !g.is_free(4, 0)); // padding is obstacle
        assert_eq!(g.free_cells(), 12);
    }

    #[test]
    fn save_then_load_gives_the_same_grid() {
        let dir = tempfile::tempdir().unwrap();
        let mut g = Grid::blocked("rt", 320);
        for r in 10..50 {
            for c in 20..90 {
                g.set_free(r, c, (r * 7 + c) % 5 != 0);
            }
        }
        let p = dir.path().join("rt.png");
        save_png(&g, &p).unwrap();
        assert_eq!(load_png(&p).unwrap(), g);
    }
}
