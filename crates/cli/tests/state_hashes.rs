//! The model's results pinned across refactors: each job (a demo, a season on a real DEM, both
//! mesh covers, a transport run, an avalanche) runs at a small size and the decoded values of
//! its state outputs are hashed and compared with the hashes recorded before the architecture
//! refactor (issue 22). Rasters are hashed by their decoded values and OBJ meshes by their
//! parsed vertices and faces, so that a change of file layout (tags, number formatting) does
//! not count, but any change of a number does.
//!
//! A deliberate change of the physics updates the table: the failure message prints the new
//! one. The outputs are deterministic by construction (fixed seeds, no time budgets: the
//! Fearing cover ends every stage on a work count; its wall-clock budget is a safety net).
//!
//! The demo runs 100 days at 192² (3 avalanches, with entrainment): the earlier 4-day demo
//! had no snow yet and pinned only the environment (its layers all hashed as zeros).

mod common;

use common::{shared, snowscape, stderr};
use std::path::Path;

/// FNV-1a, 64 bits (stable across platforms and Rust versions, unlike `DefaultHasher`).
struct Fnv(u64);

impl Fnv {
    fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
    fn bytes(&mut self, b: &[u8]) {
        for &x in b {
            self.0 ^= u64::from(x);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }
}

/// Hash of a GeoTIFF's size and decoded samples (f32 bits, or the integer samples).
fn raster_hash(path: &Path) -> u64 {
    use tiff::decoder::{Decoder, DecodingResult};
    let f = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut d = Decoder::new(std::io::BufReader::new(f)).unwrap();
    let (w, h) = d.dimensions().unwrap();
    let mut hash = Fnv::new();
    hash.bytes(&w.to_le_bytes());
    hash.bytes(&h.to_le_bytes());
    match d.read_image().unwrap() {
        DecodingResult::F32(v) => v
            .iter()
            .for_each(|x| hash.bytes(&x.to_bits().to_le_bytes())),
        DecodingResult::F64(v) => v
            .iter()
            .for_each(|x| hash.bytes(&x.to_bits().to_le_bytes())),
        DecodingResult::U8(v) => hash.bytes(&v),
        DecodingResult::U16(v) => v.iter().for_each(|x| hash.bytes(&x.to_le_bytes())),
        DecodingResult::U32(v) => v.iter().for_each(|x| hash.bytes(&x.to_le_bytes())),
        other => panic!("{}: unexpected sample type {other:?}", path.display()),
    }
    hash.0
}

/// Hash of an OBJ's vertices (parsed to f32 bits) and faces (vertex indices).
fn obj_hash(path: &Path) -> u64 {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut hash = Fnv::new();
    for line in text.lines() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                hash.bytes(b"v");
                for w in words {
                    hash.bytes(&w.parse::<f32>().unwrap().to_bits().to_le_bytes());
                }
            }
            Some("f") => {
                hash.bytes(b"f");
                for w in words {
                    let index: u32 = w.split('/').next().unwrap().parse().unwrap();
                    hash.bytes(&index.to_le_bytes());
                }
            }
            _ => {}
        }
    }
    hash.0
}

/// Hash of a file's bytes (for the transport's binary wind field).
fn bytes_hash(path: &Path) -> u64 {
    let mut hash = Fnv::new();
    hash.bytes(&std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())));
    hash.0
}

/// Runs `snowscape` with `args` (an `--out` folder added), failing on a non-zero exit.
fn job(out: &Path, args: &[&str]) {
    let mut a = vec!["--quiet"];
    a.extend_from_slice(args);
    a.extend(["--out", out.to_str().unwrap()]);
    let o = snowscape(&a);
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
}

