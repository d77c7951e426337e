//! The pose a panorama carries in its own JPEG file: EXIF GPS tags (position, altitude, time, image direction)
//! and Google's Photo Sphere XMP tags (GPano: heading, pitch and roll of the image centre).
//!
//! Followed: the EXIF 2.32 specification (CIPA DC-008-2019), GPS attribute IFD — `GPSLatitudeRef` (N/S) +
//! `GPSLatitude` and `GPSLongitudeRef` (E/W) + `GPSLongitude` as three rationals (degrees, minutes, seconds),
//! `GPSAltitudeRef` (0 = above, 1 = below the reference) + `GPSAltitude` (m; the specification's reference is
//! sea level, what a device writes varies, so the import configuration declares it), `GPSTimeStamp` (three
//! rationals, UTC) + `GPSDateStamp` (`YYYY:MM:DD`), `GPSImgDirectionRef` (T = true, M = magnetic north) +
//! `GPSImgDirection` (degrees); without GPS time `DateTimeOriginal` with `OffsetTimeOriginal` (EXIF 2.31).
//! And Google's "Photo Sphere XMP metadata" (namespace `http://ns.google.com/photos/1.0/panorama/`):
//! `PoseHeadingDegrees` (compass heading of the image centre, true north), `PosePitchDegrees` (above the
//! horizon), `PoseRollDegrees` (the horizon turns counter-clockwise in the image as it grows), as attributes
//! or elements of the XMP packet in a JPEG APP1 segment. Parsing EXIF uses the `kamadak-exif` crate; the XMP
//! packet is read with `roxmltree`.

use crate::campaign::{parse_time_s, Problem};
use exif::{In, Tag, Value};
use std::path::Path;

/// The GPano namespace.
pub const GPANO_NS: &str = "http://ns.google.com/photos/1.0/panorama/";

/// What a panorama's tags say (`None` where a tag is absent).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ImageTags {
    pub lat_deg: Option<f64>,
    pub lon_deg: Option<f64>,
    /// Signed altitude, m (negative below the reference).
    pub altitude_m: Option<f64>,
    /// Acquisition time, Unix seconds UTC.
    pub time_unix_s: Option<f64>,
    /// `GPSImgDirection` to true north, degrees.
    pub gps_direction_true_deg: Option<f64>,
    /// GPano pose of the image centre: heading (true north), pitch, roll, degrees.
    pub gpano_heading_deg: Option<f64>,
    pub gpano_pitch_deg: Option<f64>,
    pub gpano_roll_deg: Option<f64>,
}

fn rationals(exif: &exif::Exif, tag: Tag) -> Option<Vec<f64>> {
    match &exif.get_field(tag, In::PRIMARY)?.value {
        Value::Rational(v) => Some(v.iter().map(|r| r.to_f64()).collect()),
        _ => None,
    }
}

fn ascii(exif: &exif::Exif, tag: Tag) -> Option<String> {
    match &exif.get_field(tag, In::PRIMARY)?.value {
        Value::Ascii(v) => v
            .first()
            .map(|s| String::from_utf8_lossy(s).trim().to_string()),
        _ => None,
    }
}

fn dms(v: &[f64]) -> Option<f64> {
    (v.len() == 3).then(|| v[0] + v[1] / 60.0 + v[2] / 3600.0)
}

/// Signed degrees of a latitude/longitude tag pair, `Err` for a reference that is neither of `pos`/`neg`.
fn coordinate(
    exif: &exif::Exif,
    value: Tag,
    reference: Tag,
    pos: &str,
    neg: &str,
) -> Result<Option<f64>, String> {
    let Some(deg) = rationals(exif, value).and_then(|v| dms(&v)) else {
        return Ok(None);
    };
    match ascii(exif, reference).as_deref() {
        Some(r) if r.eq_ignore_ascii_case(pos) => Ok(Some(deg)),
        Some(r) if r.eq_ignore_ascii_case(neg) => Ok(Some(-deg)),
        other => Err(format!("{reference} is {other:?}, not {pos} or {neg}")),
    }
}

fn gps_time(exif: &exif::Exif) -> Option<f64> {
    let date = ascii(exif, Tag::GPSDateStamp)?;
    let hms = rationals(exif, Tag::GPSTimeStamp)?;
    if hms.len() != 3 {
        return None;
    }
    let day = parse_time_s(&format!("{}T00:00:00Z", date.replace(':', "-"))).ok()?;
    Some(day + hms[0] * 3600.0 + hms[1] * 60.0 + hms[2])
}

fn original_time(exif: &exif::Exif) -> Option<f64> {
    let t = ascii(exif, Tag::DateTimeOriginal)?;
    let zone = ascii(exif, Tag::OffsetTimeOriginal)?;
    let (date, time) = t.split_once(' ')?;
    parse_time_s(&format!("{}T{time}{zone}", date.replace(':', "-"))).ok()
}

