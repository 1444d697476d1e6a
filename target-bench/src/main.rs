//! Instruction counts of `shared`'s hot paths on a Cortex-M7 (pair selection well under 10 ms
//! at 480 MHz; the formation solve bounded; one 400 Hz step a few microseconds;
//! docs/firmware.md#optimisation-settings has the goals and the figures).
//!
//! Runs under QEMU's mps2-an500 with `-icount shift=0`, where each instruction advances the
//! virtual clock by 1 ns and SysTick counts the 25 MHz core clock: one tick is 40
//! instructions. A calibration loop of known length checks that ratio before anything is
//! measured. Instructions are not cycles (the M7 dual-issues; flash wait states and FPU
//! latencies add), so the figures are an estimate of the cycle count, printed as
//! instructions and as milliseconds at one instruction per cycle at 480 MHz.
//!
//! `bash .ci/target-bench` builds and runs it.
#![no_std]
#![no_main]

use cortex_m::peripheral::{SYST, syst::SystClkSource};
use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use shared::control::allocation::{Mixer, MixerKind, RotorLayout};
use shared::control::navigator::{ImuSample, MocapFix};
use shared::control::vector::{Quat, Vec3};
use shared::control::vehicle::VehicleModel;
use shared::estimation::{Estimator, EstimatorOptions, Measurement};
use shared::formation::{FormationProblem, solve};
use shared::geometry::Vec2;
use shared::paper;
use shared::scenario::GRAVITY;

/// Instructions per SysTick tick under `-icount shift=0` on mps2-an500.
const INSTRUCTIONS_PER_TICK: u32 = 40;
/// Core clock of the Pixhawk 6C's STM32H743, Hz.
const TARGET_HZ: f32 = 480e6;

struct Timer {
    syst: SYST,
}

impl Timer {
    fn new(mut syst: SYST) -> Self {
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(0x00FF_FFFF);
        syst.clear_current();
        syst.enable_counter();
        Self { syst }
    }

    /// Instructions spent in `f` (SysTick counts down, 24 bits; every measured section is far
    /// shorter than one wrap of 671 million instructions).
    fn instructions<R>(&mut self, f: impl FnOnce() -> R) -> (u32, R) {
        self.syst.clear_current();
        let start = SYST::get_current();
        let r = f();
        let end = SYST::get_current();
        let ticks = start.wrapping_sub(end) & 0x00FF_FFFF;
        (ticks * INSTRUCTIONS_PER_TICK, r)
    }
}

/// [`report`] with the path's budget (docs/firmware.md#optimisation-settings): whether the
/// count is within it.
fn report_against(name: &str, instructions: u32, goal: u32) {
    report(name, instructions);
    hprintln!(
        "    goal <= {} instructions: {}",
        goal,
        if instructions <= goal {
            "met"
        } else {
            "NOT met"
        }
    );
}

fn report(name: &str, instructions: u32) {
    let ms = instructions as f32 / TARGET_HZ * 1e3;
    hprintln!(
        "{}: {} instructions (~{} ms at 480 MHz)",
        name,
        instructions,
        ms
    );
}

