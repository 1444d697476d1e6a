//! What goes through the map origin (docs/ground-link.md#the-map-origin): the position as
//! `GLOBAL_POSITION_INT`, the take-off point ([`Home`], `HOME_POSITION`) and the origin itself
//! (`GPS_GLOBAL_ORIGIN`).

use super::VehicleSnapshot;
use crate::geo::GeoOrigin;
use crate::msg::{GLOBAL_POSITION_INT_DATA, GPS_GLOBAL_ORIGIN_DATA, HOME_POSITION_DATA};

/// A velocity, m/s, in MAVLink's cm/s, saturating (not a number: 0).
fn centimetres(v: f32) -> i16 {
    // `as` saturates and takes NaN to 0.
    (v * 100.0) as i16
}

impl VehicleSnapshot {
    /// `GLOBAL_POSITION_INT`: the position through the map `origin` (latitude, longitude,
    /// altitude above mean sea level; `relative_alt` the height above the origin, `-z`), the
    /// velocity in cm/s and the heading (yaw) in centidegrees. `None` when the origin is
    /// unusable or the position not finite ([`GeoOrigin::to_global`]).
    pub fn global_position_int(&self, origin: &GeoOrigin) -> Option<GLOBAL_POSITION_INT_DATA> {
        let p = origin.to_global(self.position)?;
        let [w, x, y, z] = self.attitude;
        let yaw = shared::math::atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z));
        let degrees = yaw.to_degrees();
        let heading = if degrees < 0.0 {
            degrees + 360.0
        } else {
            degrees
        };
        // Not a number, or a rounding to 360 degrees: unknown, as MAVLink marks it.
        let hdg = match (heading * 100.0 + 0.5) as u16 {
            h if h < 36_000 && heading.is_finite() => h,
            36_000 => 0,
            _ => u16::MAX,
        };
        Some(GLOBAL_POSITION_INT_DATA {
            time_boot_ms: self.time_boot_ms(),
            lat: p.lat_e7,
            lon: p.lon_e7,
            alt: p.alt_mm,
            relative_alt: (-self.position[2] * 1000.0) as i32,
            vx: centimetres(self.velocity[0]),
            vy: centimetres(self.velocity[1]),
            vz: centimetres(self.velocity[2]),
            hdg,
        })
    }
}

/// The take-off point: the local position (NED) where the vehicle last armed; before any
/// flight, the origin itself.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Home {
    /// Where, m, NED from the origin.
    position: [f32; 3],
    /// The vehicle was armed at the last look.
    armed: bool,
}

impl Default for Home {
    fn default() -> Self {
        Self::START
    }
}

impl Home {
    /// Before any flight: the origin.
    pub const START: Self = Self {
        position: [0.0; 3],
        armed: false,
    };

    /// Looks at the vehicle's state: when it has armed since the last look, its position (if
    /// finite) is the new home. `true` when the home moved.
    pub fn observe(&mut self, vehicle: &VehicleSnapshot) -> bool {
        let armed_now = vehicle.armed && !self.armed;
        self.armed = vehicle.armed;
        if armed_now && vehicle.position.iter().all(|v| v.is_finite()) {
            let moved = self.position != vehicle.position;
            self.position = vehicle.position;
            return moved;
        }
        false
    }

    /// The home's local position, m, NED from the origin.
    pub fn position(&self) -> [f32; 3] {
        self.position
    }

    /// `HOME_POSITION` through the map `origin` (the local position too, the approach
    /// vector zero, the attitude level); `None` when the origin is unusable.
    pub fn home_position(&self, origin: &GeoOrigin) -> Option<HOME_POSITION_DATA> {
        let p = origin.to_global(self.position)?;
        let [x, y, z] = self.position;
        Some(HOME_POSITION_DATA {
            latitude: p.lat_e7,
            longitude: p.lon_e7,
            altitude: p.alt_mm,
            x,
            y,
            z,
            q: [1.0, 0.0, 0.0, 0.0],
            ..Default::default()
        })
    }
}

