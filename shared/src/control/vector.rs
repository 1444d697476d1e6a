//! Three-vectors and unit quaternions for attitude (docs/models.md#conventions), on the
//! crate's `libm` math so host and target rotate identically.
//!
//! Conventions: body frame FRD (x forward, y right, z down), world frame NED; Hamilton
//! quaternions `q = (w, x, y, z)` rotating body vectors into the world (`v_w = q v_b q*`).

use core::ops::{Add, AddAssign, Mul, Neg, Sub};

use crate::math;

/// A 3-vector.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Vec3 {
    /// x.
    pub x: f32,
    /// y.
    pub y: f32,
    /// z.
    pub z: f32,
}

impl Vec3 {
    /// The zero vector.
    pub const ZERO: Self = Self::new(0.0, 0.0, 0.0);
    /// World down (NED z).
    pub const DOWN: Self = Self::new(0.0, 0.0, 1.0);

    /// A vector from components.
    pub const fn new(x: f32, y: f32, z: f32) -> Self {
        Self { x, y, z }
    }

    /// From an array.
    pub const fn from_array(a: [f32; 3]) -> Self {
        Self::new(a[0], a[1], a[2])
    }

    /// As an array.
    pub const fn to_array(self) -> [f32; 3] {
        [self.x, self.y, self.z]
    }

    /// Dot product.
    pub fn dot(self, o: Self) -> f32 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// Cross product.
    pub fn cross(self, o: Self) -> Self {
        Self::new(
            self.y * o.z - self.z * o.y,
            self.z * o.x - self.x * o.z,
            self.x * o.y - self.y * o.x,
        )
    }

    /// Euclidean length.
    pub fn norm(self) -> f32 {
        math::sqrt(self.dot(self))
    }

    /// This vector scaled to unit length (zero stays zero).
    pub fn normalized(self) -> Self {
        let n = self.norm();
        if n > 0.0 { self * (1.0 / n) } else { self }
    }

    /// Component-wise product.
    pub fn component_mul(self, o: Self) -> Self {
        Self::new(self.x * o.x, self.y * o.y, self.z * o.z)
    }

    /// Every component `v`.
    pub const fn splat(v: f32) -> Self {
        Self::new(v, v, v)
    }

    /// Component-wise least of the two.
    pub fn min(self, o: Self) -> Self {
        Self::new(
            math::min(self.x, o.x),
            math::min(self.y, o.y),
            math::min(self.z, o.z),
        )
    }

    /// Component-wise greatest of the two.
    pub fn max(self, o: Self) -> Self {
        Self::new(
            math::max(self.x, o.x),
            math::max(self.y, o.y),
            math::max(self.z, o.z),
        )
    }

    /// Each component clamped to `[-limit, limit]`.
    pub fn clamp_each(self, limit: Self) -> Self {
        Self::new(
            math::clamp(self.x, -limit.x, limit.x),
            math::clamp(self.y, -limit.y, limit.y),
            math::clamp(self.z, -limit.z, limit.z),
        )
    }

    /// The vector shortened to at most `limit` long.
    pub fn limit_norm(self, limit: f32) -> Self {
        let n = self.norm();
        if n > limit && n > 0.0 {
            self * (limit / n)
        } else {
            self
        }
    }

    /// True when all components are finite.
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.z.is_finite()
    }
}

impl Add for Vec3 {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}

impl AddAssign for Vec3 {
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}

impl Sub for Vec3 {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Self::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}

impl Mul<f32> for Vec3 {
    type Output = Self;
    fn mul(self, k: f32) -> Self {
        Self::new(self.x * k, self.y * k, self.z * k)
    }
}

impl Neg for Vec3 {
    type Output = Self;
    fn neg(self) -> Self {
        Self::new(-self.x, -self.y, -self.z)
    }
}

/// A unit quaternion (Hamilton, scalar first): the attitude of the body in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quat {
    /// Scalar part.
    pub w: f32,
    /// x.
    pub x: f32,
    /// y.
    pub y: f32,
    /// z.
    pub z: f32,
}

impl Default for Quat {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Mul for Quat {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        Self {
            w: self.w * o.w - self.x * o.x - self.y * o.y - self.z * o.z,
            x: self.w * o.x + self.x * o.w + self.y * o.z - self.z * o.y,
            y: self.w * o.y - self.x * o.z + self.y * o.w + self.z * o.x,
            z: self.w * o.z + self.x * o.y - self.y * o.x + self.z * o.w,
        }
    }
}

