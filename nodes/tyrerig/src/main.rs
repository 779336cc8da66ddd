//! `tyrerig`: the command-line entry point of the suite.
//!
//! Every subcommand lives in its own `cmd_*.rs` module with a clap `Args`/`Subcommand` type and a
//! `run` function; this file only dispatches. Errors reach the user through `anyhow` here, at the
//! binary edge, and nowhere else.

use clap::{Parser, Subcommand};

// --- subcommand modules (one per capability) ---
mod cmd_model;

#[derive(Debug, Parser)]
#[command(name = "tyrerig", version, about = "Tyre test rig suite: GS2MF procedures, MF-Tyre 6.1 models, ROS 2 nodes")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    // --- subcommand variants ---
    /// MF-Tyre 6.1 model: evaluate and plot
    #[command(subcommand)]
    Model(cmd_model::ModelCmd),
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    match cli.command {
        // --- subcommand dispatch ---
        Command::Model(cmd) => cmd_model::run(cmd),
    }
}
