//! The vehicle on a ground station's map (docs/ground-link.md#the-map-origin): the local
//! frame's origin as a latitude, longitude and altitude, and the local position (NED, m) to a
//! global one and back.
//!
//! The local frame is motion capture's: flat, NED, from the take-off point, so a local point is
//! a point of the plane tangent to the WGS-84 ellipsoid at the origin. Its latitude and
//! longitude come from the ellipsoid's radii of curvature at the origin (meridian `M`, prime
//! vertical `N`), with the terms of second order that a flat plane leaves on a curved earth:
//!
//! - latitude `lat0 + (n - e^2 tan(lat0) / (2 N)) / (M + h)` (a line due east in the plane
//!   leaves the parallel southwards, north of the equator: 8 cm at 1 km at 47 degrees);
//! - longitude `lon0 + e / ((N + h) cos(lat0) - n sin(lat0))` (the parallel a point north of the
//!   origin lies on is shorter), with `h = alt0 - d` (the altitude taken as the height over
//!   the ellipsoid: the geoid's 100 m at most change a kilometre by 2 cm);
//! - altitude `alt0 - d` (the room's floor is level: the plane's rise over the ellipsoid,
//!   `(n^2 + e^2) / (2 R)`, 8 cm at 1 km, is left out).
//!
//! Against the exact conversion (through earth-centred coordinates, the tests') that is within
//! a centimetre (MAVLink's 1e-7 degree steps) at 1 km, and at 10 km within 5 cm up to 60
//! degrees of latitude (half a metre at 84): the terms left out grow with the cube of the
//! distance and with `tan(lat0)`. Near the poles east is ill-defined and the ground stations' maps
//! (Web Mercator) end at 85.05 degrees: an origin beyond [`MAX_LAT_E7`] is refused (no global
//! position). Longitudes wrap across the antimeridian into -180 to 180 degrees. A position not
//! finite, or one that would leave -90 to 90 degrees of latitude (thousands of km away), has no
//! global position either. The firmware converts in the link's send path, never in the
//! control step.

use shared::math::{cos, sin, sqrt};
use shared::mission::params::{ORIGIN, ORIGIN_LEN, ParamValues};

/// Latitude beyond which an origin is refused, 1e-7 degrees (85 degrees).
pub const MAX_LAT_E7: i32 = 850_000_000;
/// 180 degrees in 1e-7 degrees.
const HALF_TURN_E7: i64 = 1_800_000_000;
/// One degree in 1e-7 degrees (the parameters' split).
const DEGREE_E7: i32 = 10_000_000;
/// WGS-84 semi-major axis, m.
const WGS84_A: f64 = 6_378_137.0;
/// WGS-84 first eccentricity squared.
const WGS84_E2: f64 = 6.694_379_990_141_316e-3;
/// 1e-7 degrees in a radian.
const E7_PER_RAD: f64 = 1e7 * 180.0 / core::f64::consts::PI;
/// Lowest and highest altitude an origin may have, m (`ORIG_ALT`'s range).
const ALT_RANGE_M: (f32, f32) = (-1_000.0, 10_000.0);

/// The local frame's origin on the earth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GeoOrigin {
    /// Latitude, 1e-7 degrees (north positive).
    pub lat_e7: i32,
    /// Longitude, 1e-7 degrees (east positive), -180 to 180 degrees.
    pub lon_e7: i32,
    /// Altitude above mean sea level, m.
    pub alt_m: f32,
}

/// A point on the earth, in MAVLink's units.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GlobalPoint {
    /// Latitude, 1e-7 degrees.
    pub lat_e7: i32,
    /// Longitude, 1e-7 degrees.
    pub lon_e7: i32,
    /// Altitude above mean sea level, mm.
    pub alt_mm: i32,
}

/// Why an origin is refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OriginError {
    /// The latitude is beyond 85 degrees (or 90).
    Latitude,
    /// The longitude is beyond 180 degrees.
    Longitude,
    /// The altitude is outside -1,000 to 10,000 m.
    Altitude,
}

