//! Progress reporting while a DAG runs. On a terminal: one overall bar (nodes done of all, rate, ETA) and one
//! bar per stage that has nodes running now (done/total, rate, ETA; a spinner with the elapsed time for a stage
//! of a single node, whose ETA would mean nothing); a stage's bar goes away when its last node finishes, so a
//! run of twenty stages shows only the ones at work. Plain lines when stderr is not a terminal, nothing but
//! errors with `--quiet`. Warnings (e.g. a corrupt cache entry) are printed once each, above the bars.
//! Which bars are on screen is decided by [`BarModel`], plain bookkeeping tested without a terminal.

use crate::dag::status::NodeStatus;
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::collections::BTreeMap;
use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::Duration;

/// Counts per stage and overall, and which stages have a bar: a stage gets one when nodes of it start
/// running and loses it when its last node is done (cached, executed, failed or skipped).
#[derive(Debug, Default)]
pub struct BarModel {
    stages: BTreeMap<&'static str, StageCount>,
    done: usize,
    total: usize,
}

#[derive(Debug, Default)]
struct StageCount {
    done: usize,
    total: usize,
    shown: bool,
}

/// What a finished node changed.
#[derive(Debug, PartialEq, Eq)]
pub struct NodeFinished {
    /// The stage's nodes done now, and its total.
    pub stage_done: usize,
    pub stage_total: usize,
    /// The stage's bar is to be removed (its last node is done and it had one).
    pub hide: bool,
}

impl BarModel {
    /// A run of `totals` (stage → node count).
    pub fn new(totals: &BTreeMap<&'static str, usize>) -> BarModel {
        BarModel {
            stages: totals
                .iter()
                .map(|(&stage, &total)| {
                    let count = StageCount {
                        total,
                        ..StageCount::default()
                    };
                    (stage, count)
                })
                .collect(),
            done: 0,
            total: totals.values().sum(),
        }
    }

    /// Nodes of `stage` start running; true when its bar is to be shown now (it had none and is unfinished).
    pub fn start(&mut self, stage: &'static str) -> bool {
        match self.stages.get_mut(stage) {
            Some(c) if !c.shown && c.done < c.total => {
                c.shown = true;
                true
            }
            _ => false,
        }
    }

    /// One node of `stage` is done; `None` for a stage the run did not announce.
    pub fn finish(&mut self, stage: &'static str) -> Option<NodeFinished> {
        let c = self.stages.get_mut(stage)?;
        c.done = (c.done + 1).min(c.total);
        self.done = (self.done + 1).min(self.total);
        let hide = c.shown && c.done == c.total;
        if hide {
            c.shown = false;
        }
        Some(NodeFinished {
            stage_done: c.done,
            stage_total: c.total,
            hide,
        })
    }

    /// Stages with a bar now, by name.
    pub fn shown(&self) -> Vec<&'static str> {
        self.stages
            .iter()
            .filter(|(_, c)| c.shown)
            .map(|(&s, _)| s)
            .collect()
    }

    /// Nodes done of all, and all.
    pub fn overall(&self) -> (usize, usize) {
        (self.done, self.total)
    }

    /// A stage's nodes done, and its total.
    pub fn stage(&self, stage: &str) -> Option<(usize, usize)> {
        self.stages.get(stage).map(|c| (c.done, c.total))
    }
}

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

/// Receives node starts and completions from the executor (from many threads).
pub struct Progress {
    mode: ProgressMode,
    state: Mutex<Bars>,
    multi: Option<MultiProgress>,
}

/// The model and, on a terminal, the bars it shows.
#[derive(Default)]
struct Bars {
    model: BarModel,
    overall: Option<ProgressBar>,
    stages: BTreeMap<&'static str, ProgressBar>,
    /// Single-node stages whose node reports its own steps: their bar counts steps (last printed tenth in
    /// plain mode).
    stepped: BTreeMap<&'static str, u64>,
}

/// Bar template: items done of all, rate and ETA.
const COUNT_TEMPLATE: &str = "{prefix:>16} [{bar:30}] {pos}/{len} {per_sec} ETA {eta}";
/// Spinner template of a stage with a single node (no count to show, no ETA to estimate).
const SINGLE_TEMPLATE: &str = "{prefix:>16} {spinner} running for {elapsed}";

fn style(template: &str) -> ProgressStyle {
    ProgressStyle::with_template(template)
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> ")
}

