//! The HTML report of a run: `skytie report OUT [--campaign DIR]`, also written at the end of
//! `skytie run`. A pure function of the output folder OUT (plus, optionally, the campaign folder for images
//! and `truth/`): it never runs the pipeline.
//!
//! Writes `OUT/report/index.html` (summary, and for a plain run the result sections; for a sweep the sweep
//! tables and charts plus one page `variant-<name>.html` per variant), figures as SVG / PNG files in
//! `OUT/report/figures/`, and every table also as CSV and Markdown in `OUT/report/tables/`. The same OUT
//! gives byte-identical files (no timestamps except those read from OUT). The tables that describe the run
//! itself rather than its results — wall and node times, nodes executed / served from the cache, when it
//! finished — go to `OUT/report/run-log/` instead, so that re-running a workflow reproduces `tables/`
//! byte-identically (a warm rerun executes nothing and takes less time, which is all that changes).

pub mod headline;
pub mod headline_section;
pub mod html;
pub mod image_cache;
pub mod inputs;
pub mod interactive_map;
pub mod map_background;
pub mod map_data;
pub mod map_thinning;
pub mod plots;
pub mod reasons;
pub mod registration;
pub mod results;
pub mod set_cache;
pub mod summary;
pub mod sweep;
pub mod tables;
pub mod thesis_values;

use html::Page;
use inputs::RunOutputs;
use rayon::prelude::*;
use skytie_util::fsutil::atomic_write;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use tables::Table;

/// How to build a report.
#[derive(Clone, Debug, Default)]
pub struct ReportOptions {
    /// Campaign folder (images, `truth/`); default: the one named in `OUT/provenance.json`.
    pub campaign: Option<PathBuf>,
    /// How many recordings get registration views (0 = none).
    pub registration_views: usize,
}

impl ReportOptions {
    /// The defaults used by `skytie run` and `skytie report`.
    pub fn standard(campaign: Option<PathBuf>) -> Self {
        Self {
            campaign,
            registration_views: 3,
        }
    }
}

/// What was written.
#[derive(Debug)]
pub struct ReportSummary {
    /// `OUT/report/index.html`.
    pub index: PathBuf,
    /// Every page written (index first).
    pub pages: Vec<PathBuf>,
    /// Table ids (each written as `tables/<id>.csv` and `.md`).
    pub tables: Vec<String>,
    /// Ids of the run-log tables (`run-log/<id>.csv` and `.md`).
    pub run_log_tables: Vec<String>,
    /// Figure files written.
    pub figures: Vec<PathBuf>,
    /// Sections left out or degraded, one line each (e.g. "no campaign folder: no true positions").
    pub notes: Vec<String>,
}

/// Shared state while the pages are assembled: where files go, what has been written.
pub struct Builder {
    pub report_dir: PathBuf,
    pub campaign: Option<PathBuf>,
    pub options: ReportOptions,
    tables: Vec<Table>,
    /// Tables about the run itself (times, cache use), written to [`RUN_LOG_DIR`].
    run_log: Vec<Table>,
    table_ids: BTreeSet<String>,
    pub figures: Vec<PathBuf>,
    pub notes: Vec<String>,
    /// Campaign images decoded for the registration views, shared with the variants' builders.
    pub images: std::sync::Arc<image_cache::ImageCache>,
    /// The registration views' campaign, truth and drawn views, shared with the variants' builders.
    pub views: std::sync::Arc<registration::SharedViews>,
    /// Registration views of the current result set per recording id: (href, caption), for the map's panel.
    pub recording_views: std::collections::HashMap<String, Vec<(String, String)>>,
    /// Files of the result sets read once for all sections.
    pub cache: set_cache::SetCache,
}

/// Folder names inside `OUT/report/`.
pub const TABLES_DIR: &str = "tables";
pub const RUN_LOG_DIR: &str = "run-log";
pub const FIGURES_DIR: &str = "figures";

impl Builder {
    /// Adds a table to `page` and queues its CSV/Markdown files. Ids must be unique in the report.
    pub fn table(&mut self, page: &mut Page, t: Table) {
        self.show(page, &t, TABLES_DIR);
        self.tables.push(t);
    }

