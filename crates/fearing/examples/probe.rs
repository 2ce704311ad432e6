//! Prints the per-pass reports of a cover of one shared mesh (diagnostics):
//! `cargo run --release -p snowscape-fearing --example probe -- FILE SCALE [SITES]`.

#[path = "../benches/common/mod.rs"]
mod common;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let scene = if a[1] == "big" {
        common::big_scene()
    } else {
        common::mesh(&a[1], a[2].parse().unwrap())
    };
    let mut p = snowscape_fearing::FearingParams::default();
    if let Ok(v) = std::env::var("MIN_NZ") {
        p.min_normal_z = v.parse().unwrap();
    }
    if let Some(s) = a.get(3) {
        p.target_sites = s.parse().unwrap();
    }
    let c = snowscape_fearing::cover(&scene, &p).unwrap();
    let r = &c.report;
    println!(
        "sites {} flakes {} flakes/s {:.0} rays {} timings {:?}",
        r.sites_final, r.flakes_shot, r.flakes_per_s, r.rays, r.timings
    );
    for p in &r.passes {
        println!("{:?}\n{:?}", p.accumulation, p.stability);
    }
}
