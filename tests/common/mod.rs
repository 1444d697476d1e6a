//! Helpers the test binaries (`tests/simulation`, `tests/hil`, `tests/tools`) share: where the
//! scenario files are, loading one, running the `host-sim` binary, the flight log's helpers
//! ([`ulog`]), and the firmware-in-the-loop tests' image, their turns at QEMU and skipping (a
//! test that needs a missing tool says it was skipped and why; with `HIL_REQUIRED=1`, CI, it
//! fails).
#![allow(dead_code)] // each test binary uses its own subset

pub mod ulog;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The paper's cases (docs/system.md#paper-cases), by their files' names in `tests/scenarios/`.
pub const PAPER_CASES: [&str; 6] = [
    "rect-sim1",
    "rect-sim2",
    "L-sim1",
    "L-sim2",
    "rect-ex1",
    "rect-ex2",
];

/// Path of `tests/scenarios/<name>.toml`.
pub fn scenario_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/scenarios")
        .join(format!("{name}.toml"))
}

/// A paper scenario, read and checked.
pub fn load(name: &str) -> shared::scenario::Scenario {
    host_sim::scenario_file::load(&scenario_path(name))
        .expect("paper scenario")
        .scenario
}

/// Runs the `host-sim` binary with `args`.
pub fn host_sim(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(args)
        .output()
        .expect("host-sim runs")
}

/// The repository's root.
pub fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Why a firmware-in-the-loop test is skipped on a machine without QEMU.
pub const NO_QEMU: &str =
    "qemu-system-arm is not installed (Debian: apt-get install qemu-system-arm)";

/// Says that `test` was skipped for `reason` (counted for the process's closing line), or,
/// with `HIL_REQUIRED=1`, fails it.
pub fn skip(test: &str, reason: &str) {
    if std::env::var("HIL_REQUIRED").is_ok_and(|v| v == "1") {
        panic!("{test}: HIL_REQUIRED=1 but {reason}");
    }
    host_sim::hil::qemu::note_skipped(reason == NO_QEMU);
    // Straight to stderr: the test harness hides what `eprintln!` prints in a passing test.
    use std::io::Write;
    let _ = writeln!(std::io::stderr(), "{test}: SKIPPED: {reason}");
}

/// With `HIL_LOAD=N` in the environment, `N` threads (0 or not a number: one per core) spin
/// from the first firmware-in-the-loop test on, for as long as the test process runs: the HIL
/// tests then run as on a loaded CI machine (QEMU, the plant and the ground station starved of
/// their cores), so a test that races the vehicle fails on a developer's machine rather than
/// now and then in CI (docs/build.md#tests-under-load).
pub fn load_if_asked() {
    static LOAD: std::sync::Once = std::sync::Once::new();
    let Ok(asked) = std::env::var("HIL_LOAD") else {
        return;
    };
    LOAD.call_once(|| {
        let cores = std::thread::available_parallelism().map_or(2, |n| n.get());
        let threads = asked.trim().parse::<usize>().ok().filter(|&n| n > 0);
        let threads = threads.unwrap_or(cores);
        use std::io::Write;
        let _ = writeln!(
            std::io::stderr(),
            "HIL_LOAD: {threads} spinning threads load the machine's {cores} cores"
        );
        for _ in 0..threads {
            std::thread::spawn(|| {
                let mut x = 0u64;
                loop {
                    x = std::hint::black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
                }
            });
        }
    });
}

/// The firmware's QEMU image if `test` can run (built first when it is missing or stale);
/// otherwise [`skip`]s it. Starts the load `HIL_LOAD` asks for ([`load_if_asked`]).
pub fn image_or_skip(test: &str) -> Option<PathBuf> {
    load_if_asked();
    let reason = if host_sim::hil::qemu::available() {
        match host_sim::hil::qemu::test_image(&workspace()) {
            Ok(elf) => return Some(elf),
            Err(why) => why,
        }
    } else {
        NO_QEMU.to_string()
    };
    skip(test, &reason);
    None
}

/// Firmware-in-the-loop runs at once in a test process when `HIL_JOBS` does not say: each is
/// a QEMU and its plant in lockstep (and the ground station's script, if any), which take
/// turns at the processor and keep about one core busy between them, or less when the run is
/// paced to a multiple of real time. Two keep a two-core machine busy.
pub const DEFAULT_HIL_JOBS: usize = 2;

/// A turn at QEMU, held for as long as the guard lives ([`qemu_slot`]).
pub struct QemuSlot(());

