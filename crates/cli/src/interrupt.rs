//! Ctrl-C (SIGINT) and SIGTERM (what Slurm and Kubernetes send before they kill a job) stop a
//! render: the first asks the renderer to stop (it returns within a batch of samples, and with
//! `--save-partial` writes what it has); a second ends the process at once, exit code 130.
//!
//! signal-hook rather than ctrlc: it sets an `AtomicBool` from the handler itself (nothing but
//! an atomic store runs in signal context, no thread is started), covers SIGTERM as well as
//! SIGINT, and has the "second signal exits" rule built in (`register_conditional_shutdown`).

use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use anyhow::Context as _;
use aperture_render::Cancel;
use signal_hook::consts::{SIGINT, SIGTERM};

/// Exit code of a render stopped by a signal: 128 + SIGINT, as shells report it.
pub const EXIT_INTERRUPTED: u8 = 130;

/// Exit code when stdout's reader went away (`aperture info … | head`): 128 + SIGPIPE.
#[cfg(unix)]
pub const EXIT_BROKEN_PIPE: u8 = 141;

/// A closed pipe on stdout ends the process at once with [`EXIT_BROKEN_PIPE`], as Unix tools
/// end, instead of the print panicking on its write error (Rust ignores SIGPIPE). For commands
/// whose output is text to read (`info`); a render keeps going whatever reads its progress.
pub fn end_on_broken_pipe() -> anyhow::Result<()> {
    #[cfg(unix)]
    signal_hook::flag::register_conditional_shutdown(
        signal_hook::consts::SIGPIPE,
        i32::from(EXIT_BROKEN_PIPE),
        Arc::new(AtomicBool::new(true)),
    )
    .context("installing the SIGPIPE handler")?;
    Ok(())
}

/// Installs the handlers and returns the token they cancel.
pub fn install() -> anyhow::Result<Cancel> {
    let flag = Arc::new(AtomicBool::new(false));
    for signal in [SIGINT, SIGTERM] {
        // Registered first, so it sees the flag as the previous signal left it: set means
        // this is the second signal.
        signal_hook::flag::register_conditional_shutdown(
            signal,
            i32::from(EXIT_INTERRUPTED),
            Arc::clone(&flag),
        )
        .context("installing the signal handler")?;
        signal_hook::flag::register(signal, Arc::clone(&flag))
            .context("installing the signal handler")?;
    }
    Ok(Cancel::from_flag(flag))
}
