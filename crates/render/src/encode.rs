//! Encoding previews: PNG stills and looping animated GIF time-lapses, into byte buffers.

use crate::RenderError;
use image::codecs::png::PngEncoder;
use image::{ImageEncoder, RgbaImage};
use rayon::prelude::*;

/// NeuQuant sampling speed of the GIF palette quantiser (1 = best, 30 = fastest); 10 is the
/// gif crate's recommended balance (the palette is trained once per GIF).
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
///
/// One 256-colour palette serves every frame (the GIF's global colour table): NeuQuant
/// (Dekker 1994) trained once on a sample of all frames' pixels, and a table from each colour
/// quantised to 6 bits per channel to its palette entry, so that a pixel costs a lookup. A
/// palette per frame cost 40 % of an avalanche command and made colours flicker between
/// frames.
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
    let palette = GifPalette::train(frames);
    let indexed = palette.index_frames(frames);
    let mut out = Vec::new();
    {
        let mut encoder = gif::Encoder::new(&mut out, width as u16, height as u16, &palette.rgb)?;
        encoder.set_repeat(gif::Repeat::Infinite)?;
        let delay = (frame_delay_ms / 10).min(u16::MAX as u32) as u16;
        for pixels in indexed {
            let mut frame =
                gif::Frame::from_indexed_pixels(width as u16, height as u16, pixels, None);
            frame.delay = delay;
            encoder.write_frame(&frame)?;
        }
    }
    Ok(out)
}

/// Pixels of all frames NeuQuant learns the palette from, at most.
const PALETTE_SAMPLE_PIXELS: usize = 1 << 20;

/// Bits per channel of the colour-to-entry table.
const TABLE_BITS: u32 = 6;

/// A GIF palette for a set of frames, and how a colour finds its entry.
struct GifPalette {
    /// 256 entries, `[r, g, b, ...]`.
    rgb: Vec<u8>,
    nq: color_quant::NeuQuant,
}

/// Marks a colour whose entry is not looked up yet.
const UNSET: u16 = u16::MAX;

impl GifPalette {
    fn train(frames: &[RgbaImage]) -> Self {
        let pixels: usize = frames.iter().map(|f| f.as_raw().len() / 4).sum();
        let stride = pixels.div_ceil(PALETTE_SAMPLE_PIXELS).max(1);
        let mut sample = Vec::with_capacity(4 * pixels.div_ceil(stride));
        let mut k = 0usize;
        for f in frames {
            for p in f.as_raw().chunks_exact(4) {
                if k.is_multiple_of(stride) {
                    sample.extend_from_slice(&[p[0], p[1], p[2], 255]);
                }
                k += 1;
            }
        }
        let nq = color_quant::NeuQuant::new(GIF_QUANTISER_SPEED, 256, &sample);
        let mut rgb = nq.color_map_rgb();
        rgb.resize(3 * 256, 0);
        Self { rgb, nq }
    }

    /// Every frame's pixels as palette entries. Each colour, quantised to [`TABLE_BITS`] per
    /// channel, is looked up once per worker (at the centre of its bin) and then read from a
    /// table: frames hold few distinct colours.
    fn index_frames(&self, frames: &[RgbaImage]) -> Vec<Vec<u8>> {
        let levels = 1usize << TABLE_BITS;
        let shift = 8 - TABLE_BITS;
        let centre = |v: usize| ((v << shift) + (1 << (shift - 1))) as u8;
        frames
            .par_iter()
            .map_init(
                || vec![UNSET; levels * levels * levels],
                |table, frame| {
                    frame
                        .as_raw()
                        .chunks_exact(4)
                        .map(|p| {
                            let (r, g, b) = (
                                (p[0] >> shift) as usize,
                                (p[1] >> shift) as usize,
                                (p[2] >> shift) as usize,
                            );
                            let slot = &mut table[(r << (2 * TABLE_BITS)) | (g << TABLE_BITS) | b];
                            if *slot == UNSET {
                                *slot = self.nq.index_of(&[centre(r), centre(g), centre(b), 255])
                                    as u16;
                            }
                            *slot as u8
                        })
                        .collect()
                },
            )
            .collect()
    }
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
        // One palette of 256 colours for 7680 distinct ones spread over the colour cube (a
        // hard case: per-frame palettes do better here, at 40 % of an avalanche command).
        let (mean, worst) = gif_error(&frames);
        eprintln!("GIF colour error: mean {mean:.2}, worst {worst} levels");
        assert!(mean < 16.0 && worst <= 64, "mean {mean}, worst {worst}");
    }

    /// Mean and worst error per channel, levels, of a GIF's frames against the originals.
    fn gif_error(frames: &[RgbaImage]) -> (f64, i32) {
        let bytes = encode_gif(frames, 100).unwrap();
        let decoded = GifDecoder::new(Cursor::new(bytes))
            .unwrap()
            .into_frames()
            .collect_frames()
            .unwrap();
        let (mut sum, mut worst, mut n) = (0i64, 0i32, 0i64);
        for (f, d) in frames.iter().zip(&decoded) {
            for (a, b) in f.pixels().zip(d.buffer().pixels()) {
                for ch in 0..3 {
                    let e = (a[ch] as i32 - b[ch] as i32).abs();
                    (sum, worst, n) = (sum + e as i64, worst.max(e), n + 1);
                }
            }
        }
        (sum as f64 / n as f64, worst)
    }

    #[test]
    fn a_time_lapse_keeps_its_colours_in_one_palette() {
        // A shaded slope (brown rock) that snow (blue-white) covers from the top down, as a
        // season's time-lapse does.
        let frames: Vec<RgbaImage> = (0..12)
            .map(|k| {
                RgbaImage::from_fn(160, 120, |x, y| {
                    let shade = 0.55 + 0.45 * ((x as f32 * 0.07).sin() * (y as f32 * 0.05).cos());
                    let rgb = if y < 10 * k {
                        [235.0, 240.0, 250.0]
                    } else {
                        [140.0, 110.0, 80.0]
                    };
                    let c = |v: f32| (v * shade).clamp(0.0, 255.0) as u8;
                    image::Rgba([c(rgb[0]), c(rgb[1]), c(rgb[2]), 255])
                })
            })
            .collect();
        let (mean, worst) = gif_error(&frames);
        eprintln!("time-lapse GIF colour error: mean {mean:.2}, worst {worst} levels");
        assert!(mean < 3.0 && worst <= 16, "mean {mean}, worst {worst}");
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
