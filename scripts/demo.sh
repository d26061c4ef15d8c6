#!/usr/bin/env bash
# `make demo`: simulate a sequence with revisits, run groundslam on it, print where the results are.
set -euo pipefail
bin=${1:-build/groundslam}
data=data/demo
run=runs/demo

echo "== simulating a 400-frame asphalt loop driven twice (mount jitter, blur, noise, exposure changes) =="
"$bin" simulate "$data" --texture-kind asphalt --path loop --laps 2 --frames 400 \
  --jitter-deg 0.5 --motion-blur 0.3 --defocus-px 0.6 --noise 2 --exposure-variation 0.15 --vignetting 0.2 --seed 7

echo "== running groundslam =="
"$bin" run "$data/sequence.txt" --out "$run" --report

echo
echo "results in $run/:"
ls -1 "$run"
echo
echo "open $run/report.html in a browser for the figures (trajectory, loop closures, threshold scores, time, error)."
