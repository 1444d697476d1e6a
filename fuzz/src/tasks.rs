//! The firmware's control task as the harness plays it (`firmware/src/app/control.rs`): one
//! step of the autonomy per IMU sample (the board's driver at rest, or a `HIL_SENSOR`), with
//! what the link queued for it (commands, route changes, a fix, the ground's heartbeat, the
//! plant's battery and rotor speeds), the payload the job task loaded, and the job's result
//! at its deadline; and the invariants of what a step puts out.

use link::command::ack;
use link::hil::{ImuSample, MAX_ROBOTS, MocapFix};
use link::status::{MissionState, PHASE_PREFIX};
use onboard::autonomy::{CommandResult, Severity, StepInput, StepOutput, TickInput};
use onboard::link_service::mav_result;
use shared::control::vector::{Quat, Vec3};
use shared::mission::{HardwareFaults, Supervision};

use crate::vehicle::{TICK_US, Vehicle};

/// Phases whose rotors may be armed (by their names in `phase: NAME: reason` texts).
const ARMED_PHASES: [&str; 7] = [
    "lift",
    "arming",
    "takeoff",
    "trajectory",
    "hover",
    "landing",
    "touchdown",
];
/// Phases whose rotors may push (armed, not idling on the ground before take-off).
const THRUST_PHASES: [&str; 6] = [
    "lift",
    "takeoff",
    "trajectory",
    "hover",
    "landing",
    "touchdown",
];
/// Phases of a mission that is not running (idle, or over).
const STOPPED_PHASES: [&str; 3] = ["idle", "disarmed", "aborted"];

impl Vehicle {
    fn faults(&self) -> HardwareFaults {
        if self.frames < u32::from(self.options.faults_from) {
            return HardwareFaults::NONE;
        }
        HardwareFaults {
            imu: self.options.imu_fault,
            stalled_robots: u16::from(self.options.stalled_robots),
            rotors_out: 0,
        }
    }

    /// A step of the board's IMU driver: a sample at rest on the board's clock.
    pub(crate) fn driver_step(&mut self) {
        self.driver_steps += 1;
        self.io.now_us += TICK_US;
        if self.options.mocap {
            self.io.mocap = Some(MocapFix {
                stamp_us: self.io.now_us,
                position: Vec3::ZERO,
                attitude: Quat::IDENTITY,
            });
        }
        let imu = ImuSample {
            // A real sensor never repeats itself: the mission's IMU monitor stops on one that
            // does (shared::control::imu_monitor), so the driver's rest has a little noise.
            gyro: Vec3::new(0.0, 0.0, crate::rest_noise(self.driver_steps)),
            accel: Vec3::new(0.0, 0.0, -shared::scenario::GRAVITY),
        };
        self.control_step(self.io.now_us, imu, false);
        self.heartbeat_due();
    }

