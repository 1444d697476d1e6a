//! Rotors that stop or fade in flight, found from the vehicle's response and the ESCs' RPM
//! (`rotor-out`, `rotor-fade`; docs/failures.md#rotors-that-stop-in-flight).
//!
//! What it implements: actuator failure detection and isolation with a momentum residual
//! (A. De Luca, R. Mattone, "Actuator failure detection and isolation using generalized
//! momenta", ICRA 2003) and isolation by the residual's direction (J. Gertler, "Fault
//! Detection and Diagnosis in Engineering Systems", 1998, directional residuals), on the
//! rigid payload's roll, pitch and collective:
//!
//! - Expected wrench: the allocator's effectiveness matrix `A` (one column per rotor,
//!   [`crate::control::allocation`]) times the rotors' commands passed through the rotors'
//!   response ([`RotorMonitorConfig::response_time`]: the motor's lag and the IMU's delay).
//! - Torque residual (roll, pitch): the observer `p_hat' = tau_expected + r - w x I w`,
//!   `r = K (I w - p_hat)` tracks the torque the model misses with bandwidth `K`, from the
//!   gyro alone (no differentiated rates).
//! - Thrust residual: the collective the accelerometer measures (mass times the specific
//!   force along body z, moved from the IMU at the payload frame's origin to the COM with the
//!   observer's angular acceleration) minus the expected one, low-passed with the same `K`.
//! - Both residuals pass a second low-pass of bandwidth `K` (the observer's residual carries
//!   the gyro's noise times `K I` at every frequency).
//! - Change: the residual minus its baseline, which absorbs what the model gets wrong for
//!   long (a COM or mass estimate off, the command-to-thrust map's bias, a slow
//!   disturbance): while the change is within [`RotorMonitorConfig::quiet`] the baseline
//!   follows the residual slowly ([`RotorMonitorConfig::baseline_time`]); beyond, it holds,
//!   and a change no rotor explains for [`RotorMonitorConfig::rebase_time`] becomes the new
//!   baseline at once (followed slowly, a step would shrink through every size, one rotor's
//!   among them).
//! - Isolation ([`crate::flight::rotor_isolation`]): one rotor's column, or two rotors'
//!   stopped together, must explain the change in size and direction for
//!   [`RotorMonitorConfig::confirm_time`]; on the next tick the rotors named are those that
//!   explain the change averaged over the last 10 ms (neighbours' columns are close, and one
//!   tick's noise can favour either). A tick judges or names, never both; the pairs (120 at
//!   sixteen rotors) are searched a few a tick ([`crate::flight::rotor_isolation::PairSweep`]),
//!   the best found so far judged again each tick.
//! - After a finding the monitor goes on: what the rotors found put into the residuals is
//!   taken out ([`RotorMonitor::mark_out`]), the baseline from before is kept, and a rotor
//!   that stopped with them still shows after [`RotorMonitorConfig::blind_time`]; until
//!   [`RotorMonitorConfig::resettle_time`] a finding must show in the collective too.
//! - A rotor that fades: its loss goes into the baseline as it grows; the baseline's drift
//!   since the monitor settled (rebases along no rotor's column left out) is judged as a
//!   change is, every [`DRIFT_EVERY`]th tick: the rotor it points along, clearly better than
//!   the next, is named once its loss reaches half the thrust the rotor had when the drift
//!   was taken from (the controller raises a fading rotor's command as it fades; sized
//!   against today's, the neighbour whose column fits worse but reads a larger loss would be
//!   named first). While the robots move in flight the model changes every tick, and the
//!   drift is taken from the latest ([`RotorMonitor::model_changed`]): the believed COM
//!   carried to the measured one drifts the baseline by a rotor's size on a large payload.
//! - The ESCs' RPM, where the vehicle has it: a rotor whose RPM squared over its expected
//!   thrust falls under half its own (learned in its first second of flight) is named in
//!   [`RPM_CONFIRM_TIME`], whatever the response says.
//!
//! The thrust row is what tells a rotor from a load that shifts: a shifted COM changes the
//! torque about the believed COM as a rotor loss does, but not the collective. The torque rows
//! are what tell a rotor from a loss of lift (a downdraft): only a rotor close to the COM has
//! (almost) no torque to show, and a sudden loss of lift of its size cannot be told from it.
//!
//! What it cannot tell apart: a force pushing down at one point (an obstacle met from below)
//! is, to the dynamics, a rotor stopping there.
//!
//! The monitor watches the response only while the caller says the vehicle is clear of the
//! ground (contact forces are no rotor's), and starts afresh
//! ([`RotorMonitorConfig::settle_time`]) after take-off.
//! State: about 320 bytes (the flight controller keeps it in its static mission); the tuning,
//! [`RotorMonitorConfig`], comes with each tick's input (the flight stack passes the
//! defaults, a constant in flash).

