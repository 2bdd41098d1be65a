#!/bin/sh
# Transparency (glTF alphaMode BLEND; seed 003's Transparency pass): on a scene after Khronos'
# AlphaBlendModeTest (tests/tools/blendscene: quads of alpha 0.25, 0.5, 0.75 and an alpha
# texture in front of an opaque wall and floor, one more blended quad behind two of them),
# every GPU integrator
# - shows the blended quads (their pixels differ from the same scene with them opaque and with
#   them absent), and the direct integrator composites them exactly: blended = a opaque +
#   (1 - a) absent per quad, the textured quad's alpha rising from left to right;
# - is held to the reference, which composites the same layers over its paths: direct within
#   relMSE 1e-6 of the reference's direct path space (measured 7.4e-9), bdpt within 0.005 of
#   bdpt's path space (3.3e-4), hybrid within 0.01 of the full one (1.0e-3), the direct layer of
#   each within 1e-6 (7.4e-9: the layers' light is direct light); drawn opaque, as before the
#   pass, bdpt's beauty was 0.068 off;
# - names the pass `transparency` in the timing sidecar, and gives the same bits twice (and on
#   one thread, as the reference does);
# and a scene with no blended material runs no transparency pass.
. tests/integration/lib.sh

"$BUILD/tests/tools/blendscene" scene "$T" || fail_all "cannot write the blended scene"

below() { # below VALUE LIMIT
    awk "BEGIN { exit !(\"$1\" != \"\" && $1 < $2) }"
}

rb reference "$T/blend.yaml" --set integrator.reference.paths=direct -q --out "$T/ref-direct"
expect_exit 0 "the reference renders the blended scene in the direct path space"
rb reference "$T/blend.yaml" --set integrator.reference.paths=bdpt --spp 256 -q --out "$T/ref-bdpt"
expect_exit 0 "the reference renders it in bdpt's path space"
rb reference "$T/blend.yaml" --spp 256 -q --out "$T/ref-full"
expect_exit 0 "the reference renders it in the full path space"
for v in opaque none; do
    rb reference "$T/$v.yaml" --set integrator.reference.paths=direct -q --out "$T/ref-$v"
    expect_exit 0 "the reference renders the $v variant"
done
f=frame.0000.exr
tap_run "$BUILD/tests/tools/blendscene" exact "$T/ref-direct/$f" "$T/ref-opaque/$f" "$T/ref-none/$f"

for i in direct bdpt hybrid; do
    for v in blend opaque none; do
        rb render "$T/$v.yaml" --integrator $i -q --out "$T/$i-$v"
        expect_exit 0 "$i renders the $v variant"
    done
    mode=show
    [ $i = direct ] && mode=exact
    tap_run "$BUILD/tests/tools/blendscene" $mode "$T/$i-blend/$f" "$T/$i-opaque/$f" "$T/$i-none/$f"
    case $i in
    direct) ref=ref-direct limit=1e-6 ;;
    bdpt) ref=ref-bdpt limit=0.005 ;;
    hybrid) ref=ref-full limit=0.01 ;;
    esac
    e=$(relmse "$T/$i-blend/$f" "$T/$ref/$f" beauty)
    ed=$(relmse "$T/$i-blend/$f" "$T/$ref/$f" direct)
    echo "# $i against $ref: beauty relMSE $e, direct layer $ed"
    check "$i is within relMSE $limit of the reference ($e)" below "$e" "$limit"
    check "$i's direct layer is within relMSE 1e-6 of the reference's ($ed)" below "$ed" 1e-6
    check "$i's timing sidecar has the transparency pass" \
        grep -q '"name": "transparency"' "$T/$i-blend/frame.0000.timing.json"
    rb render "$T/blend.yaml" --integrator $i -q --out "$T/$i-again"
    expect_exit 0 "$i renders the blended scene again"
    check "$i gives the same bits twice" \
        sh -c "\"$BUILD/tests/tools/samebits\" \"$T/$i-blend/$f\" \"$T/$i-again/$f\" >/dev/null"
done
# The blending's order is the draws' and the primitives', never the threads': one thread gives
# the same bits, on the GPU and in the reference (in bdpt's path space, whose samples draw
# random numbers).
LP_NUM_THREADS=1 "$RB" render "$T/blend.yaml" --integrator direct -q --out "$T/one-thread"
check "direct renders the blended scene on one thread" test $? -eq 0
check "... with the same bits" \
    sh -c "\"$BUILD/tests/tools/samebits\" \"$T/direct-blend/$f\" \"$T/one-thread/$f\" >/dev/null"
rb reference "$T/blend.yaml" --set integrator.reference.paths=bdpt --spp 256 --threads 1 -q \
    --out "$T/ref-one-thread"
expect_exit 0 "the reference renders the blended scene on one thread"
check "... with the same bits" \
    sh -c "\"$BUILD/tests/tools/samebits\" \"$T/ref-bdpt/$f\" \"$T/ref-one-thread/$f\" >/dev/null"

# What the test tells apart: the quads drawn opaque, as every integrator did before.
e=$(relmse "$T/bdpt-opaque/$f" "$T/ref-bdpt/$f" beauty)
echo "# the quads drawn opaque, against the blended reference: relMSE $e"
check "drawn opaque, bdpt would fail the bound ($e)" awk "BEGIN { exit !($e >= 0.005) }"

# No blended material: no pass, so no GPU work and no name in the sidecar.
rb render "$T/plain.yaml" --integrator direct -q --out "$T/plain"
expect_exit 0 "a scene with no blended material renders"
check "... without a transparency pass" \
    sh -c "! grep -q transparency \"$T/plain/frame.0000.timing.json\""

done_testing