impl OriginError {
    /// What is wrong, in a few words.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Latitude => "latitude beyond 85 degrees",
            Self::Longitude => "longitude beyond 180 degrees",
            Self::Altitude => "altitude outside -1000..10000 m",
        }
    }
}

impl core::fmt::Display for OriginError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// A value rounded to the nearest whole number (halves away from zero), saturating.
fn round(x: f64) -> i64 {
    if x >= 0.0 {
        (x + 0.5) as i64
    } else {
        (x - 0.5) as i64
    }
}

/// `lon_e7` wrapped into -180 (included) to 180 (excluded) degrees.
fn wrap_lon(lon_e7: i64) -> i64 {
    (lon_e7 + HALF_TURN_E7).rem_euclid(2 * HALF_TURN_E7) - HALF_TURN_E7
}

impl GeoOrigin {
    /// The origin the `ORIG_*` parameters of `values` give (degrees and their 1e-7 part added;
    /// the longitude wrapped into -180 to 180 degrees). It may be unusable ([`Self::check`]).
    pub fn from_params(values: &ParamValues) -> Self {
        let part = |k: usize| values.get(ORIGIN + k).unwrap_or(0.0);
        // Both parts are whole (the table's checks) and well inside i32 once combined.
        let lat = i64::from(DEGREE_E7) * part(0) as i64 + part(1) as i64;
        let lon = i64::from(DEGREE_E7) * part(2) as i64 + part(3) as i64;
        Self {
            lat_e7: lat.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32,
            lon_e7: wrap_lon(lon) as i32,
            alt_m: part(4),
        }
    }

    /// The `ORIG_*` parameter values of this origin, in table order: each coordinate's whole
    /// degrees (towards zero) and the rest in 1e-7 degrees, of the same sign; each exact as a
    /// float.
    pub fn to_params(&self) -> [f32; ORIGIN_LEN] {
        [
            (self.lat_e7 / DEGREE_E7) as f32,
            (self.lat_e7 % DEGREE_E7) as f32,
            (self.lon_e7 / DEGREE_E7) as f32,
            (self.lon_e7 % DEGREE_E7) as f32,
            self.alt_m,
        ]
    }

    /// The origin of a `SET_GPS_GLOBAL_ORIGIN` (altitude in mm), if it is usable.
    pub fn from_message(lat_e7: i32, lon_e7: i32, alt_mm: i32) -> Result<Self, OriginError> {
        let origin = Self {
            lat_e7,
            lon_e7,
            alt_m: alt_mm as f32 * 1e-3,
        };
        origin.check()?;
        Ok(origin)
    }

    /// Whether this origin can place the vehicle: latitude within 85 degrees, longitude within
    /// 180, altitude finite and within `ORIG_ALT`'s range.
    pub fn check(&self) -> Result<(), OriginError> {
        if self.lat_e7.unsigned_abs() > MAX_LAT_E7.unsigned_abs() {
            return Err(OriginError::Latitude);
        }
        if i64::from(self.lon_e7).abs() > HALF_TURN_E7 {
            return Err(OriginError::Longitude);
        }
        if !(self.alt_m >= ALT_RANGE_M.0 && self.alt_m <= ALT_RANGE_M.1) {
            return Err(OriginError::Altitude);
        }
        Ok(())
    }

    /// This origin as a [`GlobalPoint`].
    pub fn point(&self) -> GlobalPoint {
        GlobalPoint {
            lat_e7: self.lat_e7,
            lon_e7: self.lon_e7,
            alt_mm: round(f64::from(self.alt_m) * 1e3) as i32,
        }
    }

