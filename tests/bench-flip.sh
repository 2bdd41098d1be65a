#!/bin/sh
# make bench's FLIP figure (make bench runs this last; a measurement, never a test): the time
# raybundle compare spends on HDR-FLIP of a 1920x1080 EXR pair on one core. That is the CPU
# time (user + system) of compare --json less that of compare --no-flip on the same pair, each
# the median of 3 runs, pinned to one CPU where taskset is installed. The pair is the FLIP test
# pair of $RB_FLIP (default: flip beside $RB_SCENES) resized with oiiotool; without it, frames 0
# and 1 of the demo rendered at 1920x1080 with the direct integrator.
#
#   BUILD=build sh tests/bench-flip.sh
set -eu
BUILD=${BUILD:-build}
SCENES=${RB_SCENES:-../shared/scenes}
FLIP=${RB_FLIP:-$(dirname "$SCENES")/flip}
out=$(mktemp -d "${TMPDIR:-/tmp}/raybundle-bench-flip.XXXXXX")
trap 'rm -rf "$out"' EXIT
pin=
command -v taskset >/dev/null && pin="taskset -c 0"

if [ -f "$FLIP/lambert_b2_ref_8192.exr" ]; then
    what="the FLIP test pair (lambert_b2_h1_4096_s1001 against lambert_b2_ref_8192) resized"
    oiiotool "$FLIP/lambert_b2_h1_4096_s1001.exr" --resize 1920x1080 -d half -o "$out/a.exr"
    oiiotool "$FLIP/lambert_b2_ref_8192.exr" --resize 1920x1080 -d half -o "$out/b.exr"
else
    what="frames 1 and 0 of the demo (direct integrator)"
    "$BUILD/raybundle" render jobs/demo.yaml --integrator direct --size 1920x1080 --frames 0-1 \
        --out "$out/r" -q
    cp "$out/r/frame.0001.exr" "$out/a.exr"
    cp "$out/r/frame.0000.exr" "$out/b.exr"
fi

# cpu ARGS...: the median CPU seconds of 3 runs of compare a.exr b.exr ARGS.
cpu() {
    for run in 1 2 3; do
        /usr/bin/time -f '%U %S' -o "$out/time" $pin "$BUILD/raybundle" compare "$out/a.exr" \
            "$out/b.exr" "$@" >"$out/stdout"
        awk '{ print $1 + $2 }' "$out/time"
    done | sort -n | sed -n 2p
}
with=$(cpu --json)
cp "$out/stdout" "$out/flip.json"
without=$(cpu --no-flip)
set -- $(sed -n 's/.*"flip": {"kind": "\([a-z]*\)", "mean": \([^,]*\),.*"count": \([0-9]*\).*/\1 \2 \3/p' \
    "$out/flip.json")
echo "FLIP at 1920x1080, one core: $what"
awk -v a="$with" -v b="$without" -v k="$1" -v m="$2" -v n="$3" 'BEGIN {
    printf "  %s-FLIP, %d exposures, mean %.6g: %.2f s CPU (compare %.2f s, without FLIP %.2f s)\n",
        toupper(k), n, m, a - b, a, b }'
