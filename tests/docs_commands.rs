//! The documentation cannot rot: every `skytie …` command line in the fenced code blocks of README.md,
//! ARCHITECTURE.md, workflows/README.md and docs/*.md parses with the program's own command-line parser, and the
//! cheap ones run for real (the real binary, in a scratch folder per document, in document order); every
//! relative link resolves; nothing names a path outside the repository; the README's test command is the one
//! `.ci/run` runs.
//!
//! Which commands run: help and version requests, `workflows`, `params`, `init`, `synth --preset tiny`, `cache` without
//! absolute paths, `plan` of a built-in workflow or of a file the document wrote (planning stops before the
//! campaign phase, so it loads and checks the workflow), and `check` / `tool` when every input they name exists
//! in the scratch folder (for example a campaign an earlier `synth` or `init` line of the same document wrote).
//! The others — `run`, `explain`, `report`, `import`, and anything naming the user's own data — are parse-only:
//! they need a campaign, vendor files or a finished run that a documentation example cannot provide.

use clap::error::ErrorKind;
use clap::Parser;
use skytie::cli::Cli;
use std::path::{Path, PathBuf};
use std::process::Command;

const BIN: &str = env!("CARGO_BIN_EXE_skytie");

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The documents whose examples are checked, README first.
fn documents() -> Vec<PathBuf> {
    let root = repo();
    let mut docs: Vec<PathBuf> = std::fs::read_dir(root.join("docs"))
        .expect("docs/ exists")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "md"))
        .collect();
    docs.sort();
    let mut all = vec![
        root.join("README.md"),
        root.join("ARCHITECTURE.md"),
        root.join("workflows/README.md"),
    ];
    all.extend(docs);
    all
}

fn rel(path: &Path) -> String {
    path.strip_prefix(repo())
        .unwrap_or(path)
        .display()
        .to_string()
}

/// One command line found in a document.
#[derive(Debug)]
struct DocCommand {
    file: PathBuf,
    line: usize,
    text: String,
    /// The arguments after `skytie`.
    args: Vec<String>,
    /// `> FILE`: where the example sends standard output.
    stdout_to: Option<String>,
}

impl DocCommand {
    fn at(&self) -> String {
        format!("{}:{}: `{}`", rel(&self.file), self.line, self.text)
    }
}

/// Languages of fenced blocks that hold shell commands.
fn is_shell_block(info: &str) -> bool {
    matches!(info, "" | "sh" | "bash" | "shell" | "console" | "zsh")
}

/// The `skytie` command lines of the shell blocks of a Markdown text: (line number, command text). A line ending
/// in `\` continues on the next; a leading `$ ` prompt is dropped; `cargo run [--release] -- ARGS` counts as
/// `skytie ARGS`.
fn command_lines(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut fence: Option<(String, bool)> = None; // (fence marker, shell block)
    let mut pending: Option<(usize, String)> = None;
    for (i, raw) in text.lines().enumerate() {
        let line = raw.trim();
        if line.starts_with("```") || line.starts_with("~~~") {
            let marker = &line[..3];
            match &fence {
                Some((m, _)) if m == marker => fence = None,
                None => {
                    let info = line[3..].split_whitespace().next().unwrap_or("");
                    fence = Some((marker.to_string(), is_shell_block(info)));
                }
                _ => {}
            }
            continue;
        }
        let Some((_, true)) = &fence else { continue };
        let (start, mut joined) = pending.take().unwrap_or((i + 1, String::new()));
        joined.push_str(line.strip_prefix("$ ").unwrap_or(line));
        if let Some(cont) = joined.strip_suffix('\\') {
            pending = Some((start, format!("{} ", cont.trim_end())));
            continue;
        }
        let command = ["cargo run --release -- ", "cargo run -- "]
            .iter()
            .find_map(|p| joined.strip_prefix(p).map(|rest| format!("skytie {rest}")))
            .unwrap_or(joined);
        if command == "skytie" || command.starts_with("skytie ") {
            out.push((start, command));
        }
    }
    out
}

