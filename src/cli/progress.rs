//! Progress bars on a terminal, silence otherwise.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use irtp::app::Reporter;
use irtp::parallel::Progress;
use std::io::IsTerminal;

/// A progress bar on stderr when it is a terminal; hidden otherwise.
/// Cleared when dropped.
pub struct Bar(ProgressBar);

impl Bar {
    /// New bar with a label and a total count.
    pub fn new(label: &str, total: u64) -> Self {
        let pb = if std::io::stderr().is_terminal() {
            ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr())
        } else {
            ProgressBar::hidden()
        };
        pb.set_style(
            ProgressStyle::with_template("{prefix:>12} [{bar:40}] {pos}/{len} ({eta}) {msg}")
                .expect("valid template")
                .progress_chars("=> "),
        );
        pb.set_prefix(label.to_string());
        Bar(pb)
    }

    /// Show a short message after the counts (e.g. failures).
    pub fn message(&self, msg: &str) {
        if self.0.message() != msg {
            self.0.set_message(msg.to_string());
        }
    }
}

impl Progress for Bar {
    fn update(&self, done: u64, total: u64) {
        if self.0.length() != Some(total) {
            self.0.set_length(total);
        }
        self.0.set_position(done);
    }
    fn cancelled(&self) -> bool {
        super::signals::stop_requested()
    }
}

impl Drop for Bar {
    fn drop(&mut self) {
        self.0.finish_and_clear();
    }
}

/// The binary's reporter: one terminal bar per stage; cancels on Ctrl-C or
/// SIGTERM ([`super::signals`]).
pub struct Bars;

impl Reporter for Bars {
    fn stage(&self, label: &str, total: u64) -> Box<dyn Progress + '_> {
        Box::new(Bar::new(label, total))
    }
    fn cancelled(&self) -> bool {
        super::signals::stop_requested()
    }
}
