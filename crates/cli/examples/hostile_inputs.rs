//! Crafted hostile meshes, forcing CSVs, scenarios and checkpoints for
//! `scripts/input-limits.sh`, which runs `snowscape` on each under `ulimit -v` (issue 46, CI
//! item 7; the rasters have `scripts/reader-limits.sh`).
//!
//! `hostile_inputs craft DIR` writes a small DEM (`dem.asc`) and the files: each claims far
//! more than the readers' documented limits (a face of a million corners, a PLY header of
//! four billion vertices, a GLB whose one mesh 101 nodes reuse for 10.1 million triangles,
//! a glTF accessor of a million positions in 36 bytes, a 1e30 coordinate, an 8 MiB CSV line, a header of
//! 5001 columns, a 16 MiB quoted CSV field, 2.7 million records, a 600 MiB sparse CSV, a 5 MiB
//! scenario, 3651 weather periods, a key nested 5000 deep, absurd values).
//!
//! `hostile_inputs forge RUN DIR` copies the run folder `RUN` (a run stopped with
//! `--stop-at`, holding `checkpoint.bin` and `scenario.toml`) to folders `DIR/ckpt_*`, each
//! with its checkpoint replaced: a 1 TiB sparse file, a preamble announcing a header of 2^62
//! bytes, one announcing 64 MiB in a short file, and forged ones (their CRC computed anew)
//! with a weather index of 2^63, a time of -1e300 days and a NaN snow cell.

use serde_json::Value;
use std::path::Path;

/// Bytes before a checkpoint's JSON header: magic, version, header length, maps length.
/// A format-4 checkpoint's preamble: magic, version, and the lengths of its header, maps, ski
/// tracks and track tiles (`snowscape_season::checkpoint::PREAMBLE`).
const PREAMBLE: usize = 8 + 4 + 4 * 8;

type Io = std::io::Result<()>;

fn dem(dir: &Path) -> Io {
    let mut text = String::from(
        "ncols 40\nnrows 30\nxllcorner 0\nyllcorner 0\ncellsize 20\nNODATA_value -9999\n",
    );
    for r in 0..30 {
        let row: Vec<String> = (0..40)
            .map(|c| format!("{:.1}", 1800.0 + 25.0 * c as f64 - 3.0 * r as f64))
            .collect();
        text += &row.join(" ");
        text.push('\n');
    }
    std::fs::write(dir.join("dem.asc"), text)
}

/// A GLB of `json` and a BIN chunk of `bin`.
fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut json = json.as_bytes().to_vec();
    json.resize(json.len().next_multiple_of(4), b' ');
    let mut bin = bin.to_vec();
    bin.resize(bin.len().next_multiple_of(4), 0);
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

/// Three positions, then `strip` u8 indices: the BIN chunk of the reuse GLB.
fn triangle_and_strip(strip: usize) -> Vec<u8> {
    let mut bin: Vec<u8> = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]
        .iter()
        .flat_map(|c| c.to_le_bytes())
        .collect();
    bin.extend((0..strip).map(|k| (k % 3) as u8));
    bin
}

fn meshes(dir: &Path) -> Io {
    let w = |name: &str, bytes: &[u8]| std::fs::write(dir.join(name), bytes);
    let quad = "v 0 0 0\nv 1 0 0\nv 1 0 -1\nv 0 0 -1\n";
    let corners: Vec<String> = (0..1_000_000).map(|i| (1 + i % 4).to_string()).collect();
    w(
        "huge_face.obj",
        format!("{quad}f {}\n", corners.join(" ")).as_bytes(),
    )?;
    w(
        "far.obj",
        format!("{quad}v 1e30 0 0\nf 1 2 3\nf 1 3 5\n").as_bytes(),
    )?;
    w(
        "vertices.ply",
        b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n\
          property float y\nproperty float z\nelement face 1\n\
          property list uchar int vertex_indices\nend_header\n",
    )?;
    // One mesh of 100,000 strip triangles, placed by 101 nodes.
    let strip = 100_002;
    let roots: Vec<String> = (0..101).map(|k| k.to_string()).collect();
    let nodes = vec![r#"{"mesh":0}"#; 101].join(",");
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[{}]}}],"nodes":[{nodes}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"mode":5}}]}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,0,1]}},
             {{"bufferView":1,"componentType":5121,"count":{strip},"type":"SCALAR"}}],
