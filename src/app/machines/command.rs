//! The machines' subcommands, built from the registry: one `vibrofem MACHINE [FILE] [-o DIR]
//! [--json]` per entry of [`super::MACHINES`]. The command line's `Cmd` flattens
//! [`MachineCommand`] in, so a new machine needs no line there.

use std::path::PathBuf;

use clap::{Arg, ArgAction, ArgMatches, Command, FromArgMatches, Subcommand};

use super::{CommandArgs, MACHINES, machine, run_command};
use crate::Result;

/// A machine's subcommand as parsed: which machine, its case file, output folder and `--json`.
#[derive(Debug, Clone)]
pub struct MachineCommand {
    /// The machine's command name (`crank-drive`).
    pub command: String,
    /// The case file (`None`: the built-in case).
    pub file: Option<PathBuf>,
    /// Output folder.
    pub out: PathBuf,
    /// Print the JSON report instead of the summary.
    pub json: bool,
}

impl MachineCommand {
    /// Runs it (see [`run_command`]); returns the exit code.
    pub fn run(&self) -> Result<i32> {
        run_command(
            &self.command,
            &CommandArgs {
                file: self.file.as_deref(),
                out: &self.out,
                json: self.json,
            },
        )
    }
}

fn not_a_machine(m: &ArgMatches) -> clap::Error {
    clap::Error::raw(
        clap::error::ErrorKind::InvalidSubcommand,
        format!("not a machine: {:?}", m.subcommand_name()),
    )
}

impl FromArgMatches for MachineCommand {
    fn from_arg_matches(m: &ArgMatches) -> std::result::Result<Self, clap::Error> {
        let (name, sub) = m.subcommand().ok_or_else(|| not_a_machine(m))?;
        machine(name).ok_or_else(|| not_a_machine(m))?;
        Ok(MachineCommand {
            command: name.to_string(),
            file: sub.get_one::<PathBuf>("file").cloned(),
            out: sub.get_one::<PathBuf>("out").cloned().unwrap_or_default(),
            json: sub.get_flag("json"),
        })
    }

    fn update_from_arg_matches(&mut self, m: &ArgMatches) -> std::result::Result<(), clap::Error> {
        *self = Self::from_arg_matches(m)?;
        Ok(())
    }
}

impl Subcommand for MachineCommand {
    fn augment_subcommands(cmd: Command) -> Command {
        MACHINES.iter().fold(cmd, |cmd, m| {
            cmd.subcommand(
                Command::new(m.command)
                    .about(m.about)
                    .arg(
                        Arg::new("file")
                            .value_name("FILE")
                            .value_parser(clap::value_parser!(PathBuf))
                            .help(m.file_help),
                    )
                    .arg(
                        Arg::new("out")
                            .short('o')
                            .long("out")
                            .value_name("OUT")
                            .value_parser(clap::value_parser!(PathBuf))
                            .default_value(m.default_out)
                            .help("Folder for report.md, report.html, report.json and the SVG plots"),
                    )
                    .arg(
                        Arg::new("json")
                            .long("json")
                            .action(ArgAction::SetTrue)
                            .help("Print the JSON report on stdout instead of the summary"),
                    ),
            )
        })
    }

    fn augment_subcommands_for_update(cmd: Command) -> Command {
        Self::augment_subcommands(cmd)
    }

    fn has_subcommand(name: &str) -> bool {
        machine(name).is_some()
    }
}