use crate::control::allocation::Mixer;
use crate::control::vector::Vec3;
use crate::control::vehicle::VehicleModel;
use crate::flight::rotor_isolation::{Columns, Judging, PairSweep, dot, explain, explain_swept};
use crate::geometry::Vec2;
use crate::math;
use crate::scenario::MAX_ROBOTS;

/// Tuning of the rotor monitor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RotorMonitorConfig {
    /// Bandwidth `K` of the residuals, 1/s.
    pub bandwidth: f32,
    /// Time constant from a rotor command to the IMU seeing its effect (the motor's lag and
    /// the sensor's delay), s.
    pub response_time: f32,
    /// Time constant of the baseline the change is measured from, s.
    pub baseline_time: f32,
    /// Size of a change (thrust and torques over the rotors' RMS arm, N) within which the
    /// baseline follows the residual.
    pub quiet: f32,
    /// Time a larger change no rotor explains is held before it becomes the baseline, s.
    pub rebase_time: f32,
    /// Time after (re)starting before a rotor can be declared stopped, s.
    pub settle_time: f32,
    /// Time after a rotor is found in which another must show in the thrust row too, s: the
    /// recovery on the rotors left applies large torques, and the inertia's error (the
    /// residual is the torque times the model's inertia over the true one, less one) is then
    /// the size of a rotor's.
    pub resettle_time: f32,
    /// Time after a rotor is found in which nothing is judged from the vehicle's response, s:
    /// the recovery's first swing moves the thrust row too (the accelerometer sits off the
    /// COM, and its lever arm is corrected with the model's angular acceleration).
    pub blind_time: f32,
    /// Expected thrust below which a rotor is not judged (its loss is too small to see), N.
    pub min_thrust: f32,
    /// Share of the change (squared norm) one rotor's column must explain.
    pub min_explained: f32,
    /// Smallest thrust lost, as a fraction of the rotor's expected thrust.
    pub min_fraction: f32,
    /// Largest thrust lost, as a fraction of the rotor's expected thrust.
    pub max_fraction: f32,
    /// Time the same rotor must be found before it is declared stopped, s.
    pub confirm_time: f32,
}

impl RotorMonitorConfig {
    /// The defaults (measured on the paper's payloads in the simulator; tests/rotor_out.rs).
    pub const DEFAULT: Self = Self {
        bandwidth: 50.0,
        response_time: 0.025,
        baseline_time: 0.5,
        quiet: 1.0,
        rebase_time: 0.3,
        settle_time: 0.5,
        resettle_time: 1.5,
        blind_time: 0.25,
        min_thrust: 1.0,
        min_explained: 0.8,
        min_fraction: 0.5,
        max_fraction: 1.6,
        confirm_time: 0.07,
    };
}

impl Default for RotorMonitorConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Time constant of the change's average that names the rotor, s.
const SMOOTHING_TIME: f32 = 0.01;

/// Time a drift of the baseline must be explained by the same finding before it is named, s.
const DRIFT_CONFIRM_TIME: f32 = 0.2;

/// The drift is judged on one tick in this many, and the change on the others (a drift is
/// slow; the control tick's budget holds one judgement a tick).
const DRIFT_EVERY: u8 = 8;

/// Time over which each rotor's RPM-to-thrust ratio is learned once the rotors fly, s.
const RPM_LEARN_TIME: f32 = 1.0;

