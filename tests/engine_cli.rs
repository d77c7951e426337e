//! The real `skytie` binary on toy workflows: run/plan/explain, metrics and provenance files, sweeps, exit
//! codes, two concurrent runs on one cache, and a run killed with SIGKILL then resumed.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_skytie");

struct Toy {
    dir: tempfile::TempDir,
}

impl Toy {
    /// A toy campaign of `n` items (values 1..=n) and a workflow with `extra` appended.
    fn new(n: usize, extra: &str) -> Toy {
        let dir = tempfile::tempdir().unwrap();
        for i in 0..n {
            let p = dir
                .path()
                .join("camp/items")
                .join(format!("item_{i:03}.txt"));
            std::fs::create_dir_all(p.parent().unwrap()).unwrap();
            std::fs::write(&p, format!("{}\n", i + 1)).unwrap();
        }
        let t = Toy { dir };
        t.workflow(extra);
        t
    }
    fn workflow(&self, extra: &str) {
        let text = format!(
            "name = \"toytest\"\npipeline = \"toy\"\ncampaign = \"camp\"\nstages = [\"toy_parse\", \"toy_scale\", \"toy_sum\"]\n{extra}"
        );
        std::fs::write(self.wf(), text).unwrap();
    }
    fn wf(&self) -> PathBuf {
        self.dir.path().join("toy.toml")
    }
    fn cache(&self) -> PathBuf {
        self.dir.path().join("cache")
    }
    fn out(&self) -> PathBuf {
        self.dir.path().join("out")
    }
    fn cmd(&self, args: &[&str]) -> Command {
        let mut c = Command::new(BIN);
        c.args(args)
            .env_remove("SKYTIE_CACHE")
            .current_dir(self.dir.path());
        c
    }
    fn run_args(&self, out: &Path, threads: &str) -> Vec<String> {
        let mut v: Vec<String> = vec![
            "run".into(),
            self.wf().display().to_string(),
            "--cache".into(),
        ];
        v.push(self.cache().display().to_string());
        v.extend([
            "--out".into(),
            out.display().to_string(),
            "--threads".into(),
            threads.into(),
            "--quiet".into(),
        ]);
        v
    }
    fn run(&self) -> Output {
        let args = self.run_args(&self.out(), "2");
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        self.cmd(&args).output().unwrap()
    }
    fn metrics(&self, out: &Path) -> Value {
        serde_json::from_slice(&std::fs::read(out.join("metrics.json")).unwrap()).unwrap()
    }
    /// `run`, which must succeed, and its metrics.
    fn run_ok(&self) -> (Output, Value) {
        let o = self.run();
        assert!(o.status.success(), "{}", text(&o));
        let m = self.metrics(&self.out());
        (o, m)
    }
}

