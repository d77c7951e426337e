#!/usr/bin/env bash
# City-scale benchmark of a run's searches, output writers and report on image-free synthetic results of
# 10^4 and 10^5 recordings (stages/benches/outputs_scale.rs): one process per step, each timed with its peak
# resident memory by /usr/bin/time; then `skytie report` on the written output folder, and the sizes of
# report/index.html and of the map's data file. The generation of the synthetic results is part of every
# step's process (the `generate` row shows it alone). `--linear` also runs the per-image scans the footprint
# index replaced (10^4 only: at 10^5 they take minutes).
# Usage: benches/outputs_scale.sh [--linear] [SCRATCH_DIR]   (from the repository root; needs /usr/bin/time)
set -euo pipefail
cd "$(dirname "$0")/.."
linear=0
if [[ "${1:-}" == "--linear" ]]; then linear=1; shift; fi
scratch=${1:-$(mktemp -d)}
target=${CARGO_TARGET_DIR:-target}
cargo build --release -q --bin skytie
bin=$(cargo bench -q -p skytie-stages --bench outputs_scale --no-run 2>&1 | sed -n 's/.*(\(.*outputs_scale-[0-9a-f]*\)).*/\1/p' | tail -1)
if [[ -z "$bin" ]]; then
  bin=$(ls -t "$target"/release/deps/outputs_scale-* | grep -v '\.d$' | head -1)
fi
timed() { /usr/bin/time -f "    wall %e s, max RSS %M KiB" "$@"; }
for n in 10000 100000; do
  dir="$scratch/outputs-$n"
  rm -rf "$dir"
  mkdir -p "$dir"
  steps=(generate overlap oblique verify exports)
  if [[ $linear == 1 && $n == 10000 ]]; then steps+=(overlap-linear oblique-linear); fi
  for step in "${steps[@]}"; do
    echo "== $n recordings: $step"
    timed "$bin" "$n" "$dir" "$step"
  done
  echo "== $n recordings: skytie report"
  timed "$target/release/skytie" report "$dir/out" > /dev/null
  echo "    report/index.html $(stat -c %s "$dir/out/report/index.html") bytes," \
    "figures/map-data.js $(stat -c %s "$dir/out/report/figures/map-data.js") bytes," \
    "figures/trajectory.svg $(stat -c %s "$dir/out/report/figures/trajectory.svg") bytes," \
    "output folder $(du -sm "$dir/out" | cut -f1) MB"
done
if [[ -z "${1:-}" ]]; then rm -rf "$scratch"; fi
