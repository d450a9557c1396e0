#!/bin/sh
# Gao's colliding jellos at his finest dx, 1/256 (docs/gao-table2.md, "At Gao's scale"): the
# uniform run, the 3-level one refined around the whole surface (Gao's) and the one refined
# where the bodies will meet (jello_collision_256_contact), frame 1 each (about 133 steps), on
# THREADS threads (default 2); prints particles, ms per step of frame 1 (stats.csv, so the
# setup is left out) and the run's maximum resident set.
# Run from anywhere after make build; outputs under /tmp/m256_NAME. MPM=path picks the binary.
cd "$(dirname "$0")/../.."
THREADS=${THREADS:-2}
MPM=${MPM:-./build/mpm}
for name in ${SCENES:-jello_collision_256_uniform jello_collision_256_dynamic jello_collision_256_contact}; do
  /usr/bin/time -f %M -o /tmp/m256_rss "$MPM" run examples/gao/$name.json -o /tmp/m256_$name \
    --frames 1 --overwrite --threads "$THREADS" --quiet > /dev/null || exit 1
  awk -F, -v n=$name -v t="$THREADS" -v rss="$(cat /tmp/m256_rss)" 'NR==1{for(i=1;i<=NF;i++)h[$i]=i}
    NR==3{printf "%s: %d particles, %d threads, %.1f ms per step (frame 1, %d steps), %.0f MB\n",
          n, $h["particles"], t, 1000*$h["wall_seconds"]/$h["steps"], $h["steps"], rss/1024}' \
    /tmp/m256_$name/stats.csv
done
