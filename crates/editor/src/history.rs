//! What the user did in a session, in order: a saved project's `history.json`
//! (`{"source", "day", "snapshot_days", "actions": [{"action": "brush", ...}, ...]}`).

use crate::protocol::{BrushOp, BrushTarget};
use serde::{Deserialize, Serialize};

/// One thing the user did.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "action", rename_all = "snake_case")]
pub enum Action {
    /// The season ran from day `from` to day `to`.
    Step { from: f64, to: f64 },
    /// A new scenario replaced the season.
    SetScenario,
    /// A brush stroke began (its dabs are not recorded).
    Brush {
        stroke: u32,
        op: BrushOp,
        target: BrushTarget,
        day: f64,
    },
    /// An avalanche was triggered at a cell (column, row: fractional cells from the north-west
    /// corner).
    Avalanche { col: f64, row: f64, day: f64 },
    /// A skier was launched at a cell.
    Skier { col: f64, row: f64, day: f64 },
    /// The saved project `name` was loaded.
    Load { name: String },
}

/// A saved project's `history.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ProjectHistory {
    /// Where the session's terrain came from.
    pub source: String,
    /// The season's day when it was saved.
    pub day: f64,
    /// The days of the timeline's snapshots.
    pub snapshot_days: Vec<f64>,
    /// What the user did, in order.
    pub actions: Vec<Action>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn actions_keep_their_json_keys() {
        let a = Action::Brush {
            stroke: 3,
            op: BrushOp::Add,
            target: BrushTarget::Powder,
            day: 2.5,
        };
        let v = serde_json::to_value(&a).unwrap();
        assert_eq!(v["action"], "brush");
        assert_eq!(v["stroke"], 3);
        assert_eq!(v["target"], "powder");
        assert_eq!(serde_json::from_value::<Action>(v).unwrap(), a);
        let v = serde_json::to_value(Action::SetScenario).unwrap();
        assert_eq!(v, serde_json::json!({"action": "set_scenario"}));
        assert!(serde_json::from_str::<Action>(r#"{"action": "rm -rf"}"#).is_err());
    }
}
