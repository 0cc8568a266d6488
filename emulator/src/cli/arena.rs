//! `robot-emulator arena`: arena files (`arena generate` writes a generated arena).

use std::path::PathBuf;

use clap::{Args, Subcommand};

/// `arena` subcommands.
#[derive(Debug, Clone, Args)]
pub struct ArenaArgs {
    #[command(subcommand)]
    pub command: ArenaCommand,
}

/// What to do with arenas.
#[derive(Debug, Clone, Subcommand)]
pub enum ArenaCommand {
    /// Write a generated arena: CiberRato lab XML (plus its grid file of start positions,
    /// `...Grid.xml` beside a `...Lab.xml`) or micromouse maze text. Same seed, same arena;
    /// every arena is checked solvable at its robot's size before it is written.
    Generate(GenerateArgs),
}

/// `arena generate` options.
#[derive(Debug, Clone, Args)]
pub struct GenerateArgs {
    /// Micro-Rato labyrinth (as Dom Dinis met, Seabra Lopes, Lau, Reis §2), micromouse maze,
    /// or Khepera box (as in the Khepera foraging paper's Fig. 17, Löffler et al.).
    #[arg(long, value_enum)]
    pub kind: crate::arena_gen::Kind,
    /// The arena's seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output file: `...Lab.xml` for micro-rato and box (the grid file goes beside it), any
    /// name for a maze.
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
    /// Replace existing files at `--out` (and its grid file); never a device, FIFO or directory.
    #[arg(long)]
    pub force: bool,
}
