//! Property tests: the message decoder never panics on random or hostile input, and every
//! message it accepts re-encodes to a message it accepts again.

use proptest::prelude::*;
use snowscape_editor::protocol::{ClientMessage, MAX_MESSAGE_BYTES, decode};

const TYPES: &[&str] = &[
    "brush",
    "undo",
    "redo",
    "step",
    "seek",
    "trigger_avalanche",
    "launch_skier",
    "set_scenario",
    "save",
    "load",
    "export",
    "probe",
    "resync",
    "nope",
    "",
];

fn hostile_value() -> impl Strategy<Value = serde_json::Value> {
    prop_oneof![
        Just(serde_json::json!(null)),
        Just(serde_json::json!(1e308)),
        Just(serde_json::json!(-1e308)),
        Just(serde_json::json!(-1)),
        Just(serde_json::json!(u64::MAX)),
        Just(serde_json::json!("../../etc/passwd")),
        Just(serde_json::json!("/abs")),
        Just(serde_json::json!([1, 2, 3])),
        Just(serde_json::json!({"type": "undo"})),
        any::<f64>().prop_map(|f| serde_json::json!(f)),
        any::<i64>().prop_map(|i| serde_json::json!(i)),
        ".{0,40}".prop_map(|s| serde_json::json!(s)),
    ]
}

fn hostile_object() -> impl Strategy<Value = Vec<u8>> {
    (
        proptest::sample::select(TYPES),
        proptest::collection::vec(
            (
                proptest::sample::select(
                    &[
                        "stroke", "op", "target", "col", "row", "radius_m", "strength", "value",
                        "days", "index", "name", "scenario", "extra",
                    ][..],
                ),
                hostile_value(),
            ),
            0..8,
        ),
    )
        .prop_map(|(t, fields)| {
            let mut m = serde_json::Map::new();
            m.insert("type".into(), serde_json::json!(t));
            for (k, v) in fields {
                m.insert(k.to_string(), v);
            }
            serde_json::to_vec(&m).unwrap_or_default()
        })
}

fn check(bytes: &[u8]) {
    if let Ok(msg) = decode(bytes, MAX_MESSAGE_BYTES) {
        let again = serde_json::to_vec(&msg).expect("accepted messages encode");
        let back: ClientMessage = decode(&again, MAX_MESSAGE_BYTES).expect("and decode again");
        assert_eq!(back, msg);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..512)) {
        check(&bytes);
    }

    #[test]
    fn hostile_objects_never_panic(bytes in hostile_object()) {
        check(&bytes);
    }

    #[test]
    fn truncated_and_nested_input_never_panics(cut in 0usize..200, depth in 0usize..2000) {
        let good = br#"{"type":"brush","stroke":1,"op":"add","target":"all","col":1,"row":2,"radius_m":30,"strength":0.5}"#;
        check(&good[..cut.min(good.len())]);
        let nested = format!("{}{}", "[".repeat(depth), "]".repeat(depth));
        check(nested.as_bytes());
    }
}

#[test]
fn oversized_messages_are_refused_before_parsing() {
    let big = vec![b'{'; MAX_MESSAGE_BYTES + 1];
    let e = decode(&big, MAX_MESSAGE_BYTES).unwrap_err();
    assert!(e.to_string().contains("larger than the limit"), "{e}");
}