/// Time constant of that learning, s.
const RPM_LEARN_AVERAGE: f32 = 0.2;

/// Time a rotor's RPM must show less than [`RotorMonitorConfig::min_fraction`] of its
/// expected thrust before it is named, s.
const RPM_CONFIRM_TIME: f32 = 0.01;

/// What the monitor reads each tick.
#[derive(Clone, Copy, Debug)]
pub struct MonitorInput<'a> {
    /// The tuning.
    pub config: &'a RotorMonitorConfig,
    /// The mixer flown (its effectiveness matrix; rotors already out have zero columns).
    pub mixer: &'a Mixer,
    /// Mass and inertia as the controller believes them.
    pub vehicle: &'a VehicleModel,
    /// The COM the mixer's torques are about, from the IMU (the payload frame's origin), m.
    pub com: Vec2,
    /// This tick's rotor commands, N.
    pub thrusts: &'a [f32],
    /// Each rotor's RPM from its ESC's telemetry (NaN where this tick has none), or `None`
    /// without ESC telemetry.
    pub rpm: Option<&'a [f32]>,
    /// Each RPM is the ESC's latest message, held between messages that come slower than the
    /// tick (DroneCAN's `Status`, 50 Hz, CRC-checked): one low message confirms. Otherwise
    /// each tick brings a reading of its own (bidirectional DShot's answers, a 4-bit CRC) and
    /// [`RPM_CONFIRM_TIME`] of them confirm.
    pub rpm_per_message: bool,
    /// Body rate, rad/s.
    pub rate: Vec3,
    /// The accelerometer's specific force, body frame, m/s^2.
    pub accel: Vec3,
    /// Whether the rotors fly the vehicle (airborne): the RPM is judged.
    pub flying: bool,
    /// Whether to watch the vehicle's response: flying, clear of the ground, the IMU trusted.
    pub active: bool,
    /// Seconds since the previous tick.
    pub dt: f32,
}

/// The rotor monitor's state.
#[derive(Clone, Debug, PartialEq)]
pub struct RotorMonitor {
    /// Each rotor's command through the rotors' response, N.
    expected: [f32; MAX_ROBOTS],
    /// The torque observer's momentum (roll, pitch), N m s.
    momentum: [f32; 2],
    /// Residuals: thrust (N), roll and pitch torque (N m).
    residual: [f32; 3],
    /// The residuals through a second low-pass of the same bandwidth (the torque observer
    /// passes the gyro's noise times `K I` at every frequency).
    filtered: [f32; 3],
    /// Their slow baseline.
    baseline: [f32; 3],
    /// The baseline when the monitor settled, moved with every rebase: the baseline's drift
    /// from it is what a rotor that fades slowly shows.
    reference: [f32; 3],
    /// Time left before judging, s.
    wait: f32,
    /// Time left in which a finding must show in the thrust row (after a rotor was found), s.
    guard: f32,
    /// Time the change has been beyond [`RotorMonitorConfig::quiet`], s.
    loud: f32,
    /// Time some rotor has explained the change without a break, s.
    confirming: f32,
    /// Time the same rotors have explained the baseline's drift, s.
    drifting: f32,
    /// The rotors the drift was last explained by.
    drift_rotors: u16,
    /// Ticks judged, modulo [`DRIFT_EVERY`].
    tick: u8,
    /// The change through a [`SMOOTHING_TIME`] low-pass.
    smoothed: [f32; 3],
    started: bool,
    /// Rotors known to be out (bit `i` for rotor `i`): never candidates again.
    out: u16,
    /// Each rotor's RPM squared over its expected thrust, learned in the first
    /// [`RPM_LEARN_TIME`] of flight.
    rpm_ratio: [f32; MAX_ROBOTS],
    /// Time the RPM has been learned, s.
    rpm_learned: f32,
    /// Ticks each rotor's RPM has been too low in a row.
    rpm_low: [u8; MAX_ROBOTS],
    /// Each rotor's expected thrust when the reference was taken, N: a fading rotor's loss
    /// is sized against it (the controller raises a fading rotor's command as it fades).
    reference_thrust: [f32; MAX_ROBOTS],
    /// The search of the pairs under way (a few a tick).
    sweep: PairSweep,
}

