//! Brushes: "directly painting height changes into the snow layers" (Cordonnier et al. 2018,
//! Section 3), and painting the avalanche release probability and the skier areas.
//!
//! A dab changes the cells within `radius_m` of its centre with a raised-cosine falloff
//! `w = (1 + cos(π d / r)) / 2`: add and remove change a value by `strength · w` metres,
//! smooth moves it towards its 3x3 mean and set towards `value`, both by `strength · w`.
//! Layers never go below 0 and paint maps stay within [0, 1]. On the total depth
//! ([`BrushTarget::All`]) a change keeps the layers' shares: more snow goes to the layers in
//! proportion (to the stable layer on bare ground), less snow comes off the top (powder,
//! unstable, stable, then compacted).
//!
//! Every change is recorded in an [`Edit`] (first value of each touched cell), so a stroke is
//! undone and redone exactly. A dab's radius may not exceed the terrain's extent (the
//! diagonal of its grid, [`max_radius_m`]; larger ones are refused): a dab's work is bounded
//! by the grid's cells, and a stroke's record by the cells it touched (the session bounds the
//! whole undo history by bytes, `session::UNDO_BUDGET_BYTES`).

use crate::protocol::{BrushOp, BrushTarget};
use snowscape_terrain::{LayeredTerrain, SnowLayer};
use std::collections::HashMap;

/// The editor's painted maps (grid-sized, row-major).
#[derive(Debug, Clone, PartialEq)]
pub struct PaintMaps {
    /// Avalanche release probability per day, 0..1.
    pub avalanche_probability: Vec<f32>,
    /// Skier area, 0..1.
    pub ski_area: Vec<f32>,
}

impl PaintMaps {
    pub fn new(cells: usize) -> Self {
        Self {
            avalanche_probability: vec![0.0; cells],
            ski_area: vec![0.0; cells],
        }
    }
}

/// A value the brushes can change: a snow layer or a paint map.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Slot {
    Layer(SnowLayer),
    AvalancheProbability,
    SkiArea,
}

/// One brush dab.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dab {
    pub op: BrushOp,
    pub target: BrushTarget,
    pub col: f64,
    pub row: f64,
    pub radius_m: f64,
    pub strength: f64,
    pub value: f64,
}

/// Cells a change touched: an inclusive rectangle of columns and rows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CellRect {
    pub c0: usize,
    pub r0: usize,
    pub c1: usize,
    pub r1: usize,
}

impl CellRect {
    /// The smallest rectangle holding both.
    pub fn union(self, o: CellRect) -> CellRect {
        CellRect {
            c0: self.c0.min(o.c0),
            r0: self.r0.min(o.r0),
            c1: self.c1.max(o.c1),
            r1: self.r1.max(o.r1),
        }
    }
}

/// The first values of the cells a stroke changed: undoing restores them.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Edit {
    pub stroke: u32,
    pub before: HashMap<(Slot, usize), f32>,
    /// Record nothing (a stroke past the undo history's budget: it cannot be undone).
    pub unrecorded: bool,
}

fn slot_values<'a>(t: &'a mut LayeredTerrain, p: &'a mut PaintMaps, s: Slot) -> &'a mut [f32] {
    match s {
        Slot::Layer(l) => t.layer_mut(l),
        Slot::AvalancheProbability => &mut p.avalanche_probability,
        Slot::SkiArea => &mut p.ski_area,
    }
}

impl Edit {
    /// Whether the edit changed nothing.
    pub fn is_empty(&self) -> bool {
        self.before.is_empty()
    }

    /// Estimated memory of the edit, bytes: its map's buckets (key, value and control byte,
    /// at the map's 7/8 load) and the edit itself.
    pub fn bytes(&self) -> u64 {
        let bucket = std::mem::size_of::<((Slot, usize), f32)>() + 1;
        let buckets = self.before.capacity().saturating_mul(8) / 7;
        (buckets * bucket + std::mem::size_of::<Self>()) as u64
    }

    /// Puts the recorded values back and returns the edit that redoes the change, with the
    /// cells it touched.
    pub fn revert(
        &self,
        terrain: &mut LayeredTerrain,
        paint: &mut PaintMaps,
    ) -> (Edit, Option<CellRect>) {
        let w = terrain.geometry().width();
        let mut inverse = Edit {
            stroke: self.stroke,
            before: HashMap::with_capacity(self.before.len()),
            unrecorded: false,
        };
        let mut rect: Option<CellRect> = None;
        for (&(slot, i), &v) in &self.before {
            let values = slot_values(terrain, paint, slot);
            if let Some(cur) = values.get_mut(i) {
                inverse.before.insert((slot, i), *cur);
                *cur = v;
                let (c, r) = (i % w, i / w);
                let cell = CellRect {
                    c0: c,
                    r0: r,
                    c1: c,
                    r1: r,
                };
                rect = Some(rect.map_or(cell, |x| x.union(cell)));
            }
        }
        (inverse, rect)
    }
}

