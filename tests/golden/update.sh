#!/bin/sh
# make update-golden: renders the golden frames of the direct integrator with the current build.
# Run it only for a change that is meant to change pixels, and look at the difference images
# (idiff -o) before committing the new files. t0130-golden.sh renders the same frames and
# requires identical pixels in every layer.
set -eu
BUILD=${BUILD:-build}
G=tests/golden/direct
T=$(mktemp -d "${TMPDIR:-/tmp}/raybundle-golden.XXXXXX")
trap 'rm -rf "$T"' EXIT
mkdir -p "$G"
# The demo: frames 0, 1 and 7 of a run of 0-7 (frame 0 has no predecessor in the range).
"$BUILD/raybundle" render jobs/demo.yaml --integrator direct --frames 0-7 --size 160x90 --out "$T/demo" -q >/dev/null
for f in 0000 0001 0007; do cp "$T/demo/frame.$f.exr" "$G/demo.$f.exr"; done
# The analytic scenes (tests/tools/analytic writes them), smaller than the analytic test's.
mkdir -p "$T/an"
"$BUILD/tests/tools/analytic" scene "$T/an" >/dev/null
for j in point spot sun glossy metal lights; do
    "$BUILD/raybundle" render "$T/an/$j.yaml" --size 128x80 -q >/dev/null
    cp "$T/an/$j/frame.0000.exr" "$G/$j.exr"
done
echo "update-golden: wrote $(ls "$G" | wc -l) files to $G"
