//! Checkpoints of a season: writing the whole run state, and resuming from it only when the
//! file is intact (`checkpoint::read` checks lengths and checksum) and was written for the
//! same terrain and scenario. The cheap checks (file, terrain, scenario) run before the
//! environment precompute, so a refused resume costs no time; a refusal names what changed.

use super::{RunState, SeasonError, SnowpackState, Winter};
use crate::avalanches::HazardSources;
use crate::checkpoint::{self, bedrock_fingerprint};
use crate::forcing::StationForcing;
use crate::scenario::Scenario;
use snowscape_terrain::LayeredTerrain;

/// Extra per-cell maps after the four layers: scour, deposit, the pack's four arrays, rain.
const EXTRA_MAPS: usize = 7;

/// Size and cell size of a terrain, for messages.
pub(super) fn terrain_summary(terrain: &LayeredTerrain) -> String {
    let g = terrain.geometry();
    format!(
        "{}x{} cells of {} x {} m",
        g.width(),
        g.height(),
        g.cell_size_x(),
        g.cell_size_y()
    )
}

/// The first key (dotted path) whose value differs between two JSON documents, with both
/// values; `None` when they are equal.
fn first_difference(
    key: &str,
    old: &serde_json::Value,
    new: &serde_json::Value,
) -> Option<(String, String, String)> {
    use serde_json::Value;
    let path = |k: &str| {
        if key.is_empty() {
            k.to_string()
        } else {
            format!("{key}.{k}")
        }
    };
    match (old, new) {
        (Value::Object(a), Value::Object(b)) => {
            let keys: std::collections::BTreeSet<&String> = a.keys().chain(b.keys()).collect();
            keys.into_iter().find_map(|k| {
                let null = Value::Null;
                first_difference(
                    &path(k),
                    a.get(k).unwrap_or(&null),
                    b.get(k).unwrap_or(&null),
                )
            })
        }
        (Value::Array(a), Value::Array(b)) if a.len() == b.len() => a
            .iter()
            .zip(b)
            .enumerate()
            .find_map(|(i, (x, y))| first_difference(&format!("{key}[{i}]"), x, y)),
        _ if old == new => None,
        _ => Some((key.to_string(), short(old), short(new))),
    }
}

/// A value for a message, at most 80 characters.
fn short(v: &serde_json::Value) -> String {
    let mut s = match v {
        serde_json::Value::Null => "(unset)".to_string(),
        v => v.to_string(),
    };
    if s.len() > 80 {
        let cut = (0..=77).rev().find(|&i| s.is_char_boundary(i)).unwrap_or(0);
        s.truncate(cut);
        s.push_str("...");
    }
    s
}

impl Winter {
    /// Writes a checkpoint of the whole run state to `w`.
    pub fn write_checkpoint(&self, w: &mut impl std::io::Write) -> Result<(), SeasonError> {
        let m = &self.avalanche_maps;
        let [age, cold, liquid, melting] = self.pack.arrays();
        checkpoint::write(
            w,
            &self.state,
            &self.terrain,
            &[
                &m.scour,
                &m.deposit,
                age,
                cold,
                liquid,
                melting,
                &self.pending_rain,
            ],
        )?;
        Ok(())
    }

    /// Restores a run from a checkpoint written by a run of the same scenario on the same
    /// terrain (anything else is refused).
    pub fn resume(
        scenario: Scenario,
        terrain: LayeredTerrain,
        r: &mut impl std::io::Read,
    ) -> Result<Self, SeasonError> {
        Self::resume_with_forcing(scenario, terrain, None, r)
    }

