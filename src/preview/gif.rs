//! The frames as an animated GIF that loops forever, through the `gif` crate's encoder: each
//! frame gets its own 256-colour palette by NeuQuant (Dekker, "Kohonen neural networks for
//! optimal colour quantization", 1994), which is deterministic, so the same frames give the
//! same bytes.

use std::io::{self, Write};

use super::picture::Picture;

/// NeuQuant's sampling factor (1 best, 30 fastest); 10 is its recommended balance.
const SPEED: i32 = 10;

/// Encodes `frames` (all the same size, at most 65535 pixels a side) shown `fps` times a second
/// (GIF rounds each delay to hundredths of a second).
///
/// # Errors
/// When writing fails or a frame is too large for GIF.
pub fn encode(out: &mut impl Write, frames: &[Picture], fps: u32) -> io::Result<()> {
    let Some(first) = frames.first() else {
        return Ok(());
    };
    let side = |n: u32| {
        u16::try_from(n).map_err(|_| io::Error::other(format!("{n} pixels is too large for GIF")))
    };
    let (width, height) = (side(first.width())?, side(first.height())?);
    let mut encoder = ::gif::Encoder::new(out, width, height, &[]).map_err(io::Error::other)?;
    encoder
        .set_repeat(::gif::Repeat::Infinite)
        .map_err(io::Error::other)?;
    // Hundredths of a second, rounded.
    let fps = fps.max(1);
    let delay = u16::try_from((100 + fps / 2) / fps).map_or(u16::MAX, |d| d.max(1));
    for picture in frames {
        let mut frame = ::gif::Frame::from_rgb_speed(width, height, picture.bytes(), SPEED);
        frame.delay = delay;
        encoder.write_frame(&frame).map_err(io::Error::other)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn encodes_a_looping_animation_deterministically() {
        let frames: Vec<Picture> = (0..3u8)
            .map(|i| {
                let mut p = Picture::filled(8, 6, [0, 0, 0]);
                for (x, y) in (0..8).flat_map(|x| (0..6).map(move |y| (x, y))) {
                    p.set(x, y, [i * 80, x as u8 * 30, y as u8 * 40]);
                }
                p
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
