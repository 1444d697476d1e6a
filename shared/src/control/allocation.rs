//! Control allocation: from the commanded wrench (collective thrust, roll, pitch, yaw torque)
//! to one thrust per rotor (docs/models.md#allocation-and-mixer;
//! the mixer is rebuilt from the robots' positions).
//!
//! Rotor `i` at `r_i = (x_i, y_i)` from the estimated COM (body FRD), spin `s_i`, thrust `T_i`
//! upwards produces roll torque `-y_i T_i`, pitch torque `x_i T_i` and yaw torque
//! `s_i c_q T_i`. The effectiveness matrix `A` (4 x n) stacks `[1; -y_i; x_i; s_i c_q]`.
//!
//! Two mixers, built whenever the formation changes (never in the control step):
//! - [`MixerKind::EqualSplit`], the paper's: the collective thrust split equally, the torques
//!   through `B^+ = B^T (B B^T)^-1` of the torque rows `B` of `A`.
//! - [`MixerKind::Allocation`]: the pseudo-inverse `A^T (A A^T)^-1` of the whole matrix, so each
//!   rotor carries its own trim when the COM is off the robots' centroid.
//!
//! Saturation: thrusts stay within `[0, max_thrust]`. Roll, pitch and collective are fitted
//! first (the collective moves along its own column to make room; roll and pitch are scaled
//! down only if that is not enough), and yaw gets what room is left, so yaw is given up first.
//! The caller is told which axes were cut.

use nalgebra::SMatrix;

use crate::control::vector::Vec3;
use crate::geometry::Vec2;
use crate::math;
use crate::scenario::MAX_ROBOTS;

/// Which mixer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MixerKind {
    /// The paper's mixer: equal collective split, torques through `B^+`.
    EqualSplit,
    /// Pseudo-inverse of the full effectiveness matrix.
    Allocation,
}

/// Collective thrust and body torque.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Wrench {
    /// Collective thrust, upwards, N.
    pub thrust: f32,
    /// Body torque (roll, pitch, yaw), N m.
    pub torque: Vec3,
}

/// Which parts of a wrench the rotors could not deliver.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Saturation {
    /// The collective thrust was moved to make room.
    pub collective: bool,
    /// Roll and pitch torque were cut.
    pub roll_pitch: bool,
    /// Yaw torque was cut.
    pub yaw: bool,
}

impl Saturation {
    /// True when anything was cut.
    pub fn any(&self) -> bool {
        self.collective || self.roll_pitch || self.yaw
    }
}

/// One allocation's result.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Allocation {
    /// Thrust of each rotor, N (the first `count` entries are used).
    pub thrusts: [f32; MAX_ROBOTS],
    /// Rotors.
    pub count: usize,
    /// The wrench those thrusts produce.
    pub achieved: Wrench,
    /// What was cut.
    pub saturation: Saturation,
}

/// The rotors as the mixer needs them.
#[derive(Clone, Copy, Debug)]
pub struct RotorLayout<'a> {
    /// Rotor points, body frame, m.
    pub points: &'a [Vec2],
    /// Spin of each rotor (+1 or -1).
    pub spin: &'a [i8],
    /// Estimated COM: the origin of the torques.
    pub com: Vec2,
    /// `c_q / c_t`, m.
    pub torque_per_thrust: f32,
    /// Largest thrust of one rotor, N.
    pub max_thrust: f32,
}

/// Why a mixer cannot be built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AllocationError {
    /// No rotors, more than [`MAX_ROBOTS`], or spins not matching the rotors.
    BadLayout,
    /// The rotors cannot produce every axis of the wrench (for example all on one line).
    Uncontrollable,
}

impl core::fmt::Display for AllocationError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::BadLayout => write!(f, "rotor layout needs 1 to 16 rotors with a spin each"),
            Self::Uncontrollable => write!(
                f,
                "the rotors cannot produce every axis of roll, pitch, yaw and thrust"
            ),
        }
    }
}

impl core::error::Error for AllocationError {}

