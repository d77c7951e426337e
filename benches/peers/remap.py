#!/usr/bin/env python3
"""Peer comparison of skytie's ortho-projection sampling with `cv2.remap` using the SAME map (thesis 3.4.3).

Setup (never part of the test path; see benches/README.md):
    python3 -m venv /tmp/peers && /tmp/peers/bin/pip install opencv-contrib-python-headless numpy
    cargo bench -p skytie-stages --bench ortho              # writes <temp>/skytie_peers/ortho/
    /tmp/peers/bin/python benches/peers/remap.py [<temp>/skytie_peers/ortho]

The Rust bench writes `panorama.png` (8-bit), per GSD the float32 maps `map_{gsd}cm_{u,v}.npy` (campaign pixel
convention, pixel centres at +0.5; NaN where the vehicle hides the ground), skytie's output `ortho_{gsd}cm.npy`
and its timings `skytie_{gsd}cm.csv`. Here the panorama gets one wrapped column on each side (as skytie does for
the ±180° seam), the map is converted to OpenCV's convention (x = u − 0.5 + 1 for the padding, y = v − 0.5),
masked pixels are sent outside the image, and `cv2.remap(INTER_LINEAR, BORDER_REPLICATE)` is timed (median wall
time, 1 thread and the default thread count). Prints the max difference to skytie's output on valid pixels and
the ratios skytie / OpenCV for the full `ortho_project` (which also computes the map) and for skytie's `remap`
given the same map; and, for the whole job, `ortho_project` against the map computed with NumPy from
`geometry_{gsd}cm.json` followed by `cv2.remap`.
"""
import csv
import glob
import os
import sys
import tempfile
import time

import cv2
import json
import numpy as np


def median_ms(fn, reps):
    t = []
    for _ in range(reps):
        t0 = time.perf_counter()
        fn()
        t.append((time.perf_counter() - t0) * 1e3)
    return float(np.median(t))


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


def main(folder):
    pano8 = cv2.imread(os.path.join(folder, "panorama.png"), cv2.IMREAD_GRAYSCALE)
    if pano8 is None:
        sys.exit(f"no panorama.png in {folder}: run the Rust bench first (see the docstring)")
    pano = pano8.astype(np.float32) / 255.0
    padded = np.ascontiguousarray(np.hstack([pano[:, -1:], pano, pano[:, :1]]))
    print(f"{'GSD':>5} | {'ortho px':>9} | {'threads':>7} | {'cv2.remap ms':>12} | {'skytie remap ms':>15} | "
          f"{'ortho_project ms':>16} | {'remap/cv2':>9} | {'ortho/cv2':>9}")
    print("-" * 104)
    for u_path in sorted(glob.glob(os.path.join(folder, "map_*cm_u.npy"))):
        tag = os.path.basename(u_path)[len("map_"):-len("_u.npy")]
        mu = np.load(u_path)
        mv = np.load(os.path.join(folder, f"map_{tag}_v.npy"))
        ours = np.load(os.path.join(folder, f"ortho_{tag}.npy"))
        valid = ~np.isnan(mu)
        w = pano.shape[1]
        map_x = np.where(valid, np.mod(mu, w) - 0.5 + 1.0, -10.0).astype(np.float32)
        map_y = np.where(valid, mv - 0.5, -10.0).astype(np.float32)
        out = cv2.remap(padded, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        diff = float(np.abs(out[valid] - ours[valid]).max()) if valid.any() else 0.0
        sky = {}
        for r in csv.DictReader(open(os.path.join(folder, f"skytie_{tag}.csv"))):
            sky[(r["method"], int(r["threads"]))] = float(r["ms"])
        reps = 30 if mu.size > 100_000 else 200
        geometry = json.load(open(os.path.join(folder, f"geometry_{tag}.json")))
        nx, ny = numpy_map(geometry)
        map_err = float(np.abs(nx[valid] - map_x[valid]).max()) if valid.any() else 0.0
        full = {}
        for threads in sorted({t for _, t in sky}):
            cv2.setNumThreads(threads)
            ms = median_ms(lambda: cv2.remap(padded, map_x, map_y, cv2.INTER_LINEAR,
                                             borderMode=cv2.BORDER_REPLICATE), reps)
            full[threads] = median_ms(lambda: cv2.remap(padded, *numpy_map(geometry), cv2.INTER_LINEAR,
                                                        borderMode=cv2.BORDER_REPLICATE), max(reps // 4, 8))
            s_remap = sky[("skytie remap (same map)", threads)]
            s_ortho = sky[("skytie ortho_project", threads)]
            print(f"{tag:>5} | {mu.shape[1]:>4}x{mu.shape[0]:<4} | {threads:>7} | {ms:>12.3f} | {s_remap:>15.3f} | "
                  f"{s_ortho:>16.3f} | {s_remap / ms:>8.2f}x | {s_ortho / ms:>8.2f}x")
        print(f"{tag:>5} | max |cv2.remap − skytie ortho| on {int(valid.sum())} valid px: {diff:.2e}")
        for threads, ms in full.items():
            s_ortho = sky[("skytie ortho_project", threads)]
            print(f"{tag:>5} | whole job, {threads} thread(s): NumPy map + cv2.remap {ms:.3f} ms (NumPy single-threaded), "
                  f"skytie ortho_project {s_ortho:.3f} ms: {s_ortho / ms:.2f}x (NumPy map vs skytie's: max "
                  f"{map_err:.1e} px)")


if __name__ == "__main__":
    default = os.path.join(tempfile.gettempdir(), "skytie_peers", "ortho")
    main(sys.argv[1] if len(sys.argv) > 1 else default)
