//! docs/cli.md, the command-line reference, is generated from the clap definitions of `station`
//! and `robot-emulator`: every command's `--help`, exactly as the binaries print it. This test
//! regenerates it in memory and fails when the file differs, so the reference cannot drift
//! from the code. With `UPDATE_CLI_REFERENCE=1` it writes the file instead:
//!
//! ```text
//! UPDATE_CLI_REFERENCE=1 cargo test -p station --test cli_reference
//! ```
#![allow(clippy::unwrap_used, clippy::panic)]

use std::fmt::Write as _;
use std::path::PathBuf;

use clap::CommandFactory;

/// The command that rewrites docs/cli.md, as the failure message names it.
const REGENERATE: &str = "UPDATE_CLI_REFERENCE=1 cargo test -p station --test cli_reference";

fn reference_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../docs/cli.md")
}

/// The whole reference: a short preface, a table of contents, then every command's help.
fn reference() -> String {
    let programs = [
        (
            station::cli::Cli::command(),
            "the station: the TUI (with no command) and the headless commands",
        ),
        (
            emulator::cli::Cli::command(),
            "the emulator: the robot's firmware in a simulated world, on a pseudo-terminal",
        ),
    ];
    let mut commands = Vec::new();
    for (mut cmd, _) in programs.clone() {
        cmd.build();
        collect(&cmd, &mut Vec::new(), &mut commands);
    }
    let mut out = String::new();
    out.push_str(
        "# Command-line reference\n\n\
         <!-- Generated from the clap definitions by station/tests/cli_reference.rs: do not \
         edit by hand. Regenerate with\n     ",
    );
    out.push_str(REGENERATE);
    out.push_str(" -->\n\n");
    out.push_str("Every command's `--help`, exactly as the binaries print it. Two programs:\n\n");
    for (cmd, what) in &programs {
        let name = cmd.get_name();
        let _ = writeln!(out, "- [`{name}`](#{}): {what}", anchor(name));
    }
    out.push_str(
        "\nThe guides explain the workflows: [the station](station.md), \
         [the emulator](emulator.md), [recordings](recordings.md).\n\n",
    );
    out.push_str("## Contents\n\n");
    for (path, _) in &commands {
        let indent = "  ".repeat(path.len() - 1);
        let title = path.join(" ");
        let _ = writeln!(out, "{indent}- [`{title}`](#{})", anchor(&title));
    }
    for (path, help) in &commands {
        let hashes = "#".repeat((path.len() + 1).min(6));
        let _ = writeln!(out, "\n{hashes} {}\n\n```text\n{help}\n```", path.join(" "));
    }
    out
}

/// Every command under `cmd` (itself first), depth first, with its full path and its long
/// help. clap's own `help` subcommand is left out: it prints the same texts.
fn collect(cmd: &clap::Command, parent: &mut Vec<String>, out: &mut Vec<(Vec<String>, String)>) {
    parent.push(cmd.get_name().to_string());
    let help = cmd.clone().render_long_help().to_string();
    let help: Vec<&str> = help.lines().map(str::trim_end).collect();
    out.push((parent.clone(), help.join("\n").trim_end().to_string()));
    for sub in cmd.get_subcommands().filter(|s| s.get_name() != "help") {
        collect(sub, parent, out);
    }
    parent.pop();
}

/// The anchor GitHub gives a heading: lower case, spaces to hyphens, punctuation dropped.
fn anchor(title: &str) -> String {
    title
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c.to_ascii_lowercase()),
            _ => None,
        })
        .collect()
}

#[test]
fn docs_cli_md_is_the_help_of_every_command() {
    let want = reference();
    let path = reference_path();
    if std::env::var_os("UPDATE_CLI_REFERENCE").is_some() {
        std::fs::write(&path, &want).unwrap();
        return;
    }
    let have = std::fs::read_to_string(&path).unwrap_or_default();
    if have != want {
        let line = have
            .lines()
            .zip(want.lines())
            .position(|(a, b)| a != b)
            .unwrap_or_else(|| have.lines().count().min(want.lines().count()));
        panic!(
            "docs/cli.md is stale: run `{REGENERATE}` (first difference at line {}: \
             the file has {:?}, the code gives {:?})",
            line + 1,
            have.lines().nth(line).unwrap_or("<end of file>"),
            want.lines().nth(line).unwrap_or("<end of file>"),
        );
    }
}
