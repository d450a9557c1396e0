#!/bin/sh
# Gao's colliding jellos at his finest dx, 1/256 (docs/gao-table2.md, "At Gao's scale"): the
# uniform run and the 3-level one, frame 1 each (about 133 steps), on THREADS threads (default
# 2); prints particles and ms per step of frame 1 (stats.csv, so the setup is left out).
# Run from anywhere after make build; outputs under /tmp/m256_NAME.
cd "$(dirname "$0")/../.."
THREADS=${THREADS:-2}
for name in jello_collision_256_uniform jello_collision_256_dynamic; do
  ./build/mpm run examples/gao/$name.json -o /tmp/m256_$name --frames 1 --overwrite \
    --threads "$THREADS" --quiet > /dev/null || exit 1
  awk -F, -v n=$name -v t="$THREADS" 'NR==1{for(i=1;i<=NF;i++)h[$i]=i}
    NR==3{printf "%s: %d particles, %d threads, %.1f ms per step (frame 1, %d steps)\n", n,
          $h["particles"], t, 1000*$h["wall_seconds"]/$h["steps"], $h["steps"]}' \
    /tmp/m256_$name/stats.csv
done
