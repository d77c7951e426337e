#!/usr/bin/env bash
# End to end on a single-node Slurm cluster: the `street` synthetic campaign (320 panoramas) run once as a
# single process and once through `skytie slurm` (prepare job, a job array of SHARDS shards, merge job) on a
# separate cache; the outputs must be byte-identical (metrics.json apart from its engine bookkeeping), and
# submitting the finished campaign again must execute nothing. Prints wall times for docs/cluster.md.
#
# Needs root (it installs and starts slurm-wlm and munge with apt when `sinfo` does not answer) and a release
# build. Not part of `cargo test`.
#
#   benches/slurm_e2e.sh [SHARDS] [WORKDIR]        (defaults: 4 shards, /tmp/skytie-slurm-e2e)
#
# Environment: SKYTIE (binary; default: target/release/skytie, built if missing), SLURM_CPUS (CPUs of the node,
# default: nproc), SLURM_MEM_MB (RealMemory, default: 80 % of MemTotal).
set -euo pipefail
SHARDS=${1:-4}
WORK=${2:-/tmp/skytie-slurm-e2e}
REPO=$(cd "$(dirname "$0")/.." && pwd)
WF="$REPO/benches/slurm/street.toml"
SKYTIE=${SKYTIE:-"${CARGO_TARGET_DIR:-$REPO/target}/release/skytie"}
say() { printf '[slurm-e2e] %s\n' "$*"; }

start_slurm() {
    if sinfo -h >/dev/null 2>&1; then return; fi
    say "installing and starting a single-node Slurm (slurm-wlm, munge)"
    command -v slurmctld >/dev/null || { apt-get update -q && DEBIAN_FRONTEND=noninteractive apt-get install -y -q slurm-wlm munge; }
    mkdir -p /etc/munge /run/munge /etc/slurm /var/spool/slurmctld /var/spool/slurmd /var/log/slurm
    if [ ! -s /etc/munge/munge.key ]; then
        dd if=/dev/urandom bs=1 count=1024 of=/etc/munge/munge.key 2>/dev/null
        chmod 400 /etc/munge/munge.key
    fi
    chown munge:munge /etc/munge/munge.key /run/munge 2>/dev/null || true
    pgrep -x munged >/dev/null || su -s /bin/sh munge -c munged 2>/dev/null || munged --force
    local cpus=${SLURM_CPUS:-$(nproc)}
    local mem=${SLURM_MEM_MB:-$(awk '/MemTotal/ {printf "%d", $2 / 1024 * 0.8}' /proc/meminfo)}
    cat >/etc/slurm/slurm.conf <<EOF
ClusterName=local
SlurmctldHost=$(hostname -s)(127.0.0.1)
SlurmUser=root
AuthType=auth/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
StateSaveLocation=/var/spool/slurmctld
SlurmdSpoolDir=/var/spool/slurmd
SlurmctldLogFile=/var/log/slurm/slurmctld.log
SlurmdLogFile=/var/log/slurm/slurmd.log
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
ReturnToService=2
MpiDefault=none
MaxArraySize=100001
MaxJobCount=200000
NodeName=$(hostname -s) NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=debug Nodes=$(hostname -s) Default=YES MaxTime=INFINITE State=UP
SchedulerParameters=sched_min_interval=0,defer_batch
CompleteWait=0
EOF
    slurmctld && slurmd
    for _ in $(seq 60); do sinfo -h -o %t 2>/dev/null | grep -q idle && return; sleep 2; done
    echo "Slurm did not come up: see /var/log/slurm/" >&2
    exit 1
}

# Wait until none of the jobs named skytie-street-* is queued or running.
wait_jobs() {
    while squeue -h -n skytie-street-prepare,skytie-street-shard,skytie-street-merge 2>/dev/null | grep -q .; do
        sleep 2
    done
}

# Every output file but the report, the shard summaries and the job scripts; metrics.json without the engine's
# bookkeeping; provenance.json left out (it records run times and the cache's own paths).
fingerprint() {
    (cd "$1" && find . -type f ! -path './report/*' ! -path './shards/*' ! -path './slurm/*' \
        ! -name metrics.json ! -name provenance.json -print0 | sort -z | xargs -0 sha256sum)
    python3 -c 'import json,sys; m=json.load(open(sys.argv[1])); m.pop("engine"); m.pop("stages"); print(json.dumps(m, sort_keys=True))' \
        "$1/metrics.json" | sha256sum | sed 's/-$/metrics.json (without engine, stages)/'
}

