//! HTML page assembly for the report: escaping, the shared style sheet, and the page frame (title,
//! navigation, sections). Pages are self-contained (no network): figures are files next to the page,
//! referenced by relative paths. A tiny inline script records each image's natural size in
//! `data-natural-width` / `data-natural-height` once the page has loaded (the headless-Chromium test reads
//! them from the dumped DOM; a person sees nothing of it).

use std::fmt::Write as _;

/// Escapes text for HTML element content and attribute values.
pub fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            _ => out.push(c),
        }
    }
    out
}

const STYLE: &str = "body{font-family:sans-serif;margin:1.5em;max-width:1300px;color:#222}\
h1{font-size:1.6em}h2{border-bottom:1px solid #999;margin-top:1.8em}h3{margin-top:1.2em}\
table{border-collapse:collapse;margin:0.6em 0}td,th{border:1px solid #bbb;padding:2px 8px;text-align:right}\
th{background:#eee}td:first-child,th:first-child{text-align:left}\
caption{text-align:left;font-weight:bold;padding:4px 0}caption a{font-weight:normal;font-size:0.85em}\
table.thesis th{background:#fde9c9}span.origin{font-weight:normal;font-style:italic;color:#555}\
table.thesis span.origin{color:#a05a00}p.note{font-size:0.9em;color:#555;margin-top:0}\
figure{margin:1em 0}figcaption{font-size:0.9em;color:#444}img{max-width:100%;border:1px solid #ddd}\
.pair{display:flex;gap:12px;flex-wrap:wrap}.pair figure{margin:0}.fail{color:#b00;font-weight:bold}\
.ok{color:#070;font-weight:bold}nav a{margin-right:1em}\
.headline{font-size:1.1em;border-left:6px solid #0072B2;padding:0.4em 1em;background:#f4f8fb}\
.headline.warn{border-color:#D55E00;background:#fdf1ea}.headline li{margin:0.25em 0}\
.headline .status{font-weight:bold;font-size:1.15em}.convention{font-size:0.9em;color:#444}\
.mapwrap{display:flex;gap:12px;flex-wrap:wrap}.skymap{height:560px;flex:3 1 600px;border:1px solid #bbb}\
.mappanel{flex:1 1 280px;max-height:560px;overflow:auto;font-size:0.9em}.mappanel img{max-width:100%}\
.mappanel th{text-align:left;background:none;font-weight:normal;color:#555}\
.skytie-vector-scale{background:rgba(255,255,255,0.85);padding:2px 6px;font-size:11px}\
.skytie-vector-scale .bar{height:5px;background:#333;margin-bottom:2px}\
.skytie-toggles{background:rgba(255,255,255,0.9);padding:4px 8px;font-size:12px;line-height:1.5}";

const SIZE_SCRIPT: &str = "window.addEventListener('load',function(){var n=0;\
document.querySelectorAll('img').forEach(function(i){i.setAttribute('data-natural-width',i.naturalWidth);\
i.setAttribute('data-natural-height',i.naturalHeight);if(i.naturalWidth>0)n++;});\
document.body.setAttribute('data-images-loaded',n);});";

/// One HTML page being assembled.
pub struct Page {
    title: String,
    nav: Vec<(String, String)>,
    /// Extra `<head>` lines (style sheets and scripts of the interactive map).
    head: String,
    body: String,
}

impl Page {
    pub fn new(title: &str) -> Self {
        Self {
            title: title.to_string(),
            nav: Vec::new(),
            head: String::new(),
            body: String::new(),
        }
    }

    /// Adds lines to `<head>` (once: the same lines again are ignored).
    pub fn head(&mut self, html: &str) {
        if !self.head.contains(html) {
            self.head.push_str(html);
        }
    }

    /// Appends another page's body and head lines (sections assembled out of order).
    pub fn append(&mut self, other: Page) {
        self.head(&other.head);
        self.body.push_str(&other.body);
    }

    /// A link in the navigation bar (href relative to the page).
    pub fn nav_link(&mut self, href: &str, text: &str) {
        self.nav.push((href.to_string(), text.to_string()));
    }

    /// A `<h2>` section heading with an anchor id.
    pub fn heading(&mut self, id: &str, text: &str) {
        let _ = writeln!(self.body, "<h2 id=\"{}\">{}</h2>", escape(id), escape(text));
    }

    pub fn subheading(&mut self, text: &str) {
        let _ = writeln!(self.body, "<h3>{}</h3>", escape(text));
    }

    /// A paragraph of plain text (escaped).
    pub fn para(&mut self, text: &str) {
        let _ = writeln!(self.body, "<p>{}</p>", escape(text));
    }

    /// Raw, already escaped HTML.
    pub fn raw(&mut self, html: &str) {
        self.body.push_str(html);
    }

    /// A figure: image file (relative path) with alt text and caption.
    pub fn figure(&mut self, src: &str, alt: &str, caption: &str) {
        self.body.push_str(&figure_html(src, alt, caption));
    }

    /// The finished document.
    pub fn render(&self) -> String {
        let mut s = String::new();
        let _ = write!(
            s,
            "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{}</title>\n\
             <style>{STYLE}</style>\n<script>{SIZE_SCRIPT}</script>\n{}</head>\n<body>\n<h1>{}</h1>\n",
            escape(&self.title),
            self.head,
            escape(&self.title)
        );
        if !self.nav.is_empty() {
            s.push_str("<nav>");
            for (href, text) in &self.nav {
                let _ = write!(s, "<a href=\"{}\">{}</a>", escape(href), escape(text));
            }
            s.push_str("</nav>\n");
        }
        s.push_str(&self.body);
        s.push_str("</body>\n</html>\n");
        s
    }
}

/// `<figure><img …><figcaption>…</figcaption></figure>`.
pub fn figure_html(src: &str, alt: &str, caption: &str) -> String {
    format!(
        "<figure><img src=\"{}\" alt=\"{}\"><figcaption>{}</figcaption></figure>\n",
        escape(src),
        escape(alt),
        escape(caption)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_markup_characters() {
        assert_eq!(escape("a<b>&\"c'"), "a&lt;b&gt;&amp;&quot;c&#39;");
    }

    #[test]
    fn page_has_title_nav_and_size_script() {
        let mut p = Page::new("R & D");
        p.nav_link("x.html", "X");
        p.figure("f/a.svg", "alt", "cap");
        let h = p.render();
        assert!(h.contains("<title>R &amp; D</title>"));
        assert!(h.contains("<a href=\"x.html\">X</a>"));
        assert!(h.contains("<img src=\"f/a.svg\" alt=\"alt\">"));
        assert!(h.contains("data-natural-width"));
    }
}
