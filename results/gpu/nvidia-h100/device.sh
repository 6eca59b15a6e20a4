#!/usr/bin/env bash
# One lease: adapters, the compute-timestamp test, ceilings, paper-scenes, liktor-table1,
# instrumentation overhead, and wavefront old (a47f9ac) vs new (HEAD) side by side.
set -uo pipefail
for f in .gl/*.deb; do dpkg -x $f /; done; ldconfig
G=target/gpu-bin; W=/tmp/w; mkdir -p $W/sbs
xz -dk $G/caustics.xz $G/compute_timestamps.xz $G/caustics-old.xz
chmod +x $G/caustics $G/compute_timestamps $G/caustics-old
B=$G/caustics; export CAUSTICS_SOURCE_COMMIT=aaa1b12a99ec5c1fb119ccdacf574ece23c8698d
step() { echo "== $* $(date -u +%H:%M:%S)"; }
step adapters
if ! $B adapters --json $W/adapters.json > $W/adapters.txt 2>&1 || ! grep -qi nvidia $W/adapters.txt; then
  echo "no NVIDIA adapter at first; with the driver's ICD named"
  export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
  $B adapters --json $W/adapters.json > $W/adapters.txt 2>&1
fi
nvidia-smi --query-gpu=name,driver_version,clocks.max.sm,clocks.max.mem --format=csv | tee -a $W/adapters.txt
head -2 $W/adapters.txt
step compute_timestamps test
$G/compute_timestamps --nocapture 2>&1 | tee $W/compute_timestamps.txt | tail -12
step ceilings
$B ceilings --out $W/ceilings > $W/ceilings.txt 2>&1; tail -25 $W/ceilings.txt
common="--references $G/refs --ceilings $W/ceilings --no-render-references"
step paper-scenes
$B reproduce bench/experiments/gpu/paper-scenes.json --out $W $common --time-budget-s 170 2>&1 | tail -4
step liktor-table1
$B reproduce liktor-table1 --out $W $common --time-budget-s 60 2>&1 | tail -3
step instrumentation
CAUSTICS=$B bench/instrumentation_overhead.sh $W/instrumentation 9 > $W/instrumentation.txt 2>&1; cat $W/instrumentation.txt
step wavefront side by side
ext="--param bounces=8 --param reflections=true --param splat_orphans=true"
for round in 1 2; do
  for s in water_pool sphere_on_plane bumpy_glass; do
    for setting in default extended; do
      p=""; [ $setting = extended ] && p=$ext
      for bin in old new; do
        b=$B; [ $bin = old ] && b=$G/caustics-old
        o=$W/sbs/$bin-$setting-r$round
        $b run --scene $s --method wavefront $p --resolution 1024x768 --frames 10 --warmup 2 --score-grid 1 \
          --references $G/refs --quick-reference-photons 0 --ceilings $W/ceilings --out $o > $o-$s.log 2>&1
        echo "$bin $setting r$round $s rc=$? $(grep -m1 -i 'gpu ms\|method' $o-$s.log | cut -c1-150)"
      done
    done
  done
done
rm -rf $W/references
step pack
cd $W
{ find . -type f ! -name '*.png' ! -name '*.exr' | sort; find . -type f \( -name caustic.png -o -name composite.png -o -name fill_heatmap.png -o -path './*/plots/*' -o -path './*/figures/*' \) -name '*.png' | sort; } > /tmp/list
tar czf /tmp/all.tgz -T /tmp/list
ls -la /tmp/all.tgz
split -b 15M -d /tmp/all.tgz $OUT/part
step done
