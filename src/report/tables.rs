//! Report tables: one [`Table`] is rendered as HTML (in the page), CSV and Markdown (files in
//! `OUT/report/tables/<id>.{csv,md}`). Cells are pre-formatted strings so that the three renderings show
//! exactly the same numbers and a rebuild from the same OUT is byte-identical.

use super::html::escape;
use std::fmt::Write as _;

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
        }
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
            let cells: Vec<String> = row.iter().map(|c| csv_field(c)).collect();
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
        for r in &self.rows {
            s.push_str("<tr>");
            for c in r {
                let _ = write!(s, "<td>{}</td>", escape(c));
            }
            s.push_str("</tr>\n");
        }
        s.push_str("</tbody>\n</table>\n");
        if !self.note.is_empty() {
            let _ = writeln!(s, "<p class=\"note\">{}</p>", escape(&self.note));
        }
        s
    }
}

fn csv_field(c: &str) -> String {
    if c.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", c.replace('"', "\"\""))
    } else {
        c.to_string()
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
    fn number_formats() {
        assert_eq!(fmt_num(Some(0.12345), 3), "0.123");
        assert_eq!(fmt_num(Some(f64::NAN), 3), "n/a");
        assert_eq!(fmt_num(None, 2), "n/a");
        assert_eq!(fmt_count(Some(41.0)), "41");
        assert_eq!(fmt_percent(Some(0.9016)), "90.2");
        assert_eq!(fmt_percent(Some(0.9014)), "90.1");
    }
}
