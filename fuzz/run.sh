#!/usr/bin/env bash
# Runs the libFuzzer targets of a sanitizer build (normally through `./dev fuzz`).
#
#   bash fuzz/run.sh --build DIR [TARGET] [--seconds N] [--jobs J] [--seed S]
#
# Each target fuzzes for N seconds (default 60), J targets at a time (default 2), starting from
# its committed seed corpus fuzz/corpus/<target>/ plus a working corpus that grows in
# DIR/fuzz/work/<target>/ (never in the repository). Logs go to DIR/fuzz/logs/<target>.log;
# a crash, hang (> 10 s) or out-of-memory (> 2 GB) input is written to DIR/fuzz/artifacts/.
# --seed S fixes libFuzzer's random seed, so that a run from the committed corpora tries the same
# inputs on every machine (CI's smoke run); without it every run explores afresh.
# Prints per target the executions and whether it found anything; exits non-zero when any
# target found something, naming the input file. Reproduce with: DIR/fuzz/fuzz_<target> FILE
set -uo pipefail

build=""
target=""
seconds=60
jobs=2
seed=""
while [ $# -gt 0 ]; do
  case "$1" in
    --build) build="$2"; shift 2 ;;
    --seconds) seconds="$2"; shift 2 ;;
    --jobs) jobs="$2"; shift 2 ;;
    --seed) seed="$2"; shift 2 ;;
    -h|--help) sed -n '2,13p' "$0"; exit 0 ;;
    -*) echo "fuzz/run.sh: unknown option $1" >&2; exit 2 ;;
    *) target="$1"; shift ;;
  esac
done
if [ -z "$build" ]; then
  echo "usage: fuzz/run.sh --build DIR [TARGET] [--seconds N] [--jobs J]" >&2
  exit 2
fi
list="$build/fuzz/targets.txt"
if [ ! -f "$list" ]; then
  echo "fuzz/run.sh: $list not found: configure $build with clang and -DCONFLUENT_SANITIZE=ON" >&2
  exit 2
fi
case "$seconds" in ''|*[!0-9]*) echo "fuzz/run.sh: --seconds needs a whole number" >&2; exit 2 ;; esac
case "$seed" in *[!0-9]*) echo "fuzz/run.sh: --seed needs a whole number" >&2; exit 2 ;; esac

names=()
declare -A max_len corpus
while read -r name len dir; do
  [ -n "$name" ] || continue
  names+=("$name")
  max_len[$name]=$len
  corpus[$name]=$dir
done <"$list"
if [ -n "$target" ]; then
  target="${target#fuzz_}"
  if [ -z "${max_len[$target]+x}" ]; then
    echo "fuzz/run.sh: unknown target '$target'; the targets are:" >&2
    printf '  %s\n' "${names[@]}" >&2
    exit 2
  fi
  names=("$target")
fi
for name in "${names[@]}"; do
  if [ ! -x "$build/fuzz/fuzz_$name" ]; then
    echo "fuzz/run.sh: $build/fuzz/fuzz_$name is not built (cmake --build $build --target fuzz_$name)" >&2
    exit 2
  fi
done

logs="$build/fuzz/logs"
artifacts="$build/fuzz/artifacts"
mkdir -p "$logs" "$artifacts"

# Fuzzes one target; its log ends with libFuzzer's "Done N runs in S second(s)" or a report.
fuzz_one() {
  local name="$1"
  local work="$build/fuzz/work/$name"
  mkdir -p "$work"
  "$build/fuzz/fuzz_$name" "$work" "${corpus[$name]}" \
    -max_total_time="$seconds" -max_len="${max_len[$name]}" -timeout=10 -rss_limit_mb=2048 \
    -artifact_prefix="$artifacts/$name-" -print_final_stats=1 ${seed:+-seed="$seed"} >"$logs/$name.log" 2>&1
  echo $? >"$logs/$name.rc"
}

echo "fuzzing ${#names[@]} target(s), ${seconds} s each, $jobs at a time; logs in $logs"
running=0
for name in "${names[@]}"; do
  rm -f "$logs/$name.rc"
  fuzz_one "$name" &
  running=$((running + 1))
  if [ "$running" -ge "$jobs" ]; then
    wait -n
    running=$((running - 1))
  fi
done
wait

failed=0
for name in "${names[@]}"; do
  log="$logs/$name.log"
  rc=$(cat "$logs/$name.rc" 2>/dev/null || echo "?")
  done_line=$(grep -o 'Done [0-9]* runs in [0-9]* second(s)' "$log" | tail -1)
  if [ "$rc" = 0 ]; then
    printf '%-16s ok       %s\n' "$name" "${done_line:-(no summary)}"
  else
    failed=1
    execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1)
    found=$(grep -o "Test unit written to [^ ]*" "$log" | tail -1 | sed 's/Test unit written to //')
    # The first report in the log: an escaping exception, a failed assertion, UBSan, ASan/LSan
    # or libFuzzer's own (deadly signal, timeout, out-of-memory).
    kind=$(grep -o -m1 "terminate called after throwing an instance of '[^']*'\|Assertion .* failed\|runtime error: .*\|ERROR: [A-Za-z]*: .*" "$log" | head -1 | cut -c1-200)
    printf '%-16s FOUND    after %s executions (exit %s): %s\n' "$name" "${execs:-?}" "$rc" "${kind:-see the log}"
    echo "                 input: ${found:-none written}; log: $log"
    [ -n "$found" ] && echo "                 reproduce: $build/fuzz/fuzz_$name $found"
  fi
done
if [ "$failed" != 0 ]; then
  echo "fuzz/run.sh: some targets found crashes, hangs or sanitizer reports (above)" >&2
  exit 1
fi
