#!/bin/sh
# The hybrid integrator's hits (seed 003): what the screen trace hits is the surface the BVH
# finds along the same ray; the BVH passes alpha-masked texels as the G-buffer does; and the
# baked light of emitters and the environment gives an
# area-lit room (the Cornell box, lit by its ceiling panel alone) its bounce, converging to the
# reference with one bounce, where without the bake the bounce is missing.
. tests/integration/lib.sh

SAME="$BUILD/tests/tools/samebits"
same() { "$SAME" "$1" "$2" >/dev/null; }
below() { awk -v a="$1" -v b="$2" 'BEGIN { exit !(a + 0 < b + 0) }'; }
# screen_check FILE: "checked agreed" of a timing sidecar
screen_check() {
    sed -n 's/.*"screen_check": {"checked": \([0-9]*\), "agreed": \([0-9]*\)}.*/\1 \2/p' "$1"
}

# ---- the screen trace against the BVH, on the demo ------------------------------------------

# The demo's own job, moving, at a small size: every screen-space hit is traced again through
# the BVH (integrator.hybrid.check_screen), which must find the same surface: its hit projects
# to the pixel the screen trace hit, or one beside it, on the plane of the G-buffer's surface.
rb render jobs/demo.yaml --integrator hybrid --size 160x90 --frames 0-3 --out "$T/d" -q \
    --set integrator.hybrid.check_screen=true --set integrator.hybrid.rays=2
expect_exit 0 "4 frames of the demo with the screen check"
for f in 0000 0003; do
    # shellcheck disable=SC2046 # two numbers; 0 0 when the sidecar has none
    set -- $(screen_check "$T/d/frame.$f.timing.json") 0 0
    share=$(awk -v c="${1:-0}" -v a="${2:-0}" 'BEGIN { printf "%.4f", c ? a / c : 0 }')
    echo "# frame $f: $2 of $1 screen hits agree with the BVH ($share)"
    check "frame $f: at least 95% of the screen hits agree with the BVH ($share of ${1:-0})" \
        awk -v s="$share" -v c="${1:-0}" 'BEGIN { exit !(s >= 0.95 && c > 1000) }'
done
check "without the check the sidecar has no screen_check" \
    sh -c "rm -rf '$T/n' && '$RB' render jobs/demo.yaml --integrator hybrid --size 32x18 --frames 0 --out '$T/n' -q >/dev/null && ! grep -q screen_check '$T/n/frame.0000.timing.json'"

# ---- budgets and limits ----------------------------------------------------------------------

# A BVH budget of 0 holds every object: the demo's frames have the default budget's bits (2
# million triangles, more than the demo has).
for b in 0 2000000; do
    rb render jobs/demo.yaml --integrator hybrid --size 64x36 --frames 0-1 --out "$T/b$b" -q \
        --set integrator.hybrid.bvh_triangles=$b
    expect_exit 0 "the demo with a BVH budget of $b triangles"
done
check "a BVH budget of 0 gives the whole scene's bits" same "$T/b0/frame.0001.exr" "$T/b2000000/frame.0001.exr"
# Seed 003's LOD: under a budget of 300 of the demo's 754 triangles, objects over their share
# enter by a quarter of their triangles (the info log says so), and the BVH finds more
# of the scene: more BVH hits, and more screen hits it agrees with, than without coarser objects.
bvh_hits() { sed -n 's/.*"bvh_hits": \([0-9]*\).*/\1/p' "$1"; }
agreed() { sed -n 's/.*"agreed": \([0-9]*\).*/\1/p' "$1"; }
for lod in true false; do
    rb render jobs/demo.yaml --integrator hybrid --size 96x54 --frames 0-1 --out "$T/lod$lod" -v \
        --set integrator.hybrid.bvh_triangles=300 --set integrator.hybrid.bvh_lod=$lod \
        --set integrator.hybrid.check_screen=true
    expect_exit 0 "the demo under a BVH budget of 300 triangles, bvh_lod $lod"
    cp "$T/stderr" "$T/lod$lod.log"
