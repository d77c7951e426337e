#!/usr/bin/env python3
"""Summary of benches/realsize.sh: reads WORK_DIR/{synth,run}-{twin,real}.time (GNU time -v), the runs'
metrics.json and ingest_decode.txt, and prints Markdown tables: wall time and peak RSS per command, node-seconds
per stage of both runs, time per recording after ingestion (real / twin) and the accuracy of both runs, with the
issue's targets (peak RSS <= 3 GiB, ingestion <= 1.5x a plain decode, time per recording <= 2x the twin)."""
import json
import re
import sys
from pathlib import Path

work = Path(sys.argv[1] if len(sys.argv) > 1 else "/tmp/skytie_realsize")
GIB = 1024**3


def gnu_time(name):
    """(wall s, peak RSS bytes) from WORK_DIR/NAME.time, or None."""
    p = work / f"{name}.time"
    if not p.exists():
        return None
    text = p.read_text()
    rss = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", text).group(1)) * 1024
    wall = re.search(r"Elapsed \(wall clock\) time.*: (.+)", text).group(1).strip()
    secs = 0.0
    for part in wall.split(":"):
        secs = secs * 60 + float(part)
    return secs, rss


def metrics(kind):
    p = work / f"out-{kind}" / "metrics.json"
    return json.loads(p.read_text()) if p.exists() else None


def get(m, *path):
    for k in path:
        if not isinstance(m, dict) or k not in m:
            return None
        m = m[k]
    return m


def fmt(x, digits=3):
    if x is None:
        return "–"
    if isinstance(x, float):
        return f"{x:.{digits}f}"
    return str(x)


print("### Commands: wall time and peak RSS\n")
print("| command | wall s | peak RSS GiB | target |")
print("|---|---|---|---|")
for name in ["synth-twin", "synth-real", "run-twin", "run-real", "ingest-decode"]:
    t = gnu_time(name)
    if t:
        target = "≤ 3 GiB" if name.startswith("run") else ""
        ok = "" if not target else (" ✓" if t[1] <= 3 * GIB else " ✗")
        print(f"| {name} | {t[0]:.1f} | {t[1] / GIB:.2f} | {target}{ok} |")

mt, mr = metrics("twin"), metrics("real")
print("\n### Node-seconds per stage (sum over the stage's nodes)\n")
print("| stage | twin s | real-size s | real / twin |")
print("|---|---|---|---|")
stages = sorted(set((get(mt, "stages") or {}).keys()) | set((get(mr, "stages") or {}).keys()))
for s in stages:
    a = get(mt, "stages", s, "seconds")
    b = get(mr, "stages", s, "seconds")
    ratio = f"{b / a:.2f}" if a and b else "–"
    print(f"| {s} | {fmt(a, 2)} | {fmt(b, 2)} | {ratio} |")

# Time per recording after ingestion: every node-second except generating and ingesting the images.
SETUP = {"synth", "ingest"}
per_rec = {}
for kind, m in [("twin", mt), ("real", mr)]:
    if not m:
        continue
    n = get(m, "campaign", "recordings") or 0
    total = sum(v["seconds"] for k, v in m["stages"].items() if k not in SETUP)
    failed = get(m, "engine", "nodes_failed")
    per_rec[kind] = (total / n if n else None, n, total, failed, get(m, "engine", "seconds"))
print("\n### Time per recording after ingestion (node-seconds of every stage but synth and ingest)\n")
print("| campaign | recordings | node-s after ingestion | per recording s | run wall s | failed nodes |")
print("|---|---|---|---|---|---|")
for kind, (pr, n, total, failed, wall) in per_rec.items():
    print(f"| {kind} | {n} | {total:.1f} | {fmt(pr, 2)} | {fmt(wall, 1)} | {failed} |")
if "twin" in per_rec and "real" in per_rec and per_rec["twin"][0]:
    r = per_rec["real"][0] / per_rec["twin"][0]
    print(f"\nreal / twin per recording: **{r:.2f}×** (target ≤ 2×{' ✓' if r <= 2 else ' ✗'})")

print("\n### Ingestion against a plain decode of the same file (same process)\n")
p = work / "ingest_decode.txt"
if p.exists():
    print("```")
    print(p.read_text().strip())
    print("```")

# The adjustment's label: `combined` for the default workflow, `nadir` with CHAIN=nadir.
label = next(iter(get(mr, "adjust") or get(mt, "adjust") or {"combined": None}))
print(f"\n### Accuracy (adjustment: {label})\n")
rows = [
    ("nadir MM tie points", ("nadir", "mm_tie_points")),
    ("nadir tie points graded", ("nadir", "graded_tie_points")),
    ("nadir inlier ratio", ("nadir", "inlier_ratio")),
    ("nadir control points", ("nadir", "control_point_error_m", "count")),
    ("nadir control points RMS horizontal m", ("nadir", "control_point_error_m", "rms_horizontal")),
    ("oblique correspondences graded", ("oblique", "graded_correspondences")),
    ("oblique inlier ratio after consensus", ("oblique", "inlier_ratio_after_consensus")),
    ("check points 2D before m", ("adjust", label, "checkpoints", "before", "2d")),
    ("check points 2D after m", ("adjust", label, "checkpoints", "after", "2d")),
    ("recordings RMSE 2D before m", ("adjust", label, "recordings", "before", "rmse_2d")),
    ("recordings RMSE 2D after m", ("adjust", label, "recordings", "after", "rmse_2d")),
    ("verification of the recorded trajectory passed", ("verify", "passed")),
    ("verification of the adjusted trajectory passed", ("verify_adjusted", "passed")),
]
print("| quantity | twin | real-size |")
print("|---|---|---|")
for name, path in rows:
    print(f"| {name} | {fmt(get(mt, *path))} | {fmt(get(mr, *path))} |")
