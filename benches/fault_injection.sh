#!/usr/bin/env bash
# Fault injection: a run of WORKFLOW (default workflows/tiny.toml, which renders the tiny campaign itself) is
# killed with SIGKILL at KILLS (default 20) random moments, resumed each time on the same cache, and finally
# run to completion; its outputs must equal a clean run's byte for byte (the exports, the report's tables, and
# metrics.json without the engine's counters and timings, which differ by design).
#
#   benches/fault_injection.sh [KILLS] [WORKFLOW]      (SKYTIE=path/to/skytie, default target/release/skytie)
#
# Prints one line per kill (the moment, what the interrupted run had printed last) and a verdict; exit 0 when
# the outputs are identical, 1 when they differ.
set -euo pipefail
cd "$(dirname "$0")/.."
KILLS=${1:-20}
WF=${2:-workflows/tiny.toml}
SKYTIE=${SKYTIE:-${CARGO_TARGET_DIR:-target}/release/skytie}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

start=$(date +%s.%N)
"$SKYTIE" run "$WF" --cache "$work/cache-clean" --out "$work/out-clean" --quiet >"$work/clean.log" 2>&1 || true
clean_s=$(python3 -c "print($(date +%s.%N) - $start)")
echo "clean run: ${clean_s} s ($(tail -n 1 "$work/clean.log"))"

RANDOM=${SEED:-1}
for k in $(seq 1 "$KILLS"); do
  at=$(python3 -c "import random; random.seed($RANDOM * 7919 + $k); print(round(random.uniform(0.2, $clean_s), 2))")
  "$SKYTIE" run "$WF" --cache "$work/cache-killed" --out "$work/out-killed" --quiet >"$work/kill-$k.log" 2>&1 &
  pid=$!
  sleep "$at"
  if kill -9 "$pid" 2>/dev/null; then state="killed"; else state="had finished"; fi
  wait "$pid" 2>/dev/null || true
  echo "kill $k at ${at} s: $state"
done
"$SKYTIE" run "$WF" --cache "$work/cache-killed" --out "$work/out-killed" --quiet >"$work/final.log" 2>&1 || true
echo "resumed run: $(tail -n 1 "$work/final.log")"

python3 - "$work/out-clean" "$work/out-killed" <<'PY'
import json, os, sys
a, b = sys.argv[1], sys.argv[2]
def files(root):
    out = {}
    for d, _, names in os.walk(root):
        for n in names:
            rel = os.path.relpath(os.path.join(d, n), root)
            if rel.startswith("report/run-log") or rel in ("provenance.json", "report/index.html"):
                continue
            out[rel] = os.path.join(d, n)
    return out
def content(path, rel):
    data = open(path, "rb").read()
    if rel.endswith("metrics.json"):
        m = json.loads(data)
        for k in ("engine", "stages"):
            m.pop(k, None)
        return json.dumps(m, sort_keys=True).encode()
    return data
fa, fb = files(a), files(b)
diff = sorted(set(fa) ^ set(fb))
diff += [r for r in sorted(set(fa) & set(fb)) if content(fa[r], r) != content(fb[r], r)]
print(f"compared {len(set(fa) & set(fb))} files")
if diff:
    print("DIFFERENT:", ", ".join(diff))
    sys.exit(1)
print("identical outputs after the kills")
PY