type Effectiveness = SMatrix<f32, 4, MAX_ROBOTS>;
/// Thrust, roll and pitch rows of an effectiveness matrix.
type Rows3 = SMatrix<f32, 3, MAX_ROBOTS>;
/// A mixing matrix with `R` axes, one column per axis and one thrust per rotor in each
/// (zeros past the rotors in use): the layout [`Mixer`] keeps.
type MixColumns<const R: usize> = [[f32; MAX_ROBOTS]; R];

/// Whether `product` (effectiveness times mixing) is the identity: a nearly singular
/// `A A^T` inverts to garbage in f32, and the mixing must reproduce each axis it claims.
fn reproduces<const R: usize>(product: &[[f32; R]; R]) -> bool {
    product.iter().enumerate().all(|(r, row)| {
        row.iter().enumerate().all(|(c, &v)| {
            let want = if r == c { 1.0 } else { 0.0 };
            (v - want).abs() <= 1e-3
        })
    })
}

/// The first `count` columns of `a`, each as an array, borrowed from its storage (nalgebra
/// stores a matrix column after column).
fn used_columns<const R: usize>(a: &SMatrix<f32, R, MAX_ROBOTS>, count: usize) -> &[[f32; R]] {
    &a.data.0[..count.min(MAX_ROBOTS)]
}

/// The right pseudo-inverse `a^T (a a^T)^-1` of `a`'s first `count` columns (the rest of
/// `a` is zero, and so are the result's rotors past `count`), as one column per row of `a`,
/// or `None` when `a a^T` is not positive definite (the rows are not independent).
/// `a a^T` (only its lower triangle summed) `= L D L^T` (`L` unit lower triangular), and each
/// rotor's row of the result solves `L D L^T m_i = a_i` for its column `a_i`, multiplying by
/// the pivots' reciprocals: products over the rotors in use only and no explicit inverse (a
/// rebuild is a job; this is most of its cost).
fn pseudo_inverse<const R: usize>(
    a: &SMatrix<f32, R, MAX_ROBOTS>,
    count: usize,
) -> Option<MixColumns<R>> {
    let columns = used_columns(a, count);
    let mut gram = [[0.0f32; R]; R];
    for col in columns {
        for r in 0..R {
            for c in 0..=r {
                gram[r][c] += col[r] * col[c];
            }
        }
    }
    let mut l = [[0.0f32; R]; R];
    let mut d = [0.0f32; R];
    let mut inv_d = [0.0f32; R];
    for j in 0..R {
        let mut dj = gram[j][j];
        for k in 0..j {
            dj -= l[j][k] * l[j][k] * d[k];
        }
        if !(dj > 0.0 && dj.is_finite()) {
            return None;
        }
        d[j] = dj;
        inv_d[j] = 1.0 / dj;
        for i in j + 1..R {
            let mut v = gram[i][j];
            for k in 0..j {
                v -= l[i][k] * l[j][k] * d[k];
            }
            l[i][j] = v * inv_d[j];
        }
    }
    let mut out = [[0.0f32; MAX_ROBOTS]; R];
    for (i, col) in columns.iter().enumerate() {
        // L y = a_i, D z = y, L^T x = z.
        let mut y = *col;
        for r in 0..R {
            for k in 0..r {
                y[r] -= l[r][k] * y[k];
            }
        }
        for r in 0..R {
            y[r] *= inv_d[r];
        }
        for r in (0..R).rev() {
            for k in r + 1..R {
                y[r] -= l[k][r] * y[k];
            }
        }
        for (axis, &v) in out.iter_mut().zip(&y) {
            axis[i] = v;
        }
    }
    Some(out)
}

/// Whether every thrust of mixing `m` for its first `count` rotors is finite.
fn all_finite<const R: usize>(m: &MixColumns<R>, count: usize) -> bool {
    m.iter()
        .all(|axis| axis[..count.min(MAX_ROBOTS)].iter().all(|v| v.is_finite()))
}

