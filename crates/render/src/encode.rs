//! Encoding previews: PNG stills and looping animated GIF time-lapses, into byte buffers.

use crate::RenderError;
use image::codecs::gif::{GifEncoder, Repeat};
use image::codecs::png::PngEncoder;
use image::{Delay, Frame, ImageEncoder, RgbaImage};

/// NeuQuant sampling speed of the GIF palette quantiser (1 = best, 30 = fastest); 10 is the
/// gif crate's recommended balance, fast enough for 512-pixel frames.
pub const GIF_QUANTISER_SPEED: i32 = 10;

/// The largest GIF side, pixels (the format stores sizes in 16 bits).
pub const GIF_MAX_SIDE: u32 = u16::MAX as u32;

/// The image as an RGBA8 PNG.
pub fn encode_png(img: &RgbaImage) -> Result<Vec<u8>, RenderError> {
    let mut out = Vec::new();
    PngEncoder::new(&mut out)
        .write_image(
            img.as_raw(),
            img.width(),
            img.height(),
            image::ExtendedColorType::Rgba8,
        )
        .map_err(|source| RenderError::Encode {
            format: "PNG",
            source,
        })?;
    Ok(out)
}

/// The frames as a looping animated GIF (GIF89a, repeat forever), each shown for
/// `frame_delay_ms` milliseconds (GIF stores hundredths of a second, so the delay is
/// rounded down to 10 ms steps). Every frame must have the size of the first.
pub fn encode_gif(frames: &[RgbaImage], frame_delay_ms: u32) -> Result<Vec<u8>, RenderError> {
    let first = frames.first().ok_or(RenderError::NoFrames)?;
    let (width, height) = first.dimensions();
    if width > GIF_MAX_SIDE || height > GIF_MAX_SIDE || width == 0 || height == 0 {
        return Err(RenderError::ImageTooLarge {
            width: width as usize,
            height: height as usize,
            limit: "GIF frames need sides between 1 and 65535 pixels",
        });
    }
    for (index, frame) in frames.iter().enumerate() {
        let (actual_width, actual_height) = frame.dimensions();
        if (actual_width, actual_height) != (width, height) {
            return Err(RenderError::FrameSizeMismatch {
                index,
                width,
                height,
                actual_width,
                actual_height,
            });
        }
    }
    let gif_error = |source| RenderError::Encode {
        format: "GIF",
        source,
    };
    let mut out = Vec::new();
    {
        let mut encoder = GifEncoder::new_with_speed(&mut out, GIF_QUANTISER_SPEED);
        encoder.set_repeat(Repeat::Infinite).map_err(gif_error)?;
        let delay = Delay::from_numer_denom_ms(frame_delay_ms, 1);
        for frame in frames {
            encoder
                .encode_frame(Frame::from_parts(frame.clone(), 0, 0, delay))
                .map_err(gif_error)?;
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::AnimationDecoder;
    use image::codecs::gif::GifDecoder;
    use std::io::Cursor;

    fn frame(w: u32, h: u32, shade: u8) -> RgbaImage {
        RgbaImage::from_fn(w, h, |x, y| {
            image::Rgba([shade, (x * 7) as u8, (y * 5) as u8, 255])
        })
    }

    #[test]
    fn gif_loops_and_decodes_back_to_every_frame() {
        let frames: Vec<_> = (0..5).map(|k| frame(48, 32, 40 * k)).collect();
        let bytes = encode_gif(&frames, 120).unwrap();
        assert_eq!(&bytes[..6], b"GIF89a");
        // The NETSCAPE2.0 application extension carries the loop count (0 = forever).
        let netscape = bytes.windows(11).position(|w| w == b"NETSCAPE2.0");
        let at = netscape.expect("loop extension") + 11;
        assert_eq!(&bytes[at..at + 4], &[3, 1, 0, 0]);
        let decoded = GifDecoder::new(Cursor::new(bytes))
            .unwrap()
            .into_frames()
            .collect_frames()
            .unwrap();
        assert_eq!(decoded.len(), 5);
        for f in &decoded {
            assert_eq!(f.buffer().dimensions(), (48, 32));
            let (num, den) = f.delay().numer_denom_ms();
            assert_eq!(num / den, 120);
        }
        // Frame k's red channel is 40 k (quantisation may move it a little).
        let red = decoded[3].buffer().get_pixel(10, 10)[0];
        assert!((red as i32 - 120).abs() <= 8, "{red}");
    }

    #[test]
    fn gif_rejects_empty_and_mismatched_frames() {
        assert!(matches!(encode_gif(&[], 100), Err(RenderError::NoFrames)));
        let e = encode_gif(&[frame(8, 8, 0), frame(8, 8, 1), frame(9, 8, 2)], 100).unwrap_err();
        assert!(matches!(
            e,
            RenderError::FrameSizeMismatch {
                index: 2,
                actual_width: 9,
                ..
            }
        ));
    }

    #[test]
    fn png_round_trips() {
        let img = frame(20, 10, 99);
        let bytes = encode_png(&img).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
        let back = image::load_from_memory_with_format(&bytes, image::ImageFormat::Png)
            .unwrap()
            .to_rgba8();
        assert_eq!(back, img);
    }
}
