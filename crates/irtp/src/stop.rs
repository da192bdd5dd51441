//! The process-wide stop request (SIGINT, SIGTERM): a utility that the
//! numerics' long loops (band solves, time steppers) poll as well as the
//! parallel loops, so it imports nothing but `error`.

use std::sync::atomic::{AtomicBool, Ordering};

/// The process-wide stop request. A front end sets it (the binary registers
/// it as the flag of its SIGINT and SIGTERM handlers, [`stop_flag`]); the
/// library's long loops poll it through [`check_stop`] once per time step,
/// linear solve, mesh, point or chunk, and [`crate::parallel::Progress::cancelled`] answers it
/// by default. The binary never clears it (a process asked to stop stays
/// stopped); a front end that outlives a cancelled run withdraws its request
/// when the run has ended ([`stop_during`]).
static STOP: AtomicBool = AtomicBool::new(false);

/// The flag behind [`stop_requested`], for a signal handler to set.
pub fn stop_flag() -> &'static AtomicBool {
    &STOP
}

/// Ask this process's long loops to stop while `wait` runs (a front end
/// waiting for its cancelled run to end), then withdraw the request, so the
/// next run starts (the Python module after a `KeyboardInterrupt`). Work
/// running beside it in the process ends `Interrupted` too.
pub fn stop_during<R>(wait: impl FnOnce() -> R) -> R {
    STOP.store(true, Ordering::Relaxed);
    let r = wait();
    STOP.store(false, Ordering::Relaxed);
    r
}

/// Whether this process was asked to stop (one relaxed atomic load).
pub fn stop_requested() -> bool {
    STOP.load(Ordering::Relaxed)
}

/// Steps of a particle's loop between two polls of the stop request (a
/// step is tens of nanoseconds: a poll every few milliseconds).
pub const STOP_POLL_STEPS: u64 = 1 << 16;

/// Whether a particle loop at step `step` must stop: polls the stop request
/// every [`STOP_POLL_STEPS`] steps, so a long particle (many steps to t_max)
/// ends promptly; the caller then discards its chunk.
#[inline]
pub fn stop_due(step: u64) -> bool {
    step % STOP_POLL_STEPS == 0 && stop_requested()
}

/// [`crate::Error::Interrupted`] once this process was asked to stop: the
/// poll of a long loop, whose partial result is then never returned.
pub fn check_stop() -> crate::Result<()> {
    if stop_requested() {
        Err(crate::Error::Interrupted)
    } else {
        Ok(())
    }
}