impl Default for RotorMonitor {
    fn default() -> Self {
        Self::new()
    }
}

impl RotorMonitor {
    /// A monitor that has seen nothing yet (its tuning comes with each tick's input).
    pub const fn new() -> Self {
        Self {
            expected: [0.0; MAX_ROBOTS],
            momentum: [0.0; 2],
            residual: [0.0; 3],
            filtered: [0.0; 3],
            baseline: [0.0; 3],
            reference: [0.0; 3],
            wait: 0.0,
            guard: 0.0,
            loud: 0.0,
            confirming: 0.0,
            drifting: 0.0,
            drift_rotors: 0,
            tick: 0,
            smoothed: [0.0; 3],
            started: false,
            out: 0,
            rpm_ratio: [0.0; MAX_ROBOTS],
            rpm_learned: 0.0,
            rpm_low: [0; MAX_ROBOTS],
            reference_thrust: [0.0; MAX_ROBOTS],
            sweep: PairSweep::new(),
        }
    }

    /// Rotors known to be out, bit `i` for rotor `i`.
    pub fn out(&self) -> u16 {
        self.out
    }

    /// Takes rotors in `out` as stopped (found here or reported by their ESCs), `mixer` the
    /// one flown until now: they are not judged again; what their loss put into the residuals
    /// is taken out (the mixer rebuilt without them no longer expects their thrust), so a
    /// rotor that stopped with them still shows; for [`RotorMonitorConfig::resettle_time`] a
    /// new finding must show in the thrust row as well.
    pub fn mark_out(&mut self, out: u16, mixer: &Mixer, config: &RotorMonitorConfig) {
        let newly = out & !self.out;
        if newly == 0 {
            return;
        }
        self.out |= newly;
        if self.started {
            let k = config.bandwidth;
            for j in (0..mixer.count().min(MAX_ROBOTS)).filter(|&j| newly & (1 << j) != 0) {
                let c = mixer.column(j);
                let lost = [c[0], c[1], c[2]].map(|v| v * self.expected[j]);
                for (row, l) in lost.iter().enumerate() {
                    self.residual[row] += l;
                    self.filtered[row] += l;
                }
                for axis in 0..2 {
                    if k > 0.0 {
                        self.momentum[axis] -= lost[axis + 1] / k;
                    }
                }
            }
        }
        self.reference = self.baseline;
        self.reference_thrust = self.expected;
        self.confirming = 0.0;
        self.drifting = 0.0;
        self.loud = 0.0;
        self.smoothed = [0.0; 3];
        self.sweep = PairSweep::new();
        self.guard = config.resettle_time;
    }

    /// The model judged against was changed on purpose (the robots moved in flight, and the
    /// mixer, COM and mass with them): what the baseline drifts by meanwhile is the model's
    /// error changing (a believed COM carried towards the measured one takes the torque the
    /// old error made out of the residual), not a rotor fading, so the drift is measured from
    /// here on. A rotor that stops is still found from the change; one that fades while the
    /// robots move is found from the drift after they stop.
    pub fn model_changed(&mut self) {
        self.reference = self.baseline;
        self.reference_thrust = self.expected;
        self.drifting = 0.0;
    }

    /// Each rotor's expected thrust: its command through the rotors' response, N.
    pub fn expected(&self) -> &[f32; MAX_ROBOTS] {
        &self.expected
    }

    /// The change of the residuals from their baseline: thrust (N), roll and pitch torque
    /// (N m); zero before the monitor has settled.
    pub fn change(&self) -> [f32; 3] {
        if !self.started || self.wait > 0.0 {
            return [0.0; 3];
        }
        core::array::from_fn(|i| self.filtered[i] - self.baseline[i])
    }

    /// The baseline's drift since the monitor settled (rebases left out): thrust (N), roll
    /// and pitch torque (N m).
    pub fn drift(&self) -> [f32; 3] {
        if !self.started || self.wait > 0.0 {
            return [0.0; 3];
        }
        core::array::from_fn(|i| self.baseline[i] - self.reference[i])
    }

