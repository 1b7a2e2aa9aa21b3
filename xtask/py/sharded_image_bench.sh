#!/bin/sh
# A per-pixel image in SHARDS shards (strips of rows: --block-points, default one row of 96) on 2
# workers of WORKER_THREADS threads each (default: rayon's, every core; xargs -P 2 hands out the
# next shard as one ends), then the merge run (--from-shards): the command timed against one
# process in docs/design/sharding.md. Usage: SHARDS=2 sh xtask/py/sharded_image_bench.sh
set -e
G=${GCR:-target/release/gcr}; N=${SHARDS:-2}; D=${OUT:-/tmp/gcr-image-shards}
O="cornell-box --image-mode pixel --resolution 96x96 --block-points ${BLOCK:-96}"
mkdir -p "$D"
[ -n "$WORKER_THREADS" ] && export RAYON_NUM_THREADS="$WORKER_THREADS"
seq 0 $((N - 1)) | xargs -P 2 -I{} $G solve $O --image "$D/view.exr" --shard {}/"$N" 2>/dev/null
unset RAYON_NUM_THREADS
$G solve $O --image "$D/view.exr" --from-shards "$D"/view.shard-*-of-"$N".txt 2>/dev/null
rm -f "$D"/view.shard-*-of-"$N".txt