"bufferViews":[{{"buffer":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":{strip}}}],
"buffers":[{{"byteLength":{}}}]}}"#,
        roots.join(","),
        36 + strip
    );
    w("reused.glb", &glb(&json, &triangle_and_strip(strip)))?;
    // An accessor of a million positions in a 36-byte buffer.
    let json = r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
"accessors":[{"bufferView":0,"componentType":5126,"count":1000000,"type":"VEC3","min":[0,0,0],"max":[1,0,1]}],
"bufferViews":[{"buffer":0,"byteLength":36}],"buffers":[{"byteLength":36}]}"#;
    w("accessor.glb", &glb(json, &triangle_and_strip(0)))
}

fn forcing(dir: &Path) -> std::io::Result<()> {
    let w = |name: &str, bytes: &[u8]| std::fs::write(dir.join(name), bytes);
    let head = "time,air_temperature_c,precipitation_mm,wind_speed_m_s\n";
    let row = "2000-01-01T00:00,1,0,2\n";
    w(
        "long_line.csv",
        format!("{head}{}\n", "7".repeat(8 << 20)).as_bytes(),
    )?;
    w(
        "columns.csv",
        format!("{}\n{row}", ",".repeat(5000)).as_bytes(),
    )?;
    // A quoted field of 16 MiB over lines of 1 KiB: every line within the line limit.
    let field = format!("\"{}\"", format!("{}\n", "x".repeat(1023)).repeat(16 << 10));
    w(
        "field.csv",
        format!("{head}2000-01-01T00:00,{field},0,2\n").as_bytes(),
    )?;
    let mut records = String::with_capacity(8 * 2_700_000 + head.len());
    records += head;
    for _ in 0..2_700_000 {
        records += "1,1,1,1\n";
    }
    w("records.csv", records.as_bytes())?;
    let big = std::fs::File::create(dir.join("big.csv"))?;
    big.set_len(600 << 20)
}

fn scenarios(dir: &Path) -> Io {
    let w = |name: &str, text: &str| std::fs::write(dir.join(name), text);
    w(
        "big.toml",
        &"# a comment line of 64 bytes, repeated to five mebibytes ......\n".repeat(5 << 14),
    )?;
    let period = "[[weather]]\nfrom_day = {k}\nsea_level_temperature_c = 5\nwind_from_deg = 0\nwind_speed_m_s = 5\nsnowfall_per_week = 1\n";
    let mut text = String::from("days = 3650\n");
    for k in 0..3651 {
        text += &period.replace("{k}", &k.to_string());
    }
    w("weather.toml", &text)?;
    w(
        "deep.toml",
        &format!("days = 10\n{} = 1\n", vec!["a"; 5000].join(".")),
    )?;
    w("days.toml", "days = 1e308\n")?;
    w(
        "snapshots.toml",
        "days = 100\nsnapshot_every_days = 1e-300\n",
    )
}

fn craft(dir: &Path) -> Io {
    std::fs::create_dir_all(dir)?;
    dem(dir)?;
    meshes(dir)?;
    forcing(dir)?;
    scenarios(dir)
}

