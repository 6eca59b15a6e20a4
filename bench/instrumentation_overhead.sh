#!/usr/bin/env bash
# Issue 17's instrumentation overhead: every method on sphere_on_plane at 1024x768, each
# timed frame followed by a bare frame (no timestamp or statistics queries), compared by
# CPU wall time per frame in one run (`caustics run --instrumentation-overhead`).
# Usage: bench/instrumentation_overhead.sh [OUT_DIR] [FRAMES]
#   METHODS="static-grid adaptive-beams" measures only those methods.
# (builds the release binary; CAUSTICS=path/to/caustics uses that one instead)
set -euo pipefail
out=${1:-target/instrumentation-overhead}
frames=${2:-9}
bin=${CAUSTICS:-}
if [ -z "$bin" ]; then
  cargo build --release -q -p caustics
  bin=target/release/caustics
fi
# pinhole is left out: its run at 1024x768 had not finished after 10 minutes on lavapipe.
for method in ${METHODS:-wavefront caustic-triangles splatting static-grid adaptive-beams}; do
  $bin run --scene sphere_on_plane --method "$method" --frames "$frames" --warmup 1 \
    --score-grid 1 --instrumentation-overhead --out "$out" 2>/dev/null |
    grep -E "^sphere_on_plane|instrumentation:"
done
