//! `skytie run [WORKFLOW] [--campaign DIR] [--cache DIR] [--out DIR] [--threads N] [--quiet]`.
//!
//! Runs the workflow's pipeline, then writes `OUT/metrics.json`, `OUT/provenance.json` and, for a sweep,
//! `OUT/variants/<name>/metrics.json` and `OUT/sweep.csv` (default OUT: `out/<workflow name>/`), and prints
//! a summary table (stage, executed, cached, failed, skipped, seconds) plus the failed and skipped nodes.
//!
//! Exit code rule: **0** when the run produced something useful — at least one requested output of the
//! last phase (e.g. the final report/metrics node of one variant) was produced, or, if the pipeline
//! requests no outputs, at least one node succeeded — and nothing was lost: no input row dropped by
//! validation, no node failed or skipped. **3** (partial success) when it produced something useful but input
//! rows were dropped (counted in `campaign.input_errors`, `campaign.dropped_rows`) or nodes failed or were
//! skipped (`engine.nodes_failed` / `engine.nodes_skipped`); the outputs cover the rest. The last line of
//! the output says which, with the counts, also with `--quiet`. **1** when nothing useful was produced:
//! the pipeline stopped with an error (e.g. the campaign could not be generated or read) or every
//! requested output failed or was skipped. **2** for usage/setup errors before anything ran (workflow does
//! not load, unknown pipeline, cache cannot be opened) or when the output files cannot be written.

use crate::cli::common::{
    exit_code, load_workflow, print_problems, CacheOpt, ThreadsOpt, DEFAULT_WORKFLOW,
};
use crate::cli::shard::ShardOpt;
use crate::dag::progress::{Progress, ProgressMode};
use crate::dag::{Mode, NodeStatus, Partition, PipelineError, Session};
use crate::hashing::StatCache;
use crate::metrics::{add_sections, sweep_csv, write_json, Summary};
use crate::report::headline::{Headline, Status};
use crate::workflow::Workflow;
use clap::Args;
use std::path::{Path, PathBuf};
use std::time::{Instant, SystemTime, UNIX_EPOCH};

#[derive(Args, Debug, Clone)]
pub struct RunArgs {
    /// Workflow: a built-in name (`skytie workflows` lists them) or a TOML file.
    #[arg(default_value = DEFAULT_WORKFLOW)]
    pub workflow: PathBuf,
    /// Use this campaign folder instead of the workflow's `campaign`.
    #[arg(long, value_name = "DIR")]
    pub campaign: Option<PathBuf>,
    #[command(flatten)]
    pub cache: CacheOpt,
    /// Output folder (default: `out/<workflow name>/`).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    #[command(flatten)]
    pub threads: ThreadsOpt,
    /// Memory budget for decoding images, e.g. 4G (suffixes K, M, G, T; default: a quarter of the available
    /// memory, 512 MiB to 2 GiB, or $SKYTIE_MEMORY_BUDGET). The image tile cache takes a quarter of it.
    #[arg(long, value_name = "SIZE")]
    pub memory_budget: Option<String>,
    /// Print only errors and the final summary.
    #[arg(long)]
    pub quiet: bool,
    /// Also print the per-stage table (nodes executed / cached / failed / skipped, seconds).
    #[arg(long)]
    pub timings: bool,
    #[command(flatten)]
    pub shard: ShardOpt,
}

/// What a finished run reports back (for the exit code and for tests).
pub struct RunResult {
    pub exit_code: i32,
    pub out_dir: PathBuf,
    pub summary: Summary,
}

pub fn main(args: &RunArgs) -> i32 {
    exit_code(run(args), |r| r.exit_code)
}

