#!/usr/bin/env bash
# Global localization on simulated sequences (issue: relocalization, map reuse). Two tables:
#  1. kidnapped robot: each texture and path with path frames GAP left out mid-run (the robot is carried
#     along its path and put down on ground it has mapped); when it relocalizes and the run's accuracy;
#  2. second session: a map from a lawnmower session, then another session (random walk, other seed, wet
#     look) over the same ground: `localize` (each image on its own) and `run --map`.
# Usage: scripts/localization_matrix.sh [BIN] [OUT] [SEED]   (env: KINDS, PATHS_, GAP, RESOLUTION, EXTRA)
set -euo pipefail
bin=${1:-build/groundslam}
out=${2:-data/localization}
seed=${3:-11}
kinds=${KINDS:-"asphalt concrete carpet tiles"}
paths=${PATHS_:-"loop random_walk"}
gap=${GAP:-250:330}
resolution=${RESOLUTION:-320x240}
base=(--jitter-deg 0.5 --motion-blur 0.3 --defocus-px 0.6 --noise 2 --exposure-variation 0.15 --vignetting 0.2)
look=("${base[@]}" ${EXTRA:-})  # EXTRA: more disturbances for the kidnapped runs and the first session
mkdir -p "$out"

echo "### Kidnapped robot (path frames $gap left out, seed $seed, $resolution)"
echo "| texture | path | frames | back on mapped ground after (frames) | relocalized after (frames) | lost frames | cm/m | deg | ATE mm | loops | wrong |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
for kind in $kinds; do
  for path in $paths; do
    seq="$out/gap_${kind}_${path}_$seed"
    [ -f "$seq/sequence.txt" ] || "$bin" simulate "$seq" --texture-kind "$kind" --path "$path" --frames 400 --laps 2 \
      --gap "$gap" --seed "$seed" --resolution "$resolution" "${look[@]}" >/dev/null
    "$bin" run "$seq/sequence.txt" --out "$out/runs/gap_${kind}_${path}_$seed" >/dev/null
    /usr/bin/python3 - "$out/runs/gap_${kind}_${path}_$seed" "$kind" "$path" "${gap%%:*}" <<'PY'
import csv, json, math, sys
run, kind, path, gap_start = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
rows = list(csv.DictReader(open(run + "/frames.csv")))
reloc = [int(r["index"]) for r in rows if r["status"] == "relocalized" and int(r["index"]) >= gap_start]
lost = sum(1 for r in rows if r["status"].startswith("lost"))  # lost_<reason>: the frame that lost tracking
m = json.load(open(run + "/metrics.json")); l = m["loop_closure"]
truth = {}
for line in open(run + "/groundtruth.tum"):
    v = line.split()
    if v: truth[int(round(float(v[0])))] = (float(v[1]), float(v[2]))
# Mapped ground: within 3 cm of where a frame before the gap was (its footprint is mostly on the map).
before = [p for i, p in truth.items() if i < gap_start]
back = next((i for i in sorted(truth) if i >= gap_start and min(math.hypot(truth[i][0] - p[0], truth[i][1] - p[1]) for p in before) < 0.03), None)
on_map = str(back - gap_start) if back is not None else "never"
after = str(reloc[0] - gap_start) if reloc else "never"
print(f"| {kind} | {path} | {len(rows)} | {on_map} | {after} | {lost} | {m['translation_mae_cm_per_m']:.3f} | {m['rotation_mae_deg']:.3f} | "
      f"{1000 * m['ate_rmse_m']:.2f} | {l['accepted']} | {l['wrong_accepted']} |")
PY
  done
done