/// A checkpoint of the header bytes `json` and `maps`, lengths and CRC computed anew.
/// A checkpoint of `json` and `maps` with the ski sections `tail` (their two lengths
/// `tail_lens`, then their bytes) and a CRC over it all.
fn assemble(version: &[u8], json: &[u8], maps: &[u8], tail: (&[u8], &[u8])) -> Vec<u8> {
    let mut out = b"SNOWCKPT".to_vec();
    out.extend_from_slice(version);
    out.extend_from_slice(&(json.len() as u64).to_le_bytes());
    out.extend_from_slice(&(maps.len() as u64).to_le_bytes());
    out.extend_from_slice(tail.0);
    out.extend_from_slice(json);
    out.extend_from_slice(maps);
    out.extend_from_slice(tail.1);
    let crc = crc32fast::hash(&out);
    out.extend_from_slice(&crc.to_le_bytes());
    out
}

/// Copies the run folder `run` to `dir/name` with its checkpoint replaced by `bytes` (or by
/// a sparse file of `sparse` bytes).
fn variant(run: &Path, dir: &Path, name: &str, bytes: Option<&[u8]>, sparse: u64) -> Io {
    let to = dir.join(name);
    std::fs::create_dir_all(&to)?;
    for entry in std::fs::read_dir(run)? {
        let entry = entry?;
        if entry.file_type()?.is_file() {
            std::fs::copy(entry.path(), to.join(entry.file_name()))?;
        }
    }
    let ckpt = to.join("checkpoint.bin");
    match bytes {
        Some(b) => std::fs::write(ckpt, b),
        None => std::fs::File::create(ckpt)?.set_len(sparse),
    }
}

fn forge(run: &Path, dir: &Path) -> Io {
    let bytes = std::fs::read(run.join("checkpoint.bin"))?;
    let word = |at: usize| u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap()) as usize;
    let (header_len, maps_len) = (word(12), word(20));
    let json = &bytes[PREAMBLE..PREAMBLE + header_len];
    let maps = &bytes[PREAMBLE + header_len..PREAMBLE + header_len + maps_len];
    // The ski tracks' and tiles' lengths and bytes, kept as they are.
    let tail = (
        &bytes[28..PREAMBLE],
        &bytes[PREAMBLE + header_len + maps_len..bytes.len() - 4],
    );
    let version = &bytes[8..12];
    variant(run, dir, "ckpt_sparse", None, 1 << 40)?;
    let mut long = bytes.clone();
    long[12..20].copy_from_slice(&(1u64 << 62).to_le_bytes());
    variant(run, dir, "ckpt_header_len", Some(&long), 0)?;
    let mut short = bytes.clone();
    short[12..20].copy_from_slice(&(64u64 << 20).to_le_bytes());
    variant(run, dir, "ckpt_short", Some(&short), 0)?;
    let header: Value = serde_json::from_slice(json)?;
    let edited = |edit: &dyn Fn(&mut Value)| {
        let mut h = header.clone();
        edit(&mut h);
        serde_json::to_vec(&h).expect("a JSON value")
    };
    let index = edited(&|h| h["weather_index"] = Value::from(1u64 << 63));
    variant(
        run,
        dir,
        "ckpt_index",
        Some(&assemble(version, &index, maps, tail)),
        0,
    )?;
    let time = edited(&|h| h["scheduler"]["time_days"] = Value::from(-1e300));
    variant(
        run,
        dir,
        "ckpt_time",
        Some(&assemble(version, &time, maps, tail)),
        0,
    )?;
    let mut nan = maps.to_vec();
    nan[20..24].copy_from_slice(&f32::NAN.to_le_bytes());
    variant(
        run,
        dir,
        "ckpt_nan",
        Some(&assemble(version, json, &nan, tail)),
        0,
    )
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let r = match (args.get(1).map(String::as_str), args.len()) {
        (Some("craft"), 3) => craft(Path::new(&args[2])),
        (Some("forge"), 4) => forge(Path::new(&args[2]), Path::new(&args[3])),
        _ => {
            eprintln!("usage: hostile_inputs craft DIR | hostile_inputs forge RUN DIR");
            std::process::exit(64);
        }
    };
    if let Err(e) = r {
        eprintln!("hostile_inputs: {e}");
        std::process::exit(1);
    }
}
