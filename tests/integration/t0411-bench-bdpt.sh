#!/bin/sh
# make bench's bdpt figures (tests/bench-bdpt.sh) in their quick mode: the script runs to the
# end and prints every line it promises, each figure a finite number. The figures themselves
# are measurements and are never checked.
. tests/integration/lib.sh

if ! have_scene cornell-box/CornellBox.glb; then
    skip "the bdpt bench prints its lines" "no $SCENES/cornell-box/CornellBox.glb (set RB_SCENES)"
    done_testing
fi
# Scenes of the Cornell box alone: it is then the largest scene too, and cheap.
mkdir "$T/scenes"
ln -s "$(cd "$SCENES/cornell-box" && pwd)" "$T/scenes/cornell-box"
RB_BENCH_QUICK=1 RB_SCENES="$T/scenes" sh tests/bench-bdpt.sh >"$T/stdout" 2>"$T/stderr"
status=$?
expect_exit 0 "the bdpt bench's quick mode exits 0"
check "it writes nothing on stderr" test ! -s "$T/stderr"
stdout_has "^largest scene in $T/scenes: cornell-box/CornellBox.glb (36 triangles)$" \
    "the largest scene is named with its triangles"
x='[0-9][0-9.e+-]*'
for scene in demo cornell-box CornellBox; do
    stdout_has "^bdpt $scene 32x18 pass connect  *median  *$x ms gpu (2 a frame)$" \
        "$scene: bdpt's passes, bundle by bundle"
    stdout_has "^bdpt $scene 32x18 frame: wall $x ms, GPU passes $x ms; direct frame (no emitter samples): wall $x ms, GPU passes $x ms$" \
        "$scene: both frames' times"
    stdout_has "^bdpt $scene 32x18 bdpt / direct: $x wall, $x GPU passes" "$scene: their ratio"
    stdout_has "^bdpt $scene 32x18 relMSE $x (indirect layer $x) in $x s; reference 4 spp in $x s$" \
        "$scene: bdpt's error at the budget"
done
stdout_has "^bdpt demo 32x18 bdpt / direct: .* (goal: <= 2.5)$" "the demo's ratio has its goal"
stdout_has "^bdpt device: .* (CPU)$" "the device is named with its type"
stdout_has "^bdpt at 1920x1080: skipped, the device is a CPU" "lavapipe skips 1920x1080"
for spp in 1 4; do
    stdout_has "^  reference  *$spp spp: relMSE $x in $x s$" "the reference's error at $spp spp"
done
stdout_has "^  reference fit: relMSE = $x \* (time / 1 s)^-\{0,1\}$x" "the reference's fit"
for k in 1 2; do
    stdout_has "^  bdpt K=$k: relMSE $x in $x s; the reference" "bdpt's error and time at K=$k"
done
stdout_has "^  bdpt relMSE from K=1 to K=2: x$x (1/K: x0.50): " "whether bdpt levels off"
for f in 3 4; do
    stdout_has "^  demo frame $f: relMSE $x (indirect layer $x)$" "the demo's quality at frame $f"
done
stdout_has "^  demo worst frame: [34], relMSE $x$" "the demo's worst frame"
for label in defaults x4-VPLs-and-bundles no-interleave no-filter bundle-grid-1024 vpl-maps-1024; do
    stdout_has "^  $label  *relMSE $x (direct $x, indirect $x); 4x4 grid \($x%\|none\)$" \
        "the Cornell box's quality: $label"
done
stdout_has "^bdpt bench took $x min; load average" "the bench's own time and the machine's load"
check "no figure is NaN or infinite" sh -c "! grep -qiE '(^|[^a-z])-?(nan|inf)([^a-z]|$)' '$T/stdout'"

done_testing