    /// Like [`Builder::table`] for a table about the run itself (times, nodes executed / cached), which
    /// differs between runs of the same workflow: its files go to `run-log/`, not `tables/`.
    pub fn run_log_table(&mut self, page: &mut Page, t: Table) {
        self.show(page, &t, RUN_LOG_DIR);
        self.run_log.push(t);
    }

    /// Puts `t` on `page`, its CSV/Markdown links pointing into `dir`, and reserves its id.
    fn show(&mut self, page: &mut Page, t: &Table, dir: &str) {
        debug_assert!(
            !self.table_ids.contains(&t.id),
            "duplicate table id {}",
            t.id
        );
        page.raw(&t.to_html(dir));
        self.table_ids.insert(t.id.clone());
    }

    /// The absolute path and the page-relative href of a figure file named `name`.
    pub fn figure_path(&self, name: &str) -> (PathBuf, String) {
        (
            self.report_dir.join(FIGURES_DIR).join(name),
            format!("{FIGURES_DIR}/{name}"),
        )
    }

    /// Records a written figure.
    pub fn wrote_figure(&mut self, path: PathBuf) {
        self.figures.push(path);
    }

    /// An empty builder writing into the same report (for one variant's pages, built in parallel).
    fn child(&self) -> Builder {
        Builder {
            report_dir: self.report_dir.clone(),
            campaign: self.campaign.clone(),
            options: self.options.clone(),
            tables: Vec::new(),
            run_log: Vec::new(),
            table_ids: BTreeSet::new(),
            figures: Vec::new(),
            notes: Vec::new(),
            images: std::sync::Arc::clone(&self.images),
            views: std::sync::Arc::clone(&self.views),
            recording_views: Default::default(),
            cache: Default::default(),
        }
    }

    /// Takes over what a [`Builder::child`] collected (called in variant order: deterministic output).
    fn absorb(&mut self, child: Builder) {
        for (t, run_log) in child
            .tables
            .into_iter()
            .map(|t| (t, false))
            .chain(child.run_log.into_iter().map(|t| (t, true)))
        {
            debug_assert!(
                !self.table_ids.contains(&t.id),
                "duplicate table id {}",
                t.id
            );
            self.table_ids.insert(t.id.clone());
            if run_log {
                self.run_log.push(t);
            } else {
                self.tables.push(t);
            }
        }
        self.figures.extend(child.figures);
        self.notes.extend(child.notes);
    }

    /// A section that could not be drawn: a note on the page and in the summary.
    pub fn note(&mut self, page: &mut Page, text: String) {
        page.raw(&format!("<p class=\"note\">{}</p>\n", html::escape(&text)));
        self.notes.push(text);
    }
}

