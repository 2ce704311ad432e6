//! Writes the boundary alpha mask composited over a dark ground, to look at its shape:
//! `cargo run --release -p snowscape-festenberg --example mask_preview -- OUT.png`.

use snowscape_festenberg::mask::{MASK_SIZE, boundary_mask};

fn main() {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "mask_preview.png".into());
    let m = boundary_mask(MASK_SIZE, 1);
    let img = image::RgbImage::from_fn(m.width() * 2, m.height(), |x, y| {
        let p = m.get_pixel(x % m.width(), y).0;
        let a = p[3] as f32 / 255.0;
        let ground = [60.0, 70.0, 55.0];
        image::Rgb([0, 1, 2].map(|k| (p[k] as f32 * a + ground[k] * (1.0 - a)) as u8))
    });
    img.save(&out).expect("write the preview");
}
