#!/usr/bin/env python3
"""Peer comparison of skytie's phase correlation with OpenCV and scikit-image on IDENTICAL 8-bit PNG pairs.

Setup (never part of the test path; see benches/README.md):
    python3 -m venv /tmp/peers && /tmp/peers/bin/pip install opencv-contrib-python-headless scikit-image numpy
    /tmp/peers/bin/python benches/peers/phasecorr.py [--rounds N] [<temp>/skytie_peers/phasecorr]

Each of the N rounds (default 5) runs the Rust bench (`cargo bench -p skytie-stages --bench phasecorr`, which
writes <temp>/skytie_peers/phasecorr/) and then times `cv2.phaseCorrelate` with a Hann window right after it;
the summary gives the median (min–max) of the paired ratios skytie / cv2. The full table (all peers, errors)
is printed for the first round. `--rounds 0` uses the files already in the folder (one round, no cargo).

The bench writes `pc{size}_{k}_ref.png` / `_mov.png` (moving = reference translated by +t, an exact Fourier
shift of a band-limited texture, then gain/offset/gamma and noise), `truth_{size}.csv` (t and skytie's estimate
on the same PNGs) and `skytie_{size}.csv` (skytie's time per call, thread CPU time). Conventions: OpenCV
`phaseCorrelate` returns +t as (x, y); skimage `phase_cross_correlation` returns the shift registering moving
onto reference, i.e. -t as (row, col). Peers are timed the same way (median over rounds of the mean thread CPU
time per call, 1 OpenCV thread), inputs converted to float64 beforehand. Prints RMS error (px), ms per call and
the ratio skytie / peer of the times.
"""
import argparse
import csv
import glob
import os
import sys
import tempfile
import time

import cv2
import numpy as np
from skimage.registration import phase_cross_correlation

from rust_bench import run_rust_bench


def load(path):
    img = cv2.imread(path, cv2.IMREAD_GRAYSCALE)
    if img is None:
        sys.exit(f"cannot read {path}: run the Rust bench first (see the docstring)")
    return img.astype(np.float64) / 255.0


def median_ms_per_call(pairs, call, rounds):
    """Median over rounds of the mean thread CPU time per call, in ms."""
    samples = []
    for _ in range(rounds):
        t0 = time.thread_time_ns()
        for a, b in pairs:
            call(a, b)
        samples.append((time.thread_time_ns() - t0) * 1e-6 / len(pairs))
    return float(np.median(samples))


def one_round(folder, all_peers):
    """Rows (size, method, RMS error px, ms per call, skytie / peer) for the files now in `folder`; with
    `all_peers` False only skytie and cv2.phaseCorrelate (hann)."""
    cv2.setNumThreads(1)
    rows_out = []
    for truth_path in sorted(glob.glob(os.path.join(folder, "truth_*.csv")),
                             key=lambda p: int(os.path.basename(p)[6:-4])):
        size = int(os.path.basename(truth_path)[len("truth_"):-len(".csv")])
        rows = list(csv.DictReader(open(truth_path)))
        pairs = [(load(os.path.join(folder, r["reference"])), load(os.path.join(folder, r["moving"])))
                 for r in rows]
        truth = np.array([[float(r["tx_px"]), float(r["ty_px"])] for r in rows])
        sky = np.array([[float(r["skytie_dx_px"]), float(r["skytie_dy_px"])] for r in rows])
        sky_times = {r["method"]: (float(r["rms_px"]), float(r["ms_per_call"]))
                     for r in csv.DictReader(open(os.path.join(folder, f"skytie_{size}.csv")))}
        sky_ms = sky_times["skytie PhaseCorrelator (default)"][1]
        sky_free_ms = sky_times["skytie phase_correlate (default)"][1]
        win = cv2.createHanningWindow((size, size), cv2.CV_64F)

        peers = {
            "cv2.phaseCorrelate (hann)": lambda a, b: cv2.phaseCorrelate(a, b, win)[0],
            "cv2.phaseCorrelate (none)": lambda a, b: cv2.phaseCorrelate(a, b)[0],
            "skimage (upsample 1)": lambda a, b: tuple(-phase_cross_correlation(a, b)[0][::-1]),
            "skimage (upsample 100)": lambda a, b: tuple(
                -phase_cross_correlation(a, b, upsample_factor=100)[0][::-1]),
        }
        if not all_peers:
            peers = {k: v for k, v in peers.items() if k == "cv2.phaseCorrelate (hann)"}
        rounds = 20 if size >= 128 else 50
        rms = float(np.sqrt(np.mean(np.sum((sky - truth) ** 2, axis=1))))
        rows_out.append((size, "skytie phase_correlate (default)", rms, sky_free_ms, None))
        rows_out.append((size, "skytie PhaseCorrelator (default)", rms, sky_ms, None))
        for name, call in peers.items():
            est = np.array([call(a, b) for a, b in pairs], dtype=np.float64)
            err = float(np.sqrt(np.mean(np.sum((est - truth) ** 2, axis=1))))
            ms = median_ms_per_call(pairs, call, rounds)
            rows_out.append((size, name, err, ms, sky_ms / ms))
    return rows_out


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rounds", type=int, default=5,
                        help="Rust bench + OpenCV rounds (0: use the files already in FOLDER, one round)")
    parser.add_argument("folder", nargs="?",
                        default=os.path.join(tempfile.gettempdir(), "skytie_peers", "phasecorr"))
    args = parser.parse_args()
    paired = {}
    for k in range(max(args.rounds, 1)):
        if args.rounds > 0:
            run_rust_bench("phasecorr", args.folder)
        rows_out = one_round(args.folder, all_peers=k == 0)
        if k == 0:
            print(f"{'size':>7} | {'method':<33} | {'RMS err px':>10} | {'ms/call':>8} | {'skytie/peer time':>16}")
            print("-" * 88)
            for size, name, err, ms, ratio in rows_out:
                r = f"{ratio:.2f}x" if ratio is not None else ""
                print(f"{size:>3}x{size:<3} | {name:<33} | {err:>10.4f} | {ms:>8.4f} | {r:>16}")
            print("times: thread CPU time; skytie/peer uses the reused PhaseCorrelator (default: a pass and one "
                  "refinement)")
        for size, name, _, _, ratio in rows_out:
            if name == "cv2.phaseCorrelate (hann)":
                paired.setdefault(size, []).append(ratio)
    print(f"\nskytie PhaseCorrelator / cv2.phaseCorrelate (hann), median (min–max) of {max(args.rounds, 1)} "
          f"paired round(s):")
    for size, ratios in sorted(paired.items()):
        r = np.array(ratios)
        print(f"{size:>3}x{size:<3} | {np.median(r):.2f}x ({r.min():.2f}–{r.max():.2f})")


if __name__ == "__main__":
    main()
