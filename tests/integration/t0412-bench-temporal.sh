#!/bin/sh
# make bench's temporal figures (tests/bench-temporal.sh) in their quick mode: the script runs to
# the end and prints every line it promises, each figure a number. The figures themselves are
# measurements and are never checked.
. tests/integration/lib.sh

# Scenes of the Cornell box and Fox alone (CesiumMan and BoxAnimated say they are skipped).
mkdir "$T/scenes"
for s in cornell-box Fox; do
    if [ -d "$SCENES/$s" ]; then ln -s "$(cd "$SCENES/$s" && pwd)" "$T/scenes/$s"; fi
done
RB_BENCH_QUICK=1 RB_SCENES="$T/scenes" sh tests/bench-temporal.sh >"$T/stdout" 2>"$T/stderr"
status=$?
expect_exit 0 "the temporal bench's quick mode exits 0"
check "it writes nothing on stderr" test ! -s "$T/stderr"
x='[0-9][0-9.e+-]*'
stdout_has "^temporal demo 32x18 frame: 4 caches wall $x ms, GPU passes $x ms; 1 cache wall $x ms, GPU passes $x ms; direct wall $x ms, GPU passes $x ms$" \
    "the frame times with 4 caches, 1 and direct"
stdout_has "^temporal demo 32x18 4 caches / 1 cache: $x wall, $x GPU passes; 4 caches / direct: $x wall, $x GPU passes (goal: about 2.5)$" \
    "their ratios"
for pass in reproject reconstruct; do
    stdout_has "^temporal demo 32x18 4 caches pass $pass *median *$x ms gpu$" "the $pass pass's time"
done
stdout_has "^temporal CesiumMan: skipped, no " "a missing scene is named"
line="frames 0-5: excess temporal error $x (goal: <= 0.0002); warped temporal error bdpt $x, reference $x; relMSE against the reference (2 spp) mean $x, last frame $x$"
stdout_has "^temporal demo 32x18 $line" "the demo's flicker against its reference"
if [ -d "$SCENES/Fox" ]; then
    stdout_has "^temporal Fox 32x18 $line" "Fox's flicker against its reference"
else
    skip "Fox's flicker line" "no $SCENES/Fox (set RB_SCENES)"
fi
if [ -d "$SCENES/cornell-box" ]; then
    stdout_has "^temporal cornell-box 32x18 static: bdpt warped temporal error over frames 3-7 0.000000 (goal: 0, the same bits); excess against the reference sequence $x" \
        "the static Cornell box keeps its bits"
else
    stdout_has "^temporal cornell-box: skipped" "a missing Cornell box is named"
fi
done_testing
