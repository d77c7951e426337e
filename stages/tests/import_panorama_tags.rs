//! Panoramas with their pose in EXIF GPS and GPano XMP tags, written by hand after the EXIF 2.32 GPS IFD and
//! Google's Photo Sphere XMP documentation into small JPEG files: the tags are read exactly (degrees-minutes-
//! seconds, N/S/E/W and altitude references, GPS date + time in UTC or DateTimeOriginal with its offset,
//! GPano as attributes or elements, magnetic directions ignored), and `skytie import` turns them into
//! recordings in RD New + NAP with grid yaw and the driving direction from the neighbours.

use exif::experimental::Writer;
use exif::{Field, In, Rational, Tag, Value};
use skytie_stages::campaign::read_campaign;
use skytie_stages::formats::image_tags::read_image_tags;
use skytie_stages::import::config::CampaignSection;
use skytie_stages::import::context::ImportContext;
use skytie_stages::import::{run_import, ImportConfig};
use std::path::Path;

fn field(tag: Tag, value: Value) -> Field {
    Field {
        tag,
        ifd_num: In::PRIMARY,
        value,
    }
}

fn ascii(s: &str) -> Value {
    Value::Ascii(vec![s.as_bytes().to_vec()])
}

fn rat(v: &[(u32, u32)]) -> Value {
    Value::Rational(
        v.iter()
            .map(|&(num, denom)| Rational { num, denom })
            .collect(),
    )
}

/// A 16 × 8 JPEG with an EXIF segment of `fields` and an XMP packet `xmp` (if any).
fn jpeg(path: &Path, fields: &[Field], xmp: Option<&str>) {
    let mut pixels = Vec::new();
    image::codecs::jpeg::JpegEncoder::new(&mut pixels)
        .encode(&[128u8; 16 * 8 * 3], 16, 8, image::ExtendedColorType::Rgb8)
        .unwrap();
    let mut w = Writer::new();
    for f in fields {
        w.push_field(f);
    }
    let mut tiff = std::io::Cursor::new(Vec::new());
    w.write(&mut tiff, false).unwrap();
    let segment = |payload: &[u8]| {
        let mut s = vec![0xFF, 0xE1];
        s.extend_from_slice(&u16::try_from(payload.len() + 2).unwrap().to_be_bytes());
        s.extend_from_slice(payload);
        s
    };
    let mut out = pixels[..2].to_vec();
    out.extend(segment(&[b"Exif\0\0".as_slice(), tiff.get_ref()].concat()));
    if let Some(x) = xmp {
        out.extend(segment(
            &[b"http://ns.adobe.com/xap/1.0/\0".as_slice(), x.as_bytes()].concat(),
        ));
    }
    out.extend_from_slice(&pixels[2..]);
    std::fs::write(path, out).unwrap();
}

fn xmp_attributes(heading: f64, pitch: f64, roll: f64) -> String {
    format!(
        r#"<x:xmpmeta xmlns:x="adobe:ns:meta/"><rdf:RDF xmlns:rdf="http://www.w3.org/1999/02/22-rdf-syntax-ns#"><rdf:Description rdf:about="" xmlns:GPano="http://ns.google.com/photos/1.0/panorama/" GPano:ProjectionType="equirectangular" GPano:PoseHeadingDegrees="{heading}" GPano:PosePitchDegrees="{pitch}" GPano:PoseRollDegrees="{roll}"/></rdf:RDF></x:xmpmeta>"#
    )
}

/// GPS fields at 52° 5' s_lat" N, 5° 7' s_lon" E (seconds in 1/100), altitude in dm, UTC time 10:31:(s/100).
fn gps(s_lat: u32, s_lon: u32, alt_dm: u32, s_time: u32) -> Vec<Field> {
    vec![
        field(Tag::GPSLatitudeRef, ascii("N")),
        field(Tag::GPSLatitude, rat(&[(52, 1), (5, 1), (s_lat, 100)])),
        field(Tag::GPSLongitudeRef, ascii("E")),
        field(Tag::GPSLongitude, rat(&[(5, 1), (7, 1), (s_lon, 100)])),
        field(Tag::GPSAltitudeRef, Value::Byte(vec![0])),
        field(Tag::GPSAltitude, rat(&[(alt_dm, 10)])),
        field(Tag::GPSTimeStamp, rat(&[(10, 1), (31, 1), (s_time, 100)])),
        field(Tag::GPSDateStamp, ascii("2019:06:14")),
    ]
}

