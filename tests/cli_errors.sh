#!/usr/bin/env bash
# Bad input reaches the user as a clear message naming the culprit and a non-zero exit, never a crash.
set -u
bin=$1
tmp=$2
rm -rf "$tmp" && mkdir -p "$tmp"
failures=0
passes=0

expect_error() {  # expect_error NAME PATTERN COMMAND...
  local name=$1 pattern=$2
  shift 2
  local output status
  output=$("$@" 2>&1)
  status=$?
  if [ $status -ne 0 ] && [ $status -lt 128 ] && grep -qF -- "$pattern" <<<"$output"; then
    passes=$((passes + 1))
  else
    echo "FAIL $name: exit $status, output: $output"
    failures=$((failures + 1))
  fi
}

expect_error "run on a missing path" "$tmp/no/such/dataset.txt" "$bin" run "$tmp/no/such/dataset.txt" --out "$tmp/run"
"$bin" simulate "$tmp/seq" --frames 3 --resolution 64x48 >/dev/null
printf 'features:\n  num_featurez: 5\n' >"$tmp/bad_key.yaml"
expect_error "unknown config key" "features.num_featurez" "$bin" run "$tmp/seq/sequence.txt" --config "$tmp/bad_key.yaml" --out "$tmp/run"
printf 'matching:\n  ratio: 1.5\n' >"$tmp/bad_value.yaml"
expect_error "config value out of range" "matching.ratio" "$bin" run "$tmp/seq/sequence.txt" --config "$tmp/bad_value.yaml" --out "$tmp/run"
cp -r "$tmp/seq" "$tmp/seq_bad"
sed -i '2s/.*/1 2 3/' "$tmp/seq_bad/sequence.txt"
expect_error "malformed pose line" "sequence.txt:2: expected 9 numbers" "$bin" run "$tmp/seq_bad/sequence.txt" --out "$tmp/run"
expect_error "unknown subcommand option" "--frobnicate" "$bin" simulate "$tmp/x" --frobnicate
expect_error "bad resolution" "--resolution" "$bin" simulate "$tmp/x" --resolution 12by4
head -c 1000 /dev/urandom >"$tmp/garbage.gslmvoc"
printf 'loop_closure:\n  vocabulary: %s\n' "$tmp/garbage.gslmvoc" >"$tmp/bad_vocabulary.yaml"
expect_error "corrupt vocabulary" "garbage.gslmvoc: not a groundslam vocabulary file" "$bin" run "$tmp/seq/sequence.txt" --config "$tmp/bad_vocabulary.yaml" --out "$tmp/run"
expect_error "vocabulary from nothing" "nothing.txt" "$bin" vocabulary train "$tmp/seq/nothing.txt" -o "$tmp/v.gslmvoc"
expect_error "vocabulary into a missing folder, checked before training" "does not exist" "$bin" vocabulary train "$tmp/seq/images" -o "$tmp/no/such/folder/v.gslmvoc"
expect_error "run --start past the end" "leaves no frame" "$bin" run "$tmp/seq/sequence.txt" --start 100000 --out "$tmp/start_run"
expect_error "run a calibration that is not one" "not a calibration file" "$bin" run "$tmp/seq/sequence.txt" --calibration "$tmp/seq/camera.yaml" --out "$tmp/cal_run"
expect_error "run with both DATASET and --camera" "either DATASET or --camera" "$bin" run "$tmp/seq/sequence.txt" --camera 0 --out "$tmp/cam_run"
expect_error "evaluate a folder without ground truth" "groundtruth.tum" "$bin" evaluate "$tmp/seq/images"
mkdir -p "$tmp/user_folder" && echo notes >"$tmp/user_folder/notes.txt"
expect_error "simulate into a folder of other files" "holds no earlier simulation" "$bin" simulate "$tmp/user_folder" --frames 3
"$bin" run "$tmp/seq/sequence.txt" --out "$tmp/good_run" >/dev/null
expect_error "evaluate --json over an input" "is an input" "$bin" evaluate "$tmp/good_run/groundtruth.tum" "$tmp/good_run/trajectory.tum" --json "$tmp/good_run/trajectory.tum"
expect_error "config naming a folder" "not a configuration file" "$bin" run "$tmp/seq/sequence.txt" --config "$tmp/seq" --out "$tmp/run"
printf 'loop_closure:\n  vocabulary: no_such.gslmvoc\n' >"$tmp/missing_vocabulary.yaml"
expect_error "missing vocabulary names the key and the resolved path" "key 'loop_closure.vocabulary': $tmp/no_such.gslmvoc" "$bin" run "$tmp/seq/sequence.txt" --config "$tmp/missing_vocabulary.yaml" --out "$tmp/run"
for crafted in "$(cd "$(dirname "$0")" && pwd)"/data/vocabulary/*.gslmvoc; do
  case $crafted in *valid_*) continue ;; esac
  printf 'loop_closure:\n  vocabulary: %s\n' "$crafted" >"$tmp/crafted_vocabulary.yaml"
  expect_error "crafted vocabulary $(basename "$crafted")" "vocabulary file is inconsistent" "$bin" run "$tmp/seq/sequence.txt" --config "$tmp/crafted_vocabulary.yaml" --out "$tmp/run"
done
[ -d "$tmp/run" ] && [ -f "$tmp/run/trajectory.tum" ] && { echo "FAIL: a failed run left a trajectory"; failures=$((failures + 1)); }
echo "$passes passed, $failures failed"
[ $failures -eq 0 ]