fn text(o: &Output) -> String {
    format!(
        "status {:?}\nstdout:\n{}\nstderr:\n{}",
        o.status,
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

fn engine(m: &Value, field: &str) -> u64 {
    m["engine"][field]
        .as_u64()
        .unwrap_or_else(|| panic!("engine.{field} missing in {m}"))
}

#[test]
fn run_twice_then_plan_and_explain() {
    let t = Toy::new(4, "[toy_scale]\nfactor = 2.0\n");
    let (o, m) = t.run_ok();
    assert_eq!(
        (
            engine(&m, "nodes_total"),
            engine(&m, "nodes_executed"),
            engine(&m, "nodes_cached")
        ),
        (9, 9, 0)
    );
    assert_eq!(m["stages"]["toy_scale"]["executed"], 4);
    assert_eq!(m["toy"]["sum"], 20.0);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("9 nodes: 9 executed, 0 cached, 0 failed, 0 skipped"),
        "node counts: {stdout}"
    );
    assert!(
        stdout.trim_end().ends_with("(exit 0)"),
        "last line: {stdout}"
    );
    let prov: Value =
        serde_json::from_slice(&std::fs::read(t.out().join("provenance.json")).unwrap()).unwrap();
    let wf_hash = blake3::hash(&std::fs::read(t.wf()).unwrap())
        .to_hex()
        .to_string();
    assert_eq!(prov["workflow"]["file_hash"], wf_hash.as_str());
    assert_eq!(prov["raw_inputs"].as_object().unwrap().len(), 4);
    assert_eq!(
        prov["stages"]["toy_scale"]["params"]["default"]["factor"],
        2.0
    );
    assert_eq!(prov["outputs"]["toy_sum"]["status"], "executed");

    let (_, m) = t.run_ok();
    assert_eq!(
        (engine(&m, "nodes_executed"), engine(&m, "nodes_cached")),
        (0, 9)
    );
    assert_eq!(m["toy"]["sum"], 20.0);

    t.workflow("[toy_scale]\nfactor = 3.0\n");
    let cache = t.cache().display().to_string();
    let wf = t.wf().display().to_string();
    let o = t.cmd(&["plan", &wf, "--cache", &cache]).output().unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let plan = String::from_utf8_lossy(&o.stdout);
    assert!(
        plan.contains("toy_scale[item_001]: param changed: factor: 2.0 -> 3.0"),
        "{plan}"
    );
    assert!(plan.contains("total: 4 cached, 5 will run"), "{plan}");

    let o = t
        .cmd(&["explain", &wf, "toy_parse[item_002]", "--cache", &cache])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    let ex = String::from_utf8_lossy(&o.stdout);
    assert!(
        ex.contains("stage     toy_parse (version 1)") && ex.contains("item_002.txt"),
        "{ex}"
    );
    assert!(
        ex.contains("status    cached") && ex.contains("last run  [default] key"),
        "{ex}"
    );
    let o = t
        .cmd(&["explain", &wf, "nope", "--cache", &cache])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
}

#[test]
fn sweep_writes_per_variant_metrics_and_sweep_csv() {
    let sweep = "[[sweep.variant]]\nname = \"a\"\n\n[[sweep.variant]]\nname = \"b\"\n\"toy_sum.offset\" = 100.0\n";
    let t = Toy::new(3, sweep);
    let (_, m) = t.run_ok();
    // 3 parse + 3 scale shared, one sum per variant.
    assert_eq!(
        (engine(&m, "nodes_total"), engine(&m, "nodes_executed")),
        (8, 8)
    );
    let a: Value =
        serde_json::from_slice(&std::fs::read(t.out().join("variants/a/metrics.json")).unwrap())
            .unwrap();
    let b: Value =
        serde_json::from_slice(&std::fs::read(t.out().join("variants/b/metrics.json")).unwrap())
            .unwrap();
    assert_eq!(
        (a["toy"]["sum"].as_f64(), b["toy"]["sum"].as_f64()),
        (Some(12.0), Some(112.0))
    );
    assert_eq!(engine(&b, "nodes_total"), 7);
    let csv = std::fs::read_to_string(t.out().join("sweep.csv")).unwrap();
    assert_eq!(csv, "variant,toy.count,toy.sum\na,3,12\nb,3,112\n");
}

#[test]
fn exit_codes_say_failed_partial_or_complete() {
    // The only output fails: exit 1, failure listed.
    let t = Toy::new(3, "[toy_scale.faults]\nfail_item = \"item_001\"\n");
    let o = t.run();
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("toy_scale[item_001]: toy failure injected"),
        "{stdout}"
    );
    assert!(
        stdout.contains("toy_sum (upstream toy_scale[item_001])"),
        "{stdout}"
    );
    let m = t.metrics(&t.out());
    assert_eq!(
        (engine(&m, "nodes_failed"), engine(&m, "nodes_skipped")),
        (1, 1)
    );
    // One variant of two fails: still useful, but partial: exit 3, said in the last line.
    t.workflow("[[sweep.variant]]\nname = \"ok\"\n\n[[sweep.variant]]\nname = \"bad\"\n\"toy_sum.faults.panic_item\" = \"*\"\n");
    let o = t.run();
    assert_eq!(o.status.code(), Some(3), "{}", text(&o));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout
            .trim_end()
            .lines()
            .last()
            .is_some_and(|l| l.starts_with("run PARTIAL: 1 node(s) failed")),
        "{stdout}"
    );
    assert_eq!(engine(&t.metrics(&t.out()), "nodes_failed"), 1);
    // A workflow error: exit 2 with file:line:col.
    t.workflow("[toy_scale]\nfactr = 1.0\n");
    let o = t.run();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stderr.contains("toy.toml:6:1") && stderr.contains("factor"),
        "{stderr}"
    );
}

