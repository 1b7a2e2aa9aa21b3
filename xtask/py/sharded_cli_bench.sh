#!/bin/sh
# SHARDS shards of 20 000 Cornell-box probes (2 % target, blocks of 1 000) on 2 workers of
# WORKER_THREADS threads each (default: rayon's, every core; xargs -P 2 hands out the next shard
# as one ends), then `gcr merge`: the command timed against one process in
# docs/design/sharding.md. Usage: SHARDS=2 sh xtask/py/sharded_cli_bench.sh (probes:
# python3 xtask/py/area_probes.py cornell-box 20000 /tmp/P20k.txt).
set -e
G=${GCR:-target/release/gcr}; P=${PROBES:-/tmp/P20k.txt}; N=${SHARDS:-2}; D=${OUT:-/tmp/gcr-shards}
mkdir -p "$D"
[ -n "$WORKER_THREADS" ] && export RAYON_NUM_THREADS="$WORKER_THREADS"
seq 0 $((N - 1)) | xargs -P 2 -I{} "$G" solve cornell-box --probes "$P" \
    --probe-out "$D/part{}.txt" --target-error 0.02 --block-points 1000 --shard {}/"$N" 2>/dev/null
"$G" merge "$D"/part*.txt --probe-out "$D/merged.txt" 2>/dev/null
