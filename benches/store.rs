//! Benchmark of storing and loading a 4000×3000 `f32` GrayImage (48 MB) through the artifact store, with
//! the pieces it is made of measured alone in the same run, so the totals can be explained.
//!
//! Plain `main` timing harness; every row is the best of several runs; 1 GB = 1e9 bytes of image samples.
//! Each row gives GB/s by wall time and by CPU time of this process (user + system, all threads: blake3
//! hashes big blocks on the rayon pool, so CPU time can exceed wall time), and the CPU-time ratio to one
//! memcpy into a fresh Vec. On a machine shared with other processes the CPU figures are the meaningful
//! ones. Loads read a file that is in the page cache (it was just written): they measure the CPU path, not
//! the disk. `fsync` is measured alone (wall time: it waits for the device, costs little CPU).
//!
//! Rows:
//! - references: memcpy into a reused buffer and into a fresh Vec (page faults of fresh memory included);
//! - pieces: blake3 of 48 MB; `write` of 48 MB to a new file without fsync (copy into the page cache);
//!   fsync of that file; `read` of the file into a fresh `Vec<f32>`;
//! - codec: encode into a fresh Vec, decode from bytes into a fresh image (the buffer path);
//! - store, buffer path (`encode` + `Store::save`, `Store::load` + `decode`): what a caller holding bytes
//!   pays;
//! - store, streaming path (`Store::save_with(encode_to)`, `Store::load_with(decode_from)`): header + the
//!   image's own memory written to the entry file, hashed on the way; one read straight into the new image.
//!
//! Run: `cargo bench --bench store`.

use std::fs::File;
use std::io::{Read, Write};
use std::time::{Duration, Instant};

use skytie::codec::Artifact;
use skytie::hashing::{hash_bytes, KeyBuilder};
use skytie::store::{EntryMeta, Loaded, Lookup, Store};
use skytie::testing::harness::cpu_time;
use skytie_stages::imaging::GrayImage;

const RUNS: usize = 7;

/// Best wall time and best CPU time of `RUNS` calls of `f`; `setup` runs before each call, untimed.
fn measure_with(mut setup: impl FnMut(), mut f: impl FnMut()) -> (Duration, Duration) {
    let (mut wall, mut cpu) = (Duration::MAX, Duration::MAX);
    for _ in 0..RUNS {
        setup();
        let (t, c) = (Instant::now(), cpu_time());
        f();
        wall = wall.min(t.elapsed());
        cpu = cpu.min(cpu_time().saturating_sub(c));
    }
    (wall, cpu)
}

fn measure(f: impl FnMut()) -> (Duration, Duration) {
    measure_with(|| {}, f)
}

fn gbps(bytes: usize, t: Duration) -> f64 {
    bytes as f64 / t.as_secs_f64().max(1e-9) / 1e9
}

fn as_bytes(samples: &[f32]) -> &[u8] {
    // SAFETY: f32 has no padding; the view covers exactly the samples and borrows them.
    unsafe { std::slice::from_raw_parts(samples.as_ptr().cast::<u8>(), samples.len() * 4) }
}

fn as_bytes_mut(samples: &mut [f32]) -> &mut [u8] {
    // SAFETY: as above; any 4 bytes are a valid f32.
    unsafe { std::slice::from_raw_parts_mut(samples.as_mut_ptr().cast::<u8>(), samples.len() * 4) }
}

fn remove_entry<'a>(store: &'a Store, key: &'a skytie::hashing::NodeKey) -> impl FnMut() + 'a {
    move || {
        let _ = std::fs::remove_file(store.object_path(key));
    }
}

/// MADV_HUGEPAGE on the 2 MiB-aligned part of `samples` (what the codec does for fresh image buffers).
fn advise_huge(samples: &mut [f32]) {
    let start = samples.as_mut_ptr() as usize;
    let end = start + samples.len() * 4;
    let a = (start + (2 << 20) - 1) & !((2 << 20) - 1);
    if end > a {
        unsafe {
            libc::madvise(
                a as *mut libc::c_void,
                (end - a) & !((2 << 20) - 1),
                libc::MADV_HUGEPAGE,
            );
        }
    }
}

