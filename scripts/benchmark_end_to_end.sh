#!/usr/bin/env bash
# End-to-end speed: one simulated sequence (PNG files on disk, a loop driven twice so loop closures happen),
# measured in one go: the reference floor (decode + OpenCV's default ORB, one thread), groundslam's own
# extraction floor (decode + ORB as configured, one thread) and the full `groundslam run`, wall clock from
# start to exit. Prints frames/s, full/floor, per-stage medians and peak memory.
# Usage: scripts/benchmark_end_to_end.sh [BIN] [FRAMES=300] [RESOLUTION=1600x1200]
# (scripts/benchmark_realistic.sh measures the same on noisier images, a photo texture and JPEG files.)
set -euo pipefail
bin=${1:-build/groundslam}
frames=${2:-300}
resolution=${3:-1600x1200}
if [ "$resolution" = 1600x1200 ]; then
  data=data/benchmark_hd_$frames; run=runs/benchmark_hd_$frames  # the name earlier results were recorded under
else
  data=data/benchmark_${resolution}_$frames; run=runs/benchmark_${resolution}_$frames
fi
if [ ! -f "$data/sequence.txt" ]; then
  "$bin" simulate "$data" --resolution "$resolution" --frames "$frames" --path loop --laps 2 --step-m 0.01 \
    --jitter-deg 0.3 --motion-blur 0.3 --noise 2 --seed 21 >/dev/null
fi
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)"
"$bin" floor "$data/sequence.txt" | tee /tmp/groundslam_floor.txt
reference_ms=$(sed -n 's/^floor.* \([0-9.]*\) ms\/frame.*/\1/p' /tmp/groundslam_floor.txt)
extraction_ms=$(sed -n 's/^groundslam extraction.* \([0-9.]*\) ms\/frame.*/\1/p' /tmp/groundslam_floor.txt)
rm -rf "$run"
start=$(date +%s.%N)
/usr/bin/time -f "%M" -o /tmp/groundslam_peak_kb "$bin" run "$data/sequence.txt" --out "$run" >/dev/null
end=$(date +%s.%N)
/usr/bin/python3 - "$run/frames.csv" "$start" "$end" "$reference_ms" "$extraction_ms" "$(cat /tmp/groundslam_peak_kb)" <<'PY'
import csv, statistics, sys
rows = list(csv.DictReader(open(sys.argv[1])))
wall = float(sys.argv[3]) - float(sys.argv[2])
reference_ms, extraction_ms, peak_kb = float(sys.argv[4]), float(sys.argv[5]), float(sys.argv[6])
full_ms = 1000.0 * wall / len(rows)
print(f"full run: {len(rows)} frames in {wall:.2f} s wall clock: {len(rows) / wall:.2f} frames/s, {full_ms:.1f} ms/frame")
print(f"full / reference floor: {full_ms / reference_ms:.2f}; full / own extraction floor: {full_ms / extraction_ms:.2f}")
stages = ["load_ms", "extract_ms", "project_ms", "match_ms", "fit_ms", "loop_ms", "optimise_ms", "total_ms"]
print("per-stage medians (ms): " + ", ".join(f"{s[:-3]} {statistics.median(float(r[s]) for r in rows):.2f}" for s in stages))
print(f"loop closures: {sum(1 for _ in open(sys.argv[1].replace('frames.csv', 'loop_closures.csv'))) - 1}")
print(f"peak memory: {peak_kb / 1024:.0f} MB")
PY
