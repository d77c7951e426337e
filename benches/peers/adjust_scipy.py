#!/usr/bin/env python3
"""Peer for the skytie adjustment bench: solves the SAME bundle problem with scipy.optimize.least_squares
(trust-region reflective, sparse finite-difference Jacobian) and compares the final cost and time.

Setup: pip install scipy numpy
Usage: cargo bench -p skytie-stages --bench adjust   (writes $TMPDIR/adjust_bench_problem.json)
       python3 benches/peers/adjust_scipy.py [$TMPDIR/adjust_bench_problem.json]

Model (see stages/src/adjustment/prepared.rs and residuals.rs): unknowns are recording centres and tie points
(local frame, metres); residuals are whitened panorama angle errors (wrap(A - A_obs), E - E_obs) * w, whitened
control-point residuals W (X - X_ctrl) and weak priors (C - C_recorded) / sigma; cost = 1/2 sum r^2.
"""
import json
import os
import sys
import tempfile
import time

import numpy as np
from scipy.optimize import least_squares
from scipy.sparse import lil_matrix


def main():
    path = sys.argv[1] if len(sys.argv) > 1 else os.path.join(tempfile.gettempdir(), "adjust_bench_problem.json")
    with open(path) as f:
        prob = json.load(f)
    c0 = np.array(prob["centers_local"])
    r0 = np.array(prob["rotations0"])  # (n, 3, 3) pano -> world
    inv_sig = np.array(prob["prior_inv_sigma"])  # (n, 2): xy, z
    x0_pts = np.array(prob["points_local"])
    pano = np.array(prob["pano"])
    rec = pano[:, 0].astype(int)
    pt = pano[:, 1].astype(int)
    az_obs, el_obs, wpano = pano[:, 2], pano[:, 3], pano[:, 4]
    ctrl = prob["control"]
    cpt = np.array([c["point"] for c in ctrl], dtype=int)
    cpos = np.array([c["position"] for c in ctrl]).reshape(-1, 3)
    cw = np.array([c["whitening"] for c in ctrl]).reshape(-1, 3, 3)
    n, m = len(c0), len(x0_pts)
    prior_w = np.stack([inv_sig[:, 0], inv_sig[:, 0], inv_sig[:, 1]], axis=1)

    def fun(x):
        c = x[: 3 * n].reshape(n, 3)
        p = x[3 * n:].reshape(m, 3)
        d = p[pt] - c[rec]
        q = np.einsum("kji,kj->ki", r0[rec], d)  # R0^T d
        az = np.arctan2(q[:, 0], q[:, 1])
        el = np.arctan2(q[:, 2], np.hypot(q[:, 0], q[:, 1]))
        daz = (az - az_obs + np.pi) % (2 * np.pi) - np.pi
        res_pano = np.stack([daz * wpano, (el - el_obs) * wpano], axis=1).ravel()
        res_ctrl = np.einsum("kij,kj->ki", cw, p[cpt] - cpos).ravel()
        res_prior = ((c - c0) * prior_w).ravel()
        return np.concatenate([res_pano, res_ctrl, res_prior])

    n_res = 2 * len(rec) + 3 * len(cpt) + 3 * n
    sp = lil_matrix((n_res, 3 * n + 3 * m), dtype=int)
    for k in range(len(rec)):
        for row in (2 * k, 2 * k + 1):
            sp[row, 3 * rec[k]: 3 * rec[k] + 3] = 1
            sp[row, 3 * n + 3 * pt[k]: 3 * n + 3 * pt[k] + 3] = 1
    base = 2 * len(rec)
    for k in range(len(cpt)):
        sp[base + 3 * k: base + 3 * k + 3, 3 * n + 3 * cpt[k]: 3 * n + 3 * cpt[k] + 3] = 1
    base += 3 * len(cpt)
    for i in range(n):
        for a in range(3):
            sp[base + 3 * i + a, 3 * i + a] = 1
    x0 = np.concatenate([c0.ravel(), x0_pts.ravel()])
    t = time.perf_counter()
    sol = least_squares(fun, x0, jac_sparsity=sp.tocsr(), method="trf", x_scale="jac",
                        ftol=1e-15, xtol=1e-15, gtol=1e-15, max_nfev=200)
    dt = time.perf_counter() - t
    cost_rust = prob["final_cost_rust"]
    rel = abs(sol.cost - cost_rust) / cost_rust
    print(f"scipy least_squares: {n} recordings, {m} points; cost {sol.cost:.10e} (rust {cost_rust:.10e}, "
          f"relative difference {rel:.2e}); time {dt:.2f} s vs rust {prob['time_rust_s']:.3f} s "
          f"(ratio scipy/rust {dt / prob['time_rust_s']:.1f}); nfev {sol.nfev}, status {sol.status}")
    sys.exit(0 if rel <= 1e-6 else 1)


if __name__ == "__main__":
    main()
