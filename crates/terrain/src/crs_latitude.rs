//! Latitude of a position in a projected CRS, for the sun: the inverse of the Transverse
//! Mercator and Lambert Conformal Conic projections on their ellipsoids, for the EPSG codes
//! that cover the project's data and the common cases (UTM on WGS84 and ETRS89, the Austrian
//! MGI grids). The formulas are those of EPSG Guidance Note 7-2 (§3.2.1.1 Lambert Conic
//! Conformal 2SP, §3.5.3 Transverse Mercator, USGS series). Accuracy: a few metres of latitude
//! near the central meridian, far better than the sun needs.

use crate::Crs;

/// An ellipsoid: semi-major axis (m) and inverse flattening.
#[derive(Debug, Clone, Copy)]
struct Ellipsoid {
    a: f64,
    inv_f: f64,
}

impl Ellipsoid {
    fn e2(self) -> f64 {
        let f = 1.0 / self.inv_f;
        f * (2.0 - f)
    }
}

const WGS84: Ellipsoid = Ellipsoid {
    a: 6_378_137.0,
    inv_f: 298.257_223_563,
};
const GRS80: Ellipsoid = Ellipsoid {
    a: 6_378_137.0,
    inv_f: 298.257_222_101,
};
const BESSEL: Ellipsoid = Ellipsoid {
    a: 6_377_397.155,
    inv_f: 299.152_812_8,
};

/// A supported projection, angles in degrees.
#[derive(Debug, Clone, Copy)]
enum Projection {
    TransverseMercator {
        ell: Ellipsoid,
        lat0: f64,
        k0: f64,
        false_northing: f64,
        false_easting: f64,
    },
    LambertConic2Sp {
        ell: Ellipsoid,
        lat0: f64,
        lat1: f64,
        lat2: f64,
        false_easting: f64,
        false_northing: f64,
    },
}

fn projection(code: u32) -> Option<Projection> {
    use Projection::*;
    let tm = |ell, lat0, k0, fe, fnorth| TransverseMercator {
        ell,
        lat0,
        k0,
        false_easting: fe,
        false_northing: fnorth,
    };
    Some(match code {
        // WGS 84 / UTM zones north and south.
        32601..=32660 => tm(WGS84, 0.0, 0.9996, 500_000.0, 0.0),
        32701..=32760 => tm(WGS84, 0.0, 0.9996, 500_000.0, 10_000_000.0),
        // ETRS89 / UTM zones 28N-38N.
        25828..=25838 => tm(GRS80, 0.0, 0.9996, 500_000.0, 0.0),
        // MGI / Austria GK West, Central, East (false northing -5,000,000 m).
        31254..=31256 => tm(BESSEL, 0.0, 1.0, 0.0, -5_000_000.0),
        // MGI / Austria M28, M31, M34.
        31257..=31259 => tm(
            BESSEL,
            0.0,
            1.0,
            150_000.0 + 300_000.0 * (code - 31257) as f64,
            -5_000_000.0,
        ),
        // MGI / Austria Lambert.
        31287 => LambertConic2Sp {
            ell: BESSEL,
            lat0: 47.5,
            lat1: 49.0,
            lat2: 46.0,
            false_easting: 400_000.0,
            false_northing: 400_000.0,
        },
        _ => return None,
    })
}

/// Latitude (degrees north) of map position `(x, y)` in `crs`, when the CRS is geographic or
/// one of the supported projections.
pub fn latitude_deg(crs: &Crs, x: f64, y: f64) -> Option<f64> {
    if crs.is_geographic() {
        return (-90.0..=90.0).contains(&y).then_some(y);
    }
    let Crs::Epsg(code) = crs else { return None };
    let lat = match projection(*code)? {
        Projection::TransverseMercator {
            ell,
            lat0,
            k0,
            false_easting,
            false_northing,
        } => tm_latitude(ell, lat0, k0, x - false_easting, y - false_northing),
        Projection::LambertConic2Sp {
            ell,
            lat0,
            lat1,
            lat2,
            false_easting,
            false_northing,
        } => lcc_latitude(ell, lat0, lat1, lat2, x - false_easting, y - false_northing),
    };
    (lat.is_finite() && lat.abs() <= 90.0).then_some(lat)
}

/// Meridian arc length from the equator to latitude `phi` (radians), metres.
fn meridian_arc(ell: Ellipsoid, phi: f64) -> f64 {
    let e2 = ell.e2();
    let (e4, e6) = (e2 * e2, e2 * e2 * e2);
    ell.a
        * ((1.0 - e2 / 4.0 - 3.0 * e4 / 64.0 - 5.0 * e6 / 256.0) * phi
            - (3.0 * e2 / 8.0 + 3.0 * e4 / 32.0 + 45.0 * e6 / 1024.0) * (2.0 * phi).sin()
            + (15.0 * e4 / 256.0 + 45.0 * e6 / 1024.0) * (4.0 * phi).sin()
            - (35.0 * e6 / 3072.0) * (6.0 * phi).sin())
}

