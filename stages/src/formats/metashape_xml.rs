//! Agisoft Metashape camera XML export (File › Export › Export Cameras, "Agisoft XML", document versions
//! 1.x as written by Metashape 1.5–2.x): `<sensors>` with a `<calibration>` per sensor (`f`, `cx`, `cy`,
//! `b1`, `b2`, `k1`…`k4`, `p1`, `p2` — see [`super::camera_model`]), `<cameras>` with a 4 × 4 `<transform>`
//! (camera → chunk, row-major; camera axes x right, y down, z forward), and the chunk's `<transform>`
//! (`<rotation>` 3 × 3, `<translation>`, `<scale>`: chunk → geocentric, p = s·R·q + t) and `<reference>`
//! (the chunk CRS as WKT). Geocentric coordinates are earth-centred on the datum of the chunk CRS.
//! Unsupported model terms (p3, p4, non-frame sensors) are refused, never dropped.

use super::camera_model::MetashapeCalibration;
use crate::campaign::Problem;
use nalgebra::{Matrix3, Matrix4, Vector3};
use std::path::Path;

/// A sensor with its (adjusted) calibration.
#[derive(Debug, Clone, PartialEq)]
pub struct MetashapeSensor {
    pub id: String,
    pub label: String,
    pub calibration: MetashapeCalibration,
}

/// An aligned camera.
#[derive(Debug, Clone, PartialEq)]
pub struct MetashapeCamera {
    pub line: usize,
    pub sensor_id: String,
    pub label: String,
    /// Camera → chunk (Metashape camera axes).
    pub transform: Matrix4<f64>,
}

/// The chunk → geocentric similarity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChunkTransform {
    pub rotation: Matrix3<f64>,
    pub translation: Vector3<f64>,
    pub scale: f64,
}

/// What skytie uses of the document.
#[derive(Debug, Clone, PartialEq)]
pub struct MetashapeDocument {
    pub sensors: Vec<MetashapeSensor>,
    pub cameras: Vec<MetashapeCamera>,
    pub chunk_transform: Option<ChunkTransform>,
    pub reference_wkt: Option<String>,
}

fn numbers(text: &str) -> Option<Vec<f64>> {
    text.split_whitespace()
        .map(|t| t.parse().ok().filter(|v: &f64| v.is_finite()))
        .collect()
}

type Node<'a, 'input> = roxmltree::Node<'a, 'input>;

/// The file being read: where its problems are reported (file, line, field, and what to do).
struct Source<'a> {
    path: &'a Path,
    text: &'a str,
}

impl Source<'_> {
    fn err(&self, line: Option<usize>, field: Option<&str>, msg: String) -> Problem {
        Problem::error(
            self.path,
            line,
            field,
            msg,
            "export the cameras again from Metashape as Agisoft XML",
        )
    }

    /// The error at element `n`.
    fn err_at(&self, n: Node, field: &str, msg: String) -> Problem {
        self.err(Some(self.line(n)), Some(field), msg)
    }

    /// The line of element `n` (1-based).
    fn line(&self, n: Node) -> usize {
        line_of(self.text, n.range().start)
    }
}

