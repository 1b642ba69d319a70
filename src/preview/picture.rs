//! An 8-bit RGB picture in memory, and its PNG encoding through the `png` crate.
//!
//! The preview needs little of an image library: a pixel buffer to compose tiles in, PNG out
//! and (in [`super::gif`]) GIF out. The `png` and `gif` crates do the encoding; this type is
//! the buffer between them and the rasterizer.

use std::io::{self, Write};

use super::raster::Rgb;

/// Row-major RGB pixels, three bytes each.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Picture {
    width: u32,
    height: u32,
    bytes: Vec<u8>,
}

impl Picture {
    /// A `width × height` picture of one colour.
    #[must_use]
    pub fn filled(width: u32, height: u32, colour: Rgb) -> Self {
        Self {
            width,
            height,
            bytes: colour.repeat(width as usize * height as usize),
        }
    }

    /// The picture whose row-major RGB bytes are `bytes`, if there are `3 · width · height`.
    #[must_use]
    pub fn from_bytes(width: u32, height: u32, bytes: Vec<u8>) -> Option<Self> {
        (bytes.len() == 3 * width as usize * height as usize).then_some(Self {
            width,
            height,
            bytes,
        })
    }

    /// Width in pixels.
    #[must_use]
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    #[must_use]
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The row-major RGB bytes.
    #[must_use]
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }

    fn offset(&self, x: u32, y: u32) -> usize {
        assert!(
            x < self.width && y < self.height,
            "pixel ({x}, {y}) outside"
        );
        3 * (y as usize * self.width as usize + x as usize)
    }

    /// The colour at column `x`, row `y` (for tests: the tool only writes pictures).
    ///
    /// # Panics
    /// Outside the picture.
    #[cfg(test)]
    #[must_use]
    pub fn get(&self, x: u32, y: u32) -> Rgb {
        let i = self.offset(x, y);
        [self.bytes[i], self.bytes[i + 1], self.bytes[i + 2]]
    }

    /// Sets the colour at column `x`, row `y`.
    ///
    /// # Panics
    /// Outside the picture.
    pub fn set(&mut self, x: u32, y: u32, colour: Rgb) {
        let i = self.offset(x, y);
        self.bytes[i..i + 3].copy_from_slice(&colour);
    }

    /// Copies `other` in with its top-left corner at column `x`, row `y`.
    ///
    /// # Panics
    /// When it does not fit.
    pub fn paste(&mut self, other: &Self, x: u32, y: u32) {
        assert!(x + other.width <= self.width && y + other.height <= self.height);
        let row = 3 * other.width as usize;
        for (r, line) in other.bytes.chunks_exact(row).enumerate() {
            let start = self.offset(x, y + r as u32);
            self.bytes[start..start + row].copy_from_slice(line);
        }
    }

    /// Encodes the picture as PNG.
    ///
    /// # Errors
    /// When writing fails.
    pub fn write_png(&self, out: impl Write) -> io::Result<()> {
        let mut encoder = png::Encoder::new(out, self.width, self.height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(io::Error::other)?;
        writer
            .write_image_data(&self.bytes)
            .map_err(io::Error::other)?;
        writer.finish().map_err(io::Error::other)
    }

    /// Decodes an 8-bit RGB PNG (what [`Self::write_png`] writes; for tests).
    ///
    /// # Errors
    /// When reading fails or the PNG is not 8-bit RGB.
    #[cfg(test)]
    pub fn read_png(input: impl io::BufRead + io::Seek) -> io::Result<Self> {
        let mut reader = png::Decoder::new(input)
            .read_info()
            .map_err(io::Error::other)?;
        let size = reader.output_buffer_size().ok_or_else(|| {
            io::Error::new(io::ErrorKind::InvalidData, "PNG too large for memory")
        })?;
        let mut bytes = vec![0; size];
        let info = reader.next_frame(&mut bytes).map_err(io::Error::other)?;
        if (info.color_type, info.bit_depth) != (png::ColorType::Rgb, png::BitDepth::Eight) {
            return Err(io::Error::new(
                io::ErrorKind::InvalidData,
                "not an 8-bit RGB PNG",
            ));
        }
        bytes.truncate(info.buffer_size());
        Ok(Self::from_bytes(info.width, info.height, bytes).expect("the decoder's size"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pixels_paste_and_png_round_trip() {
        let mut p = Picture::filled(5, 4, [1, 2, 3]);
        p.set(4, 3, [9, 8, 7]);
        let mut q = Picture::filled(2, 2, [0, 0, 0]);
        q.set(1, 0, [5, 5, 5]);
        p.paste(&q, 3, 0);
        assert_eq!(
            (p.get(0, 0), p.get(4, 0), p.get(3, 1), p.get(4, 3)),
            ([1, 2, 3], [5, 5, 5], [0, 0, 0], [9, 8, 7])
        );
        let mut png = Vec::new();
        p.write_png(&mut png).unwrap();
        assert_eq!(Picture::read_png(io::Cursor::new(png)).unwrap(), p);
        assert!(Picture::from_bytes(2, 2, vec![0; 11]).is_none());
    }
}