/// Run a workflow as the CLI does. Err = (exit code, message).
pub fn run(args: &RunArgs) -> Result<RunResult, (i32, String)> {
    if let Some(size) = &args.memory_budget {
        let bytes = skytie_stages::imaging::budget::parse_size(size)
            .map_err(|e| (2, format!("--memory-budget {size}: {e}")))?;
        skytie_stages::imaging::budget::global().set_total(bytes);
    }
    let (wf, pipeline) =
        load_workflow(&args.workflow, args.campaign.as_deref()).map_err(|e| (2, e))?;
    let store = args.cache.open().map_err(|e| (2, e))?;
    let _lease = store
        .begin_run()
        .map_err(|e| (2, format!("cannot register the run in the cache: {e}")))?;
    let stat_cache = StatCache::open(store.root());
    let progress = Progress::new(if args.quiet {
        ProgressMode::Quiet
    } else {
        ProgressMode::Auto
    });
    let out_dir = args
        .out
        .clone()
        .unwrap_or_else(|| Path::new("out").join(&wf.name));
    let started_unix_s = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0);
    let start = Instant::now();
    let partition = args.shard.partition();
    let mut session = Session::new(&store, &stat_cache, &progress, Mode::Run);
    session.partition = partition;
    session.out_dir = partition.writes_outputs().then(|| out_dir.clone());
    let result = args
        .threads
        .install(|| pipeline.run(&wf, &mut session))
        .map_err(|e| (2, e))?;
    if let Err(PipelineError::Workflow(m)) = &result {
        return Err((2, m.clone()));
    }
    if let (Partition::Merge { .. }, Err(e)) = (partition, &result) {
        // Nothing of the campaign's outputs is written until every shard is complete.
        return Err((1, e.to_string()));
    }
    let wall = start.elapsed().as_secs_f64();
    if let Err(e) = stat_cache.save() {
        progress.warn(&format!("could not save the stat cache: {e}"));
    }
    let summary = Summary::of(session.reports());
    if !partition.writes_outputs() {
        let exit_code =
            super::shard::finish_part(&session, &summary, result, &out_dir, partition, wall)?;
        return Ok(RunResult {
            exit_code,
            out_dir,
            summary,
        });
    }
    let metrics = write_outputs(&wf, &session, &out_dir, started_unix_s, wall).map_err(|e| {
        (
            2,
            format!("cannot write outputs to {}: {e}", out_dir.display()),
        )
    })?;
    // The HTML report (a failure is a warning: the run's outputs are already written).
    let report = crate::report::build_report(
        &out_dir,
        &crate::report::ReportOptions::standard(args.campaign.clone()),
    );
    if let Err(e) = &report {
        progress.warn(&format!("the HTML report was not written: {e}"));
    }
    if args.timings {
        print!("{}", summary.table(wall));
    }
    print_problems(&session);
    let useful = produced_something(&session);
    if let Err(e) = &result {
        eprintln!("error: {e}");
    }
    let t = &summary.total;
    println!(
        "{} nodes: {} executed, {} cached, {} failed, {} skipped ({wall:.0} s{})",
        summary.nodes_total,
        t.executed,
        t.cached,
        t.failed,
        t.skipped,
        if args.timings {
            ""
        } else {
            "; per-stage times with --timings"
        }
    );
    let mut warning = false;
    // The headline speaks of campaigns (the engine's test pipeline has none).
    let campaign_run = metrics.iter().any(|(_, m)| m.get("campaign").is_some());
    for (variant, _) in metrics.iter().filter(|_| campaign_run) {
        let dir = if metrics.len() > 1 {
            out_dir.join("variants").join(variant)
        } else {
            out_dir.clone()
        };
        let h = match Headline::from_dir(&dir) {
            Ok(h) => h,
            Err(e) => {
                progress.warn(&format!("no summary: {e}"));
                continue;
            }
        };
        warning |= matches!(h.status, Status::NotCorrected(_) | Status::Worse(_));
        let lines = h.lines();
        if metrics.len() > 1 {
            println!("[{variant}] {}", lines.first().map_or("", String::as_str));
        } else {
            println!();
            for l in &lines {
                println!("{l}");
            }
            println!("(signs: corrections are adjusted − recorded; offsets MM − aerial; docs/outputs.md)");
        }
    }
    match &report {
        Ok(r) => println!(
            "outputs: {} (report: {})",
            out_dir.display(),
            r.index.display()
        ),
        Err(_) => println!("outputs: {}", out_dir.display()),
    }
    let mut outcome = RunOutcome::of(&session, result.is_ok() && useful);
    outcome.result_warning = warning;
    println!("{}", outcome.last_line(&out_dir));
    let exit_code = outcome.exit_code();
    Ok(RunResult {
        exit_code,
        out_dir,
        summary,
    })
}

/// Exit code of a run that finished but whose result must not be used as it is: input rows dropped, nodes
/// failed or skipped, nothing corrected, or check points worse (the last line says which).
pub const PARTIAL_EXIT_CODE: i32 = 3;

/// What the run's last line and exit code say.
struct RunOutcome {
    useful: bool,
    rows_dropped: u64,
    input_errors: u64,
    failed: usize,
    skipped: usize,
    /// The headline's status asks for attention (nothing corrected, check points worse).
    result_warning: bool,
}

impl RunOutcome {
    fn of(session: &Session<'_>, useful: bool) -> Self {
        let campaign = session
            .metrics()
            .find(|(_, ns, _)| ns == "campaign")
            .map(|(_, _, v)| v.clone())
            .unwrap_or_default();
        let count = |k: &str| campaign.get(k).and_then(|v| v.as_u64()).unwrap_or(0);
        let count_status =
            |f: fn(&NodeStatus) -> bool| session.reports().filter(|r| f(&r.status)).count();
        RunOutcome {
            useful,
            rows_dropped: count("rows_dropped"),
            input_errors: count("input_errors"),
            failed: count_status(|s| matches!(s, NodeStatus::Failed(_))),
            skipped: count_status(|s| matches!(s, NodeStatus::Skipped { .. })),
            result_warning: false,
        }
    }

