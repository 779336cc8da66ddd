//! `tyrerig`: the command-line entry point of the suite.
//!
//! Every subcommand lives in its own `cmd_*.rs` module with a clap `Args`/`Subcommand` type and a
//! `run` function; this file only dispatches. Errors reach the user through `anyhow` here, at the
//! binary edge, and nowhere else.

use clap::{Parser, Subcommand};

// --- subcommand modules (one per capability) ---
mod bench_adaptive;
mod bench_doctor;
mod bench_foxglove;
mod bench_livefit;
mod cmd_bench;
mod cmd_command;
mod cmd_data;
mod cmd_doctor;
mod cmd_export_ttc;
mod cmd_fit;
mod cmd_inject;
mod cmd_launch;
mod cmd_mcap;
mod cmd_model;
mod cmd_replay;
mod cmd_report;
mod cmd_rig;
mod cmd_run;
mod cmd_security;
mod launch;

#[derive(Debug, Parser)]
#[command(name = "tyrerig", version, about = "Tyre test rig suite: GS2MF procedures, MF-Tyre 6.1 models, ROS 2 nodes")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    // --- subcommand variants ---
    /// Speed figures through real DDS (latency, recorder throughput)
    #[command(subcommand)]
    Bench(cmd_bench::BenchCmd),
    /// End-of-run report: replay a log through the channels and monitor, write Markdown and plots
    Report(Box<cmd_report::ReportArgs>),
    /// Find where model and logs disagree, name the missing effect, add it, show the gap shrink
    Doctor(Box<cmd_doctor::DoctorArgs>),
    /// Hide known effects (thermal, wear, break-in) in recorded virtual-rig logs, computed by the run's true tyre
    Inject(Box<cmd_inject::InjectArgs>),
    /// Fit an MF-Tyre 6.1 model (.tir) to GS2MF logs or measured files, staged as in the thesis
    Fit(Box<cmd_fit::FitArgs>),
    /// Export log data (TYDEX, TTC-style .dat) or a measured file's channels (MATLAB .mat)
    #[command(subcommand)]
    Export(cmd_data::ExportCmd),
    /// Import measured rig data (Calspan TTC .dat/.mat, TYDEX .tdx, folders) into an MCAP log the fitter reads
    #[command(subcommand)]
    Import(cmd_data::ImportCmd),
    /// Show what a measured file holds: tyre, test, channels and units, sweeps per cell, excluded rows, warnings
    Inspect(cmd_data::InspectArgs),
    /// Run a procedure on the virtual rig, log it to MCAP and print the rig-time summary
    Run(Box<cmd_run::RunArgs>),
    /// Virtual rig: calibration against the thesis
    #[command(subcommand)]
    Rig(cmd_rig::RigCmd),
    /// MF-Tyre 6.1 model: evaluate and plot
    #[command(subcommand)]
    Model(cmd_model::ModelCmd),
    /// Start the nodes a launch file lists (in this process, or --processes)
    Launch(cmd_launch::LaunchArgs),
    /// Run one node of a launch file alone
    Node(cmd_launch::NodeArgs),
    /// Republish a recorded MCAP log onto its topics with its original timing
    Replay(cmd_replay::ReplayArgs),
    /// Inspect and repair MCAP logs
    #[command(subcommand)]
    Mcap(cmd_mcap::McapCmd),
    /// DDS Security: SROS2 keystores and enclaves (build with --features security)
    #[command(subcommand)]
    Security(cmd_security::SecurityCmd),
    /// Send an operator command (START, PAUSE, RESUME, ABORT, ESTOP) to the sequencer
    #[command(name = "command")]
    Operator(cmd_command::CommandArgs),
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    node_runtime::logging::init();
    match cli.command {
        // --- subcommand dispatch ---
        Command::Bench(cmd) => cmd_bench::run(cmd),
        Command::Report(args) => cmd_report::run(*args),
        Command::Doctor(args) => cmd_doctor::run(*args),
        Command::Inject(args) => cmd_inject::run(*args),
        Command::Fit(args) => cmd_fit::run(*args),
        Command::Export(cmd) => cmd_data::run_export(cmd),
        Command::Import(cmd) => cmd_data::run_import(cmd),
        Command::Inspect(args) => cmd_data::run_inspect(args),
        Command::Run(args) => cmd_run::run(*args),
        Command::Rig(cmd) => cmd_rig::run(cmd),
        Command::Model(cmd) => cmd_model::run(cmd),
        Command::Launch(args) => cmd_launch::run_launch(args),
        Command::Node(args) => cmd_launch::run_single(args),
        Command::Replay(args) => cmd_replay::run(args),
        Command::Mcap(cmd) => cmd_mcap::run(cmd),
        Command::Security(cmd) => cmd_security::run(cmd),
        Command::Operator(args) => cmd_command::run(args),
    }
}