#[test]
fn tags_are_read_as_documented() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.jpg");
    let mut f = gps(2652, 1704, 476, 725);
    f.push(field(Tag::GPSImgDirectionRef, ascii("T")));
    f.push(field(Tag::GPSImgDirection, rat(&[(615, 10)])));
    jpeg(&a, &f, Some(&xmp_attributes(61.5, 1.25, -0.5)));
    let t = read_image_tags(&a).unwrap();
    assert!((t.lat_deg.unwrap() - (52.0 + 5.0 / 60.0 + 26.52 / 3600.0)).abs() < 1e-12);
    assert!((t.lon_deg.unwrap() - (5.0 + 7.0 / 60.0 + 17.04 / 3600.0)).abs() < 1e-12);
    assert_eq!(t.altitude_m, Some(47.6));
    assert_eq!(t.time_unix_s, Some(1_560_508_267.25)); // 2019-06-14T10:31:07.25Z
    assert_eq!(t.gps_direction_true_deg, Some(61.5));
    assert_eq!(
        (t.gpano_heading_deg, t.gpano_pitch_deg, t.gpano_roll_deg),
        (Some(61.5), Some(1.25), Some(-0.5))
    );

    // South/west, below the reference, local time with its offset, a magnetic direction, GPano as elements.
    let b = dir.path().join("b.jpg");
    let f = vec![
        field(Tag::GPSLatitudeRef, ascii("S")),
        field(Tag::GPSLatitude, rat(&[(33, 1), (51, 1), (3600, 100)])),
        field(Tag::GPSLongitudeRef, ascii("W")),
        field(Tag::GPSLongitude, rat(&[(70, 1), (30, 1), (0, 1)])),
        field(Tag::GPSAltitudeRef, Value::Byte(vec![1])),
        field(Tag::GPSAltitude, rat(&[(25, 10)])),
        field(Tag::DateTimeOriginal, ascii("2019:06:14 12:31:07")),
        field(Tag::OffsetTimeOriginal, ascii("+02:00")),
        field(Tag::GPSImgDirectionRef, ascii("M")),
        field(Tag::GPSImgDirection, rat(&[(90, 1)])),
    ];
    let xmp = r#"<x:xmpmeta xmlns:x="adobe:ns:meta/"><rdf:RDF xmlns:rdf="http://www.w3.org/1999/02/22-rdf-syntax-ns#"><rdf:Description xmlns:P="http://ns.google.com/photos/1.0/panorama/"><P:PoseHeadingDegrees>271.25</P:PoseHeadingDegrees></rdf:Description></rdf:RDF></x:xmpmeta>"#;
    jpeg(&b, &f, Some(xmp));
    let t = read_image_tags(&b).unwrap();
    assert!((t.lat_deg.unwrap() + 33.86).abs() < 1e-12);
    assert_eq!(t.lon_deg, Some(-70.5));
    assert_eq!(t.altitude_m, Some(-2.5));
    assert_eq!(t.time_unix_s, Some(1_560_508_267.0));
    assert_eq!(t.gps_direction_true_deg, None);
    assert_eq!(
        (t.gpano_heading_deg, t.gpano_pitch_deg),
        (Some(271.25), None)
    );

    // A reference that is not N/S is an error naming the tag.
    let c = dir.path().join("c.jpg");
    let mut f = gps(2652, 1704, 476, 725);
    f[0] = field(Tag::GPSLatitudeRef, ascii("X"));
    jpeg(&c, &f, None);
    let e = read_image_tags(&c).unwrap_err();
    assert!(e.message.contains("GPSLatitudeRef"), "{e:?}");
}