    /// [`Winter::resume`] for a season driven by station forcing (the same record).
    pub fn resume_with_forcing(
        scenario: Scenario,
        terrain: LayeredTerrain,
        forcing: Option<StationForcing>,
        r: &mut impl std::io::Read,
    ) -> Result<Self, SeasonError> {
        let mut saved = checkpoint::read::<RunState>(r, terrain.geometry().len(), EXTRA_MAPS)?;
        if saved.header.fingerprint != bedrock_fingerprint(&terrain) {
            let now = terrain_summary(&terrain);
            let now = if now == saved.header.terrain {
                format!("{now}, with other altitudes")
            } else {
                now
            };
            return Err(SeasonError::CheckpointTerrain {
                checkpoint: saved.header.terrain.clone(),
                now,
            });
        }
        let now = serde_json::to_value(&scenario).unwrap_or_default();
        if let Some((key, checkpoint, now)) = first_difference("", &saved.header.scenario, &now) {
            return Err(SeasonError::CheckpointScenario {
                key,
                checkpoint,
                now,
            });
        }
        let mut w = Self::with_forcing(scenario, terrain, forcing)?;
        if saved.header.scenario_digest != w.state.scenario_digest {
            return Err(SeasonError::CheckpointForcing);
        }
        saved.restore_layers(&mut w.terrain);
        let mut extra = std::mem::take(&mut saved.extra);
        w.pending_rain = extra.pop().unwrap_or_default();
        let pack = extra.split_off(2);
        w.pack = SnowpackState::from_arrays(pack);
        w.avalanche_maps.deposit = extra.pop().unwrap_or_default();
        w.avalanche_maps.scour = extra.pop().unwrap_or_default();
        let state = saved.header;
        let weather_changed = state.weather_index != 0;
        w.state = state;
        if weather_changed {
            w.refresh_weather_maps()?;
        }
        w.refresh_air_temperature();
        // The hazard map of the restored snow (for `avalanche_hazard`; a start recomputes it);
        // the scheduler's rate is the checkpointed one.
        w.hazard.compute(
            &w.scenario.parameters.avalanche,
            &w.terrain,
            &w.slope_deg,
            &HazardSources::default(),
        );
        w.hazard_stale = true;
        Ok(w)
    }

    /// Sets this season to the state of a checkpoint written by it or by a fork of it (the
    /// same scenario and weather on the same terrain) as [`Winter::resume`] restores it, but
    /// without the environment precompute: this season's is kept (the weather period's maps
    /// are refreshed when the checkpoint's period is another). What a checkpoint does not
    /// hold is left as a resume leaves it (no ski area, no painted release rates). The
    /// editor's timeline keeps its snapshots as checkpoints and restores them so.
    pub fn restore_checkpoint(&mut self, r: &mut impl std::io::Read) -> Result<(), SeasonError> {
        let mut saved = checkpoint::read::<RunState>(r, self.terrain.geometry().len(), EXTRA_MAPS)?;
        if saved.header.fingerprint != bedrock_fingerprint(&self.terrain) {
            return Err(SeasonError::CheckpointTerrain {
                checkpoint: saved.header.terrain.clone(),
                now: terrain_summary(&self.terrain),
            });
        }
        if saved.header.scenario_digest != self.state.scenario_digest {
            let now = serde_json::to_value(&self.scenario).unwrap_or_default();
            return Err(match first_difference("", &saved.header.scenario, &now) {
                Some((key, checkpoint, now)) => SeasonError::CheckpointScenario {
                    key,
                    checkpoint,
                    now,
                },
                None => SeasonError::CheckpointForcing,
            });
        }
        let period_changed = saved.header.weather_index != self.state.weather_index;
        saved.restore_layers(&mut self.terrain);
        let mut extra = std::mem::take(&mut saved.extra);
        self.pending_rain = extra.pop().unwrap_or_default();
        let pack = extra.split_off(2);
        self.pack = SnowpackState::from_arrays(pack);
        self.avalanche_maps.deposit = extra.pop().unwrap_or_default();
        self.avalanche_maps.scour = extra.pop().unwrap_or_default();
        self.state = saved.header;
        self.ski_area = None;
        self.painted_release = None;
        self.terminus_stale = false;
        if period_changed {
            self.refresh_weather_maps()?;
        }
        self.refresh_air_temperature();
        self.hazard.compute(
            &self.scenario.parameters.avalanche,
            &self.terrain,
            &self.slope_deg,
            &HazardSources::default(),
        );
        self.hazard_stale = true;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::first_difference;
    use serde_json::json;

    #[test]
    fn the_first_changed_key_is_named_with_both_values() {
        let a = json!({"days": 100.0, "parameters": {"melt": {"k_melt": 0.01}}, "weather": [1, 2]});
        let b = json!({"days": 100.0, "parameters": {"melt": {"k_melt": 0.02}}, "weather": [1, 2]});
        assert_eq!(
            first_difference("", &a, &b),
            Some((
                "parameters.melt.k_melt".into(),
                "0.01".into(),
                "0.02".into()
            ))
        );
        assert_eq!(first_difference("", &a, &a), None);
        let c = json!({"days": 60.0, "parameters": {"melt": {"k_melt": 0.01}}, "weather": [1, 2]});
        assert_eq!(
            first_difference("", &a, &c).map(|d| d.0),
            Some("days".into())
        );
    }
}
