//! `host-sim`: the simulator's command line (docs/formats.md#command-line).
//!
//! Errors print as one line on stderr; nothing panics on bad input. The exit code says how the
//! run ended (docs/commands.md#exit-codes): 0 done, 1 bad input, 2 usage, 3 mission aborted, 4 not
//! delivered, 5 payload dropped. A reader that goes away (`| head -1`) ends the run quietly.

use std::io::Write;
use std::process::ExitCode;

use host_sim::cli::{CliError, EXIT_BAD_INPUT, EXIT_USAGE};

fn main() -> ExitCode {
    match host_sim::cli::run(std::env::args_os()) {
        Ok(outcome) => ExitCode::from(outcome.exit_code()),
        Err(CliError::Usage(e)) => {
            // clap formats help, version and usage errors itself and picks the exit code.
            let _ = e.print();
            ExitCode::from(u8::try_from(e.exit_code()).unwrap_or(EXIT_USAGE))
        }
        Err(CliError::Failed(e)) => {
            if is_broken_pipe(&e) {
                return ExitCode::SUCCESS;
            }
            let line = one_line(&format!("{e:#}"));
            let _ = writeln!(std::io::stderr(), "error: {line}");
            ExitCode::from(EXIT_BAD_INPUT)
        }
    }
}

/// True when `e` comes from writing to a reader that has gone away.
fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|cause| {
        cause
            .downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// Folds a multi-line message into one line.
fn one_line(message: &str) -> String {
    message.split_whitespace().collect::<Vec<_>>().join(" ")
}
