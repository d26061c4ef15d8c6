#!/usr/bin/env bash
# `groundslam run --report` and `groundslam report`: every figure is drawn, the page shows them in a real
# headless browser (Debian's chromium), runs without ground truth leave figures out with a reason, and a
# malformed run file is named.
set -u
bin=$1
tmp=$2
rm -rf "$tmp" && mkdir -p "$tmp"
passes=0
failures=0
check() {  # check NAME CONDITION-EXIT-STATUS [DETAIL]
  if [ "$2" -eq 0 ]; then passes=$((passes + 1)); else echo "FAIL $1 ${3:-}"; failures=$((failures + 1)); fi
}

"$bin" simulate "$tmp/seq" --frames 90 --laps 2 --path loop --seed 4 >/dev/null
"$bin" run "$tmp/seq/sequence.txt" --out "$tmp/run" --report >"$tmp/run.log" 2>&1
check "run --report exits 0" $? "$(tail -5 "$tmp/run.log")"
for figure in trajectory loop_closures threshold_scores loop_accuracy time errors; do
  [ -s "$tmp/run/report/$figure.png" ]
  check "figure $figure.png drawn" $?
done
[ -f "$tmp/run/odometry/trajectory.tum" ]
check "odometry-only comparison run written" $?

# The page in a real browser: every figure loaded with a non-zero size, the metrics table present.
browser=$(command -v chromium || command -v chromium-browser || true)
if [ -n "$browser" ]; then
  dom=$("$browser" --headless --no-sandbox --disable-gpu --disable-quic --no-first-run --disable-background-networking \
    --disable-component-update --disable-sync --user-data-dir="$tmp/profile" --virtual-time-budget=5000 \
    --dump-dom "file://$(realpath "$tmp/run/report.html")" 2>/dev/null)
  grep -q 'data-figures-shown="6"' <<<"$dom"
  check "browser shows all 6 figures" $? "$(grep -o 'data-figures-[a-z]*="[0-9]*"' <<<"$dom" | tr '\n' ' ')"
  grep -q '<table id="metrics">' <<<"$dom" && grep -q 'translational MAE (cm/m)' <<<"$dom"
  check "browser shows the metrics table" $?
  grep -Eq 'src="(https?:)?//' "$tmp/run/report.html"
  [ $? -ne 0 ]
  check "page loads nothing from the network" $?
else
  echo "FAIL chromium is not installed (make deps installs it)"
  failures=$((failures + 1))
fi

# Without ground truth: an image folder. Ground-truth figures are left out, each with a line saying why.
mkdir -p "$tmp/folder" && cp "$tmp/seq/images/"*.png "$tmp/folder/" && cp "$tmp/seq/camera.yaml" "$tmp/folder/"
"$bin" run "$tmp/folder" --out "$tmp/run_nogt" >/dev/null 2>&1
"$bin" report "$tmp/run_nogt" >"$tmp/nogt.log" 2>&1
check "report without ground truth exits 0" $? "$(cat "$tmp/nogt.log")"
grep -q "left out: 6. Error over the run: the dataset has no ground truth." "$tmp/nogt.log"
check "error figure left out with a reason" $?
grep -q "Figures left out" "$tmp/run_nogt/report.html"
check "the page lists what was left out" $?

# Bad input is named.
cp -r "$tmp/run" "$tmp/broken"
sed -i '3s/.*/1,1,xx,1,1,ok,1,1,1,1,1,1,1,1/' "$tmp/broken/frames.csv"
out=$("$bin" report "$tmp/broken" 2>&1)
status=$?
[ $status -ne 0 ] && grep -q "broken/frames.csv:3" <<<"$out"
check "malformed frames.csv is named" $? "$out"
rm "$tmp/broken/trajectory.tum"
out=$("$bin" report "$tmp/broken" 2>&1)
[ $? -ne 0 ] && grep -q "broken/trajectory.tum: no such file" <<<"$out"
check "missing trajectory.tum is named" $? "$out"

echo "$passes passed, $failures failed"
[ $failures -eq 0 ]
