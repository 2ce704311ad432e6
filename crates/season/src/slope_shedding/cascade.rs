//! The sequential sweep of slope shedding (see the parent module's documentation: order,
//! routing, the no-overtaking limit and the queue of passed receivers).

use super::*;

/// What one strip's sweep moved: depths (m) summed over cells, and counts.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct SweepTotals {
    pub(super) moved: f64,
    pub(super) received: f64,
    pub(super) border: f64,
    pub(super) cells_shed: usize,
    pub(super) unsettled: usize,
}

/// A strip's sequential sweep in its order, with the queue of passed receivers, over its pending
/// cells; `snow` holds the strip's own rows of the four layers.
pub(super) fn sweep<V: Validity>(
    tables: &Tables,
    bedrock: &[f32],
    strip: &mut Strip,
    snow: [&mut [f32]; 4],
    valid: &V,
    generation: u32,
) -> SweepTotals {
    let Tables {
        params,
        holding,
        retained,
    } = *tables;
    let tan_min = params.min_slope_deg.to_radians().tan() as f32;
    let width = strip.geometry.width();
    let snow_offset = strip.own(width).start;
    let valid = &valid.window(strip.window.clone());
    let bedrock = &bedrock[strip.window.clone()];
    let Strip {
        window,
        geometry,
        order,
        cells,
        pending,
        queue,
        dirty,
        outbox,
        revisits,
        ..
    } = strip;
    queue.clear();
    let budget = 16 * order.len() + 1024;
    let mut c = Cascade {
        holding,
        retained,
        geometry,
        valid,
        nb: neighbours(geometry),
        bedrock,
        snow,
        snow_offset,
        window_start: window.start,
        generation,
        cells,
        dirty,
        tan_min,
        queue,
        pending,
        outbox,
        sweep: 0,
        deposit: params.deposit_layer.index(),
        power: params.flow_exponent as f32,
        tan_entrain: params.entrain_min_slope_deg.to_radians().tan() as f32,
        totals: SweepTotals::default(),
    };
    // The pending ranks in increasing order; a cell only ever becomes pending ahead of the
    // sweep, so one pass over the words finds them all.
    let mut word = 0;
    loop {
        while word < c.pending.len() && c.pending[word] == 0 {
            word += 1;
        }
        let Some(bits) = c.pending.get_mut(word) else {
            break;
        };
        let bit = bits.trailing_zeros() as usize;
        *bits &= *bits - 1;
        let p = word * 64 + bit;
        c.sweep = p as u32;
        let i = order[p] as usize;
        c.cells[i].flags &= !PENDING;
        c.shed(i);
        while let Some(entry) = c.queue.pop() {
            let j = !(entry as u32) as usize;
            // Current while the cell is queued with this surface; older entries of a cell that
            // received snow again since are skipped.
            let cell = &mut c.cells[j];
            if cell.flags & QUEUED == 0 || entry != queue_key(cell.surface, j) {
                continue;
            }
            cell.flags &= !QUEUED;
            if *revisits >= budget {
                c.totals.unsettled += 1;
                continue;
            }
            *revisits += 1;
            c.shed(j);
        }
    }
    c.totals
}

/// Queue key of cell `j`: the highest snow surface first, ties by the lower index.
#[inline]
fn queue_key(surface: f32, j: usize) -> u64 {
    (u64::from(monotone(surface)) << 32) | u64::from(!(j as u32))
}

/// State of the sweep.
struct Cascade<'a, V> {
    holding: &'a HoldingTable,
    retained: &'a [RetainedTable; 3],
    geometry: &'a GridGeometry,
    valid: &'a V,
    nb: [Neighbour; 8],
    /// The strip's window of the bedrock (cells are indexed in the window).
    bedrock: &'a [f32],
    /// The strip's own rows of the snow layers, from window index `snow_offset` on.
    snow: [&'a mut [f32]; 4],
    snow_offset: usize,
    /// Grid index of the window's first cell.
    window_start: usize,
    /// See [`set_up`].
    generation: u32,
    cells: &'a mut [CellState],
    /// Cells whose surface changed in this phase.
    dirty: &'a mut Vec<u32>,
    tan_min: f32,
    queue: &'a mut BinaryHeap<u64>,
    pending: &'a mut [u64],
    /// Snow sent into the halo: grid index and depth, m.
    outbox: &'a mut Vec<(u32, f32)>,
    /// Rank of the sweep's cell.
    sweep: u32,
    deposit: usize,
    power: f32,
    /// tan of [`SheddingParams::entrain_min_slope_deg`].
    tan_entrain: f32,

    totals: SweepTotals,
}

