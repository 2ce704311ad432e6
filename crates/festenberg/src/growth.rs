//! Snow-cover growth (von Festenberg & Gumhold 2011, Section 4, Eq. 2, and the growth
//! animation of Section 6): `∂h/∂t = D ∇²h + σ(x)`, "iteratively accumulating solutions of
//! Equation (2) with a diffusion kernel as small as a four-nearest-neighbours Laplacian
//! without bridges and overhangs".
//!
//! Discretisation: explicit Euler on the four-neighbour graph of [`crate::links`], time step
//! at most `stability · dx² / (4 D)` (the 2D explicit limit) and a whole number of steps per
//! frame. Linked neighbours exchange snow; a wall (a rise of more than `h0`) and the map's
//! border pass none (zero flux); a site next to a drop is a snow boundary held at `h = 0`
//! (Dirichlet, "vanishing snow heights at boundaries"; Fig. 2's rod has `h(0) = h(1) = 0`).
//! The snowfall `σ(x)` falls on sites open to the sky (the vertical visibility of Section 4:
//! "local vertical visibility can be expressed in the variation of σ with x"); heights are
//! capped at each site's capacity. The state is f64, so long runs do not drift.

use crate::error::{FestenbergError, invalid};
use crate::links::{Link, SiteLinks};
use crate::sites::SiteField;
use rayon::prelude::*;
use serde::Serialize;

/// Parameters of a growth run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct GrowthParams {
    /// Diffusion coefficient `D`, m² per unit time (Eq. 2; Fig. 2 uses 0.001 to 0.1).
    pub diffusion_m2: f64,
    /// Snowfall rate `σ`, metres per unit time.
    pub snowfall_m: f64,
    /// Simulated time, units.
    pub duration: f64,
    /// Frames handed out, evenly spaced in time (the last at `duration`).
    pub frames: usize,
    /// Share of the explicit stability limit used as time step (0, 1].
    pub stability: f64,
}

impl Default for GrowthParams {
    /// The paper's supplementary animation has 64 frames.
    fn default() -> Self {
        Self {
            diffusion_m2: 0.01,
            snowfall_m: 0.01,
            duration: 1.0,
            frames: 64,
            stability: 0.9,
        }
    }
}

impl GrowthParams {
    /// The growth animation of a cover with the lengths `r`, in `frames` frames: one unit of
    /// time in which `σ = h0` lays the cover's open-ground depth and `D = R² / 2` spreads the
    /// edges over the kernel radius (a heat kernel of variance `2Dt = R²`), at 0.9 of the
    /// explicit stability limit. What `snowscape cover --growth N` animates.
    pub fn for_cover(r: &crate::Resolved, frames: usize) -> Self {
        Self {
            diffusion_m2: 0.5 * r.radius_m * r.radius_m,
            snowfall_m: r.depth_m,
            duration: 1.0,
            frames,
            stability: 0.9,
        }
    }
}

/// What a growth run did.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct GrowthReport {
    pub steps: usize,
    pub time_step: f64,
    /// Snow volume at the end, m³.
    pub volume_m3: f64,
}

/// Runs Eq. 2 from `h = 0`, calling `frame(index, time, heights)` after each frame.
pub fn grow<E: From<FestenbergError>>(
    field: &SiteField,
    links: &[SiteLinks],
    params: &GrowthParams,
    mut frame: impl FnMut(usize, f64, &[f32]) -> Result<(), E>,
) -> Result<GrowthReport, E> {
    let p = params;
    if !(p.diffusion_m2.is_finite() && p.diffusion_m2 > 0.0) {
        return Err(invalid(
            "diffusion coefficient D",
            p.diffusion_m2,
            "a finite value > 0 m²",
        )
        .into());
    }
    if !(p.snowfall_m.is_finite() && p.snowfall_m >= 0.0) {
        return Err(invalid("snowfall rate", p.snowfall_m, "a finite rate >= 0 m").into());
    }
    if !(p.duration.is_finite() && p.duration > 0.0) {
        return Err(invalid("growth duration", p.duration, "a finite time > 0").into());
    }
    if !(p.stability > 0.0 && p.stability <= 1.0) {
        return Err(invalid("growth stability share", p.stability, "a share in (0, 1]").into());
    }
    if p.frames == 0 || p.frames > 100_000 {
        return Err(invalid("growth frames", p.frames as f64, "1..=100000 frames").into());
    }
    let dx2 = field.cell_size * field.cell_size;
    let dt_max = p.stability * dx2 / (4.0 * p.diffusion_m2);
    let frame_time = p.duration / p.frames as f64;
    let steps_per_frame = (frame_time / dt_max).ceil().max(1.0) as usize;
    if steps_per_frame.saturating_mul(p.frames) > 50_000_000 {
        return Err(invalid(
            "growth steps",
            (steps_per_frame * p.frames) as f64,
            "at most 5e7 explicit steps (a larger resolution or a smaller D or duration)",
        )
        .into());
    }
    let dt = frame_time / steps_per_frame as f64;
    let k = p.diffusion_m2 * dt / dx2;
    let fixed: Vec<bool> = links.iter().map(|l| l.contains(&Link::Drop)).collect();
    let source: Vec<f64> = (0..field.len())
        .map(|i| {
            if field.visible(i) {
                p.snowfall_m * dt
            } else {
                0.0
            }
        })
        .collect();
    let mut h = vec![0.0f64; field.len()];
    let mut next = vec![0.0f64; field.len()];
    let mut out = vec![0.0f32; field.len()];
    for f in 0..p.frames {
        for _ in 0..steps_per_frame {
            next.par_iter_mut()
                .enumerate()
                .with_min_len(4096)
                .for_each(|(i, n)| {
                    if fixed[i] {
                        *n = 0.0;
                        return;
                    }
                    let mut lap = 0.0;
                    for l in &links[i] {
                        if let Some(j) = l.site() {
                            lap += h[j] - h[i];
                        }
                    }
                    *n = (h[i] + k * lap + source[i]).clamp(0.0, field.capacity[i] as f64);
                });
            std::mem::swap(&mut h, &mut next);
        }
        for (o, v) in out.iter_mut().zip(&h) {
            *o = *v as f32;
        }
        frame(f, frame_time * (f + 1) as f64, &out)?;
    }
    Ok(GrowthReport {
        steps: steps_per_frame * p.frames,
        time_step: dt,
        volume_m3: h.iter().sum::<f64>() * dx2,
    })
}

/// The closed-form solution of Eq. 2 on the rod `[0, 1]` with `h(0) = h(1) = 0`,
/// `h(x, 0) = 0` and constant `σ` (Fig. 2): `h = Σ_{n odd} 4σ / (D n³ π³) (1 - e^{-D n² π² t})
/// sin(nπx)`, summed until the terms fall below 1e-12 of the first.
pub fn rod_solution(x: f64, t: f64, diffusion: f64, snowfall: f64) -> f64 {
    let pi = std::f64::consts::PI;
    let mut sum = 0.0;
    let mut n = 1.0f64;
    loop {
        let amp = 4.0 * snowfall / (diffusion * n.powi(3) * pi.powi(3));
        let term = amp * (1.0 - (-diffusion * n * n * pi * pi * t).exp()) * (n * pi * x).sin();
        sum += term;
        if amp < 1e-12 * 4.0 * snowfall / (diffusion * pi.powi(3)) || n > 1e5 {
            break;
        }
        n += 2.0;
    }
    sum
}
