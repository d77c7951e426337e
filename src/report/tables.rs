//! Report tables: one [`Table`] is rendered as HTML (in the page), CSV and Markdown (files in
//! `OUT/report/tables/<id>.{csv,md}`). Cells are pre-formatted strings so that the three renderings show
//! exactly the same numbers and a rebuild from the same OUT is byte-identical. A table longer than
//! [`HTML_ROW_LIMIT`] rows (per-segment tables of a city campaign have thousands) shows only that many rows in
//! the page — the worst first when the table was given a ranking ([`Table::rank_for_html`]), else the first
//! ones — with a line saying so; its CSV and Markdown files always hold every row.

use super::html::escape;
use skytie_util::csv_out::quote;
use std::fmt::Write as _;

/// Most rows a table shows in the HTML page; every row stays in its CSV and Markdown files.
pub const HTML_ROW_LIMIT: usize = 40;

/// Who a table's values come from: this run, or the thesis' published Rotterdam results (never mixed).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Origin {
    /// Computed from this run's outputs.
    Skytie,
    /// Transcribed from the thesis (Rotterdam data), shown beside ours for comparison.
    Thesis,
}

impl Origin {
    /// The label shown above the table.
    pub fn label(self) -> &'static str {
        match self {
            Origin::Skytie => "skytie (this campaign)",
            Origin::Thesis => "thesis (Rotterdam data)",
        }
    }
}

/// One table: an id (file name stem, unique in a report), a title, column headers and rows of cells.
#[derive(Clone, Debug)]
pub struct Table {
    pub id: String,
    pub title: String,
    pub origin: Origin,
    pub header: Vec<String>,
    pub rows: Vec<Vec<String>>,
    /// One sentence under the table (units, what "before/after" means…); may be empty.
    pub note: String,
    /// The rows the page shows when the table is longer than [`HTML_ROW_LIMIT`] (indices, in display order)
    /// and what they are ("the segments with the largest offsets"); `None`: the first rows.
    html_ranking: Option<(Vec<usize>, String)>,
}

impl Table {
    pub fn new(id: &str, title: &str, origin: Origin, header: &[&str]) -> Self {
        Self {
            id: id.to_string(),
            title: title.to_string(),
            origin,
            header: header.iter().map(|s| s.to_string()).collect(),
            rows: Vec::new(),
            note: String::new(),
            html_ranking: None,
        }
    }

    /// Rows in order of interest (most interesting first) and what the first ones are, for a table longer than
    /// [`HTML_ROW_LIMIT`]: the page shows the first [`HTML_ROW_LIMIT`] of `ranked`, in table order.
    pub fn rank_for_html(mut self, ranked: Vec<usize>, what: &str) -> Self {
        self.html_ranking = Some((ranked, what.to_string()));
        self
    }

    /// The rows the page shows (indices in table order) and the sentence saying which, when not all.
    fn html_rows(&self) -> (Vec<usize>, Option<String>) {
        let n = self.rows.len();
        if n <= HTML_ROW_LIMIT {
            return ((0..n).collect(), None);
        }
        let (mut shown, what) = match &self.html_ranking {
            Some((ranked, what)) => (
                ranked
                    .iter()
                    .copied()
                    .filter(|&i| i < n)
                    .take(HTML_ROW_LIMIT)
                    .collect::<Vec<_>>(),
                what.clone(),
            ),
            None => ((0..HTML_ROW_LIMIT).collect(), "the first ones".to_string()),
        };
        shown.sort_unstable();
        shown.dedup();
        let line = format!(
            "{} of {n} rows shown ({what}); the CSV and MD files hold all of them.",
            shown.len()
        );
        (shown, Some(line))
    }

    pub fn with_note(mut self, note: &str) -> Self {
        self.note = note.to_string();
        self
    }

    /// Appends a row; short rows are padded with empty cells, long rows are cut to the header's width.
    pub fn push(&mut self, mut row: Vec<String>) {
        row.resize(self.header.len(), String::new());
        self.rows.push(row);
    }

    /// RFC 4180 CSV (fields with a comma, quote or line break are quoted), `\n` line ends.
    pub fn to_csv(&self) -> String {
        let mut s = String::new();
        for row in std::iter::once(&self.header).chain(&self.rows) {
            let cells: Vec<String> = row.iter().map(|c| quote(c)).collect();
            s.push_str(&cells.join(","));
            s.push('\n');
        }
        s
    }

    /// GitHub-flavoured Markdown: a heading with the title and origin, the table, the note.
    pub fn to_markdown(&self) -> String {
        let mut s = format!("### {} — {}\n\n", self.title, self.origin.label());
        let line = |cells: &[String]| {
            let cells: Vec<String> = cells.iter().map(|c| md_cell(c)).collect();
            format!("| {} |\n", cells.join(" | "))
        };
        s.push_str(&line(&self.header));
        s.push_str(&format!(
            "|{}\n",
            self.header.iter().map(|_| "---|").collect::<String>()
        ));
        for r in &self.rows {
            s.push_str(&line(r));
        }
        if !self.note.is_empty() {
            let _ = write!(s, "\n{}\n", self.note);
        }
        s
    }