#[entry]
fn main() -> ! {
    let peripherals = cortex_m::Peripherals::take();
    let Some(p) = peripherals else { finish(false) };
    let mut timer = Timer::new(p.SYST);

    // Calibration: delay(n) runs n + 1 iterations of a two-instruction loop (subs, bne).
    let (calibration, _) = timer.instructions(|| cortex_m::asm::delay(4_000_000));
    hprintln!("calibration: 8000002 expected, {} counted", calibration);

    // Cost of the scalar math every algorithm leans on (libm through shared::math).
    {
        use core::hint::black_box;
        use shared::math;
        let x = black_box(0.7f32);
        let (n, _) = timer.instructions(|| black_box(math::sqrt(black_box(x))));
        report("math::sqrt", n);
        let (n, _) = timer.instructions(|| black_box(math::sin(black_box(x))));
        report("math::sin", n);
        let (n, _) = timer.instructions(|| black_box(math::acos(black_box(x))));
        report("math::acos", n);
        let (n, _) = timer.instructions(|| black_box(math::atan2(black_box(x), 0.3)));
        report("math::atan2", n);
        let (n, _) = timer.instructions(|| black_box(math::exp(black_box(-x))));
        report("math::exp", n);
        let (n, _) = timer.instructions(|| black_box(math::ln(black_box(x))));
        report("math::ln", n);
        let (n, _) = timer.instructions(|| black_box(math::erfc(black_box(x))));
        report("math::erfc", n);
        let (n, _) = timer.instructions(|| black_box(black_box(x) * 1.5 + 0.25));
        report("multiply-add (timer overhead)", n);
    }

    // MAVLink 2 signing: SHA-256 over the key, the frame and the signature's head, for every
    // frame sent and checked on a signed link (the form of SHA-256 is the build's: unrolled,
    // or compact with `--cfg sha2_backend_soft="compact"`).
    {
        use core::hint::black_box;
        use link::MessageData;
        use link::frame::{Encoder, Frame};
        use link::msg::LOG_DATA_DATA;
        let mut signing = link::signing::Signing::new();
        signing.set_key([7; 32], 1_000_000_000, 0, 1);
        let data = LOG_DATA_DATA {
            ofs: 0,
            id: 0,
            count: 90,
            data: [0x5a; 90],
        };
        let mut frame = Frame::default();
        Encoder::new(1, 1).encode(&data, &mut frame);
        let (n, _) = timer.instructions(|| {
            signing.sign(black_box(&mut frame), LOG_DATA_DATA::EXTRA_CRC, 1_000);
        });
        report("MAVLink 2 signature of a LOG_DATA (102-byte frame)", n);
    }

    // Cost of a mission text with three numbers (the steps that write one are the tick's
    // worst): shared::numbers instead of core's float formatting.
    {
        use core::fmt::Write;
        use core::hint::black_box;
        use shared::numbers::{Fixed, Num, Sci};
        let (x, y, m) = (
            black_box(0.0123f32),
            black_box(-0.0456f32),
            black_box(1.234f32),
        );
        let mut text = TextSink(0);
        let (n, _) = timer.instructions(|| {
            write!(
                text,
                "phase: LIFT: COM ({}, {}) m, mass {} kg",
                Fixed(x, 3),
                Fixed(y, 3),
                Num(m)
            )
        });
        report("text with Fixed, Fixed, Num", n);
        let (n, _) = timer.instructions(|| write!(text, "det {}", Sci(black_box(0.0036f32), 3)));
        report("text with Sci", n);
        black_box(text.0);
    }

    let l_shape = paper::checked(paper::l_sim1());
    let rect = paper::checked(paper::rect_sim1());

    // Estimation: one full pair selection and one update on the L-shape grid.
    for (name, scenario) in [("L-shape", &l_shape), ("rectangle", &rect)] {
        let Ok(mut estimator) = Estimator::new(scenario, EstimatorOptions::default()) else {
            hprintln!("estimator for {} could not start", name);
            finish(false)
        };
        let _ = estimator.update(0, Measurement::Lifted { thrust: 6.0 });
        let _ = estimator.update(3, Measurement::Lifted { thrust: 7.5 });
        let (n, _) = timer.instructions(|| estimator.select_group());
        hprintln!("pair selection, {}:", name);
        if name == "L-shape" {
            report_against("  select", n, 1_000_000);
        } else {
            report("  select", n);
        }
        let (n, _) =
            timer.instructions(|| estimator.update(1, Measurement::Lifted { thrust: 6.5 }));
        if name == "L-shape" {
            report_against("  update", n, 1_000_000);
        } else {
            report("  update", n);
        }
    }

    // Formation decision on the paper's four cases (rect-ex1 and L-sim2: the built-in rails
    // and robots with those cases' COMs) and on twelve robots (rect-sim1 with 12 robots).
    let l_sim2 = with_com(paper::l_sim1(), Vec2::new(0.4, 0.1));
    let rect_ex1 = with_com(paper::rect_sim1(), Vec2::new(0.21, 0.0));
    let mut twelve_input = paper::rect_sim1();
    twelve_input.robots.count = 12;
    twelve_input.robots.spin = &SPIN_12;
    let twelve = paper::checked(twelve_input);
    for (name, scenario) in [
        ("rect-sim1", &rect),
        ("L-sim1", &l_shape),
        ("L-sim2", &l_sim2),
        ("rect-ex1", &rect_ex1),
        ("rect-sim1, 12 robots", &twelve),
    ] {
        let com = scenario.truth.map_or(Vec2::default(), |t| t.com);
        let problem = FormationProblem::for_scenario(scenario, com, Some(&scenario.robots.initial));
        let (n, result) = timer.instructions(|| solve(&problem));
        match result {
            Ok(f) => hprintln!("formation, {} (det {}):", name, f.figures.det),
            Err(_) => hprintln!("formation, {} (no formation):", name),
        }
        report("  solve", n);
    }

    // The mixer rebuild (a job, off the tick) and one 400 Hz tick with 8 rotors.
    let points = shared::paper::RECT_ROTORS;
    let spin = shared::paper::ALTERNATING_SPIN;
    let layout = RotorLayout {
        points: &points,
        spin: &spin,
        com: Vec2::new(0.12, 0.01),
        torque_per_thrust: 0.016,
        max_thrust: 14.2,
    };
    let (n, mixer) = timer.instructions(|| Mixer::build(MixerKind::Allocation, &layout));
    report_against("mixer rebuild (pseudo-inverse), 8 rotors", n, 3_000);
    if mixer.is_err() {
        finish(false)
    }
    // The tick the firmware runs, on eight rotors and on sixteen (every robot the software
    // takes; the worst step's budget holds for both).
    let eight = (&paper::RECT[..], &points[..], &spin[..], 3.5);
    let sixteen = (
        &paper::LONG_RECT[..],
        &paper::LONG_RECT_ROTORS[..],
        &paper::ALTERNATING_SPIN_16[..],
        6.0,
    );
    for (outline, rotors, spins, mass) in [eight, sixteen] {
        tick_figures(&mut timer, outline, rotors, spins, mass);
    }
    rotor_monitor_ticks(&mut timer, &mixer, layout.com, &paper::RECT, &points, 3.5);
    let long_layout = RotorLayout {
        points: &paper::LONG_RECT_ROTORS,
        spin: &paper::ALTERNATING_SPIN_16,
        ..layout
    };
    let long_mixer = Mixer::build(MixerKind::Allocation, &long_layout);
    // A rotor found stopped: the step flies the interim mixer from the next tick (in the step,
    // within the budget's room) and the full one comes from a job (off the step).
    for (label, m) in [("8 rotors", &mixer), ("16 rotors", &long_mixer)] {
        if let Ok(m) = m {
            for (which, out) in [("rotor 2", 1u16 << 2), ("rotors 0 and 5", 0b10_0001)] {
                let mut interim = m.clone();
                let (n, _) = timer.instructions(|| interim.leave_out(out));
                hprintln!("mixer without {}, {}:", which, label);
                report_against("  interim (in the step)", n, 3_000);
                let (n, _) = timer.instructions(|| m.without(out));
                hprintln!("  full (a job): {} instructions", n);
            }
        }
    }
    rotor_monitor_ticks(
        &mut timer,
        &long_mixer,
        layout.com,
        &paper::LONG_RECT,
        &paper::LONG_RECT_ROTORS,
        6.0,
    );
    flight_log_step(&mut timer, &rect);
    finish(true)
}

