//! Options and setup shared by subcommands: cache location, thread pool, workflow loading.

use crate::dag::Pipeline;
use crate::pipelines::pipeline_by_name;
use crate::store::Store;
use crate::workflow::Workflow;
use clap::Args;
use std::path::{Path, PathBuf};

/// The workflow `skytie run` runs when none is named (built in, see [`super::builtin_workflows`]).
pub const DEFAULT_WORKFLOW: &str = "default";

/// `--cache DIR` (default: `$SKYTIE_CACHE`, else `cache/` in the working directory) and `--cache-remote URL`
/// (default: `$SKYTIE_CACHE_REMOTE`, else none).
#[derive(Args, Debug, Clone, Default)]
pub struct CacheOpt {
    /// Cache folder (default: $SKYTIE_CACHE, else ./cache).
    #[arg(long, value_name = "DIR", global = true)]
    pub cache: Option<PathBuf>,
    /// Remote cache behind the cache folder: s3://BUCKET/PREFIX (S3, MinIO; AWS_* variables) or
    /// file:///PATH (default: $SKYTIE_CACHE_REMOTE, else none). See docs/cache.md.
    #[arg(long, value_name = "URL", global = true)]
    pub cache_remote: Option<String>,
}

impl CacheOpt {
    /// The cache root to use.
    pub fn root(&self) -> PathBuf {
        if let Some(c) = &self.cache {
            return c.clone();
        }
        match std::env::var_os("SKYTIE_CACHE") {
            Some(v) if !v.is_empty() => PathBuf::from(v),
            _ => PathBuf::from("cache"),
        }
    }

    /// The remote cache URL to use, if any.
    pub fn remote(&self) -> Option<String> {
        if let Some(r) = &self.cache_remote {
            return Some(r.clone());
        }
        std::env::var("SKYTIE_CACHE_REMOTE")
            .ok()
            .filter(|v| !v.trim().is_empty())
    }

    /// Open the store, or print why not.
    pub fn open(&self) -> Result<Store, String> {
        let root = self.root();
        Store::open_with_remote(&root, self.remote().as_deref()).map_err(|e| {
            format!(
                "cannot open the cache at {}: {e} (use --cache DIR)",
                root.display()
            )
        })
    }
}

/// The workflow a command works on, its campaign override and the cache: `WORKFLOW [--campaign DIR]
/// [--cache DIR]`, shared by `plan`, `explain` and `slurm`.
#[derive(Args, Debug, Clone)]
pub struct WorkflowTarget {
    /// Workflow: a built-in name (`skytie workflows` lists them) or a TOML file.
    pub workflow: PathBuf,
    /// Use this campaign folder instead of the workflow's `campaign`.
    #[arg(long, value_name = "DIR")]
    pub campaign: Option<PathBuf>,
    #[command(flatten)]
    pub cache: CacheOpt,
}

impl WorkflowTarget {
    /// Load the workflow with the campaign override (see [`load_workflow`]).
    pub fn load(&self) -> Result<(Workflow, &'static dyn Pipeline), String> {
        load_workflow(&self.workflow, self.campaign.as_deref())
    }
}

/// The exit code of a command's result: `ok`'s for a success; for an error (exit code, message) the message
/// printed to stderr and the code.
pub fn exit_code<T>(result: Result<T, (i32, String)>, ok: impl FnOnce(T) -> i32) -> i32 {
    match result {
        Ok(value) => ok(value),
        Err((code, msg)) => {
            eprintln!("error: {msg}");
            code
        }
    }
}

/// `--threads N` (0 = all cores).
#[derive(Args, Debug, Clone, Default)]
pub struct ThreadsOpt {
    /// Worker threads (default: all cores). Results do not depend on it.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub threads: usize,
}

impl ThreadsOpt {
    /// Run `f` in a rayon pool of the requested size.
    pub fn install<R: Send>(&self, f: impl FnOnce() -> R + Send) -> Result<R, String> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(self.threads)
            .build()
            .map_err(|e| format!("cannot start {} worker threads: {e}", self.threads))?;
        Ok(pool.install(f))
    }
}

