#!/usr/bin/env bash
# City-scale adjustment benchmark: time and peak memory of the adjustment on image-free street-network blocks
# of 10^4, 10^5 (and with --million 10^6) recordings, once as the pipeline builds them (ties between
# consecutive recordings only) and once with road-marking ties between the passes at every crossing, each
# without and with the relative release of the shipped default.toml (threshold 9.21).
# Each run prints the load average before it and its wall time, CPU time and peak RSS (on a shared machine the
# CPU time is the steadier number).
# Usage: benches/adjust_scale.sh [--million]    (from the repository root; needs /usr/bin/time)
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q -p skytie-stages --bench adjust_scale
bin=$(cargo bench -q -p skytie-stages --bench adjust_scale --no-run 2>&1 | sed -n 's/.*(\(.*adjust_scale-[0-9a-f]*\)).*/\1/p' | tail -1)
if [[ -z "$bin" ]]; then
  bin=$(ls -t "${CARGO_TARGET_DIR:-target}"/release/deps/adjust_scale-* | grep -v '\.d$' | head -1)
fi
sizes=(10000 100000)
if [[ "${1:-}" == "--million" ]]; then sizes+=(1000000); fi
for n in "${sizes[@]}"; do
  for crossings in 0 4; do
    for release in "" "--relative-release=9.21"; do
      echo "== $n recordings, $crossings crossing ties per crossing ${release:-(no release)}; load average $(cut -d' ' -f1-3 /proc/loadavg)"
      /usr/bin/time -f "wall %e s, CPU %U s user + %S s system, max RSS %M KiB" \
        "$bin" "$n" "--crossing-points=$crossings" --structure $release
    done
  done
done
