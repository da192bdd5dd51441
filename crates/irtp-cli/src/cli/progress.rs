//! Progress bars on a terminal, silence otherwise.
//!
//! Each bar names its unit (particles, points, grid points, time steps, per cent of a
//! figure...) and estimates the time left from the average rate since the
//! stage began (elapsed · (1 - f) / f at fraction f done), not from
//! indicatif's recent-rate estimate, which jumps when chunks take uneven
//! time (a figure's curves, a slow first chunk). The estimate is hidden
//! until there is enough to go on (5 % done and 1 s elapsed).

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressState, ProgressStyle};
use irtp::parallel::Progress;
use irtp_app::Reporter;
use std::io::IsTerminal;
use std::time::Duration;

/// What a stage counts, from its label (the stages `irtp_app` reports).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unit {
    /// Whole things with a name (plural).
    Count(&'static str),
    /// A figure's progress, shown in per cent.
    Percent,
}

/// The unit of the stage `label`.
pub fn unit_of(label: &str) -> Unit {
    match label {
        "simulate" | "simulate part" | "mfpt" => Unit::Count("particles"),
        l if l.starts_with("point ") => Unit::Count("particles"),
        "mfpt scan" | "points" => Unit::Count("points"),
        "mfpt optimize" => Unit::Count("grid points"),
        "fp transient" => Unit::Count("time steps"),
        "search (mesh)" => Unit::Count("Mflop"),
        "fp msd" => Unit::Count("mesh-times"),
        l if l.starts_with("fig") => Unit::Percent,
        _ => Unit::Count("steps"),
    }
}

/// Time left at fraction `f` done after `elapsed`: the average rate so far;
/// `None` until 5 % is done and a second has passed.
pub fn time_left(elapsed: Duration, f: f64) -> Option<Duration> {
    if !(0.05..1.0).contains(&f) || elapsed < Duration::from_secs(1) {
        return None;
    }
    Some(elapsed.mul_f64((1.0 - f) / f))
}

/// "~12 s left", "~3 min 05 s left", or "" while there is no estimate.
pub fn fmt_left(left: Option<Duration>) -> String {
    let Some(d) = left else {
        return String::new();
    };
    let s = d.as_secs_f64().round() as u64;
    match s {
        0 => "<1 s left".to_string(),
        1..=59 => format!("~{s} s left"),
        60..=3599 => format!("~{} min {:02} s left", s / 60, s % 60),
        _ => format!("~{} h {:02} min left", s / 3600, (s % 3600) / 60),
    }
}

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
        let counts = match unit_of(label) {
            Unit::Count(u) => format!("{{pos}}/{{len}} {u}"),
            Unit::Percent => "{percent:>3}% of the figure".to_string(),
        };
        let template =
            format!("{{prefix:>12}} [{{bar:40}}] {counts}, {{elapsed}} {{left}} {{msg}}");
        pb.set_style(
            ProgressStyle::with_template(&template)
                .expect("valid template")
                .with_key("left", |s: &ProgressState, w: &mut dyn std::fmt::Write| {
                    let left = time_left(s.elapsed(), f64::from(s.fraction()));
                    let _ = w.write_str(&fmt_left(left));
                })
                .progress_chars("=> "),
        );
        pb.set_prefix(label.to_string());
        // Redraw steadily, so the elapsed time and estimate move during a slow chunk.
        pb.enable_steady_tick(Duration::from_millis(500));
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
