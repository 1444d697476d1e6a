//! rect-ex1 flown once under QEMU as `host-sim hil --storage DIR --json` (the default seed, the
//! Ethernet link, a fresh storage, no ground station) for the three tests that need that very
//! flight: the firmware's log against the simulator's (`flight_log::storage`), the log
//! downloaded from the firmware restarted on that storage (`flight_log::download`) and the
//! clean run each flooded mission must match (`ground::flood`). They used to fly it once each.
//! Its report and the files it left in the storage are kept in memory; each test gets its own
//! copy, so none sees what another changed (the log download erases the logs).

use crate::common::{qemu_slot, workspace};
use std::ffi::OsString;
use std::path::Path;
use std::process::Command;
use std::sync::OnceLock;
use std::time::Instant;

/// What the flight left: its report and its storage.
pub struct StorageFlight {
    /// `hil --json`'s report.
    pub report: String,
    /// The storage's files, by name (the parameter flash and `log-000.ulg`).
    files: Vec<(OsString, Vec<u8>)>,
}

impl StorageFlight {
    /// The bytes of the storage's file `name`.
    pub fn file(&self, name: &str) -> Option<&[u8]> {
        self.files
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, bytes)| bytes.as_slice())
    }

    /// A copy of the storage in `dir`, made afresh (what was there removed).
    pub fn copy_storage_to(&self, dir: &Path) {
        let _ = std::fs::remove_dir_all(dir);
        std::fs::create_dir_all(dir).expect("a temporary folder");
        for (name, bytes) in &self.files {
            std::fs::write(dir.join(name), bytes).expect("the storage copied");
        }
    }
}

/// The flight, flown by the first test that asks (with a turn at QEMU) while the others wait
/// for it; a flight that failed fails every test that asked, with its reason.
pub fn flown(elf: &Path) -> &'static StorageFlight {
    static FLIGHT: OnceLock<Result<StorageFlight, String>> = OnceLock::new();
    FLIGHT
        .get_or_init(|| fly(elf))
        .as_ref()
        .unwrap_or_else(|why| panic!("{why}"))
}

fn fly(elf: &Path) -> Result<StorageFlight, String> {
    let _slot = qemu_slot();
    let storage = std::env::temp_dir().join(format!("storage-flight-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&storage);
    std::fs::create_dir_all(&storage).map_err(|e| format!("a temporary folder: {e}"))?;
    let started = Instant::now();
    let flight = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .arg("hil")
        .arg("--scenario")
        .arg(workspace().join("tests/scenarios/rect-ex1.toml"))
        .arg("--qemu")
        .arg(elf)
        .arg("--storage")
        .arg(&storage)
        .arg("--json")
        .output()
        .map_err(|e| format!("host-sim cannot be run: {e}"))?;
    if !flight.status.success() {
        return Err(format!(
            "the flight with --storage ({}): {}",
            flight.status,
            String::from_utf8_lossy(&flight.stderr)
        ));
    }
    if !storage.join("log-000.ulg").is_file() {
        return Err(format!("the flight left no log in {}", storage.display()));
    }
    let mut files = Vec::new();
    for entry in std::fs::read_dir(&storage).map_err(|e| format!("the storage: {e}"))? {
        let path = entry.map_err(|e| format!("the storage: {e}"))?.path();
        let bytes = std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        files.push((path.file_name().unwrap_or_default().to_owned(), bytes));
    }
    let _ = std::fs::remove_dir_all(&storage);
    use std::io::Write;
    let _ = writeln!(
        std::io::stderr(),
        "rect-ex1 flown once with --storage (for flight_log::storage, flight_log::download and ground::flood) in {:.1} s",
        started.elapsed().as_secs_f64()
    );
    Ok(StorageFlight {
        report: String::from_utf8_lossy(&flight.stdout).into_owned(),
        files,
    })
}