fn styled(bar: ProgressBar, template: &str, prefix: &'static str) -> ProgressBar {
    bar.set_style(style(template));
    bar.set_prefix(prefix);
    bar
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
            state: Mutex::new(Bars::default()),
            multi,
        }
    }

    fn state(&self) -> std::sync::MutexGuard<'_, Bars> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// A run of `totals` (stage → node count) is starting.
    pub fn begin(&self, totals: &BTreeMap<&'static str, usize>) {
        let mut st = self.state();
        st.model = BarModel::new(totals);
        st.stages.clear();
        st.stepped.clear();
        st.overall = self.multi.as_ref().map(|m| {
            let total = st.model.overall().1 as u64;
            styled(m.add(ProgressBar::new(total)), COUNT_TEMPLATE, "all nodes")
        });
    }

    /// Nodes of `stage` start running (called once per stage and wave, before they run).
    pub fn stage_running(&self, stage: &'static str) {
        let mut st = self.state();
        if !st.model.start(stage) {
            return;
        }
        let Some(m) = &self.multi else {
            return;
        };
        let (done, total) = st.model.stage(stage).unwrap_or((0, 1));
        let bar = if total == 1 {
            let b = styled(m.add(ProgressBar::new_spinner()), SINGLE_TEMPLATE, stage);
            b.enable_steady_tick(Duration::from_millis(200));
            b
        } else {
            let b = styled(m.add(ProgressBar::new(total as u64)), COUNT_TEMPLATE, stage);
            b.set_position(done as u64);
            b
        };
        st.stages.insert(stage, bar);
    }

    /// One node of `stage` finished with `status`.
    pub fn node_done(&self, stage: &'static str, status: &NodeStatus) {
        if let NodeStatus::Failed(msg) = status {
            if self.mode != ProgressMode::Silent {
                self.println(&format!("error: {stage}: {msg}"));
            }
        }
        let mut st = self.state();
        let Some(f) = st.model.finish(stage) else {
            return;
        };
        if let Some(b) = &st.overall {
            b.inc(1);
        }
        if let Some(b) = st.stages.get(stage) {
            b.inc(1);
        }
        if f.hide {
            if let Some(b) = st.stages.remove(stage) {
                b.finish_and_clear();
            }
        }
        if self.mode == ProgressMode::Plain && f.stage_done == f.stage_total {
            eprintln!("{stage}: {}/{} done", f.stage_done, f.stage_total);
        }
    }

    /// The node of single-node stage `stage` has done `done` of `total` steps; its spinner becomes a bar of
    /// steps with rate and ETA. Ignored for stages of several nodes (their bar counts nodes).
    pub fn node_steps(&self, stage: &'static str, done: u64, total: u64) {
        let mut st = self.state();
        if st.model.stage(stage).map(|(_, t)| t) != Some(1) || total == 0 {
            return;
        }
        let first = !st.stepped.contains_key(stage);
        if self.mode == ProgressMode::Plain {
            let tenth = done * 10 / total;
            if first || st.stepped.get(stage) != Some(&tenth) {
                eprintln!("{stage}: {done}/{total}");
            }
            st.stepped.insert(stage, tenth);
            return;
        }
        st.stepped.insert(stage, done);
        let Some(bar) = st.stages.get(stage) else {
            return;
        };
        if first {
            bar.disable_steady_tick();
            bar.set_style(style(COUNT_TEMPLATE));
            bar.reset_eta();
        }
        bar.set_length(total);
        bar.set_position(done);
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
        let mut st = self.state();
        for (_, b) in std::mem::take(&mut st.stages) {
            b.finish_and_clear();
        }
        if let Some(b) = st.overall.take() {
            b.finish_and_clear();
        }
        st.model = BarModel::default();
        st.stepped.clear();
        if let Some(m) = &self.multi {
            let _ = m.clear();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn totals(pairs: &[(&'static str, usize)]) -> BTreeMap<&'static str, usize> {
        pairs.iter().copied().collect()
    }

    #[test]
    fn only_stages_at_work_have_a_bar() {
        let mut m = BarModel::new(&totals(&[("ingest", 3), ("ortho", 2), ("synth", 1)]));
        assert_eq!(m.overall(), (0, 6));
        assert!(m.shown().is_empty(), "nothing runs yet");
        assert!(m.start("synth"));
        assert!(!m.start("synth"), "one bar per stage");
        assert_eq!(m.shown(), vec!["synth"]);
        let f = m.finish("synth").unwrap();
        assert_eq!((f.stage_done, f.stage_total, f.hide), (1, 1, true));
        assert!(m.shown().is_empty(), "a finished stage's bar goes away");
        assert!(m.start("ingest") && m.start("ortho"));
        assert_eq!(m.shown(), vec!["ingest", "ortho"]);
        assert!(!m.finish("ingest").unwrap().hide);
        assert_eq!(m.stage("ingest"), Some((1, 3)));
        assert!(!m.finish("ingest").unwrap().hide);
        assert!(m.finish("ingest").unwrap().hide);
        assert_eq!(m.shown(), vec!["ortho"]);
        assert_eq!(m.overall(), (4, 6));
    }

    #[test]
    fn cached_stages_never_show_a_bar_and_a_finished_stage_is_not_shown_again() {
        let mut m = BarModel::new(&totals(&[("load", 1), ("refine", 2)]));
        // Cached nodes are done without running: counted overall, no bar.
        let f = m.finish("load").unwrap();
        assert_eq!((f.stage_done, f.stage_total, f.hide), (1, 1, false));
        assert!(!m.start("load"), "a finished stage is not shown again");
        assert!(m.shown().is_empty());
        assert_eq!(m.finish("unknown"), None);
        // Over-reporting never counts past the totals.
        m.finish("refine");
        m.finish("refine");
        m.finish("refine");
        assert_eq!(m.stage("refine"), Some((2, 2)));
        assert_eq!(m.overall(), (3, 3));
    }
}
