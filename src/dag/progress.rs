//! Progress reporting while a DAG runs: one indicatif bar per stage (done/total, ETA) on a terminal, plain
//! lines when stderr is not a terminal, nothing but errors with `--quiet`. Warnings (e.g. a corrupt cache
//! entry) are printed once each, above the bars.

use crate::dag::status::NodeStatus;
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::collections::BTreeMap;
use std::io::IsTerminal;
use std::sync::Mutex;

/// How progress is shown.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProgressMode {
    /// Bars when stderr is a terminal, else plain lines.
    Auto,
    /// Plain lines (one per stage when it completes).
    Plain,
    /// Only warnings and errors.
    Quiet,
    /// Nothing at all (library use, benchmarks); warnings are still collected in the outcome.
    Silent,
}

/// Receives node completions from the executor (from many threads).
pub struct Progress {
    mode: ProgressMode,
    bars: Mutex<BTreeMap<&'static str, StageBar>>,
    multi: Option<MultiProgress>,
}

struct StageBar {
    total: usize,
    done: usize,
    bar: Option<ProgressBar>,
}

impl Progress {
    pub fn new(mode: ProgressMode) -> Progress {
        let mode = match mode {
            ProgressMode::Auto if !std::io::stderr().is_terminal() => ProgressMode::Plain,
            m => m,
        };
        let multi = (mode == ProgressMode::Auto)
            .then(|| MultiProgress::with_draw_target(ProgressDrawTarget::stderr()));
        Progress {
            mode,
            bars: Mutex::new(BTreeMap::new()),
            multi,
        }
    }

    /// A run of `totals` (stage → node count) is starting.
    pub fn begin(&self, totals: &BTreeMap<&'static str, usize>) {
        let mut bars = self.bars.lock().unwrap_or_else(|e| e.into_inner());
        bars.clear();
        for (&stage, &total) in totals {
            let bar = self.multi.as_ref().map(|m| {
                let b = m.add(ProgressBar::new(total as u64));
                b.set_style(
                    ProgressStyle::with_template(
                        "{prefix:>16} [{bar:30}] {pos}/{len} {msg} ETA {eta}",
                    )
                    .unwrap_or_else(|_| ProgressStyle::default_bar())
                    .progress_chars("=> "),
                );
                b.set_prefix(stage);
                b
            });
            bars.insert(
                stage,
                StageBar {
                    total,
                    done: 0,
                    bar,
                },
            );
        }
    }

    /// One node of `stage` finished with `status`.
    pub fn node_done(&self, stage: &'static str, status: &NodeStatus) {
        if let NodeStatus::Failed(msg) = status {
            if self.mode != ProgressMode::Silent {
                self.println(&format!("error: {stage}: {msg}"));
            }
        }
        let mut bars = self.bars.lock().unwrap_or_else(|e| e.into_inner());
        let Some(sb) = bars.get_mut(stage) else {
            return;
        };
        sb.done += 1;
        if let Some(b) = &sb.bar {
            b.inc(1);
            if sb.done == sb.total {
                b.finish();
            }
        } else if self.mode == ProgressMode::Plain && sb.done == sb.total {
            eprintln!("{stage}: {}/{} done", sb.done, sb.total);
        }
    }

    /// Print a warning once (the caller deduplicates).
    pub fn warn(&self, message: &str) {
        if self.mode != ProgressMode::Silent {
            self.println(&format!("warning: {message}"));
        }
    }

    /// Print an informational line (suppressed by `--quiet`).
    pub fn info(&self, message: &str) {
        if matches!(self.mode, ProgressMode::Auto | ProgressMode::Plain) {
            self.println(message);
        }
    }

    fn println(&self, line: &str) {
        match &self.multi {
            Some(m) => {
                let _ = m.println(line);
            }
            None => eprintln!("{line}"),
        }
    }

    /// Remove the bars (end of a phase).
    pub fn end(&self) {
        let mut bars = self.bars.lock().unwrap_or_else(|e| e.into_inner());
        for sb in bars.values() {
            if let Some(b) = &sb.bar {
                b.finish_and_clear();
            }
        }
        bars.clear();
        if let Some(m) = &self.multi {
            let _ = m.clear();
        }
    }
}
