//! The synthetic campaign is deterministic: `tiny` with seed 1 generated twice, and with 1 vs 2 rayon
//! threads, gives byte-identical folders (every file compared); the folder follows the campaign format;
//! regenerating over a previous synthetic campaign replaces it, while a foreign folder is refused; a generation
//! resumed from the render store of an interrupted one gives the same folder.

use skytie_stages::campaign::RECORDING_COLUMNS;
use skytie_stages::synth::render_store::RenderStore;
use skytie_stages::synth::{
    generate, generate_resumable, Preset, SynthError, SynthOptions, SynthSummary,
};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Every file below `root` (relative path → bytes).
fn read_tree(root: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for e in std::fs::read_dir(&dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.insert(
                    p.strip_prefix(root).unwrap().to_path_buf(),
                    std::fs::read(&p).unwrap(),
                );
            }
        }
    }
    out
}

fn generate_with_threads(threads: usize, out: &Path) -> SynthSummary {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| generate(&SynthOptions::new(Preset::Tiny, 1), out).unwrap())
}

fn assert_same_tree(a: &BTreeMap<PathBuf, Vec<u8>>, b: &BTreeMap<PathBuf, Vec<u8>>, what: &str) {
    assert_eq!(
        a.keys().collect::<Vec<_>>(),
        b.keys().collect::<Vec<_>>(),
        "{what}: different file sets"
    );
    for (k, v) in a {
        assert!(v == &b[k], "{what}: {} differs", k.display());
    }
}

#[test]
fn tiny_is_byte_identical_across_runs_and_thread_counts() {
    let dir = tempfile::tempdir().unwrap();
    let (one, two) = (dir.path().join("one"), dir.path().join("two"));
    let s1 = generate_with_threads(1, &one);
    eprintln!(
        "tiny (1 thread): {s1:?}, {:.2e} primary rays/s",
        s1.rays_per_second()
    );
    let s2 = generate_with_threads(2, &two);
    eprintln!(
        "tiny (2 threads): {:.2} s, {:.2e} primary rays/s",
        s2.seconds,
        s2.rays_per_second()
    );
    let t1 = read_tree(&one);
    assert_same_tree(&t1, &read_tree(&two), "1 vs 2 threads");
    // A second 2-thread run, generated over the previous synthetic campaign (which it replaces).
    let s3 = generate_with_threads(2, &two);
    assert_same_tree(
        &t1,
        &read_tree(&two),
        "second run, replacing the previous folder",
    );

    // Counts and layout (campaign-format.md).
    assert_eq!(
        (s1.recordings, s1.nadir_images, s1.oblique_images),
        (s3.recordings, s3.nadir_images, s3.oblique_images)
    );
    assert!(
        (4..=8).contains(&s1.recordings),
        "tiny has ~6 panoramas: {}",
        s1.recordings
    );
    assert!(
        s1.nadir_images >= 2
            && s1.oblique_images >= 8
            && s1.checkpoints >= 1
            && s1.observations >= 2,
        "{s1:?}"
    );
    let toml = String::from_utf8(t1[Path::new("campaign.toml")].clone()).unwrap();
    assert!(
        toml.contains("name = \"synth-tiny-seed1\"") && toml.contains("crs = \"EPSG:28992\""),
        "{toml}"
    );
    let panos = t1
        .keys()
        .filter(|k| k.starts_with("mm/panoramas") && k.extension().is_some_and(|e| e == "jpg"))
        .count();
    assert_eq!(panos, s1.recordings);
    for f in [
        "mm/recordings.csv",
        "truth/recordings.csv",
        "truth/README.md",
        "aerial/nadir/cameras.csv",
        "aerial/oblique/cameras.csv",
        "control/checkpoints.csv",
        "control/observations.csv",
    ] {
        assert!(t1.contains_key(Path::new(f)), "missing {f}");
    }
    assert!(
        !t1.keys().any(|k| k.starts_with("truth/aerial")),
        "aerial poses are not perturbed by default"
    );
    let header = String::from_utf8(t1[Path::new("mm/recordings.csv")].clone()).unwrap();
    let first = header.lines().next().unwrap();
    for col in RECORDING_COLUMNS.iter().chain(&["sigma_xy", "sigma_z"]) {
        assert!(
            first.split(',').any(|c| c == *col),
            "column {col} missing in {first}"
        );
    }
    let pano = image::image_dimensions(one.join("mm/panoramas").join("pano_0_000.jpg")).unwrap();
    assert_eq!(pano, (1024, 512));
    // No temporary folders left next to the outputs.
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names.len(), 2, "{names:?}");

    // A foreign folder is refused and left alone.
    let foreign = dir.path().join("foreign");
    std::fs::create_dir_all(&foreign).unwrap();
    std::fs::write(foreign.join("notes.txt"), b"mine").unwrap();
    let e = generate(&SynthOptions::new(Preset::Tiny, 1), &foreign).unwrap_err();
    assert!(matches!(e, SynthError::OutputExists { .. }), "{e}");
    assert_eq!(std::fs::read(foreign.join("notes.txt")).unwrap(), b"mine");
}

#[test]
fn seeds_change_the_campaign() {
    // Different seeds give different errors (cheap: no rendering needed to see it).
    let a =
        skytie_stages::synth::generate::plan_campaign(&SynthOptions::new(Preset::Tiny, 1)).unwrap();
    let b =
        skytie_stages::synth::generate::plan_campaign(&SynthOptions::new(Preset::Tiny, 2)).unwrap();
    assert_ne!(a.recorded()[0].x, b.recorded()[0].x);
    assert_eq!(a.name, "synth-tiny-seed1");
}

