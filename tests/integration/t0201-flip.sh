#!/bin/sh
# raybundle compare's FLIP: on the image pairs NVIDIA's reference tool (FLIP 1.6) was run on
# (../shared/flip, beside the scenes; skipped without them), the mean that compare prints is the
# tool's within 1% (and so are its weighted median, quartiles, largest error and the exposures
# HDR-FLIP chose), HDR-FLIP for EXRs and LDR-FLIP for PNGs; --max-flip fails above its bound,
# --flip-map writes the per-pixel error (an EXR, and a PNG in FLIP's colour map, magma),
# --no-flip leaves it out, and layers that are not RGB have none.
. tests/integration/lib.sh
PIXELS="$BUILD/tests/tools/pixels"

FLIP=${RB_FLIP:-$(dirname "$SCENES")/flip}

# within A B: A is within 1% of B.
within() {
    awk -v a="$1" -v b="$2" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(a != "" && d <= 0.01 * b) }'
}
json_flip_mean() {
    python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["flip"]["mean"])' "$T/stdout"
}

if [ -f "$FLIP/expected.tsv" ]; then
    tail -n +2 "$FLIP/expected.tsv" >"$T/expected.tsv"
    while IFS='	' read -r ref test kind mean wmedian q1 q3 max start stop count; do
        rb compare "$FLIP/$test" "$FLIP/$ref" --json
        expect_exit 0 "compare $test $ref exits 0"
        got=$(json_flip_mean)
        if within "$got" "$mean"; then
            ok "$kind-FLIP of $test against $ref: $got, the tool's $mean within 1%"
        else
            not_ok "$kind-FLIP of $test against $ref: $got, the tool's $mean within 1%"
        fi
        check "the JSON says $kind" grep -q "\"kind\": \"$kind\"" "$T/stdout"
        # The pooled figures and, for HDR-FLIP, the exposures it chose: each within 1%.
        for field in weighted_median:$wmedian q1:$q1 q3:$q3 max:$max exposures.start:$start \
            exposures.stop:$stop exposures.count:$count; do
            name=${field%%:*} want=${field#*:}
            [ "$want" = - ] && continue
            got=$(python3 -c 'import json, sys
v = json.load(open(sys.argv[1]))["flip"]
for k in sys.argv[2].split("."):
    v = v[k]
print(v)' "$T/stdout" "$name")
            # within 1% of the magnitude (an exposure may be negative)
            check "$kind-FLIP of $test: $name $got, the tool's $want within 1%" \
                awk -v a="$got" -v b="$want" 'BEGIN { d = a - b; if (d < 0) d = -d; m = b < 0 ? -b : b
                    exit !(a != "" && d <= 0.01 * m) }'
        done
    done <"$T/expected.tsv"
    a="$FLIP/lambert_b2_h1_4096_s1001.exr" b="$FLIP/lambert_b2_ref_8192.exr"
    rb compare "$a" "$b"
    check "the text output has a flip line" grep -q '^flip  *0\.00689.* (HDR-FLIP, 13 exposures' \
        "$T/stdout"
    rb compare "$a" "$b" --max-flip 0.001
    expect_exit 1 "--max-flip 0.001 fails a mean FLIP of 0.0069"
    check "and says so" grep -q 'exceeds --max-flip' "$T/stderr"
    rb compare "$a" "$b" --max-flip 0.01
    expect_exit 0 "--max-flip 0.01 passes it"
    rb compare "$a" "$b" --flip-map "$T/map/flip.exr"
    expect_exit 0 "--flip-map exits 0"
    rb info "$T/map/flip.exr"
    check "--flip-map writes a 320x180 map" grep -qx 'size: 320x180' "$T/stdout"
    check "with one channel, flip.Y" grep -qx 'layers: flip (Y)' "$T/stdout"
    rb info "$T/map/flip.png"
    check "and its PNG beside it, 320x180" grep -qx 'size: 320x180' "$T/stdout"
    rb compare "$a" "$b" --no-flip
    check "--no-flip prints no flip line" sh -c "! grep -q '^flip' '$T/stdout'"
else
    skip "FLIP against the reference tool's figures" "no $FLIP/expected.tsv"
fi

# Rendered frames: FLIP of a frame against itself is 0; a layer that is not RGB has none.
rb render jobs/demo.yaml --frames 1-2 --size 64x36 --out "$T/r" -q
expect_exit 0 "two small frames render"
rb compare "$T/r/frame.0001.exr" "$T/r/frame.0001.exr" --json
check "a frame against itself: FLIP 0" test "$(json_flip_mean)" = 0
rb compare "$T/r/frame.####.exr" "$T/r/frame.####.exr" --frames 1-2
check "a sequence prints the mean of its frames' FLIP" grep -q '^flip  *0 (mean of the frames' \
    "$T/stdout"

# The map as a PNG in magma: FLIP 0 is its first colour (0, 0, 4), the largest error a bright
# one. A green box on frame 1 leaves the pixels farther from it than the filters reach at 0.
oiiotool "$T/r/frame.0001.exr" --ch R,G,B --box:color=0,4,0:fill=1 40,12,47,19 -d float \
    -o "$T/box.exr" >/dev/null 2>&1
rb compare "$T/box.exr" "$T/r/frame.0001.exr" --flip-map "$T/fm/box.exr" --json
expect_exit 0 "--flip-map of a frame with a box on it exits 0"
check "it writes the EXR and the PNG, and no temporary file" \
    test "$(ls "$T/fm" | tr '\n' ' ')" = "box.exr box.png "
rb info "$T/fm/box.png"
check "the PNG is the image's size, 64x36" grep -qx 'size: 64x36' "$T/stdout"
check "a pixel far from the box (FLIP 0) is magma's first colour" \
    test "$("$PIXELS" "$T/fm/box.png" 2 2)" = 000004
rb compare "$T/box.exr" "$T/r/frame.0001.exr" --json
at=$(python3 -c 'import json, sys; print(*json.load(open(sys.argv[1]))["flip"]["max_pixel"])' \
    "$T/stdout")
max=$("$PIXELS" "$T/fm/box.png" $at)
check "the largest error's pixel ($at) is bright ($max)" \
    sh -c "printf '%d %d\n' 0x${max%????} 0x$(echo "$max" | cut -c3-4) | awk '{ exit !(\$1 > 224 && \$2 > 192) }'"
rb compare "$T/r/frame.0001.exr" "$T/r/frame.0001.exr" --flip-map "$T/fm/self.png"
expect_exit 0 "--flip-map PATH.png of a frame against itself exits 0"
check "it writes the PNG alone" test ! -e "$T/fm/self.exr" -a ! -e "$T/fm/self.png.exr"
check "every pixel of it is magma's first colour" \
    test "$("$PIXELS" "$T/fm/self.png" 0 0 64 36 000004)" = 2304
rb compare "$T/r/frame.####.exr" "$T/r/frame.####.exr" --frames 1-2 --flip-map "$T/fm/s.##.exr"
expect_exit 0 "--flip-map with '#' for a sequence exits 0"
check "it writes each frame's EXR and PNG" \
    test "$(ls "$T/fm" | grep '^s\.' | tr '\n' ' ')" = "s.01.exr s.01.png s.02.exr s.02.png "

rb compare "$T/r/frame.0001.exr" "$T/r/frame.0002.exr" --layer depth --json
check "the depth layer has no FLIP" grep -q '"flip": null' "$T/stdout"
rb compare "$T/r/frame.0001.exr" "$T/r/frame.0002.exr" --layer normal --json
expect_exit 0 "the normal layer compares"
check "the normal layer (three channels, not colour) has no FLIP" grep -q '"flip": null' \
    "$T/stdout"
rb compare "$T/r/frame.0001.exr" "$T/r/frame.0002.exr" --layer depth --max-flip 0.1
expect_exit 2 "--max-flip on the depth layer is bad usage"
check "it says FLIP needs an RGB layer" grep -q 'needs an RGB layer' "$T/stderr"

# A reference mostly black (median luminance 0): HDR-FLIP cannot choose exposures from it, as the
# reference tool cannot. Shown, it says why in its place; asked for, it fails.
oiiotool --pattern constant:color=0,0,0 64x36 3 --box:color=1,1,1:fill=1 0,0,7,7 -d float \
    -o "$T/dark.exr" >/dev/null 2>&1
rb compare "$T/dark.exr" "$T/dark.exr"
expect_exit 0 "a dark reference compares"
check "its flip line says why there is none" grep -q '^flip  *none: .*median 0' "$T/stdout"
check "and nothing goes to stderr" test ! -s "$T/stderr"
rb compare "$T/dark.exr" "$T/dark.exr" --max-flip 0.1
expect_exit 2 "--max-flip against it fails"
check "naming the reason" grep -q 'median 0' "$T/stderr"
done_testing