/// The hashes recorded on 2026-12-04 at commit 585ce0d, before the refactor (issue 22). Two
/// deliberate changes since: the 3D transport's gravity is the model's one value, 9.81 m/s²,
/// instead of 9.80665 (its depth, density and saltation maps; `terrain::materials`), and the
/// Sx drift sweep's carries along a row regrouped into a segmented scan (2026-12-05: the
/// demo's layers and avalanche maps, to f32 round-off in each wind step;
/// `wind_transport::sheltered::drift_row`). Issue 47 (storm meteorology): storm hours are
/// colder with a damped cycle, the phase is psychrometric and storms are laid hour by hour
/// (`season::storms`): the demo's and the run's layers and avalanche maps changed, and the
/// demo's temperature map (the daily mean at the last melt window, whose day moved with the
/// events). Issue 47 (avalanches): the avalanche job's defaults are AvaFrame's samosATSmall law
/// with the slope-projected gravity and the bed's curvature (its maps changed); the energy-balance
/// melt and the two-scale wind (the seasons' layers, avalanche and temperature maps); the
/// energy balance's 4-hour dark steps and the wind's coarser long-range blocks (2026-12-07 merge);
/// the drifting snow's sublimation in the climate's humidity and the energy balance's two-hour
/// sun steps from a predicted surface temperature (the demo's and the run's layers).
const RECORDED: &[(&str, &str, u64)] = &[
    ("demo", "depth.tif", 0xa452df6ccd7d94cf),
    ("demo", "layers_compacted.tif", 0xd68b9231e3e8410a),
    ("demo", "layers_stable.tif", 0xc838f60c42ff220c),
    ("demo", "layers_unstable.tif", 0x573838ea55d5bfa9),
    ("demo", "layers_powder.tif", 0x2cb557c3a2d3cf49),
    ("demo", "avalanche_deposit.tif", 0x776da0df4d3d7621),
    ("demo", "avalanche_scour.tif", 0x5d7849980bacba4d),
    ("demo", "sun.tif", 0xfcb39c4ed645fea0),
    ("demo", "temperature.tif", 0x087f7d39f09d1ff8),
    ("demo", "wind.tif", 0x3b9f07eae1d5ecd2),
    ("run", "depth.tif", 0x63030feae503ae95),
    ("run", "layers_compacted.tif", 0xa637ba08c7779599),
    ("run", "layers_stable.tif", 0xbcac3cc7fd2acda6),
    ("run", "layers_unstable.tif", 0x1cae586f8241362c),
    ("run", "layers_powder.tif", 0xfb2b2338cac91475),
    ("run", "avalanche_deposit.tif", 0xfb2b2338cac91475),
    ("run", "avalanche_scour.tif", 0xfb2b2338cac91475),
    ("run", "sun.tif", 0xe739275127ee5dd5),
    ("run", "temperature.tif", 0x2b957da5e5e27435),
    ("run", "wind.tif", 0xd7f694f7d15963f9),
    ("cover_diffusion", "snow.obj", 0xfa5d24f00cb32d4d),
    ("cover_fearing", "snow.obj", 0x3eb5132f1795c826),
    ("transport", "depth.tif", 0x67de4a3e5a6bfab6),
    ("transport", "density.tif", 0x6abfe3f33142848f),
    ("transport", "q_salt.tif", 0x3657c6dcd74952ac),
    ("transport", "wind3d.bin", 0x06360c31bb2aa121),
    ("avalanche", "peak_thickness.tif", 0xe66e39a4a1f0a00d),
    ("avalanche", "peak_velocity.tif", 0x63089f6d71670767),
    ("avalanche", "thickness.tif", 0x10f981307ce34a4f),
    ("avalanche", "footprint.tif", 0xf5cc94245f1e5ac3),
];

#[test]
fn every_job_reproduces_the_recorded_state() {
    let d = tempfile::tempdir().unwrap();
    let p = |rel: &str| shared(rel).to_str().unwrap().to_owned();
    let (dam, wog, rel) = (
        p("dem/avaframe_synthetic_avaDamBreak/DEM_IP_Topo.asc"),
        p("dem/avaframe_avaWog/avaWog.asc"),
        p("dem/avaframe_avaWog/REL/relWog.shp"),
    );
    let (spider, bunny) = (p("meshes/spider.obj"), p("meshes/bunny_npm.obj"));
    let dir = |name: &str| d.path().join(name);
    job(
        &dir("demo"),
        &[
            "demo", "--size", "192", "--days", "100", "--frames", "1", "--seed", "5",
        ],
    );
    job(
        &dir("run"),
        &["run", "--dem", &dam, "--days", "10", "--seed", "2"],
    );
    job(
        &dir("cover_diffusion"),
        &[
            "cover",
            "--mesh",
            &spider,
            "--method",
            "diffusion",
            "--growth",
            "3",
        ],
    );
    job(
        &dir("cover_fearing"),
        &[
            "cover", "--mesh", &bunny, "--scale", "0.1", "--method", "fearing", "--passes", "2",
            "--sites", "2500", "--budget", "1000",
        ],
    );
    job(
        &dir("transport"),
        &[
            "transport",
            "--dem",
            &wog,
            "--voxel-size",
            "40",
            "--voxel-layers",
            "50",
            "--hours",
            "2",
            "--flakes",
            "30000",
            "--wind-iterations",
            "4",
            "--seed",
            "3",
        ],
    );
    job(
        &dir("avalanche"),
        &[
            "avalanche",
            "--dem",
            &wog,
            "--release",
            &rel,
            "--duration",
            "15",
            "--frame-interval",
            "5",
        ],
    );
    let season = [
        "depth.tif",
        "layers_compacted.tif",
        "layers_stable.tif",
        "layers_unstable.tif",
        "layers_powder.tif",
        "avalanche_deposit.tif",
        "avalanche_scour.tif",
        "sun.tif",
        "temperature.tif",
        "wind.tif",
    ];
    let mut files: Vec<(&str, &str)> = Vec::new();
    files.extend(season.iter().map(|f| ("demo", *f)));
    files.extend(season.iter().map(|f| ("run", *f)));
    files.extend([
        ("cover_diffusion", "snow.obj"),
        ("cover_fearing", "snow.obj"),
        ("transport", "depth.tif"),
        ("transport", "density.tif"),
        ("transport", "q_salt.tif"),
        ("transport", "wind3d.bin"),
        ("avalanche", "peak_thickness.tif"),
        ("avalanche", "peak_velocity.tif"),
        ("avalanche", "thickness.tif"),
        ("avalanche", "footprint.tif"),
    ]);
    let actual: Vec<(&str, &str, u64)> = files
        .iter()
        .map(|&(j, f)| {
            let path = dir(j).join(f);
            let h = if f.ends_with(".tif") {
                raster_hash(&path)
            } else if f.ends_with(".obj") {
                obj_hash(&path)
            } else {
                bytes_hash(&path)
            };
            (j, f, h)
        })
        .collect();
    let table: String = actual
        .iter()
        .map(|(j, f, h)| format!("    ({j:?}, {f:?}, 0x{h:016x}),\n"))
        .collect();
    assert!(
        actual == RECORDED,
        "the jobs' results changed; if deliberately, the new table is:\n{table}"
    );
}