    fn restart(&mut self) {
        self.started = false;
        self.wait = 0.0;
        self.loud = 0.0;
        self.confirming = 0.0;
        self.drifting = 0.0;
        self.smoothed = [0.0; 3];
        self.sweep = PairSweep::new();
    }

    /// One tick; the rotors (bit `i` for rotor `i`) newly found stopped, 0 if none. The
    /// caller rebuilds the mixer without them (this has called [`Self::mark_out`] for them).
    pub fn update(&mut self, input: &MonitorInput<'_>) -> u16 {
        let config = input.config;
        let n = input.mixer.count().min(input.thrusts.len()).min(MAX_ROBOTS);
        let dt = input.dt;
        let expected = input.mixer.wrench_of(&self.expected[..n]);
        // The commands of this tick act from now on: through the rotors' response.
        let alpha = if dt > 0.0 {
            math::clamp(dt / math::max(config.response_time, dt), 0.0, 1.0)
        } else {
            0.0
        };
        for (e, &t) in self.expected.iter_mut().zip(input.thrusts).take(n) {
            if t.is_finite() {
                *e += alpha * (t - *e);
            }
        }
        let by_rpm = self.watch_rpm(input, n);
        if by_rpm != 0 {
            self.mark_out(by_rpm, input.mixer, config);
            return by_rpm;
        }
        let inertia = input.vehicle.inertia;
        let w = input.rate;
        let usable = input.active
            && dt > 0.0
            && w.is_finite()
            && input.accel.is_finite()
            && inertia.x > 0.0
            && inertia.y > 0.0;
        if !usable {
            self.restart();
            return 0;
        }
        let p = [inertia.x * w.x, inertia.y * w.y];
        if !self.started {
            self.momentum = p;
            self.residual = [0.0; 3];
            self.filtered = [0.0; 3];
            self.baseline = [0.0; 3];
            self.reference = [0.0; 3];
            self.started = true;
            self.wait = math::max(self.wait, config.settle_time);
            return 0;
        }
        let k = config.bandwidth;
        let gyroscopic = w.cross(inertia.component_mul(w));
        let torque = [expected.torque.x, expected.torque.y];
        let gyro = [gyroscopic.x, gyroscopic.y];
        let moments = [inertia.x, inertia.y];
        for axis in 0..2 {
            self.momentum[axis] += dt * (torque[axis] + self.residual[axis + 1] - gyro[axis]);
            self.residual[axis + 1] = k * (p[axis] - self.momentum[axis]);
        }
        // The specific force at the COM `c` from the IMU's at the origin, `-c` from it:
        // f_com = f_imu + dw/dt x c + w x (w x c) (z components; c in the body's xy plane).
        // dw/dt is the model's, (tau - w x I w) / I, here, and the missed torque's part,
        // residual / I, after the low-pass: the observer's residual is that torque through
        // the same first-order lag, so both rows see a stopped rotor with the same delay.
        let c = input.com;
        let lever = |alpha: [f32; 2]| alpha[0] * c.y - alpha[1] * c.x;
        let modelled = lever([0, 1].map(|a| (torque[a] - gyro[a]) / moments[a]));
        let centripetal = w.z * (w.x * c.x + w.y * c.y);
        let mass = input.vehicle.mass;
        let measured = -mass * (input.accel.z + modelled + centripetal);
        let beta = math::clamp(k * dt, 0.0, 1.0);
        self.residual[0] += beta * (measured - expected.thrust - self.residual[0]);
        let missed = lever([1, 2].map(|a| self.residual[a] / moments[a - 1]));
        let rows = [
            self.residual[0] - mass * missed,
            self.residual[1],
            self.residual[2],
        ];
        for (f, r) in self.filtered.iter_mut().zip(rows) {
            *f += beta * (r - *f);
        }
        self.wait -= dt;
        if self.wait > 0.0 {
            self.baseline = self.filtered;
            self.reference = self.filtered;
            self.reference_thrust = self.expected;
            return 0;
        }
        self.guard = math::max(self.guard - dt, 0.0);
        let Some(scale) = input.mixer.torque_scale() else {
            return 0;
        };
        if self.guard > config.resettle_time - config.blind_time {
            // The baseline stays what it was before: a rotor that stopped with the one found
            // shows once this has passed.
            self.loud = 0.0;
            return 0;
        }
        let scaled = |v: &[f32; 3]| [v[0], v[1] * scale, v[2] * scale];
        let change = self.change();
        let d = scaled(&change);
        // Squared sizes throughout: the software square root costs a few hundred
        // instructions a tick on the Cortex-M7.
        let size2 = dot(&d, &d);
        if size2 <= config.quiet * config.quiet {
            self.loud = 0.0;
            let gamma = math::clamp(dt / math::max(config.baseline_time, dt), 0.0, 1.0);
            for (b, r) in self.baseline.iter_mut().zip(self.filtered) {
                *b += gamma * (r - *b);
            }
        } else {
            self.loud += dt;
        }
        let recent = math::clamp(dt / math::max(SMOOTHING_TIME, dt), 0.0, 1.0);
        for (m, v) in self.smoothed.iter_mut().zip(change) {
            *m += recent * (v - *m);
        }
        // Nothing a rotor's loss could be: spare the search (most ticks).
        let least = config.min_fraction * config.min_thrust;
        self.tick = (self.tick + 1) % DRIFT_EVERY;
        let drift_tick = self.tick == 0;
        let drift = scaled(&self.drift());
        if drift_tick {
            // A drift a rotor could explain shows in the collective: `min_fraction` of at
            // least `min_fraction` of the least thrust a rotor judged carries.
            let lightest = (0..n)
                .filter(|&j| self.out & (1 << j) == 0 && self.expected[j] >= config.min_thrust)
                .fold(f32::INFINITY, |m, j| math::min(m, self.expected[j]));
            let shown = -drift[0] >= config.min_fraction * config.min_fraction * lightest;
            if !shown || dot(&drift, &drift) < least * least {
                self.drifting = 0.0;
                return 0;
            }
        } else if size2 < least * least {
            self.confirming = 0.0;
            return 0;
        }
        // A drift is sized against the thrusts the rotors had when it was taken from: the
        // controller raises a fading rotor's command as it fades.
        let thrust = if drift_tick {
            self.reference_thrust
        } else {
            self.expected
        };
        let columns = Columns::new(
            n,
            input.mixer.columns_raw(),
            scale,
            &thrust,
            !self.out,
            config.min_thrust,
        );
        let guarded = self.guard > 0.0;
        if self.confirming >= config.confirm_time {
            // Confirmed by the last tick: name the rotors that explain the recent change
            // (neighbours' columns are close; one tick's noise can pick either). A tick judges
            // the change or names the rotors, never both (the control tick's budget).
            let named = explain_swept(
                &scaled(&self.smoothed),
                &columns,
                config,
                Judging {
                    sized: false,
                    thrust_shown: guarded,
                    pairs: true,
                    decisive: false,
                },
                &mut self.sweep,
            );
            if named == 0 {
                // Judged again on the next tick, named on the one after if it still holds.
                self.confirming -= dt;
            } else {
                self.mark_out(named, input.mixer, config);
            }
            return named;
        }
        if drift_tick {
            return self.watch_drift(input, &columns, &drift);
        }
        let judged = Judging {
            sized: true,
            thrust_shown: guarded,
            pairs: true,
            decisive: false,
        };
        let found = explain_swept(&d, &columns, config, judged, &mut self.sweep);
        if found == 0 {
            self.confirming = 0.0;
            if self.loud >= config.rebase_time {
                // A change no rotor's size explains becomes the new baseline. Pointing along
                // a rotor's column, collective included, it is part of a rotor that fades
                // and stays in the drift; otherwise (a load that moved) it is not.
                self.loud = 0.0;
                let rotorlike = Judging {
                    sized: false,
                    thrust_shown: true,
                    pairs: false,
                    decisive: false,
                };
                if explain(&d, &columns, config, rotorlike) == 0 {
                    for i in 0..3 {
                        self.reference[i] += self.filtered[i] - self.baseline[i];
                    }
                }
                self.baseline = self.filtered;
            }
            return 0;
        }
        // Some rotor explains it: confirm over time; the next tick names the rotors.
        self.confirming += dt;
        0
    }

