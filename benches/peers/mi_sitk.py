#!/usr/bin/env python3
"""Peer comparison of skytie's Mattes MI translation registration with SimpleITK on IDENTICAL 8-bit PNG pairs.

Setup (never part of the test path; see benches/README.md):
    python3 -m venv /tmp/peers && /tmp/peers/bin/pip install SimpleITK numpy
    cargo bench -p skytie-stages --bench mi                  # writes <temp>/skytie_peers/mi/
    /tmp/peers/bin/python benches/peers/mi_sitk.py [<temp>/skytie_peers/mi]

The bench writes `mi_{k}_fixed.png` / `mi_{k}_moving.png` (moving = fixed translated by +t, an exact Fourier shift
of a band-limited texture, then gain/offset/gamma and noise), `params.csv` (bins, samples, iteration budget and
the (1+1)-ES settings), `truth.csv` (t and skytie's estimates) and `skytie.csv` (skytie's RMS error and time per
registration). SimpleITK gets the same settings: `SetMetricAsMattesMutualInformation(bins)`, sampling NONE
(every pixel) or RANDOM with percentage samples/pixels, `SetOptimizerAsOnePlusOneEvolutionary` with the same
iterations, epsilon, initial radius, growth and shrink factors (unit scales), linear interpolation, a
`TranslationTransform` starting at (0, 0), one resolution level, 1 thread. Convention: ITK's transform maps a
fixed point x to the moving point x + t, the same as skytie's, so both estimate +t (spacing 1, so physical units
are pixels). Differences that remain: ITK v4 RANDOM sampling draws pixels with replacement and moves each by a
normal deviate of sigma = 1/3 pixel (fixed values then interpolated), skytie draws distinct pixel centres; the ES
normal deviates come from different generators (per-pair seeds on both sides).

Timing: median over rounds of the mean CPU time per registration (SimpleITK images built beforehand; the
registration method is set up and executed inside the timed region, as skytie's `mi_search` builds its metric).
Both thread and process CPU time are measured for SimpleITK: with 1 ITK thread they agree, which shows no work
ran on other threads. Prints the RMS error (px) against t and the ratio skytie / SimpleITK of the times.
"""
import csv
import os
import sys
import tempfile
import time

import numpy as np
import SimpleITK as sitk


def load(path):
    img = sitk.ReadImage(path, sitk.sitkFloat32)
    if img.GetDimension() != 2:
        sys.exit(f"{path}: expected a 2-D grey image")
    return img / 255.0


def register(fixed, moving, p, samples, seed):
    r = sitk.ImageRegistrationMethod()
    r.SetNumberOfThreads(1)
    r.SetMetricAsMattesMutualInformation(numberOfHistogramBins=p["bins"])
    if samples is None:
        r.SetMetricSamplingStrategy(r.NONE)
    else:
        npx = fixed.GetWidth() * fixed.GetHeight()
        r.SetMetricSamplingStrategy(r.RANDOM)
        r.SetMetricSamplingPercentage(samples / npx, seed)
    r.SetInterpolator(sitk.sitkLinear)
    r.SetOptimizerAsOnePlusOneEvolutionary(
        numberOfIterations=p["iterations"], epsilon=p["epsilon_px"], initialRadius=p["initial_radius_px"],
        growthFactor=p["growth_factor"], shrinkFactor=p["shrink_factor"], seed=seed)
    r.SetOptimizerScales([1.0, 1.0])
    r.SetShrinkFactorsPerLevel([1])
    r.SetSmoothingSigmasPerLevel([0])
    r.SetInitialTransform(sitk.TranslationTransform(2), inPlace=False)
    t = r.Execute(fixed, moving)
    dx, dy = t.GetParameters() if t.GetName() == "TranslationTransform" else \
        sitk.CompositeTransform(t).GetNthTransform(0).GetParameters()
    return dx, dy, -r.GetMetricValue(), r.GetOptimizerIteration()


def median_ms(pairs, call, rounds, clock):
    samples = []
    for _ in range(rounds):
        t0 = clock()
        for k, (a, b) in enumerate(pairs):
            call(k, a, b)
        samples.append((clock() - t0) * 1e-6 / len(pairs))
    return float(np.median(samples))


def main(folder):
    sitk.ProcessObject.SetGlobalDefaultNumberOfThreads(1)
    pfile = os.path.join(folder, "params.csv")
    if not os.path.exists(pfile):
        sys.exit(f"no params.csv in {folder}: run the Rust bench first (see the docstring)")
    raw = next(csv.DictReader(open(pfile)))
    p = {k: (int(v) if k in ("size_px", "bins", "samples", "iterations") else float(v)) for k, v in raw.items()}
    rows = list(csv.DictReader(open(os.path.join(folder, "truth.csv"))))
    pairs = [(load(os.path.join(folder, r["fixed"])), load(os.path.join(folder, r["moving"]))) for r in rows]
    truth = np.array([[float(r["tx_px"]), float(r["ty_px"])] for r in rows])
    sky = {r["setting"]: r for r in csv.DictReader(open(os.path.join(folder, "skytie.csv")))}

    print(f"{len(pairs)} pairs {p['size_px']}x{p['size_px']}, {p['bins']} bins, (1+1)-ES {p['iterations']} iterations, "
          f"r0 {p['initial_radius_px']}, growth {p['growth_factor']}, shrink {p['shrink_factor']:.5f}, "
          f"eps {p['epsilon_px']}; CPU ms per registration")
    print(f"{'sampling':<16} | {'method':<22} | {'RMS err px':>10} | {'max err px':>10} | {'mean iter.':>10} "
          f"| {'ms/reg (thread)':>15} | {'ms/reg (process)':>16} | {'skytie/peer':>11}")
    print("-" * 130)
    for setting, samples in (("all", None), ("sampled", p["samples"])):
        label = "all pixels" if samples is None else f"{samples} random"
        s = sky[setting]
        sky_est = np.array([[float(r[f"skytie_{setting}_dx_px"]), float(r[f"skytie_{setting}_dy_px"])] for r in rows])
        sky_it = np.mean([int(r[f"skytie_{setting}_iterations"]) for r in rows])
        sky_err = np.hypot(*(sky_est - truth).T)
        sky_ms = float(s["ms_per_registration"])
        print(f"{label:<16} | {'skytie mi_search':<22} | {np.sqrt(np.mean(sky_err ** 2)):>10.4f} | "
              f"{sky_err.max():>10.4f} | {sky_it:>10.1f} | {sky_ms:>15.3f} | {'':>16} |")

        def call(k, a, b):
            return register(a, b, p, samples, k + 1)
        est = [call(k, a, b) for k, (a, b) in enumerate(pairs)]
        e = np.array([[x[0], x[1]] for x in est])
        err = np.hypot(*(e - truth).T)
        it = np.mean([x[3] for x in est])
        ms_thread = median_ms(pairs, call, 5, time.thread_time_ns)
        ms_proc = median_ms(pairs, call, 5, time.process_time_ns)
        print(f"{label:<16} | {'SimpleITK ' + sitk.Version_VersionString():<22} | {np.sqrt(np.mean(err ** 2)):>10.4f} | "
              f"{err.max():>10.4f} | {it:>10.1f} | {ms_thread:>15.3f} | {ms_proc:>16.3f} | "
              f"{sky_ms / ms_proc:>10.2f}x")
    print("skytie: thread CPU time; skytie/peer divides by SimpleITK's process CPU time (1 ITK thread)")


if __name__ == "__main__":
    default = os.path.join(tempfile.gettempdir(), "skytie_peers", "mi")
    main(sys.argv[1] if len(sys.argv) > 1 else default)