/// `a m` over the first `count` rotors.
fn product<const R: usize>(
    a: &SMatrix<f32, R, MAX_ROBOTS>,
    m: &MixColumns<R>,
    count: usize,
) -> [[f32; R]; R] {
    let mut p = [[0.0f32; R]; R];
    for (i, col) in used_columns(a, count).iter().enumerate() {
        for c in 0..R {
            let share = m[c][i];
            for r in 0..R {
                p[r][c] += col[r] * share;
            }
        }
    }
    p
}

/// The inverse of `k` by cofactors, or `None` when `k` is singular for `f32` (its determinant
/// below 1e-6 of the product of its rows' norms).
fn inverse_3x3(k: &[[f32; 3]; 3]) -> Option<[[f32; 3]; 3]> {
    let cof =
        |r0: usize, r1: usize, c0: usize, c1: usize| k[r0][c0] * k[r1][c1] - k[r0][c1] * k[r1][c0];
    let c = [
        [cof(1, 2, 1, 2), -cof(1, 2, 0, 2), cof(1, 2, 0, 1)],
        [-cof(0, 2, 1, 2), cof(0, 2, 0, 2), -cof(0, 2, 0, 1)],
        [cof(0, 1, 1, 2), -cof(0, 1, 0, 2), cof(0, 1, 0, 1)],
    ];
    let det = k[0][0] * c[0][0] + k[0][1] * c[0][1] + k[0][2] * c[0][2];
    let scale: f32 = k
        .iter()
        .map(|row| math::sqrt(row.iter().map(|v| v * v).sum::<f32>()))
        .product();
    if !det.is_finite() || math::abs(det) <= 1e-6 * scale {
        return None;
    }
    let inv = 1.0 / det;
    // The inverse is the transposed cofactors over the determinant.
    Some([
        [c[0][0] * inv, c[1][0] * inv, c[2][0] * inv],
        [c[0][1] * inv, c[1][1] * inv, c[2][1] * inv],
        [c[0][2] * inv, c[1][2] * inv, c[2][2] * inv],
    ])
}

/// The pseudo-inverse `a^T (a a^T)^-1` of thrust, roll and pitch rows of `count` rotors, if
/// they are independent.
fn right_inverse(a: &Rows3, count: usize) -> Option<MixColumns<3>> {
    let m = pseudo_inverse(a, count)?;
    (all_finite(&m, count) && reproduces(&product(a, &m, count))).then_some(m)
}

/// Smallest share of the hover a flown rotor must carry, as a fraction of the flown rotors'
/// mean share.
const MIN_HOVER_SHARE: f32 = 0.2;

/// The rotors of `count` that can hover: in the least-norm thrusts that make one newton of
/// thrust and no roll or pitch torque, each must carry at least [`MIN_HOVER_SHARE`] of the
/// mean (none negative, and none so close to zero that the allocator could only lift it off
/// zero for a torque by raising the whole collective); the one with the smallest share is left
/// out and the rest solved again. Returns the rows left (the rotors left out with zero
/// columns) and the pseudo-inverse of those rows; `None` when they can no longer produce the
/// three axes.
fn hovering_rotors(a: &Rows3, count: usize) -> Option<(Rows3, MixColumns<3>)> {
    let mut left = *a;
    for _ in 0..count {
        let m = right_inverse(&left, count)?;
        let flown = (0..count).filter(|&i| left[(0, i)] != 0.0).count();
        let least = MIN_HOVER_SHARE / math::max(flown as f32, 1.0);
        let mut worst: Option<(usize, f32)> = None;
        for i in (0..count).filter(|&i| left[(0, i)] != 0.0) {
            let share = m[0][i];
            if share < least && worst.is_none_or(|(_, w)| share < w) {
                worst = Some((i, share));
            }
        }
        match worst {
            None => return Some((left, m)),
            Some((i, _)) => left.column_mut(i).fill(0.0),
        }
    }
    None
}

