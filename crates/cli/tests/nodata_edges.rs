//! Issue 46 item 9: the nodata outline is a boundary with a stated condition, not a wall that
//! snow piles against. On avaMal (5 m, a nodata outline around the basin) the Sx drift kept
//! the shares aimed at nodata in the sending cell: the one-cell rim held 2.3 m on average
//! between 1400 and 1700 m where the cells one step inside held 0.17 m (avalanches off). The
//! drift now lets them leave the terrain as border outflow, as at the grid's border.
//!
//! The avalanche flow did the same with natural avalanches on (the default scenario): nodata
//! cells were walls, and the rim held 0.19 m where one step inside held 0.15 m (+30 %). With
//! the open border the nodata outline is open as the grid's border is (snow that flows into
//! nodata leaves as border outflow; `snowscape_avalanche::flow`, *Borders*): 0.085 m against
//! 0.079 m.

mod common;

use common::{shared, snowscape, stderr};

/// Mean depth of the valid cells with a nodata neighbour (the rim) and of the valid cells next
/// to the rim (one step inside), within `band` metres of altitude.
fn rim_and_inside(
    depth: &[f32],
    bed: &[f32],
    valid: &[bool],
    w: usize,
    band: (f32, f32),
) -> (f64, f64) {
    let h = valid.len() / w;
    let at = |c: isize, r: isize| -> Option<usize> {
        (c >= 0 && r >= 0 && (c as usize) < w && (r as usize) < h)
            .then(|| r as usize * w + c as usize)
    };
    let neighbours = |i: usize| {
        let (c, r) = ((i % w) as isize, (i / w) as isize);
        (-1..=1)
            .flat_map(move |dr| (-1..=1).map(move |dc| (dc, dr)))
            .filter(|&d| d != (0, 0))
            .filter_map(move |(dc, dr)| at(c + dc, r + dr))
    };
    let rim: Vec<bool> = (0..valid.len())
        .map(|i| valid[i] && neighbours(i).any(|j| !valid[j]))
        .collect();
    let inside: Vec<bool> = (0..valid.len())
        .map(|i| valid[i] && !rim[i] && neighbours(i).any(|j| rim[j]))
        .collect();
    let mean = |set: &[bool]| {
        let v: Vec<f64> = (0..set.len())
            .filter(|&i| set[i] && bed[i] >= band.0 && bed[i] <= band.1)
            .map(|i| f64::from(depth[i]))
            .collect();
        assert!(v.len() > 100, "{} cells", v.len());
        v.iter().sum::<f64>() / v.len() as f64
    };
    (mean(&rim), mean(&inside))
}

/// Runs a season on avaMal (with `scenario`, TOML text; `None`: the default scenario) and
/// returns the mean depth of the rim and of the cells one step inside between 1400 and 1700 m;
/// checks the mass budget closes.
fn avamal_rim(scenario: Option<&str>) -> (f64, f64) {
    let dem = shared("dem/avaframe_avaMal/avaMal.asc");
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    let mut args = vec![
        "--quiet".to_string(),
        "run".to_string(),
        "--dem".to_string(),
        dem.to_str().unwrap().to_string(),
    ];
    if let Some(text) = scenario {
        let path = d.path().join("scenario.toml");
        std::fs::write(&path, text).unwrap();
        args.extend(["--scenario".to_string(), path.to_str().unwrap().to_string()]);
    }
    args.extend(["--out".to_string(), out.to_str().unwrap().to_string()]);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let o = snowscape(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let opts = snowscape_io::ReadOptions::default();
    let depth = snowscape_io::read_dem(&out.join("depth.tif"), &opts).unwrap();
    let bed = snowscape_io::read_dem(&out.join("bedrock.tif"), &opts).unwrap();
    let n = bed.geometry().len();
    let valid: Vec<bool> = (0..n).map(|i| bed.mask().is_valid(i)).collect();
    assert!(valid.iter().any(|v| !v), "avaMal has a nodata outline");
    let budget = &common::report(&out)["mass_budget"];
    assert!(
        budget["closure_error"].as_f64().unwrap().abs() < 1e-5,
        "{budget}"
    );
    rim_and_inside(
        depth.data(),
        bed.data(),
        &valid,
        bed.geometry().width(),
        (1400.0, 1700.0),
    )
}

#[test]
fn the_rim_along_a_nodata_outline_holds_no_snow_wall() {
    let (rim, inside) = avamal_rim(Some("[parameters.avalanche]\nnatural = false\n"));
    eprintln!("avalanches off: rim {rim:.3} m, one step inside {inside:.3} m");
    assert!(
        (rim - inside).abs() <= 0.2 * inside,
        "rim {rim:.3} m against {inside:.3} m one step inside"
    );
}

/// The same with the default scenario, natural avalanches on: the avalanche flow takes the
/// nodata outline as an open border (snow that flows into nodata leaves the terrain), so
/// avalanche debris does not pile against it either.
#[test]
fn avalanches_do_not_pile_against_a_nodata_outline() {
    let (rim, inside) = avamal_rim(None);
    eprintln!("avalanches on: rim {rim:.3} m, one step inside {inside:.3} m");
    assert!(
        (rim - inside).abs() <= 0.2 * inside,
        "rim {rim:.3} m against {inside:.3} m one step inside"
    );
}
