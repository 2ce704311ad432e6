//! Regression tests of issue 46 items 3 and 4: a checkpoint is read only from a regular file
//! of bounded size (a link to /dev/zero read 4.2 GB, a FIFO hung), and a checkpoint whose
//! checksum matches but whose values are absurd (forged here: each edit re-computes the CRC)
//! is refused with a typed error naming the field, never a panic or a hang.

#[path = "support/forge.rs"]
mod forge;

use forge::*;
use serde_json::{Value, json};
use snowscape_season::checkpoint::{self, CheckpointError};
use snowscape_season::winter::{SeasonError, Winter};
use std::path::Path;

fn resume(bytes: &[u8]) -> Result<Winter, SeasonError> {
    Winter::resume(scenario(), terrain(), &mut &bytes[..])
}

/// The field an `Implausible` refusal of a resume names, and its message.
fn implausible<T>(resumed: Result<T, SeasonError>) -> (String, String) {
    match resumed {
        Err(SeasonError::Checkpoint(e @ CheckpointError::Implausible { .. })) => {
            let m = e.to_string();
            let CheckpointError::Implausible { field, .. } = e else {
                unreachable!()
            };
            (field, m)
        }
        Err(e) => panic!("expected an implausible value, got {e:?}"),
        Ok(_) => panic!("a forged checkpoint was resumed"),
    }
}

/// The field an `Implausible` refusal names, and its message.
fn refused_field(bytes: &[u8]) -> (String, String) {
    implausible(resume(bytes))
}

#[test]
fn the_forger_round_trips_a_genuine_checkpoint() {
    // A genuine checkpoint resumes (mid-season and at the season's end), and so does one
    // re-assembled untouched (its keys re-ordered): a forged one differs only in its edit.
    let bytes = checkpoint_at(2.5);
    let w = resume(&bytes).unwrap();
    assert!(w.day() >= 2.5);
    let same = resume(&forge(&bytes, |_| {})).unwrap();
    assert_eq!(same.day(), w.day());
    let end = checkpoint_at(6.0);
    assert!(resume(&end).unwrap().finished());
}

/// An edit of a checkpoint's header.
type Edit = Box<dyn Fn(&mut Value)>;

#[test]
fn absurd_indices_times_and_counters_are_refused_naming_the_field() {
    let bytes = checkpoint_at(2.5);
    let cases: Vec<(&str, Edit)> = vec![
        (
            "weather_index",
            Box::new(|h| h["weather_index"] = json!(1u64 << 63)),
        ),
        ("weather_index", Box::new(|h| h["weather_index"] = json!(7))),
        ("forced_index", Box::new(|h| h["forced_index"] = json!(3))),
        (
            "user_avalanche_index",
            Box::new(|h| h["user_avalanche_index"] = json!(u64::MAX)),
        ),
        (
            "scheduler.time_days",
            Box::new(|h| h["scheduler"]["time_days"] = json!(-1e300)),
        ),
        (
            "scheduler.time_days",
            Box::new(|h| h["scheduler"]["time_days"] = json!(1e300)),
        ),
        (
            "scheduler.time_days",
            Box::new(|h| h["scheduler"]["time_days"] = json!(-1.0)),
        ),
        (
            "scheduler.time_days",
            Box::new(|h| h["scheduler"]["time_days"] = json!(500.0)),
        ),
        (
            "scheduler.draws",
            Box::new(|h| h["scheduler"]["draws"] = json!(u64::MAX)),
        ),
        (
            "scheduler.seed",
            Box::new(|h| h["scheduler"]["seed"] = json!(12345)),
        ),
        (
            "scheduler.snowfall_mean_days",
            Box::new(|h| h["scheduler"]["snowfall_mean_days"] = json!(0.0)),
        ),
        (
            "scheduler.rates[2].per_day",
            Box::new(|h| h["scheduler"]["rates"][2]["per_day"] = json!(1e-300)),
        ),
        (
            "scheduler.rates[0].per_day",
            Box::new(|h| h["scheduler"]["rates"][0]["per_day"] = json!(-5.0)),
        ),
        (
            "melt_clock_days",
            Box::new(|h| h["melt_clock_days"] = json!(-3.0)),
        ),
        (
            "budget.snowfall",
            Box::new(|h| h["budget"]["snowfall"] = json!(1e300)),
        ),
        (
            "budget.water.store",
            Box::new(|h| h["budget"]["water"]["store"] = json!(-1e200)),
        ),
        (
            "event_counts.wind_transport_step",
            Box::new(|h| h["event_counts"]["wind_transport_step"] = json!(1u64 << 62)),
        ),
        (
            "event_counts",
            Box::new(|h| h["event_counts"]["wind_transport_step"] = json!(1_000_000)),
        ),
        (
            "ski.finished",
            Box::new(|h| h["ski"]["finished"] = json!(9)),
        ),
        (
            "terrain",
            Box::new(|h| h["terrain"] = json!("x".repeat(100_000))),
        ),
    ];
    for (want, edit) in cases {
        let forged = forge(&bytes, edit);
        let t = std::time::Instant::now();
        let (field, message) = refused_field(&forged);
        assert_eq!(field, want, "{message}");
        assert!(
            message.len() < 400,
            "{} bytes: {message:.400}",
            message.len()
        );
        assert!(t.elapsed().as_secs() < 20, "{want}: {:?}", t.elapsed());
    }
}

