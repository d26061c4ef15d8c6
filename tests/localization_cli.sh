#!/usr/bin/env bash
# End to end through the command line: a first session's run writes map.gsmap; a second session over the
# same simulated floor (other path, other seed, wet) is localized image by image (`localize`) and tracked on
# the map (`run --map`); a corrupt map is refused with its name.
set -u
source "$(dirname "$0")/checks.sh" "$1" "$2"

"$bin" simulate first --path lawnmower --frames 250 --lane-length-m 0.3 --ground-seed 5 --ground-size-m 1.2 --seed 1 >/dev/null
"$bin" simulate second --path random_walk --area-m 0.15 --frames 40 --ground-seed 5 --ground-size-m 1.2 --seed 2 --wet-after 0 >/dev/null
"$bin" run first/sequence.txt --out mapping >/dev/null
check "the run writes a map" [ -s mapping/map.gsmap ]

out=$("$bin" localize mapping/map.gsmap second/sequence.txt --out localized 2>&1); status=$?
check "localize succeeds" [ $status -eq 0 ]
check "localizations.csv has a row per image" [ "$(($(wc -l <localized/localizations.csv) - 1))" -eq 40 ]
localized=$(grep -c ",localized," localized/localizations.csv)
check "most images localize ($localized of 40)" [ "$localized" -ge 30 ]
check "localized.tum holds the localized images" [ "$(wc -l <localized/localized.tum)" -eq "$localized" ]
check "every localized image is within 1 cm and 1 deg" grep -qF "$localized of $localized localized images within 1 cm and 1 deg, 0 off" <<<"$out"

out=$("$bin" run second/sequence.txt --map mapping/map.gsmap --out on_map 2>&1); status=$?
check "run --map succeeds" [ $status -eq 0 ]
check "run --map relocalizes" grep -q ",relocalized," on_map/frames.csv
check "run --map measures every frame" grep -qF "frames measured       40 / 40" <<<"$out"
check "run --map writes the merged map" [ "$(stat -c %s on_map/map.gsmap)" -gt "$(stat -c %s mapping/map.gsmap)" ]
# In the map frame (the first session's first pose, (-0.15, 0, 0) in the world): compare with the truth.
err=$(/usr/bin/python3 - <<'PY'
import math
est = [list(map(float, l.split())) for l in open("on_map/trajectory.tum") if l.strip()]
gt = [list(map(float, l.split())) for l in open("second/groundtruth.tum") if l.strip()]
print(max(math.hypot(e[1] - 0.15 - g[1], e[2] - g[2]) for e, g in zip(est, gt)))
PY
)
check "run --map poses within 1 cm in the map frame (max $err m)" /usr/bin/python3 -c "import sys; sys.exit(0 if $err < 0.01 else 1)"

head -c 100 mapping/map.gsmap >truncated.gsmap
out=$("$bin" localize truncated.gsmap second/sequence.txt --out bad 2>&1); status=$?
check "a truncated map is refused" [ $status -eq 2 ]
check "the refusal names the file" grep -qF "truncated.gsmap: map file is" <<<"$out"
out=$("$bin" run second/sequence.txt --map truncated.gsmap --out bad 2>&1); status=$?
check "run --map refuses it too" [ $status -eq 2 ]
check "and leaves no output folder" [ ! -e bad ]
finish_checks