/// Split a shell command line into words (quotes, backslashes and `#` comments as the shell treats them); stop at
/// a pipe, `;` or `&&`; return the words and the target of a `>` redirection.
fn shell_words(line: &str) -> Result<(Vec<String>, Option<String>), String> {
    let mut words = Vec::new();
    let mut redirect = None;
    let mut word = String::new();
    let mut in_word = false;
    let mut to_redirect = false;
    let mut chars = line.chars().peekable();
    let mut finish = |word: &mut String, in_word: &mut bool, to_redirect: &mut bool| {
        if *in_word {
            if *to_redirect {
                redirect = Some(std::mem::take(word));
                *to_redirect = false;
            } else {
                words.push(std::mem::take(word));
            }
        }
        *in_word = false;
    };
    while let Some(c) = chars.next() {
        match c {
            '\'' => {
                in_word = true;
                loop {
                    match chars.next() {
                        Some('\'') => break,
                        Some(x) => word.push(x),
                        None => return Err("unterminated ' quote".into()),
                    }
                }
            }
            '"' => {
                in_word = true;
                loop {
                    match chars.next() {
                        Some('"') => break,
                        Some('\\') => word.extend(chars.next()),
                        Some(x) => word.push(x),
                        None => return Err("unterminated \" quote".into()),
                    }
                }
            }
            '\\' => {
                in_word = true;
                word.extend(chars.next());
            }
            '#' if !in_word => break,
            '|' | ';' => break,
            '&' if chars.peek() == Some(&'&') => break,
            '>' => {
                finish(&mut word, &mut in_word, &mut to_redirect);
                if chars.peek() == Some(&'>') {
                    chars.next();
                }
                to_redirect = true;
            }
            c if c.is_whitespace() => finish(&mut word, &mut in_word, &mut to_redirect),
            c => {
                in_word = true;
                word.push(c);
            }
        }
    }
    finish(&mut word, &mut in_word, &mut to_redirect);
    Ok((words, redirect))
}

/// Every command of one document.
fn commands_of(file: &Path) -> Vec<Result<DocCommand, String>> {
    let text = std::fs::read_to_string(file).unwrap_or_else(|e| panic!("{}: {e}", rel(file)));
    command_lines(&text)
        .into_iter()
        .map(|(line, text)| {
            let at = format!("{}:{line}: `{text}`", rel(file));
            let (words, stdout_to) = shell_words(&text).map_err(|e| format!("{at}: {e}"))?;
            let words: Vec<String> = words.into_iter().skip_while(|w| w.contains('=')).collect();
            Ok(DocCommand {
                file: file.to_path_buf(),
                line,
                text,
                args: words.into_iter().skip(1).collect(),
                stdout_to,
            })
        })
        .collect()
}

/// `None` when the command line parses (a help or version request counts), else the parser's complaint.
fn parse_problem(c: &DocCommand) -> Option<String> {
    let argv = std::iter::once("skytie".to_string()).chain(c.args.iter().cloned());
    match Cli::try_parse_from(argv) {
        Ok(_) => None,
        Err(e)
            if matches!(
                e.kind(),
                ErrorKind::DisplayHelp
                    | ErrorKind::DisplayVersion
                    | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
            ) =>
        {
            None
        }
        Err(e) => Some(
            e.to_string()
                .lines()
                .next()
                .unwrap_or("does not parse")
                .to_string(),
        ),
    }
}

#[test]
fn every_documented_command_parses() {
    let mut problems = Vec::new();
    let mut count = 0;
    for doc in documents() {
        for c in commands_of(&doc) {
            count += 1;
            match c {
                Err(e) => problems.push(e),
                Ok(c) => {
                    if let Some(p) = parse_problem(&c) {
                        problems.push(format!("{}: {p}", c.at()));
                    }
                }
            }
        }
    }
    assert!(
        count >= 20,
        "only {count} skytie commands found in the documents"
    );
    assert!(
        problems.is_empty(),
        "documented commands that the CLI does not accept:\n{}",
        problems.join("\n")
    );
}

