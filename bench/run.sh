#!/bin/sh
# make bench: every benchmark program, then whole-command timings with hyperfine. Results go
# to stdout; quote figures in docs/PERFORMANCE.md together with the command that made them.
# BENCH_FULL=1 adds the prefilter's accuracy table against the reference (tens of minutes).
# BENCH_LARGE=1 adds the prefilter at film sizes (bench/large.sh: 512 and 1024 chains from
# 2048x1024 and 4096x2048 inputs it makes; minutes).
set -eu
BUILD=${1:-build}
DATA=${IBL_TESTDATA:-tests/data}
HDRI=$DATA/hdri
[ -d "$HDRI" ] || { DATA=tests/data; HDRI=tests/data; }
B=$BUILD/bench
run() { echo "== $*"; "$@"; }
run "$B/bench_brdf"
run "$B/bench_containers" x 2
run "$B/bench_io" "$DATA"
run "$B/bench_layout" 1024 256 2 11
run "$B/bench_render"
run "$B/bench_triace_kernels"
run "$B/bench_sh" "$HDRI"
run "$B/bench_dynamic" 64 201 1
run "$B/bench_scene" 2000000
run "$B/bench_skin"
run sh bench/compress_tables.sh "$BUILD" "$HDRI"
if [ "${BENCH_FULL:-0}" = 1 ]; then
  mkdir -p "$BUILD/refcache"
  run "$B/bench_specular" --sizes 128,256 --samples 2000 --filters ggx,phong,blinn \
      --ref-cache "$BUILD/refcache" "$HDRI"/*.exr
fi
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
IN=$HDRI/city.exr
echo "== whole commands (hyperfine, 2 threads)"
hyperfine -w 1 -r 5 -N \
  "$BUILD/ibl convert -q $IN -o $OUT/c.ktx2 --size 256" \
  "$BUILD/ibl sh --json $IN" \
  "$BUILD/ibl irradiance -q $IN -o $OUT/i.ktx2" \
  "$BUILD/ibl lut -q -o $OUT/l.ktx2" \
  "$BUILD/ibl render -q $IN -o $OUT/r.png --specular-size 64"
hyperfine -w 1 -r 5 -N "$BUILD/ibl prefilter -q $IN -o $OUT/p.ktx2 --size 256" \
  "$BUILD/ibl bake -q $IN -o $OUT/bake"
hyperfine -w 1 -r 5 -N "$BUILD/ibl render -q $OUT/bake -o $OUT/rb.png"
# the 512-face case (budget: 400 ms for the whole command) needs a 2048x1024 input: the same
# HDRI resampled up by ibl, written as float RGB with OpenEXR's ZIP (the writer's default
# compression). --format rgb32f: the resampled cube's alpha is 1 only to within float rounding
# (0.9999998..1.0000004), which would otherwise make the writer keep a fourth channel that no
# real HDRI has.
"$BUILD/ibl" convert -q "$IN" -o "$OUT/cube512.ktx2" --size 512 --format rgba32f
"$BUILD/ibl" convert -q "$OUT/cube512.ktx2" -o "$OUT/big.exr" --format rgb32f
hyperfine -w 1 -r 3 -N "$BUILD/ibl prefilter -q $OUT/big.exr -o $OUT/p512.ktx2 --size 512"
# probe capture of the sample scene (docs/PERFORMANCE.md "Scene ray casting and probe capture")
hyperfine -w 1 -r 3 -N "$BUILD/ibl capture -q examples/rooms/scene.gltf --probes examples/rooms/probes.json -o $OUT/caps --size 32 --samples 64"
hyperfine -w 1 -r 3 -N "$BUILD/ibl bake -q --probes examples/rooms/probes.json --captures $OUT/caps -o $OUT/probe_bake"
run "$B/bench_probes" 20
# the same culling on the GPU (llvmpipe here; built with IBL_BUILD_GL), and the sample set's
# capture + bake at 128 texels a face (docs/PERFORMANCE.md "Probe bake and tiled culling")
if [ -x "$B/bench_probes_gpu" ]; then run "$B/bench_probes_gpu" 3; fi
run "$B/bench_probe_bake" 16 2
if [ "${BENCH_LARGE:-0}" = 1 ]; then
  sh bench/large.sh "$BUILD"
fi