impl<V: Validity> Cascade<'_, V> {
    /// Sets up cell `j` the first time the step looks at it.
    #[inline(always)]
    fn touch(&mut self, j: usize) {
        set_up(j, self.generation, self.cells, || {
            column(self.bedrock, j, &self.snow, j - self.snow_offset)
        });
    }

    /// Sets up cell `i` and its valid neighbours: everything a visit of `i` reads.
    #[inline]
    fn touch_around(&mut self, i: usize) {
        self.touch(i);
        let mut cells = [0usize; 8];
        let mut m = 0;
        for_each_around_of(
            self.geometry,
            self.valid,
            &self.nb,
            i,
            self.cells[i].interior,
            |_, a| {
                if let Around::Cell(j) = a {
                    cells[m] = j;
                    m += 1;
                }
            },
        );
        for &j in &cells[..m] {
            self.touch(j);
        }
    }

    /// Surface of neighbour `j` as seen by a sender: the current one once the sweep has passed
    /// it (its snow rests), before that the one it is expected to keep (its surface at the
    /// start of the step less its own excess; its receipts are in transit).
    #[inline]
    fn seen(&self, j: usize) -> f32 {
        let cell = &self.cells[j];
        if cell.rank > self.sweep {
            cell.surface0
        } else {
            cell.surface
        }
    }

    /// Depth a cell that received snow keeps, m: the `d` in `[0, depth]` that equals its
    /// (dynamic) holding depth on the slope its surface would then have, the descent from
    /// `base + d` (`base` the bedrock under the column) to its neighbours' surfaces as seen
    /// ([`Self::seen`]), or past the border the bed's: the smallest of the roots for the
    /// highest rise `base − seen` at each neighbour distance (east-west, north-south,
    /// diagonal), tabulated, and of the holding depth on the border's slope (see
    /// [`super::retained`]).
    fn retained(&self, i: usize, base: f32, depth: f32) -> f32 {
        let mut fixed = 0.0f32;
        let mut rises = [f32::NEG_INFINITY; 3];
        for_each_around_of(
            self.geometry,
            self.valid,
            &self.nb,
            i,
            self.cells[i].interior,
            |n, a| match a {
                Around::Cell(j) => {
                    let g = &mut rises[distance_group(n)];
                    *g = g.max(base - self.seen(j));
                }
                Around::Ghost(o) => {
                    fixed = fixed.max((self.cells[o].bed - self.cells[i].bed) * n.inv_l)
                }
            },
        );
        let mut keep = depth.min(self.holding.hold(fixed, true));
        for (table, &rise) in self.retained.iter().zip(&rises) {
            if rise > f32::NEG_INFINITY {
                keep = keep.min(table.keep(self.holding, rise));
            }
        }
        keep
    }

    /// Sheds cell `i`'s excess, if any. A round cut short by a receiver it would overtake is
    /// followed by another without it, at most [`ROUNDS`] in all.
    fn shed(&mut self, i: usize) {
        self.touch_around(i);
        let (s, k) = (&self.snow, i - self.snow_offset);
        let depth = s[0][k] + s[1][k] + s[2][k] + s[3][k];
        let cell = self.cells[i];
        let keep = if cell.flags & RECEIVED != 0 {
            let base = cell.surface - depth;
            let retained = self.retained(i, base, depth);
            if cell.flags & ACTIVE != 0 || cell.bedrock_tan >= self.tan_entrain {
                retained
            } else {
                // Below `entrain_min_slope_deg` a cell keeps its own snow: the depth it had at
                // the start of the step.
                retained.max((cell.surface0 - base).min(depth))
            }
        } else {
            if cell.tan_slope < self.tan_min {
                return;
            }
            self.holding.hold(cell.tan_slope, false)
        };
        let mut left = depth - keep;
        for _ in 0..ROUNDS {
            if left <= MIN_SHED_M {
                return;
            }
            let (removed, limited) = self.shed_round(i, left);
            left -= removed;
            if removed <= 0.0 || !limited {
                return;
            }
        }
    }

    /// One round: sends up to `excess` to the lower neighbours; returns the depth removed and
    /// whether the no-overtaking limit cut it.
    fn shed_round(&mut self, i: usize, excess: f32) -> (f32, bool) {
        let a_i = self.cells[i].surface;
        let bed_i = self.cells[i].bed;
        // The directions: drops from the surface the sender will have once its excess is
        // gone, so that snow in transit over a slope runs down it rather than spilling
        // sideways onto the neighbours that already shed; from its current surface if none is
        // lower than that (a pile on level ground).
        let mut targets = [(Around::Ghost(0), 0.0f32, f32::INFINITY); 8];
        let mut count = 0;
        let mut total = 0.0f32;
        // Each neighbour with the surface the sender sees there, whether it limits the amount
        // (a receiver the sweep has passed) and `1 / distance`.
        let mut seen_around = [(Around::Ghost(0), 0.0f32, false, 0.0f32); 8];
        let mut m = 0;
        for_each_around_of(
            self.geometry,
            self.valid,
            &self.nb,
            i,
            self.cells[i].interior,
            |n, a| {
                seen_around[m] = match a {
                    Around::Cell(j) => {
                        let cell = &self.cells[j];
                        if cell.rank > self.sweep {
                            (a, cell.surface0, false, n.inv_l)
                        } else {
                            (a, cell.surface, true, n.inv_l)
                        }
                    }
                    Around::Ghost(o) => (a, a_i - (self.cells[o].bed - bed_i), false, n.inv_l),
                };
                m += 1;
            },
        );
        for after in [a_i - excess, a_i] {
            for &(target, seen, limit_of, inv_l) in &seen_around[..m] {
                // A neighbour within a millimetre is level (and would cut the round to nothing).
                let drop = after - seen;
                if drop > LEVEL_M {
                    let t = drop * inv_l;
                    let wt = if self.power == 1.0 {
                        t
                    } else {
                        t.powf(self.power)
                    };
                    if wt > 0.0 {
                        let limit = if limit_of { a_i - seen } else { f32::INFINITY };
                        targets[count] = (target, wt, limit);
                        count += 1;
                        total += wt;
                    }
                }
            }
            if count > 0 {
                break;
            }
        }
        if count == 0 || total.is_nan() || total <= 0.0 {
            return (0.0, false);
        }
        // Never leave the sender below a receiver the sweep has passed (one it has not
        // reached will pass the snow on when it does).
        let mut amount = excess;
        for &(_, wt, limit) in &targets[..count] {
            amount = amount.min(limit / (1.0 + wt / total));
        }
        let limited = amount < excess;
        if amount <= MIN_SHED_M {
            return (0.0, false);
        }
        let removed = take(&mut self.snow, i - self.snow_offset, amount);
        let cell = &mut self.cells[i];
        cell.surface -= removed;
        if cell.flags & DIRTY == 0 {
            cell.flags |= DIRTY;
            self.dirty.push(i as u32);
        }
        self.totals.moved += f64::from(removed);
        if cell.flags & SHED == 0 {
            cell.flags |= SHED;
            self.totals.cells_shed += 1;
        }
        // Shares in neighbour order, the last one taking the rest, so they sum to `removed`.
        let mut left = removed;
        for (k, &(target, wt, _)) in targets[..count].iter().enumerate() {
            let share = if k + 1 == count {
                left
            } else {
                (removed * (wt / total)).min(left)
            };
            left -= share;
            if share <= 0.0 {
                continue;
            }
            match target {
                Around::Ghost(_) => self.totals.border += f64::from(share),
                Around::Cell(j) => {
                    self.totals.received += f64::from(share);
                    let cell = &mut self.cells[j];
                    if cell.flags & HALO != 0 {
                        // Another strip's cell: it takes the snow in the next phase (in
                        // transit until then, like any receiver the sweep has not reached).
                        self.outbox.push(((self.window_start + j) as u32, share));
                        continue;
                    }
                    cell.surface += share;
                    self.snow[self.deposit][j - self.snow_offset] += share;
                    if cell.flags & DIRTY == 0 {
                        cell.flags |= DIRTY;
                        self.dirty.push(j as u32);
                    }
                    // A receiver the sweep has passed is queued with its new surface (an older
                    // entry goes stale); the sweep reaches the others.
                    if cell.rank > self.sweep && cell.flags & PENDING == 0 {
                        cell.flags |= PENDING;
                        set_pending(self.pending, cell.rank);
                    }
                    cell.flags |= RECEIVED;
                    if cell.rank <= self.sweep {
                        cell.flags |= QUEUED;
                        self.queue.push(queue_key(cell.surface, j));
                    }
                }
            }
        }
        (removed, limited)
    }
}

/// Which of the three neighbour distances `n` lies at: 0 east-west, 1 north-south, 2 diagonal.
#[inline]
fn distance_group(n: &Neighbour) -> usize {
    match (n.dc, n.dr) {
        (_, 0) => 0,
        (0, _) => 1,
        _ => 2,
    }
}

/// Removes `amount` m from the top of cell `i` (powder, unstable, stable, compacted); returns
/// the depth removed.
fn take(snow: &mut [&mut [f32]; 4], i: usize, amount: f32) -> f32 {
    let mut left = amount;
    let mut removed = 0.0;
    for layer in [
        SnowLayer::Powder,
        SnowLayer::Unstable,
        SnowLayer::Stable,
        SnowLayer::Compacted,
    ] {
        let v = &mut snow[layer.index()][i];
        let t = left.min(*v);
        *v -= t;
        removed += t;
        left -= t;
        if left <= 0.0 {
            break;
        }
    }
    removed
}