/// Inverse Transverse Mercator latitude from easting/northing relative to the false origin.
fn tm_latitude(ell: Ellipsoid, lat0: f64, k0: f64, dx: f64, dy: f64) -> f64 {
    let e2 = ell.e2();
    let m = meridian_arc(ell, lat0.to_radians()) + dy / k0;
    let mu = m / (ell.a * (1.0 - e2 / 4.0 - 3.0 * e2 * e2 / 64.0 - 5.0 * e2 * e2 * e2 / 256.0));
    let s = (1.0 - e2).sqrt();
    let e1 = (1.0 - s) / (1.0 + s);
    let phi1 = mu
        + (1.5 * e1 - 27.0 * e1.powi(3) / 32.0) * (2.0 * mu).sin()
        + (21.0 * e1 * e1 / 16.0 - 55.0 * e1.powi(4) / 32.0) * (4.0 * mu).sin()
        + (151.0 * e1.powi(3) / 96.0) * (6.0 * mu).sin()
        + (1097.0 * e1.powi(4) / 512.0) * (8.0 * mu).sin();
    let (sin1, cos1, tan1) = (phi1.sin(), phi1.cos(), phi1.tan());
    let ep2 = e2 / (1.0 - e2);
    let c1 = ep2 * cos1 * cos1;
    let t1 = tan1 * tan1;
    let w = (1.0 - e2 * sin1 * sin1).sqrt();
    let n1 = ell.a / w;
    let r1 = ell.a * (1.0 - e2) / (w * w * w);
    let d = dx / (n1 * k0);
    let phi = phi1
        - (n1 * tan1 / r1)
            * (d * d / 2.0
                - (5.0 + 3.0 * t1 + 10.0 * c1 - 4.0 * c1 * c1 - 9.0 * ep2) * d.powi(4) / 24.0
                + (61.0 + 90.0 * t1 + 298.0 * c1 + 45.0 * t1 * t1 - 252.0 * ep2 - 3.0 * c1 * c1)
                    * d.powi(6)
                    / 720.0);
    phi.to_degrees()
}

/// Inverse Lambert Conformal Conic (2 standard parallels) latitude from easting/northing
/// relative to the false origin.
fn lcc_latitude(ell: Ellipsoid, lat0: f64, lat1: f64, lat2: f64, dx: f64, dy: f64) -> f64 {
    let e2 = ell.e2();
    let e = e2.sqrt();
    let m = |phi: f64| phi.cos() / (1.0 - e2 * phi.sin().powi(2)).sqrt();
    let t = |phi: f64| {
        (std::f64::consts::FRAC_PI_4 - phi / 2.0).tan()
            / ((1.0 - e * phi.sin()) / (1.0 + e * phi.sin())).powf(e / 2.0)
    };
    let (p0, p1, p2) = (lat0.to_radians(), lat1.to_radians(), lat2.to_radians());
    let n = (m(p1).ln() - m(p2).ln()) / (t(p1).ln() - t(p2).ln());
    let f = m(p1) / (n * t(p1).powf(n));
    let r0 = ell.a * f * t(p0).powf(n);
    let rho = n.signum() * (dx * dx + (r0 - dy).powi(2)).sqrt();
    let tp = (rho / (ell.a * f)).powf(1.0 / n);
    let mut phi = std::f64::consts::FRAC_PI_2 - 2.0 * tp.atan();
    for _ in 0..8 {
        let es = e * phi.sin();
        phi = std::f64::consts::FRAC_PI_2
            - 2.0 * (tp * ((1.0 - es) / (1.0 + es)).powf(e / 2.0)).atan();
    }
    phi.to_degrees()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utm_inverse_matches_known_points() {
        // EPSG guidance: UTM 31N (500000, 5540000) is near 50.0 N on the central meridian.
        let lat = latitude_deg(&Crs::Epsg(32631), 500_000.0, 5_538_630.703).unwrap();
        assert!((lat - 50.0).abs() < 1e-4, "{lat}");
        // Reynolds Mountain East, Idaho (UTM 11N), 43.07 N.
        let lat = latitude_deg(&Crs::Epsg(32611), 520_000.0, 4_768_000.0).unwrap();
        assert!((lat - 43.07).abs() < 0.02, "{lat}");
        // Southern hemisphere: UTM 33S, 10 S on the central meridian is k0 times the 1105854.8 m
        // meridian arc south of the false northing.
        let lat = latitude_deg(
            &Crs::Epsg(32733),
            500_000.0,
            10_000_000.0 - 0.9996 * 1_105_854.8,
        )
        .unwrap();
        assert!((lat + 10.0).abs() < 1e-3, "{lat}");
    }

    #[test]
    fn austrian_grids_give_the_data_readme_latitudes() {
        // avaMal (EPSG:31287) centre: 47.02 N per the shared data README.
        let lat = latitude_deg(&Crs::Epsg(31287), 166_773.0 + 1417.0, 349_654.0 + 1967.0).unwrap();
        assert!((lat - 47.02).abs() < 0.02, "{lat}");
        // The Lambert false origin is at 47.5 N.
        let lat = latitude_deg(&Crs::Epsg(31287), 400_000.0, 400_000.0).unwrap();
        assert!((lat - 47.5).abs() < 1e-9, "{lat}");
        // Fluchthorn (EPSG:31254, GK West) lies near 46.89 N.
        let lat = latitude_deg(&Crs::Epsg(31254), -10_805.0 + 1500.0, 193_395.0 + 1100.0).unwrap();
        assert!((lat - 46.89).abs() < 0.03, "{lat}");
    }

    #[test]
    fn unknown_projections_give_none() {
        assert_eq!(
            latitude_deg(&Crs::Epsg(2056), 2_600_000.0, 1_200_000.0),
            None
        );
        assert_eq!(
            latitude_deg(&Crs::Wkt("PROJCS[\"x\"]".into()), 0.0, 0.0),
            None
        );
        assert_eq!(latitude_deg(&Crs::Epsg(4326), 10.0, 47.5), Some(47.5));
    }
}
