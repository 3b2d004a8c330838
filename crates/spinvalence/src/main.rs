//! `spinvalence`: the command line of the Spin-Valence frame tools.
//!
//! Thin by design: parse arguments ([`cli`]), call the library crates, print, and map
//! errors to exit codes. Exit codes: 0 success, 1 `check` found a violation, 2 bad input
//! or usage (or unmet goals with `build --strict`), 3 `build` wrote what it could make but
//! some goals are not met. Every error is one line on stderr: `error: what and
//! where`.

mod build;
mod check;
mod cli;
mod config;
mod nest;
mod output;
mod report;
mod serve;
mod sheets;
mod solve;
mod strips;

use std::process::ExitCode;

use anyhow::Result;
use clap::error::ErrorKind;
use clap::Parser;

use cli::{Cli, Command};

/// Exit code of a failed `check`.
const EXIT_VIOLATION: u8 = 1;
/// Exit code of bad input or usage.
const EXIT_ERROR: u8 = 2;
/// Exit code of a build that wrote what it could make with some goals unmet.
const EXIT_UNMET: u8 = 3;

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(err) => return clap_exit(err),
    };
    match run(&cli) {
        Ok(code) => code,
        Err(err) => {
            eprintln!("error: {}", one_line(&err));
            ExitCode::from(EXIT_ERROR)
        }
    }
}

/// The error and its causes on one line, like `{:#}`, but without repeating a cause whose
/// text its parent already contains (library errors often interpolate their source).
fn one_line(err: &anyhow::Error) -> String {
    let mut message = String::new();
    for cause in err.chain() {
        let text = cause.to_string();
        if message.contains(&text) {
            continue;
        }
        if !message.is_empty() {
            message.push_str(": ");
        }
        message.push_str(&text);
    }
    message.replace(['\n', '\r'], " ")
}

fn run(cli: &Cli) -> Result<ExitCode> {
    match &cli.command {
        Command::Solve(args) => {
            solve::run(args)?;
            Ok(ExitCode::SUCCESS)
        }
        Command::Check(args) => Ok(if check::run(args)? {
            ExitCode::SUCCESS
        } else {
            ExitCode::from(EXIT_VIOLATION)
        }),
        Command::Nest(args) => {
            nest::run(args)?;
            Ok(ExitCode::SUCCESS)
        }
        Command::Serve(args) => {
            serve::run(args)?;
            Ok(ExitCode::SUCCESS)
        }
        Command::Build(args) => {
            if args.print_config {
                output::print_out(&config::default_toml())?;
                return Ok(ExitCode::SUCCESS);
            }
            let outcome = build::run(args)?;
            if outcome.unmet.is_empty() {
                return Ok(ExitCode::SUCCESS);
            }
            let goals = outcome.unmet.join("; ");
            let out = outcome.out.display();
            if args.strict {
                eprintln!(
                    "error: {} goal(s) not met (--strict): {goals}; the files are in {out}",
                    outcome.unmet.len()
                );
                Ok(ExitCode::from(EXIT_ERROR))
            } else {
                let written = if outcome.partial {
                    "the hub mesh, the frame and the report were written to"
                } else {
                    "everything was built and written to"
                };
                eprintln!(
                    "warning: {} goal(s) not met: {goals}; {written} {out} (exit code {EXIT_UNMET})",
                    outcome.unmet.len()
                );
                Ok(ExitCode::from(EXIT_UNMET))
            }
        }
    }
}

/// Help and version as clap prints them; usage errors as one line.
fn clap_exit(err: clap::Error) -> ExitCode {
    match err.kind() {
        ErrorKind::DisplayHelp | ErrorKind::DisplayVersion => {
            let _ = err.print();
            ExitCode::SUCCESS
        }
        ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
            let _ = err.print();
            ExitCode::from(EXIT_ERROR)
        }
        _ => {
            eprintln!("error: {} (see --help)", usage_error_line(&err.to_string()));
            ExitCode::from(EXIT_ERROR)
        }
    }
}

/// clap's usage error as one line: its first paragraph (the message and what it lists,
/// such as the missing arguments), without the usage that follows.
fn usage_error_line(text: &str) -> String {
    let lines: Vec<&str> = text
        .lines()
        .take_while(|l| !l.trim().is_empty() && !l.starts_with("Usage:"))
        .map(str::trim)
        .collect();
    let line = lines.join(" ");
    let line = line.strip_prefix("error: ").unwrap_or(&line);
    if line.is_empty() {
        "invalid arguments".into()
    } else {
        line.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_usage_error_names_what_is_missing_on_one_line() {
        let text = "error: the following required arguments were not provided:\n  --mesh <HUBS.obj>\n  --out <DIR>\n\nUsage: spinvalence solve --mesh <HUBS.obj> --out <DIR>\n\nFor more information, try '--help'.\n";
        assert_eq!(
            usage_error_line(text),
            "the following required arguments were not provided: --mesh <HUBS.obj> --out <DIR>"
        );
        assert_eq!(
            usage_error_line("error: unexpected argument '--foo' found\n\n  tip: to pass '--foo' as a value, use '-- --foo'\n"),
            "unexpected argument '--foo' found"
        );
    }

    #[test]
    fn one_line_keeps_context_and_drops_repeated_causes() {
        let mesh = sv_frame::MeshError::Empty;
        let io = sv_io::IoError::Mesh {
            file: "m.obj".into(),
            problem: mesh,
            face_lines: Vec::new(),
        };
        let err = anyhow::Error::new(io).context("reading\nthe mesh");
        assert_eq!(one_line(&err), "reading the mesh: m.obj: mesh has no faces");
    }
}
