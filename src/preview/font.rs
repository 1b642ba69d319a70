//! A built-in 3 × 5 pixel font for the digits, enough to label frames without a font file.

/// Rows of each digit, top first; bit 2 is the left column.
const DIGITS: [[u8; 5]; 10] = [
    [0b111, 0b101, 0b101, 0b101, 0b111],
    [0b010, 0b110, 0b010, 0b010, 0b111],
    [0b111, 0b001, 0b111, 0b100, 0b111],
    [0b111, 0b001, 0b011, 0b001, 0b111],
    [0b101, 0b101, 0b111, 0b001, 0b001],
    [0b111, 0b100, 0b111, 0b001, 0b111],
    [0b111, 0b100, 0b111, 0b101, 0b111],
    [0b111, 0b001, 0b010, 0b010, 0b010],
    [0b111, 0b101, 0b111, 0b101, 0b111],
    [0b111, 0b101, 0b111, 0b001, 0b111],
];

/// Width and height of a glyph in font pixels, and the advance from one digit to the next.
pub const GLYPH: (usize, usize, usize) = (3, 5, 4);

/// The font pixels `(column, row)` that are set when `number` is written, left to right from
/// the origin.
pub fn pixels(number: u32) -> impl Iterator<Item = (usize, usize)> {
    number
        .to_string()
        .into_bytes()
        .into_iter()
        .enumerate()
        .flat_map(|(i, digit)| {
            let rows = DIGITS[usize::from(digit - b'0')];
            (0..GLYPH.1).flat_map(move |row| {
                (0..GLYPH.0)
                    .filter(move |&col| rows[row] >> (GLYPH.0 - 1 - col) & 1 == 1)
                    .map(move |col| (i * GLYPH.2 + col, row))
            })
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_is_a_stroke_with_a_flag_and_a_foot() {
        let mut grid = [[' '; 3]; 5];
        for (x, y) in pixels(1) {
            grid[y][x] = '#';
        }
        let text: Vec<String> = grid.iter().map(|r| r.iter().collect()).collect();
        assert_eq!(text, [" # ", "## ", " # ", " # ", "###"]);
    }

    #[test]
    fn digits_advance() {
        let right = pixels(10).map(|(x, _)| x).max();
        assert_eq!(right, Some(GLYPH.2 + 2));
    }
}
