//! The season's skier runs (Cordonnier 2018 §6.2) as [`Winter`] runs them: one run from its
//! start to its terminus inside its start event, and the tracks fading under new snow.

use super::{SeasonError, Trigger, Winter};
use crate::scheduler::SECONDS_PER_DAY;
use snowscape_skiers::SkiArea;

impl Winter {
    /// One scheduled skier run, from its start to its terminus (temporal zoom): the next of
    /// the scenario's start points, or a start drawn from the snow; the season's clock moves
    /// on by the run's duration. See [`crate::skiing`].
    pub(super) fn run_skier(&mut self, event_day: f64) -> Result<(), SeasonError> {
        let p = self.scenario.skiers.clone();
        let k = self.state.run.ski.runs as usize;
        let start = p.starts.get(k % p.starts.len().max(1)).copied();
        if let Some(elapsed) = self.ski_run(event_day, start)? {
            self.state
                .run
                .scheduler
                .advance_clock(elapsed / SECONDS_PER_DAY);
            self.update_avalanche_rate();
        }
        Ok(())
    }

    /// One skier from the map position `(x, y)` to its terminus, on the season's ski area, as
    /// a scheduled run goes (its compaction in the budget, its avalanches started at once, its
    /// tracks kept), without moving the season's clock: the editor's painted skier areas.
    /// Returns the simulated seconds, `None` where no run could start (no skiable snow).
    pub fn ski_from(&mut self, x: f64, y: f64) -> Result<Option<f64>, SeasonError> {
        self.ensure_workspace()?;
        let day = self.state.run.scheduler.time_days();
        let run = self.ski_run(day, Some([x, y]))?;
        if run.is_some() {
            self.update_avalanche_rate();
        }
        Ok(run)
    }

    /// The one skier-run path: the ski area (built or its terminus refreshed), a skier
    /// spawned at `start` (or drawn from the snow), stepped to its terminus or `max_run_s`
    /// with every step in the season's statistics and budget and the avalanches it triggers
    /// started at once; returns the simulated seconds (`None` when no run could start).
    fn ski_run(&mut self, day: f64, start: Option<[f64; 2]>) -> Result<Option<f64>, SeasonError> {
        let ski_err = |e: snowscape_skiers::SkiError| SeasonError::Skier {
            day,
            reason: e.to_string(),
        };
        let p = self.scenario.skiers.clone();
        // Without skiable snow there is no terminus: no run today.
        let no_snow =
            |e: &snowscape_skiers::SkiError| matches!(e, snowscape_skiers::SkiError::NoTerminus(_));
        if self.state.ski_area.is_none() {
            match SkiArea::new(
                &p.ski,
                &self.terrain,
                p.terminus.clone(),
                self.scenario.seed,
            ) {
                Ok(a) => self.state.ski_area = Some(a),
                Err(e) if no_snow(&e) => return Ok(None),
                Err(e) => return Err(ski_err(e)),
            }
            self.state.run.terminus_stale = false;
        }
        let Some(area) = self.state.ski_area.as_mut() else {
            return Ok(None);
        };
        if self.state.run.terminus_stale {
            match area.refresh_terminus(&p.ski, &self.terrain) {
                Ok(()) => self.state.run.terminus_stale = false,
                Err(e) if no_snow(&e) => return Ok(None),
                Err(e) => return Err(ski_err(e)),
            }
        }
        area.time_s = day * SECONDS_PER_DAY;
        let spawned = match start {
            Some([x, y]) => area.spawn_at(&p.ski, &self.terrain, x, y).map(|_| 1),
            None => area
                .spawn_weighted(&p.ski, &self.terrain, 1)
                .map(|v| v.len()),
        };
        // A start point on bare ground or a map without snow: no run today.
        if !matches!(spawned, Ok(n) if n > 0) {
            return Ok(None);
        }
        self.state.run.ski.runs += 1;
        let mut elapsed = 0.0;
        let mut triggers = Vec::new();
        while elapsed < p.max_run_s {
            let Some(area) = self.state.ski_area.as_mut() else {
                break;
            };
            let r = snowscape_skiers::step(
                &p.ski,
                area,
                &mut self.terrain,
                &mut self.workspace.ski,
                p.step_s,
            )
            .map_err(ski_err)?;
            elapsed += p.step_s;
            self.state.run.ski.steps += 1;
            self.state.run.ski.distance_m += r.distance_m;
            self.state.run.budget.densification += r.compaction.densification_m3;
            self.state.run.ski.finished += r
                .finished
                .iter()
                .filter(|f| f.stop == snowscape_skiers::StopReason::Terminus)
                .count() as u64;
            triggers.extend(r.triggers.iter().map(|t| t.cell));
            for cell in triggers.drain(..) {
                match self.start_avalanche(cell, Trigger::Skier) {
                    Ok(_) => self.state.run.ski.avalanches_triggered += 1,
                    Err(SeasonError::AvalanchePosition { .. }) => {}
                    Err(e) => return Err(e),
                }
            }
            if r.active == 0 {
                break;
            }
        }
        Ok(Some(elapsed))
    }

    /// Fades the ski tracks under snow that `before` (total depth per cell) did not hold.
    pub(super) fn fade_tracks(&mut self, before: Option<Vec<f32>>) -> Result<(), SeasonError> {
        let (Some(before), Some(area)) = (before, self.state.ski_area.as_mut()) else {
            return Ok(());
        };
        let added: Vec<f32> = self
            .terrain
            .total_depth()
            .iter()
            .zip(&before)
            .map(|(a, b)| a - b)
            .collect();
        area.fade_tracks(&self.scenario.skiers.ski, &added)
            .map_err(|e| SeasonError::Skier {
                day: self.state.run.scheduler.time_days(),
                reason: e.to_string(),
            })
    }
}