    /// A rotor that fades slowly: its loss goes into the baseline as it grows. The drift
    /// since the monitor settled is judged as a change is, the thrust row always required
    /// (a slow torque is a load, or the COM believed elsewhere): the rotor whose column it
    /// points along best, clearly better than the next ([`Judging::decisive`]), once that
    /// rotor's loss is large enough (`columns` carry the thrusts it is sized against), named
    /// once the same rotor is found for [`DRIFT_CONFIRM_TIME`].
    fn watch_drift(
        &mut self,
        input: &MonitorInput<'_>,
        columns: &Columns,
        drift: &[f32; 3],
    ) -> u16 {
        let config = input.config;
        let judged = Judging {
            sized: true,
            thrust_shown: true,
            pairs: false,
            decisive: false,
        };
        // The rotor whose column the drift points along, named once its loss is large
        // enough: sized first, a rotor that fits worse but reads larger would be found
        // before the one fading.
        let pointed = explain(
            drift,
            columns,
            config,
            Judging {
                sized: false,
                decisive: true,
                ..judged
            },
        );
        let sized = explain(drift, columns, config, judged);
        let found = if pointed == sized { sized } else { 0 };
        if found == 0 || found != self.drift_rotors {
            self.drift_rotors = found;
            self.drifting = 0.0;
            return 0;
        }
        self.drifting += input.dt * f32::from(DRIFT_EVERY);
        if self.drifting < DRIFT_CONFIRM_TIME {
            return 0;
        }
        self.mark_out(found, input.mixer, config);
        found
    }