fn record(edit: &mut Edit, slot: Slot, i: usize, old: f32) {
    if edit.unrecorded {
        return;
    }
    edit.before.entry((slot, i)).or_insert(old);
}

/// Changes the total depth of cell `i` to `new` keeping the layer shares (see module docs).
fn set_total(terrain: &mut LayeredTerrain, edit: &mut Edit, i: usize, new: f32) {
    let layers = SnowLayer::ALL.map(|l| terrain.layer(l)[i]);
    let total: f32 = layers.iter().sum();
    let new = new.max(0.0);
    let mut out = layers;
    if new > total {
        if total > 0.0 {
            out = layers.map(|v| v * (new / total));
        } else {
            out[SnowLayer::Stable.index()] = new;
        }
    } else {
        let mut excess = total - new;
        for l in [3, 2, 1, 0] {
            let take = out[l].min(excess);
            out[l] -= take;
            excess -= take;
        }
    }
    for (l, &v) in SnowLayer::ALL.iter().zip(&out) {
        let cur = terrain.layer(*l)[i];
        if cur != v {
            record(edit, Slot::Layer(*l), i, cur);
            terrain.layer_mut(*l)[i] = v;
        }
    }
}

/// The value of the target at cell `i` (the total depth for [`BrushTarget::All`]).
fn read(terrain: &LayeredTerrain, paint: &PaintMaps, target: BrushTarget, i: usize) -> f32 {
    match target {
        BrushTarget::All => terrain.depth_at(i),
        BrushTarget::Compacted => terrain.layer(SnowLayer::Compacted)[i],
        BrushTarget::Stable => terrain.layer(SnowLayer::Stable)[i],
        BrushTarget::Unstable => terrain.layer(SnowLayer::Unstable)[i],
        BrushTarget::Powder => terrain.layer(SnowLayer::Powder)[i],
        BrushTarget::AvalancheProbability => paint.avalanche_probability[i],
        BrushTarget::SkiArea => paint.ski_area[i],
    }
}

/// The largest brush radius on `terrain`, m: the diagonal of its grid (a dab that size covers
/// every cell from anywhere on it).
pub fn max_radius_m(terrain: &LayeredTerrain) -> f64 {
    let g = terrain.geometry();
    (g.width() as f64 * g.cell_size_x()).hypot(g.height() as f64 * g.cell_size_y())
}

/// Applies one dab; returns the cells it may have changed (`None` when it misses the grid).
pub fn apply(
    terrain: &mut LayeredTerrain,
    paint: &mut PaintMaps,
    dab: &Dab,
    edit: &mut Edit,
) -> Option<CellRect> {
    let g = terrain.geometry().clone();
    let (w, h) = (g.width(), g.height());
    let (dx, dy) = (g.cell_size_x(), g.cell_size_y());
    let rc = dab.radius_m / dx;
    let rr = dab.radius_m / dy;
    let c0 = (dab.col - rc).floor().max(0.0);
    let r0 = (dab.row - rr).floor().max(0.0);
    let c1 = (dab.col + rc).ceil().min(w as f64 - 1.0);
    let r1 = (dab.row + rr).ceil().min(h as f64 - 1.0);
    if c1 < c0 || r1 < r0 {
        return None;
    }
    let rect = CellRect {
        c0: c0 as usize,
        r0: r0 as usize,
        c1: c1 as usize,
        r1: r1 as usize,
    };
    // Smoothing reads the values before the dab (a window one cell wider).
    let smooth_src: Option<(CellRect, Vec<f32>)> = (dab.op == BrushOp::Smooth).then(|| {
        let win = CellRect {
            c0: rect.c0.saturating_sub(1),
            r0: rect.r0.saturating_sub(1),
            c1: (rect.c1 + 1).min(w - 1),
            r1: (rect.r1 + 1).min(h - 1),
        };
        let mut v = Vec::with_capacity((win.c1 - win.c0 + 1) * (win.r1 - win.r0 + 1));
        for r in win.r0..=win.r1 {
            for c in win.c0..=win.c1 {
                v.push(read(terrain, paint, dab.target, r * w + c));
            }
        }
        (win, v)
    });
    let paint_target = matches!(
        dab.target,
        BrushTarget::AvalancheProbability | BrushTarget::SkiArea
    );
    for r in rect.r0..=rect.r1 {
        for c in rect.c0..=rect.c1 {
            let i = r * w + c;
            if !terrain.mask().is_valid(i) {
                continue;
            }
            let d =
                (((c as f64 - dab.col) * dx).powi(2) + ((r as f64 - dab.row) * dy).powi(2)).sqrt();
            if d > dab.radius_m {
                continue;
            }
            let wgt = 0.5 * (1.0 + (std::f64::consts::PI * d / dab.radius_m).cos());
            let s = (dab.strength * wgt) as f32;
            let cur = read(terrain, paint, dab.target, i);
            let mut new = match dab.op {
                BrushOp::Add => cur + s,
                BrushOp::Remove => cur - s,
                BrushOp::Set => cur + (dab.value as f32 - cur) * s,
                BrushOp::Smooth => {
                    let (win, src) = smooth_src.as_ref()?;
                    let ww = win.c1 - win.c0 + 1;
                    let (mut sum, mut n) = (0.0f32, 0.0f32);
                    for rr in r.saturating_sub(1).max(win.r0)..=(r + 1).min(win.r1) {
                        for cc in c.saturating_sub(1).max(win.c0)..=(c + 1).min(win.c1) {
                            let v = src[(rr - win.r0) * ww + (cc - win.c0)];
                            if v.is_finite() {
                                sum += v;
                                n += 1.0;
                            }
                        }
                    }
                    if n > 0.0 {
                        cur + (sum / n - cur) * s
                    } else {
                        cur
                    }
                }
            };
            new = if paint_target {
                new.clamp(0.0, 1.0)
            } else {
                new.max(0.0)
            };
            if !new.is_finite() || new == cur {
                continue;
            }
            let slot = match dab.target {
                BrushTarget::All => {
                    set_total(terrain, edit, i, new);
                    continue;
                }
                BrushTarget::Compacted => Slot::Layer(SnowLayer::Compacted),
                BrushTarget::Stable => Slot::Layer(SnowLayer::Stable),
                BrushTarget::Unstable => Slot::Layer(SnowLayer::Unstable),
                BrushTarget::Powder => Slot::Layer(SnowLayer::Powder),
                BrushTarget::AvalancheProbability => Slot::AvalancheProbability,
                BrushTarget::SkiArea => Slot::SkiArea,
            };
            record(edit, slot, i, cur);
            slot_values(terrain, paint, slot)[i] = new;
        }
    }
    Some(rect)
}

