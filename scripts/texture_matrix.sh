#!/usr/bin/env bash
# Simulates every texture kind on every path with the standard perturbations (mount jitter 0.5 deg,
# motion and defocus blur, noise, exposure changes, vignetting, wet ground after 60% of the path), runs
# groundslam on each twice (full SLAM and --no-loop-closure) and prints a markdown table row per sequence.
# Usage: scripts/texture_matrix.sh [BIN] [OUT] [EXTRA RUN ARGS...]   (env: FRAMES, KINDS, PATHS_)
set -euo pipefail
bin=${1:-build/groundslam}
out=${2:-data/matrix}
shift 2 || true
frames=${FRAMES:-400}
kinds=${KINDS:-"asphalt concrete carpet tiles"}
paths=${PATHS_:-"loop lawnmower random_walk"}
echo "| texture | path | frames | odometry cm/m | odometry deg | SLAM cm/m | SLAM deg | SLAM ATE mm | loops accepted | wrong | precision | recall | fallback or lost frames |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|"
for kind in $kinds; do
  for path in $paths; do
    seq="$out/${kind}_${path}"
    if [ ! -f "$seq/sequence.txt" ]; then
      "$bin" simulate "$seq" --texture-kind "$kind" --path "$path" --frames "$frames" --laps 2 \
        --jitter-deg 0.5 --motion-blur 0.3 --defocus-px 0.6 --noise 2 --exposure-variation 0.15 \
        --vignetting 0.2 --wet-after 0.6 --seed 11 >/dev/null
    fi
    "$bin" run "$seq/sequence.txt" --out "$out/runs/${kind}_${path}" "$@" >/dev/null
    "$bin" run "$seq/sequence.txt" --out "$out/runs/${kind}_${path}_odometry" --no-loop-closure "$@" >/dev/null
    fallback=$(grep -cE ",(fallback|lost)" "$out/runs/${kind}_${path}/frames.csv" || true)
    /usr/bin/python3 - "$out/runs/${kind}_${path}" "$kind" "$path" "$fallback" <<'PY'
import json, sys
run, kind, path, fallback = sys.argv[1:5]
m = json.load(open(run + "/metrics.json"))
o = json.load(open(run + "_odometry/metrics.json"))
l = m["loop_closure"]
print(f"| {kind} | {path} | {m['paired_frames']} | {o['translation_mae_cm_per_m']:.3f} | {o['rotation_mae_deg']:.3f} | "
      f"{m['translation_mae_cm_per_m']:.3f} | {m['rotation_mae_deg']:.3f} | {1000 * m['ate_rmse_m']:.2f} | "
      f"{l['accepted']} | {l['wrong_accepted']} | {l['precision']:.3f} | {l['recall']:.3f} | {fallback} |")
PY
  done
done
