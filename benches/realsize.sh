#!/usr/bin/env bash
# Real sensor sizes benchmark: the `realsize` preset (26460 × 17004 px nadir frames as tiled JPEG TIFF,
# 14192 × 10640 px obliques, 8192 × 4096 px panoramas) and its demo-size twin (`--at-render-size`: the same
# scene, trajectory, flight plans and content at the rendered size) are generated, the default workflow runs on
# each with a cold cache, and the script reports per stage node-seconds, wall time and peak RSS of every
# command (/usr/bin/time), one-time ingestion of a frame of each kind against a plain decode of the same file
# in one process (`stages/benches/ingest_decode.rs`), time per recording after ingestion against the twin,
# and the accuracy of both runs.
#
# Usage: benches/realsize.sh [WORK_DIR]    (from anywhere; default WORK_DIR $TMPDIR/skytie_realsize)
# Environment: SEED (default 1), THREADS (default: all cores), SKIP_SYNTH=1 reuses the campaigns in WORK_DIR,
# CHAIN=nadir runs the default workflow without the oblique chain (adjustment on the nadir correspondences
# only: the obliques are then not ingested, which saves their ≈ 3.2 GB of pyramids in the cache).
# INGEST_REPS (default 2): runs of each ingestion and plain decode timed (the minimum is kept).
# Disk: the real-size campaign takes ≈ 0.6 GB and its cache ≈ 7.7 GB (uncompressed pyramids of 7 nadir frames of
# 450 MP, 16 obliques of 151 MP and 12 panoramas of 34 MP), ≈ 4.8 GB with CHAIN=nadir.
# Needs /usr/bin/time (Debian package `time`) and python3 for the summary.
set -euo pipefail
cd "$(dirname "$0")/.."
work=${1:-${TMPDIR:-/tmp}/skytie_realsize}
seed=${SEED:-1}
threads=()
if [[ -n "${THREADS:-}" ]]; then threads=(--threads "$THREADS"); fi
mkdir -p "$work"
target=${CARGO_TARGET_DIR:-target}
cargo build --release -q --bin skytie
bin="$target/release/skytie"
cargo bench -q -p skytie-stages --bench ingest_decode --no-run
ingest_bin=$(ls -t "$target"/release/deps/ingest_decode-* | grep -v '\.d$' | head -1)

# `timed NAME CMD...`: runs CMD under /usr/bin/time, keeps its report in WORK_DIR/NAME.time.
timed() {
  local name=$1
  shift
  echo "== $name: $*"
  /usr/bin/time -v -o "$work/$name.time" "$@"
}

if [[ -z "${SKIP_SYNTH:-}" ]]; then
  rm -rf "$work/real" "$work/twin"
  timed synth-twin "$bin" synth --preset realsize --at-render-size --seed "$seed" --out "$work/twin"
  timed synth-real "$bin" synth --preset realsize --seed "$seed" --out "$work/real"
fi
workflow=default
if [[ "${CHAIN:-full}" == nadir ]]; then
  workflow="$work/default-nadir.toml"
  python3 - benches/../workflows/default.toml "$workflow" <<'PY'
import re, sys
text = open(sys.argv[1]).read()
text = re.sub(r'stages = \[[^\]]*\]', 'stages = ["synth", "load", "ortho", "summary", "mm_match", "ortho_aerial", '
              '"transform", "refine", "control", "nadir", "grade_nadir", "adjust", "grade_adjust", "verify"]', text)
text = text.replace('sources = "combined"', 'sources = "nadir"')
# Drop the parameter tables of the oblique stages (a table needs its stage in `stages`).
text = re.sub(r'(?ms)^\[(facades|patches|oblique|sparse_cloud)[^\]]*\].*?(?=^\[|\Z)', '', text)
text = text.replace('name = "default"', 'name = "default-nadir"')
open(sys.argv[2], "w").write(text)
PY
fi
for kind in twin real; do
  rm -rf "$work/cache-$kind" "$work/out-$kind"
  # The exit code reports the adjustment's verdict; the metrics are read either way.
  timed "run-$kind" "$bin" run "$workflow" --campaign "$work/$kind" --cache "$work/cache-$kind" \
    --out "$work/out-$kind" --quiet --timings "${threads[@]}" || echo "(run-$kind exit code $?)"
done

# One frame of each kind, ingested and decoded plainly in the same process (SKIP_DECODE=1 keeps an earlier
# WORK_DIR/ingest_decode.txt).
first() { find "$1" -maxdepth 1 -type f ! -name '*.csv' | sort | head -1; }
files=("$(first "$work/real/aerial/nadir")" "$(first "$work/real/aerial/oblique")" "$(first "$work/real/mm/panoramas")")
[[ -n "${SKIP_DECODE:-}" && -s "$work/ingest_decode.txt" ]] ||
  timed ingest-decode env SKYTIE_INGEST_REPS="${INGEST_REPS:-2}" "$ingest_bin" "${files[@]}" | tee "$work/ingest_decode.txt"

python3 benches/realsize_summary.py "$work" | tee "$work/summary.md"