/// What running a command for real must give: the allowed exit codes, or `None` for parse-only.
fn run_for_real(c: &DocCommand, dir: &Path) -> Option<&'static [i32]> {
    let args: Vec<&str> = c.args.iter().map(String::as_str).collect();
    let help = args
        .iter()
        .any(|a| matches!(*a, "--help" | "-h" | "--version" | "-V"))
        || args.first() == Some(&"help")
        || args.is_empty();
    if help {
        return Some(&[0]);
    }
    let outside = args
        .iter()
        .any(|a| a.starts_with('/') || a.starts_with("..") || a.starts_with('~'));
    if outside {
        return None;
    }
    // Positional arguments and the values of input options must exist for `check` and `tool`.
    let inputs_exist = || {
        let mut it = args.iter().skip(1).peekable();
        let mut ok = true;
        while let Some(a) = it.next() {
            if let Some(flag) = a.strip_prefix("--") {
                let takes_value = it.peek().is_some_and(|v| !v.starts_with("--"));
                let value = if takes_value { it.next() } else { None };
                if matches!(flag, "campaign" | "points") {
                    ok &= value.is_some_and(|v| dir.join(v).exists());
                }
            } else if args[0] == "check" || *a != args[1] {
                ok &= dir.join(a).exists();
            }
        }
        ok
    };
    match args[0] {
        "workflows" | "init" | "params" => Some(&[0]),
        "synth" if args.windows(2).any(|w| w == ["--preset", "tiny"]) => Some(&[0]),
        "cache" => Some(&[0]),
        // Planning stops before the campaign phase has run, so it only loads and checks the workflow.
        "plan" if args.len() > 1 && builtin_or_file(args[1], dir) => Some(&[0]),
        "check" if inputs_exist() => Some(&[0, 1]),
        "tool" if inputs_exist() => Some(&[0]),
        _ => None,
    }
}

/// A built-in workflow's name, or a file that exists in the scratch folder.
fn builtin_or_file(workflow: &str, dir: &Path) -> bool {
    skytie::cli::builtin_workflows::names().contains(&workflow) || dir.join(workflow).is_file()
}

#[test]
fn the_cheap_documented_commands_run() {
    let mut failures = Vec::new();
    let mut ran = 0;
    for doc in documents() {
        let scratch = tempfile::tempdir().unwrap();
        let dir = scratch.path();
        for c in commands_of(&doc).into_iter().flatten() {
            let Some(allowed) = run_for_real(&c, dir) else {
                continue;
            };
            let out = Command::new(BIN)
                .args(&c.args)
                .current_dir(dir)
                .env_remove("SKYTIE_CACHE")
                .output()
                .expect("the skytie binary starts");
            ran += 1;
            let code = out.status.code();
            println!("{} -> exit {code:?}", c.at());
            if let Some(target) = &c.stdout_to {
                std::fs::write(dir.join(target), &out.stdout).unwrap();
            }
            if !code.is_some_and(|code| allowed.contains(&code)) {
                failures.push(format!(
                    "{}: exit {code:?} (expected one of {allowed:?})\n{}",
                    c.at(),
                    String::from_utf8_lossy(&out.stderr)
                ));
            }
        }
    }
    assert!(ran >= 10, "only {ran} documented commands were run");
    assert!(
        failures.is_empty(),
        "documented commands that fail:\n{}",
        failures.join("\n")
    );
}

/// The link targets `](target)` of a Markdown text with their line numbers.
fn links(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let mut rest = line;
        while let Some(p) = rest.find("](") {
            rest = &rest[p + 2..];
            let Some(end) = rest.find(')') else { break };
            out.push((i + 1, rest[..end].to_string()));
            rest = &rest[end..];
        }
    }
    out
}

