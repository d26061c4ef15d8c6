#!/usr/bin/env bash
# The extraction choices of issue #14 measured side by side on the realistic HD sequences that
# scripts/benchmark_realistic.sh simulates (run it first): for each choice, groundslam's own extraction floor
# (decode + ORB, one thread), the full run's frames/s and its accuracy against ground truth.
# Usage: scripts/extraction_choices.sh [BIN] [FRAMES=300] [OUT_TABLE=runs/extraction_choices.md]
set -euo pipefail
bin=${1:-build/groundslam}
frames=${2:-300}
table=${3:-runs/extraction_choices.md}
choices=(
  "reduced to 800 px wide (default)|"
  "full resolution|max_extraction_width: 0"
  "reduced to 534 px wide (factor 3)|max_extraction_width: 534"
  "800 px, 3 pyramid levels|num_levels: 3"
  "800 px, FAST threshold 10|fast_threshold: 10"
)
mkdir -p "$(dirname "$table")" runs/extraction_choices
echo "| sequence | extraction | extraction floor ms | frames/s | cm/m | heading ° | ATE mm | not ok |" > "$table"
echo "|---|---|---|---|---|---|---|---|" >> "$table"
for sequence in asphalt_n4_png gravel_n4_png asphalt_n8_png; do
  data=data/benchmark_realistic/${sequence}_$frames
  [ -f "$data/sequence.txt" ] || { echo "$data: run scripts/benchmark_realistic.sh first" >&2; exit 1; }
  for i in "${!choices[@]}"; do
    label=${choices[$i]%%|*}; key=${choices[$i]#*|}
    config=runs/extraction_choices/choice_$i.yaml
    if [ -n "$key" ]; then printf 'features:\n  %s\n' "$key" > "$config"; else printf '{}\n' > "$config"; fi
    floor_ms=$("$bin" floor "$data/sequence.txt" --config "$config" | sed -n 's/^groundslam extraction.* \([0-9.]*\) ms\/frame.*/\1/p')
    run=runs/extraction_choices/${sequence}_$i
    rm -rf "$run"
    start=$(date +%s.%N)
    "$bin" run "$data/sequence.txt" --config "$config" --out "$run" > "$run.log" 2>&1
    end=$(date +%s.%N)
    /usr/bin/python3 - "$run" "$start" "$end" "$floor_ms" "$sequence" "$label" >> "$table" <<'PY'
import csv, json, sys
run, start, end, floor_ms, sequence, label = sys.argv[1:]
rows = list(csv.DictReader(open(f"{run}/frames.csv")))
m = json.load(open(f"{run}/metrics.json"))
not_ok = sum(1 for r in rows if r["status"] not in ("ok", "first"))
print(f"| {sequence} | {label} | {float(floor_ms):.1f} | {len(rows) / (float(end) - float(start)):.1f} | "
      f"{m['translation_mae_cm_per_m']:.3f} | {m['rotation_mae_deg']:.3f} | {1000 * m['ate_rmse_m']:.2f} | {not_ok} |")
PY
    tail -1 "$table"
  done
done