impl Quat {
    /// No rotation.
    pub const IDENTITY: Self = Self {
        w: 1.0,
        x: 0.0,
        y: 0.0,
        z: 0.0,
    };

    /// The vector part.
    pub fn vector(self) -> Vec3 {
        Vec3::new(self.x, self.y, self.z)
    }

    /// The inverse rotation.
    pub fn conjugate(self) -> Self {
        Self {
            w: self.w,
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }

    /// Scaled back to unit length (identity if degenerate).
    pub fn normalized(self) -> Self {
        let n = math::sqrt(self.w * self.w + self.x * self.x + self.y * self.y + self.z * self.z);
        if n > 1e-9 && n.is_finite() {
            Self {
                w: self.w / n,
                x: self.x / n,
                y: self.y / n,
                z: self.z / n,
            }
        } else {
            Self::IDENTITY
        }
    }

    /// Rotation by `angle` radians about unit `axis`.
    pub fn from_axis_angle(axis: Vec3, angle: f32) -> Self {
        let (s, c) = (math::sin(0.5 * angle), math::cos(0.5 * angle));
        let a = axis.normalized();
        Self {
            w: c,
            x: a.x * s,
            y: a.y * s,
            z: a.z * s,
        }
    }

    /// The rotation vector `theta` (axis times angle) as a quaternion: integrates a rate over
    /// one step. Below 0.2 rad (every step of the 400 Hz loop) the half-angle sine and cosine
    /// come from their Taylor series, exact to `f32` there and far cheaper on the target than
    /// `libm`'s `sinf`, which works in software double precision.
    pub fn from_rotation_vector(theta: Vec3) -> Self {
        let angle = theta.norm();
        if angle < 0.2 {
            let h2 = 0.25 * angle * angle; // (angle / 2)^2
            let cos_half = 1.0 - h2 / 2.0 + h2 * h2 / 24.0 - h2 * h2 * h2 / 720.0;
            // sin(angle / 2) / angle
            let sin_half_over_angle =
                0.5 * (1.0 - h2 / 6.0 + h2 * h2 / 120.0 - h2 * h2 * h2 / 5040.0);
            Self {
                w: cos_half,
                x: theta.x * sin_half_over_angle,
                y: theta.y * sin_half_over_angle,
                z: theta.z * sin_half_over_angle,
            }
            .normalized()
        } else {
            Self::from_axis_angle(theta, angle)
        }
    }

    /// From roll, pitch, yaw (radians, Z-Y-X intrinsic: yaw, then pitch, then roll).
    pub fn from_euler(roll: f32, pitch: f32, yaw: f32) -> Self {
        let (sr, cr) = (math::sin(0.5 * roll), math::cos(0.5 * roll));
        let (sp, cp) = (math::sin(0.5 * pitch), math::cos(0.5 * pitch));
        let (sy, cy) = (math::sin(0.5 * yaw), math::cos(0.5 * yaw));
        Self {
            w: cr * cp * cy + sr * sp * sy,
            x: sr * cp * cy - cr * sp * sy,
            y: cr * sp * cy + sr * cp * sy,
            z: cr * cp * sy - sr * sp * cy,
        }
    }

    /// Roll, pitch, yaw (radians, Z-Y-X).
    pub fn to_euler(self) -> Vec3 {
        let roll = math::atan2(
            2.0 * (self.w * self.x + self.y * self.z),
            1.0 - 2.0 * (self.x * self.x + self.y * self.y),
        );
        let sin_pitch = math::clamp(2.0 * (self.w * self.y - self.z * self.x), -1.0, 1.0);
        let pitch = math::asin(sin_pitch);
        let yaw = math::atan2(
            2.0 * (self.w * self.z + self.x * self.y),
            1.0 - 2.0 * (self.y * self.y + self.z * self.z),
        );
        Vec3::new(roll, pitch, yaw)
    }

    /// Rotates body vector `v` into the world.
    pub fn rotate(self, v: Vec3) -> Vec3 {
        let u = self.vector();
        let t = u.cross(v) * 2.0;
        v + t * self.w + u.cross(t)
    }

    /// Rotates world vector `v` into the body.
    pub fn inverse_rotate(self, v: Vec3) -> Vec3 {
        self.conjugate().rotate(v)
    }

    /// The shortest rotation taking unit vector `from` onto unit vector `to`.
    pub fn between(from: Vec3, to: Vec3) -> Self {
        let d = from.dot(to);
        let c = from.cross(to);
        if d < -0.999_999 {
            // Opposite: turn half a turn about any axis normal to `from`.
            let axis = if from.x.abs() < 0.9 {
                from.cross(Vec3::new(1.0, 0.0, 0.0))
            } else {
                from.cross(Vec3::new(0.0, 1.0, 0.0))
            };
            return Self::from_axis_angle(axis, core::f32::consts::PI);
        }
        Self {
            w: 1.0 + d,
            x: c.x,
            y: c.y,
            z: c.z,
        }
        .normalized()
    }

    /// The rotation whose body axes x, y, z point along the given orthonormal world vectors.
    pub fn from_axes(x: Vec3, y: Vec3, z: Vec3) -> Self {
        // Columns of the rotation matrix are x, y, z (Shepperd's method).
        let (m00, m11, m22) = (x.x, y.y, z.z);
        let trace = m00 + m11 + m22;
        let q = if trace > 0.0 {
            let s = 2.0 * math::sqrt(1.0 + trace);
            Self {
                w: 0.25 * s,
                x: (y.z - z.y) / s,
                y: (z.x - x.z) / s,
                z: (x.y - y.x) / s,
            }
        } else if m00 > m11 && m00 > m22 {
            let s = 2.0 * math::sqrt(1.0 + m00 - m11 - m22);
            Self {
                w: (y.z - z.y) / s,
                x: 0.25 * s,
                y: (y.x + x.y) / s,
                z: (z.x + x.z) / s,
            }
        } else if m11 > m22 {
            let s = 2.0 * math::sqrt(1.0 + m11 - m00 - m22);
            Self {
                w: (z.x - x.z) / s,
                x: (y.x + x.y) / s,
                y: 0.25 * s,
                z: (z.y + y.z) / s,
            }
        } else {
            let s = 2.0 * math::sqrt(1.0 + m22 - m00 - m11);
            Self {
                w: (x.y - y.x) / s,
                x: (z.x + x.z) / s,
                y: (z.y + y.z) / s,
                z: 0.25 * s,
            }
        };
        q.normalized()
    }

    /// True when all components are finite.
    pub fn is_finite(self) -> bool {
        self.w.is_finite() && self.vector().is_finite()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn euler_round_trip_and_rotation_agree() {
        let q = Quat::from_euler(0.3, -0.2, 1.1);
        let e = q.to_euler();
        assert!((e - Vec3::new(0.3, -0.2, 1.1)).norm() < 1e-5, "{e:?}");
        // Body forward of a vehicle yawed by 90 degrees points east (world y).
        let yawed = Quat::from_euler(0.0, 0.0, core::f32::consts::FRAC_PI_2);
        let fwd = yawed.rotate(Vec3::new(1.0, 0.0, 0.0));
        assert!((fwd - Vec3::new(0.0, 1.0, 0.0)).norm() < 1e-6);
        let back = yawed.inverse_rotate(fwd);
        assert!((back - Vec3::new(1.0, 0.0, 0.0)).norm() < 1e-6);
    }

    #[test]
    fn rotation_vector_series_matches_the_exact_form() {
        for angle in [0.0f32, 1e-6, 0.01, 0.1, 0.199, 0.2, 0.5] {
            let theta = Vec3::new(0.6, -0.48, 0.64) * angle; // unit axis times angle
            let q = Quat::from_rotation_vector(theta);
            let exact = Quat::from_axis_angle(Vec3::new(0.6, -0.48, 0.64), angle);
            let d = (q.w - exact.w).abs() + (q.vector() - exact.vector()).norm();
            assert!(d < 2e-7, "angle {angle}: {q:?} vs {exact:?}");
        }
    }

    #[test]
    fn from_axes_recovers_the_rotation() {
        let q = Quat::from_euler(0.4, -0.3, 2.5);
        let axes = [
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
        ];
        let [x, y, z] = axes.map(|a| q.rotate(a));
        let back = Quat::from_axes(x, y, z);
        assert!((back.to_euler() - q.to_euler()).norm() < 1e-5);
    }

    #[test]
    fn between_takes_one_vector_onto_the_other() {
        let a = Vec3::new(0.2, -0.3, 1.0).normalized();
        let b = Vec3::new(-0.5, 0.1, 0.8).normalized();
        let q = Quat::between(a, b);
        assert!((q.rotate(a) - b).norm() < 1e-5);
        let opposite = Quat::between(a, -a);
        assert!((opposite.rotate(a) + a).norm() < 1e-5);
    }
}