#[test]
fn panoramas_with_tags_import_into_rd_new() {
    let dir = tempfile::tempdir().unwrap();
    let panos = dir.path().join("panos");
    std::fs::create_dir_all(&panos).unwrap();
    // Three panoramas driving east-north-east, 0.64 s apart; the fourth has no GPS tags.
    for (i, (s_lat, s_lon)) in [(2652, 1704), (2664, 1730), (2676, 1756)]
        .into_iter()
        .enumerate()
    {
        jpeg(
            &panos.join(format!("p{i}.jpg")),
            &gps(s_lat, s_lon, 476 + i as u32, 725 + 64 * i as u32),
            Some(&xmp_attributes(61.5 + i as f64, 1.25, -0.5)),
        );
    }
    jpeg(
        &panos.join("p3.jpg"),
        &[field(Tag::DateTimeOriginal, ascii("2019:06:14 12:31:09"))],
        None,
    );
    let cfg = dir.path().join("import.toml");
    std::fs::write(&cfg, "[campaign]\nname = \"tags\"\ncrs = \"EPSG:28992+5709\"\ngeoid_separation_m = 43.25\n[panorama_tags]\npanoramas = \"panos\"\ncrs = \"EPSG:4937\"\nheights = \"ellipsoidal\"\ncamera_height_m = 2.5\nsigma_xy_m = 3.0\n").unwrap();
    let report = run_import(&ImportConfig::read(&cfg).unwrap(), &dir.path().join("c")).unwrap();
    assert_eq!(report.skipped(), 1, "{report}");
    assert!(
        report.to_string().contains("p3.jpg") && report.to_string().contains("GPSLatitude"),
        "{report}"
    );
    let (c, problems) = read_campaign(&dir.path().join("c")).unwrap();
    assert!(problems.is_empty(), "{problems:?}");
    assert_eq!(c.recordings.len(), 3);
    let ctx = ImportContext::new(&CampaignSection {
        name: "t".into(),
        crs: "EPSG:28992+5709".into(),
        geoid_grid: None,
        geoid_separation_m: Some(43.25),
        datum_grid: None,
        frame: Default::default(),
    })
    .unwrap();
    let conv = ctx
        .converter(Some("EPSG:4937"), Some("ellipsoidal"))
        .unwrap();
    for (i, r) in c.recordings.iter().enumerate() {
        let lat = 52.0 + 5.0 / 60.0 + [26.52, 26.64, 26.76][i] / 3600.0;
        let lon = 5.0 + 7.0 / 60.0 + [17.04, 17.30, 17.56][i] / 3600.0;
        let (x, y, z) = conv.position(lat, lon, 47.6 + 0.1 * i as f64).unwrap();
        assert!((r.x - x).abs() < 1e-6 && (r.y - y).abs() < 1e-6 && (r.z - z).abs() < 1e-6);
        assert!(
            (47.6 + 0.1 * i as f64 - 43.25 - r.z).abs() < 0.01,
            "NAP height {}",
            r.z
        );
        // Grid yaw = true heading + the grid azimuth of true north (west of RD New's central meridian: ≈ +0.21°).
        let gamma = conv.north_azimuth_deg(lat, lon).unwrap();
        assert!(gamma > 0.1 && gamma < 0.4, "{gamma}");
        assert!(
            (r.yaw_deg - (61.5 + i as f64 + gamma)).abs() < 1e-6,
            "{} {}",
            r.yaw_deg,
            gamma
        );
        assert!((r.pitch_deg - 1.25).abs() < 1e-6 && (r.roll_deg + 0.5).abs() < 1e-6);
        assert_eq!(
            (r.camera_height_m, r.sigma_xy_m, r.sigma_z_m),
            (2.5, Some(3.0), None)
        );
    }
    assert_eq!(c.recordings[0].time, "2019-06-14T10:31:07.250Z");
    // Driving direction: along the track (north-east), not the panorama's heading.
    let (a, b) = (&c.recordings[0], &c.recordings[2]);
    let track = (b.x - a.x).atan2(b.y - a.y).to_degrees();
    assert!(
        (c.recordings[1].heading_deg - track).abs() < 1e-9,
        "{}",
        c.recordings[1].heading_deg
    );
}