    /// An HTML `<table>` with a caption naming the origin and links to the CSV and Markdown files
    /// (`tables_href` is the folder holding them, relative to the page).
    pub fn to_html(&self, tables_href: &str) -> String {
        let class = match self.origin {
            Origin::Skytie => "skytie",
            Origin::Thesis => "thesis",
        };
        let mut s = format!(
            "<table class=\"{class}\" id=\"table-{id}\">\n<caption>{title} <span class=\"origin\">{origin}</span> \
             <a href=\"{href}/{id}.csv\">CSV</a> <a href=\"{href}/{id}.md\">MD</a></caption>\n<thead><tr>",
            id = escape(&self.id),
            title = escape(&self.title),
            origin = escape(self.origin.label()),
            href = escape(tables_href),
        );
        for h in &self.header {
            let _ = write!(s, "<th>{}</th>", escape(h));
        }
        s.push_str("</tr></thead>\n<tbody>\n");
        let (shown, cut) = self.html_rows();
        for r in shown.iter().map(|&i| &self.rows[i]) {
            s.push_str("<tr>");
            for c in r {
                let _ = write!(s, "<td>{}</td>", escape(c));
            }
            s.push_str("</tr>\n");
        }
        s.push_str("</tbody>\n</table>\n");
        if let Some(cut) = cut {
            let _ = writeln!(s, "<p class=\"note\">{}</p>", escape(&cut));
        }
        if !self.note.is_empty() {
            let _ = writeln!(s, "<p class=\"note\">{}</p>", escape(&self.note));
        }
        s
    }
}

fn md_cell(c: &str) -> String {
    c.replace('|', "\\|").replace('\n', " ")
}

/// A number with `decimals` digits, or "n/a" when missing or not finite.
pub fn fmt_num(v: Option<f64>, decimals: usize) -> String {
    match v {
        Some(x) if x.is_finite() => format!("{x:.decimals$}"),
        _ => "n/a".to_string(),
    }
}

/// A count, or "n/a".
pub fn fmt_count(v: Option<f64>) -> String {
    match v {
        Some(x) if x.is_finite() => format!("{}", x.round() as i64),
        _ => "n/a".to_string(),
    }
}

/// A fraction shown as a percentage with one decimal, or "n/a".
pub fn fmt_percent(v: Option<f64>) -> String {
    match v {
        Some(x) if x.is_finite() => format!("{:.1}", x * 100.0),
        _ => "n/a".to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Table {
        let mut t = Table::new("t1", "RMSE <m>", Origin::Skytie, &["config", "x, m"]);
        t.push(vec!["a|b".into(), "0.100".into()]);
        t.push(vec!["q\"uote".into()]);
        t
    }

    #[test]
    fn csv_quotes_and_pads() {
        assert_eq!(
            sample().to_csv(),
            "config,\"x, m\"\na|b,0.100\n\"q\"\"uote\",\n"
        );
    }

    #[test]
    fn markdown_escapes_pipes_and_labels_origin() {
        let md = sample().to_markdown();
        assert!(md.starts_with("### RMSE <m> — skytie (this campaign)\n"));
        assert!(md.contains("| a\\|b | 0.100 |\n"));
        assert!(md.contains("|---|---|\n"));
    }

    #[test]
    fn html_escapes_cells() {
        let h = sample().to_html("tables");
        assert!(h.contains("RMSE &lt;m&gt;"));
        assert!(h.contains("<td>q&quot;uote</td>"));
        assert!(h.contains("href=\"tables/t1.csv\""));
    }

    #[test]
    fn long_tables_show_the_ranked_rows_in_the_page_and_all_rows_in_the_files() {
        let mut t = Table::new("long", "long", Origin::Skytie, &["i"]);
        for i in 0..1000 {
            t.push(vec![format!("row{i}")]);
        }
        let plain = t.to_html("tables");
        assert_eq!(plain.matches("<tr><td>").count(), HTML_ROW_LIMIT);
        assert!(plain.contains("40 of 1000 rows shown (the first ones)"));
        let ranked = t.rank_for_html((0..1000).rev().collect(), "the last ones");
        let h = ranked.to_html("tables");
        assert_eq!(h.matches("<tr><td>").count(), HTML_ROW_LIMIT);
        assert!(h.contains("<td>row999</td>") && !h.contains("<td>row0</td>"));
        // Table order in the page: row960 before row999.
        assert!(h.find("row960").unwrap() < h.find("row999").unwrap());
        assert_eq!(ranked.to_csv().lines().count(), 1001);
    }

    #[test]
    fn number_formats() {
        assert_eq!(fmt_num(Some(0.12345), 3), "0.123");
        assert_eq!(fmt_num(Some(f64::NAN), 3), "n/a");
        assert_eq!(fmt_num(None, 2), "n/a");
        assert_eq!(fmt_count(Some(41.0)), "41");
        assert_eq!(fmt_percent(Some(0.9016)), "90.2");
        assert_eq!(fmt_percent(Some(0.9014)), "90.1");
    }
}
