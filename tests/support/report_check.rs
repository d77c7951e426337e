//! Helpers of the report test: the files a report page references, headless Chromium (find, render,
//! read each image's natural size from the dumped DOM, screenshot).
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

/// Every value of `attr="…"` in `html` (attribute values are escaped by the report, never contain `"`).
pub fn attr_values(html: &str, attr: &str) -> Vec<String> {
    let pat = format!("{attr}=\"");
    let mut out = Vec::new();
    let mut rest = html;
    while let Some(i) = rest.find(&pat) {
        rest = &rest[i + pat.len()..];
        if let Some(j) = rest.find('"') {
            out.push(rest[..j].replace("&amp;", "&"));
            rest = &rest[j..];
        }
    }
    out
}

/// Local files referenced by `<img src>` and `<a href>` of a page (external and anchor links excluded).
pub fn referenced_files(page: &Path) -> (Vec<PathBuf>, Vec<PathBuf>) {
    let html = std::fs::read_to_string(page).unwrap();
    let dir = page.parent().unwrap();
    let imgs = attr_values(&html, "src")
        .into_iter()
        .map(|s| dir.join(s))
        .collect();
    let links = attr_values(&html, "href")
        .into_iter()
        .filter(|h| !h.starts_with('#') && !h.contains("://"))
        .map(|s| dir.join(s))
        .collect();
    (imgs, links)
}

/// `chromium` or `chromium-browser` on PATH.
pub fn find_chromium() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    for dir in std::env::split_paths(&path) {
        for name in ["chromium", "chromium-browser"] {
            let p = dir.join(name);
            if p.is_file() {
                return Some(p);
            }
        }
    }
    None
}

fn headless(chromium: &Path, profile: &Path) -> Command {
    let mut c = Command::new(chromium);
    c.arg("--headless")
        .arg("--disable-gpu")
        .arg("--no-sandbox")
        .arg("--no-first-run")
        .arg("--disable-extensions")
        .arg("--allow-file-access-from-files")
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg("--disable-background-networking")
        .arg("--disable-component-update")
        .arg("--disable-sync")
        .arg("--virtual-time-budget=8000");
    c
}

/// The value of attribute `attr` on the element with `id="{id}"` in a dumped DOM.
pub fn element_attr(dom: &str, id: &str, attr: &str) -> Option<String> {
    let start = dom.find(&format!("id=\"{id}\""))?;
    let open = dom[..start].rfind('<')?;
    let end = start + dom[start..].find('>')?;
    attr_values(&dom[open..end], attr).into_iter().next()
}

/// The DOM of `page` after loading (scripts run), as Chromium dumps it.
pub fn dump_dom(chromium: &Path, page: &Path, profile: &Path) -> String {
    dump_dom_fragment(chromium, page, "", profile)
}

/// Like [`dump_dom`] with a fragment (`#…`) appended to the page's address.
pub fn dump_dom_fragment(chromium: &Path, page: &Path, fragment: &str, profile: &Path) -> String {
    let mut cmd = headless(chromium, profile);
    cmd.arg("--dump-dom")
        .arg(format!("{}{fragment}", file_url(page)));
    String::from_utf8(succeed(&mut cmd, "--dump-dom")).unwrap()
}

/// The `file://` address of `page`.
fn file_url(page: &Path) -> String {
    format!("file://{}", page.canonicalize().unwrap().display())
}

/// Runs the Chromium command `cmd` (its main option `what`), which must succeed; returns its stdout.
fn succeed(cmd: &mut Command, what: &str) -> Vec<u8> {
    let out = cmd.output().expect("start chromium");
    assert!(
        out.status.success(),
        "chromium {what} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    out.stdout
}

/// Screenshot of `page` into `png` (window `width` × `height` px).
pub fn screenshot(
    chromium: &Path,
    page: &Path,
    png: &Path,
    profile: &Path,
    width: u32,
    height: u32,
) {
    let mut cmd = headless(chromium, profile);
    cmd.arg(format!("--screenshot={}", png.display()))
        .arg(format!("--window-size={width},{height}"))
        .arg("--hide-scrollbars")
        .arg(file_url(page));
    succeed(&mut cmd, "--screenshot");
}

/// Per `<img>` of a dumped DOM: (src, natural width, natural height) as recorded by the page's script. The
/// map's own tiles (Leaflet image overlays, created by the map script) are not counted.
pub fn image_sizes(dom: &str) -> Vec<(String, u32, u32)> {
    let mut out = Vec::new();
    for tag in dom.split("<img").skip(1) {
        let tag = &tag[..tag.find('>').unwrap_or(tag.len())];
        if tag.contains("leaflet-image-layer") {
            continue;
        }
        let get = |a: &str| attr_values(tag, a).into_iter().next();
        let num = |a: &str| get(a).and_then(|v| v.parse::<u32>().ok()).unwrap_or(0);
        out.push((
            get("src").unwrap_or_default(),
            num("data-natural-width"),
            num("data-natural-height"),
        ));
    }
    out
}