#[test]
fn two_concurrent_runs_on_one_cache_are_both_correct() {
    let t = Toy::new(
        12,
        "[toy_parse.faults]\nsleep_ms = 20\n[toy_scale.faults]\nsleep_ms = 20\n",
    );
    let outs = [t.dir.path().join("out1"), t.dir.path().join("out2")];
    let children: Vec<_> = outs
        .iter()
        .map(|out| {
            let args = t.run_args(out, "2");
            let args: Vec<&str> = args.iter().map(String::as_str).collect();
            t.cmd(&args)
                .stdout(Stdio::piped())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    for c in children {
        let o = c.wait_with_output().unwrap();
        assert!(o.status.success(), "{}", text(&o));
    }
    for out in &outs {
        let m = t.metrics(out);
        assert_eq!(m["toy"]["sum"], 156.0, "2 * (1 + … + 12)");
        assert_eq!(engine(&m, "nodes_failed"), 0);
    }
    // Afterwards the cache holds everything exactly once per key and a third run executes nothing.
    let (_, m) = t.run_ok();
    assert_eq!(engine(&m, "nodes_executed"), 0);
}

#[test]
fn a_run_killed_mid_way_is_resumed_with_finished_nodes_reused() {
    let t = Toy::new(12, "[toy_parse.faults]\nsleep_ms = 120\n");
    let args = t.run_args(&t.out(), "1");
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let mut child = t
        .cmd(&args)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // Wait until a few nodes have stored their results, then SIGKILL.
    let objects = t.cache().join("objects");
    let stored = || -> usize {
        let Ok(folders) = std::fs::read_dir(&objects) else {
            return 0;
        };
        folders
            .flatten()
            .filter_map(|f| std::fs::read_dir(f.path()).ok())
            .flat_map(|d| d.flatten())
            .filter(|e| !e.file_name().to_string_lossy().starts_with('.'))
            .count()
    };
    let start = Instant::now();
    loop {
        let done = stored();
        if done >= 3 || start.elapsed() > Duration::from_secs(20) {
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.kill().unwrap(); // SIGKILL on Unix
    child.wait().unwrap();
    assert!(
        !t.out().join("metrics.json").exists(),
        "the killed run must not have finished"
    );
    let (_, m) = t.run_ok();
    assert_eq!(m["toy"]["sum"], 156.0);
    let cached = engine(&m, "nodes_cached");
    assert!(cached >= 3, "finished nodes are reused: {m}");
    assert_eq!(engine(&m, "nodes_executed") + cached, 25);
}

#[test]
fn a_relative_cache_path_is_reused_from_another_working_folder() {
    // A generated campaign (`synth:`) records its folder in the cache; given as `--cache cache` from one
    // folder and as `--cache ../cache` from a sub-folder, the cache is the same and nothing runs again.
    let t = Toy::new(0, "");
    std::fs::write(
        t.wf(),
        "name = \"toytest\"\npipeline = \"toy\"\ncampaign = \"synth:tiny\"\n\
         stages = [\"toy_gen\", \"toy_parse\", \"toy_scale\", \"toy_sum\"]\n[toy_gen]\ncount = 3\n",
    )
    .unwrap();
    let sub = t.dir.path().join("sub");
    std::fs::create_dir_all(&sub).unwrap();
    let run_from = |cwd: &Path, cache: &str, out: &str| {
        let o = t
            .cmd(&[
                "run",
                &t.wf().display().to_string(),
                "--cache",
                cache,
                "--out",
                out,
                "--quiet",
            ])
            .current_dir(cwd)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", text(&o));
        t.metrics(&cwd.join(out))
    };
    let first = run_from(t.dir.path(), "cache", "out1");
    assert_eq!(engine(&first, "nodes_cached"), 0, "{first}");
    let again = run_from(&sub, "../cache", "out2");
    assert_eq!(engine(&again, "nodes_executed"), 0, "{again}");
    assert_eq!(first["toy"]["sum"], again["toy"]["sum"]);
}
