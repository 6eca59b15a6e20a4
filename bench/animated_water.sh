#!/usr/bin/env bash
# Issue 16's animated water: water_pool over 2 s at 30 FPS (60 instants) with every
# method that renders it, each frame a new instant, errors against references at the
# scored instants (every 15th frame and the one after: 8 instants, 4 temporal pairs),
# then `caustics animations` puts the sequences side by side (animations.md).
#
#   bench/animated_water.sh                      # 128x96, results/animation/water_pool
#   WIDTH=256 HEIGHT=192 METHODS="wavefront splatting" OUT=/tmp/aw bench/animated_water.sh
#
# References: 20 M photons per instant (seed 1) rendered into the cache on first use.
set -euo pipefail
cd "$(dirname "$0")/.."
width=${WIDTH:-128}
height=${HEIGHT:-96}
out=${OUT:-results/animation/water_pool}
refs=${REFERENCES:-results/references}
methods=${METHODS:-wavefront caustic-triangles splatting static-grid adaptive-beams pinhole}
bin=${BIN:-target/release/caustics}
[ -x "$bin" ] || cargo build --release -p caustics
mkdir -p "$out"
scene="$out/water_pool-${width}x${height}.json"
sed -e "s/\"width\": 1024, \"height\": 768/\"width\": $width, \"height\": $height/" \
    scenes/water_pool.json > "$scene.tmp"
grep -q "\"width\": $width, \"height\": $height" "$scene.tmp" || {
    echo "could not set the camera of scenes/water_pool.json to ${width}x${height}" >&2
    exit 1
}
mv "$scene.tmp" "$scene"
for m in $methods; do
    echo "== $m ($(date +%T))"
    "$bin" run --scene "$scene" --method "$m" --animate 0:2:30 --reference-every 15 \
        --out "$out" --references "$refs" --quick-reference-photons 20000000
done
"$bin" animations "$out"
