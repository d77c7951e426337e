#!/usr/bin/env python3
"""Peer comparison of skytie's ortho-projection sampling with `cv2.remap` using the SAME map (thesis 3.4.3).

Setup (never part of the test path; see benches/README.md):
    python3 -m venv /tmp/peers && /tmp/peers/bin/pip install opencv-contrib-python-headless numpy
    /tmp/peers/bin/python benches/peers/remap.py [--rounds N] [<temp>/skytie_peers/ortho]

Each of the N rounds (default 5) first runs the Rust bench (`cargo bench -p skytie-stages --bench ortho` from
this repository; `--rounds 0` skips it and uses the files already there, one round) and then times OpenCV right
after it, so every ratio compares two measurements taken seconds apart; the summary gives the median ratio over
the rounds and its range (the machines are shared and noisy: absolute times swing by ±50 %, paired ratios less).

The Rust bench writes `panorama.png` (8-bit) and the float32 values it decoded from it (`panorama.npy`, used
here so that both sides sample identical floats), per GSD the float32 maps `map_{gsd}cm_{u,v}.npy` (campaign pixel
convention, pixel centres at +0.5; NaN where the vehicle hides the ground), skytie's output `ortho_{gsd}cm.npy`
and its timings `skytie_{gsd}cm.csv`. Here the panorama gets one wrapped column on each side (as the Rust bench
does for skytie's `remap_with_map`), the map is converted to OpenCV's convention (x = u − 0.5 + 1 for the
padding, y = v − 0.5), masked pixels are sent outside the image, and `cv2.remap(INTER_LINEAR, BORDER_REPLICATE)`
is timed: median over repetitions, thread CPU time with 1 thread (`time.thread_time_ns`, the clock the Rust side
uses), wall time with the default thread count. Prints the max difference to skytie's output on valid pixels and
the ratios skytie / OpenCV for skytie's `remap_with_map` given the same map and for the full `ortho_project`
(which also computes the map); and, for the whole job, `ortho_project` against the map computed with NumPy from
`geometry_{gsd}cm.json` followed by `cv2.remap`. Accuracy: both `cv2.remap` and skytie's `remap_with_map`
(`remap_{gsd}cm.npy`) against float64 bilinear interpolation on the same map.
"""
import argparse
import csv
import glob
import os
import sys
import tempfile
import time

import cv2
import json
import numpy as np
from rust_bench import run_rust_bench


def median_ms(fn, reps, cpu_time=False):
    """Median time of `fn` in ms: thread CPU time (single-threaded peers) or wall time."""
    clock = time.thread_time if cpu_time else time.perf_counter
    t = []
    for _ in range(reps):
        t0 = clock()
        fn()
        t.append((clock() - t0) * 1e3)
    return float(np.median(t))


def bilinear_reference(img, x, y):
    """Bilinear interpolation in float64 at OpenCV-convention positions (x, y) (pixel centres at integers), all
    inside: the exact value both samplers approximate (OpenCV rounds the fractions to 1/32 px, INTER_BITS = 5)."""
    img = img.astype(np.float64)
    x0, y0 = np.floor(x).astype(np.int64), np.floor(y).astype(np.int64)
    fx, fy = x - x0, y - y0
    top = img[y0, x0] + (img[y0, x0 + 1] - img[y0, x0]) * fx
    bottom = img[y0 + 1, x0] + (img[y0 + 1, x0 + 1] - img[y0 + 1, x0]) * fx
    return top + (bottom - top) * fy


def numpy_map(g):
    """The ortho → panorama map computed with NumPy from the exported geometry (no vehicle mask: less work than
    skytie's `ortho_project`, which also masks the car), in OpenCV's convention with the seam padding."""
    w, h, gsd = g["width_px"], g["height_px"], g["gsd_m"]
    a = (np.arange(w) + 0.5 - w / 2.0) * gsd
    b = (h / 2.0 - np.arange(h) - 0.5) * gsd
    fo, right, up = g["foot_offset_m"], g["right"], g["up"]
    dx = fo[0] + a[None, :] * right[0] + b[:, None] * up[0]
    dy = fo[1] + a[None, :] * right[1] + b[:, None] * up[1]
    dz = np.full((h, w), fo[2])
    r = np.array(g["rotation_pano_to_world"]).reshape(3, 3)
    px = r[0, 0] * dx + r[1, 0] * dy + r[2, 0] * dz  # Rᵀ·d
    py = r[0, 1] * dx + r[1, 1] * dy + r[2, 1] * dz
    pz = r[0, 2] * dx + r[1, 2] * dy + r[2, 2] * dz
    pw, ph = g["panorama_width_px"], g["panorama_height_px"]
    u = (np.arctan2(px, py) + np.pi) * (pw / (2 * np.pi))
    v = (np.pi / 2 - np.arctan2(pz, np.hypot(px, py))) * (ph / np.pi)
    return (np.mod(u, pw) - 0.5 + 1.0).astype(np.float32), (v - 0.5).astype(np.float32)


