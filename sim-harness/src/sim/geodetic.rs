//! The simulator's NED frame on the WGS-84 ellipsoid. Its flat-earth NED position is taken as
//! the local tangent plane at [`ORIGIN`] (north_m = east_m = 0, altitude 0 there), and
//! converted through ECEF by the `map_3d` crate (exact on the ellipsoid, no small-area
//! approximation).

use crate::sim::rotation::V3;
use map_3d::Ellipsoid;

/// The NED origin: latitude, longitude (deg), WGS-84 height (m). PX4 SITL's default home
/// (Zürich); any site would do, the estimator does not use position.
pub const ORIGIN: [f64; 3] = [47.397_742, 8.545_594, 488.0];

/// NED metres about `origin` (deg, deg, m) → latitude, longitude (deg), WGS-84 height (m).
pub fn offset(origin: [f64; 3], ned: V3) -> [f64; 3] {
    let (lat, lon, h) = map_3d::ned2geodetic(
        ned[0],
        ned[1],
        ned[2],
        origin[0].to_radians(),
        origin[1].to_radians(),
        origin[2],
        Ellipsoid::WGS84,
    );
    [lat.to_degrees(), lon.to_degrees(), h]
}

/// A simulator NED position (m, about [`ORIGIN`]) → latitude, longitude (deg), height (m).
pub fn lla_of(ned: V3) -> [f64; 3] {
    offset(ORIGIN, ned)
}

/// Latitude, longitude (deg), height (m) → NED metres about `origin` (the inverse of [`offset`]).
pub fn ned_of(origin: [f64; 3], lla: [f64; 3]) -> V3 {
    let (n, e, d) = map_3d::geodetic2ned(
        lla[0].to_radians(),
        lla[1].to_radians(),
        lla[2],
        origin[0].to_radians(),
        origin[1].to_radians(),
        origin[2],
        Ellipsoid::WGS84,
    );
    [n, e, d]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 1 km north at 47.4° N and height h is 1000 / (M + h) radians, M the meridian radius of
    /// curvature a(1 − e²)/(1 − e² sin²φ)^{3/2}; the round trip returns the offset.
    #[test]
    fn north_offset_matches_the_meridian_radius_and_round_trips() {
        let (a, e2) = (6_378_137.0_f64, 6.694_379_990_14e-3_f64);
        let s = ORIGIN[0].to_radians().sin();
        let m = a * (1.0 - e2) / (1.0 - e2 * s * s).powf(1.5);
        let p = offset(ORIGIN, [1000.0, 0.0, 0.0]);
        let dlat = (p[0] - ORIGIN[0]).to_radians();
        let arc = dlat * (m + ORIGIN[2]);
        assert!((arc - 1000.0).abs() < 0.01, "{arc}");
        let back = ned_of(ORIGIN, offset(ORIGIN, [1234.5, -678.9, -140.0]));
        for (b, x) in back.iter().zip([1234.5, -678.9, -140.0]) {
            assert!((b - x).abs() < 1e-6, "{back:?}");
        }
    }
}
