#!/bin/sh
# make bench's hybrid figures (tests/bench-hybrid.sh) in their quick mode: the script runs to the
# end and prints every line it promises, each figure a finite number. The figures themselves are
# measurements and are never checked.
. tests/integration/lib.sh

# Scenes of the Cornell box alone (the demo is always benched); none at all says so.
mkdir "$T/scenes"
if have_scene cornell-box/CornellBox.glb; then
    ln -s "$(cd "$SCENES/cornell-box" && pwd)" "$T/scenes/cornell-box"
    names="demo cornell-box"
else
    names="demo"
fi
RB_BENCH_QUICK=1 RB_SCENES="$T/scenes" sh tests/bench-hybrid.sh >"$T/stdout" 2>"$T/stderr"
status=$?
expect_exit 0 "the hybrid bench's quick mode exits 0"
check "it writes nothing on stderr" test ! -s "$T/stderr"
x='[0-9][0-9.e+-]*'
if [ "$names" = demo ]; then
    stdout_has "^hybrid shared scenes: skipped, no glTF in $T/scenes" "missing scenes are named"
fi
stdout_has "^hybrid per-pass GPU ms at 32x18, medians over frames 0-0; scenes: \[1\] demo" \
    "the per-pass table names its scenes"
for pass in gbuffer shadow diffuse_rays bvh_rays accumulate diffuse_filter output; do
    stdout_has "^  $pass  *$x" "the per-pass table has the pass $pass"
done
stdout_has "^  frame wall  *$x" "the per-pass table has the frame's wall time"
stdout_has "^  Diffuse Rays (diffuse_rays)  *1\.4  *$x" "the seed's table has its rows and figures"
stdout_has "^  Total  *10\.5  *$x" "the seed's table has its total"
for scene in $names; do
    stdout_has "^hybrid $scene 32x18 rays a frame (medians): requested $x, screen hits $x, queued $x (BVH hits $x, misses $x, dropped $x); BVH rays per second" \
        "$scene: its rays and BVH rays per second"
    stdout_has "^hybrid $scene 32x18 frame: wall $x ms, GPU passes $x ms; direct frame: wall $x ms, GPU passes $x ms; bdpt frame: wall $x ms, GPU passes $x ms$" \
        "$scene: the three integrators' frames"
    stdout_has "^hybrid $scene 32x18 hybrid / direct: $x wall, $x GPU passes; hybrid / bdpt: $x wall, $x GPU passes$" \
        "$scene: their ratios"
done
stdout_has "^hybrid device: .* (CPU)$" "the device is named with its type"
stdout_has "^hybrid at 1920x1080: skipped, the device is a CPU" "lavapipe skips 1920x1080"
stdout_has "^hybrid error on the still demo at 32x18 (history 64: .*) against the reference with one bounce" \
    "the error section says its truth"
for run in "1 ray:64" "4 rays:256"; do
    for f in " 1 frame " " 8 frames" "64 frames"; do
        stdout_has "^  ${run%:*} a lobe and frame (spp ${run#*:}), after $f: relMSE indirect $x, beauty $x; rays requested $x$" \
            "${run%:*} a lobe: the error after $f"
    done
done
if [ "$names" = demo ]; then
    stdout_has "^hybrid still Cornell box: skipped" "a missing Cornell box skips its error section"
else
    stdout_has "^hybrid error on the still Cornell box at 32x18 (defaults) against the reference (default path space)" \
        "the Cornell box's error section says its truth"
    for f in " 1 frame " " 8 frames"; do
        stdout_has "^  after  *$f: relMSE beauty $x, direct $x, indirect $x; rays requested $x$" \
            "the Cornell box: the error after $f"
    done
    stdout_has "^hybrid rays requested a frame over the still Cornell box (frame:rays): 0:$x" \
        "the Cornell box: rays a frame over the shot"
fi
stdout_has "^hybrid moving demo (jobs/demo-hybrid.yaml) at 32x18, medians over frames 1-2: frame wall $x ms, GPU passes $x ms, wall / GPU $x$" \
    "the moving demo's wall over GPU time"
stdout_has "^hybrid bench took $x min; load average" "the bench's own time and the machine's load"
check "no figure is NaN or infinite" sh -c "! grep -qiE '(^|[^a-z])-?(nan|inf)([^a-z]|$)' '$T/stdout'"

done_testing