#[test]
fn huge_values_are_named_with_an_exponent() {
    // -1e300 written out is 302 characters, cut before its value shows.
    let bytes = checkpoint_at(2.5);
    let forged = forge(&bytes, |h| h["scheduler"]["time_days"] = json!(-1e300));
    let (_, message) = refused_field(&forged);
    assert!(
        message.contains("scheduler.time_days = -1e300 is implausible"),
        "{message}"
    );
}

#[test]
fn an_avalanche_off_the_grid_is_refused() {
    let bytes = checkpoint_at(2.5);
    let record = json!({
        "day": 1.0, "trigger": "user", "cell": [COLS + 5, 0], "map_xy": [0.0, 0.0],
        "released_m3": 1.0, "entrained_m3": 0.0, "deposited_m3": 1.0, "outflow_m3": 0.0,
        "runout_length_m": 10.0, "travel_angle_deg": 30.0, "footprint_area_m2": 400.0,
        "max_speed_m_s": 5.0, "simulated_s": 10.0, "steps": 100,
        "release_temperature_c": null, "alpha": 0.5
    });
    let forged = forge(&bytes, |h| h["avalanches"] = json!([record.clone()]));
    let (field, message) = refused_field(&forged);
    assert_eq!(field, "avalanches[0].cell", "{message}");
    // On the grid but on a day past the season's reach.
    let mut late = record.clone();
    late["cell"] = json!([3, 4]);
    late["day"] = json!(-2.0);
    let (field, message) = refused_field(&forge(&bytes, |h| h["avalanches"] = json!([late])));
    assert_eq!(field, "avalanches[0].day", "{message}");
}

#[test]
fn nan_negative_or_off_terrain_snow_is_refused() {
    let bytes = checkpoint_at(2.5);
    for (map, cell, v, want) in [
        (0, 5, f32::NAN, "layer 0 cell 5"),
        (2, 17, -1.0, "layer 2 cell 17"),
        (3, 0, f32::INFINITY, "layer 3 cell 0"),
        (4, 9, f32::NAN, "scour cell 9"),
        (10, 3, f32::NEG_INFINITY, "pending_rain cell 3"),
    ] {
        let (field, message) = refused_field(&forge_map(&bytes, map, cell, v));
        assert_eq!(field, want, "{message}");
    }
}

