#!/usr/bin/env bash
# Fault cases of a run and what the user sees: an output folder that would overwrite inputs, Ctrl-C and
# SIGTERM mid-run, a planted symbolic link, a full disk (a file size limit), an unwritable folder, the
# default output folder, and results that have nothing to compare. Nothing the user had may be lost.
set -u
source "$(dirname "$0")/checks.sh" "$1" "$2"
digest() { find "$1" -type f -print0 | sort -z | xargs -0 md5sum | md5sum; }

"$bin" simulate seq --frames 40 --resolution 160x120 >/dev/null
"$bin" simulate long --frames 1500 --resolution 160x120 >/dev/null

# 1. --out naming the dataset's own folder: refused, the dataset untouched.
before=$(digest seq)
out=$("$bin" run seq/sequence.txt --out seq 2>&1); status=$?
check "run into the dataset folder is refused" [ $status -eq 2 ]
check "the refusal names the input" grep -qF "holds seq/sequence.txt, an input of this run" <<<"$out"
check "the dataset is untouched" [ "$(digest seq)" = "$before" ]

# 2. Ctrl-C while re-running into a finished run's folder: previous results stay, the partial ones go beside.
"$bin" run seq/sequence.txt --out done >/dev/null
before=$(digest done)
"$bin" run long/sequence.txt --out done >/dev/null 2>&1 &
pid=$!
sleep 1.5
kill -INT $pid
wait $pid; status=$?
check "SIGINT exits 130" [ $status -eq 130 ]
check "the previous results are untouched" [ "$(digest done)" = "$before" ]
check "the partial results say so" grep -q "status: interrupted" done.interrupted/run.yaml
check "the partial trajectory is there" [ -s done.interrupted/trajectory.tum ]
processed=$(sed -n 's/frames_processed: //p' done.interrupted/run.yaml)
check "fewer frames than the sequence were processed" [ "${processed:-1500}" -lt 1500 ]
check "the trajectory holds the processed frames" [ "$(wc -l <done.interrupted/trajectory.tum)" -eq "${processed:-0}" ]

# 3. SIGTERM into a new folder: the partial results land there, marked.
"$bin" run long/sequence.txt --out fresh >/dev/null 2>&1 &
pid=$!
sleep 1.5
kill -TERM $pid
wait $pid; status=$?
check "SIGTERM exits 143" [ $status -eq 143 ]
check "a new folder receives the partial results" grep -q "status: interrupted" fresh/run.yaml

# 4. A planted symbolic link in the output folder: refused, its target untouched.
echo precious >precious.txt
ln -s "$tmp/precious.txt" done/frames.csv.partial
out=$("$bin" run seq/sequence.txt --out done 2>&1); status=$?
check "a folder with a planted link is refused" [ $status -eq 2 ]
check "the link's target is untouched" [ "$(cat precious.txt)" = precious ]
rm done/frames.csv.partial

# 5. A full disk (here: a file size limit): a clear error, nothing left behind, the previous results kept.
before=$(digest done)
out=$(trap '' XFSZ; ulimit -f 4; "$bin" run seq/sequence.txt --out done 2>&1); status=$?
check "a write error exits 2" [ $status -eq 2 ]
check "the write error carries the system's reason" grep -qF "File too large" <<<"$out"
check "the previous results are kept after a write error" [ "$(digest done)" = "$before" ]
check "no staging folder is left behind" [ -z "$(find . -maxdepth 1 -name '.*staging*')" ]

# 6. An unwritable place.
out=$("$bin" run seq/sequence.txt --out /proc/groundslam_run 2>&1); status=$?
check "an unwritable output folder exits 2" [ $status -eq 2 ]
check "its error names the folder" grep -qF "/proc" <<<"$out"

# 7. No --out: a new folder per run and runs/latest pointing at the newest.
"$bin" run seq/sequence.txt >/dev/null
sleep 1.1
"$bin" run seq/sequence.txt --no-loop-closure >/dev/null
check "two runs, two folders" [ "$(find runs -mindepth 1 -maxdepth 1 -type d | wc -l)" -eq 2 ]
check "runs/latest is a link" [ -L runs/latest ]
check "runs/latest is the newest run" grep -q "enabled: false" runs/latest/config.yaml

# 8. Nothing to compare is an error, not a perfect score.
awk '{ $1 = $1 + 1000; print }' done/trajectory.tum >shifted.tum
out=$("$bin" evaluate done/groundtruth.tum shifted.tum 2>&1); status=$?
check "no common timestamps exits 2" [ $status -eq 2 ]
check "no common timestamps is named" grep -qF "nothing to compare" <<<"$out"
: >empty.tum
out=$("$bin" evaluate done/groundtruth.tum empty.tum 2>&1); status=$?
check "an empty estimate exits 2" [ $status -eq 2 ]
cp -r seq unreliable
sed -i '2~2s/^/* /' unreliable/sequence.txt
out=$("$bin" run unreliable/sequence.txt --out unreliable_run 2>&1); status=$?
check "a run with only unreliable ground truth succeeds" [ $status -eq 0 ]
check "and says why it has no metrics" grep -qF "no metrics: every pose line" <<<"$out"
check "and writes none" [ ! -e unreliable_run/metrics.json ]

# 9. Featureless (black) images: poses assumed, not counted as measured; no vocabulary from them.
printf 'P5\n64 64\n255\n' >black.pgm && head -c 4096 /dev/zero >>black.pgm
"$bin" simulate black --texture black.pgm --texture-width-m 2 --frames 20 --resolution 160x120 --noise 0 >/dev/null
out=$("$bin" run black/sequence.txt --out black_run 2>&1); status=$?
check "a black sequence runs" [ $status -eq 0 ]
check "a black sequence is not counted as measured" grep -qF "frames measured       1 / 20 (5.0%; 19 more" <<<"$out"
check "its lost frames are in the summary" grep -qF "1 measured, 0 measured at low overlap (less certain), 0 measured by aligning the images (too few features; less certain), 0 measured from few keypoints the images did not confirm (less certain), 0 measured with a covariance too wide for ok (less certain), 0 measured across a sharp turn (translation less certain), 0 measured across dropped frames (less certain), 0 with fallback odometry (pose assumed from earlier motion), 19 lost" <<<"$out"
out=$("$bin" vocabulary train black/images -o black.gslmvoc 2>&1); status=$?
check "no vocabulary from black images" [ $status -eq 2 ] && [ ! -e black.gslmvoc ]
check "the refusal says why" grep -qF "hold 0 ORB features" <<<"$out"

finish_checks