/// Whether some shift along the collective's column fits thrusts `thrust + scale * tilt`
/// within `[0, max]`, as a function of `scale`, for the search that scales roll and pitch
/// down: each rotor's limits on the shift are lines in `scale`, worked out once
/// ([`Mixer::room`] for one scale).
struct ScaledRoom {
    count: usize,
    /// Rotor by rotor: the shift's lower and upper limits at scale 0, and their slopes.
    lower: [(f32, f32); MAX_ROBOTS],
    upper: [(f32, f32); MAX_ROBOTS],
    /// Rotors the collective does not move: their thrust at scale 0 and its slope.
    unmoved_count: usize,
    unmoved: [(f32, f32); MAX_ROBOTS],
    max_thrust: f32,
}

impl ScaledRoom {
    /// The lines for `mixer`; `None` when no shift fits even at scale 0 (or a rotor the
    /// collective does not move is out of its limits there).
    fn new(
        mixer: &Mixer,
        thrust: &[f32; MAX_ROBOTS],
        tilt: &[f32; MAX_ROBOTS],
        collective: &[f32; MAX_ROBOTS],
    ) -> Option<Self> {
        mixer.room(thrust, collective)?;
        let mut room = Self {
            count: 0,
            lower: [(0.0, 0.0); MAX_ROBOTS],
            upper: [(0.0, 0.0); MAX_ROBOTS],
            unmoved_count: 0,
            unmoved: [(0.0, 0.0); MAX_ROBOTS],
            max_thrust: mixer.max_thrust,
        };
        for i in 0..mixer.count {
            let (t, p, d) = (thrust[i], tilt[i], collective[i]);
            if d.abs() < 1e-9 {
                // A rotor the collective does not move limits the scale alone:
                // `0 <= t + scale p <= max`, checked in `at` as `Mixer::room` checks it.
                room.unmoved[room.unmoved_count] = (t, p);
                room.unmoved_count += 1;
                continue;
            }
            let inv = 1.0 / d;
            // Shift k with 0 <= t + s p + k d <= max: k between (0 - t - s p) / d and
            // (max - t - s p) / d, whichever is lower.
            let (a0, a1) = (-t * inv, (mixer.max_thrust - t) * inv);
            let slope = -p * inv;
            let (low, high) = if inv > 0.0 { (a0, a1) } else { (a1, a0) };
            room.lower[room.count] = (low, slope);
            room.upper[room.count] = (high, slope);
            room.count += 1;
        }
        Some(room)
    }

    /// Whether a shift fits at `scale`.
    fn at(&self, scale: f32) -> bool {
        for &(t, p) in &self.unmoved[..self.unmoved_count] {
            let b = t + scale * p;
            if b < -1e-6 || b > self.max_thrust + 1e-6 {
                return false;
            }
        }
        let (mut lo, mut hi) = (f32::NEG_INFINITY, f32::INFINITY);
        for (&(l0, ls), &(h0, hs)) in self.lower[..self.count].iter().zip(&self.upper) {
            lo = math::max(lo, l0 + scale * ls);
            hi = math::min(hi, h0 + scale * hs);
        }
        lo <= hi
    }
}

/// A mixer for one formation.
#[derive(Clone, Debug, PartialEq)]
pub struct Mixer {
    kind: MixerKind,
    count: usize,
    max_thrust: f32,
    effectiveness: Effectiveness,
    /// Columns of the mixing matrix (collective, roll, pitch, yaw), one thrust per rotor.
    columns: [[f32; MAX_ROBOTS]; 4],
    /// One over the flown rotors' RMS arm, 1/m ([`Self::torque_scale`]).
    torque_scale: Option<f32>,
}

