//! The session's immediate edits, one method a message: a brush dab, undo and redo, a seek
//! along the timeline and a triggered avalanche ([`Session::start`] dispatches to them).

use super::*;

impl Session {
    /// A dab of the stroke `stroke`: applied at once, recorded for undo (a stroke's dabs make
    /// one edit), and the tiles it changed sent to every tab.
    pub(super) fn brush(&mut self, stroke: u32, dab: Dab) -> Result<Vec<Out>, Refusal> {
        let Dab {
            op,
            target,
            radius_m,
            ..
        } = dab;
        let most = brush::max_radius_m(&self.winter.terrain);
        if radius_m > most {
            return refuse(
                ErrorCode::InvalidValue,
                format!(
                    "brush radius_m = {radius_m} is larger than the terrain ({most:.0} m across its diagonal): use a radius within it"
                ),
            );
        }
        let unrecorded = self.unrecorded_stroke == Some(stroke);
        let mut edit = match self.undo.pop() {
            other if unrecorded => {
                self.undo.extend(other);
                Edit {
                    stroke,
                    unrecorded: true,
                    ..Edit::default()
                }
            }
            Some(e) if e.stroke == stroke => e,
            other => {
                self.unrecorded_stroke = None;
                self.undo.extend(other);
                self.log(Action::Brush {
                    stroke,
                    op,
                    target,
                    day: self.winter.day(),
                });
                Edit {
                    stroke,
                    ..Edit::default()
                }
            }
        };
        let rect = brush::apply(&mut self.winter.terrain, &mut self.paint, &dab, &mut edit);
        let notice = if edit.unrecorded {
            self.timeline.mark_edited();
            None
        } else if !edit.is_empty() {
            self.undo.push(edit);
            self.redo.clear();
            self.timeline.mark_edited();
            self.enforce_undo_budget(Some(stroke))
        } else {
            None
        };
        let mut out = rect
            .map(|r| self.rect_frames(target, r))
            .unwrap_or_default();
        out.extend(notice);
        out.push(self.state_out());
        Ok(out)
    }

    /// Undoes (`undo`) or redoes the last edit, sending the tiles it changed.
    pub(super) fn undo_or_redo(&mut self, undo: bool) -> Result<Vec<Out>, Refusal> {
        let (from, to) = if undo {
            (&mut self.undo, &mut self.redo)
        } else {
            (&mut self.redo, &mut self.undo)
        };
        let Some(edit) = from.pop() else {
            return refuse(
                ErrorCode::InvalidValue,
                if undo {
                    "nothing to undo"
                } else {
                    "nothing to redo"
                },
            );
        };
        let (inverse, rect) = edit.revert(&mut self.winter.terrain, &mut self.paint);
        to.push(inverse);
        self.timeline.mark_edited();
        let mut out = Vec::new();
        if let Some(r) = rect {
            let tiles = Self::tiles_of_rect(r);
            out.extend(self.layer_frames(&tiles));
            for c in [Channel::AvalancheProbability, Channel::SkiArea] {
                out.extend(self.frame(c, Some(&tiles)).map(Out::All));
            }
        }
        out.push(self.state_out());
        Ok(out)
    }

    /// Moves to snapshot `index` of the timeline (the present stored first).
    pub(super) fn seek(&mut self, index: usize) -> Result<Vec<Out>, Refusal> {
        self.timeline.store(&self.winter, &self.paint);
        let (w, p) = self
            .timeline
            .seek(index, &self.winter)
            .ok_or_else(|| {
                (
                    ErrorCode::InvalidValue,
                    format!(
                        "snapshot {index} does not exist ({} snapshots)",
                        self.timeline.len()
                    ),
                )
            })?
            .map_err(|e| (ErrorCode::Failed, e))?;
        self.winter = w;
        self.paint = p;
        self.clear_undo();
        Ok(self.everything())
    }

    /// Starts a live avalanche at the cell nearest `(col, row)`.
    pub(super) fn trigger_avalanche(&mut self, col: f64, row: f64) -> Result<Vec<Out>, Refusal> {
        let params = self.winter.scenario().parameters.avalanche.clone();
        let temperature = self.winter.environment().temperature.clone();
        let live = LiveAvalanche::start(
            &mut self.winter.terrain,
            Some(&temperature),
            &params,
            col.round() as usize,
            row.round() as usize,
        )
        .map_err(|e| {
            (
                ErrorCode::InvalidValue,
                format!("no avalanche at ({col}, {row}): {e}"),
            )
        })?;
        let tiles = live.release_tiles();
        let progress = live.progress.clone();
        self.avalanche = Some(live);
        self.undo.clear();
        self.redo.clear();
        self.timeline.mark_edited();
        self.log(Action::Avalanche {
            col,
            row,
            day: self.winter.day(),
        });
        let mut out = self.layer_frames(&tiles);
        out.push(Out::All(text(&ServerMessage::Avalanche(progress))));
        out.push(self.state_out());
        Ok(out)
    }
}
