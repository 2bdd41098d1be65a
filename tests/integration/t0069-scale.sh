#!/bin/sh
# Scenes past one storage binding's range render (issue 26, scale): the GPU integrators read the
# vertices and indices by device address (shaders/common/geometry_shared.h), so a scene whose
# source vertices outgrow maxStorageBufferRange (128 MiB on lavapipe), once refused with exit 1,
# renders with every integrator, finite, and agrees with the CPU reference.
. tests/integration/lib.sh

TRI="$BUILD/tests/tools/triangles"
# A rolling terrain of 530 x 530 quads without normals: 561,800 triangles, which the loader
# gives three vertices each (flat shading): 1,685,400 vertices of 80 bytes, 134,832,000 bytes,
# just past lavapipe's 134,217,728.
mkdir -p "$T/big"
counts=$("$TRI" write "$T/big" 561800 flat)
check "the terrain is written ($counts: triangles, vertices)" test "$counts" = "561800 1685400"
range=$("$RB" info 2>/dev/null | sed -n 's/^ *max storage buffer range: \([0-9]*\) bytes$/\1/p' |
    head -n 1)
if [ -n "$range" ] && [ $((1685400 * 80)) -gt "$range" ]; then
    ok "its source vertices (134832000 bytes) pass one binding's range ($range bytes)"
else
    skip "its source vertices pass one binding's range" \
        "the device binds ${range:-?} bytes, more than the scene needs"
fi

job="$T/big/terrain.yaml"
# hybrid with the shortest history: a frame pre-rolls W frames (128 by default), each as costly
# as the frame at this scale.
for integrator in direct bdpt hybrid; do
    rb render "$job" --integrator $integrator --out "$T/$integrator" -q \
        --set integrator.hybrid.history=2
    expect_exit 0 "$integrator renders the 1.7 M vertices"
    tap_run "$BUILD/tests/tools/exrstat" "$T/$integrator/frame.0000.exr" R 0.05
done
# Under a sky, hybrid bakes its light into points (16 bytes each: three a side of every triangle
# and bake_texels more) that follow the BVH's triangles in one buffer; with 5 M more they pass
# one binding's range too (163 MB), and are read by address.
sed 's/^environment: .*/environment: {color: [0.3, 0.4, 0.5]}/' "$job" >"$T/big/sky.yaml"
rb render "$T/big/sky.yaml" --integrator hybrid --out "$T/sky" -q --set integrator.hybrid.history=2 \
    --set integrator.hybrid.bake_samples=1 --set integrator.hybrid.bake_texels=5000000
expect_exit 0 "hybrid bakes a sky's light into 8.4 M points"
tap_run "$BUILD/tests/tools/exrstat" "$T/sky/frame.0000.exr" R 0.05

rb reference "$job" --spp 4 --set integrator.reference.paths=direct --out "$T/refdirect" -q
expect_exit 0 "the reference renders its direct path space"
rb reference "$job" --spp 64 --out "$T/ref" -q
expect_exit 0 "the reference renders every path"

# The light above leaves no shadow on the terrain, so the direct integrator's shading is the
# reference's direct light (measured: relMSE 1.2e-7); bdpt and hybrid add the little light the
# slopes exchange, within the noise of one frame and of 64 samples (measured 1.1e-4, 2.6e-4).
e=$(relmse "$T/direct/frame.0000.exr" "$T/refdirect/frame.0000.exr")
check "direct agrees with the reference's direct light (relMSE $e < 1e-4)" \
    awk "BEGIN { exit !(\"$e\" != \"\" && $e < 1e-4) }"
for integrator in bdpt hybrid; do
    e=$(relmse "$T/$integrator/frame.0000.exr" "$T/ref/frame.0000.exr")
    check "$integrator agrees with the reference (relMSE $e < 2e-3)" \
        awk "BEGIN { exit !(\"$e\" != \"\" && $e < 2e-3) }"
done

done_testing
