#!/usr/bin/env bash
# The installed package works without the source tree's paths: install into a temporary prefix, build
# examples/ against it with find_package(groundslam), run the example and the installed program on a small
# simulated sequence; both must find the shipped vocabulary under the prefix and agree on the trajectory.
# Usage: tests/install_package.sh BUILD_DIR SOURCE_DIR WORK_DIR
set -euo pipefail
build=$1; source=$2; work=$3
rm -rf "$work"; mkdir -p "$work"
prefix=$work/prefix
cmake --install "$build" --prefix "$prefix" > "$work/install.log"
for f in bin/groundslam lib/groundslam/groundslam_media.so share/groundslam/vocabulary/ground.gslmvoc share/groundslam/default.yaml \
         include/groundslam/groundslam.hpp lib/cmake/groundslam/groundslamConfig.cmake; do
  [ -f "$prefix/$f" ] || { echo "not installed: $f"; exit 1; }
done
cmake -S "$source/examples" -B "$work/examples" -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_TYPE=Release > "$work/configure.log" 2>&1 \
  || { cat "$work/configure.log"; exit 1; }
cmake --build "$work/examples" -j 2 > "$work/build.log" 2>&1 || { cat "$work/build.log"; exit 1; }
# The installed program, copied elsewhere with the prefix: it must not look into the build or source tree.
"$prefix/bin/groundslam" --version | grep -q "^groundslam [0-9]"
"$prefix/bin/groundslam" simulate "$work/seq" --frames 40 --seed 3 > /dev/null
"$prefix/bin/groundslam" run "$work/seq/sequence.txt" --out "$work/run" > "$work/run.log"
vocabulary=$(sed -n "s/^vocabulary: '\(.*\)'$/\1/p" "$work/run/run.yaml")
case "$vocabulary" in
  "$prefix"/share/groundslam/vocabulary/ground.gslmvoc) ;;
  *) echo "the installed program used the vocabulary '$vocabulary', not the prefix's"; exit 1 ;;
esac
# Other programs linking the package find the data through GROUNDSLAM_DATA_DIR (or the configured prefix).
GROUNDSLAM_DATA_DIR="$prefix/share/groundslam" "$work/examples/run_folder" "$work/seq/sequence.txt" > "$work/example.tum" 2> "$work/example.log"
lines=$(grep -c . "$work/example.tum")
[ "$lines" -eq 40 ] || { echo "example wrote $lines poses, expected 40"; cat "$work/example.log"; exit 1; }
# The example and `groundslam run` are the same pipeline on the same frames: same poses to the printed digits.
if ! diff <(cut -d' ' -f1-4 "$work/example.tum") <(cut -d' ' -f1-4 "$work/run/trajectory.tum") > "$work/diff.txt"; then
  echo "example and groundslam run disagree:"; head "$work/diff.txt"; exit 1
fi
# The Python module installed with the package imports and finds the shipped data beside itself (P/share/groundslam
# for P/lib/python3/dist-packages), with no environment variable, though P is not the configured prefix.
if ls "$build"/python/groundslam.*.so >/dev/null 2>&1; then
  ls "$prefix"/lib/python3/dist-packages/groundslam.*.so >/dev/null 2>&1 || { echo "the Python module was not installed"; exit 1; }
  env -u GROUNDSLAM_DATA_DIR PYTHONPATH="$prefix/lib/python3/dist-packages" /usr/bin/python3 -c \
    "import groundslam, sys; p = '$prefix/share/groundslam/'; sys.exit(0 if groundslam.__version__ and groundslam.default_vocabulary().startswith(p) and groundslam.default_config().startswith(p) else 1)" \
    || { echo "the installed Python module does not import or find its data under $prefix/share/groundslam"; exit 1; }
fi
echo "installed package: example built and run, trajectory identical to groundslam run ($lines poses)"
