#!/usr/bin/env bash
# A rendered sequence with some frames covered (uniform grey images of the same size, as a lens covered for a
# moment) and groundslam run on it: how many frames a short loss costs (docs/accuracy.md, Session 16).
# Usage: scripts/covered_frames.sh BIN SEQUENCE_DIR OUT_DIR [RUN ARGS...]   (env: COVERED, image numbers, "100 200 300")
# OUT_DIR gets the covered copy (OUT_DIR/sequence) and the run (OUT_DIR/run); prints the run's lost frames and metrics.
set -euo pipefail
bin=$1; seq=$2; out=$3; shift 3
covered=${COVERED:-"100 200 300"}
rm -rf "$out"; mkdir -p "$out"
cp -r "$seq" "$out/sequence"
rm -rf "$out/sequence/runs"*
for n in $covered; do
  image=$(printf "%s/sequence/images/%06d.png" "$out" "$n")
  [ -f "$image" ] || { echo "$image: no such image" >&2; exit 2; }
  /usr/bin/python3 - "$image" <<'PY'
import struct, sys, zlib
path = sys.argv[1]
header = open(path, 'rb').read(33)
if header[:8] != b'\x89PNG\r\n\x1a\n':
    sys.exit(f'{path}: not a PNG')
width, height = struct.unpack('>II', header[16:24])
def chunk(kind, data):
    return struct.pack('>I', len(data)) + kind + data + struct.pack('>I', zlib.crc32(kind + data) & 0xffffffff)
rows = b''.join(b'\x00' + bytes([128]) * width for _ in range(height))  # filter byte 0, grey 128
png = b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', width, height, 8, 0, 0, 0, 0))
png += chunk(b'IDAT', zlib.compress(rows)) + chunk(b'IEND', b'')
open(path, 'wb').write(png)
PY
done
"$bin" run "$out/sequence/sequence.txt" --out "$out/run" "$@" >/dev/null
lost=$(grep -cE ",(fallback|lost)" "$out/run/frames.csv" || true)
/usr/bin/python3 - "$out/run/metrics.json" "$lost" <<'PY'
import json, sys
m = json.load(open(sys.argv[1]))
l = m['loop_closure']
print(f"lost or fallback frames {sys.argv[2]}, SLAM {m['translation_mae_cm_per_m']:.3f} cm/m, {m['rotation_mae_deg']:.3f} deg, "
      f"ATE {1000 * m['ate_rmse_m']:.2f} mm, loop closures {l['accepted']} ({l['wrong_accepted']} wrong)")
PY
