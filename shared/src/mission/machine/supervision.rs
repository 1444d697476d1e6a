//! The flight's supervision (docs/system.md#failsafes): what the ground link's and the
//! battery's changes mean in the phase the mission is in (the monitors are
//! [`crate::mission::supervision`]'s), and the rotors watched in flight for one that stops
//! (the monitor is [`crate::flight::rotor_monitor`]'s); the rotors' commands raised for a pack
//! that sags ([`crate::control::voltage_compensation`]).

use super::Mission;
use crate::control::navigator::NavState;
use crate::flight::EscTelemetry;
use crate::mission::interface::TickInput;
use crate::mission::phases::{AbortReason, Phase, Transition};
use crate::mission::supervision::{
    BatteryLevel, FenceAction, GcsLossAction, LinkChange, LinkResponse, Notice,
};
use crate::scenario::MAX_ROBOTS;

impl Mission {
    /// What the ground link's and the battery's changes mean in this phase: a transition (on
    /// the ground after the start: stop), the reason of a landing in place to begin (in
    /// flight), and what to tell people.
    pub(super) fn supervise(
        &mut self,
        link: Option<LinkChange>,
        battery: Option<BatteryLevel>,
        time_us: u64,
        dt: f32,
    ) -> (Option<Transition>, Option<AbortReason>, [Option<Notice>; 2]) {
        let sup = self.config.supervision;
        let on_ground = !matches!(
            self.phase,
            Phase::Idle | Phase::Disarmed | Phase::Aborted | Phase::Flying(_)
        );
        let cruising = self.cruising();
        let watched = sup.gcs_action != GcsLossAction::Off;
        let mut notices = [None, None];
        let mut landing = None;
        match link {
            Some(LinkChange::Lost) if watched => {
                if on_ground {
                    return (Some(self.abort(AbortReason::GcsLost)), None, notices);
                }
                let response = match sup.gcs_action {
                    _ if !cruising => LinkResponse::Nothing,
                    GcsLossAction::HoldThenLand => {
                        self.gcs_hold = Some(sup.gcs_hold_time);
                        self.apply_hold();
                        LinkResponse::Hold(sup.gcs_hold_time)
                    }
                    _ => LinkResponse::Continue,
                };
                notices[0] = Some(Notice::LinkLost {
                    silent: self.link.silence(time_us).unwrap_or(0.0),
                    response,
                });
            }
            Some(LinkChange::Regained) if watched => {
                let resumed = self.gcs_hold.take().is_some();
                self.apply_hold();
                notices[0] = Some(Notice::LinkRegained { resumed });
            }
            _ => {}
        }
        if let Some(left) = self.gcs_hold.as_mut() {
            *left -= dt;
            if *left <= 0.0 || !cruising {
                self.gcs_hold = None;
                self.apply_hold();
                if cruising {
                    landing = Some(AbortReason::GcsLost);
                }
            }
        }
        let volts = self.battery.volts().unwrap_or(0.0);
        match battery {
            Some(BatteryLevel::Low) if on_ground => {
                return (
                    Some(self.abort(AbortReason::BatteryLow { volts })),
                    None,
                    notices,
                );
            }
            Some(BatteryLevel::Critical) if on_ground => {
                return (
                    Some(self.abort(AbortReason::BatteryCritical { volts })),
                    None,
                    notices,
                );
            }
            Some(BatteryLevel::Critical) if cruising => {
                self.gcs_hold = None;
                self.held = false;
                self.apply_hold();
                landing = Some(AbortReason::BatteryCritical { volts });
            }
            Some(BatteryLevel::Critical) => {
                notices[1] = Some(Notice::BatteryCritical {
                    volts,
                    threshold: sup.battery_critical,
                });
            }
            Some(BatteryLevel::Low) => {
                notices[1] = Some(Notice::BatteryLow {
                    volts,
                    threshold: sup.battery_low,
                });
            }
            Some(BatteryLevel::Ok) | None => {}
        }
        (None, landing, notices)
    }

