#!/usr/bin/env python3
"""Peer comparison of skytie's KAZE with OpenCV's (`cv2.xfeatures2d.KAZE_create` in opencv-contrib 5.x,
`cv2.KAZE_create` in 4.x) on IDENTICAL 8-bit PNGs: time, repeatability under an integer shift, and keypoint
agreement with skytie on the same image.

Setup (never part of the test path; see benches/README.md):
    python3 -m venv /tmp/peers && /tmp/peers/bin/pip install opencv-contrib-python-headless numpy
    cargo bench -p skytie-stages --bench kaze               # writes <temp>/skytie_peers/kaze/
    /tmp/peers/bin/python benches/peers/kaze.py [<temp>/skytie_peers/kaze]

Setting as skytie's bench (thesis 3.4.5.2): threshold 0.001, 1 octave, 4 sublevels, PM G2 diffusivity, upright,
extended. Times: one untimed warm-up call, then the median of 5 calls (wall and process CPU), as the Rust
bench does. Repeatability: share of A's keypoints whose position minus the shift lies >= border px inside B that
have a B keypoint within match_radius px (values from shift.csv, the rule skytie's bench applies). Agreement:
share of skytie's keypoints on A with an OpenCV keypoint within 1.5 px, and vice versa. OpenCV's pixel centres
are at integers, skytie's at +0.5: OpenCV positions are shifted by +0.5 before comparing.
"""
import csv
import os
import sys
import tempfile
import time

import cv2
import numpy as np


def kaze_create():
    mod = cv2.xfeatures2d if hasattr(cv2, "xfeatures2d") and hasattr(cv2.xfeatures2d, "KAZE_create") else cv2
    return mod.KAZE_create(extended=True, upright=True, threshold=0.001, nOctaves=1, nOctaveLayers=4,
                           diffusivity=getattr(mod, "KAZE_DIFF_PM_G2", getattr(cv2, "KAZE_DIFF_PM_G2", 1)))


RUNS = 5


def detect(img, threads, runs=RUNS):
    """Keypoints of img and the median wall / process CPU time of `runs` timed calls after one untimed warm-up
    (as skytie's bench: first-touch allocation and lazy initialisation are not timed on either side)."""
    cv2.setNumThreads(threads)
    kaze = kaze_create()
    kps, _ = kaze.detectAndCompute(img, None)
    walls, cpus = [], []
    for _ in range(runs):
        c0, w0 = time.process_time(), time.perf_counter()
        kps, desc = kaze.detectAndCompute(img, None)
        walls.append(time.perf_counter() - w0)
        cpus.append(time.process_time() - c0)
    pts = np.array([[k.pt[0] + 0.5, k.pt[1] + 0.5] for k in kps], dtype=np.float64).reshape(-1, 2)
    med = lambda v: float(np.median(v)) if v else float("nan")
    return pts, med(walls), med(cpus)


def read_points(path):
    rows = list(csv.DictReader(open(path)))
    return np.array([[float(r["u_px"]), float(r["v_px"])] for r in rows], dtype=np.float64).reshape(-1, 2)


def share_with_neighbour(src, dst, radius):
    """Share of src points with a dst point within radius (brute force in chunks)."""
    if len(src) == 0:
        return 0.0
    if len(dst) == 0:
        return 0.0
    hit = 0
    for chunk in np.array_split(src, max(1, len(src) // 512)):
        d2 = ((chunk[:, None, :] - dst[None, :, :]) ** 2).sum(axis=2)
        hit += int((d2.min(axis=1) <= radius * radius).sum())
    return hit / len(src)


def repeatability(a, b, shift, border, radius, size):
    moved = a - shift
    inside = np.all((moved >= border) & (moved <= size - border), axis=1)
    return share_with_neighbour(moved[inside], b, radius), int(inside.sum())


def main(folder):
    img_a = cv2.imread(os.path.join(folder, "kaze_a.png"), cv2.IMREAD_GRAYSCALE)
    img_b = cv2.imread(os.path.join(folder, "kaze_b.png"), cv2.IMREAD_GRAYSCALE)
    if img_a is None or img_b is None:
        sys.exit(f"no kaze_a.png / kaze_b.png in {folder}: run the Rust bench first (see the docstring)")
    size = img_a.shape[1]
    meta = next(csv.DictReader(open(os.path.join(folder, "shift.csv"))))
    shift = np.array([float(meta["shift_x_px"]), float(meta["shift_y_px"])])
    border, radius = float(meta["border_px"]), float(meta["match_radius_px"])
    sky = list(csv.DictReader(open(os.path.join(folder, "skytie_kaze.csv"))))
    sky_a = read_points(os.path.join(folder, "skytie_keypoints_a.csv"))

    print(f"{'method':<34} | {'threads':>7} | {'wall s':>7} | {'CPU s':>6} | {'keypoints':>9} | {'repeat.':>7} "
          f"| {'skytie/peer wall':>16}")
    print("-" * 105)
    cv_results = {}
    for threads in (1, os.cpu_count() or 1):
        pa, wall, cpu = detect(img_a, threads)
        pb, _, _ = detect(img_b, threads, runs=0)
        rep, _ = repeatability(pa, pb, shift, border, radius, size)
        cv_results[threads] = (pa, wall, cpu, rep)
    for row in sky:
        t = int(row["threads"])
        peer_wall = cv_results.get(t, cv_results[1])[1]
        print(f"{'skytie KAZE ' + row['scheme']:<34} | {t:>7} | {float(row['wall_s']):>7.3f} | "
              f"{row['cpu_s']:>6} | {row['keypoints_a']:>9} | {100 * float(row['repeatability']):>6.1f}% | "
              f"{float(row['wall_s']) / peer_wall:>15.2f}x")
    for t, (pa, wall, cpu, rep) in cv_results.items():
        print(f"{'OpenCV KAZE (PM G2, AOS)':<34} | {t:>7} | {wall:>7.3f} | {cpu:>6.2f} | {len(pa):>9} | "
              f"{100 * rep:>6.1f}% |")
    pa = cv_results[1][0]
    print(f"agreement on image A: {100 * share_with_neighbour(sky_a, pa, 1.5):.1f} % of skytie's keypoints have an "
          f"OpenCV keypoint within 1.5 px; {100 * share_with_neighbour(pa, sky_a, 1.5):.1f} % vice versa")


if __name__ == "__main__":
    default = os.path.join(tempfile.gettempdir(), "skytie_peers", "kaze")
    main(sys.argv[1] if len(sys.argv) > 1 else default)
