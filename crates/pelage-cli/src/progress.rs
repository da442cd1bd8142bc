//! Progress bars for the long jobs (animate, the labs, the benchmark).

use std::fmt::Display;

use indicatif::{ProgressBar, ProgressStyle, style::TemplateError};

/// A progress bar on stderr that keeps the job's own report lines on stdout.
///
/// indicatif hides the bar when stderr is not a terminal (CI, a pipe); the report
/// lines printed through [`Progress::println`] are printed either way.
pub struct Progress(ProgressBar);

impl Progress {
    /// A bar of `len` steps counted in `unit` ("frames", "runs", ...).
    pub fn new(len: u64, unit: &str) -> Result<Self, TemplateError> {
        let template =
            format!("{{bar:40}} {{pos}}/{{len}} {unit}, {{elapsed}} elapsed, eta {{eta}}  {{msg}}");
        Ok(Self(
            ProgressBar::new(len).with_style(ProgressStyle::with_template(&template)?),
        ))
    }

    /// Prints `line` to stdout above the bar (also when the bar is hidden).
    pub fn println(&self, line: impl Display) {
        self.0.suspend(|| println!("{line}"));
    }

    /// Shows `message` after the bar: what runs now.
    pub fn set_message(&self, message: impl Into<String>) {
        self.0.set_message(message.into());
    }

    /// Advances the bar by `steps`.
    pub fn inc(&self, steps: u64) {
        self.0.inc(steps);
    }

    /// Removes the bar from the terminal.
    pub fn finish_and_clear(&self) {
        self.0.finish_and_clear();
    }
}

/// [`Progress::new`].
pub fn bar(len: u64, unit: &str) -> Result<Progress, TemplateError> {
    Progress::new(len, unit)
}
