//! A heat map of values in [0, 1] with row and column labels (the league's
//! payoff matrix), drawn with plotters: blue at 0, red at 1, each cell
//! captioned with its value in percent, blank where there is no value.

use super::canvas::Canvas;
use super::plotters_font;
use image::RgbImage;
use plotters::element::Text as PlotText;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// What a heat map shows.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HeatMap {
    pub title: String,
    pub row_labels: Vec<String>,
    pub column_labels: Vec<String>,
    /// `cells[row][column]`, in [0, 1]; `None` (or a non-finite value) is
    /// left blank.
    pub cells: Vec<Vec<Option<f64>>>,
    /// Lines of text to the right of the cells (what the columns' short
    /// labels stand for); left out where they do not fit.
    pub notes: Vec<String>,
}

/// Side of a cell in pixels.
pub const CELL: u32 = 38;
const TOP: u32 = 70;
const LABEL_PX: u32 = 12;

/// The colour of a value: blue (0) to red (1).
pub fn cell_color(v: f64) -> RGBColor {
    let v = v.clamp(0.0, 1.0);
    RGBColor((255.0 * v) as u8, 60, (255.0 * (1.0 - v)) as u8)
}

/// Draws the heat map, at least 900 x 200 pixels and as large as its
/// labels and cells need.
pub fn heat_map(h: &HeatMap) -> RgbImage {
    plotters_font::register();
    let font: TextStyle = (plotters_font::FAMILY, LABEL_PX).into_font().into();
    let rows = h.row_labels.len() as u32;
    let columns = h.column_labels.len() as u32;
    // Measured on a scratch area: the row labels set where the cells start.
    let longest = {
        let mut scratch = vec![255u8; 3];
        let area = Canvas::new(&mut scratch, (1, 1)).into_drawing_area();
        h.row_labels
            .iter()
            .filter_map(|l| area.estimate_text_size(l, &font).ok())
            .map(|(w, _)| w)
            .max()
            .unwrap_or(0)
    };
    let left = (16 + longest).max(230);
    let width = 900u32.max(left + CELL * columns + 20);
    let height = (TOP + CELL * rows + 40).max(200);
    let mut buf = vec![255u8; width as usize * height as usize * 3];
    {
        let root = Canvas::new(&mut buf, (width, height)).into_drawing_area();
        // Text that does not fit is clipped by plotters; nothing here can
        // fail but the font, which `plotters_font::register` has checked.
        let _ = draw(&root, h, &font, left, width);
        root.present().ok();
    }
    RgbImage::from_raw(width, height, buf).expect("buffer of width x height x 3")
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    h: &HeatMap,
    font: &TextStyle,
    left: u32,
    width: u32,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let (left, cell, top) = (left as i32, CELL as i32, TOP as i32);
    let black = font.color(&BLACK);
    fn centered(style: TextStyle<'_>) -> TextStyle<'_> {
        style.pos(Pos::new(HPos::Center, VPos::Center))
    }
    root.draw(&PlotText::new(
        h.title.clone(),
        (width as i32 / 2, 14),
        centered(font.color(&BLACK)),
    ))?;
    for (j, label) in h.column_labels.iter().enumerate() {
        let x = left + cell * j as i32 + cell / 2;
        root.draw(&PlotText::new(
            label.clone(),
            (x, top - 24),
            centered(font.color(&BLACK)),
        ))?;
    }
    for (i, label) in h.row_labels.iter().enumerate() {
        let y = top + cell * i as i32;
        root.draw(&PlotText::new(
            label.clone(),
            (8, y + cell / 2),
            black.clone().pos(Pos::new(HPos::Left, VPos::Center)),
        ))?;
        for j in 0..h.column_labels.len() {
            let x = left + cell * j as i32;
            let value = h
                .cells
                .get(i)
                .and_then(|row| row.get(j))
                .copied()
                .flatten()
                .filter(|v| v.is_finite());
            if let Some(v) = value {
                root.draw(&Rectangle::new(
                    [(x, y), (x + cell, y + cell)],
                    cell_color(v).filled(),
                ))?;
                root.draw(&PlotText::new(
                    format!("{:.0}", 100.0 * v),
                    (x + cell / 2, y + cell / 2),
                    centered(font.color(&WHITE)),
                ))?;
            }
            root.draw(&Rectangle::new(
                [(x, y), (x + cell, y + cell)],
                RGBColor(200, 200, 200),
            ))?;
        }
    }
    let notes_x = left + cell * h.column_labels.len() as i32 + 20;
    if notes_x + 200 < width as i32 {
        for (k, line) in h.notes.iter().enumerate() {
            root.draw(&PlotText::new(
                line.clone(),
                (notes_x, top + 14 * k as i32),
                font.color(&RGBColor(60, 60, 60)),
            ))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn count(img: &RgbImage, c: RGBColor) -> usize {
        img.pixels().filter(|p| p.0 == [c.0, c.1, c.2]).count()
    }

    #[test]
    fn cells_are_coloured_by_value_and_blank_without_one() {
        let h = HeatMap {
            title: "payoff".into(),
            row_labels: vec!["#1 captors-main".into(), "#2 expert-captors".into()],
            column_labels: vec!["#3".into(), "#4".into()],
            cells: vec![vec![Some(1.0), None], vec![Some(0.0), Some(f64::NAN)]],
            notes: vec!["#3 target-main".into()],
        };
        let img = heat_map(&h);
        assert_eq!(img.dimensions(), (900, 200));
        // One red and one blue cell, each less the white digits drawn on it.
        let (red, blue) = (count(&img, cell_color(1.0)), count(&img, cell_color(0.0)));
        let full = (CELL * CELL) as usize;
        assert!(red > full / 2 && red < full, "{red}");
        assert!(blue > full / 2 && blue < full, "{blue}");
        // The blank cells (no games, NaN) stay white inside their border.
        let left = 230;
        let (x, y) = (left + CELL + CELL / 2, TOP + 4);
        assert_eq!(img.get_pixel(x, y).0, [255, 255, 255]);
        let (x, y) = (left + CELL + CELL / 2, TOP + CELL + 4);
        assert_eq!(img.get_pixel(x, y).0, [255, 255, 255]);
        // Labels are drawn: dark pixels left of the cells.
        let dark_left = img
            .enumerate_pixels()
            .filter(|(x, _, p)| *x < left && p.0.iter().all(|c| *c < 100))
            .count();
        assert!(dark_left > 50, "{dark_left}");
    }

    #[test]
    fn long_row_labels_and_many_columns_widen_the_image() {
        let h = HeatMap {
            row_labels: vec!["#12 captors-exploiter-snap-0000000000000000000000000000".into()],
            column_labels: (0..40).map(|i| format!("#{i}")).collect(),
            cells: vec![vec![Some(0.5); 40]],
            ..HeatMap::default()
        };
        let img = heat_map(&h);
        assert!(img.width() > 230 + 40 * CELL, "{}", img.width());
        assert!(count(&img, cell_color(0.5)) > 40 * (CELL * CELL) as usize / 2);
        // An empty map is an image too.
        assert_eq!(heat_map(&HeatMap::default()).dimensions(), (900, 200));
    }
}