/// The anchors of a Markdown text's headings, as GitHub makes them: lower case, letters, digits, `-` and `_`
/// kept, spaces turned into `-`, everything else dropped.
fn anchors(text: &str) -> Vec<String> {
    let mut in_code = false;
    let mut out = Vec::new();
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            in_code = !in_code;
        }
        let Some(heading) = line.strip_prefix('#').filter(|_| !in_code) else {
            continue;
        };
        let title = heading.trim_start_matches('#').trim();
        out.push(
            title
                .to_lowercase()
                .chars()
                .filter_map(|c| match c {
                    ' ' => Some('-'),
                    c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
                    _ => None,
                })
                .collect(),
        );
    }
    out
}

#[test]
fn relative_links_resolve() {
    let mut broken = Vec::new();
    for doc in documents() {
        let text = std::fs::read_to_string(&doc).unwrap();
        for (line, target) in links(&text) {
            if target.contains("://") || target.starts_with("mailto:") {
                continue;
            }
            let (path, anchor) = target.split_once('#').unwrap_or((&target, ""));
            let file = if path.is_empty() {
                doc.clone()
            } else {
                doc.parent().unwrap().join(path)
            };
            let found = if !file.exists() {
                false
            } else if anchor.is_empty() || file.is_dir() {
                true
            } else {
                let linked = std::fs::read_to_string(&file).unwrap_or_default();
                anchors(&linked).iter().any(|a| a == anchor)
            };
            if !found {
                broken.push(format!("{}:{line}: {target}", rel(&doc)));
            }
        }
    }
    assert!(
        broken.is_empty(),
        "links to files or headings that do not exist:\n{}",
        broken.join("\n")
    );
}

/// README, ARCHITECTURE, docs/ and every file of workflows/.
fn user_facing_files() -> Vec<PathBuf> {
    let mut files = documents();
    for entry in std::fs::read_dir(repo().join("workflows"))
        .unwrap()
        .flatten()
    {
        if entry.path().extension().is_some_and(|x| x == "toml") {
            files.push(entry.path());
        }
    }
    files
}

/// `file:line: text` of every line of the user-facing files for which `bad` holds.
fn offending_lines(bad: impl Fn(&str) -> bool) -> Vec<String> {
    let mut found = Vec::new();
    for file in user_facing_files() {
        let text = std::fs::read_to_string(&file).unwrap();
        for (i, line) in text.lines().enumerate().filter(|(_, l)| bad(l)) {
            found.push(format!("{}:{}: {}", rel(&file), i + 1, line.trim()));
        }
    }
    found
}

#[test]
fn nothing_refers_to_a_path_outside_the_repository() {
    let found = offending_lines(|line| {
        // `concat!` keeps this file itself free of the path it looks for.
        [
            concat!("..", "/shared"),
            "shared/docs/",
            "shared/reference/",
            "/work/",
        ]
        .iter()
        .any(|needle| line.contains(needle))
    });
    assert!(
        found.is_empty(),
        "paths outside the repository:\n{}",
        found.join("\n")
    );
}

/// A line's words outside `code spans`, lower case.
fn prose(line: &str) -> String {
    line.split('`')
        .step_by(2)
        .collect::<Vec<_>>()
        .join(" ")
        .to_lowercase()
}

/// An ISO date (`2024-05-17`) that is not the start of a timestamp (`2024-05-17T10:31:07Z`).
fn has_bare_date(line: &str) -> bool {
    let b = line.as_bytes();
    (0..b.len().saturating_sub(9)).any(|i| {
        let d = |k: usize| b[i + k].is_ascii_digit();
        let boundary = i == 0 || !b[i - 1].is_ascii_alphanumeric();
        let after = b.get(i + 10).copied();
        boundary
            && b[i] == b'2'
            && b[i + 1] == b'0'
            && d(2)
            && d(3)
            && b[i + 4] == b'-'
            && d(5)
            && d(6)
            && b[i + 7] == b'-'
            && d(8)
            && d(9)
            && !after.is_some_and(|c| c == b'T' || c.is_ascii_digit())
    })
}