impl Mixer {
    /// Builds the mixer of `kind` for `layout` (a matrix inverse: do it when the formation
    /// changes, not in the control step).
    pub fn build(kind: MixerKind, layout: &RotorLayout<'_>) -> Result<Self, AllocationError> {
        let count = layout.points.len();
        if count == 0 || count > MAX_ROBOTS || layout.spin.len() != count {
            return Err(AllocationError::BadLayout);
        }
        let mut a = Effectiveness::zeros();
        for (i, (&p, &s)) in layout.points.iter().zip(layout.spin).enumerate() {
            let r = p - layout.com;
            a[(0, i)] = 1.0;
            a[(1, i)] = -r.y;
            a[(2, i)] = r.x;
            a[(3, i)] = f32::from(s) * layout.torque_per_thrust;
        }
        Self::from_effectiveness(kind, count, layout.max_thrust, a)
    }

    /// The mixer of `kind` for effectiveness `a` of `count` rotors.
    fn from_effectiveness(
        kind: MixerKind,
        count: usize,
        max_thrust: f32,
        a: Effectiveness,
    ) -> Result<Self, AllocationError> {
        let columns = match kind {
            MixerKind::Allocation => {
                let columns = pseudo_inverse(&a, count).ok_or(AllocationError::Uncontrollable)?;
                // A nearly singular `A A^T` inverts to garbage in f32: the mixing must
                // reproduce each axis it claims (the identity on the rows inverted).
                if !all_finite(&columns, count) || !reproduces(&product(&a, &columns, count)) {
                    return Err(AllocationError::Uncontrollable);
                }
                columns
            }
            MixerKind::EqualSplit => {
                let b: SMatrix<f32, 3, MAX_ROBOTS> = a.fixed_rows::<3>(1).into_owned();
                let [roll, pitch, yaw] =
                    pseudo_inverse(&b, count).ok_or(AllocationError::Uncontrollable)?;
                let mut collective = [0.0f32; MAX_ROBOTS];
                collective[..count].fill(1.0 / count as f32);
                let columns = [collective, roll, pitch, yaw];
                if !all_finite(&columns, count) {
                    return Err(AllocationError::Uncontrollable);
                }
                columns
            }
        };
        Ok(Self {
            kind,
            count,
            max_thrust,
            torque_scale: torque_scale(&a, count),
            effectiveness: a,
            columns,
        })
    }

    /// This mixer's rotors without those in `out` (bit `i` for rotor `i`): their thrust is
    /// forced to zero and the others take the wrench, whatever this mixer's kind (an equal
    /// split over rotors whose centroid is no longer the COM would itself make a torque).
    /// Yaw is given up first:
    /// - thrust, roll and pitch come from the pseudo-inverse of those three rows of the
    ///   remaining columns, without holding yaw: a hover that balanced the two spins as well
    ///   can need a negative thrust on a few rotors, which no rotor makes (the allocator would
    ///   cut the collective to nothing);
    /// - the hover must need no negative thrust: rotors whose least-norm share of it comes out
    ///   negative or near zero are not flown (left out, smallest first, while three remain; if
    ///   no such set is found all are flown, and the payload cannot hover level on them);
    /// - yaw's column is the full pseudo-inverse's over the rotors flown (pure yaw), or none
    ///   when they cannot make yaw apart from the rest ([`Self::flies_yaw`] false).
    ///
    /// `Uncontrollable` if not even thrust, roll and pitch are left (the rotors left on one
    /// line). Matrix inverses: once per rotor lost, not every tick.
    pub fn without(&self, out: u16) -> Result<Self, AllocationError> {
        let count = self.count;
        let mut a = self.effectiveness;
        for i in 0..count {
            if out & (1 << i) != 0 {
                a.column_mut(i).fill(0.0);
            }
        }
        let a3: Rows3 = a.fixed_rows::<3>(0).into_owned();
        let plain = right_inverse(&a3, count).ok_or(AllocationError::Uncontrollable)?;
        // Fly only the rotors that can share the hover: one held at zero by its column could
        // not go below it for a torque, and the allocator would give up roll and pitch.
        let (flown, m3) = hovering_rotors(&a3, count).unwrap_or((a3, plain));
        let [collective, roll, pitch] = m3;
        let mut columns = [collective, roll, pitch, [0.0f32; MAX_ROBOTS]];
        let mut full = a;
        full.fixed_rows_mut::<3>(0).copy_from(&flown);
        for i in 0..count {
            if flown[(0, i)] == 0.0 {
                full[(3, i)] = 0.0;
            }
        }
        if let Ok(mixer) =
            Self::from_effectiveness(MixerKind::Allocation, count, self.max_thrust, full)
        {
            columns[3] = mixer.columns[3];
        }
        Ok(Self {
            kind: MixerKind::Allocation,
            count,
            max_thrust: self.max_thrust,
            torque_scale: torque_scale(&a, count),
            effectiveness: a,
            columns,
        })
    }