#[test]
fn a_resumed_generation_takes_the_stored_images_and_gives_the_same_folder() {
    let dir = tempfile::tempdir().unwrap();
    let options = SynthOptions::new(Preset::Tiny, 1);
    let full = dir.path().join("full");
    let store_dir = dir.path().join("store");
    let (first, reused) = generate_resumable(&options, &full, &store_dir).unwrap();
    assert_eq!(reused, 0);
    assert!(
        !store_dir.exists(),
        "the store is removed once the campaign is installed"
    );
    let expected = read_tree(&full);

    // What an interrupted generation leaves: some finished images (with their hashes), one image whose bytes
    // were damaged afterwards, and a stray file of an unfinished write.
    let store = RenderStore::open(&store_dir, &options.store_identity().unwrap()).unwrap();
    let images: Vec<&PathBuf> = expected
        .keys()
        .filter(|k| k.extension().is_some_and(|e| e == "jpg"))
        .collect();
    assert!(images.len() >= 6, "{images:?}");
    let rel = |p: &Path| p.to_string_lossy().replace('\\', "/");
    for p in &images[..4] {
        store.keep(&rel(p), &full.join(p)).unwrap();
    }
    std::fs::write(store_dir.join(rel(images[3])), b"damaged").unwrap();
    std::fs::write(store_dir.join(format!("{}.tmp", rel(images[4]))), b"half").unwrap();

    let resumed = dir.path().join("resumed");
    let (second, reused) = generate_resumable(&options, &resumed, &store_dir).unwrap();
    assert_eq!(
        reused, 3,
        "three intact images are reused, the damaged one is rendered again"
    );
    assert!(second.primary_rays < first.primary_rays, "{second:?}");
    assert_same_tree(&expected, &read_tree(&resumed), "resumed vs uninterrupted");
    assert!(!store_dir.exists());

    // A store left by other options (another seed) is not used.
    let other = RenderStore::open(
        &store_dir,
        &SynthOptions::new(Preset::Tiny, 2).store_identity().unwrap(),
    )
    .unwrap();
    other.keep(&rel(images[0]), &full.join(images[0])).unwrap();
    let third = dir.path().join("third");
    let (_, reused) = generate_resumable(&options, &third, &store_dir).unwrap();
    assert_eq!(reused, 0);
}

/// Table-only error profiles share one rendering: the profile is applied to the rendered error-free folder,
/// the images are hard links to its files (same bytes, no copy), only the tables and `truth/` differ, and the
/// tables are the ones the in-memory plan makes (so a workflow's nodes and `skytie synth` write the same).
#[test]
fn table_profiles_share_one_rendering_of_the_images() {
    use skytie_stages::campaign::{read_aerial_csv, read_recordings_csv};
    use skytie_stages::synth::generate::plan_campaign;
    use skytie_stages::synth::{apply_profile, render_campaign, Profile};
    use std::os::unix::fs::MetadataExt;
    let dir = tempfile::tempdir().unwrap();
    let rendered = dir.path().join("rendered");
    let thesis = SynthOptions::new(Preset::Tiny, 3);
    render_campaign(&thesis, &rendered, &dir.path().join("store"), &|_, _| {}).unwrap();
    let mut rich = thesis.clone();
    rich.profile = Profile::parse("outage+ins+vertical+aerial").unwrap();
    assert_eq!(rich.render_identity(), thesis.render_identity());
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    apply_profile(&rendered, &thesis, &a).unwrap();
    apply_profile(&rendered, &rich, &b).unwrap();
    let (ta, tb) = (read_tree(&a), read_tree(&b));
    let mut differ: Vec<String> = Vec::new();
    for (k, v) in &ta {
        if k.starts_with("mm/panoramas")
            || k.starts_with("aerial") && k.extension().is_some_and(|e| e == "jpg")
        {
            assert!(tb[k] == *v, "{} differs", k.display());
            let (ia, ib) = (
                std::fs::metadata(a.join(k)).unwrap().ino(),
                std::fs::metadata(b.join(k)).unwrap().ino(),
            );
            assert_eq!(ia, ib, "{} is not shared", k.display());
        } else if tb.get(k) != Some(v) {
            differ.push(k.display().to_string());
        }
    }
    differ.sort();
    assert_eq!(
        differ,
        [
            "aerial/nadir/cameras.csv",
            "aerial/oblique/cameras.csv",
            "campaign.toml",
            "mm/recordings.csv",
            "truth/README.md"
        ]
    );
    assert!(
        tb.contains_key(Path::new("truth/aerial_nadir.csv"))
            && !ta.contains_key(Path::new("truth/aerial_nadir.csv"))
    );
    // The tables are those of the plan (the in-memory path).
    for (options, root) in [(&thesis, &a), (&rich, &b)] {
        let plan = plan_campaign(options).unwrap();
        let (recs, _) = read_recordings_csv(&root.join("mm/recordings.csv"));
        assert_eq!(recs.len(), plan.recorded().len());
        for (r, p) in recs.iter().zip(plan.recorded()) {
            assert_eq!(
                (r.x, r.y, r.z, r.yaw_deg, r.heading_deg),
                (p.x, p.y, p.z, p.yaw_deg, p.heading_deg)
            );
        }
        let (nadir, _) = read_aerial_csv(&root.join("aerial/nadir/cameras.csv"));
        assert_eq!(nadir, plan.applied.tables.nadir);
    }
    let readme = String::from_utf8(tb[Path::new("truth/README.md")].clone()).unwrap();
    assert!(readme.contains("`outage+ins+vertical+aerial`"), "{readme}");
}