#[cfg(test)]
mod tests {
    use super::*;
    use snowscape_terrain::{Grid, GridGeometry};

    fn flat(n: usize) -> (LayeredTerrain, PaintMaps) {
        let g = GridGeometry::square(n, n, 10.0).unwrap();
        let grid = Grid::filled(g, 1000.0);
        (LayeredTerrain::from_bedrock(grid), PaintMaps::new(n * n))
    }

    fn dab(op: BrushOp, target: BrushTarget) -> Dab {
        Dab {
            op,
            target,
            col: 10.0,
            row: 10.0,
            radius_m: 50.0,
            strength: 1.0,
            value: 0.0,
        }
    }

    #[test]
    fn add_then_undo_then_redo() {
        let (mut t, mut p) = flat(32);
        let mut e = Edit::default();
        apply(
            &mut t,
            &mut p,
            &dab(BrushOp::Add, BrushTarget::Powder),
            &mut e,
        )
        .unwrap();
        let i = t.geometry().index(10, 10);
        assert!((t.layer(SnowLayer::Powder)[i] - 1.0).abs() < 1e-6);
        let edge = t.geometry().index(15, 10);
        assert_eq!(
            t.layer(SnowLayer::Powder)[edge],
            0.0,
            "falloff reaches 0 at the radius"
        );
        let after = t.clone();
        let (redo, rect) = e.revert(&mut t, &mut p);
        assert!(rect.is_some());
        assert_eq!(t.snow_volume(), 0.0);
        redo.revert(&mut t, &mut p);
        assert_eq!(t, after);
    }

    #[test]
    fn remove_on_all_takes_from_the_top() {
        let (mut t, mut p) = flat(32);
        let i = t.geometry().index(10, 10);
        t.layer_mut(SnowLayer::Stable)[i] = 1.0;
        t.layer_mut(SnowLayer::Powder)[i] = 0.3;
        let mut d = dab(BrushOp::Remove, BrushTarget::All);
        d.strength = 0.5;
        apply(&mut t, &mut p, &d, &mut Edit::default());
        assert_eq!(t.layer(SnowLayer::Powder)[i], 0.0);
        assert!((t.layer(SnowLayer::Stable)[i] - 0.8).abs() < 1e-6);
    }

    #[test]
    fn set_smooth_and_paint_stay_in_range() {
        let (mut t, mut p) = flat(32);
        let mut d = dab(BrushOp::Set, BrushTarget::All);
        d.value = 2.0;
        apply(&mut t, &mut p, &d, &mut Edit::default());
        let i = t.geometry().index(10, 10);
        assert!((t.depth_at(i) - 2.0).abs() < 1e-6);
        let before = t.depth_at(t.geometry().index(14, 10));
        apply(
            &mut t,
            &mut p,
            &dab(BrushOp::Smooth, BrushTarget::All),
            &mut Edit::default(),
        );
        assert!(t.depth_at(i) < 2.0, "smoothing lowers the peak");
        assert!(t.depth_at(t.geometry().index(14, 10)) >= before);
        let mut d = dab(BrushOp::Add, BrushTarget::AvalancheProbability);
        d.strength = 5.0;
        apply(&mut t, &mut p, &d, &mut Edit::default());
        assert_eq!(p.avalanche_probability[i], 1.0);
        let far = dab(BrushOp::Add, BrushTarget::Stable);
        let far = Dab { col: -100.0, ..far };
        assert!(apply(&mut t, &mut p, &far, &mut Edit::default()).is_none());
    }
}
