#!/bin/sh
# Temporal interleaved sampling's figures (make bench runs this after tests/bench-bdpt.sh; a
# measurement, never a test). Speeds are ratios measured in this run, never asserted.
#  1. bdpt's frame with 4 temporal caches and with 1 (each frame its own), beside direct's: the
#     demo at $size, medians over frames 4 to 8 (every cache written).
#  2. Flicker against the ground truth: the demo and the animated shared scenes (Fox, CesiumMan,
#     BoxAnimated, as quick looks), frames 0 to $last at $seq_size, bdpt with 4 caches against the
#     reference sequence in bdpt's path space at $spp spp: raybundle flicker's excess temporal
#     error E (goal: <= 0.0002), bdpt's warped temporal error beside the reference's, and bdpt's
#     relMSE against the reference frame by frame (mean, and the last frame's). The reference's
#     own noise, which changes from frame to frame, is part of E.
#  3. The static Cornell box: bdpt's warped temporal error over frames 3 to 7 (0 when the steady
#     state keeps its bits, the goal) and its excess against the reference sequence.
#
#   BUILD=build sh tests/bench-temporal.sh
#
# RB_SCENES: the shared scenes (default ../shared/scenes). RB_BENCH_QUICK=1: tiny sizes, few
# frames and samples, so that a test can check that every line is printed; its figures mean
# nothing.
set -eu
BUILD=${BUILD:-build}
SCENES=${RB_SCENES:-../shared/scenes}
. tests/bench-lib.sh
out=$(mktemp -d "${TMPDIR:-/tmp}/raybundle-bench-temporal.XXXXXX")
trap 'rm -rf "$out"' EXIT

if [ "${RB_BENCH_QUICK:-0}" = 1 ]; then
    size=32x18 seq_size=32x18 last=5 spp=2
else
    size=640x360 seq_size=160x90 last=11 spp=64
fi
RB="$BUILD/raybundle"

# json KEY FILE: the summary's KEY in raybundle flicker's --json.
json() { sed -n "s/^    \"$1\": \([^,]*\),*\$/\1/p" "$2"; }

echo "temporal bench: bdpt with 4 caches (integrator.bdpt.caches) against 1, and against the" \
    "reference sequence"

# ---- 1. frame time ---------------------------------------------------------------------------

for run in direct:1 bdpt:4 bdpt:1; do
    # (direct without its emitter samples, punctual lights only: see bench-bdpt.sh)
    "$RB" render jobs/demo.yaml --integrator "${run%:*}" --size "$size" --frames 4-8 -q \
        --set integrator.bdpt.caches="${run#*:}" --set integrator.direct.emitter_lights=0 \
        --out "$out/time-$run" </dev/null >/dev/null
done
w() { field wall_ms "$out/time-$1"/frame.*.timing.json | median; }
g() { field gpu_total_ms "$out/time-$1"/frame.*.timing.json | median; }
awk -v w4="$(w bdpt:4)" -v g4="$(g bdpt:4)" -v w1="$(w bdpt:1)" -v g1="$(g bdpt:1)" \
    -v wd="$(w direct:1)" -v gd="$(g direct:1)" -v size="$size" 'BEGIN {
    printf "temporal demo %s frame: 4 caches wall %.1f ms, GPU passes %.1f ms; 1 cache wall %.1f ms, GPU passes %.1f ms; direct wall %.1f ms, GPU passes %.1f ms\n",
        size, w4, g4, w1, g1, wd, gd
    printf "temporal demo %s 4 caches / 1 cache: %.2f wall, %.2f GPU passes; 4 caches / direct: %.2f wall, %.2f GPU passes (goal: about 2.5)\n",
        size, w4 / w1, g4 / g1, w4 / wd, g4 / gd }'
