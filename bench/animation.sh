#!/usr/bin/env bash
# Issue 16's animated experiments: one scene over a sequence with every method that
# renders it, each frame a new instant (scene posed, uploaded, method created anew),
# errors against references at the scored instants (every 15th frame and the one
# after), then `caustics animations` puts the sequences side by side (animations.md).
#
#   bench/animation.sh water_pool                       # 2 s at 30 FPS, 128x96
#   bench/animation.sh scenes/extended/moving_ball.json 0:1:30
#   RESOLUTION=256x192 METHODS="wavefront splatting" OUT=/tmp/a bench/animation.sh water_pool
#
# References: 20 M photons per scored instant (seed 1), rendered into the cache on
# first use. Methods that decline the scene are listed as skipped.
set -euo pipefail
cd "$(dirname "$0")/.."
scene=${1:?usage: bench/animation.sh SCENE [START:END:FPS]}
spec=${2:-0:2:30}
resolution=${RESOLUTION:-128x96}
out=${OUT:-results/animation}
refs=${REFERENCES:-results/references}
every=${REFERENCE_EVERY:-15}
methods=${METHODS:-wavefront caustic-triangles splatting static-grid adaptive-beams pinhole}
bin=${BIN:-target/release/caustics}
[ -x "$bin" ] || cargo build --release -p caustics
for m in $methods; do
    echo "== $m ($(date +%T))"
    status=0
    "$bin" run --scene "$scene" --method "$m" --resolution "$resolution" --animate "$spec" \
        --reference-every "$every" --out "$out" --references "$refs" \
        --quick-reference-photons 20000000 || status=$?
    # 3: the method declined the scene (its reason is on stderr).
    [ "$status" -eq 0 ] || [ "$status" -eq 3 ] || exit "$status"
done
"$bin" animations "$out"
