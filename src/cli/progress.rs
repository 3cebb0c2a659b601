//! The progress bar of a render: an observer of the session's passes (`session::Observer`),
//! drawn on stderr when it is a terminal, with samples/s and the ETA. The only module that
//! names indicatif.

use crate::session::{Control, Observer, PassStats};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;

pub struct Progress {
    bar: ProgressBar,
    pixels: u64,
}

impl Progress {
    /// A bar over `pixels` × the target samples per pixel, or a spinner when the target is
    /// unknown (a time budget); hidden when stderr is not a terminal.
    pub fn image(pixels: u64, target_spp: Option<u64>) -> Progress {
        if !std::io::stderr().is_terminal() {
            return Progress {
                bar: ProgressBar::hidden(),
                pixels,
            };
        }
        let (bar, template) = match target_spp {
            Some(n) => (
                ProgressBar::new(pixels * n),
                "{bar:40} {percent:>3}%  {human_pos}/{human_len} samples  {per_sec}  ETA {eta}",
            ),
            None => (
                ProgressBar::new_spinner(),
                "{spinner} {elapsed_precise} {human_pos} samples  {per_sec}",
            ),
        };
        bar.set_draw_target(ProgressDrawTarget::stderr());
        if let Ok(style) = ProgressStyle::with_template(template) {
            bar.set_style(style);
        }
        Progress { bar, pixels }
    }

    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

impl Observer for Progress {
    fn pass(&mut self, stats: &PassStats) -> Control {
        self.bar.set_position(stats.samples * self.pixels);
        Control::Continue
    }
}
