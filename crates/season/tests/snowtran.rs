//! The physical wind transport (Jubert 2018, SnowTran-3D) as the season's wind phenomenon:
//! the scenario switch, the volume budget with sublimation, erosion upwind and deposit
//! downwind of a ridge, untouched bed layers, and thread-count determinism.

use snowscape_season::scenario::Scenario;
use snowscape_season::snowtran_transport::{
    SnowTranForcing, SnowTranParams, SnowTranScratch, step_season,
};
use snowscape_season::wind_transport::WindModel;
use snowscape_season::winter::Winter;
use snowscape_terrain::{Grid, GridGeometry, LayeredTerrain, SnowLayer};

const W: usize = 80;
const H: usize = 12;
const CREST: usize = 40;

/// A north-south ridge 40 m high of 5 m cells, 30 cm of powder on 20 cm of unstable snow
/// on 50 cm of stable snow.
fn ridge() -> LayeredTerrain {
    let geo = GridGeometry::square(W, H, 5.0).unwrap();
    let bed = Grid::from_fn(geo, |c, _| {
        let x = (c as f32 - CREST as f32) * 5.0;
        1000.0 + 40.0 * (-(x / 40.0).powi(2)).exp()
    });
    let mut t = LayeredTerrain::from_bedrock(bed);
    t.layer_mut(SnowLayer::Powder).fill(0.3);
    t.layer_mut(SnowLayer::Unstable).fill(0.2);
    t.layer_mut(SnowLayer::Stable).fill(0.5);
    t
}

/// A westerly wind (towards the east) of 16 m/s up to the crest that drops to 4 m/s in
/// the lee (the sheltered side).
fn forcing_maps() -> (Vec<f32>, Vec<f32>, Vec<f32>) {
    let u: Vec<f32> = (0..W * H)
        .map(|i| {
            let x = (i % W) as f32 - CREST as f32;
            16.0 - 12.0 * (x / 3.0).clamp(0.0, 1.0)
        })
        .collect();
    (u, vec![0.0; W * H], vec![-8.0; W * H])
}

fn one_day(
    threads: usize,
) -> (
    LayeredTerrain,
    snowscape_season::snowtran_transport::SnowTranReport,
) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let mut t = ridge();
        let (u, v, temp) = forcing_maps();
        let forcing = SnowTranForcing {
            wind_u: &u,
            wind_v: &v,
            temperature: &temp,
            latitude_deg: 46.0,
            day_of_year: 20.0,
            start_day: 0.0,
        };
        let r = step_season(
            &SnowTranParams::default(),
            &mut t,
            &forcing,
            &mut SnowTranScratch::default(),
            1.0,
        )
        .unwrap();
        (t, r)
    })
}

fn column(t: &LayeredTerrain, layer: SnowLayer, c: usize) -> f32 {
    (2..H - 2).map(|r| t.layer(layer)[r * W + c]).sum::<f32>() / (H - 4) as f32
}

#[test]
fn wind_scours_the_windward_slope_fills_the_lee_and_the_budget_closes() {
    let before = ridge();
    let (t, r) = one_day(2);
    assert!(r.eroded > 0.0 && r.deposited > 0.0, "{r:?}");
    assert!(
        r.sublimated > 0.0,
        "blowing snow sublimates in dry air: {r:?}"
    );
    assert_eq!(r.substeps, 24);
    // The volume budget: what left the layers is what sublimated or blew out of the grid.
    let lost = before.snow_volume() - t.snow_volume();
    let expected = r.sublimated + r.border_net_outflow;
    assert!(
        (lost - expected).abs() <= 1e-4 * before.snow_volume(),
        "lost {lost} m³, sublimated + outflow {expected} m³"
    );
    // The bed is untouched, nothing is negative.
    assert_eq!(t.layer(SnowLayer::Stable), before.layer(SnowLayer::Stable));
    t.check_invariants().unwrap();
    // The windward slope is scoured, powder first; the sheltered lee, where the flux that
    // crossed the crest drops out, gains snow (a drift behind the crest).
    let erodible = |c: usize| column(&t, SnowLayer::Powder, c) + column(&t, SnowLayer::Unstable, c);
    assert!(
        erodible(CREST - 5) < 0.45,
        "windward {}",
        erodible(CREST - 5)
    );
    assert!(column(&t, SnowLayer::Powder, CREST - 5) < 0.25);
    let lee = (CREST + 1..CREST + 8).map(erodible).fold(0.0f32, f32::max);
    assert!(lee > 0.55, "lee drift {lee}");
}

#[test]
fn bit_identical_for_one_and_two_threads() {
    let (a, ra) = one_day(1);
    let (b, rb) = one_day(2);
    assert_eq!(a, b);
    assert_eq!(ra, rb);
}

#[test]
fn bad_parameters_are_named() {
    let mut p = SnowTranParams {
        erodible_density: -3.0,
        ..Default::default()
    };
    let e = p.validate().unwrap_err().to_string();
    assert!(e.contains("erodible_density") && e.contains("-3"), "{e}");
    p.erodible_density = 150.0;
    p.transport.fetch_m = 0.0;
    let e = p.validate().unwrap_err().to_string();
    assert!(e.contains("fetch_m"), "{e}");
}

/// A 64x64 mountain of 20 m cells rising from 600 m to 2600 m.
fn mountain() -> LayeredTerrain {
    let n = 64;
    let g = GridGeometry::square(n, n, 20.0).unwrap();
    LayeredTerrain::from_bedrock(Grid::from_fn(g, |c, r| {
        let (x, y) = (c as f32 / n as f32 - 0.5, r as f32 / n as f32 - 0.5);
        let d = (x * x + y * y).sqrt();
        600.0 + 2000.0 * (1.0 - 2.0 * d).max(0.0).powf(1.5)
    }))
}

fn winter(model: WindModel) -> Winter {
    let mut s = Scenario::from_toml(
        "days = 30\n[parameters.wind_transport]\nmodel = \"snowtran\"\n[parameters.snowtran]\nrelative_humidity_pct = 60\n",
        "test",
    )
    .unwrap();
    assert_eq!(s.parameters.wind_transport.model, WindModel::Snowtran);
    s.parameters.wind_transport.model = model;
    s.parameters.environment.sky.directions = 8;
    s.parameters.environment.sun.day_step = 30;
    let mut w = Winter::new(s, mountain()).unwrap();
    w.run_until(30.0).unwrap();
    w
}

#[test]
fn a_season_driven_by_the_physical_wind_closes_its_budget() {
    let w = winter(WindModel::Snowtran);
    let b = w.budget();
    let store = w.terrain.snow_volume();
    let rel = (store - b.expected_store()).abs() / b.snowfall.max(1.0);
    assert!(b.snowfall > 0.0);
    assert!(
        rel < 1e-5,
        "closure error {rel}: store {store}, budget {b:?}"
    );
    assert!(b.wind_sublimation > 0.0, "{b:?}");
    w.terrain.check_invariants().unwrap();
    // The switch changes the physics: the Cordonnier winter's sublimation is its Sx drift's
    // (issue 47), and its snow differs.
    let c = winter(WindModel::Cordonnier);
    assert_ne!(c.budget().wind_sublimation, b.wind_sublimation);
    assert_ne!(c.terrain.total_depth(), w.terrain.total_depth());
}
