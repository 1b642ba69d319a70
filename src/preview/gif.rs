//! The frames as an animated GIF that loops forever, through the `image` crate's encoder: each
//! frame gets its own 256-colour palette by NeuQuant (Dekker, "Kohonen neural networks for
//! optimal colour quantization", 1994), which is deterministic, so the same frames give the
//! same bytes.

use std::io::{self, Write};

use image::codecs::gif::{GifEncoder, Repeat};
use image::{Delay, DynamicImage, Frame, RgbImage};

/// NeuQuant's sampling factor (1 best, 30 fastest); 10 is its recommended balance.
const SPEED: i32 = 10;

/// Encodes `frames` (all the same size, at most 65535 pixels a side) shown `fps` times a second
/// (GIF rounds each delay to hundredths of a second).
///
/// # Errors
/// When writing fails or a frame is too large for GIF.
pub fn encode(out: &mut impl Write, frames: &[RgbImage], fps: u32) -> io::Result<()> {
    let mut encoder = GifEncoder::new_with_speed(out, SPEED);
    encoder
        .set_repeat(Repeat::Infinite)
        .map_err(io::Error::other)?;
    let delay = Delay::from_numer_denom_ms(1000, fps);
    encoder
        .encode_frames(frames.iter().map(|f| {
            let rgba = DynamicImage::ImageRgb8(f.clone()).into_rgba8();
            Frame::from_parts(rgba, 0, 0, delay)
        }))
        .map_err(io::Error::other)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn encodes_a_looping_animation_deterministically() {
        let frames: Vec<RgbImage> = (0..3u8)
            .map(|i| {
                RgbImage::from_fn(8, 6, |x, y| {
                    image::Rgb([i * 80, x as u8 * 30, y as u8 * 40])
                })
            })
            .collect();
        let mut first = Vec::new();
        encode(&mut first, &frames, 12).unwrap();
        let mut second = Vec::new();
        encode(&mut second, &frames, 12).unwrap();
        assert_eq!(first, second);
        assert!(first.starts_with(b"GIF89a"));
        assert!(
            first.windows(11).any(|w| w == b"NETSCAPE2.0"),
            "no loop extension"
        );
    }
}
