//! Running a command off the Python thread: the GIL is released while the
//! library computes on a worker thread; the calling thread wakes every
//! 50 ms to run Python's signal handlers (Ctrl-C → `KeyboardInterrupt`,
//! which cancels the run through [`irtp_app::Reporter::cancelled`] and the
//! process's stop request that the numerical kernels poll, withdrawn once
//! the run has ended: [`irtp::parallel::stop_during`]) and to report
//! progress.

use irtp::parallel::Progress;
use irtp_app::{Context, Outcome, Reporter};
use irtp_paper::Command;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{mpsc, Arc, Mutex};
use std::time::{Duration, Instant};

/// How often the calling thread looks at signals.
const POLL: Duration = Duration::from_millis(50);
/// How often a progress callback is called.
const REPORT: Duration = Duration::from_millis(100);

/// State shared by the worker (writer) and the calling thread (reader).
#[derive(Default)]
struct Shared {
    cancel: AtomicBool,
    label: Mutex<String>,
    done: AtomicU64,
    total: AtomicU64,
}

impl Shared {
    fn snapshot(&self) -> (String, u64, u64) {
        let label = self.label.lock().map(|l| l.clone()).unwrap_or_default();
        let total = self.total.load(Ordering::Relaxed);
        (label, self.done.load(Ordering::Relaxed).min(total), total)
    }
}

/// The worker's reporter: records the current stage, answers cancellation.
struct WorkerReporter(Arc<Shared>);

impl Reporter for WorkerReporter {
    fn stage(&self, label: &str, total: u64) -> Box<dyn Progress + '_> {
        if let Ok(mut l) = self.0.label.lock() {
            *l = label.to_string();
        }
        self.0.done.store(0, Ordering::Relaxed);
        self.0.total.store(total, Ordering::Relaxed);
        Box::new(Stage(&self.0))
    }
    fn cancelled(&self) -> bool {
        self.0.cancel.load(Ordering::Relaxed)
    }
}

struct Stage<'a>(&'a Shared);

impl Progress for Stage<'_> {
    fn update(&self, done: u64, total: u64) {
        self.0.total.store(total, Ordering::Relaxed);
        self.0.done.fetch_max(done, Ordering::Relaxed);
    }
    fn cancelled(&self) -> bool {
        self.0.cancel.load(Ordering::Relaxed)
    }
}

/// The most threads a call may start (more only costs memory and start-up).
const MAX_THREADS: usize = 1024;

/// A rayon pool of `threads` threads, or `None` for the global pool.
fn pool(threads: Option<usize>) -> PyResult<Option<rayon::ThreadPool>> {
    let Some(n) = threads else { return Ok(None) };
    if n > MAX_THREADS {
        return Err(PyValueError::new_err(format!(
            "invalid threads = {n}: allowed 1 <= threads <= {MAX_THREADS}"
        )));
    }
    if n == 0 {
        return Err(PyValueError::new_err(
            "invalid threads = 0: allowed threads >= 1",
        ));
    }
    rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .map(Some)
        .map_err(|e| PyRuntimeError::new_err(format!("cannot start {n} threads: {e}")))
}

/// Run `command` on a worker thread; see the module documentation.
pub fn run(
    py: Python<'_>,
    command: Command,
    argv: Vec<String>,
    progress: Option<Bound<'_, PyAny>>,
    threads: Option<usize>,
) -> PyResult<irtp::Result<Outcome>> {
    let pool = pool(threads)?;
    let shared = Arc::new(Shared::default());
    let (tx, rx) = mpsc::channel();
    // Behind a mutex: the GIL-free closures below need a shareable receiver.
    let rx = Mutex::new(rx);
    let worker = {
        let shared = Arc::clone(&shared);
        std::thread::spawn(move || {
            let reporter = WorkerReporter(shared);
            let ctx = Context {
                reporter: &reporter,
                argv,
            };
            let work = || command.run(&ctx);
            let result = match &pool {
                Some(p) => p.install(work),
                None => work(),
            };
            let _ = tx.send(result);
        })
    };
    let stop = |py: Python<'_>, e: PyErr| {
        shared.cancel.store(true, Ordering::Relaxed);
        py.detach(|| irtp::parallel::stop_during(|| worker_join(&rx)));
        Err(e)
    };
    let mut last = Instant::now();
    loop {
        match py.detach(|| receive(&rx, POLL)) {
            Ok(result) => {
                let _ = worker.join();
                report(progress.as_ref(), &shared, true)?;
                return Ok(result);
            }
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                let panic = worker.join().err().map(panic_message).unwrap_or_default();
                return Err(PyRuntimeError::new_err(format!(
                    "irtp: internal error: {panic}"
                )));
            }
            Err(mpsc::RecvTimeoutError::Timeout) => {}
        }
        if let Err(e) = py.check_signals() {
            return stop(py, e);
        }
        if last.elapsed() >= REPORT {
            last = Instant::now();
            if let Err(e) = report(progress.as_ref(), &shared, false) {
                return stop(py, e);
            }
        }
    }
}

type Receiver = Mutex<mpsc::Receiver<irtp::Result<Outcome>>>;

/// The worker's result, if it arrives within `wait`.
fn receive(rx: &Receiver, wait: Duration) -> Result<irtp::Result<Outcome>, mpsc::RecvTimeoutError> {
    match rx.lock() {
        Ok(rx) => rx.recv_timeout(wait),
        Err(_) => Err(mpsc::RecvTimeoutError::Disconnected),
    }
}

/// Wait for a cancelled worker's (discarded) result.
fn worker_join(rx: &Receiver) {
    if let Ok(rx) = rx.lock() {
        let _ = rx.recv();
    }
}

/// Call the progress callback with (label, done, total); `last`: the run
/// finished, so report the stage as complete.
fn report(progress: Option<&Bound<'_, PyAny>>, shared: &Shared, last: bool) -> PyResult<()> {
    let Some(cb) = progress else { return Ok(()) };
    let (label, done, total) = shared.snapshot();
    if total == 0 {
        return Ok(());
    }
    let done = if last { total } else { done };
    cb.call1((label, done, total)).map(|_| ())
}

fn panic_message(p: Box<dyn std::any::Any + Send>) -> String {
    p.downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| p.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic".into())
}