executed() { python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["engine"]["nodes_executed"])' "$1"; }

[ -x "$SKYTIE" ] || (cd "$REPO" && cargo build --release)
start_slurm
mkdir -p "$WORK"
CAMPAIGN="$WORK/campaign"
if [ ! -f "$CAMPAIGN/campaign.toml" ]; then
    say "generating the street campaign"
    t0=$(date +%s.%N)
    "$SKYTIE" synth --preset street --seed 1 --out "$CAMPAIGN" >/dev/null
    say "generated in $(echo "$(date +%s.%N) - $t0" | bc) s"
fi
RECORDINGS=$(($(grep -cv '^\s*\(#\|$\)' "$CAMPAIGN/mm/recordings.csv") - 1))
say "campaign: $RECORDINGS recordings, $SHARDS shards ($((RECORDINGS / SHARDS)) recordings per shard)"

rm -rf "$WORK/cache-single" "$WORK/out-single" "$WORK/cache-slurm" "$WORK/out-slurm"
say "single process"
t0=$(date +%s.%N)
set +e
"$SKYTIE" run "$WF" --campaign "$CAMPAIGN" --cache "$WORK/cache-single" --out "$WORK/out-single" --quiet \
    >"$WORK/single.log" 2>&1
single_code=$?
set -e
single_s=$(echo "$(date +%s.%N) - $t0" | bc)
say "single process: exit $single_code, $single_s s"

say "Slurm: prepare, $SHARDS-task array, merge"
t0=$(date +%s.%N)
"$SKYTIE" slurm "$WF" --campaign "$CAMPAIGN" --cache "$WORK/cache-slurm" --out "$WORK/out-slurm" \
    --shards "$SHARDS" --cpus 1 --mem 4G --merge-cpus "$(nproc)" --merge-mem 8G --time 2:00:00
wait_jobs
slurm_s=$(echo "$(date +%s.%N) - $t0" | bc)
say "Slurm: $slurm_s s from submission to the end of the merge"
for k in $(seq "$SHARDS"); do
    say "  shard $k/$SHARDS: $(python3 -c 'import json,sys; e=json.load(open(sys.argv[1]))["engine"]; print(e["nodes_executed"], "executed,", e["nodes_cached"], "cached,", e["nodes_failed"], "failed,", round(e["seconds"]), "s")' "$WORK/out-slurm/shards/shard-$k-of-$SHARDS.json")"
done
[ -f "$WORK/out-slurm/metrics.json" ] || { echo "the merge wrote no metrics.json: see $WORK/out-slurm/slurm/logs" >&2; exit 1; }
say "  merge: $(executed "$WORK/out-slurm/metrics.json") nodes executed"

if diff <(fingerprint "$WORK/out-single") <(fingerprint "$WORK/out-slurm") >"$WORK/diff.txt"; then
    say "EQUAL: $(fingerprint "$WORK/out-single" | wc -l) output files byte-identical to the single process"
else
    say "DIFFERENT outputs:"; cat "$WORK/diff.txt"; exit 1
fi

say "submitting the finished campaign again"
t0=$(date +%s.%N)
"$SKYTIE" slurm "$WF" --campaign "$CAMPAIGN" --cache "$WORK/cache-slurm" --out "$WORK/out-slurm" \
    --shards "$SHARDS" --cpus 1 --mem 4G --merge-cpus "$(nproc)" --merge-mem 8G --time 2:00:00 >/dev/null
wait_jobs
again_s=$(echo "$(date +%s.%N) - $t0" | bc)
total=$(executed "$WORK/out-slurm/metrics.json")
for k in $(seq "$SHARDS"); do
    total=$((total + $(executed "$WORK/out-slurm/shards/shard-$k-of-$SHARDS.json")))
done
total=$((total + $(executed "$WORK/out-slurm/shards/prepare.json")))
say "again: $total nodes executed, $again_s s"
[ "$total" -eq 0 ] || { echo "a re-submitted finished campaign executed $total nodes" >&2; exit 1; }
say "PASS: $RECORDINGS recordings, $SHARDS shards; single $single_s s, Slurm $slurm_s s, re-submission $again_s s"