def one_round(folder, rows, whole_job):
    """Time cv2.remap (and, in the first round, the whole NumPy + OpenCV job) against the Rust timings now in
    `folder`; append (tag, threads, cv2 ms, skytie remap ms, skytie ortho ms) to `rows`."""
    npy = os.path.join(folder, "panorama.npy")
    if not os.path.exists(npy):
        sys.exit(f"no panorama.npy in {folder}: run the Rust bench first (see the docstring)")
    pano = np.load(npy)  # the float32 grey values skytie decoded from panorama.png
    padded = np.ascontiguousarray(np.hstack([pano[:, -1:], pano, pano[:, :1]]))
    for u_path in sorted(glob.glob(os.path.join(folder, "map_*cm_u.npy"))):
        tag = os.path.basename(u_path)[len("map_"):-len("_u.npy")]
        mu = np.load(u_path)
        mv = np.load(os.path.join(folder, f"map_{tag}_v.npy"))
        ours = np.load(os.path.join(folder, f"ortho_{tag}.npy"))
        valid = ~np.isnan(mu)
        w = pano.shape[1]
        # (u mod w + 1) − 0.5 in float32, the operations and rounding of the Rust bench's map (+1: the padding).
        map_x = np.where(valid, (np.mod(mu, w) + np.float32(1.0)) - np.float32(0.5), -10.0).astype(np.float32)
        map_y = np.where(valid, mv - 0.5, -10.0).astype(np.float32)
        sky = {}
        for r in csv.DictReader(open(os.path.join(folder, f"skytie_{tag}.csv"))):
            sky[(r["method"], int(r["threads"]))] = float(r["ms"])
        reps = 30 if mu.size > 100_000 else 200
        for threads in sorted({t for _, t in sky}):
            cv2.setNumThreads(threads)
            remap = lambda: cv2.remap(padded, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
            ms = median_ms(remap, reps, cpu_time=threads == 1)
            rows.append((tag, threads, ms, sky[("skytie remap (same map)", threads)],
                         sky[("skytie ortho_project", threads)]))
        if tag in whole_job:
            continue
        out = cv2.remap(padded, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        diff = float(np.abs(out[valid] - ours[valid]).max()) if valid.any() else 0.0
        # Accuracy on the same f32 map against float64 bilinear interpolation, where all four neighbours are inside.
        inner = valid & (map_y >= 0) & (map_y < padded.shape[0] - 1)
        ref = bilinear_reference(padded, map_x[inner].astype(np.float64), map_y[inner].astype(np.float64))
        sky_remap = np.load(os.path.join(folder, f"remap_{tag}.npy"))
        accuracy = {name: (float(np.abs(v[inner] - ref).max()), float(np.sqrt(np.mean((v[inner] - ref) ** 2))))
                    for name, v in (("cv2.remap", out), ("skytie remap_with_map", sky_remap))}
        geometry = json.load(open(os.path.join(folder, f"geometry_{tag}.json")))
        nx, _ = numpy_map(geometry)
        map_err = float(np.abs(nx[valid] - map_x[valid]).max()) if valid.any() else 0.0
        full = {}
        for threads in sorted({t for _, t in sky}):
            cv2.setNumThreads(threads)
            full[threads] = (median_ms(lambda: cv2.remap(padded, *numpy_map(geometry), cv2.INTER_LINEAR,
                                                         borderMode=cv2.BORDER_REPLICATE), max(reps // 4, 8)),
                             sky[("skytie ortho_project", threads)])
        whole_job[tag] = (mu.shape, int(valid.sum()), diff, map_err, full, accuracy)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    parser.add_argument("--rounds", type=int, default=5,
                        help="Rust bench + OpenCV rounds (0: use the files already in FOLDER, one round)")
    parser.add_argument("folder", nargs="?", default=os.path.join(tempfile.gettempdir(), "skytie_peers", "ortho"))
    args = parser.parse_args()
    rows, whole_job = [], {}
    for k in range(max(args.rounds, 1)):
        if args.rounds > 0:
            run_rust_bench("ortho", args.folder)
        one_round(args.folder, rows, whole_job)
    print(f"{'round':>5} | {'GSD':>5} | {'threads':>7} | {'cv2.remap ms':>12} | {'skytie remap ms':>15} | "
          f"{'ortho_project ms':>16} | {'remap/cv2':>9} | {'ortho/cv2':>9}")
    print("-" * 104)
    per_key = {}
    n_keys = len({(t, th) for t, th, *_ in rows})
    for i, (tag, threads, ms, s_remap, s_ortho) in enumerate(rows):
        print(f"{i // n_keys + 1:>5} | {tag:>5} | {threads:>7} | {ms:>12.3f} | {s_remap:>15.3f} | {s_ortho:>16.3f} | "
              f"{s_remap / ms:>8.2f}x | {s_ortho / ms:>8.2f}x")
        per_key.setdefault((tag, threads), []).append((s_remap / ms, s_ortho / ms))
    print(f"\nmedian (min–max) over {max(args.rounds, 1)} round(s), 1 thread in thread CPU time, more in wall time:")
    for (tag, threads), ratios in sorted(per_key.items()):
        r = np.array(ratios)
        print(f"{tag:>5} | {threads} thread(s) | remap_with_map / cv2.remap {np.median(r[:, 0]):.2f}x "
              f"({r[:, 0].min():.2f}–{r[:, 0].max():.2f}) | ortho_project / cv2.remap {np.median(r[:, 1]):.2f}x "
              f"({r[:, 1].min():.2f}–{r[:, 1].max():.2f})")
    for tag, (shape, n_valid, diff, map_err, full, accuracy) in sorted(whole_job.items()):
        print(f"{tag:>5} | {shape[1]}x{shape[0]} px | max |cv2.remap − skytie ortho| on {n_valid} valid px: {diff:.2e}")
        for name, (worst, rms) in accuracy.items():
            print(f"{tag:>5} | {name} vs float64 bilinear on the same map (image range 0..1): max {worst:.2e}, "
                  f"RMS {rms:.2e}")
        for threads, (ms, s_ortho) in full.items():
            print(f"{tag:>5} | whole job (first round), {threads} thread(s): NumPy map + cv2.remap {ms:.3f} ms "
                  f"(NumPy single-threaded), skytie ortho_project {s_ortho:.3f} ms: {s_ortho / ms:.2f}x "
                  f"(NumPy map vs skytie's: max {map_err:.1e} px)")


if __name__ == "__main__":
    main()
