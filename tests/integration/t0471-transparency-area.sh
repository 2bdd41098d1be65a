#!/bin/sh
# Blended layers lit like opaque surfaces by area lights and the environment: on the blended
# scene of t0470 lit by an emissive quad and a uniform environment alone (tests/tools/blendscene
# area), bdpt's and the hybrid's blended quads get the emitters' point samples and the
# environment's directions (the layer lights) with their shadow maps, and are held to the
# reference over the four front quads' pixels (blendscene mask): bdpt within relMSE 0.005 of
# bdpt's path space (measured 7.3e-4), hybrid within 0.01 of the full one (1.1e-3). With
# emission and the punctual lights alone, as before the layer lights, the quads were far too
# dark: 0.20 and 0.19. An environment map of the same colour gives the layers the same light
# (the map's texels integrated over each direction's cell), and the frames are the same bits
# twice.
. tests/integration/lib.sh

"$BUILD/tests/tools/blendscene" area "$T" || fail_all "cannot write the area-lit blended scene"

relmse() { # relmse A B: over the front quads' pixels
    "$RB" compare "$1" "$2" --mask "$T/mask.png" --json |
        sed -n 's/.*"relmse": \([0-9.e+-]*\).*/\1/p'
}
below() { # below VALUE LIMIT
    awk "BEGIN { exit !(\"$1\" != \"\" && $1 < $2) }"
}
f=frame.0000.exr

rb render "$T/area-opaque.yaml" --integrator direct -q --out "$T/opaque"
expect_exit 0 "the scene with the quads opaque renders (for their pixels)"
check "the mask of the quads' pixels" "$BUILD/tests/tools/blendscene" mask "$T/opaque/$f" \
    "$T/mask.png"
rb reference "$T/area.yaml" --set integrator.reference.paths=bdpt --spp 256 -q --out "$T/ref-bdpt"
expect_exit 0 "the reference renders the area-lit blended scene in bdpt's path space"
rb reference "$T/area.yaml" --spp 256 -q --out "$T/ref-full"
expect_exit 0 "the reference renders it in the full path space"

for i in bdpt hybrid; do
    rb render "$T/area.yaml" --integrator $i -q --out "$T/$i"
    expect_exit 0 "$i renders the area-lit blended scene"
    case $i in
    bdpt) ref=ref-bdpt limit=0.005 ;;
    hybrid) ref=ref-full limit=0.01 ;;
    esac
    e=$(relmse "$T/$i/$f" "$T/$ref/$f")
    echo "# $i's blended quads against $ref: relMSE $e"
    check "$i's blended quads are within relMSE $limit of the reference ($e)" below "$e" "$limit"
done

# The map path of the environment's directions: a map of the environment's colour.
oiiotool --pattern constant:color=0.1,0.13,0.18,1 64x32 4 -d float -o "$T/sky.exr" >/dev/null 2>&1 ||
    fail_all "oiiotool cannot write the environment map"
rb render "$T/area.yaml" --integrator bdpt -q --out "$T/bdpt-map" \
    --set "environment.map=$T/sky.exr" --set 'environment.color=[0, 0, 0]'
expect_exit 0 "bdpt renders the scene under an environment map"
e=$(relmse "$T/bdpt-map/$f" "$T/bdpt/$f")
echo "# the map against the colour: relMSE $e"
check "an environment map of the same colour lights the quads alike ($e)" below "$e" 1e-4

rb render "$T/area.yaml" --integrator bdpt -q --out "$T/bdpt-again"
expect_exit 0 "bdpt renders the scene again"
check "... with the same bits" \
    sh -c "\"$BUILD/tests/tools/samebits\" \"$T/bdpt/$f\" \"$T/bdpt-again/$f\" >/dev/null"

done_testing