/// A fresh folder under the system's temporary one.
fn temp_dir(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("snowscape-ckpt-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn resume_file(path: &Path) -> Result<Winter, SeasonError> {
    Winter::resume_from_file(scenario(), terrain(), None, path)
}

#[test]
fn only_a_regular_file_of_bounded_length_is_read() {
    let d = temp_dir("files");
    let bytes = checkpoint_at(2.5);
    let p = d.join("checkpoint.bin");
    std::fs::write(&p, &bytes).unwrap();
    assert!(resume_file(&p).is_ok());

    // A link to /dev/zero (read 4.2 GB before), a directory: refused before any read.
    let zero = d.join("zero.bin");
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    for (path, kind) in [(&zero, "a character device"), (&d, "a directory")] {
        match resume_file(path) {
            Err(SeasonError::Checkpoint(CheckpointError::NotRegular { kind: k, .. })) => {
                assert_eq!(k, kind)
            }
            other => panic!("{}: {:?}", path.display(), other.map(|_| ())),
        }
    }
    // A FIFO (hung before): refused without opening it.
    let fifo = d.join("fifo.bin");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .is_ok_and(|s| s.success());
    if made {
        let t = std::time::Instant::now();
        assert!(matches!(
            resume_file(&fifo),
            Err(SeasonError::Checkpoint(CheckpointError::NotRegular {
                kind: "a FIFO (named pipe)",
                ..
            }))
        ));
        assert!(t.elapsed().as_secs() < 5);
    }
    // Longer than the largest checkpoint of this terrain (sparse: no disk used).
    let big = d.join("big.bin");
    // 11 extra maps; the 24x20 grid at 8 texels per cell is 3x3 tiles of 64².
    let max = checkpoint::max_len(checkpoint::Bounds {
        cells: COLS * ROWS,
        extra: 11,
        tiles: 9,
    });
    std::fs::File::create(&big)
        .unwrap()
        .set_len(max + 1)
        .unwrap();
    assert!(matches!(
        resume_file(&big),
        Err(SeasonError::Checkpoint(CheckpointError::TooLarge { bytes, .. })) if bytes == max + 1
    ));
    // A preamble announcing the largest header, in a short file: refused by the file's
    // length before the body is allocated.
    let mut lying = bytes.clone();
    lying[12..20].copy_from_slice(&checkpoint::MAX_HEADER.to_le_bytes());
    std::fs::write(&p, &lying).unwrap();
    assert!(matches!(
        resume_file(&p),
        Err(SeasonError::Checkpoint(CheckpointError::Truncated { found, .. })) if found == bytes.len() as u64
    ));
    // One byte more than announced.
    let mut longer = bytes.clone();
    longer.push(0);
    std::fs::write(&p, &longer).unwrap();
    assert!(matches!(
        resume_file(&p),
        Err(SeasonError::Checkpoint(CheckpointError::TrailingBytes {
            extra: 1
        }))
    ));
    std::fs::remove_dir_all(&d).unwrap();
}

/// The season of these tests with 48 skiers a day stepped 2 s a start (so that skiers are
/// on the slopes at a checkpoint) and painted release rates, on the cone under 1 m of snow.
fn ski_scenario() -> snowscape_season::scenario::Scenario {
    let mut s = scenario();
    s.skiers.per_day = 48.0;
    s.skiers.max_run_s = 2.0;
    s
}

/// A genuine checkpoint of the skiing season at day 1.5.
fn ski_checkpoint() -> Vec<u8> {
    let mut t = terrain();
    t.layer_mut(snowscape_terrain::SnowLayer::Stable).fill(1.0);
    let mut w = Winter::new(ski_scenario(), t).unwrap();
    let paint: Vec<f32> = (0..COLS * ROWS).map(|i| (i % 5) as f32 * 0.05).collect();
    w.set_painted_release(Some(&paint), 60.0).unwrap();
    w.run_until(1.5).unwrap();
    let area = w.ski_area().expect("skiers came");
    assert!(!area.skiers().is_empty(), "no skier on the slopes");
    assert!(!area.finished_tracks().is_empty(), "no finished track");
    assert!(area.texture().allocated_tiles() > 0);
    let mut bytes = Vec::new();
    w.write_checkpoint(&mut bytes).unwrap();
    bytes
}

/// The refusal of a forged skiing checkpoint: the field named and the message.
fn ski_refused(bytes: &[u8]) -> (String, String) {
    implausible(Winter::resume(ski_scenario(), terrain(), &mut &bytes[..]))
}

/// `bytes` with its header, ski tracks (as JSON) and tiles edited, lengths and CRC anew.
fn forge_ski(
    bytes: &[u8],
    edit: impl FnOnce(&mut Value, &mut Value, &mut Vec<u8>, &mut Vec<u8>),
) -> Vec<u8> {
    let (header, rest) = split_raw(bytes);
    let (mut maps, tracks, mut tiles) = sections(&rest);
    let mut header: Value = serde_json::from_slice(&header).unwrap();
    let mut tracks: Value = serde_json::from_slice(&tracks).unwrap();
    edit(&mut header, &mut tracks, &mut maps, &mut tiles);
    assemble_sections(
        &serde_json::to_vec(&header).unwrap(),
        &maps,
        &serde_json::to_vec(&tracks).unwrap(),
        &tiles,
    )
}

/// An edit of a skiing checkpoint: header, tracks, maps, tiles.
type SkiEdit = Box<dyn Fn(&mut Value, &mut Value, &mut Vec<u8>, &mut Vec<u8>)>;

/// Sets the f32 at `at` (in words) of `bytes`.
fn set_word(bytes: &mut [u8], at: usize, v: f32) {
    bytes[4 * at..4 * at + 4].copy_from_slice(&v.to_le_bytes());
}

#[test]
fn a_forged_ski_area_or_paint_is_refused_naming_the_field() {
    let bytes = ski_checkpoint();
    let w = Winter::resume(ski_scenario(), terrain(), &mut &bytes[..]).unwrap();
    assert!(w.ski_area().is_some());
    let n = COLS * ROWS;
    // The maps: 4 layers, then scour, deposit, 4 pack arrays, rain, paint, ski distance,
    // recent count, recent time.
    let map = move |k: usize, cell: usize| (4 + k) * n + cell;
    // A tile: its u64 index, then TILE² texels.
    let texel = |k: usize| 2 + k;
    let cases: Vec<(&str, SkiEdit)> = vec![
        (
            "ski_area.next_id",
            Box::new(|h, _, _, _| h["ski_area"]["next_id"] = json!(1u64 << 62)),
        ),
        (
            "ski_area.seed",
            Box::new(|h, _, _, _| h["ski_area"]["seed"] = json!(987_654_321u64)),
        ),
        (
            "ski_area.time_s",
            Box::new(|h, _, _, _| h["ski_area"]["time_s"] = json!(1e300)),
        ),
        (
            "ski_area.time_s",
            Box::new(|h, _, _, _| h["ski_area"]["time_s"] = json!(-5.0)),
        ),
        (
            "ski_area.texels_per_cell",
            Box::new(|h, _, _, _| h["ski_area"]["texels_per_cell"] = json!(3)),
        ),
        (
            "ski tracks",
            Box::new(|h, _, _, _| h["ski_area"] = Value::Null),
        ),
        (
            "ski tracks",
            Box::new(|_, t, _, _| t["skiers"] = json!("not a list")),
        ),
        (
            "ski skiers[0].pos",
            Box::new(|_, t, _, _| t["skiers"][0]["pos"] = json!([-1e9, 3.0])),
        ),
        (
            "ski skiers[0].cell",
            Box::new(|_, t, _, _| t["skiers"][0]["cell"] = json!([COLS, 0])),
        ),
        (
            "ski skiers[0].id",
            Box::new(|_, t, _, _| t["skiers"][0]["track"]["id"] = json!(1u64 << 40)),
        ),
        (
            "ski skiers[0].track.cells",
            Box::new(move |_, t, _, _| t["skiers"][0]["track"]["cells"] = json!([n])),
        ),
        (
            "ski finished[0].cells",
            Box::new(|_, t, _, _| t["finished"][0]["cells"][0] = json!(1u64 << 40)),
        ),
        (
            "painted_release cell 7",
            Box::new(move |_, _, m, _| set_word(m, map(7, 7), f32::NAN)),
        ),
        (
            "painted_release cell 8",
            Box::new(move |_, _, m, _| set_word(m, map(7, 8), -1.0)),
        ),
        (
            "ski distance cell 9",
            Box::new(move |_, _, m, _| set_word(m, map(8, 9), f32::NAN)),
        ),
        (
            "ski distance cell 10",
            Box::new(move |_, _, m, _| set_word(m, map(8, 10), -3.0)),
        ),
        (
            "recent skiers cell 11",
            Box::new(move |_, _, m, _| set_word(m, map(9, 11), f32::INFINITY)),
        ),
        (
            "recent skier time cell 12",
            Box::new(move |_, _, m, _| set_word(m, map(10, 12), -1.0)),
        ),
        (
            "ski texture tile",
            Box::new(|_, _, _, t| t[..8].copy_from_slice(&99u64.to_le_bytes())),
        ),
        (
            "ski texture tile",
            Box::new(|_, _, _, t| t[..8].copy_from_slice(&u64::MAX.to_le_bytes())),
        ),
        (
            "texel 5",
            Box::new(move |_, _, _, t| set_word(t, texel(5), 2.0)),
        ),
        (
            "texel 6",
            Box::new(move |_, _, _, t| set_word(t, texel(6), f32::NAN)),
        ),
    ];
    for (want, edit) in cases {
        let forged = forge_ski(&bytes, edit);
        let (field, message) = ski_refused(&forged);
        assert!(field.contains(want), "{want}: refused {field}: {message}");
        assert!(message.contains(&field), "{message}");
    }
}
