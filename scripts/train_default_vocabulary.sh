#!/usr/bin/env bash
# Trains the vocabulary shipped in config/vocabulary/ground.gslmvoc: simulated sequences of every
# procedural texture, dry and wet, with seeds that no test or benchmark sequence uses.
# Usage: scripts/train_default_vocabulary.sh [BIN] [WORK_DIR]
set -euo pipefail
bin=${1:-build/groundslam}
work=${2:-data/vocabulary_training}
inputs=()
for kind in asphalt concrete carpet tiles; do
  for seed in 901 902; do
    seq="$work/${kind}_${seed}"
    [ -f "$seq/sequence.txt" ] || "$bin" simulate "$seq" --texture-kind "$kind" --path random_walk --frames 60 \
      --step-m 0.05 --area-m 1.0 --noise 2 --defocus-px 0.5 --exposure-variation 0.15 --wet-after 0.5 --seed "$seed" >/dev/null
    inputs+=("$seq/sequence.txt")
  done
done
"$bin" vocabulary train "${inputs[@]}" -o config/vocabulary/ground.gslmvoc --branching 10 --depth 4 --max-images 480 --seed 1