done
check "with bvh_lod objects enter by their coarser version" \
    grep -q "objects ([0-9]* triangles), [1-9][0-9]* of them by their coarser version" "$T/lodtrue.log"
check "without it none does" grep -q "0 of them by their coarser version" "$T/lodfalse.log"
hl=$(bvh_hits "$T/lodtrue/frame.0001.timing.json") hn=$(bvh_hits "$T/lodfalse/frame.0001.timing.json")
al=$(agreed "$T/lodtrue/frame.0001.timing.json") an=$(agreed "$T/lodfalse/frame.0001.timing.json")
echo "# BVH hits $hl with coarser objects, $hn without; screen hits agreed $al and $an"
check "coarser objects: more BVH hits ($hl > $hn) and agreements ($al > $an)" \
    test "${hl:-0}" -gt "${hn:-0}" -a "${al:-0}" -gt "${an:-0}"
# Ray slots past the device's storage range are refused before anything renders, naming the
# buffer and the limit (lavapipe's 128 MiB: 1920x1080 holds one ray a lobe, not two).
if grep -q llvmpipe "$T/b0/frame.0000.timing.json"; then
    rb render jobs/demo.yaml --integrator hybrid --size 1920x1080 --frames 0 --out "$T/big" -q \
        --set integrator.hybrid.rays=2
    expect_exit 1 "2 rays a lobe at 1920x1080 on lavapipe are refused (the device cannot)"
    stderr_has "storage buffer 'ray slots' binds 265420800 bytes, more than the device's maxStorageBufferRange" \
        "the refusal names the ray slots, their size and the limit"
    check "nothing was written" test ! -e "$T/big/frame.0000.exr"
else
    skip "the storage-range refusal" "the device is not lavapipe, whose 128 MiB range it needs"
fi

# ---- alpha masks: the BVH passes what the G-buffer discards ----------------------------------

# t0040's floor and occluder quad, the quad given a material of its own: masked out entirely
# (alpha 0.1 under the cutoff 0.5: the G-buffer, the shadow maps and the reference see no quad)
# or solid. A point light between the floor and the quad lights the quad's underside, so a ray
# from the floor that hits the quad brings back light; the floor cannot light itself and the
# environment is black, so the masked scene's indirect light is exactly zero everywhere. Every
# ray goes through the BVH (screen_steps 0).
"$BUILD/tests/tools/analytic" scene "$T" || fail_all "cannot write the analytic scene"
ghost='{"name":"Ghost","doubleSided":true,"alphaMode":"MASK","alphaCutoff":0.5,"pbrMetallicRoughness":{"baseColorFactor":[0.8,0.8,0.8,0.1]}}'
solid='{"name":"Ghost","doubleSided":true,"pbrMetallicRoughness":{"baseColorFactor":[0.8,0.8,0.8,1]}}'
single='{"name":"Ghost","doubleSided":false,"pbrMetallicRoughness":{"baseColorFactor":[0.8,0.8,0.8,1]}}'
for v in ghost solid single; do
    case $v in ghost) m=$ghost ;; solid) m=$solid ;; *) m=$single ;; esac
    sed -e 's/"indices":5,"material":0/"indices":5,"material":1/' \
        -e "s/],\"buffers\"/,$m],\"buffers\"/" "$T/plane.gltf" >"$T/$v.gltf"
    sed -e "s/plane.gltf/$v.gltf/" -e 's/position: \[0, 2, 0\]/position: [1.5, 0.5, 0]/' \
        -e 's/resolution: \[320, 200\]/resolution: [96, 60]/' "$T/point.yaml" >"$T/$v.yaml"
    rb render "$T/$v.yaml" --integrator hybrid --frames 0-3 --out "$T/o$v" -q \
        --set integrator.hybrid.screen_steps=0
    expect_exit 0 "the floor under a $v quad renders"
