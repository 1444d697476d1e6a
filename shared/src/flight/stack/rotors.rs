//! The flight's rotors in the air (docs/failures.md#rotors-that-stop-in-flight): watching
//! them after each step, flying without those found stopped (the interim mixer in the step,
//! the full one from a job) and what the rotors left can hold.

use super::FlightStack;
#[cfg(doc)]
use super::LandingCause;
use crate::control::allocation::Mixer;
use crate::control::land_detector::LandDetector;
use crate::control::navigator::NavState;
use crate::control::vector::Vec3;
use crate::flight::rotor_findings::{EscTelemetry, RotorFinding, RotorOut};
use crate::flight::rotor_monitor::{MonitorInput, RotorMonitor, RotorMonitorConfig};
use crate::geometry::Vec2;

/// Where the mixer stands with the rotors found stopped: the tick that finds them judges
/// (the monitor's busiest tick), the next leaves them out of the mixer, and the one after
/// asks for the full mixer without them (each within the control step's budget).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum RotorsMixer {
    /// The mixer flown is built for every rotor not out.
    Whole,
    /// Rotors were found this tick: the next step leaves them out ([`Mixer::leave_out`]).
    LeaveOutNext,
    /// The step flies the interim mixer (or the mixer before, if none of the rotors left
    /// makes thrust, roll and pitch): the full mixer without them is wanted.
    Interim,
}

impl FlightStack {
    /// Flies without rotors `out` from this step: on the interim mixer
    /// ([`Mixer::leave_out`]) until the full one comes ([`Self::take_mixer`]). When the
    /// rotors left cannot make thrust, roll and pitch, the mixer flies on as it was (the lost
    /// rotors' share is lost) and the full one is still asked for (it says so).
    pub(super) fn fly_without(&mut self, out: u16) {
        let _ = self.mixer.leave_out(out);
        self.rotors_mixer = RotorsMixer::Interim;
    }

    /// Leaves the rotors found stopped on the last tick out of the mixer, before this step's
    /// allocation.
    pub(super) fn leave_out_found(&mut self) {
        if self.rotors_mixer == RotorsMixer::LeaveOutNext {
            self.fly_without(self.monitor.out());
        }
    }

    /// The rotors out, while the step flies the interim mixer without them and wants the full
    /// one ([`Mixer::without`], a job: [`crate::mission::JobRequest::MixerWithout`]).
    pub fn mixer_wanted(&self) -> Option<u16> {
        (self.rotors_mixer == RotorsMixer::Interim).then(|| self.monitor.out())
    }

    /// Flies on with the interim mixer, wanting no other (no mixer of the rotors left makes
    /// thrust, roll and pitch).
    pub fn keep_interim_mixer(&mut self) {
        self.rotors_mixer = RotorsMixer::Whole;
    }

    /// Takes `mixer`, the full mixer without the rotors out, in place of the interim one, if
    /// it flies the rotors left from the same places (not one built for an earlier layout or
    /// other rotors); whether it was taken. One copy: this runs in the control step.
    pub fn take_mixer(&mut self, mixer: &Mixer) -> bool {
        let fits = self.rotors_mixer == RotorsMixer::Interim
            && self.mixer.same_rotors_except(mixer, self.monitor.out());
        if fits {
            self.mixer.clone_from(mixer);
            self.rotors_mixer = RotorsMixer::Whole;
        }
        fits
    }

    /// The thrust that holds the vehicle as the controller believes it, N (for the full
    /// mixer's check that the rotors left hold a level hover, [`Mixer::holds_hover`]).
    pub fn hover_thrust(&self) -> f32 {
        self.controller.model().hover_thrust()
    }

    /// Rotors found stopped in flight, in the order found (the first two).
    pub fn rotors_lost(&self) -> &[RotorOut] {
        &self.rotors_lost
    }

    /// The rotor monitor (its residuals, for tests and logs).
    pub fn rotor_monitor(&self) -> &RotorMonitor {
        &self.monitor
    }

    /// The COM the mixer's torques are about (body frame), m.
    pub fn com(&self) -> Vec2 {
        self.com
    }

    /// Rotors flown without, bit `i` for rotor `i`.
    pub fn rotors_out(&self) -> u16 {
        self.monitor.out()
    }

    /// After a tick's [`Self::step`]: watches the rotors with the accelerometer's specific
    /// force `accel` (body frame, m/s^2), the tick's rotor commands `thrusts` and what the
    /// ESCs tell, `esc` (each rotor's RPM, the rotors they report stopped). The monitor judges
    /// the vehicle's response only in the air, clear of the ground and not resting on an edge
    /// ([`LandDetector::settling`]), and the RPM in the air.
    /// Rotors found stopped are flown without from the next tick (on the interim mixer until
    /// the full one is taken, [`Self::mixer_wanted`]), and the next tick begins
    /// the landing ([`LandingCause::RotorOut`]; under a descent without position, that descent
    /// goes on). With `response_trusted` false (the IMU failed: its samples explain nothing;
    /// or the pack cannot deliver the thrust asked, so every rotor makes less than expected) only
    /// the ESCs count. Returns what this tick found, if anything.
    pub fn watch_rotors(
        &mut self,
        nav: &NavState,
        accel: Vec3,
        thrusts: &[f32],
        esc: EscTelemetry<'_>,
        response_trusted: bool,
        dt: f32,
    ) -> Option<RotorFinding> {
        if self.stopped.is_some() {
            return None;
        }
        let n = self.mixer.count();
        let all = if n >= 16 { u16::MAX } else { (1u16 << n) - 1 };
        // Clear of the ground, and not resting on it: in wind a vehicle leaning into it comes
        // down on one edge, its origin up to 0.1 m up, and the ground's push there is a
        // wrench no rotor made. Resting is the land detector's: its lowest point down and
        // still (a rotor stopping in the air tips the payload fast, and is watched on).
        let clear = nav.height_above(self.ground_z) > 3.0 * LandDetector::LAND_HEIGHT
            && !self.land.settling();
        let newly_reported = esc.stopped & all & !self.monitor.out();
        let vehicle = *self.controller.model();
        let found = self.monitor.update(&MonitorInput {
            config: &RotorMonitorConfig::DEFAULT,
            mixer: &self.mixer,
            vehicle: &vehicle,
            com: self.com,
            thrusts,
            rpm: esc.rpm,
            rpm_per_message: esc.rpm_per_message,
            rate: nav.attitude.rate,
            accel,
            flying: self.config.watch_rotors && self.land.airborne(),
            active: self.config.watch_rotors && response_trusted && self.land.airborne() && clear,
            dt,
        });
        let newly = newly_reported | found;
        if newly == 0 {
            return None;
        }
        self.monitor
            .mark_out(newly, &self.mixer, &RotorMonitorConfig::DEFAULT);
        // Left out of the mixer by the next step, before its allocation: the first commands
        // after this tick's already fly without them.
        self.rotors_mixer = RotorsMixer::LeaveOutNext;
        let mut first = None;
        for robot in (0..n).filter(|&i| newly & (1 << i) != 0) {
            let event = RotorOut {
                robot: robot as u8,
                at: self.clock,
                reported: newly_reported & (1 << robot) != 0,
            };
            // Beyond the first two, flown without but not recorded.
            let _ = self.rotors_lost.push(event);
            first.get_or_insert(event);
        }
        self.rotor_landing = first.map(|e| e.robot);
        let out = self.monitor.out();
        first.map(|first| RotorFinding {
            first,
            newly,
            out,
            left: (n as u32 - (out & all).count_ones()) as u8,
        })
    }
}