/// Load a workflow, applying `--campaign`, and find its pipeline (checking the stage names against it).
pub fn load_workflow(
    path: &Path,
    campaign: Option<&Path>,
) -> Result<(Workflow, &'static dyn Pipeline), String> {
    let mut wf = super::builtin_workflows::load(path).map_err(|e| e.to_string())?;
    if let Some(c) = campaign {
        wf.override_campaign(c.to_path_buf());
    }
    let pipeline =
        pipeline_by_name(&wf.pipeline).map_err(|e| format!("{}: {e}", wf.path.display()))?;
    wf.check_stage_names(&pipeline.stage_names())
        .map_err(|e| e.to_string())?;
    pipeline.validate(&wf)?;
    Ok((wf, pipeline))
}

/// Build a workflow's graph in plan mode (nothing executes) and hand the session to `report`, with the note
/// `plan_stop` gives when planning stopped at a phase whose inputs are not computed yet. Shared by `plan` and
/// `explain`. Errors are (exit code, message).
pub fn with_plan_session<T>(
    target: &WorkflowTarget,
    threads: &ThreadsOpt,
    report: impl FnOnce(
        &crate::dag::Session<'_>,
        Option<crate::dag::PipelineError>,
    ) -> Result<T, (i32, String)>,
) -> Result<T, (i32, String)> {
    use crate::dag::progress::{Progress, ProgressMode};
    let (wf, pipeline) = target.load().map_err(|e| (2, e))?;
    let store = target.cache.open().map_err(|e| (2, e))?;
    let stat_cache = crate::hashing::StatCache::open(store.root());
    let progress = Progress::new(ProgressMode::Quiet);
    let mut session =
        crate::dag::Session::new(&store, &stat_cache, &progress, crate::dag::Mode::Plan);
    let result = threads
        .install(|| pipeline.run(&wf, &mut session))
        .map_err(|e| (2, e))?;
    let _ = stat_cache.save();
    let stopped = plan_stop(result).map_err(|e| (1, e.to_string()))?;
    report(&session, stopped)
}

/// Turn a pipeline error of a plan into "planning stopped here" (not an error) or a real error.
pub fn plan_stop(
    result: Result<(), crate::dag::PipelineError>,
) -> Result<Option<crate::dag::PipelineError>, crate::dag::PipelineError> {
    match result {
        Ok(()) => Ok(None),
        Err(e @ crate::dag::PipelineError::NotYetAvailable(_)) => Ok(Some(e)),
        Err(e) => Err(e),
    }
}

/// Print the failed and skipped nodes of a run (at most 30 of each).
pub(crate) fn print_problems(session: &crate::dag::Session<'_>) {
    const MAX: usize = 30;
    let failed: Vec<_> = session
        .reports()
        .filter(|r| matches!(r.status, crate::dag::NodeStatus::Failed(_)))
        .collect();
    let skipped: Vec<_> = session
        .reports()
        .filter(|r| matches!(r.status, crate::dag::NodeStatus::Skipped { .. }))
        .collect();
    if !failed.is_empty() {
        println!("failed ({}):", failed.len());
        for r in failed.iter().take(MAX) {
            if let crate::dag::NodeStatus::Failed(m) = &r.status {
                println!("  {}: {m}", r.identity);
            }
        }
        if failed.len() > MAX {
            println!("  … and {} more", failed.len() - MAX);
        }
    }
    if !skipped.is_empty() {
        println!("skipped (upstream failed) ({}):", skipped.len());
        for r in skipped.iter().take(MAX) {
            if let crate::dag::NodeStatus::Skipped { upstream } = &r.status {
                println!("  {} (upstream {upstream})", r.identity);
            }
        }
        if skipped.len() > MAX {
            println!("  … and {} more", skipped.len() - MAX);
        }
    }
}