    /// Leaves the rotors `out` out of this mixer, in place, for the ticks between a rotor
    /// found stopped and [`Self::without`]'s answer (a matrix inverse per rotor left out, too
    /// long for the control step: the mission asks for it as a job): the thrust, roll and
    /// pitch columns with the rotors `out` given no share, corrected by one 3 x 3 inverse so
    /// that they make exactly the thrust, roll and pitch asked again (`A' M0 K^-1 = I` with
    /// `K = A' M0`); yaw is not flown for those few ticks. `Uncontrollable`, the mixer left as
    /// it was, when the columns left cannot make the three axes. No copy of the mixer: this
    /// runs in the control step.
    pub fn leave_out(&mut self, out: u16) -> Result<(), AllocationError> {
        let count = self.count.min(MAX_ROBOTS);
        let kept = |i: usize| out & (1 << i) == 0;
        // K = A' M0 over thrust, roll and pitch: what the columns left make.
        let mut k = [[0.0f32; 3]; 3];
        for (i, col) in used_columns(&self.effectiveness, count).iter().enumerate() {
            if !kept(i) {
                continue;
            }
            for (c, column) in self.columns.iter().take(3).enumerate() {
                let share = column[i];
                for (r, row) in k.iter_mut().enumerate() {
                    row[c] += col[r] * share;
                }
            }
        }
        let inverse = inverse_3x3(&k)
            .filter(|m| m.iter().flatten().all(|v| v.is_finite()))
            .ok_or(AllocationError::Uncontrollable)?;
        let [collective, roll, pitch, yaw] = &mut self.columns;
        for i in 0..count {
            let m0 = if kept(i) {
                [collective[i], roll[i], pitch[i]]
            } else {
                self.effectiveness.column_mut(i).fill(0.0);
                [0.0; 3]
            };
            let mut m = [0.0f32; 3];
            for (c, v) in m.iter_mut().enumerate() {
                *v = m0[0] * inverse[0][c] + m0[1] * inverse[1][c] + m0[2] * inverse[2][c];
            }
            [collective[i], roll[i], pitch[i]] = m;
            yaw[i] = 0.0;
        }
        self.kind = MixerKind::Allocation;
        self.torque_scale = torque_scale(&self.effectiveness, count);
        Ok(())
    }

    /// Whether this mixer allocates a level hover of collective `thrust`, N (the vehicle's
    /// weight, no torque), within every rotor's range.
    pub fn holds_hover(&self, thrust: f32) -> bool {
        let hover = self.allocate(&Wrench {
            thrust,
            torque: Vec3::ZERO,
        });
        !hover.saturation.collective && !hover.saturation.roll_pitch
    }

    /// Whether `other` flies this mixer's rotors but `out` from the same places about the same
    /// COM, and none of `out` (their columns zero): the mixer without `out` built for this
    /// layout, whether or not this one has left them out yet.
    pub fn same_rotors_except(&self, other: &Self, out: u16) -> bool {
        let count = self.count.min(MAX_ROBOTS);
        self.count == other.count
            && self.max_thrust == other.max_thrust
            && (0..count).all(|i| {
                let theirs = other.effectiveness.column(i);
                if out & (1 << i) != 0 {
                    theirs.iter().all(|v| *v == 0.0)
                } else {
                    theirs == self.effectiveness.column(i)
                }
            })
    }

