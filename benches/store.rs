//! Benchmark of storing and loading a 4000×3000 `f32` GrayImage (48 MB): codec encode/decode, and the full
//! store path (encode, hash, write, fsync, rename; then read, verify hash, decode), next to a plain memcpy of
//! the same buffer measured in the same run. Plain `main` timing harness, best of several runs, 1 GB = 1e9
//! bytes. Each row gives GB/s by wall time and by CPU time of this process (user + system, all threads), and
//! the CPU-time ratio to one memcpy into a fresh Vec: on a machine shared with other processes the CPU-time
//! figures are the meaningful ones. Run: `cargo bench --bench store`.

use std::time::{Duration, Instant};

use skytie::codec::Artifact;
use skytie::hashing::KeyBuilder;
use skytie::store::{EntryMeta, Lookup, Store};
use skytie_stages::imaging::GrayImage;

const RUNS: usize = 7;

/// CPU time (user + system, all threads) used by this process so far.
fn cpu_time() -> Duration {
    // SAFETY: getrusage only writes the zero-initialised struct we pass.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut usage) } != 0 {
        return Duration::ZERO;
    }
    let tv = |t: libc::timeval| Duration::new(t.tv_sec as u64, t.tv_usec as u32 * 1000);
    tv(usage.ru_utime) + tv(usage.ru_stime)
}

/// Best wall time and best CPU time of `RUNS` calls of `f`.
fn measure(mut f: impl FnMut()) -> (Duration, Duration) {
    let (mut wall, mut cpu) = (Duration::MAX, Duration::MAX);
    for _ in 0..RUNS {
        let (t, c) = (Instant::now(), cpu_time());
        f();
        wall = wall.min(t.elapsed());
        cpu = cpu.min(cpu_time().saturating_sub(c));
    }
    (wall, cpu)
}

fn gbps(bytes: usize, t: Duration) -> f64 {
    bytes as f64 / t.as_secs_f64().max(1e-9) / 1e9
}

fn main() {
    if let Ok(load) = std::fs::read_to_string("/proc/loadavg") {
        println!(
            "machine load average (other processes compete for the cores): {}",
            load.trim()
        );
    }
    let (w, h) = (4000, 3000);
    let data: Vec<f32> = (0..w * h)
        .map(|i| ((i % 4099) as f32 * 0.000_244).sin())
        .collect();
    let img = GrayImage::from_vec(w, h, data).expect("image");
    let bytes = w * h * 4;

    let mut dst = vec![0f32; w * h];
    let memcpy = measure(|| {
        dst.copy_from_slice(std::hint::black_box(&img.data));
        std::hint::black_box(&dst);
    });
    let memcpy_new = measure(|| {
        std::hint::black_box(std::hint::black_box(&img.data).clone());
    });
    let mut reused = Vec::with_capacity(bytes + 64);
    img.encode(&mut reused);
    let encode_reused = measure(|| {
        reused.clear();
        img.encode(&mut reused);
        std::hint::black_box(&reused);
    });
    let encode = measure(|| {
        let mut out = Vec::new();
        img.encode(&mut out);
        std::hint::black_box(out);
    });
    let decode = measure(|| {
        std::hint::black_box(GrayImage::decode(&reused).expect("decode"));
    });

    let dir = tempfile::tempdir().expect("temp dir");
    let store = Store::open(dir.path()).expect("store");
    let key = KeyBuilder::new("bench", 1).finish();
    let meta = EntryMeta::new("bench", "1", "image 4000x3000");
    let save = measure(|| {
        let mut buf = Vec::new();
        img.encode(&mut buf);
        store.save(&key, &meta, &buf).expect("save");
    });
    let load = measure(|| match store.load(&key).expect("load") {
        Lookup::Hit(e) => {
            std::hint::black_box(GrayImage::decode(&e.payload).expect("decode"));
        }
        other => panic!("expected a hit, got {other:?}"),
    });
    let save_load = (save.0 + load.0, save.1 + load.1);

    println!(
        "{:<58} {:>10} {:>10} {:>12}",
        "48 MB GrayImage 4000x3000", "wall GB/s", "CPU GB/s", "CPU vs memcpy"
    );
    let row = |name: &str, (wall, cpu): (Duration, Duration)| {
        println!(
            "{:<58} {:>10.2} {:>10.2} {:>11.2}×",
            name,
            gbps(bytes, wall),
            gbps(bytes, cpu),
            cpu.as_secs_f64() / memcpy_new.1.as_secs_f64().max(1e-9)
        );
    };
    row("memcpy into a pre-allocated buffer", memcpy);
    row("memcpy into a fresh Vec (page faults included)", memcpy_new);
    row("codec encode into a reused buffer", encode_reused);
    row("codec encode into a fresh Vec", encode);
    row("codec decode (fresh Vec)", decode);
    row("Store save (encode+hash+write+fsync+rename)", save);
    row("Store load (read+verify hash+decode)", load);
    row("Store save + load", save_load);
    println!(
        "save wall {:.1} ms vs CPU {:.1} ms (the difference is fsync and waiting for a core); load wall {:.1} ms, CPU {:.1} ms",
        save.0.as_secs_f64() * 1e3,
        save.1.as_secs_f64() * 1e3,
        load.0.as_secs_f64() * 1e3,
        load.1.as_secs_f64() * 1e3
    );
}
