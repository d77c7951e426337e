//! `skytie slurm WORKFLOW --shards N --cache SHARED_DIR [...] [--dry-run]`: runs a workflow on a Slurm cluster
//! as three jobs sharing one cache — `prepare` (campaign, loading, image validation), a job array of N shards
//! (`skytie run --shard K/N`, one task per contiguous trajectory segment) after it, and the `merge`
//! (`skytie run --merge N`: adjustment, verification, exports, report) after the whole array
//! (`--dependency=afterok`). The job scripts are written to `OUT/slurm/`; `--dry-run` prints them and the
//! `sbatch` commands instead of submitting. Re-submitting a finished campaign executes nothing (every node is
//! cached); after a failed task, submitting again recomputes only what is missing (`--tasks` limits the array
//! to some shards). See docs/cluster.md.

use crate::cli::common::{exit_code, WorkflowTarget};
use crate::workflow::CampaignSource;
use clap::Args;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Recordings per shard below which array tasks cost more in scheduling than they save.
pub const MIN_RECORDINGS_PER_SHARD: usize = 100;

#[derive(Args, Debug, Clone)]
pub struct SlurmArgs {
    #[command(flatten)]
    pub target: WorkflowTarget,
    /// Output folder, on a file system every node sees (default: `out/<workflow name>/`).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Number of shards (array tasks); each should hold at least 100 recordings.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    pub shards: u64,
    /// Submit only these array tasks (Slurm syntax, e.g. `3,5-6`), e.g. to retry failed shards.
    #[arg(long, value_name = "LIST")]
    pub tasks: Option<String>,
    /// Run at most this many shards at once (`--array=…%M`).
    #[arg(long, value_name = "M")]
    pub max_parallel: Option<u32>,
    /// Slurm partition (`--partition`); default: the cluster's default partition.
    #[arg(long)]
    pub partition: Option<String>,
    /// Slurm account to charge (`--account`).
    #[arg(long)]
    pub account: Option<String>,
    /// CPUs per shard task (`--cpus-per-task`; skytie uses all of them).
    #[arg(long, value_name = "N", default_value_t = 2)]
    pub cpus: u32,
    /// Memory per shard task (`--mem`, Slurm units: 8G, 16000M).
    #[arg(long, value_name = "SIZE", default_value = "8G")]
    pub mem: String,
    /// Time limit per shard task (`--time`, e.g. 4:00:00).
    #[arg(long, value_name = "TIME", default_value = "4:00:00")]
    pub time: String,
    /// CPUs of the prepare and merge jobs (the adjustment runs in the merge).
    #[arg(long, value_name = "N", default_value_t = 4)]
    pub merge_cpus: u32,
    /// Memory of the prepare and merge jobs.
    #[arg(long, value_name = "SIZE", default_value = "16G")]
    pub merge_mem: String,
    /// Time limit of the prepare and merge jobs.
    #[arg(long, value_name = "TIME", default_value = "4:00:00")]
    pub merge_time: String,
    /// Extra `#SBATCH` option for every job (repeatable), e.g. `--sbatch-option=--qos=long`.
    #[arg(long, value_name = "OPTION")]
    pub sbatch_option: Vec<String>,
    /// The skytie binary the jobs run (default: this one).
    #[arg(long, value_name = "PATH")]
    pub skytie: Option<PathBuf>,
    /// Write and print the job scripts and the sbatch commands; submit nothing.
    #[arg(long)]
    pub dry_run: bool,
}

pub fn main(args: &SlurmArgs) -> i32 {
    exit_code(run(args), |()| 0)
}

/// Absolute form of a path (jobs start in another working directory).
fn absolute(p: &Path) -> PathBuf {
    std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf())
}

/// A value the job script puts on a shell command line, single-quoted.
fn quoted(p: &Path) -> String {
    format!("'{}'", p.display().to_string().replace('\'', r"'\''"))
}

/// Everything the three job scripts have in common.
struct Plan {
    name: String,
    command: String,
    logs: PathBuf,
    shards: u64,
}