    /// `(sin, cos, tan)` of the latitude and the radii of curvature `(M, N)`, m; `None` for an
    /// origin [`Self::check`] refuses.
    fn frame(&self) -> Option<(f64, f64, f64, f64, f64)> {
        self.check().ok()?;
        let lat = (f64::from(self.lat_e7) / E7_PER_RAD) as f32;
        // Single precision is plenty for the scales: 1e-7 of 1 km is 0.1 mm.
        let (s, c) = (f64::from(sin(lat)), f64::from(cos(lat)));
        let w = 1.0 - WGS84_E2 * s * s;
        let root = f64::from(sqrt(w as f32));
        let n = WGS84_A / root;
        let m = WGS84_A * (1.0 - WGS84_E2) / (w * root);
        Some((s, c, s / c, m, n))
    }

    /// The global position of local point `ned` (m, NED from the origin); `None` for an
    /// unusable origin, a point not finite or one beyond -90 to 90 degrees of latitude.
    pub fn to_global(&self, ned: [f32; 3]) -> Option<GlobalPoint> {
        if !ned.iter().all(|v| v.is_finite()) {
            return None;
        }
        let (s, c, t, m, n) = self.frame()?;
        let [north, east, down] = ned.map(f64::from);
        let h = -down;
        // Height over the ellipsoid (mean sea level for it: the geoid's 100 m at most change
        // a kilometre by 2 cm).
        let up = f64::from(self.alt_m) + h;
        let dlat = (north - east * east * t / (2.0 * n)) / (m + up);
        let radius = (n + up) * c - north * s;
        if radius <= 0.0 {
            return None;
        }
        let dlon = east / radius;
        let lat = i64::from(self.lat_e7) + round(dlat * E7_PER_RAD);
        if lat.abs() > HALF_TURN_E7 / 2 {
            return None;
        }
        let lon = wrap_lon(i64::from(self.lon_e7) + round(dlon * E7_PER_RAD));
        let alt_mm = round((f64::from(self.alt_m) + h) * 1e3);
        Some(GlobalPoint {
            lat_e7: lat as i32,
            lon_e7: lon as i32,
            alt_mm: alt_mm.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32,
        })
    }

