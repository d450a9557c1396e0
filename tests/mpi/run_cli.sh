#!/bin/sh
# run_cli.sh - ctest mpi_cli_npN: `mpm run` under mpirun on N ranks, as a user runs it. Each rank
# runs the program inside a shell that records its exit status (so that mpirun, which ends the
# job when a rank exits non-zero, lets every rank finish and shows each one's status):
#   - a run of an example scene: every rank exits 0, frame_0001.pvtu lists N pieces, and the
#     start and summary lines are printed once (by rank 0 alone);
#   - an implicit scene (refused on ranks), a folder holding a user's file of a run's name
#     without --overwrite, and --resume (no checkpoints on ranks yet): every rank exits 2, one
#     line is printed, and the user's folder is as it was.
#
#   run_cli.sh MPM MPIEXEC N SOURCE_DIR
set -eu
mpm=$1 mpiexec=$2 np=$3 src=$4
tmp=$(mktemp -d "${TMPDIR:-/tmp}/mpm-mpi-cli.XXXXXX")
trap '[ -n "${KEEP:-}" ] || rm -rf "$tmp"' EXIT INT TERM
fail=0
bad() {
  echo "run_cli ($np ranks): $*" >&2
  fail=1
}

# ranks NAME ARGS...: `mpm ARGS` on the ranks; stderr to $tmp/NAME.err, the ranks' exit
# statuses one a line to $tmp/NAME.exits
ranks() {
  name=$1
  shift
  : >"$tmp/$name.exits"
  EXITS="$tmp/$name.exits" timeout 120 "$mpiexec" -n "$np" --oversubscribe -x EXITS \
    sh -c '"$0" "$@"; echo $? >>"$EXITS"' "$mpm" "$@" >"$tmp/$name.out" 2>"$tmp/$name.err" ||
    bad "$name: mpiexec failed or timed out"
}

# every_rank NAME STATUS: each of the np ranks exited with STATUS
every_rank() {
  n=$(grep -c "^$2\$" "$tmp/$1.exits" || true)
  [ "$n" -eq "$np" ] || bad "$1: $n of $np ranks exited $2 ($(tr '\n' ' ' <"$tmp/$1.exits"))"
}

# lines NAME PATTERN COUNT: stderr has COUNT lines matching PATTERN
lines() {
  n=$(grep -c -- "$2" "$tmp/$1.err" || true)
  [ "$n" -eq "$3" ] || { bad "$1: $n lines of '$2', not $3:"; cat "$tmp/$1.err" >&2; }
}

ranks good run "$src/examples/jello_cubes.json" -o "$tmp/good" --frames 1 --threads 1
every_rank good 0
lines good '^mpm: .*jello_cubes.json: .* particles' 1
lines good '^mpm: done' 1
pieces=$(grep -c '<Piece Source="frame_0001_p[0-9]*\.vtu"/>' "$tmp/good/frame_0001.pvtu" || true)
[ "$pieces" -eq "$np" ] || bad "frame_0001.pvtu lists $pieces pieces"
[ -f "$tmp/good/frame_0001_p$(printf %04d $((np - 1))).vtu" ] || bad "the last rank's piece is missing"

ranks implicit run "$src/examples/rubber_bunny_implicit.json" -o "$tmp/implicit" --threads 1
every_rank implicit 2
lines implicit '' 1
lines implicit 'implicit step.*does not run on ranks yet' 1

mkdir "$tmp/user"
echo "my numbers" >"$tmp/user/stats.csv"
ranks user run "$src/examples/jello_cubes.json" -o "$tmp/user" --frames 1 --threads 1
every_rank user 2
lines user '^mpm run: .*holds the files of a run' 1
[ "$(cat "$tmp/user/stats.csv")" = "my numbers" ] || bad "the user's stats.csv changed"
[ "$(ls "$tmp/user")" = "stats.csv" ] || bad "files were added to the user's folder: $(ls "$tmp/user")"

ranks resume run "$src/examples/jello_cubes.json" --resume "$tmp/good"
every_rank resume 2
lines resume '' 1

[ "$fail" -eq 0 ] && echo "run_cli on $np ranks: passed"
exit "$fail"