/// Whether a line speaks of the project's history: an issue number, a session, a to-do, a dated finding.
fn is_history(line: &str) -> bool {
    let p = prose(line);
    let words: Vec<&str> = p
        .split(|c: char| !c.is_alphanumeric() && c != '#')
        .filter(|w| !w.is_empty())
        .collect();
    let number = |w: &str| {
        w.trim_start_matches('#')
            .starts_with(|c: char| c.is_ascii_digit())
    };
    let issue_ref = words.windows(2).any(|w| w[0] == "issue" && number(w[1]))
        || words
            .iter()
            .any(|w| w.starts_with('#') && w[1..].parse::<u32>().is_ok());
    let process = words
        .iter()
        .any(|w| matches!(*w, "session" | "todo" | "fixme"))
        || p.contains("known failing");
    issue_ref || process || has_bare_date(line)
}

#[test]
fn user_documents_carry_no_development_history() {
    let found = offending_lines(is_history);
    assert!(
        found.is_empty(),
        "development history belongs in commit messages, not in user documents:\n{}",
        found.join("\n")
    );
}

#[test]
fn the_readme_test_command_is_the_one_ci_runs() {
    let readme = std::fs::read_to_string(repo().join("README.md")).unwrap();
    let ci = std::fs::read_to_string(repo().join(".ci/run")).unwrap();
    let command = "cargo test --release";
    let in_readme = readme.lines().any(|l| l.trim_start().starts_with(command));
    let in_ci = ci.lines().any(|l| l.trim_start().starts_with(command));
    assert!(
        in_readme && in_ci,
        "README.md shows `{command}` as a command line: {in_readme}; .ci/run runs it: {in_ci}"
    );
}

#[test]
fn the_extraction_knows_the_shell_forms() {
    let text = "text\n```sh\n$ skytie run tiny   # comment\nskytie workflows show nadir > my.toml\n\
                skytie explain tiny 'adjust[combined]' \\\n  --cache c\ncargo run --release -- run\n\
                echo skytie\n```\n```toml\nskytie = 1\n```\n";
    let lines = command_lines(text);
    let texts: Vec<&str> = lines.iter().map(|(_, t)| t.as_str()).collect();
    assert_eq!(
        texts,
        [
            "skytie run tiny   # comment",
            "skytie workflows show nadir > my.toml",
            "skytie explain tiny 'adjust[combined]' --cache c",
            "skytie run",
        ]
    );
    assert_eq!(lines[2].0, 5);
    let (words, redirect) = shell_words("skytie workflows show nadir > my.toml").unwrap();
    assert_eq!(words, ["skytie", "workflows", "show", "nadir"]);
    assert_eq!(redirect.as_deref(), Some("my.toml"));
    let (words, _) =
        shell_words("skytie explain tiny 'adjust[combined]' --cache \"a b\" # x").unwrap();
    assert_eq!(
        words,
        [
            "skytie",
            "explain",
            "tiny",
            "adjust[combined]",
            "--cache",
            "a b"
        ]
    );
    assert!(has_bare_date("measured 2026-11-24 on"));
    assert!(!has_bare_date("time 2019-06-14T10:31:07Z"));
    assert!(!has_bare_date("EPSG:28992+5709"));
    // Built at run time so that this file does not itself carry the words it checks for.
    assert!(is_history(&format!("as {} 6 (b) asked", "issue")));
    assert!(is_history(&format!("fixed in this {}", "session")));
    assert!(is_history("measured 2026-11-24"));
    assert!(!is_history("`Session` (staged phases), `Pipeline`"));
    assert!(!is_history("see [cli.md](cli.md#exit-codes) and ## Sweeps"));
    assert_eq!(
        anchors("# A\n## `skytie plan` — what would run, and why\n```\n# not a heading\n```\n### Façades 4.4.2"),
        ["a", "skytie-plan--what-would-run-and-why", "façades-442"]
    );
}