    /// The geofence (PX4's `GF_MAX_HOR_DIST`, `GF_MAX_VER_DIST`, `GF_ACTION`), watched while
    /// the flight flies its plan: the first time the vehicle is farther from its take-off
    /// point across the ground, or higher above it, than the fence allows, the action is
    /// taken once: a warning, a hold (until the operator lands or resumes), or a landing in
    /// place (the reason returned). What to tell people comes with it.
    pub(super) fn watch_fence(&mut self, nav: &NavState) -> (Option<AbortReason>, Option<Notice>) {
        let sup = self.config.supervision;
        let Some(home) = self.home else {
            return (None, None);
        };
        if sup.fence_action == FenceAction::Off || self.fence_breached || !self.cruising() {
            return (None, None);
        }
        let p = nav.position.position;
        let (north, east) = (p.x - home.x, p.y - home.y);
        let distance = libm::sqrtf(north * north + east * east);
        // NED: up is minus z.
        let height = home.z - p.z;
        let outside = (sup.fence_horizontal > 0.0 && distance > sup.fence_horizontal)
            || (sup.fence_vertical > 0.0 && height > sup.fence_vertical);
        if !outside {
            return (None, None);
        }
        self.fence_breached = true;
        match sup.fence_action {
            FenceAction::Land => (
                Some(AbortReason::GeofenceBreached { distance, height }),
                None,
            ),
            action => {
                if action == FenceAction::Hold {
                    self.held = true;
                    self.apply_hold();
                }
                (
                    None,
                    Some(Notice::FenceBreached {
                        distance,
                        height,
                        action,
                    }),
                )
            }
        }
    }

    /// After this tick's flight step: a rotor found stopped (or reported by its ESC) is flown
    /// without from the next tick and the flight lands; the formation is not re-solved for
    /// the rotors left (the adaptation gives up, a re-formation asked for is dropped).
    /// Says which rotors were found and whether the rotors left hold a level hover once the
    /// full mixer without them flies.
    pub(super) fn watch_rotors(
        &mut self,
        input: &TickInput,
        nav: &NavState,
        thrusts: &[f32; MAX_ROBOTS],
        dt: f32,
    ) {
        let Some(flight) = self.flight.as_mut() else {
            return;
        };
        let n = self.scenario.robots.count();
        let reported = input.faults.rotors_out;
        // A frozen or noisy IMU makes a residual no rotor caused, and so does a pack too low
        // for the voltage compensation to make up (every rotor makes less than asked, the
        // heavily loaded ones most): then only the ESCs' word counts.
        let response_trusted = !input.faults.imu
            && self.imu_detection.is_none()
            && !self.navigator.imu_dropped()
            && !self.compensation.short();
        let Some(found) = flight.watch_rotors(
            nav,
            input.imu.accel,
            &thrusts[..n],
            EscTelemetry {
                rpm: input.esc_rpm.as_ref().map(|r| &r[..n]),
                rpm_per_message: self.config.hardware.esc().is_ok_and(|p| p.on_can_bus()),
                stopped: reported,
            },
            response_trusted,
            dt,
        ) else {
            return;
        };
        if let Some(adapter) = self.adapter.as_mut() {
            adapter.give_up();
        }
        self.pending = None;
        self.outgoing = None;
        // Said once the full mixer without them flies (its job tells whether the rotors left
        // hold the hover): the next tick leaves them out of the mixer, the one after asks for
        // it. Rotors found before and not said yet are said with these.
        let unsaid = match self.rotors_notice {
            Some(Notice::RotorsOut { newly, .. }) => newly,
            _ => 0,
        };
        let newly = found.newly | unsaid;
        self.rotors_notice = Some(Notice::RotorsOut {
            newly,
            earlier: found.out & !newly,
            left: found.left,
            holdable: false,
        });
    }

    /// Raises the rotors' thrusts for a pack that sags below the thrust map's
    /// (`crate::control::voltage_compensation`): the rotors then make what the step asked.
    pub(super) fn compensate_voltage(&mut self, thrusts: &mut [f32; MAX_ROBOTS], dt: f32) {
        let n = self.scenario.robots.count().min(MAX_ROBOTS);
        let max = self.scenario.robots.max_thrust;
        let full = max * n as f32;
        let load = if full > 0.0 {
            thrusts[..n].iter().sum::<f32>() / full
        } else {
            0.0
        };
        let scale = self.compensation.scale(
            &self.config.supervision.pack,
            self.battery.volts(),
            load,
            dt,
        );
        if scale != 1.0 {
            for t in &mut thrusts[..n] {
                *t = crate::math::min(*t * scale, max);
            }
        }
    }
}