    /// The torque the mixer can add about each body axis (roll, pitch, yaw), N m, on top of a
    /// level hover of collective `thrust`, N, with every rotor within `[0, max_thrust]`: the
    /// smaller of the two directions, each axis alone (its column through the mixer from the
    /// hover's thrusts). Zero on an axis the hover already saturates or the mixer does not
    /// fly. For deciding whether a formation can hold a disturbance, not for the step.
    pub fn authority(&self, thrust: f32) -> Vec3 {
        let mut base = [0.0f32; MAX_ROBOTS];
        for (b, c) in base.iter_mut().zip(&self.columns[0][..self.count]) {
            *b = c * thrust;
        }
        let mut each = [0.0f32; 3];
        for (axis, value) in each.iter_mut().enumerate() {
            let column = &self.columns[axis + 1];
            if column[..self.count].iter().all(|v| *v == 0.0) {
                continue;
            }
            if let Some((lo, hi)) = self.room(&base, column) {
                *value = math::max(math::min(-lo, hi), 0.0);
            }
        }
        Vec3::new(each[0], each[1], each[2])
    }

    /// Whether the mixer delivers yaw torque (false once yaw was given up for a lost rotor).
    pub fn flies_yaw(&self) -> bool {
        self.columns[3][..self.count].iter().any(|v| *v != 0.0)
    }

    /// Rotor `i`'s column of the effectiveness matrix: what one newton of its thrust makes
    /// (collective N, roll, pitch and yaw torque N m); zeros for a rotor the mixer flies
    /// without, or beyond [`Self::count`].
    pub fn column(&self, i: usize) -> [f32; 4] {
        if i >= self.count {
            return [0.0; 4];
        }
        let c = self.effectiveness.column(i);
        [c[0], c[1], c[2], c[3]]
    }

    /// The effectiveness matrix's columns of the mixer's rotors, four numbers per rotor (as
    /// [`Self::column`] gives them), read in place.
    pub fn columns_raw(&self) -> &[f32] {
        let raw = self.effectiveness.as_slice();
        raw.get(..4 * self.count).unwrap_or(raw)
    }

    /// One over the flown rotors' RMS arm (the root mean square of each flown rotor's roll
    /// and pitch torque per newton), 1/m: torques times it are newtons, comparable with
    /// thrusts; `None` when no flown rotor has an arm. Worked out when the mixer is built (a
    /// square root, which the Cortex-M7 takes in software).
    pub fn torque_scale(&self) -> Option<f32> {
        self.torque_scale
    }

    /// The mixer's kind.
    pub fn kind(&self) -> MixerKind {
        self.kind
    }

    /// Number of rotors.
    pub fn count(&self) -> usize {
        self.count
    }

    /// The wrench that rotor thrusts `thrusts` produce.
    pub fn wrench_of(&self, thrusts: &[f32]) -> Wrench {
        // Over the rotors there are, column by column (the matrix is stored by columns): the
        // full 4 x 16 product of zero-padded thrusts cost four times the arithmetic.
        let mut w = [0.0f32; 4];
        let columns = self.effectiveness.as_slice().chunks_exact(4);
        for (column, &t) in columns.zip(thrusts.iter().take(self.count)) {
            for (w, &a) in w.iter_mut().zip(column) {
                *w += a * t;
            }
        }
        Wrench {
            thrust: w[0],
            torque: Vec3::new(w[1], w[2], w[3]),
        }
    }

    /// Interval of `k` keeping `base + k * dir` within `[0, max]` on every rotor.
    fn room(&self, base: &[f32; MAX_ROBOTS], dir: &[f32; MAX_ROBOTS]) -> Option<(f32, f32)> {
        let (mut lo, mut hi) = (f32::NEG_INFINITY, f32::INFINITY);
        for i in 0..self.count {
            let (b, d) = (base[i], dir[i]);
            if d.abs() < 1e-9 {
                if b < -1e-6 || b > self.max_thrust + 1e-6 {
                    return None;
                }
                continue;
            }
            let (k0, k1) = ((0.0 - b) / d, (self.max_thrust - b) / d);
            let (near, far) = if k0 < k1 { (k0, k1) } else { (k1, k0) };
            lo = math::max(lo, near);
            hi = math::min(hi, far);
        }
        (lo <= hi).then_some((lo, hi))
    }