    /// The rotors whose ESCs' RPM says they make less than
    /// [`RotorMonitorConfig::min_fraction`] of their expected thrust, for
    /// [`RPM_CONFIRM_TIME`] (or for one message, [`MonitorInput::rpm_per_message`]). Thrust
    /// goes with the RPM squared (one propeller, one air density):
    /// each rotor's ratio of the two is learned in the first [`RPM_LEARN_TIME`] of flight and
    /// a rotor is judged against its own.
    fn watch_rpm(&mut self, input: &MonitorInput<'_>, n: usize) -> u16 {
        let Some(rpm) = input.rpm else {
            return 0;
        };
        let config = input.config;
        let dt = input.dt;
        if !input.flying || dt <= 0.0 {
            self.rpm_low = [0; MAX_ROBOTS];
            return 0;
        }
        let learning = self.rpm_learned < RPM_LEARN_TIME;
        let first = self.rpm_learned == 0.0;
        let learn = math::clamp(dt / RPM_LEARN_AVERAGE, 0.0, 1.0);
        let confirm = if input.rpm_per_message {
            1
        } else {
            math::ceil(RPM_CONFIRM_TIME / dt) as u8
        };
        let mut found = 0u16;
        for (j, &r) in rpm.iter().enumerate().take(n) {
            let expected = self.expected[j];
            // No reading (NaN) or a nonsense one: not judged.
            if self.out & (1 << j) != 0 || expected < config.min_thrust || r.is_nan() || r < 0.0 {
                self.rpm_low[j] = 0;
                continue;
            }
            let ratio = r * r / expected;
            if learning {
                let known = &mut self.rpm_ratio[j];
                *known = if first || *known <= 0.0 {
                    ratio
                } else {
                    *known + learn * (ratio - *known)
                };
                continue;
            }
            if self.rpm_ratio[j] > 0.0 && ratio < config.min_fraction * self.rpm_ratio[j] {
                self.rpm_low[j] = self.rpm_low[j].saturating_add(1);
                if self.rpm_low[j] >= confirm.max(1) {
                    found |= 1 << j;
                }
            } else {
                self.rpm_low[j] = 0;
            }
        }
        if learning {
            self.rpm_learned += dt;
        }
        found
    }
}

#[cfg(test)]
mod tests;