echo
echo "### Second session on a map (ground seed $seed, $resolution): localize and run --map"
echo "| texture | map features | B per feature on disk | second-session images on mapped ground | localize: within 1 cm, 1 deg | off > 5 cm | median ms | run --map: frames within 1 cm, 1 deg |"
echo "|---|---|---|---|---|---|---|---|"
for kind in $kinds; do
  first="$out/first_${kind}_$seed"
  second="$out/second_${kind}_$seed"
  [ -f "$first/sequence.txt" ] || "$bin" simulate "$first" --texture-kind "$kind" --path lawnmower --frames 500 --lane-length-m 0.5 \
    --ground-seed "$seed" --ground-size-m 1.6 --seed "$seed" --resolution "$resolution" "${look[@]}" >/dev/null
  [ -f "$second/sequence.txt" ] || "$bin" simulate "$second" --texture-kind "$kind" --path random_walk --area-m 0.4 --frames 200 \
    --ground-seed "$seed" --ground-size-m 1.6 --seed $((seed + 1000)) --wet-after 0 --resolution "$resolution" "${base[@]}" >/dev/null
  "$bin" run "$first/sequence.txt" --out "$out/runs/first_${kind}_$seed" >/dev/null
  "$bin" localize "$out/runs/first_${kind}_$seed/map.gsmap" "$second/sequence.txt" --out "$out/runs/localize_${kind}_$seed" >/dev/null
  "$bin" run "$second/sequence.txt" --map "$out/runs/first_${kind}_$seed/map.gsmap" --out "$out/runs/second_${kind}_$seed" >/dev/null
  /usr/bin/python3 - "$out" "$kind" "$seed" <<'PY'
import csv, math, os, sys
out, kind, seed = sys.argv[1:4]
def tum(path):
    poses = {}
    for line in open(path):
        v = line.split()
        if v: poses[round(float(v[0]), 6)] = (float(v[1]), float(v[2]), 2 * math.atan2(float(v[6]), float(v[7])))
    return poses
first_truth = tum(f"{out}/first_{kind}_{seed}/groundtruth.tum")
truth = tum(f"{out}/second_{kind}_{seed}/groundtruth.tum")
ox, oy, oth = first_truth[min(first_truth)]  # the map frame: the first session's first pose
def in_world(p):
    x, y, th = p
    return (ox + math.cos(oth) * x - math.sin(oth) * y, oy + math.sin(oth) * x + math.cos(oth) * y, oth + th)
def error(t, p):
    w, g = in_world(p), truth[t]
    return math.hypot(w[0] - g[0], w[1] - g[1]), abs((w[2] - g[2] + math.pi) % (2 * math.pi) - math.pi) * 180 / math.pi
mapped = [p for p in first_truth.values()]
on_map = {t for t, g in truth.items() if min(math.hypot(g[0] - m[0], g[1] - m[1]) for m in mapped) < 0.05}
rows = list(csv.DictReader(open(f"{out}/runs/localize_{kind}_{seed}/localizations.csv")))
ok = {round(float(r["timestamp"]), 6): (float(r["x"]), float(r["y"]), float(r["theta"])) for r in rows if r["status"] == "localized"}
good = sum(1 for t in on_map if t in ok and error(t, ok[t])[0] <= 0.01 and error(t, ok[t])[1] <= 1.0)
off = sum(1 for t, p in ok.items() if error(t, p)[0] > 0.05)
ms = sorted(float(r["ms"]) for r in rows)
track = tum(f"{out}/runs/second_{kind}_{seed}/trajectory.tum")
tracked = sum(1 for t, p in track.items() if error(t, p)[0] <= 0.01 and error(t, p)[1] <= 1.0)
size = os.path.getsize(f"{out}/runs/first_{kind}_{seed}/map.gsmap")
features = (size - 28) // 49  # upper bound; keyframes are 32 B each
print(f"| {kind} | ~{features} | 49 | {len(on_map)} of {len(truth)} | {good} ({100 * good / max(1, len(on_map)):.1f}%) | {off} | "
      f"{ms[len(ms) // 2]:.1f} | {tracked} of {len(track)} ({100 * tracked / max(1, len(track)):.1f}%) |")
PY
done