    fn partial(&self) -> bool {
        self.input_errors > 0 || self.failed > 0 || self.skipped > 0 || self.result_warning
    }

    fn exit_code(&self) -> i32 {
        match (self.useful, self.partial()) {
            (false, _) => 1,
            (true, true) => PARTIAL_EXIT_CODE,
            (true, false) => 0,
        }
    }

    /// One line saying whether everything was processed, what was dropped or failed, and the exit code.
    fn last_line(&self, out_dir: &Path) -> String {
        let mut lost = Vec::new();
        if self.input_errors > 0 {
            lost.push(format!(
                "{} input error(s), {} row(s) dropped (metrics.json campaign.dropped_rows; `skytie check` lists them)",
                self.input_errors, self.rows_dropped
            ));
        }
        if self.failed > 0 {
            lost.push(format!("{} node(s) failed", self.failed));
        }
        if self.skipped > 0 {
            lost.push(format!("{} skipped because an input failed", self.skipped));
        }
        if self.result_warning {
            lost.push(
                "the result must not be used as it is (first line of the summary)".to_string(),
            );
        }
        let code = self.exit_code();
        match (self.useful, lost.is_empty()) {
            (true, true) => format!(
                "run complete: every item processed; outputs in {} (exit 0)",
                out_dir.display()
            ),
            (true, false) => format!(
                "run PARTIAL: {}; outputs in {} cover the rest (exit {code})",
                lost.join(", "),
                out_dir.display()
            ),
            (false, _) => format!(
                "run FAILED: no usable result{}{} (exit {code})",
                if lost.is_empty() { "" } else { "; " },
                lost.join(", ")
            ),
        }
    }
}

/// Whether the run produced anything useful (see the module documentation).
pub fn produced_something(session: &Session<'_>) -> bool {
    let Some(last) = session.phases.last() else {
        return false;
    };
    if last.requested.is_empty() {
        return session.reports().any(|r| r.status.is_ok());
    }
    last.requested
        .iter()
        .any(|&id| last.reports[id].status.is_ok())
}

/// Write metrics.json, provenance.json and, for sweeps, per-variant metrics and sweep.csv. Returns the metrics
/// of each variant (one, `default`, without a sweep).
pub fn write_outputs(
    wf: &Workflow,
    session: &Session<'_>,
    out_dir: &Path,
    started_unix_s: u64,
    wall_seconds: f64,
) -> std::io::Result<Vec<(String, serde_json::Value)>> {
    let mut per_variant = Vec::new();
    let warnings: usize = session.phases.iter().map(|p| p.warnings.len()).sum();
    let summary = Summary::of(session.reports());
    let mut doc = summary.to_json(wall_seconds, warnings);
    let variants = wf.variants();
    if wf.is_sweep() {
        if let serde_json::Value::Object(m) = &mut doc {
            m.insert("variants".into(), serde_json::json!(variants));
        }
        let mut rows = Vec::new();
        for v in &variants {
            let vs = Summary::of(session.reports().filter(|r| r.variants.contains(v)));
            let mut vdoc = vs.to_json(wall_seconds, warnings);
            let sections = || {
                session
                    .metrics()
                    .filter(|(var, _, _)| var == v)
                    .map(|(_, ns, val)| (ns.as_str(), val))
            };
            add_sections(&mut vdoc, sections());
            write_json(
                &out_dir.join("variants").join(v).join("metrics.json"),
                &vdoc,
            )?;
            per_variant.push((v.clone(), vdoc));
            // sweep.csv: the contributed sections.
            let mut row = serde_json::json!({});
            add_sections(&mut row, sections());
            rows.push((v.clone(), row));
        }
        skytie_util::fsutil::atomic_write(&out_dir.join("sweep.csv"), sweep_csv(&rows).as_bytes())?;
    } else {
        add_sections(
            &mut doc,
            session.metrics().map(|(_, ns, val)| (ns.as_str(), val)),
        );
    }
    write_json(&out_dir.join("metrics.json"), &doc)?;
    let prov = crate::provenance::provenance(wf, session, started_unix_s, wall_seconds);
    write_json(&out_dir.join("provenance.json"), &prov)?;
    if per_variant.is_empty() {
        per_variant.push(("default".to_string(), doc));
    }
    Ok(per_variant)
}
