//! `aperture`: render glTF scenes with physically based depth of field.

mod bench;
mod info;
mod progress;
mod render_cmd;

use clap::{Parser, Subcommand};

/// Physically based depth-of-field renderer for glTF 2.0 scenes.
#[derive(Parser)]
#[command(name = "aperture", version, about)]
pub(crate) struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
pub(crate) enum Command {
    /// Print what a scene contains and how its cameras resolve.
    Info(info::InfoArgs),
    /// Render a scene to EXR or PNG.
    Render(render_cmd::RenderArgs),
    /// Error against time per sampler configuration: CSV, log-log plot and table.
    Bench(bench::BenchArgs),
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Info(args) => info::run(args),
        Command::Render(args) => render_cmd::run(args),
        Command::Bench(args) => bench::run(args),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
