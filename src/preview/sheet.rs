//! The contact sheet: frames laid out left to right, top to bottom, in a grid about as wide as
//! it is tall, each labelled with its frame number in the built-in font.

use super::font;
use super::picture::Picture;
use super::raster::Rgb;

/// Pixels between tiles and around the sheet.
const GAP: u32 = 4;
/// The colour between tiles.
const GAP_COLOUR: Rgb = [90, 92, 98];
/// The colour of the labels.
const INK: Rgb = [40, 40, 48];
/// Label position from the tile's top-left corner, in pixels.
const LABEL: (u32, u32) = (6, 6);

/// The number of columns that makes a sheet of `count` tiles of `width × height` closest to
/// square.
#[must_use]
pub fn columns(count: usize, width: u32, height: u32) -> u32 {
    let count = count.max(1) as u32;
    (1..=count)
        .min_by(|&a, &b| {
            let aspect = |c: u32| {
                let rows = count.div_ceil(c);
                let ratio = f64::from(c * width) / f64::from(rows * height);
                ratio.ln().abs()
            };
            aspect(a).total_cmp(&aspect(b))
        })
        .unwrap_or(1)
}

/// Writes `frame` in the tile's top-left corner, one font pixel to 1–3 pixels as the tile is
/// under 240, under 360 or taller.
pub fn label(tile: &mut Picture, frame: u32) {
    let (x0, y0) = LABEL;
    let scale = (tile.height() / 120).clamp(1, 3);
    for (x, y) in font::pixels(frame) {
        for dy in 0..scale {
            for dx in 0..scale {
                let (px, py) = (x0 + x as u32 * scale + dx, y0 + y as u32 * scale + dy);
                if px < tile.width() && py < tile.height() {
                    tile.set(px, py, INK);
                }
            }
        }
    }
}

/// Lays `tiles` (all the same size) out in a grid.
///
/// # Panics
/// When `tiles` is empty.
#[must_use]
pub fn compose(tiles: &[Picture]) -> Picture {
    let (w, h) = (tiles[0].width(), tiles[0].height());
    let cols = columns(tiles.len(), w, h);
    let rows = (tiles.len() as u32).div_ceil(cols);
    let mut sheet = Picture::filled(cols * (w + GAP) + GAP, rows * (h + GAP) + GAP, GAP_COLOUR);
    for (i, tile) in tiles.iter().enumerate() {
        let (col, row) = (i as u32 % cols, i as u32 / cols);
        let (x, y) = (GAP + col * (w + GAP), GAP + row * (h + GAP));
        sheet.paste(tile, x, y);
    }
    sheet
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sheets_are_about_square() {
        assert_eq!(columns(1, 300, 400), 1);
        assert_eq!(columns(4, 100, 100), 2);
        assert_eq!(columns(9, 100, 100), 3);
        assert_eq!(columns(12, 300, 400), 4);
        assert_eq!(columns(3, 100, 400), 3);
    }

    #[test]
    fn compose_places_tiles_in_reading_order() {
        let tiles: Vec<Picture> = (0..3u8).map(|i| Picture::filled(2, 2, [i, i, i])).collect();
        let sheet = compose(&tiles);
        assert_eq!((sheet.width(), sheet.height()), (2 * 6 + GAP, 2 * 6 + GAP));
        assert_eq!(sheet.get(GAP, GAP), [0, 0, 0]);
        assert_eq!(sheet.get(2 * GAP + 2, GAP), [1, 1, 1]);
        assert_eq!(sheet.get(GAP, 2 * GAP + 2), [2, 2, 2]);
        assert_eq!(sheet.get(2 * GAP + 2, 2 * GAP + 2), GAP_COLOUR);
    }
}