/// The 400 Hz tick the firmware runs, hovering on `points`: navigator (attitude filter,
/// position observer) and flight stack (plan, nets, cascade, allocation). Two regimes: level
/// hover (the usual case) and an IMU that disagrees with the setpoint so the allocation
/// saturates every step (the worst case: desaturation runs).
fn tick_figures(timer: &mut Timer, outline: &[Vec2], points: &[Vec2], spin: &[i8], mass: f32) {
    const STEPS: u32 = 400;
    let mut results = [(0u64, 0u32, 0u32); 2];
    for (regime, (gyro, accel)) in [
        (Vec3::ZERO, Vec3::new(0.0, 0.0, -9.80665)),
        (Vec3::new(0.3, -0.4, 0.1), Vec3::new(2.0, -1.5, -9.7)),
    ]
    .into_iter()
    .enumerate()
    {
        let Some((mut navigator, mut flight)) =
            paper::hovering_flight_on(MixerKind::Allocation, outline, points, spin, mass)
        else {
            finish(false)
        };
        let mut saturated = 0u32;
        for k in 1..=STEPS {
            let now_us = u64::from(k) * 2500;
            if k % 4 == 0 {
                navigator.motion_capture(&MocapFix {
                    position: Vec3::new(0.0, 0.0, -0.5),
                    attitude: Quat::IDENTITY,
                    stamp_us: now_us,
                });
            }
            let (n, out) = timer.instructions(|| {
                let dt = 0.0025;
                let nav = navigator.update(&ImuSample { gyro, accel }, dt, now_us);
                flight.step(&nav, None, dt)
            });
            saturated += u32::from(out.saturation.any());
            results[regime].0 += u64::from(n);
            results[regime].1 = results[regime].1.max(n);
        }
        if flight.stopped().is_some() {
            hprintln!("the benchmark flight stopped: the figures are not a flight's");
            finish(false)
        }
        results[regime].2 = saturated;
    }
    hprintln!(
        "400 Hz tick (navigator, flight stack), {} rotors:",
        points.len()
    );
    for ((label, goal), (total, worst, saturated)) in
        [("level hover", 5_000), ("saturating", 10_000)]
            .iter()
            .zip(results)
    {
        hprintln!("  {} ({} of {} steps saturated):", label, saturated, STEPS);
        report("    mean", (total / u64::from(STEPS)) as u32);
        report_against("    worst", worst, *goal);
    }
}