/// A file-name-safe version of a variant or recording name.
pub fn slug(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Builds `OUT/report/`. Err when OUT is not a run's output folder or a file cannot be written; sections
/// whose inputs are missing are left out with a note (see [`ReportSummary::notes`]).
pub fn build_report(out_dir: &Path, options: &ReportOptions) -> Result<ReportSummary, String> {
    let run = RunOutputs::read(out_dir)?;
    let report_dir = out_dir.join("report");
    for d in [TABLES_DIR, RUN_LOG_DIR, FIGURES_DIR].map(|d| report_dir.join(d)) {
        std::fs::create_dir_all(&d)
            .map_err(|e| format!("{}: cannot create the folder: {e}", d.display()))?;
    }
    let campaign = options
        .campaign
        .clone()
        .or_else(|| run.campaign_dir())
        .filter(|p| p.join("mm/recordings.csv").exists());
    let mut b = Builder {
        report_dir: report_dir.clone(),
        campaign,
        options: options.clone(),
        tables: Vec::new(),
        run_log: Vec::new(),
        table_ids: BTreeSet::new(),
        figures: Vec::new(),
        notes: Vec::new(),
        images: Default::default(),
        views: Default::default(),
        recording_views: Default::default(),
        cache: Default::default(),
    };
    interactive_map::write_assets(&report_dir)?;
    if b.campaign.is_none() {
        b.notes.push(
            "campaign folder not found (give --campaign DIR): no true positions, no registration views"
                .to_string(),
        );
    }
    let mut pages: Vec<(PathBuf, String)> = Vec::new();
    let mut index = Page::new(&format!(
        "skytie report: {}",
        inputs::str_at(&run.metrics, "campaign.name")
            .or_else(|| run
                .sets
                .first()
                .and_then(|s| inputs::str_at(&s.metrics, "campaign.name")))
            .unwrap_or("run")
    ));
    if run.is_sweep {
        sweep::sweep_section(&mut b, &mut index, &run)?;
        index.heading("variants", "Variants");
        // Variant pages are independent (figure names carry the variant's prefix): render them in parallel
        // (registration views decode panoramas and aerial images), then merge in variant order.
        let variant_pages: Vec<Result<(Builder, String, String), String>> = run
            .sets
            .par_iter()
            .map(|set| {
                let mut vb = b.child();
                let file = format!("variant-{}.html", slug(&set.name));
                let mut page = Page::new(&format!("variant {}", set.name));
                page.nav_link("index.html", "← report index");
                results::results_sections(&mut vb, &mut page, set, &run)?;
                Ok((vb, file, page.render()))
            })
            .collect();
        let mut list = String::from("<ul>\n");
        for (set, made) in run.sets.iter().zip(variant_pages) {
            let (vb, file, html_text) = made?;
            b.absorb(vb);
            list.push_str(&format!(
                "<li><a href=\"{}\">{}</a></li>\n",
                html::escape(&file),
                html::escape(&set.name)
            ));
            pages.push((report_dir.join(&file), html_text));
        }
        list.push_str("</ul>\n");
        index.raw(&list);
    } else if let Some(set) = run.sets.first() {
        results::results_sections(&mut b, &mut index, set, &run)?;
    }
    // Diagnostics last: the run, rejected items with their reasons, engine counters and stage timings.
    summary::summary_section(&mut b, &mut index, &run);
    if !b.notes.is_empty() {
        index.heading("notes", "Notes on this report");
        let mut ul = String::from("<ul>\n");
        for n in &b.notes {
            ul.push_str(&format!("<li>{}</li>\n", html::escape(n)));
        }
        ul.push_str("</ul>\n");
        index.raw(&ul);
    }
    let index_path = report_dir.join("index.html");
    pages.insert(0, (index_path.clone(), index.render()));
    let table_files = b
        .tables
        .iter()
        .map(|t| (t, TABLES_DIR))
        .chain(b.run_log.iter().map(|t| (t, RUN_LOG_DIR)));
    for (t, dir) in table_files.clone() {
        let base = report_dir.join(dir).join(&t.id);
        for (ext, text) in [("csv", t.to_csv()), ("md", t.to_markdown())] {
            let p = base.with_extension(ext);
            atomic_write(&p, text.as_bytes())
                .map_err(|e| format!("{}: cannot write: {e}", p.display()))?;
        }
    }
    for (p, text) in &pages {
        atomic_write(p, text.as_bytes())
            .map_err(|e| format!("{}: cannot write: {e}", p.display()))?;
    }
    // Files of an earlier build that this one did not write (renamed views, removed variants) would be stale.
    let mut current: BTreeSet<PathBuf> = b.figures.iter().cloned().collect();
    for (t, dir) in table_files {
        let base = report_dir.join(dir).join(&t.id);
        current.insert(base.with_extension("csv"));
        current.insert(base.with_extension("md"));
    }
    for dir in [TABLES_DIR, RUN_LOG_DIR, FIGURES_DIR] {
        let Ok(entries) = std::fs::read_dir(report_dir.join(dir)) else {
            continue;
        };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_file() && !current.contains(&p) {
                let _ = std::fs::remove_file(&p);
            }
        }
    }
    Ok(ReportSummary {
        index: index_path,
        pages: pages.into_iter().map(|(p, _)| p).collect(),
        tables: b.tables.iter().map(|t| t.id.clone()).collect(),
        run_log_tables: b.run_log.iter().map(|t| t.id.clone()).collect(),
        figures: b.figures,
        notes: b.notes,
    })
}