fn read_exif(path: &Path, tags: &mut ImageTags) -> Result<(), String> {
    let file = std::fs::File::open(path).map_err(|e| format!("cannot be read ({e})"))?;
    let exif = match exif::Reader::new().read_from_container(&mut std::io::BufReader::new(file)) {
        Ok(e) => e,
        Err(exif::Error::NotFound(_)) => return Ok(()),
        Err(e) => return Err(format!("has unreadable EXIF data ({e})")),
    };
    tags.lat_deg = coordinate(&exif, Tag::GPSLatitude, Tag::GPSLatitudeRef, "N", "S")?;
    tags.lon_deg = coordinate(&exif, Tag::GPSLongitude, Tag::GPSLongitudeRef, "E", "W")?;
    tags.altitude_m = rationals(&exif, Tag::GPSAltitude)
        .and_then(|v| v.first().copied())
        .map(|a| {
            match exif
                .get_field(Tag::GPSAltitudeRef, In::PRIMARY)
                .and_then(|f| f.value.get_uint(0))
            {
                Some(1) => -a,
                _ => a,
            }
        });
    tags.time_unix_s = gps_time(&exif).or_else(|| original_time(&exif));
    if let Some(d) = rationals(&exif, Tag::GPSImgDirection).and_then(|v| v.first().copied()) {
        match ascii(&exif, Tag::GPSImgDirectionRef).as_deref() {
            Some("T") => tags.gps_direction_true_deg = Some(d),
            Some("M") => {}
            other => return Err(format!("GPSImgDirectionRef is {other:?}, not T or M")),
        }
    }
    Ok(())
}

/// The XMP packets of a JPEG's APP1 segments.
fn xmp_packets(bytes: &[u8]) -> Vec<&str> {
    const XMP: &[u8] = b"http://ns.adobe.com/xap/1.0/\0";
    let mut out = Vec::new();
    let mut i = 2;
    if bytes.get(..2) != Some(&[0xFF, 0xD8]) {
        return out;
    }
    while i + 4 <= bytes.len() && bytes[i] == 0xFF {
        let marker = bytes[i + 1];
        if marker == 0xDA || marker == 0xD9 {
            break;
        }
        let len = usize::from(u16::from_be_bytes([bytes[i + 2], bytes[i + 3]]));
        let Some(seg) = bytes.get(i + 4..i + 2 + len) else {
            break;
        };
        if marker == 0xE1 && seg.starts_with(XMP) {
            if let Ok(s) = std::str::from_utf8(&seg[XMP.len()..]) {
                out.push(s);
            }
        }
        i += 2 + len;
    }
    out
}

fn read_gpano(path: &Path, tags: &mut ImageTags) -> Result<(), String> {
    let bytes = std::fs::read(path).map_err(|e| format!("cannot be read ({e})"))?;
    for packet in xmp_packets(&bytes) {
        let doc = roxmltree::Document::parse(packet.trim_end_matches('\0'))
            .map_err(|e| format!("has an XMP packet that is not XML ({e})"))?;
        let value = |name: &str| -> Result<Option<f64>, String> {
            for node in doc.descendants().filter(|n| n.is_element()) {
                let text = node.attribute((GPANO_NS, name)).or_else(|| {
                    (node.tag_name().namespace() == Some(GPANO_NS)
                        && node.tag_name().name() == name)
                        .then(|| node.text().unwrap_or(""))
                });
                if let Some(t) = text {
                    return t
                        .trim()
                        .parse::<f64>()
                        .ok()
                        .filter(|v| v.is_finite())
                        .map(Some)
                        .ok_or_else(|| format!("GPano:{name} '{t}' is not a number"));
                }
            }
            Ok(None)
        };
        tags.gpano_heading_deg = value("PoseHeadingDegrees")?.or(tags.gpano_heading_deg);
        tags.gpano_pitch_deg = value("PosePitchDegrees")?.or(tags.gpano_pitch_deg);
        tags.gpano_roll_deg = value("PoseRollDegrees")?.or(tags.gpano_roll_deg);
    }
    Ok(())
}

/// Read the tags of one image; `Err` is a problem naming the file.
pub fn read_image_tags(path: &Path) -> Result<ImageTags, Problem> {
    let mut tags = ImageTags::default();
    read_exif(path, &mut tags)
        .and_then(|()| read_gpano(path, &mut tags))
        .map_err(|m| {
            Problem::error(
                path,
                None,
                None,
                m,
                "check the image's EXIF/XMP tags (exiftool -G -a shows them)",
            )
        })?;
    Ok(tags)
}
