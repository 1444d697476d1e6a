//! `host-sim params`: the vehicle's parameters: every tunable of the mission the
//! firmware serves over MAVLink's parameter protocol, with unit, range, default and what it
//! does, from the table the firmware runs (`shared::mission::params`). The list in
//! docs/ground-link.md is this output (a test keeps the two equal).

use anyhow::Result;
use clap::Args;
use serde_json::json;

use crate::cli::Outcome;
use crate::report::print_json;
use crate::say;

/// Arguments of `params`.
#[derive(Debug, Args)]
pub struct ParamsArgs {
    /// Print one JSON object (`params`: name, unit, min, max, default, integer, doc) instead
    /// of the Markdown table.
    #[arg(long)]
    pub json: bool,
}

/// Runs the command.
pub fn run(args: &ParamsArgs) -> Result<Outcome> {
    use shared::mission::params::{TABLE, markdown_table};
    if args.json {
        let list: Vec<_> = TABLE
            .iter()
            .enumerate()
            .map(|(index, p)| {
                json!({
                    "index": index,
                    "name": p.name,
                    "unit": p.unit,
                    "min": p.min,
                    "max": p.max,
                    "default": p.default_value(),
                    "integer": p.integer,
                    "choices": p.allowed,
                    "doc": p.doc,
                })
            })
            .collect();
        print_json(json!({ "count": TABLE.len(), "params": list }))?;
    } else {
        let mut table = String::new();
        markdown_table(&mut table)?;
        say!("{}", table.trim_end())?;
    }
    Ok(Outcome::Done)
}
