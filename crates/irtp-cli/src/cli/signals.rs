//! Ctrl-C (SIGINT) and SIGTERM ask the running command to stop through its
//! cancellation path ([`irtp_app::Reporter::cancelled`]): the run returns
//! `Error::Interrupted`, its staging directory is removed, and the binary
//! exits with 128 + the signal number (130 for SIGINT, 143 for SIGTERM). A
//! second signal exits at once, with the same code (the next run into the
//! same place removes the staging directory left behind).

use std::sync::atomic::{AtomicUsize, Ordering};
/// The number of the last signal received (0: none).
static SIGNAL: AtomicUsize = AtomicUsize::new(0);

/// Install the handlers (once, before the run). Without Unix signals, nothing.
#[cfg(unix)]
pub fn install() -> std::io::Result<()> {
    use signal_hook::consts::{SIGINT, SIGTERM};
    use signal_hook::flag;
    // The library's process-wide stop request, which its long loops poll:
    // set by the first SIGINT or SIGTERM.
    let stop = irtp::parallel::stop_flag();
    for sig in [SIGINT, SIGTERM] {
        // Order matters: the shutdown fires only when a signal came before.
        flag::register_conditional_shutdown(sig, 128 + sig, stop)?;
        flag::register(sig, stop)?;
        flag::register_usize(sig, &SIGNAL, sig as usize)?;
    }
    Ok(())
}

#[cfg(not(unix))]
pub fn install() -> std::io::Result<()> {
    Ok(())
}

/// Whether a stop was asked for.
pub fn stop_requested() -> bool {
    irtp::parallel::stop_requested()
}

/// The exit code and name of the signal that stopped the run, if any.
pub fn received() -> Option<(u8, &'static str)> {
    if !stop_requested() {
        return None;
    }
    Some(match SIGNAL.load(Ordering::SeqCst) {
        15 => (143, "SIGTERM"),
        _ => (130, "SIGINT"),
    })
}
