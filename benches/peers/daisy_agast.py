#!/usr/bin/env python3
"""Peer comparison of skytie's AGAST (OAST 9-16) and DAISY with OpenCV's on IDENTICAL 8-bit PNGs: time, AGAST
keypoint agreement, and DAISY descriptor agreement at the same points.

Setup (never part of the test path; see benches/README.md):
    python3 -m venv /tmp/peers && /tmp/peers/bin/pip install opencv-contrib-python-headless numpy
    cargo bench -p skytie-stages --bench daisy_agast        # writes <temp>/skytie_peers/daisy_agast/
    /tmp/peers/bin/python benches/peers/daisy_agast.py [<temp>/skytie_peers/daisy_agast]

OpenCV: `AgastFeatureDetector_create(threshold, nonmaxSuppression, OAST_9_16)` (module `cv2.xfeatures2d` in
opencv-contrib 5.x, `cv2` in 4.x) and `cv2.xfeatures2d.DAISY_create(radius, q_radius, q_theta, q_hist,
NRM_PARTIAL)` with the values of params.csv (OpenCV defaults apart from the normalisation, which is the
pipeline's), computed at skytie's described points (the same points for both sides). OpenCV's pixel centres are
at integers, skytie's at +0.5: OpenCV positions are shifted by +0.5 before comparing, and skytie's points by
-0.5 before OpenCV describes them.

AGAST agreement: with NMS, the share of skytie's corners with an OpenCV corner at the same pixel (and within
1.5 px), and vice versa; the two resolve equal scores among neighbours differently (skytie by the strength, see
features/agast.rs), so some tied pixels differ. Without NMS both are the plain segment test: the sets should be
equal. DAISY agreement: cosine similarity of the two descriptors of each point (1 = identical direction).
Timing: median over rounds of the thread CPU time with 1 OpenCV thread (skytie: 1-thread pool, thread CPU time).
"""
import csv
import os
import sys
import tempfile
import time

import cv2
import numpy as np


def mod_with(name):
    x = getattr(cv2, "xfeatures2d", None)
    if x is not None and hasattr(x, name):
        return x
    if hasattr(cv2, name):
        return cv2
    sys.exit(f"OpenCV {cv2.__version__} has no {name}: install opencv-contrib-python-headless")


def agast_create(threshold, nms):
    m = mod_with("AgastFeatureDetector_create")
    oast = getattr(m, "AgastFeatureDetector_OAST_9_16", getattr(m, "AGAST_FEATURE_DETECTOR_OAST_9_16", 3))
    return m.AgastFeatureDetector_create(threshold=threshold, nonmaxSuppression=nms, type=oast)


def daisy_create(p):
    m = mod_with("DAISY_create")
    return m.DAISY_create(radius=p["radius"], q_radius=p["q_radius"], q_theta=p["q_theta"], q_hist=p["q_hist"],
                          norm=m.DAISY_NRM_PARTIAL)


def median_ms(call, rounds):
    samples = []
    for _ in range(rounds):
        t0 = time.thread_time_ns()
        call()
        samples.append((time.thread_time_ns() - t0) * 1e-6)
    return float(np.median(samples))


def read_xy(path):
    rows = list(csv.DictReader(open(path)))
    return np.array([[float(r["x"]), float(r["y"])] for r in rows], dtype=np.float64).reshape(-1, 2)


