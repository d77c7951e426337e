#!/usr/bin/env bash
# Benchmark: the 18-variant oblique sweep (workflows/oblique-sweep.toml) against its default variant
# alone (workflows/oblique.toml), each on a FRESH cache, on the same campaign folder, in one run of this script.
# Prints both wall times, their ratio (target ≤ 4) and stages.sparse_cloud.executed of both (must be equal: the
# sparse cloud does not depend on any swept parameter).
#
#   benches/oblique_sweep.sh CAMPAIGN_DIR      (e.g. a folder written by `skytie synth --preset demo --seed 1`)
set -euo pipefail
cd "$(dirname "$0")/.."
campaign=${1:?usage: benches/oblique_sweep.sh CAMPAIGN_DIR}
cargo build --release --quiet
bin=target/release/skytie
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
run() { # name workflow
  local t0 t1
  t0=$(date +%s.%N)
  "$bin" run "$2" --campaign "$campaign" --cache "$tmp/cache-$1" --out "$tmp/out-$1" --quiet >"$tmp/$1.log" 2>&1
  t1=$(date +%s.%N)
  python3 -c "import sys; print(float(sys.argv[2]) - float(sys.argv[1]))" "$t0" "$t1"
}
single=$(run single workflows/oblique.toml)
sweep=$(run sweep workflows/oblique-sweep.toml)
executed() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['stages']['sparse_cloud']['executed'])" "$1"; }
printf 'single variant: %8.1f s wall, sparse_cloud executed %s\n' "$single" "$(executed "$tmp/out-single/metrics.json")"
printf '18-variant sweep: %6.1f s wall, sparse_cloud executed %s\n' "$sweep" "$(executed "$tmp/out-sweep/metrics.json")"
printf 'ratio sweep / single: %.2f (target <= 4)\n' "$(python3 -c "import sys; print(float(sys.argv[1]) / float(sys.argv[2]))" "$sweep" "$single")"