/// The rotor monitor's share of a control step (it runs after the flight stack's step), on
/// the mixer above: a steady hover, then one rotor and two at once stopping after the
/// monitor settled. The worst is the tick that judges the change against the rotors' columns
/// and the pairs'.
fn rotor_monitor_ticks(
    timer: &mut Timer,
    mixer: &Result<Mixer, shared::control::allocation::AllocationError>,
    com: Vec2,
    outline: &[Vec2],
    points: &[Vec2],
    mass: f32,
) {
    use shared::flight::rotor_monitor::{MonitorInput, RotorMonitor, RotorMonitorConfig};
    let Ok(mixer) = mixer else { finish(false) };
    let vehicle = VehicleModel::from_payload(outline, com, mass, points, 0.1, 14.2);
    let config = RotorMonitorConfig::DEFAULT;
    let n = mixer.count();
    let dt = 0.0025;
    let hover = vehicle.mass * GRAVITY / n as f32;
    let thrusts = [hover; shared::scenario::MAX_ROBOTS];
    hprintln!(
        "rotor monitor (after the flight stack's step), {} rotors:",
        n
    );
    // One judgement of a change against the rotors' columns: one rotor's loss, then two
    // rotors' (the pairs searched when the collective shows two rotors' loss).
    {
        use shared::flight::rotor_isolation::{
            Columns, Judging, PAIRS_PER_TICK, PairSweep, explain, explain_swept,
        };
        let expected = [hover; shared::scenario::MAX_ROBOTS];
        let columns = Columns::new(
            n,
            mixer.columns_raw(),
            1.0,
            &expected,
            ((1u32 << n) - 1) as u16,
            1.0,
        );
        let loss = |rotors: &[usize]| {
            let mut d = [0.0f32; 3];
            for &j in rotors {
                let a = columns.column(j);
                for r in 0..3 {
                    d[r] -= a[r] * hover;
                }
            }
            d
        };
        for (label, lost, pairs) in [
            ("a drift (single rotors only)", &[2usize][..], false),
            ("one rotor's loss", &[2][..], true),
            ("two rotors' loss", &[0, 5][..], true),
        ] {
            let d = loss(lost);
            let how = Judging {
                sized: true,
                thrust_shown: !pairs,
                pairs,
                decisive: false,
            };
            let (count, named) = timer.instructions(|| explain(&d, &columns, &config, how));
            hprintln!(
                "  judging {} (named {:#b}): {} instructions",
                label,
                named,
                count
            );
            if pairs {
                // The step's search: the pairs a few a tick; its worst tick over a sweep.
                let mut sweep = PairSweep::new();
                let (mut worst, mut named) = (0, 0);
                for _ in 0..(n * n / 2).div_ceil(PAIRS_PER_TICK) + 1 {
                    let (count, found) = timer
                        .instructions(|| explain_swept(&d, &columns, &config, how, &mut sweep));
                    worst = worst.max(count);
                    named = found;
                }
                hprintln!(
                    "    in the step, {} pairs a tick (named {:#b}): worst tick {} instructions",
                    PAIRS_PER_TICK,
                    named,
                    worst
                );
            }
        }
    }
    for (label, lost) in [
        ("steady hover", 0u16),
        ("rotor 3 stops", 1 << 2),
        ("rotors 1 and 6 stop", (1 << 0) | (1 << 5)),
    ] {
        let mut monitor = RotorMonitor::new();
        let mut rate = Vec3::ZERO;
        let (mut total, mut worst, mut ticks, mut named) = (0u64, 0u32, 0u32, 0u16);
        for k in 0..1200u32 {
            let stopped = if k >= 800 { lost } else { 0 };
            let mut lost_thrust = 0.0;
            for j in (0..n).filter(|&j| stopped & (1 << j) != 0) {
                let c = mixer.column(j);
                lost_thrust += c[0] * hover;
                rate.x -= dt * c[1] * hover / vehicle.inertia.x;
                rate.y -= dt * c[2] * hover / vehicle.inertia.y;
            }
            let accel = Vec3::new(
                0.0,
                0.0,
                -(vehicle.mass * GRAVITY - lost_thrust) / vehicle.mass,
            );
            let (count, found) = timer.instructions(|| {
                monitor.update(&MonitorInput {
                    config: &config,
                    mixer,
                    vehicle: &vehicle,
                    com,
                    thrusts: &thrusts[..n],
                    rpm: None,
                    rpm_per_message: false,
                    rate,
                    accel,
                    flying: true,
                    active: true,
                    dt,
                })
            });
            total += u64::from(count);
            worst = worst.max(count);
            ticks += 1;
            if found != 0 {
                named = found;
                break;
            }
        }
        hprintln!("  {} (named {:#b} after {} ticks):", label, named, ticks);
        report("    mean", (total / u64::from(ticks)) as u32);
        report("    worst", worst);
    }
}