    /// The local point (m, NED from the origin) of global position `p`, the inverse of
    /// [`Self::to_global`] (to its 1e-7 degree steps, about a centimetre) for points within
    /// tens of kilometres; `None` for an unusable origin.
    pub fn to_local(&self, p: &GlobalPoint) -> Option<[f32; 3]> {
        let (s, c, t, m, n) = self.frame()?;
        let dlat = (i64::from(p.lat_e7) - i64::from(self.lat_e7)) as f64 / E7_PER_RAD;
        let dlon_e7 = wrap_lon(i64::from(p.lon_e7) - i64::from(self.lon_e7));
        let dlon = dlon_e7 as f64 / E7_PER_RAD;
        let up = f64::from(p.alt_mm) * 1e-3;
        let h = up - f64::from(self.alt_m);
        // The second-order terms are small: two rounds of substitution settle them.
        let (mut north, mut east) = (dlat * (m + up), dlon * (n + up) * c);
        for _ in 0..2 {
            east = dlon * ((n + up) * c - north * s);
            north = dlat * (m + up) + east * east * t / (2.0 * n);
        }
        let local = [north as f32, east as f32, -h as f32];
        local.iter().all(|v| v.is_finite()).then_some(local)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    /// PX4's simulation home, the parameters' default.
    const ZURICH: GeoOrigin = GeoOrigin {
        lat_e7: 473_977_420,
        lon_e7: 85_455_940,
        alt_m: 488.0,
    };

    /// The exact conversion, for reference: the local point through earth-centred,
    /// earth-fixed coordinates to geodetic ones (Bowring's start, iterated to convergence).
    /// Degrees, degrees, m.
    fn exact(origin: &GeoOrigin, [n, e, d]: [f64; 3]) -> (f64, f64, f64) {
        let rad = core::f64::consts::PI / 180.0;
        let (lat0, lon0) = (
            f64::from(origin.lat_e7) * 1e-7 * rad,
            f64::from(origin.lon_e7) * 1e-7 * rad,
        );
        let h0 = f64::from(origin.alt_m);
        let (sl, cl, so, co) = (lat0.sin(), lat0.cos(), lon0.sin(), lon0.cos());
        let nn = WGS84_A / (1.0 - WGS84_E2 * sl * sl).sqrt();
        let base = [
            (nn + h0) * cl * co,
            (nn + h0) * cl * so,
            (nn * (1.0 - WGS84_E2) + h0) * sl,
        ];
        let north = [-sl * co, -sl * so, cl];
        let east = [-so, co, 0.0];
        let down = [-cl * co, -cl * so, -sl];
        let p: Vec<f64> = (0..3)
            .map(|i| base[i] + n * north[i] + e * east[i] + d * down[i])
            .collect();
        let lon = p[1].atan2(p[0]);
        let rho = (p[0] * p[0] + p[1] * p[1]).sqrt();
        let mut lat = p[2].atan2(rho * (1.0 - WGS84_E2));
        let mut h = 0.0;
        for _ in 0..10 {
            let nl = WGS84_A / (1.0 - WGS84_E2 * lat.sin() * lat.sin()).sqrt();
            h = rho / lat.cos() - nl;
            lat = p[2].atan2(rho * (1.0 - WGS84_E2 * nl / (nl + h)));
        }
        (lat / rad, lon / rad, h)
    }

    /// Distance on the ground between the conversion's point and the exact one, m.
    fn miss(origin: &GeoOrigin, ned: [f32; 3]) -> f64 {
        let got = origin.to_global(ned).expect("a usable origin");
        let (lat, lon, _) = exact(origin, ned.map(f64::from));
        let rad = core::f64::consts::PI / 180.0;
        let dn = (f64::from(got.lat_e7) * 1e-7 - lat) * rad * 6_371_000.0;
        let de = (f64::from(got.lon_e7) * 1e-7 - lon) * rad * 6_371_000.0 * (lat * rad).cos();
        (dn * dn + de * de).sqrt()
    }

    #[test]
    fn a_kilometre_north_or_east_lands_within_a_centimetre_of_the_exact_point() {
        // 1e-7 degrees of latitude is 1.1 cm: the steps themselves.
        for origin in [
            ZURICH,
            GeoOrigin {
                lat_e7: -338_688_000,
                lon_e7: 1_512_093_000,
                alt_m: 20.0,
            },
            GeoOrigin {
                lat_e7: 0,
                lon_e7: 0,
                alt_m: 0.0,
            },
            GeoOrigin {
                lat_e7: 840_000_000,
                lon_e7: -1_700_000_000,
                alt_m: 0.0,
            },
        ] {
            for ned in [
                [1000.0, 0.0, 0.0],
                [0.0, 1000.0, 0.0],
                [-1000.0, -1000.0, -50.0],
                [700.0, -700.0, 0.0],
            ] {
                let m = miss(&origin, ned);
                assert!(m < 0.012, "{origin:?} {ned:?}: {m} m off");
            }
            // 10 km: a few centimetres up to 60 degrees; the terms left out grow with
            // tan(lat) (half a metre at 84 degrees).
            let m = miss(&origin, [7000.0, 7000.0, 0.0]);
            let within = if origin.lat_e7.abs() <= 600_000_000 {
                0.05
            } else {
                0.6
            };
            std::println!("{} at 10 km: {m:.4} m", origin.lat_e7);
            assert!(m < within, "{origin:?} at 10 km: {m} m off");
        }
    }

    #[test]
    fn a_point_east_follows_the_plane_not_the_parallel() {
        // At 47 degrees a point 1 km east in the plane is 8 cm south of the origin's parallel.
        let p = ZURICH.to_global([0.0, 1000.0, 0.0]).expect("usable");
        let south_m = f64::from(ZURICH.lat_e7 - p.lat_e7) * 1e-7 * 111_200.0;
        assert!((0.06..0.11).contains(&south_m), "{south_m} m");
        assert_eq!(ZURICH.to_global([0.0; 3]), Some(ZURICH.point()));
        let up = ZURICH.to_global([0.0, 0.0, -2.5]).expect("usable");
        assert_eq!(up.alt_mm, 490_500);
    }

    #[test]
    fn local_points_go_round_trip_within_a_centimetre() {
        for origin in [
            ZURICH,
            GeoOrigin::from_message(-1, 1_799_999_999, 0).expect("ok"),
        ] {
            for ned in [
                [0.0, 0.0, 0.0],
                [3.25, -1.5, -0.75],
                [1000.0, 1000.0, -100.0],
                [-4000.0, 2500.0, 10.0],
            ] {
                let p = origin.to_global(ned).expect("usable");
                let back = origin.to_local(&p).expect("usable");
                for k in 0..3 {
                    assert!(
                        (back[k] - ned[k]).abs() < 0.012,
                        "{ned:?} came back {back:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn the_antimeridian_wraps_and_the_poles_are_refused() {
        let date_line = GeoOrigin::from_message(0, 1_799_999_000, 0).expect("usable");
        let p = date_line.to_global([0.0, 1000.0, 0.0]).expect("usable");
        assert!(p.lon_e7 < -1_799_900_000, "{p:?}");
        assert!(
            date_line
                .to_local(&p)
                .is_some_and(|l| (l[1] - 1000.0).abs() < 0.02)
        );
        assert_eq!(
            GeoOrigin::from_message(850_000_001, 0, 0),
            Err(OriginError::Latitude)
        );
        assert_eq!(
            GeoOrigin::from_message(-900_000_000, 0, 0),
            Err(OriginError::Latitude)
        );
        assert_eq!(
            GeoOrigin::from_message(0, 1_800_000_001, 0),
            Err(OriginError::Longitude)
        );
        assert_eq!(
            GeoOrigin::from_message(0, 0, 20_000_000),
            Err(OriginError::Altitude)
        );
        assert!(GeoOrigin::from_message(MAX_LAT_E7, 0, 0).is_ok());
        let polar = GeoOrigin {
            lat_e7: 890_000_000,
            ..ZURICH
        };
        assert_eq!(polar.to_global([0.0; 3]), None);
        assert_eq!(polar.to_local(&ZURICH.point()), None);
        // Thousands of kilometres north: past the pole.
        assert_eq!(ZURICH.to_global([6.0e6, 0.0, 0.0]), None);
    }

    #[test]
    fn not_a_number_has_no_global_position() {
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            assert_eq!(ZURICH.to_global([bad, 0.0, 0.0]), None);
            assert_eq!(ZURICH.to_global([0.0, 0.0, bad]), None);
        }
        let nan_alt = GeoOrigin {
            alt_m: f32::NAN,
            ..ZURICH
        };
        assert_eq!(nan_alt.check(), Err(OriginError::Altitude));
        assert_eq!(nan_alt.to_global([0.0; 3]), None);
    }

    #[test]
    fn the_parameters_hold_an_origin_exactly() {
        assert_eq!(GeoOrigin::from_params(&ParamValues::DEFAULT), ZURICH);
        for origin in [
            ZURICH,
            GeoOrigin::from_message(-338_688_123, -1_512_093_987, -12_345).expect("usable"),
            GeoOrigin::from_message(-5, 1_800_000_000, 0).expect("usable"),
        ] {
            let mut values = ParamValues::DEFAULT;
            for (k, v) in origin.to_params().into_iter().enumerate() {
                values.set(ORIGIN + k, v).expect("in range");
            }
            let back = GeoOrigin::from_params(&values);
            assert_eq!(back.lat_e7, origin.lat_e7);
            // 180 degrees east is 180 west.
            assert_eq!(
                wrap_lon(i64::from(back.lon_e7)),
                wrap_lon(i64::from(origin.lon_e7))
            );
            assert_eq!(back.alt_m, origin.alt_m);
        }
    }
}