done
nonzero() { "$BUILD/tests/tools/layersum" "$1" 1 indirect indirect | sed -n 's/^indirect total .* nonzero \([0-9]*\)$/\1/p' | head -n 1; }
ng=$(nonzero "$T/oghost/frame.0003.exr")
ns=$(nonzero "$T/osolid/frame.0003.exr")
check "the masked quad sends no light through the BVH ($ng pixels with indirect light)" test "$ng" = 0
check "the solid quad does ($ns pixels with indirect light)" test "${ns:-0}" -gt 1000
# The quad's underside is its back: single-sided, the camera above still sees its front, and
# the floor's rays hit, shade and are lit by its back as the reference's bounce rays are.
check "a single-sided quad's back lights the floor as a double-sided one's does (same bits)" \
    same "$T/osolid/frame.0003.exr" "$T/osingle/frame.0003.exr"

# ---- the baked light: the Cornell box -------------------------------------------------------

if have_scene cornell-box/CornellBox.glb; then
    box="$SCENES/cornell-box/CornellBox.glb"
    rb reference "$box" --size 64x64 --frames 63 --spp 1024 --out "$T/ref" -q \
        --set integrator.reference.max_bounces=1
    expect_exit 0 "the Cornell box's reference with one bounce, 1024 spp"
    ref="$T/ref/frame.0063.exr"
    # Enough samples that what is left is bias: 16 rays a lobe and frame, no noise target, a
    # pixel aiming for 1024 samples, 256 light samples a baked point; one bounce (no feedback).
    for bake in 256 0; do
        rb render "$box" --integrator hybrid --size 64x64 --frames 0-63 --out "$T/c$bake" -q \
            --set integrator.hybrid.history=64 --set integrator.hybrid.rays=16 \
            --set integrator.hybrid.spp=1024 --set integrator.hybrid.noise=0 \
            --set integrator.hybrid.bake_samples=$bake --set integrator.hybrid.feedback=false
        expect_exit 0 "64 frames of the Cornell box, bake_samples $bake"
    done
    baked=$(relmse "$T/c256/frame.0063.exr" "$ref" indirect)
    bare=$(relmse "$T/c0/frame.0063.exr" "$ref" indirect)
    echo "# Cornell box indirect relMSE after 64 frames: $baked baked, $bare without the bake"
    check "Cornell box: indirect within relMSE 0.01 of the reference after 64 frames ($baked)" \
        below "$baked" 0.01
    check "Cornell box: without the bake the bounce is missing (indirect relMSE $bare > 0.1)" \
        below 0.1 "$bare"
    direct=$(relmse "$T/c256/frame.0063.exr" "$ref" direct)
    echo "# Cornell box direct relMSE after 64 frames: $direct (the panel found by BRDF samples)"
    check "Cornell box: direct within relMSE 0.1 of the reference after 64 frames ($direct)" \
        below "$direct" 0.1
    # A chunk long after the start: its warm-ups build the BVH and bake from frame 12 where the
    # whole run built them at frame 0 and kept them (the box does not move); the bake is a
    # function of the geometry, not of the frame that made it.
    for run in "0-19 w" "16-19 k"; do
        # shellcheck disable=SC2086 # two words: the frames and the directory
        set -- $run
        rb render "$box" --integrator hybrid --size 32x32 --frames "$1" --out "$T/$2" -q \
            --set integrator.hybrid.history=4
        expect_exit 0 "the Cornell box, frames $1, history 4"
    done
    for f in 0016 0019; do
        check "Cornell box: frame $f of the chunk 16-19 has the whole run's bits" \
            same "$T/w/frame.$f.exr" "$T/k/frame.$f.exr"
    done
else
    skip "the Cornell box's baked light" "no $SCENES/cornell-box/CornellBox.glb"
fi

done_testing