static SLOTS_TAKEN: std::sync::Mutex<usize> = std::sync::Mutex::new(0);
static SLOT_FREED: std::sync::Condvar = std::sync::Condvar::new();

/// How many firmware-in-the-loop runs may go at once: `HIL_JOBS=N` (at least 1; 1 runs them
/// one after the other), else [`DEFAULT_HIL_JOBS`].
pub fn hil_jobs() -> usize {
    std::env::var("HIL_JOBS")
        .ok()
        .and_then(|v| v.trim().parse::<usize>().ok())
        .map_or(DEFAULT_HIL_JOBS, |n| n.max(1))
}

/// Waits for a turn at QEMU: every test that starts the firmware holds one while it runs, so
/// that no more than [`hil_jobs`] run at once (libtest runs a binary's tests side by side).
pub fn qemu_slot() -> QemuSlot {
    let limit = hil_jobs();
    let mut taken = SLOTS_TAKEN.lock().unwrap_or_else(|e| e.into_inner());
    while *taken >= limit {
        taken = SLOT_FREED.wait(taken).unwrap_or_else(|e| e.into_inner());
    }
    *taken += 1;
    QemuSlot(())
}

impl Drop for QemuSlot {
    fn drop(&mut self) {
        let mut taken = SLOTS_TAKEN.lock().unwrap_or_else(|e| e.into_inner());
        *taken -= 1;
        SLOT_FREED.notify_one();
    }
}

/// Exit status of the Python checks when a package they need is missing (the one line on
/// their stderr says which and how to install it).
pub const PYTHON_PACKAGE_MISSING: i32 = 2;

/// Runs the Python check `script` (in tests/ or examples/) against the firmware's QEMU image
/// on rect-ex1 through `host-sim hil --gcs`; [`skip`]s `test` when QEMU, python3 or a package
/// is missing, fails it with the script's output when a check fails, and prints what the
/// script said when all held.
pub fn python_check(test: &str, script: &str) {
    if let Some(elf) = image_or_skip(test) {
        run_python_check(test, script, &elf, &[]);
    }
}

/// Longest a Python check may run, s: a backstop only (each check's own waits are bounded
/// and say what they waited for); past it the check and everything it started (the plant,
/// QEMU, MAVProxy, mavsdk_server) are killed and the test fails saying so, rather than hold
/// CI until its own limit.
const PYTHON_CHECK_LIMIT_S: u64 = 900;

/// [`python_check`] with the image `elf` already at hand and `extra` arguments for the script;
/// waits for a turn at QEMU ([`qemu_slot`]) first.
pub fn run_python_check(test: &str, script: &str, elf: &Path, extra: &[&std::ffi::OsStr]) {
    use std::os::unix::process::CommandExt;
    use std::process::Stdio;
    let _slot = qemu_slot();
    let child = Command::new("python3")
        .arg(workspace().join(script))
        .arg("--host-sim")
        .arg(env!("CARGO_BIN_EXE_host-sim"))
        .arg("--elf")
        .arg(elf)
        .arg("--scenario")
        .arg(workspace().join("tests/scenarios/rect-ex1.toml"))
        .args(extra)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        // Its own process group, so that the backstop ends whatever it started too.
        .process_group(0)
        .spawn();
    let child = match child {
        Ok(child) => child,
        Err(e) => return skip(test, &format!("python3 cannot be run ({e})")),
    };
    let pid = child.id() as libc::pid_t;
    let (done, finished) = std::sync::mpsc::channel();
    let waiter = std::thread::spawn(move || {
        let output = child.wait_with_output();
        let _ = done.send(());
        output
    });
    let limit = std::time::Duration::from_secs(PYTHON_CHECK_LIMIT_S);
    let timed_out = finished.recv_timeout(limit).is_err();
    if timed_out {
        // SAFETY: a signal to the process group this test started.
        unsafe { libc::killpg(pid, libc::SIGKILL) };
    }
    let output = match waiter.join() {
        Ok(Ok(output)) => output,
        Ok(Err(e)) => panic!("{test}: its output could not be read ({e})"),
        Err(_) => panic!("{test}: the thread reading its output failed"),
    };
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        !timed_out,
        "{test} still running after {PYTHON_CHECK_LIMIT_S} s, killed; it had said:\n{stdout}\n{stderr}"
    );
    if output.status.code() == Some(PYTHON_PACKAGE_MISSING) {
        return skip(test, stderr.trim());
    }
    assert!(
        output.status.success(),
        "{test} failed ({}):\n{stdout}\n{stderr}",
        output.status
    );
    use std::io::Write;
    let _ = writeln!(std::io::stderr(), "{stdout}");
}