# (cache_gbuffer, the caches' own G-buffer, runs only with integrator.bdpt.subpixel spread: at the
# default every cache reads the frame's G-buffer)
pass_medians "temporal demo $size 4 caches " "$out/time-bdpt:4"/frame.*.timing.json |
    grep -E ' pass (reproject|reconstruct) '

# ---- 2. flicker against the reference --------------------------------------------------------

{
    echo "demo jobs/demo.yaml"
    for s in Fox/Fox.glb CesiumMan/CesiumMan.glb BoxAnimated/BoxAnimated.gltf; do
        if [ -f "$SCENES/$s" ]; then
            echo "$(basename "${s%.*}") $SCENES/$s"
        else
            echo "temporal $(basename "${s%.*}"): skipped, no $SCENES/$s (set RB_SCENES)" >&2
        fi
    done
} >"$out/scenes" 2>"$out/skipped"
cat "$out/skipped"

# sequence NAME JOB [OPTION...]: bdpt and its reference, frames 0-$last at $seq_size, and what
# raybundle flicker and compare make of them.
sequence() {
    name=$1 job=$2
    shift 2
    dir="$out/seq-$name"
    "$RB" render "$job" --integrator bdpt --size "$seq_size" --frames "0-$last" -q \
        --out "$dir/bdpt" "$@" </dev/null >/dev/null
    "$RB" reference "$job" --set integrator.reference.paths=bdpt --size "$seq_size" \
        --frames "0-$last" --spp "$spp" -q --out "$dir/ref" "$@" </dev/null >/dev/null
    "$RB" flicker "$dir/bdpt" --reference "$dir/ref" --json </dev/null >"$dir/flicker.json"
    for f in "$dir"/bdpt/frame.*[0-9].exr; do
        "$RB" compare "$f" "$dir/ref/$(basename "$f")" </dev/null | sed -n 's/^relmse *//p'
    done >"$dir/relmse"
}

while read -r name job; do
    sequence "$name" "$job"
    dir="$out/seq-$name"
    awk -v name="$name" -v size="$seq_size" -v last="$last" -v spp="$spp" \
        -v e="$(json excess_error_mean "$dir/flicker.json")" \
        -v wb="$(json warped_error_mean "$dir/flicker.json")" \
        -v wr="$(sed -n '/^    "reference": {$/,/}/s/^      "warped_error_mean": \([^,]*\),*$/\1/p' "$dir/flicker.json")" \
        -v rm="$(awk '{ s += $1; n++ } END { printf "%.4g", n ? s / n : 0 }' "$dir/relmse")" \
        -v rl="$(tail -n 1 "$dir/relmse")" 'BEGIN {
        printf "temporal %s %s frames 0-%d: excess temporal error %.6f (goal: <= 0.0002); warped temporal error bdpt %.5f, reference %.5f; relMSE against the reference (%d spp) mean %s, last frame %s\n",
            name, size, last, e, wb, wr, spp, rm, rl }'
done <"$out/scenes"

# ---- 3. the static Cornell box ---------------------------------------------------------------

cornell="$SCENES/cornell-box/CornellBox.glb"
if [ -f "$cornell" ]; then
    sequence cornell-box "$cornell"
    dir="$out/seq-cornell-box"
    mkdir "$dir/steady"
    for f in 3 4 5 6 7; do
        if [ "$f" -le "$last" ]; then cp "$dir/bdpt/frame.000$f.exr" "$dir/steady/"; fi
    done
    "$RB" flicker "$dir/steady" --json </dev/null >"$dir/steady.json"
    awk -v size="$seq_size" -v w="$(json warped_error_mean "$dir/steady.json")" \
        -v e="$(json excess_error_mean "$dir/flicker.json")" 'BEGIN {
        printf "temporal cornell-box %s static: bdpt warped temporal error over frames 3-7 %.6f (goal: 0, the same bits); excess against the reference sequence %.6f (the reference'"'"'s own noise)\n",
            size, w, e }'
else
    echo "temporal cornell-box: skipped, no $cornell (set RB_SCENES)"
fi
