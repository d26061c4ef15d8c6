#!/usr/bin/env bash
# Runs every libFuzzer target of BUILD_DIR (built by `make fuzz`) for SECONDS each, starting from the seed
# corpus in tests/data/fuzz/<target>/. New corpus entries and crash inputs go to WORK_DIR/<target>/
# (git-ignored), never into the repository. Prints runs, coverage and findings per target; exits non-zero
# when any target crashed, hung (-timeout) or ran out of memory (-rss_limit_mb).
#   scripts/fuzz.sh build-fuzz 60 fuzz-work
set -uo pipefail
build=${1:-build-fuzz}
seconds=${2:-60}
work=${3:-fuzz-work}
root=$(cd "$(dirname "$0")/.." && pwd)
targets=(hd_ground_list tum config_yaml vocabulary map)

failed=()
summary=()
for target in "${targets[@]}"; do
  fuzzer="$build/fuzz/fuzz_$target"
  dir="$work/$target"
  mkdir -p "$dir/corpus" "$dir/artifacts"
  rm -f "$dir/artifacts/"*
  cp -n "$root/tests/data/fuzz/$target/"* "$dir/corpus/" 2>/dev/null
  echo "== fuzz_$target: ${seconds}s, corpus $dir/corpus"
  # Fork mode: a crash, timeout or out-of-memory input is saved and fuzzing goes on, so that one known bug
  # (e.g. a crash input already saved under tests/data/fuzz/) does not hide the others.
  "$fuzzer" "$dir/corpus" -fork=1 -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1 \
    -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -artifact_prefix="$dir/artifacts/" >"$dir/fuzz.log" 2>&1
  status=$?
  last=$(grep -E '^#[0-9]+: cov:' "$dir/fuzz.log" | tail -1)
  runs=$(grep -oE '^#[0-9]+' <<<"$last" | tr -d '#')
  cov=$(grep -oE 'cov: [0-9]+' <<<"$last" | grep -oE '[0-9]+')
  ft=$(grep -oE 'ft: [0-9]+' <<<"$last" | grep -oE '[0-9]+')
  corpus=$(find "$dir/corpus" -type f | wc -l)
  findings=$(find "$dir/artifacts" -type f | wc -l)
  line="fuzz_$target: runs ${runs:-?}, cov ${cov:-?}, ft ${ft:-?}, corpus $corpus files, findings $findings"
  summary+=("$line")
  if [ "$findings" -ne 0 ]; then
    failed+=("$target")
    echo "FAIL $line; distinct problems (count, first report line, first project frame):"
    # Replay each finding alone and group them by what went wrong and where.
    find "$dir/artifacts" -type f | head -100 | while read -r finding; do
      "$fuzzer" -timeout=10 -rss_limit_mb=2048 "$finding" >"$dir/replay.log" 2>&1
      what=$(grep -m1 -E 'runtime error|ERROR: (AddressSanitizer|LeakSanitizer|libFuzzer)|what\(\)' "$dir/replay.log" |
        sed -E 's/line [0-9]+, column [0-9]+/line L/; s/==[0-9]+==//; s/0x[0-9a-f]+//g')
      frame=$(grep -m1 -E '^ *#[0-9]+ .*(cpp/groundslam|apps/)' "$dir/replay.log" | grep -oE '[^ /]+\.(cpp|hpp):[0-9]+')
      printf '%s | %s | %s\n' "${what:-no report on replay}" "${frame:-?}" "$finding"
    done | sort | awk -F' [|] ' '{key=$1" | "$2; n[key]++; if (!(key in ex)) ex[key]=$3} END {for (k in n) printf "  %d x %s (e.g. %s)\n", n[k], k, ex[k]}'
    echo "  log: $dir/fuzz.log"
  elif [ "$status" -ne 0 ]; then
    failed+=("$target")
    echo "FAIL $line: fuzzer exited with $status, see $dir/fuzz.log"
  fi
done

echo "== fuzz summary (${seconds}s per target)"
printf '%s\n' "${summary[@]}"
if [ ${#failed[@]} -ne 0 ]; then
  echo "fuzzing found problems in: ${failed[*]} (copy the finding into tests/data/fuzz/<target>/ as a regression input)" >&2
  exit 1
fi
