#!/usr/bin/env bash
# Simulates every texture kind on every path with the standard perturbations (mount jitter, motion and
# defocus blur, noise, exposure changes, vignetting, wet ground after 60%), runs groundslam on each and
# prints one table row per sequence. Usage: scripts/texture_matrix.sh [BIN] [OUT] [EXTRA RUN ARGS...]
set -euo pipefail
bin=${1:-build/groundslam}
out=${2:-data/matrix}
shift 2 || true
frames=${FRAMES:-400}
kinds=${KINDS:-"asphalt concrete carpet tiles"}
paths=${PATHS_:-"loop lawnmower random_walk"}
printf "%-10s %-12s %8s %9s %9s %9s %9s %9s %9s\n" texture path frames fallback "cm/m" "rot_deg" "ate_mm" "rpe_mm" "rpe_deg"
for kind in $kinds; do
  for path in $paths; do
    seq="$out/${kind}_${path}"
    if [ ! -f "$seq/sequence.txt" ]; then
      "$bin" simulate "$seq" --texture-kind "$kind" --path "$path" --frames "$frames" --laps 2 \
        --jitter-deg 0.5 --motion-blur 0.3 --defocus-px 0.6 --noise 2 --exposure-variation 0.15 \
        --vignetting 0.2 --wet-after 0.6 --seed 11 >/dev/null
    fi
    run="$out/runs/${kind}_${path}"
    "$bin" run "$seq/sequence.txt" --out "$run" "$@" >/dev/null
    fallback=$(grep -c ",fallback" "$run/frames.csv" || true)
    /usr/bin/python3 - "$run/metrics.json" "$kind" "$path" "$fallback" <<'PY'
import json, sys
m = json.load(open(sys.argv[1]))
print(f"{sys.argv[2]:<10} {sys.argv[3]:<12} {m['paired_frames']:>8} {sys.argv[4]:>9} {m['translation_mae_cm_per_m']:>9.3f} "
      f"{m['rotation_mae_deg']:>9.3f} {1000*m['ate_rmse_m']:>9.2f} {1000*m['rpe_translation_rmse_m']:>9.3f} "
      f"{m['rpe_rotation_rmse_deg']:>9.4f}")
PY
  done
done