fn main() {
    if let Ok(load) = std::fs::read_to_string("/proc/loadavg") {
        println!(
            "machine load average (other processes compete for the cores): {}",
            load.trim()
        );
    }
    println!(
        "rayon threads: {}; best of {RUNS} runs each",
        rayon::current_num_threads()
    );
    let (w, h) = (4000, 3000);
    let data: Vec<f32> = (0..w * h)
        .map(|i| ((i % 4099) as f32 * 0.000_244).sin())
        .collect();
    let img = GrayImage::from_vec(w, h, data).expect("image");
    let bytes = w * h * 4;
    let dir = tempfile::tempdir().expect("temp dir");

    // References.
    let mut dst = vec![0f32; w * h];
    let memcpy = measure(|| {
        dst.copy_from_slice(std::hint::black_box(&img.data));
        std::hint::black_box(&dst);
    });
    let memcpy_new = measure(|| {
        std::hint::black_box(std::hint::black_box(&img.data).clone());
    });

    // Pieces.
    let hash = measure(|| {
        std::hint::black_box(hash_bytes(as_bytes(&img.data)));
    });
    let raw_path = dir.path().join("raw.bin");
    let write_raw = measure_with(
        || {
            let _ = std::fs::remove_file(&raw_path);
        },
        || {
            let mut f = File::create(&raw_path).expect("create");
            f.write_all(as_bytes(&img.data)).expect("write");
        },
    );
    let fsync = measure_with(
        || {
            let _ = std::fs::remove_file(&raw_path);
            let mut f = File::create(&raw_path).expect("create");
            f.write_all(as_bytes(&img.data)).expect("write");
        },
        || {
            File::options()
                .write(true)
                .open(&raw_path)
                .expect("open")
                .sync_all()
                .expect("fsync");
        },
    );
    // Reads the raw samples into a fresh buffer, backed by huge pages or not.
    let read_raw_into = |huge: bool| {
        let mut samples = vec![0f32; w * h];
        if huge {
            advise_huge(&mut samples);
        }
        File::open(&raw_path)
            .expect("open")
            .read_exact(as_bytes_mut(&mut samples))
            .expect("read");
        std::hint::black_box(samples);
    };
    let read_raw = measure(|| read_raw_into(false));

    let read_raw_huge = measure(|| read_raw_into(true));
    let memcpy_new_huge = measure(|| {
        let mut samples = vec![0f32; w * h];
        advise_huge(&mut samples);
        samples.copy_from_slice(std::hint::black_box(&img.data));
        std::hint::black_box(samples);
    });

    // Codec, buffer path.
    let mut encoded = Vec::new();
    img.encode(&mut encoded);
    let encode = measure(|| {
        let mut out = Vec::new();
        img.encode(&mut out);
        std::hint::black_box(out);
    });
    let decode = measure(|| {
        std::hint::black_box(GrayImage::decode(&encoded).expect("decode"));
    });

    let store = Store::open(&dir.path().join("cache")).expect("store");
    let meta = EntryMeta::new("bench", "1", "image 4000x3000");
    let check = |back: &GrayImage| {
        assert!(
            back.width == w && back.height == h && back.data == img.data,
            "round trip changed the image"
        );
    };

    // Store, buffer path.
    let key_buffered = KeyBuilder::new("bench-buffered", 1).finish();
    // Saves go to a key with no entry yet (as in a run); replacing an entry would add freeing its pages.
    let save_buffered = measure_with(remove_entry(&store, &key_buffered), || {
        let mut buf = Vec::new();
        img.encode(&mut buf);
        store.save(&key_buffered, &meta, &buf).expect("save");
    });
    let mut last = None;
    let load_buffered = measure(|| match store.load(&key_buffered).expect("load") {
        Lookup::Hit(e) => last = Some(GrayImage::decode(&e.payload).expect("decode")),
        other => panic!("expected a hit, got {other:?}"),
    });
    check(&last.take().expect("loaded"));

    // Store, streaming path.
    let key_streamed = KeyBuilder::new("bench-streamed", 1).finish();
    let save_streamed = measure_with(remove_entry(&store, &key_streamed), || {
        store
            .save_with(&key_streamed, &meta, |sink| img.encode_to(sink))
            .expect("save");
    });
    let load_streamed = measure(|| {
        match store
            .load_with(&key_streamed, GrayImage::decode_from)
            .expect("load")
        {
            Loaded::Hit { value, .. } => last = Some(value),
            Loaded::Miss => panic!("expected a hit, got a miss"),
            Loaded::Corrupt { message } => panic!("expected a hit: {message}"),
        }
    });
    check(&last.take().expect("loaded"));
    assert_eq!(
        std::fs::read(store.object_path(&key_streamed))
            .expect("entry")
            .len(),
        std::fs::read(store.object_path(&key_buffered))
            .expect("entry")
            .len(),
        "both paths write the same entry layout"
    );

    println!(
        "{:<66} {:>8} {:>9} {:>9} {:>8} {:>7}",
        "48 MB GrayImage 4000x3000", "wall ms", "wall GB/s", "CPU ms", "CPU GB/s", "CPU/cpy"
    );
    let row = |name: &str, (wall, cpu): (Duration, Duration)| {
        println!(
            "{:<66} {:>8.1} {:>9.2} {:>9.1} {:>8.2} {:>6.2}×",
            name,
            wall.as_secs_f64() * 1e3,
            gbps(bytes, wall),
            cpu.as_secs_f64() * 1e3,
            gbps(bytes, cpu),
            cpu.as_secs_f64() / memcpy_new.1.as_secs_f64().max(1e-9)
        );
    };
    let sum = |a: (Duration, Duration), b: (Duration, Duration)| (a.0 + b.0, a.1 + b.1);
    println!("references");
    row("  memcpy into a reused buffer", memcpy);
    row(
        "  memcpy into a fresh Vec (page faults included)",
        memcpy_new,
    );
    println!("pieces");
    row("  blake3 of 48 MB (rayon)", hash);
    row(
        "  write 48 MB to a new file, no fsync (page-cache copy)",
        write_raw,
    );
    row("  fsync of that 48 MB file alone", fsync);
    row(
        "  read 48 MB file (page cache) into a fresh Vec<f32>",
        read_raw,
    );
    row("  same, MADV_HUGEPAGE", read_raw_huge);
    row("  memcpy into fresh, MADV_HUGEPAGE", memcpy_new_huge);
    println!("codec, buffer path");
    row("  encode into a fresh Vec", encode);
    row("  decode into a fresh image", decode);
    println!("store, buffer path (encode + save; load + decode)");
    row(
        "  save: encode, write + hash, header, fsync, rename",
        save_buffered,
    );
    row(
        "  load: read + hash into a fresh Vec, decode",
        load_buffered,
    );
    row(
        "  save + load (bytes of one image / summed time)",
        sum(save_buffered, load_buffered),
    );
    println!("store, streaming path (save_with(encode_to); load_with(decode_from))");
    row(
        "  save: write + hash from the image's memory, header, fsync, rename",
        save_streamed,
    );
    row(
        "  load: one read + hash into the new image's buffer",
        load_streamed,
    );
    row(
        "  save + load (bytes of one image / summed time)",
        sum(save_streamed, load_streamed),
    );
    row(
        "  save without its fsync (save minus the fsync row)",
        (
            save_streamed.0.saturating_sub(fsync.0),
            save_streamed.1.saturating_sub(fsync.1),
        ),
    );
}
