#!/usr/bin/env bash
# Issue 17's check on a real GPU, in one go: the adapters wgpu finds with the chosen
# one's features and limits (`caustics adapters`), that adapter's measured ceilings
# (`caustics ceilings`), every method at 1024x768 on its paper's scene with both raster
# paths (`caustics reproduce bench/experiments/gpu/paper-scenes.json`: not part of `reproduce all`, one pinhole run at 128x96 took 8 min 17 s on lavapipe, this is 64x the pixels; references rendered on the CPU first), and
# the instrumentation overhead (bench/instrumentation_overhead.sh).
#
# Usage: bench/gpu_check.sh OUT_DIR [EXPERIMENT_SECONDS]
#   CAUSTICS=path/to/caustics uses that binary instead of building the release one.
#   EXPERIMENT_SECONDS (default 900): no run of the reproduction starts after it
#   (`reproduce --time-budget-s`); the summary lists the runs left as not run, and the
#   script again with the same OUT_DIR keeps the complete runs and does the others.
# Writes under OUT_DIR: adapters.{txt,json}, ceilings/ + ceilings.txt, paper-scenes/
# (summary.md, summary.json, runs/, plots/), instrumentation.txt, and the references
# under references/ (not meant to be committed: they are large).
set -uo pipefail
out=${1:?usage: bench/gpu_check.sh OUT_DIR [EXPERIMENT_SECONDS]}
budget_s=${2:-900}
bin=${CAUSTICS:-}
if [ -z "$bin" ]; then
  cargo build --release -q -p caustics || exit 1
  bin=target/release/caustics
fi
mkdir -p "$out"
status=0
step() { echo "== $* ($(date -u +%H:%M:%S))"; }

step adapters
"$bin" adapters --json "$out/adapters.json" | tee "$out/adapters.txt" || status=1
command -v nvidia-smi > /dev/null && nvidia-smi --query-gpu=name,driver_version,clocks.max.sm,clocks.max.mem --format=csv | tee -a "$out/adapters.txt"

step ceilings
"$bin" ceilings --out "$out/ceilings" | tee "$out/ceilings.txt" || status=1

step paper-scenes
"$bin" reproduce bench/experiments/gpu/paper-scenes.json --out "$out" --time-budget-s "$budget_s" \
  --references "$out/references" --ceilings "$out/ceilings" || status=1

step instrumentation overhead
CAUSTICS=$bin bench/instrumentation_overhead.sh "$out/instrumentation" 9 | tee "$out/instrumentation.txt" || status=1

step done
exit $status
