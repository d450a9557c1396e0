#!/usr/bin/env bash
# run.sh - run the libFuzzer targets of fuzz/ for a while each (`make fuzz`, `make test-fuzz`).
#
#   fuzz/run.sh BUILD_DIR SECONDS [TARGET ...]     TARGET: scene, obj, ply, checkpoint (default: all)
#
# Each target fuzz_T starts from a working corpus BUILD_DIR/corpus/T (the committed seeds of
# fuzz/corpus/T are copied in; what earlier runs found is kept there, and the seed folders are
# never written), with the dictionary fuzz/T.dict, for SECONDS seconds (-max_total_time). A
# crash, a sanitizer report (ASan, UBSan), a leak, an input slower than FUZZ_TIMEOUT seconds or
# more than FUZZ_RSS_MB MiB is a finding: the input is saved under BUILD_DIR/artifacts/ and the
# run fails once every target has had its turn. One line per target gives the executions run
# (libFuzzer's stat::number_of_executed_units); the full log is BUILD_DIR/logs/T.log.
set -uo pipefail
cd "$(dirname "$0")/.."
build=${1:?usage: fuzz/run.sh BUILD_DIR SECONDS [TARGET ...]}
seconds=${2:?usage: fuzz/run.sh BUILD_DIR SECONDS [TARGET ...]}
shift 2
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(scene obj ply checkpoint)
timeout_s=${FUZZ_TIMEOUT:-10}
rss_mb=${FUZZ_RSS_MB:-2048}

export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
mkdir -p "$build/artifacts" "$build/logs"
failed=()
for t in "${targets[@]}"; do
  bin=$build/fuzz/fuzz_$t
  if [ ! -x "$bin" ]; then
    echo "fuzz_$t: $bin is missing (build it with: make build-fuzz)"
    failed+=("$t")
    continue
  fi
  work=$build/corpus/$t
  mkdir -p "$work"
  cp -n fuzz/corpus/"$t"/* "$work"/ 2>/dev/null
  dict=()
  [ -f fuzz/"$t".dict ] && dict=(-dict=fuzz/"$t".dict)
  log=$build/logs/$t.log
  start=$(date +%s)
  "$bin" "$work" "${dict[@]}" -max_total_time="$seconds" -timeout="$timeout_s" \
    -rss_limit_mb="$rss_mb" -print_final_stats=1 -artifact_prefix="$build/artifacts/$t-" \
    </dev/null >"$log" 2>&1
  rc=$?
  secs=$(($(date +%s) - start))
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
  inputs=$(ls "$work" | wc -l)
  if [ $rc -eq 0 ]; then
    echo "fuzz_$t: ${execs:-?} executions in ${secs} s, corpus of $inputs inputs: no finding"
  else
    echo "fuzz_$t: FAILED (exit $rc) after ${execs:-?} executions in ${secs} s; log $log"
    grep -E '^(==[0-9]+==ERROR|SUMMARY|.*runtime error)|^artifact_prefix|Test unit written' "$log" |
      head -n 8 | sed 's/^/  /'
    failed+=("$t")
  fi
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzzing found problems in: ${failed[*]} (inputs in $build/artifacts/; reproduce with"
  echo "  $build/fuzz/fuzz_TARGET $build/artifacts/FILE)"
  exit 1
fi
