//! `aperture`: render glTF scenes with physically based depth of field.

mod bench;
mod bench_plot;
mod bench_rays;
mod bench_results;
mod denoise_cmd;
mod error_line;
mod first_image;
mod frames;
#[cfg(test)]
mod frames_tests;
mod info;
mod info_materials;
mod info_memory;
mod info_motion;
mod info_prescription;
mod interrupt;
mod load_warnings;
mod material_args;
mod merge_cmd;
mod motion_args;
mod number_args;
mod plot;
mod progress;
mod render_args;
mod render_cmd;
mod render_opts;
mod render_summary;
mod split_args;
mod time_args;
mod workers;

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
    Render(Box<render_args::RenderArgs>),
    /// Denoise an EXR that has the beauty and the Denoising Albedo/Normal passes.
    Denoise(denoise_cmd::DenoiseArgs),
    /// Put the parts of a render split across machines (tiles, sample batches) together.
    Merge(merge_cmd::MergeArgs),
    /// Error against time per sampler configuration: CSV, log-log plot and table.
    Bench(bench::BenchArgs),
    /// Closest-hit and occlusion throughput of each BVH preset on rays from the scene's camera.
    BenchRays(bench_rays::BenchRaysArgs),
}

fn main() -> std::process::ExitCode {
    // Before the first big allocation: freed buffers are reused, not faulted in again.
    aperture_budget::keep_freed_memory();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Info(args) => interrupt::end_on_broken_pipe().and_then(|()| info::run(args)),
        Command::Render(args) => render_cmd::run(*args),
        Command::Denoise(args) => denoise_cmd::run(args),
        Command::Merge(args) => merge_cmd::run(args),
        Command::Bench(args) => bench::run(args),
        Command::BenchRays(args) => bench_rays::run(args),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", error_line::error_line(&e));
            let interrupted = e.chain().any(|c| {
                matches!(
                    c.downcast_ref(),
                    Some(aperture_output::OutputError::Interrupted { .. })
                )
            }) || e.downcast_ref::<frames::Interrupted>().is_some();
            if interrupted {
                std::process::ExitCode::from(interrupt::EXIT_INTERRUPTED)
            } else {
                std::process::ExitCode::FAILURE
            }
        }
    }
}

#[cfg(test)]
/// `BoxTextured.glb` from the samples folder (see [`sample`]).
fn box_textured_sample() -> Option<std::path::PathBuf> {
    sample("correctness/BoxTextured/BoxTextured.glb")
}

#[cfg(test)]
/// A file of the samples folder (`APERTURE_SAMPLES`, else `../shared/gltf-samples` beside the
/// repository). Missing: a skip with a message, but a failure with `CI=true`, where a silent
/// skip would hide that the test never ran.
fn sample(relative: &str) -> Option<std::path::PathBuf> {
    let samples = std::env::var_os("APERTURE_SAMPLES")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| {
            std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
                .join("../../../shared/gltf-samples")
        });
    let path = samples.join(relative);
    if path.is_file() {
        return Some(path);
    }
    assert!(
        std::env::var("CI").map_or(true, |v| v != "true"),
        "CI=true but the glTF sample {} is missing",
        path.display()
    );
    eprintln!("skipping: {} not found", path.display());
    None
}