fn run(args: &SlurmArgs) -> Result<(), (i32, String)> {
    let (wf, _) = args.target.load().map_err(|e| (2, e))?;
    if args.target.cache.cache.is_none() && std::env::var_os("SKYTIE_CACHE").is_none() {
        return Err((
            2,
            "give the shared cache folder with --cache DIR (or SKYTIE_CACHE): every job must see the same cache \
             (with --cache-remote, a node-local folder at the same path on every node)"
                .into(),
        ));
    }
    warn_small_shards(&wf.campaign, args.shards);
    let out = absolute(
        &args
            .out
            .clone()
            .unwrap_or_else(|| Path::new("out").join(&wf.name)),
    );
    let workflow = if args.target.workflow.is_file() {
        absolute(&args.target.workflow)
    } else {
        args.target.workflow.clone()
    };
    let skytie = match &args.skytie {
        Some(p) => absolute(p),
        None => std::env::current_exe().map_err(|e| {
            (
                2,
                format!("cannot tell this program's path ({e}): give --skytie PATH"),
            )
        })?,
    };
    let mut command = format!(
        "{} run {} --cache {} --out {} --threads \"${{SLURM_CPUS_PER_TASK:-0}}\" --quiet",
        quoted(&skytie),
        quoted(&workflow),
        quoted(&absolute(&args.target.cache.root())),
        quoted(&out)
    );
    if let Some(c) = &args.target.campaign {
        command.push_str(&format!(" --campaign {}", quoted(&absolute(c))));
    }
    if let Some(remote) = args.target.cache.remote() {
        command.push_str(&format!(" --cache-remote {}", quoted(Path::new(&remote))));
    }
    let dir = out.join("slurm");
    let plan = Plan {
        name: format!("skytie-{}", wf.name),
        command,
        logs: dir.join("logs"),
        shards: args.shards,
    };
    let scripts = [
        ("prepare.sbatch", prepare_script(args, &plan)),
        ("shards.sbatch", shards_script(args, &plan)),
        ("merge.sbatch", merge_script(args, &plan)),
    ];
    for (name, text) in &scripts {
        skytie_util::fsutil::atomic_write(&dir.join(name), text.as_bytes())
            .map_err(|e| (2, format!("cannot write {}: {e}", dir.join(name).display())))?;
    }
    std::fs::create_dir_all(&plan.logs)
        .map_err(|e| (2, format!("cannot create {}: {e}", plan.logs.display())))?;
    if args.dry_run {
        for (name, text) in &scripts {
            println!("# ---- {} ----\n{text}", dir.join(name).display());
        }
        println!("# ---- submission (not done: --dry-run) ----");
        println!("{}", submit_commands(&dir).join("\n"));
        return Ok(());
    }
    submit(&dir)
}

/// The `#SBATCH` header shared by the jobs.
fn header(args: &SlurmArgs, job: &str, log: &str, cpus: u32, mem: &str, time: &str) -> String {
    let mut h = format!(
        "#!/bin/bash\n#SBATCH --job-name={job}\n#SBATCH --output={log}\n#SBATCH --cpus-per-task={cpus}\n\
         #SBATCH --mem={mem}\n#SBATCH --time={time}\n"
    );
    if let Some(p) = &args.partition {
        h.push_str(&format!("#SBATCH --partition={p}\n"));
    }
    if let Some(a) = &args.account {
        h.push_str(&format!("#SBATCH --account={a}\n"));
    }
    for o in &args.sbatch_option {
        h.push_str(&format!("#SBATCH {o}\n"));
    }
    h
}

fn prepare_script(args: &SlurmArgs, plan: &Plan) -> String {
    let log = plan.logs.join("prepare-%j.log");
    format!(
        "{}# Campaign, loading and image validation, once for all shards.\nset -euo pipefail\n{} --prepare\n",
        header(
            args,
            &format!("{}-prepare", plan.name),
            &log.display().to_string(),
            args.merge_cpus,
            &args.merge_mem,
            &args.merge_time
        ),
        plan.command
    )
}