def share_within(src, dst, radius):
    """Share of src points with a dst point within radius (grid hashing on integer pixel cells)."""
    if len(src) == 0 or len(dst) == 0:
        return 0.0
    cells = {}
    for i, (x, y) in enumerate(dst):
        cells.setdefault((int(x // 2), int(y // 2)), []).append(i)
    hit = 0
    for x, y in src:
        cx, cy = int(x // 2), int(y // 2)
        found = False
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for j in cells.get((cx + dx, cy + dy), ()):
                    if (dst[j, 0] - x) ** 2 + (dst[j, 1] - y) ** 2 <= radius * radius:
                        found = True
                        break
                if found:
                    break
            if found:
                break
        hit += found
    return hit / len(src)


def main(folder):
    cv2.setNumThreads(1)
    pfile = os.path.join(folder, "params.csv")
    if not os.path.exists(pfile):
        sys.exit(f"no params.csv in {folder}: run the Rust bench first (see the docstring)")
    raw = next(csv.DictReader(open(pfile)))
    p = {"threshold": int(float(raw["threshold"])), "radius": float(raw["radius"]), "q_radius": int(raw["q_radius"]),
         "q_theta": int(raw["q_theta"]), "q_hist": int(raw["q_hist"])}
    sky = list(csv.DictReader(open(os.path.join(folder, "skytie.csv"))))
    print(f"OpenCV {cv2.__version__}, 1 thread, thread CPU ms; AGAST OAST 9-16 threshold {p['threshold']}; DAISY R "
          f"{p['radius']:g} Q {p['q_radius']} T {p['q_theta']} H {p['q_hist']} partial")
    print(f"{'image':<6} | {'step':<16} | {'skytie ms':>9} | {'OpenCV ms':>9} | {'skytie/peer':>11} | "
          f"{'skytie n':>8} | {'OpenCV n':>8} | agreement")
    print("-" * 140)
    for s in sky:
        name = s["image"]
        img = cv2.imread(os.path.join(folder, f"{name}.png"), cv2.IMREAD_GRAYSCALE)
        if img is None:
            sys.exit(f"cannot read {name}.png in {folder}: run the Rust bench first")
        for nms, key_ms, key_n, suffix in ((True, "agast_ms", "corners_nms", "nms"),
                                           (False, "agast_all_ms", "corners_all", "all")):
            det = agast_create(p["threshold"], nms)
            kps = det.detect(img)
            cv_pts = np.array([[k.pt[0] + 0.5, k.pt[1] + 0.5] for k in kps]).reshape(-1, 2)
            ms = median_ms(lambda: det.detect(img), 21)
            sky_pts = read_xy(os.path.join(folder, f"skytie_agast_{name}_{suffix}.csv"))
            same_s = share_within(sky_pts, cv_pts, 0.01)
            same_c = share_within(cv_pts, sky_pts, 0.01)
            near_s = share_within(sky_pts, cv_pts, 1.5)
            near_c = share_within(cv_pts, sky_pts, 1.5)
            sky_ms = float(s[key_ms])
            print(f"{name:<6} | {'AGAST ' + ('NMS' if nms else 'no NMS'):<16} | {sky_ms:>9.2f} | {ms:>9.2f} | "
                  f"{sky_ms / ms:>10.2f}x | {int(s[key_n]):>8} | {len(cv_pts):>8} | same pixel {100 * same_s:.1f} % "
                  f"of skytie's / {100 * same_c:.1f} % of OpenCV's; within 1.5 px {100 * near_s:.1f} % / "
                  f"{100 * near_c:.1f} %")

        pts = read_xy(os.path.join(folder, f"skytie_daisy_{name}.csv"))
        sky_desc = np.load(os.path.join(folder, f"skytie_daisy_{name}.npy"))
        kps = [cv2.KeyPoint(float(x - 0.5), float(y - 0.5), 1.0) for x, y in pts]
        daisy = daisy_create(p)
        kps_out, cv_desc = daisy.compute(img, kps)
        ms = median_ms(lambda: daisy.compute(img, kps), 5)
        if cv_desc is None or len(kps_out) != len(kps):
            agreement = f"OpenCV returned {0 if cv_desc is None else len(kps_out)} of {len(kps)} descriptors"
        else:
            num = np.sum(sky_desc * cv_desc, axis=1)
            den = np.linalg.norm(sky_desc, axis=1) * np.linalg.norm(cv_desc, axis=1)
            cos = num / np.maximum(den, 1e-30)
            agreement = (f"cosine median {np.median(cos):.4f}, 5th percentile {np.percentile(cos, 5):.4f}, "
                         f"max |diff| median {np.median(np.abs(sky_desc - cv_desc).max(axis=1)):.4f}")
        sky_ms = float(s["daisy_ms"])
        print(f"{name:<6} | {'DAISY (+ layers)':<16} | {sky_ms:>9.1f} | {ms:>9.1f} | {sky_ms / ms:>10.2f}x | "
              f"{int(s['described']):>8} | {len(kps):>8} | {agreement}")


if __name__ == "__main__":
    default = os.path.join(tempfile.gettempdir(), "skytie_peers", "daisy_agast")
    main(sys.argv[1] if len(sys.argv) > 1 else default)
