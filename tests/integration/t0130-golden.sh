#!/bin/sh
# The direct integrator against golden frames (tests/golden/direct, written by
# `make update-golden`, first from the direct integrator as it was before the frame driver):
# the demo and the analytic scenes render the same pixels, in every layer, bit for bit.
. tests/integration/lib.sh

G=tests/golden/direct
same_pixels() { # same_pixels GOLDEN NEW: every channel of every pixel identical
    idiff -fail 0 -failpercent 0 -warn 0 "$1" "$2" >"$T/idiff" 2>&1
}
rb render jobs/demo.yaml --integrator direct --frames 0-7 --size 160x90 --out "$T/demo" -q
expect_exit 0 "the demo renders frames 0-7"
for f in 0000 0001 0007; do
    check "demo frame $f: the golden pixels" same_pixels "$G/demo.$f.exr" "$T/demo/frame.$f.exr"
done
# A chunk starts with warm-up frames: frame 7 alone is the golden frame 7 too.
rb render jobs/demo.yaml --integrator direct --frames 7 --size 160x90 --out "$T/seven" -q
check "demo frame 7 rendered alone: the golden pixels" \
    same_pixels "$G/demo.0007.exr" "$T/seven/frame.0007.exr"
check "the comparison can fail: frames 0 and 7 differ" \
    sh -c "! idiff -fail 0 -failpercent 0 -warn 0 '$G/demo.0000.exr' '$G/demo.0007.exr' >/dev/null 2>&1"

# The job's layers: only those are packed, read back and written, with the same values.
rb render jobs/demo.yaml --integrator direct --frames 0-3 --size 160x90 --out "$T/two" -q --set 'layers=[normal, depth]'
expect_exit 0 "the demo renders with two layers"
check "two layers: the EXR holds the beauty, depth and normal only" sh -c \
    "oiiotool --info -v '$T/two/frame.0003.exr' | grep -qx '    channel list: R, G, B, A, depth.Z, normal.X, normal.Y, normal.Z'"
oiiotool "$T/demo/frame.0003.exr" --ch R,G,B,A,depth.Z,normal.X,normal.Y,normal.Z -o "$T/all-sub.exr"
check "two layers: the same pixels as the full render's" \
    same_pixels "$T/all-sub.exr" "$T/two/frame.0003.exr"
check "two layers: a smaller file" \
    test "$(wc -c <"$T/two/frame.0003.exr")" -lt "$(wc -c <"$T/demo/frame.0003.exr")"
rb reference jobs/demo.yaml --frames 0 --size 32x18 --spp 1 --out "$T/ref-two" -q \
    --set 'layers=[indirect]'
check "the reference writes the job's layers too" sh -c \
    "oiiotool --info -v '$T/ref-two/frame.0000.exr' | grep -qx '    channel list: R, G, B, A, indirect.R, indirect.G, indirect.B'"
rb render jobs/demo.yaml --frames 0 --out "$T/never" -q --set 'layers=[depth, specular]'
expect_exit 2 "an unknown layer is refused"
stderr_has "unknown layer 'specular'" "the unknown layer is named"

mkdir -p "$T/an"
"$BUILD/tests/tools/analytic" scene "$T/an" >/dev/null || fail_all "cannot write the analytic scenes"
for j in point spot sun glossy metal lights; do
    rb render "$T/an/$j.yaml" --size 128x80 -q
    expect_exit 0 "analytic '$j' renders"
    check "analytic '$j': the golden pixels" same_pixels "$G/$j.exr" "$T/an/$j/frame.0000.exr"
done
done_testing
