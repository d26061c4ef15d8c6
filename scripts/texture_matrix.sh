#!/usr/bin/env bash
# Simulates every texture kind on every path with the standard perturbations (mount jitter 0.5 deg,
# motion and defocus blur, noise, exposure changes, vignetting, wet ground after 60% of the path), runs
# groundslam on each twice (full SLAM and --no-loop-closure) and prints a markdown table row per sequence.
# CONDITION=outdoor adds what an outdoor robot sees: its own shadow, lens dirt, glare, a part of the robot in
# view, 2 mm height jitter, 90-degree turns on the spot every 80 frames and dropped frames.
# KINDS may also name photos of real floors (a path to an image, e.g. scikit-image's gravel.png from Debian's
# python3-skimage): each is laid PHOTO_WIDTH_M wide (0.6) and, as in docs/accuracy.md, rendered without wet ground.
# Usage: scripts/texture_matrix.sh [BIN] [OUT] [EXTRA RUN ARGS...]
#        (env: FRAMES, KINDS, PATHS_, SEED, PATH_SEED, CONDITION, PHOTO_WIDTH_M; RUNS: the runs folder inside OUT, runs)
set -euo pipefail
bin=${1:-build/groundslam}
out=${2:-data/matrix}
shift 2 || true
frames=${FRAMES:-400}
kinds=${KINDS:-"asphalt concrete carpet tiles"}
paths=${PATHS_:-"loop lawnmower random_walk"}
seed=${SEED:-11}
path_seed=${PATH_SEED:-1}  # the random walk's turns (simulate --path-seed); 1: the walk of every documented table
condition=${CONDITION:-standard}
runs=${RUNS:-runs}
here=$(cd "$(dirname "$0")" && pwd)
case "$condition" in
  standard) extra_sim=() ;;
  outdoor) extra_sim=(--shadow 0.6 --lens-dirt 6 --glare 0.8 --bumper 0.15 --height-jitter-m 0.002 --spin-every 80
                      --spin-deg 90 --drop-frames 0.01 --drop-max 6) ;;
  outdoor_heavy) extra_sim=(--shadow 0.8 --lens-dirt 10 --glare 1.2 --bumper 0.25 --height-jitter-m 0.003 --spin-every 50
                            --spin-deg 75 --drop-frames 0.02 --drop-max 8) ;;
  *) echo "unknown CONDITION '$condition' (standard | outdoor | outdoor_heavy)" >&2; exit 2 ;;
esac
echo "| texture | path | frames | odometry cm/m | odometry deg | SLAM cm/m | SLAM deg | SLAM ATE mm | loops accepted | wrong | precision | recall | fallback or lost frames | wrong ok motions | low-overlap frames (off) | sharp-turn and gap frames (off) | aligned frames (off) | unconfirmed frames (off) | uncertain frames (off) | tilt error deg | wrong bridge or loop edges (of all) |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
for texture in $kinds; do
  if [ -f "$texture" ]; then
    kind=$(basename "${texture%.*}")
    texture_sim=(--texture "$texture" --texture-width-m "${PHOTO_WIDTH_M:-0.6}")
  else
    kind=$texture
    texture_sim=(--texture-kind "$kind" --wet-after 0.6)
  fi
  for path in $paths; do
    seq="$out/${kind}_${path}"
    if [ ! -f "$seq/sequence.txt" ]; then
      "$bin" simulate "$seq" "${texture_sim[@]}" --path "$path" --frames "$frames" --laps 2 \
        --jitter-deg 0.5 --motion-blur 0.3 --defocus-px 0.6 --noise 2 --exposure-variation 0.15 \
        --vignetting 0.2 --seed "$seed" --path-seed "$path_seed" "${extra_sim[@]}" >/dev/null
    fi
    "$bin" run "$seq/sequence.txt" --out "$out/$runs/${kind}_${path}" "$@" >/dev/null
    "$bin" run "$seq/sequence.txt" --out "$out/$runs/${kind}_${path}_odometry" --no-loop-closure "$@" >/dev/null
    fallback=$(grep -cE ",(fallback|lost)" "$out/$runs/${kind}_${path}/frames.csv" || true)
    motion="{}"
    if [ -f "$seq/mount.csv" ]; then motion=$(/usr/bin/python3 "$here/motion_check.py" "$out/$runs/${kind}_${path}" "$seq" --json); fi
    /usr/bin/python3 - "$out/$runs/${kind}_${path}" "$kind" "$path" "$fallback" "$motion" <<'PY'
import json, sys
run, kind, path, fallback, motion = sys.argv[1:6]
m = json.load(open(run + "/metrics.json"))
o = json.load(open(run + "_odometry/metrics.json"))
c = json.loads(motion)
l = m["loop_closure"]
wrong = c.get("silent_wrong_motions", "n/a")
low = f"{c['low_overlap_frames']} ({c['low_overlap_off']})" if "low_overlap_frames" in c else "n/a"  # off: > 5 mm or 0.5 deg
turns = (f"{c['sharp_turn_frames']} + {c['gap_frames']} ({c['sharp_turn_off']} + {c['gap_off']})"
         if "sharp_turn_frames" in c else "n/a")
aligned = f"{c['aligned_frames']} ({c['aligned_off']})" if "aligned_frames" in c else "n/a"
unconfirmed = f"{c['unconfirmed_frames']} ({c['unconfirmed_off']})" if "unconfirmed_frames" in c else "n/a"
uncertain = f"{c['uncertain_frames']} ({c['uncertain_off']})" if "uncertain_frames" in c else "n/a"
tilt = c.get("tilt_rms_error_deg")
tilt = f"{tilt:.2f} of {c['tilt_rms_true_deg']:.2f}" if isinstance(tilt, float) and tilt == tilt else "n/a"
edges = f"{c['wrong_graph_edges']} of {c['graph_edges_checked']}" if "wrong_graph_edges" in c else "n/a"
ratio = lambda v: "n/a" if v is None else f"{v:.3f}"  # null: nothing accepted (precision) or nothing true (recall)
print(f"| {kind} | {path} | {m['paired_frames']} | {o['translation_mae_cm_per_m']:.3f} | {o['rotation_mae_deg']:.3f} | "
      f"{m['translation_mae_cm_per_m']:.3f} | {m['rotation_mae_deg']:.3f} | {1000 * m['ate_rmse_m']:.2f} | "
      f"{l['accepted']} | {l['wrong_accepted']} | {ratio(l['precision'])} | {ratio(l['recall'])} | {fallback} | {wrong} | {low} | {turns} | {aligned} | {unconfirmed} | {uncertain} | {tilt} | {edges} |")
PY
  done
done
