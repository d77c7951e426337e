#!/usr/bin/env python3
"""Peer comparison of skytie's phase correlation with OpenCV and scikit-image on identical PNG pairs.

Setup (never part of the test path):
    python3 -m venv /tmp/peers && /tmp/peers/bin/pip install opencv-python-headless scikit-image numpy
    SKYTIE_PEER_DIR=/tmp/pc_pairs cargo bench -p skytie-stages --bench imaging
    /tmp/peers/bin/python benches/peers/phasecorr.py /tmp/pc_pairs

The bench writes `pc{size}_{k}_ref.png` / `_mov.png` (moving = reference translated by +t, an exact Fourier
shift of a band-limited texture, then gain/offset/gamma and noise) and `truth_{size}.csv` with t and skytie's
estimate on the same 8-bit PNGs. Conventions: OpenCV `phaseCorrelate` returns +t as (x, y); skimage
`phase_cross_correlation` returns the shift registering moving onto reference, i.e. -t as (row, col).
Prints RMS error (px) and mean time per call (ms) per method and size.
"""
import csv
import glob
import os
import sys
import time

import cv2
import numpy as np
from skimage.registration import phase_cross_correlation


def load(path):
    return cv2.imread(path, cv2.IMREAD_GRAYSCALE).astype(np.float64) / 255.0


def main(folder):
    for truth_path in sorted(glob.glob(os.path.join(folder, "truth_*.csv"))):
        rows = list(csv.DictReader(open(truth_path)))
        errors = {"skytie": [], "opencv (hann)": [], "skimage (upsample 100)": []}
        times = {"opencv (hann)": 0.0, "skimage (upsample 100)": 0.0}
        for row in rows:
            a = load(os.path.join(folder, row["reference"]))
            b = load(os.path.join(folder, row["moving"]))
            tx, ty = float(row["tx_px"]), float(row["ty_px"])
            errors["skytie"].append(np.hypot(float(row["skytie_dx_px"]) - tx, float(row["skytie_dy_px"]) - ty))
            win = cv2.createHanningWindow(a.shape[::-1], cv2.CV_64F)
            t0 = time.perf_counter()
            (dx, dy), _ = cv2.phaseCorrelate(a, b, win)
            times["opencv (hann)"] += time.perf_counter() - t0
            errors["opencv (hann)"].append(np.hypot(dx - tx, dy - ty))
            t0 = time.perf_counter()
            shift, _, _ = phase_cross_correlation(a, b, upsample_factor=100)
            times["skimage (upsample 100)"] += time.perf_counter() - t0
            errors["skimage (upsample 100)"].append(np.hypot(-shift[1] - tx, -shift[0] - ty))
        size = os.path.basename(truth_path)[len("truth_"):-len(".csv")]
        for name, errs in errors.items():
            rms = float(np.sqrt(np.mean(np.square(errs))))
            t = times.get(name)
            t_txt = f"{1e3 * t / len(rows):.3f} ms/call" if t is not None else "(time: see the Rust bench)"
            print(f"{size}x{size} {name:>24}: RMS error {rms:.4f} px over {len(rows)} pairs, {t_txt}")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "/tmp/pc_pairs")
