//! Property-based fuzzing of everything that reads user files: the CSV tables (through the campaign reader),
//! campaign.toml, the image header probe and the decoders behind it. Inputs are valid files mutated at random
//! (bytes replaced, inserted, deleted, truncated) and free-form text; the property is that nothing panics and
//! every rejection is a problem naming its file. Ignored by default (≥ 10⁵ cases, minutes):
//! `cargo test --release -p skytie-stages --test fuzz_loaders -- --ignored --nocapture`
//! (`FUZZ_CASES` overrides the number of cases per loader).

use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use skytie_stages::campaign::read_campaign;
use skytie_stages::imaging::io::load_gray;
use skytie_stages::imaging::probe::probe_bytes;
use std::io::Cursor;
use std::path::Path;

fn cases() -> u32 {
    std::env::var("FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(40_000)
}

const RECORDINGS: &str = "image_id,file,time,x,y,z,heading,camera_height,sigma_xy\n\
p0,p0.jpg,2019-06-14T10:31:07.000Z,155000,463000,2.5,90,2.4,0.5\n\
p1,p1.jpg,2019-06-14T10:31:08.000Z,155005,463000,2.5,90,2.4,\n\
# comment\n\
p2,\"p 2.jpg\",2019-06-14T11:31:09+01:00,155010,463000.5,2.5,90,2.4,1e-3\n";

/// A mutation of `seed`: each step replaces, inserts or deletes one byte, or truncates.
fn mutated(seed: &'static [u8]) -> impl Strategy<Value = Vec<u8>> {
    prop::collection::vec((0u8..4, any::<prop::sample::Index>(), any::<u8>()), 0..8).prop_map(
        move |ops| {
            let mut b = seed.to_vec();
            for (op, at, byte) in ops {
                if b.is_empty() {
                    b.push(byte);
                    continue;
                }
                let i = at.index(b.len());
                match op {
                    0 => b[i] = byte,
                    1 => b.insert(i, byte),
                    2 => {
                        b.remove(i);
                    }
                    _ => b.truncate(i),
                }
            }
            b
        },
    )
}

fn runner() -> TestRunner {
    TestRunner::new(Config {
        cases: cases(),
        failure_persistence: None,
        ..Config::default()
    })
}

#[test]
#[ignore = "fuzzing: minutes; run with --ignored"]
fn campaign_tables_and_toml_never_panic() {
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path();
    std::fs::create_dir_all(root.join("mm/panoramas")).unwrap();
    let strategy = (
        mutated(RECORDINGS.as_bytes()),
        mutated(b"name = \"x\"\ncrs = \"EPSG:28992\"\n"),
        ".{0,80}",
    );
    runner()
        .run(&strategy, |(csv, toml, free)| {
            std::fs::write(root.join("mm/recordings.csv"), &csv).unwrap();
            std::fs::write(root.join("campaign.toml"), &toml).unwrap();
            if let Ok((_, problems)) = read_campaign(root) {
                prop_assert!(problems.iter().all(|p| !p.file.as_os_str().is_empty()));
            }
            std::fs::write(root.join("mm/recordings.csv"), free.as_bytes()).unwrap();
            let _ = read_campaign(root);
            Ok(())
        })
        .unwrap();
}

fn encoded(format: image::ImageFormat) -> &'static [u8] {
    let img = image::RgbImage::from_fn(24, 12, |x, y| {
        image::Rgb([(x * 9) as u8, (y * 17) as u8, (x ^ y) as u8])
    });
    let mut out = Cursor::new(Vec::new());
    image::DynamicImage::ImageRgb8(img)
        .write_to(&mut out, format)
        .unwrap();
    Box::leak(out.into_inner().into_boxed_slice())
}

#[test]
#[ignore = "fuzzing: minutes; run with --ignored"]
fn image_probe_and_decoders_never_panic() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("img");
    for format in [
        image::ImageFormat::Jpeg,
        image::ImageFormat::Png,
        image::ImageFormat::Tiff,
    ] {
        let seed = encoded(format);
        runner()
            .run(&mutated(seed), |bytes| {
                if probe_bytes(&bytes).is_ok() {
                    // What the probe accepts goes to the decoders, as in the run.
                    std::fs::write(&path, &bytes).unwrap();
                    let _ = load_gray(Path::new(&path));
                }
                Ok(())
            })
            .unwrap();
    }
}
