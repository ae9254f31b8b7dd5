//! Progress bars and spinners for long commands (drawn only on a terminal).

use cig_bench::database::{BuildProgress, BuildStage};
use cig_terrain_io::imagery::ImageryProgress;
use indicatif::{ProgressBar, ProgressStyle};

pub fn bar(total: u64, what: &str) -> ProgressBar {
    let bar = ProgressBar::new(total);
    if let Ok(style) = ProgressStyle::with_template("{msg:>12} [{bar:40}] {pos}/{len} {elapsed}") {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_message(what.to_string());
    bar
}

/// A spinner for a stage whose length is unknown.
pub fn spinner(what: &str) -> ProgressBar {
    let spinner = ProgressBar::new_spinner();
    spinner.set_message(what.to_string());
    spinner.enable_steady_tick(std::time::Duration::from_millis(120));
    spinner
}

/// Draws a database build's progress ([`cig_bench::database::BuildProgress`]): a bar while
/// terrain is synthesized, a spinner while voids are filled and materials derived, a bar while
/// tiles are written, a bar while images are opened and the imagery pyramid is built.
pub fn build_progress() -> impl FnMut(BuildProgress<'_>) {
    let mut current: Option<ProgressBar> = None;
    move |progress| match progress {
        BuildProgress::Begin(stage) => {
            current = Some(match stage {
                BuildStage::Synthesize => bar(100, "synthesize"),
                BuildStage::Prepare => spinner("fill voids, derive materials"),
                BuildStage::Write => bar(0, "write tiles"),
                BuildStage::Imagery => bar(0, "open images"),
            });
        }
        BuildProgress::Synthesize { step, fraction } => {
            if let Some(bar) = &current {
                bar.set_message(step.to_string());
                bar.set_position((fraction * 100.0) as u64);
            }
        }
        BuildProgress::Write { done, total } => {
            if let Some(bar) = &current {
                bar.set_length(total);
                bar.set_position(done);
            }
        }
        BuildProgress::Imagery(step) => {
            // `cig bench imagery` reports the imagery alone, without a Begin.
            let bar = current.get_or_insert_with(|| bar(0, "open images"));
            let (what, done, total) = match step {
                ImageryProgress::Open { done, total } => ("open images", done, total),
                ImageryProgress::Build { done, total } => ("imagery", done, total),
            };
            bar.set_message(what);
            bar.set_length(total);
            bar.set_position(done);
        }
        BuildProgress::End => {
            if let Some(bar) = current.take() {
                bar.finish_and_clear();
            }
        }
    }
}
