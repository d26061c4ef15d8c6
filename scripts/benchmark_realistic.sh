#!/usr/bin/env bash
# Speed on realistic HD images (issue #14): 1600x1200 sequences with sensor noise 2, 4 and 8 grey levels,
# motion blur, vignetting and mount rocking, on a procedural texture (asphalt) and on a photo of a real
# surface (gravel, from Debian's python3-skimage), as PNG and, for noise 4, as JPEG (quality 95). For each:
# the reference floor (decode + OpenCV's default ORB, one thread), groundslam's own extraction floor, and the
# full `groundslam run` (wall clock, start to exit, loop closure on) with its accuracy against ground truth.
# Usage: scripts/benchmark_realistic.sh [BIN] [FRAMES=300] [OUT_TABLE=runs/benchmark_realistic.md]
set -euo pipefail
bin=${1:-build/groundslam}
frames=${2:-300}
table=${3:-runs/benchmark_realistic.md}
photo=/usr/lib/python3/dist-packages/skimage/data/gravel.png
if [ ! -f "$photo" ]; then
  echo "the photo texture comes with Debian's python3-skimage: apt-get install python3-skimage" >&2
  exit 1
fi
mkdir -p "$(dirname "$table")"
echo "| texture | noise | format | reference floor ms | extraction floor ms | frames/s | ms/frame | full/reference | cm/m | heading ° | ATE mm | not ok | wrong loops | peak MB |" > "$table"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|" >> "$table"
for texture in asphalt gravel; do
  for case in 2:png 4:png 8:png 4:jpg; do
    noise=${case%%:*}; format=${case##*:}
    data=data/benchmark_realistic/${texture}_n${noise}_${format}_$frames
    run=runs/benchmark_realistic/${texture}_n${noise}_${format}_$frames
    if [ ! -f "$data/sequence.txt" ]; then
      if [ "$texture" = gravel ]; then
        ground=(--texture "$photo" --texture-width-m 0.6 --step-m 0.004)
      else
        ground=(--texture-kind asphalt --step-m 0.01)
      fi
      "$bin" simulate "$data" "${ground[@]}" --resolution 1600x1200 --frames "$frames" --path loop --laps 2 \
        --jitter-deg 0.3 --motion-blur 0.3 --vignetting 0.3 --noise "$noise" --seed 21 --image-format "$format" >/dev/null
    fi
    floor=$("$bin" floor "$data/sequence.txt")
    reference_ms=$(echo "$floor" | sed -n 's/^floor.* \([0-9.]*\) ms\/frame.*/\1/p')
    extraction_ms=$(echo "$floor" | sed -n 's/^groundslam extraction.* \([0-9.]*\) ms\/frame.*/\1/p')
    rm -rf "$run"; mkdir -p "$(dirname "$run")"
    start=$(date +%s.%N)
    /usr/bin/time -f "%M" -o /tmp/groundslam_peak_kb "$bin" run "$data/sequence.txt" --out "$run" > "$run.log" 2>&1
    end=$(date +%s.%N)
    /usr/bin/python3 - "$run" "$start" "$end" "$reference_ms" "$extraction_ms" "$(cat /tmp/groundslam_peak_kb)" \
      "$texture" "$noise" "$format" >> "$table" <<'PY'
import csv, json, sys
run, start, end, reference_ms, extraction_ms, peak_kb, texture, noise, fmt = sys.argv[1:]
rows = list(csv.DictReader(open(f"{run}/frames.csv")))
wall = float(end) - float(start)
ms = 1000.0 * wall / len(rows)
m = json.load(open(f"{run}/metrics.json"))
lost = sum(1 for r in rows if r["status"] not in ("ok", "first"))
print(f"| {texture} | {noise} | {fmt} | {float(reference_ms):.1f} | {float(extraction_ms):.1f} | {len(rows) / wall:.1f} | {ms:.1f} | "
      f"{ms / float(reference_ms):.2f} | {m['translation_mae_cm_per_m']:.3f} | {m['rotation_mae_deg']:.3f} | {1000 * m['ate_rmse_m']:.2f} | {lost} | "
      f"{m['loop_closure']['wrong_accepted']} | {float(peak_kb) / 1024:.0f} |")
PY
    tail -1 "$table"
  done
done
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs); table in $table"