fn shards_script(args: &SlurmArgs, plan: &Plan) -> String {
    let log = plan.logs.join("shard-%a-%A.log");
    let mut array = args
        .tasks
        .clone()
        .unwrap_or_else(|| format!("1-{}", plan.shards));
    if let Some(m) = args.max_parallel {
        array.push_str(&format!("%{m}"));
    }
    format!(
        "{}#SBATCH --array={array}\n# One contiguous segment of the trajectory per array task.\nset -euo pipefail\n\
         {} --shard \"${{SLURM_ARRAY_TASK_ID}}/{}\"\n",
        header(
            args,
            &format!("{}-shard", plan.name),
            &log.display().to_string(),
            args.cpus,
            &args.mem,
            &args.time
        ),
        plan.command,
        plan.shards
    )
}

fn merge_script(args: &SlurmArgs, plan: &Plan) -> String {
    let log = plan.logs.join("merge-%j.log");
    format!(
        "{}# Adjustment, verification, exports and report from the shards' cached results.\nset -euo pipefail\n\
         {} --merge {}\n",
        header(
            args,
            &format!("{}-merge", plan.name),
            &log.display().to_string(),
            args.merge_cpus,
            &args.merge_mem,
            &args.merge_time
        ),
        plan.command,
        plan.shards
    )
}

/// The sbatch commands, as a shell script would run them.
fn submit_commands(dir: &Path) -> Vec<String> {
    let s = |n: &str| quoted(&dir.join(n));
    vec![
        format!("prepare=$(sbatch --parsable {})", s("prepare.sbatch")),
        format!(
            "shards=$(sbatch --parsable --kill-on-invalid-dep=yes --dependency=afterok:${{prepare%%;*}} {})",
            s("shards.sbatch")
        ),
        format!(
            "merge=$(sbatch --parsable --kill-on-invalid-dep=yes --dependency=afterok:${{shards%%;*}} {})",
            s("merge.sbatch")
        ),
    ]
}

/// `sbatch --parsable [dependency] SCRIPT`; the job id.
fn sbatch(script: &Path, after: Option<&str>) -> Result<String, (i32, String)> {
    let mut cmd = Command::new("sbatch");
    cmd.arg("--parsable");
    if let Some(id) = after {
        cmd.arg("--kill-on-invalid-dep=yes")
            .arg(format!("--dependency=afterok:{id}"));
    }
    let out = cmd.arg(script).output().map_err(|e| {
        (
            1,
            format!("cannot run sbatch ({e}): is Slurm installed here? (--dry-run writes the scripts only)"),
        )
    })?;
    if !out.status.success() {
        return Err((
            1,
            format!(
                "sbatch {} failed: {}",
                script.display(),
                String::from_utf8_lossy(&out.stderr).trim()
            ),
        ));
    }
    let text = String::from_utf8_lossy(&out.stdout);
    // `--parsable` prints "jobid" or "jobid;cluster".
    Ok(text
        .trim()
        .split(';')
        .next()
        .unwrap_or_default()
        .to_string())
}

fn submit(dir: &Path) -> Result<(), (i32, String)> {
    let prepare = sbatch(&dir.join("prepare.sbatch"), None)?;
    let shards = sbatch(&dir.join("shards.sbatch"), Some(&prepare))?;
    let merge = sbatch(&dir.join("merge.sbatch"), Some(&shards))?;
    println!("submitted: prepare job {prepare}, shard array {shards}, merge job {merge}");
    println!(
        "logs in {}; outputs when the merge job ends (squeue -j {merge})",
        dir.join("logs").display()
    );
    Ok(())
}

/// Warn when the campaign's recordings would make shards smaller than [`MIN_RECORDINGS_PER_SHARD`].
fn warn_small_shards(campaign: &CampaignSource, shards: u64) {
    let CampaignSource::Path(root) = campaign else {
        return;
    };
    let Ok((c, _)) = skytie_stages::campaign::read::read_campaign(root) else {
        return;
    };
    let per_shard = c.recordings.len() / usize::try_from(shards).unwrap_or(usize::MAX).max(1);
    if per_shard < MIN_RECORDINGS_PER_SHARD {
        eprintln!(
            "warning: {} recordings in {shards} shards is {per_shard} per shard; an array task costs about a \
             second of scheduling, so use at most {} shards",
            c.recordings.len(),
            (c.recordings.len() / MIN_RECORDINGS_PER_SHARD).max(1)
        );
    }
}
