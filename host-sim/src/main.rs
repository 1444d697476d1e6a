//! `host-sim`: the simulator's command line (SPEC.md section 5).
//!
//! Errors print as one line on stderr with a non-zero exit code; nothing panics on bad input.

use std::process::ExitCode;

fn main() -> ExitCode {
    match host_sim::cli::run(std::env::args_os()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(host_sim::cli::CliError::Usage(e)) => {
            // clap formats help, version and usage errors itself and picks the exit code.
            let _ = e.print();
            ExitCode::from(u8::try_from(e.exit_code()).unwrap_or(2))
        }
        Err(host_sim::cli::CliError::Failed(e)) => {
            eprintln!("error: {}", one_line(&format!("{e:#}")));
            ExitCode::FAILURE
        }
    }
}

/// Folds a multi-line message into one line.
fn one_line(message: &str) -> String {
    message.split_whitespace().collect::<Vec<_>>().join(" ")
}
