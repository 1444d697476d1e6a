//! The control task: one step of the autonomy per IMU sample, at the highest priority.
//!
//! In hardware-in-the-loop the sample is the plant's `HIL_SENSOR` and the vehicle's clock is
//! its time (PX4 lockstep): the step runs when it arrives and its reply, the actuator
//! commands, goes back over the link; the physical outputs stay disarmed. A job's result is
//! handed to the autonomy in the step at the job's deadline: if the job is not done by then,
//! the step waits for it in HIL (the plant waits for the reply, so nothing is late), and on
//! real hardware the step goes on without it and says so.
//!
//! Off HIL the step never waits on the link: a step whose messages find the send queue full
//! loses them (counted, `tlm_drop`). In HIL it waits, as the plant waits for its reply.
//!
//! Each step's cost (board cycle counter: instructions under QEMU `-icount`, cycles on the
//! Pixhawk), the wait for a job excluded, is tracked; the worst so far goes out once a second
//! of vehicle time as a `NAMED_VALUE_INT` named by the board (`tick_insn` under QEMU).

use core::sync::atomic::Ordering;
use shared::manual::ManualSamples;

use link::hil::{Actuators, JobDeadline, VehicleClock};

use super::autonomy::{Autonomy, CommandResult, Severity, StepInput, StepOutput, TickInput, Value};
use super::comms::{Outbound, SensorSample, StepMessages};
use super::logger::RingEnd;
use super::{
    ARMED, BENCH_CONFIG, CALIBRATED, COMMANDS, CONFIG_CHANGED, GCS_HEARTBEAT, IDLE_COUNTS, IN_HIL,
    JOB_REQUESTS, JOB_RESULTS, LINK_BATTERY_MV, LOADING, MISSION_STATE, MOCAP, OUTBOX, PAYLOAD,
    ROUTE, ROUTE_SENT, SENSOR, STATUS_CHANGES, STEP_OUT, VEHICLE,
};
use crate::board::{ActuatorOutputs, Board, Selected};
use shared::mission::{HardwareFaults, Supervision};

/// Steps between reports of the worst step cost (1 s at 400 Hz).
const COST_REPORT_STEPS: u64 = 400;