    /// Rotor thrusts for `wrench`, within limits, yaw given up first.
    pub fn allocate(&self, wrench: &Wrench) -> Allocation {
        let n = self.count;
        let [collective, roll, pitch, yaw] = &self.columns;
        let mut thrust_part = [0.0f32; MAX_ROBOTS];
        let mut tilt_part = [0.0f32; MAX_ROBOTS];
        let mut yaw_part = [0.0f32; MAX_ROBOTS];
        for i in 0..n {
            thrust_part[i] = collective[i] * wrench.thrust;
            tilt_part[i] = roll[i] * wrench.torque.x + pitch[i] * wrench.torque.y;
            yaw_part[i] = yaw[i] * wrench.torque.z;
        }
        let mut saturation = Saturation::default();
        let combine = |scale: f32| {
            let mut base = [0.0f32; MAX_ROBOTS];
            for i in 0..n {
                base[i] = thrust_part[i] + scale * tilt_part[i];
            }
            base
        };
        // Roll, pitch and collective: shift the collective along its column if needed; if no
        // shift fits, scale roll and pitch down until one does.
        let mut base = combine(1.0);
        let mut room = self.room(&base, collective);
        if room.is_none() {
            saturation.roll_pitch = true;
            let (mut ok, mut bad) = (0.0f32, 1.0f32);
            if let Some(fits) = ScaledRoom::new(self, &thrust_part, &tilt_part, collective) {
                // 12 halvings: the scale to 1/4096, far finer than the rotors deliver.
                for _ in 0..12 {
                    let mid = 0.5 * (ok + bad);
                    if fits.at(mid) { ok = mid } else { bad = mid }
                }
            }
            base = combine(ok);
            room = self.room(&base, collective);
        }
        let mut thrusts = [0.0f32; MAX_ROBOTS];
        match room {
            Some((lo, hi)) => {
                let shift = math::clamp(0.0f32, lo, hi);
                saturation.collective = shift != 0.0;
                for i in 0..n {
                    thrusts[i] = base[i] + shift * collective[i];
                }
                // Yaw last: as much of it as the room left allows.
                let fit = self
                    .room(&thrusts, &yaw_part)
                    .map_or(0.0, |(_, hi)| math::clamp(hi, 0.0, 1.0));
                saturation.yaw = fit < 1.0 && yaw_part[..n].iter().any(|v| v.abs() > 1e-9);
                for i in 0..n {
                    thrusts[i] += fit * yaw_part[i];
                }
            }
            None => {
                // Not even the collective alone fits: clip every rotor.
                saturation = Saturation {
                    collective: true,
                    roll_pitch: true,
                    yaw: true,
                };
                thrusts[..n].copy_from_slice(&thrust_part[..n]);
            }
        }
        for t in thrusts.iter_mut().take(n) {
            *t = math::clamp(*t, 0.0, self.max_thrust);
        }
        Allocation {
            thrusts,
            count: n,
            achieved: self.wrench_of(&thrusts[..n]),
            saturation,
        }
    }
}

/// See [`Mixer::torque_scale`]: over the first `count` columns of `a` with thrust.
fn torque_scale(a: &Effectiveness, count: usize) -> Option<f32> {
    let (mut arms, mut counted) = (0.0f32, 0.0f32);
    for c in a.as_slice().chunks_exact(4).take(count) {
        if c[0] != 0.0 {
            arms += c[1] * c[1] + c[2] * c[2];
            counted += 1.0;
        }
    }
    (counted > 0.0 && arms > 0.0).then(|| 1.0 / math::sqrt(arms / counted))
}

#[cfg(test)]
mod tests;