/// The flight log's share of a control step (the mission's records, packed into a ring that
/// always has room), hovering with 8 rotors and the cascade's setpoints: the mean over a
/// second of steps and the worst (the step that also writes a slower topic).
fn flight_log_step(timer: &mut Timer, scenario: &shared::scenario::Scenario) {
    use flight_log::session::MissionLog;
    use flight_log::session::STEP_BYTES;
    use flight_log::stream::LogRing;
    use shared::control::trajectory::FlightPhase;
    use shared::mission::{HardwareFaults, Mission, MissionConfig, Phase, Supervision, TickInput};

    /// A ring that always has room and keeps only the count.
    struct Counting {
        space: [u8; STEP_BYTES],
        total: usize,
    }
    impl LogRing for Counting {
        fn step_space(&mut self) -> &mut [u8] {
            &mut self.space
        }
        fn commit_step(&mut self, n: usize, _: bool) {
            self.total += core::hint::black_box(&self.space[..n]).len();
        }
    }

    let mut mission = Mission::new(scenario, MissionConfig::default());
    let mut input = TickInput {
        time_us: 0,
        imu: ImuSample {
            gyro: Vec3::new(0.01, -0.02, 0.003),
            accel: Vec3::new(0.1, -0.05, -9.8),
        },
        mocap: None,
        command: None,
        faults: HardwareFaults::NONE,
        esc_rpm: None,
        supervision: Supervision::NONE,
        manual: shared::manual::ManualSamples::NONE,
    };
    let mut out = mission.step(&input);
    out.phase = Phase::Flying(FlightPhase::Hover);
    out.armed = true;
    out.thrusts[..8].copy_from_slice(&[7.1; 8]);
    out.cascade = Some(shared::flight::CascadeSetpoints {
        attitude: Quat::IDENTITY,
        rate: Vec3::new(0.01, -0.02, 0.0),
        collective: 56.8,
    });
    let mut log = MissionLog::new();
    let mut ring = Counting {
        space: [0; STEP_BYTES],
        total: 0,
    };
    const STEPS: u32 = 400;
    let (mut total, mut worst) = (0u64, 0u32);
    for k in 1..=STEPS + 1 {
        input.time_us = u64::from(k) * 2500;
        input.mocap = (k % 4 == 0).then_some(MocapFix {
            position: Vec3::new(0.0, 0.0, -0.5),
            attitude: Quat::IDENTITY,
            stamp_us: input.time_us,
        });
        let (n, _) = timer.instructions(|| {
            log.step(&input, &out, &mission, 14.2, &mut ring, |_| {});
        });
        // The first step opens the log (its start marker).
        if k > 1 {
            total += u64::from(n);
            worst = worst.max(n);
        }
    }
    hprintln!(
        "flight log, hovering, 8 rotors ({} bytes a second):",
        ring.total
    );
    report("  mean", (total / u64::from(STEPS)) as u32);
    report_against("  worst", worst, 1_000);
    // A step that says something: its text (formatted for the ground already) logged too.
    let said: heapless::String<64> =
        heapless::String::try_from("phase: relax: lifted at 6.47 N per robot").unwrap_or_default();
    let (n, _) = timer.instructions(|| {
        log.step(&input, &out, &mission, 14.2, &mut ring, |sink| {
            sink.text_str(flight_log::ulog::LogLevel::Info, input.time_us, &said)
        });
    });
    report("  a step with a 40-character text", n);
}

/// Alternating spins of twelve robots.
const SPIN_12: [i64; 12] = [1, -1, 1, -1, 1, -1, 1, -1, 1, -1, 1, -1];

/// A built-in case with its truth's COM moved to `com`.
fn with_com(
    mut input: shared::scenario::ScenarioInput<'static>,
    com: Vec2,
) -> shared::scenario::Scenario {
    if let Some(truth) = input.truth.as_mut() {
        truth.com = com;
    }
    paper::checked(input)
}

/// Ends the emulation with success or failure (QEMU's exit code), never returning.
fn finish(success: bool) -> ! {
    debug::exit(if success {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    loop {
        cortex_m::asm::wfi();
    }
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    hprintln!("panic: {}", info);
    finish(false)
}

/// Counts the bytes written to it (a text's cost without a buffer's).
struct TextSink(usize);

impl core::fmt::Write for TextSink {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        self.0 += core::hint::black_box(s).len();
        Ok(())
    }
}