/// Runs the autonomy on every IMU sample, forever.
#[embassy_executor::task]
pub async fn control(autonomy: &'static mut Autonomy, mut outputs: <Selected as Board>::Outputs) {
    let mut clock = VehicleClock::new();
    let mut deadline = JobDeadline::new();
    let mut worst_cost: u32 = 0;
    // The worst step of this second, and of the last (the load `SYS_STATUS` reports).
    let mut second_worst: u32 = 0;
    let mut load_permille: u16 = 0;
    let mut holds: u32 = 0;
    // Steps whose messages found the link's queue full (off HIL only).
    let mut dropped_reports: u32 = 0;
    // Number of the last job asked for; results of other (late, dropped) jobs are discarded.
    let mut job_id: u32 = 0;
    // The cycle counter at the last busy-time report.
    let mut busy_since = <Selected as Board>::cycle_count();
    // The flight log's end of the ring (this task is its only writer).
    // The flight log's end of the ring (this task is its only writer).
    let mut log_ring = RingEnd::new();
    // The calibration under way: its command, for the acknowledgement of its end.
    let mut calibrating: Option<super::comms::PendingCommand> = None;
    // The last step had ESC RPM.
    let mut had_esc_rpm = false;
    loop {
        let sample: SensorSample = SENSOR.receive().await;
        if sample.hil {
            // The plant waits for this step: the flight log's ring gets room for it first (a
            // wait of the logger's, not the step's), so a HIL log is whole and the same as the
            // simulator's however the host's load paces QEMU.
            log_ring.wait_for_room().await;
        }
        let start = <Selected as Board>::cycle_count();
        let step = match clock.on_sensor(sample.time_us) {
            Ok(step) => step,
            Err(e) => {
                let mut out = StepOutput::new();
                out.report
                    .text(Severity::Error, format_args!("sensor refused: {e}"));
                let _ = OUTBOX.try_send(Outbound::Report(out.report));
                continue;
            }
        };
        IN_HIL.store(sample.hil, Ordering::Relaxed);

        // The job's result, in exactly the step at its deadline, handed straight from its
        // channel to the autonomy: a result (up to the 2.8 KB flight model) never crosses a wait
        // or a return, whose copies would cost the step over 1,000 instructions each.
        let mut held_counts: u32 = 0;
        let mut late = false;
        if deadline.is_due(step.index) {
            deadline.taken();
            let mut delivered = deliver_result(job_id, autonomy);
            if !delivered && sample.hil {
                // In lockstep the step waits for it: the wait is the job's time, not the step's.
                holds += 1;
                while !delivered {
                    let before = <Selected as Board>::cycle_count();
                    JOB_RESULTS.ready_to_receive().await;
                    held_counts = held_counts
                        .wrapping_add(<Selected as Board>::cycle_count().wrapping_sub(before));
                    delivered = deliver_result(job_id, autonomy);
                }
            }
            // Off HIL the step cannot wait: the result, when it comes, is dropped.
            late = !delivered;
        }

        // The step itself, in a block of its own: its payload, input and output (4 KB) are
        // gone before the wait for the link's queue below, so the task's future (a static)
        // does not keep them.
        let message = {
            // The flag before the payload: a description offered before the flag was cleared is
            // in the channel by then.
            let loading = LOADING.load(Ordering::SeqCst);
            let payload = PAYLOAD.try_receive().ok();
            let loads_payload = payload.is_some();
            if let Some(p) = payload {
                autonomy.take_payload(p.scenario, p.config);
            }
            let pending = COMMANDS.try_receive().ok();
            let route = if ROUTE_SENT.load(Ordering::Acquire) {
                let change = ROUTE.try_receive().ok();
                if ROUTE.is_empty() {
                    ROUTE_SENT.store(false, Ordering::Release);
                }
                change
            } else {
                None
            };
            let tick = TickInput {
                time_us: step.time_us,
                imu: sample.imu,
                mocap: MOCAP.try_take(),
                command: pending.map(|p| p.command),
                faults: if sample.hil {
                    HardwareFaults::NONE
                } else {
                    <Selected as Board>::hardware_faults()
                },
                // In HIL the plant's RPM; on a board its ESCs' (bidirectional DShot).
                esc_rpm: if sample.hil {
                    super::LINK_ESC_RPM.lock(|inbox| inbox.borrow().rpm_at(step.time_us))
                } else {
                    <Selected as Board>::esc_rpm()
                },
                supervision: Supervision {
                    gcs_heartbeat: GCS_HEARTBEAT.swap(false, Ordering::Relaxed),
                    // In HIL the plant's pack; on a board its own measurement.
                    battery_volts: if sample.hil {
                        match LINK_BATTERY_MV.load(Ordering::Relaxed) {
                            u32::MAX => None,
                            mv => Some(link::vehicle::volts_of(mv)),
                        }
                    } else {
                        <Selected as Board>::battery_volts()
                    },
                },
                // The RC receiver's newest frame (docs/hardware.md#rc-receivers) and a ground
                // station's joystick (`MANUAL_CONTROL`), each its newest sample.
                manual: ManualSamples {
                    rc: super::RC_INPUT.try_take(),
                    joystick: super::MANUAL.try_take(),
                },
            };
            let input = StepInput {
                tick,
                step: step.index,
                loading,
                route: route.as_ref(),
                // The flag first: parameters set after it are in the configuration read. Not
                // in a step that loads a payload (at boot both wait): the two in one step
                // exceed its budget, and the settings go in the next.
                bench: if !loads_payload && CONFIG_CHANGED.load(Ordering::Acquire) {
                    CONFIG_CHANGED.store(false, Ordering::Release);
                    Some(BENCH_CONFIG.lock(|c| c.get()))
                } else {
                    None
                },
            };
            // The RPM for the ground station: written only while there is some, and once
            // when it ends (a vehicle without ESC telemetry pays nothing).
            if input.tick.esc_rpm.is_some() || had_esc_rpm {
                super::ESC_RPM.lock(|r| r.set(input.tick.esc_rpm));
                had_esc_rpm = input.tick.esc_rpm.is_some();
            }
            let imu_failed = input.tick.faults.imu;
            // Written in place: its texts and telemetry are never copied on a return.
            let mut out = StepOutput::new();
            autonomy.tick_into(&input, &mut log_ring, &mut out);
            if late {
                out.report
                    .text(Severity::Critical, format_args!("job late at its deadline"));
            }
            if let Some(request) = out.job.take() {
                let next_id = job_id.wrapping_add(1);
                match deadline.request(step.index, request.deadline_steps) {
                    Ok(_) if JOB_REQUESTS.try_send((next_id, request)).is_ok() => job_id = next_id,
                    _ => {
                        deadline.taken();
                        out.report.text(
                            Severity::Error,
                            format_args!("job refused: another job is still running"),
                        );
                    }
                }
            }
            if sample.hil {
                // In HIL the plant flies the commands; the real outputs stay off.
                outputs.apply(&[], &[], false);
            } else {
                outputs.apply(
                    &out.thrust[..out.robots],
                    &out.rail[..out.robots],
                    out.armed,
                );
            }
            MISSION_STATE.store(out.state as u8, Ordering::SeqCst);
            ARMED.store(out.armed, Ordering::Relaxed);

            let cost = <Selected as Board>::cycle_count()
                .wrapping_sub(start)
                .wrapping_sub(held_counts)
                .saturating_mul(<Selected as Board>::TICK_COST_PER_COUNT);
            worst_cost = worst_cost.max(cost);
            second_worst = second_worst.max(cost);
            if step.index % COST_REPORT_STEPS == 0 {
                let period = u64::from(<Selected as Board>::TICK_PERIOD_COST.max(1));
                load_permille = (u64::from(second_worst) * 1000 / period).min(1000) as u16;
                second_worst = 0;
            }
            let mut snapshot = out.telemetry;
            snapshot.time_us = step.time_us;
            snapshot.imu_healthy = !imu_failed;
            snapshot.load_permille = load_permille;
            VEHICLE.lock(|v| v.set(snapshot));
            if out.status_changed {
                // One writer: a load and a store.
                let changes = STATUS_CHANGES.load(Ordering::Relaxed);
                STATUS_CHANGES.store(changes.wrapping_add(1), Ordering::Release);
            }
            if held_counts > 0 {
                out.report.value("job_holds", Value::Int(holds as i32));
            }
            if dropped_reports > 0 && step.index % COST_REPORT_STEPS == 0 {
                out.report
                    .value("tlm_drop", Value::Int(dropped_reports as i32));
            }
            if step.index % COST_REPORT_STEPS == 0 || out.state.is_over() {
                out.report.value(
                    <Selected as Board>::TICK_COST_NAME,
                    Value::Int(worst_cost.min(i32::MAX as u32) as i32),
                );
            }
            if step.index % COST_REPORT_STEPS == 0 {
                let now = <Selected as Board>::cycle_count();
                let idle = IDLE_COUNTS.swap(0, Ordering::Relaxed);
                let busy = now.wrapping_sub(busy_since).saturating_sub(idle);
                busy_since = now;
                out.report.value(
                    <Selected as Board>::BUSY_COST_NAME,
                    Value::Int(
                        busy.saturating_mul(<Selected as Board>::TICK_COST_PER_COUNT)
                            .min(i32::MAX as u32) as i32,
                    ),
                );
            }
            let actuators = Actuators {
                time_us: step.time_us,
                robots: out.robots,
                thrust: out.thrust,
                rail: out.rail,
                armed: out.armed,
            };
            // A calibration's first acknowledgement says in progress; its end says how.
            let mut done = None;
            if let Some((result, offsets)) = out.calibrated {
                if let Some(offsets) = offsets {
                    // The receive task stores them; one calibration at a time, so room.
                    let _ = CALIBRATED.try_send(offsets);
                }
                done = calibrating.take().map(|p| (p, result));
            }
            let ack = pending.map(|p| {
                (
                    p,
                    out.ack
                        .map_or(CommandResult::Accepted, |(_, result)| result),
                )
            });
            if let Some((p, CommandResult::InProgress)) = ack {
                calibrating = Some(p);
            }
            StepMessages {
                time_us: step.time_us,
                report: out.report,
                // Every command is acknowledged; one the autonomy took without a word is accepted.
                ack,
                done,
                state: out.state,
                actuators: sample.hil.then_some(actuators),
            }
        };
        if sample.hil {
            // The plant waits for this reply: it must go, and nothing else is waiting.
            STEP_OUT.send(message).await;
        } else if STEP_OUT.try_send(message).is_err() {
            // In flight the step never waits for the link: this step's telemetry is lost.
            dropped_reports = dropped_reports.wrapping_add(1);
        }
    }
}

/// Hands job `id`'s result to `autonomy` if it is in (results of earlier jobs are dropped);
/// whether it was.
fn deliver_result(id: u32, autonomy: &mut Autonomy) -> bool {
    while let Ok((got, result)) = JOB_RESULTS.try_receive() {
        if got == id {
            autonomy.deliver_job(result);
            return true;
        }
    }
    false
}