/// `GPS_GLOBAL_ORIGIN`: the map origin (altitude above mean sea level, mm).
pub fn gps_global_origin(origin: &GeoOrigin) -> GPS_GLOBAL_ORIGIN_DATA {
    let p = origin.point();
    GPS_GLOBAL_ORIGIN_DATA {
        latitude: p.lat_e7,
        longitude: p.lon_e7,
        altitude: p.alt_mm,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// PX4's simulation home, the parameters' default.
    const ORIGIN: GeoOrigin = GeoOrigin {
        lat_e7: 473_977_420,
        lon_e7: 85_455_940,
        alt_m: 488.0,
    };

    #[test]
    fn the_global_position_is_the_local_one_through_the_origin() {
        // Yawed 90 degrees (east), 2 m up, 10 m north and 5 m east of the origin.
        let half = core::f32::consts::FRAC_1_SQRT_2;
        let snap = VehicleSnapshot {
            time_us: 3_000_000,
            attitude: [half, 0.0, 0.0, half],
            position: [10.0, 5.0, -2.0],
            velocity: [1.5, -0.25, 400.0],
            ..VehicleSnapshot::START
        };
        let g = snap.global_position_int(&ORIGIN).expect("a usable origin");
        let p = ORIGIN.to_global(snap.position).expect("usable");
        assert_eq!((g.lat, g.lon, g.alt), (p.lat_e7, p.lon_e7, p.alt_mm));
        // 10 m north is 899 1e-7 degrees at 47 degrees; 5 m east 662.
        assert_eq!((g.lat - ORIGIN.lat_e7, g.lon - ORIGIN.lon_e7), (899, 662));
        assert_eq!((g.alt, g.relative_alt), (490_000, 2_000));
        assert_eq!((g.vx, g.vy, g.vz), (150, -25, i16::MAX));
        assert_eq!((g.hdg, g.time_boot_ms), (9_000, 3_000));
        let west = VehicleSnapshot {
            attitude: [half, 0.0, 0.0, -half],
            ..snap
        };
        assert_eq!(
            west.global_position_int(&ORIGIN).map(|g| g.hdg),
            Some(27_000)
        );
        let broken = VehicleSnapshot {
            attitude: [f32::NAN; 4],
            velocity: [f32::NAN; 3],
            ..snap
        };
        let g = broken
            .global_position_int(&ORIGIN)
            .expect("the position holds");
        assert_eq!((g.hdg, g.vx), (u16::MAX, 0));
        let lost = VehicleSnapshot {
            position: [f32::NAN, 0.0, 0.0],
            ..snap
        };
        assert_eq!(lost.global_position_int(&ORIGIN), None);
        let polar = GeoOrigin {
            lat_e7: 890_000_000,
            ..ORIGIN
        };
        assert_eq!(snap.global_position_int(&polar), None);
    }

    #[test]
    fn home_is_where_the_vehicle_armed_and_the_origin_before() {
        let mut home = Home::START;
        let h = home.home_position(&ORIGIN).expect("usable");
        assert_eq!(
            (h.latitude, h.longitude, h.altitude),
            (473_977_420, 85_455_940, 488_000)
        );
        assert_eq!(h.q, [1.0, 0.0, 0.0, 0.0]);
        let ground = VehicleSnapshot {
            position: [1.0, -2.0, 0.0],
            ..VehicleSnapshot::START
        };
        assert!(!home.observe(&ground), "not armed: no home");
        let armed = VehicleSnapshot {
            armed: true,
            ..ground
        };
        assert!(home.observe(&armed));
        let flying = VehicleSnapshot {
            position: [5.0, 5.0, -3.0],
            ..armed
        };
        assert!(!home.observe(&flying), "only at arming");
        assert_eq!(home.position(), [1.0, -2.0, 0.0]);
        let h = home.home_position(&ORIGIN).expect("usable");
        assert_eq!((h.x, h.y, h.z), (1.0, -2.0, 0.0));
        assert_eq!(
            Some((h.latitude, h.longitude)),
            ORIGIN
                .to_global([1.0, -2.0, 0.0])
                .map(|p| (p.lat_e7, p.lon_e7))
        );
        // Landed, disarmed, armed again elsewhere: the new take-off point.
        assert!(!home.observe(&VehicleSnapshot {
            armed: false,
            ..flying
        }));
        assert!(home.observe(&flying));
        assert_eq!(home.position(), [5.0, 5.0, -3.0]);
        let o = gps_global_origin(&ORIGIN);
        assert_eq!(
            (o.latitude, o.longitude, o.altitude),
            (473_977_420, 85_455_940, 488_000)
        );
    }
}