/// The line (1-based) of byte `pos` of `text`.
fn line_of(text: &str, pos: usize) -> usize {
    text.as_bytes()[..pos.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// The document's only `<chunk>` under its root `<document>`.
fn the_chunk<'a, 'input>(
    src: &Source,
    root: Node<'a, 'input>,
) -> Result<Node<'a, 'input>, Problem> {
    if root.tag_name().name() != "document" {
        let msg = format!(
            "has root element <{}>, not <document>",
            root.tag_name().name()
        );
        return Err(src.err(Some(1), None, msg));
    }
    let chunks: Vec<_> = root
        .children()
        .filter(|n| n.has_tag_name("chunk"))
        .collect();
    match chunks.as_slice() {
        [c] => Ok(*c),
        [] => Err(src.err(None, None, "has no <chunk>".into())),
        _ => Err(src.err_at(
            chunks[1],
            "chunk",
            format!(
                "has {} chunks; which one is meant is ambiguous",
                chunks.len()
            ),
        )),
    }
}

/// One `<sensor>` with its calibration; what makes it unusable goes to `fatal`.
fn read_sensor(src: &Source, s: Node, fatal: &mut Vec<Problem>) -> Option<MetashapeSensor> {
    let child = child_element;
    let id = s.attribute("id").unwrap_or_default().to_string();
    if s.attribute("type").is_some_and(|t| t != "frame") {
        fatal.push(src.err_at(
            s,
            "type",
            format!(
                "sensor {id} is of type '{}'; only frame cameras are supported",
                s.attribute("type").unwrap_or_default()
            ),
        ));
        return None;
    }
    let Some(cal) = child(s, "calibration") else {
        fatal.push(src.err_at(s, "calibration", format!("sensor {id} has no calibration")));
        return None;
    };
    let res = child(cal, "resolution").or_else(|| child(s, "resolution"));
    let dim = |k: &str| {
        res.and_then(|r| r.attribute(k))
            .and_then(|v| v.parse::<u32>().ok())
    };
    let mut c = MetashapeCalibration::default();
    match (dim("width"), dim("height")) {
        (Some(w), Some(h)) => (c.width_px, c.height_px) = (w, h),
        _ => fatal.push(src.err_at(
            cal,
            "resolution",
            format!("sensor {id}: calibration without resolution"),
        )),
    }
    read_calibration_terms(src, &id, cal, &mut c, fatal);
    if c.f.is_nan() || c.f <= 0.0 {
        fatal.push(src.err_at(cal, "f", format!("sensor {id}: no focal length f > 0")));
    }
    Some(MetashapeSensor {
        id,
        label: s.attribute("label").unwrap_or_default().to_string(),
        calibration: c,
    })
}

/// The model terms of `<calibration>` element `cal` of sensor `id` into `c`; p3 and p4 other than 0, and terms
/// that are not numbers, go to `fatal`.
fn read_calibration_terms(
    src: &Source,
    id: &str,
    cal: Node,
    c: &mut MetashapeCalibration,
    fatal: &mut Vec<Problem>,
) {
    for el in cal.children().filter(|n| n.is_element()) {
        let name = el.tag_name().name();
        let value = el
            .text()
            .and_then(|t| t.trim().parse::<f64>().ok())
            .filter(|v| v.is_finite());
        let slot = match name {
            "f" => &mut c.f,
            "cx" => &mut c.cx,
            "cy" => &mut c.cy,
            "b1" => &mut c.b1,
            "b2" => &mut c.b2,
            "k1" => &mut c.k1,
            "k2" => &mut c.k2,
            "k3" => &mut c.k3,
            "k4" => &mut c.k4,
            "p1" => &mut c.p1,
            "p2" => &mut c.p2,
            "p3" | "p4" => {
                if value != Some(0.0) {
                    let msg =
                        format!("sensor {id}: {name} is not supported by skytie's camera model");
                    fatal.push(src.err_at(el, name, msg));
                }
                continue;
            }
            _ => continue,
        };
        match value {
            Some(v) => *slot = v,
            None => {
                fatal.push(src.err_at(el, name, format!("sensor {id}: {name} is not a number")))
            }
        }
    }
}

/// The aligned `<camera>`s under `<cameras>`; the others are reported in `problems` and left out.
fn read_cameras(src: &Source, chunk: Node, problems: &mut Vec<Problem>) -> Vec<MetashapeCamera> {
    let mut cameras = Vec::new();
    for cam in child_element(chunk, "cameras")
        .into_iter()
        .flat_map(|c| c.descendants().filter(|n| n.has_tag_name("camera")))
    {
        let label = cam.attribute("label").unwrap_or_default().to_string();
        let sensor_id = cam.attribute("sensor_id").unwrap_or_default().to_string();
        let m = child_element(cam, "transform")
            .and_then(|t| t.text())
            .and_then(numbers);
        match m {
            Some(v) if v.len() == 16 => cameras.push(MetashapeCamera {
                line: src.line(cam),
                sensor_id,
                label,
                transform: Matrix4::from_row_slice(&v),
            }),
            Some(_) => problems.push(src.err_at(
                cam,
                "transform",
                format!("camera '{label}': transform is not 16 numbers; skipped"),
            )),
            None => problems.push(src.err_at(
                cam,
                "transform",
                format!("camera '{label}' is not aligned (no transform); skipped"),
            )),
        }
    }
    cameras
}

/// The chunk's `<transform>`, if it has one; an incomplete one goes to `fatal`.
fn read_chunk_transform(
    src: &Source,
    chunk: Node,
    fatal: &mut Vec<Problem>,
) -> Option<ChunkTransform> {
    let t = child_element(chunk, "transform")?;
    let get = |name: &str, n: usize| {
        child_element(t, name)
            .and_then(|e| e.text())
            .and_then(numbers)
            .filter(|v| v.len() == n)
    };
    match (get("rotation", 9), get("translation", 3), get("scale", 1)) {
        (Some(r), Some(tr), s) => Some(ChunkTransform {
            rotation: Matrix3::from_row_slice(&r),
            translation: Vector3::from_row_slice(&tr),
            scale: s.map_or(1.0, |s| s[0]),
        }),
        _ => {
            fatal.push(src.err_at(
                t,
                "transform",
                "chunk transform without rotation (9 numbers) and translation (3 numbers)".into(),
            ));
            None
        }
    }
}

/// Read the document; cameras without a transform (not aligned) are reported and left out.
pub fn read_metashape_xml(path: &Path) -> Result<(MetashapeDocument, Vec<Problem>), Vec<Problem>> {
    let text = std::fs::read_to_string(path).map_err(|e| vec![super::unreadable(path, &e)])?;
    let src = Source { path, text: &text };
    let doc = roxmltree::Document::parse(&text).map_err(|e| {
        vec![src.err(
            Some(e.pos().row as usize),
            None,
            format!("is not valid XML ({e})"),
        )]
    })?;
    let chunk = the_chunk(&src, doc.root_element()).map_err(|e| vec![e])?;
    let mut problems = Vec::new();
    let mut fatal = Vec::new();
    let sensors: Vec<MetashapeSensor> = child_element(chunk, "sensors")
        .into_iter()
        .flat_map(|s| s.children().filter(|c| c.has_tag_name("sensor")))
        .filter_map(|s| read_sensor(&src, s, &mut fatal))
        .collect();
    let cameras = read_cameras(&src, chunk, &mut problems);
    let chunk_transform = read_chunk_transform(&src, chunk, &mut fatal);
    if !fatal.is_empty() {
        return Err(fatal);
    }
    let reference_wkt = child_element(chunk, "reference")
        .and_then(|r| r.text())
        .map(|t| t.trim().to_string());
    Ok((
        MetashapeDocument {
            sensors,
            cameras,
            chunk_transform,
            reference_wkt,
        },
        problems,
    ))
}

/// Write a document in the layout [`read_metashape_xml`] reads (for exports and tests).
pub fn write_metashape_xml(path: &Path, doc: &MetashapeDocument) -> std::io::Result<()> {
    use std::fmt::Write;
    let mut s = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<document version=\"1.5.0\">\n  <chunk label=\"Chunk 1\" enabled=\"true\">\n    <sensors next_id=\"");
    let _ = writeln!(s, "{}\">", doc.sensors.len());
    for se in &doc.sensors {
        let c = &se.calibration;
        let _ = write!(s, "      <sensor id=\"{}\" label=\"{}\" type=\"frame\">\n        <resolution width=\"{}\" height=\"{}\"/>\n        <calibration type=\"frame\" class=\"adjusted\">\n          <resolution width=\"{}\" height=\"{}\"/>\n", se.id, se.label, c.width_px, c.height_px, c.width_px, c.height_px);
        for (k, v) in [
            ("f", c.f),
            ("cx", c.cx),
            ("cy", c.cy),
            ("b1", c.b1),
            ("b2", c.b2),
            ("k1", c.k1),
            ("k2", c.k2),
            ("k3", c.k3),
            ("k4", c.k4),
            ("p1", c.p1),
            ("p2", c.p2),
        ] {
            let _ = writeln!(s, "          <{k}>{v}</{k}>");
        }
        s.push_str("        </calibration>\n      </sensor>\n");
    }
    s.push_str("    </sensors>\n    <cameras>\n");
    for (i, c) in doc.cameras.iter().enumerate() {
        let m = space_separated(c.transform.transpose().iter());
        let _ = write!(s, "      <camera id=\"{i}\" sensor_id=\"{}\" label=\"{}\">\n        <transform>{m}</transform>\n      </camera>\n", c.sensor_id, c.label);
    }
    s.push_str("    </cameras>\n");
    if let Some(t) = &doc.chunk_transform {
        let r = space_separated(t.rotation.transpose().iter());
        let tr = space_separated(t.translation.iter());
        let _ = write!(s, "    <transform>\n      <rotation locked=\"false\">{r}</rotation>\n      <translation locked=\"false\">{tr}</translation>\n      <scale locked=\"false\">{}</scale>\n    </transform>\n", t.scale);
    }
    if let Some(w) = &doc.reference_wkt {
        let _ = writeln!(s, "    <reference>{}</reference>", xml_escape(w));
    }
    s.push_str("  </chunk>\n</document>\n");
    crate::fsutil::atomic_write(path, s.as_bytes())
}

fn xml_escape(t: &str) -> String {
    t.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The EPSG code of the top-level CRS of a WKT string (`AUTHORITY["EPSG","28992"]` or `ID["EPSG",28992]`
/// directly inside the outermost brackets; for a compound CRS, that of its first, horizontal, member).
pub fn wkt_epsg_code(wkt: &str) -> Option<u32> {
    let body = wkt.trim();
    let open = body.find('[')?;
    let keyword = body[..open].trim().to_ascii_uppercase();
    let inner = &body[open + 1..];
    // Split the top level into members at depth 0 commas.
    let mut depth = 0i32;
    let mut start = 0usize;
    let mut members = Vec::new();
    for (i, ch) in inner.char_indices() {
        match ch {
            '[' => depth += 1,
            ']' if depth == 0 => {
                members.push(&inner[start..i]);
                break;
            }
            ']' => depth -= 1,
            ',' if depth == 0 => {
                members.push(&inner[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    if keyword == "COMPD_CS" || keyword == "COMPOUNDCRS" {
        return members
            .iter()
            .find(|m| m.contains('['))
            .and_then(|m| wkt_epsg_code(m));
    }
    members.iter().rev().find_map(|m| {
        let m = m.trim();
        let upper = m.to_ascii_uppercase();
        if !(upper.starts_with("AUTHORITY[") || upper.starts_with("ID[")) {
            return None;
        }
        let parts: Vec<&str> = m[m.find('[')? + 1..]
            .trim_end_matches(']')
            .split(',')
            .map(|p| p.trim().trim_matches('"'))
            .collect();
        (parts.first()?.eq_ignore_ascii_case("EPSG"))
            .then(|| parts.get(1)?.parse().ok())
            .flatten()
    })
}

fn child_element<'a, 'input>(
    n: roxmltree::Node<'a, 'input>,
    name: &str,
) -> Option<roxmltree::Node<'a, 'input>> {
    n.children().find(|c| c.has_tag_name(name))
}

/// Numbers as XML element text: separated by single spaces, each in Rust's shortest round-trip form (a matrix
/// passed as its transpose's elements comes out row by row, as Metashape writes it).
fn space_separated<'a>(values: impl IntoIterator<Item = &'a f64>) -> String {
    values
        .into_iter()
        .map(|v| v.to_string())
        .collect::<Vec<_>>()
        .join(" ")
}