    /// control.rs: one step of the autonomy on an IMU sample.
    pub(crate) fn control_step(&mut self, time_us: u64, imu: ImuSample, hil: bool) {
        let Ok(step) = self.clock.on_sensor(time_us) else {
            self.report_text(Severity::Error, "sensor refused");
            return;
        };
        self.steps += 1;
        self.io.in_hil = hil;
        let job = if self.deadline.is_due(step.index) {
            self.deadline.taken();
            // The job ran at once: in lockstep the step would wait for it, off HIL it is in.
            match self.job_result.take() {
                Some((id, result)) if id == self.job_id => Some(result),
                _ => None,
            }
        } else {
            None
        };
        // The payload goes to the autonomy before the step, as the firmware's control task
        // hands it over.
        let payload = self.payload.take();
        let loaded_config = payload.as_ref().map(|p| p.config);
        let loads_payload = payload.is_some();
        if let Some(p) = payload {
            self.autonomy.take_payload(p.scenario, p.config);
        }
        if let Some(result) = job {
            self.autonomy.deliver_job(result);
        }
        let pending = self.io.commands.pop_front();
        let route = self.io.routes.pop_front();
        let tick = TickInput {
            time_us: step.time_us,
            imu,
            mocap: self.io.mocap.take(),
            command: pending.map(|p| p.command),
            faults: if hil {
                HardwareFaults::NONE
            } else {
                self.faults()
            },
            // The plant's RPM in HIL; no ESC telemetry off HIL (no board here).
            esc_rpm: if hil {
                self.io.esc_rpm.rpm_at(step.time_us)
            } else {
                None
            },
            supervision: Supervision {
                gcs_heartbeat: core::mem::take(&mut self.io.gcs_heartbeat),
                // The plant's pack in HIL; off HIL the board's ADC (none on the host).
                battery_volts: match self.io.battery_mv {
                    u32::MAX => None,
                    mv if hil => Some(mv as f32 * 1e-3),
                    _ => None,
                },
            },
            // The joystick's newest `MANUAL_CONTROL`, as the firmware's control task takes it.
            manual: shared::manual::ManualSamples {
                rc: None,
                joystick: self.io.manual.take(),
            },
        };
        let input = StepInput {
            tick,
            step: step.index,
            // The job task runs each load to the end before the next frame here.
            loading: false,
            route: route.as_ref(),
            // The parameters' IMU offsets and hardware settings, as the firmware's control
            // task hands them over after a change.
            // (Not in a step that loads a payload: the settings go in the next.)
            bench: if loads_payload {
                None
            } else {
                core::mem::take(&mut self.io.config_changed).then(|| (&self.io.config).into())
            },
        };
        let mut out = self.autonomy.tick(&input);
        if let Some(config) = loaded_config
            && !out.report.texts.iter().any(|t| t.text.contains("ignored"))
        {
            // Loaded: the mission is idle again, without a transition.
            assert_eq!(
                config, self.io.config,
                "the payload came with stale parameters"
            );
            self.phase = "idle".into();
        }
        for line in &out.report.texts {
            if let Some(rest) = line.text.strip_prefix(PHASE_PREFIX) {
                let name = rest.split(':').next().unwrap_or_default();
                self.phase = name.to_string();
                self.phase_since = self.steps;
                self.phases.push(rest.to_string());
            }
        }
        self.check_output(&out);
        if let Some(request) = out.job.take() {
            let next_id = self.job_id.wrapping_add(1);
            match self.deadline.request(step.index, request.deadline_steps) {
                Ok(_) => {
                    self.job_id = next_id;
                    let result = onboard::autonomy::run_job(&mut self.planner, &request.work);
                    self.job_result = Some((next_id, result));
                }
                Err(_) => {
                    self.deadline.taken();
                    out.report
                        .text(Severity::Error, format_args!("job refused: busy"));
                }
            }
        }
        self.io.mission_state = out.state;
        self.io.armed = out.armed;
        // A calibration's offsets go to the link's service to store (the firmware's
        // `CALIBRATED`), taken at its next poll.
        if let Some((_, Some(offsets))) = out.calibrated {
            self.io.calibrated = Some(offsets);
        }
        // Every command is acknowledged.
        if let Some(p) = pending {
            let result = out.ack.map_or(CommandResult::Accepted, |(given, result)| {
                assert_eq!(given, p.command, "the ack is for another command");
                result
            });
            self.send(&ack(p.mav_cmd, mav_result(result)));
        }
        let time_ms = (step.time_us / 1000) as u32;
        self.send_report(&out.report, time_ms);
        if hil {
            let actuators = link::hil::Actuators {
                time_us: step.time_us,
                robots: out.robots,
                thrust: out.thrust,
                rail: out.rail,
                armed: out.armed,
            };
            let messages = actuators.to_messages();
            if let Some(status) = &messages.status {
                self.send(status);
            }
            self.send(&messages.controls);
        }
    }

    fn check_output(&self, out: &StepOutput) {
        assert!(out.robots <= MAX_ROBOTS);
        for j in 0..MAX_ROBOTS {
            let (t, r) = (out.thrust[j], out.rail[j]);
            assert!((0.0..=1.0).contains(&t), "thrust {j} is {t}");
            assert!(r.is_finite(), "rail setpoint {j} is {r}");
            if j >= out.robots {
                assert_eq!((t, r), (0.0, 0.0), "an output past the robots in use");
            }
        }
        let pushing = out.thrust.iter().any(|&t| t > 0.0);
        let phase = self.phase.as_str();
        if out.motor_test {
            assert!(out.armed, "a motor test disarmed");
            assert_ne!(
                out.state,
                MissionState::Running,
                "a motor test in the mission"
            );
            return;
        }
        // After a lift the rotors set the payload down, armed, for the set-down's first second
        // of the relax phase, their thrusts falling.
        let setting_down = phase == "relax"
            && (self.steps - self.phase_since) as f32 * TICK_US as f32 * 1e-6
                <= shared::mission::SET_DOWN_TIME + 2e-3;
        assert_eq!(
            out.armed,
            ARMED_PHASES.contains(&phase) || (setting_down && out.armed),
            "armed {} in phase {phase} (phases so far {:?}, this step's texts {:?})",
            out.armed,
            self.phases,
            out.report
                .texts
                .iter()
                .map(|t| t.text.as_str())
                .collect::<Vec<_>>()
        );
        assert!(
            !pushing || THRUST_PHASES.contains(&phase) || setting_down,
            "thrust in phase {phase}"
        );
        assert!(out.armed || !pushing, "thrust while disarmed");
        let stopped = out.state != MissionState::Running;
        assert_eq!(
            stopped,
            STOPPED_PHASES.contains(&phase),
            "state {:?} in phase {phase}",
            out.state
        );
        assert!(!(stopped && out.armed), "armed while {:?}", out.state);
    }
}
