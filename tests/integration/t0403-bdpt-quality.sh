#!/bin/sh
# bdpt at the seed's budget (21 VPLs, 21 bundles, 4 temporal caches, the defaults), held to the
# reference in bdpt's path space:
# - the demo at 320x180, frames 3 to 6 (where a punctual light's VPL in the box's corner once made
#   a blotch of indirect R = 57.6 that lasted four frames: relMSE 0.83 at frame 4) and frame 11,
#   each within relMSE 0.03 of the reference at 512 samples a pixel, every value finite, and
#   within 0.0073, 0.0067, 0.0063, 0.0043 and 0.0044 (0.0085, 0.0075, 0.0070, 0.0052 and 0.0055
#   before the VPLs lit as disks), measured 0.0075, 0.0069, 0.0064, 0.0048 and
#   0.0048 with every cache at the pixel's centre (0.0092, 0.0079, 0.0067, 0.0046 and 0.0051 at
#   subpixel offsets once the emitters' diffuse light took their closed form; 0.0101, 0.0086,
#   0.0075, 0.0054, 0.0059 before; 0.016, 0.014, 0.012, 0.010, 0.007 before the filter stopped at
#   shadows' edges): the floor under the hovering box
#   is as dark as the reference's, where the lit floor in front of it once joined its kernel
#   (indirect G 0.24 against 0.01 at three pixels of frame 4); the bounds measured 0.0065,
#   0.0060, 0.0056, 0.0038 and 0.0039 once every VPL lit as the disk it stands for (0.0074,
#   0.0068, 0.0064, 0.0047, 0.0048 as points);
# - the floor beside the column's foot in frame 1 at 640x360, without the spot a VPL on the
#   column's side threw there as a point, and the top of the back wall within 15% of the
#   reference in frames 3 and 22, without the corner's light that a VPL just under the ceiling
#   threw back to it as a point through the bundles (+26% and +34% then);
# - the demo's frames 22 and 23, within 0.0065 and 0.0051 (0.0058 and 0.0045; 0.0072 and 0.0060
#   with the VPLs as points): the column's top seen edge-on once
#   reflected a VPL with its own glossy lobe where the bundles used the least roughness, a dot of
#   indirect 13.8 against 0.8 (relMSE 0.0110 and 0.0126; 0.0081 and 0.0069 since, 0.0072 and
#   0.0061 with the emitters' closed form);
# - the still, area-lit Cornell box once its caches are full: no 4x4 grid of the interleaved
#   sub-images above 0.5% of the local brightness in the beauty, 1% in its direct and indirect
#   layers (tests/tools/pattern; the plain mean over the filter's kernel left 15.8%), its steady
#   state the same bits from frame to frame, within relMSE 0.0064 of a converged reference (0.0062;
#   0.0065 before a bounce's disk took its parent's area and a lobe reflecting a disk widened;
#   0.0067
#   0.0071 before the emitters' specular light took its closed form; 0.0077 with the caches at
#   subpixel offsets, whose mean lit the ceiling's last row before the back wall at 1.8 times the
#   reference, 1.3 at the centre; 0.0107 before every bundle's hit took all the emitter points
#   and the filter's edges followed the slope) and its direct light within 0.0012 (0.0008; 0.0015
#   with the emitter points' maps lifting by four texels; 0.0021
#   with the points' own specular light, which drew the ceiling beside the light quad a spot per
#   point at half the reference; 0.0025 before the VPL maps' lift was bounded by the light
#   quad's gap, 0.0032 before the emitters' diffuse closed form; the room's concave edges once
#   took their neighbour's light, and the direct light's box once blurred every contact shadow),
#   the ceiling beside the quad 23% off the reference on average (61% point by point); the short
#   box's front face within 0.0025 (0.0048 while each bundle's hit saw one emitter point's hard
#   shadow and carried it across the face as bands);
#   the box in metal of roughness 0.1 within direct relMSE 0.0007 (0.0004; 0.0013 while the
#   emitter points drew its specular light a point at a time), and as mirrors too (1.2e-6;
#   84775 while the lobe's fit near a mirror missed its peak at some view angles);
#   a one-frame quick look shows that steady state; with fresh samples, frames 4-7 are within
#   0.03 too (a VPL on the back of the light quad, which no bundle finds, once lit the ceiling
#   beside it at 29 times the reference).
. tests/integration/lib.sh

rb render jobs/demo.yaml --integrator bdpt --size 320x180 --frames 0-23 -q --out "$T/d"
expect_exit 0 "bdpt renders the demo's frames 0-23 at 320x180"
rb reference jobs/demo.yaml --size 320x180 --frames 3-6,11,22-23 --spp 512 -q \
    --set integrator.reference.paths=bdpt --out "$T/r"
expect_exit 0 "the reference renders frames 3-6, 11, 22 and 23 in bdpt's path space"
for at in 3:0.0073 4:0.0067 5:0.0063 6:0.0043 11:0.0044 22:0.0065 23:0.0051; do
    f=${at%%:*} bound=${at#*:}
    name=$(printf 'frame.%04d.exr' "$f")
    tap_run "$BUILD/tests/tools/exrstat" "$T/d/$name" indirect.G 0.01
    e=$(relmse "$T/d/$name" "$T/r/$name")
    ei=$(relmse "$T/d/$name" "$T/r/$name" indirect)
    echo "# demo frame $f: relMSE $e (indirect $ei)"
    check "demo frame $f is within relMSE 0.03 of the reference ($e)" \
        awk "BEGIN { exit !($e != \"\" && $e < 0.03) }"
    check "demo frame $f is within relMSE $bound ($e)" \
        awk "BEGIN { exit !($e != \"\" && $e < $bound) }"
done
# The top of the back wall, below the ceiling's middle (a 16x8 block), frames 3 and 22: its
# two-bounce light once came out twice the reference's, in every frame, where a punctual VPL on
# the wall just under the ceiling lit the ceiling beside it as a point and the bundles carried
# that corner's light back to the wall (indirect G 0.70 and 0.79 against 0.55 and 0.59; 0.54 and
# 0.62 with the VPLs as disks).
wall_top() { # wall_top EXR: the block's mean indirect.G
    oiiotool "$1" --ch indirect.G --cut 16x8+160+28 --printstats 2>/dev/null |
        sed -n 's/.*Stats Avg: \([0-9.e+-]*\).*/\1/p'
}
for f in 3 22; do
    name=$(printf 'frame.%04d.exr' "$f")
    ours=$(wall_top "$T/d/$name")
    want=$(wall_top "$T/r/$name")
    echo "# demo frame $f, the back wall's top: indirect G $ours (reference $want)"
    check "demo frame $f: the back wall's top is within 15% of the reference ($ours, $want)" \
        awk "BEGIN { exit !(\"$ours\" != \"\" && \"$want\" != \"\" && $ours < 1.15 * $want && $ours > 0.85 * $want) }"
done
rb render jobs/demo.yaml --integrator bdpt --size 320x180 --frames 0-3 -q --out "$T/dp" \
    --set integrator.bdpt.vpl_spread=0
expect_exit 0 "bdpt renders the demo's frames 0-3 with the VPLs as points"
ours=$(wall_top "$T/dp/frame.0003.exr")
want=$(wall_top "$T/r/frame.0003.exr")
check "with the VPLs as points the back wall's top is too bright, so the check can fail ($ours)" \
    awk "BEGIN { exit !(\"$ours\" != \"\" && $ours > 1.15 * $want) }"
# row_mean EXR Y MISSING X...: the mean of indirect.G at (X, Y) over the Xs, a pixel that cannot be
# read counting as MISSING.
row_mean() {
    _exr=$1 _y=$2 _missing=$3 _sum=0
    shift 3
    for _x in "$@"; do
        _v=$("$BUILD/tests/tools/exrpixel" "$_exr" "$_x" "$_y" indirect.G)
        _sum=$(awk -v a="$_sum" -v b="${_v:-$_missing}" -v n=$# 'BEGIN { print a + b / n }')
    done
    echo "$_sum"
}
# The floor under the hovering box, frame 4 (the reference reads 0.006 to 0.014 there).
under=$(row_mean "$T/d/frame.0004.exr" 149 9 124 128 132)
echo "# the floor under the hovering box, frame 4: indirect G $under"
check "the floor under the hovering box is dark ($under < 0.08)" \
    awk "BEGIN { exit !($under < 0.08) }"
# The floor beside the column's foot, frame 1 at 640x360 (the reference reads 0.24 on average),
# where the bounce of a punctual VPL on the column's side, lighting as a point, threw a spot of
# indirect G 0.6 (0.42 on average over the three pixels); lighting as the disk it stands for,
# 0.22.
rb render jobs/demo.yaml --integrator bdpt --size 640x360 --frames 0-1 -q --out "$T/d640"
expect_exit 0 "bdpt renders the demo's frames 0-1 at 640x360"
beside=$(row_mean "$T/d640/frame.0001.exr" 316 9 408 411 414)
echo "# the floor beside the column's foot, frame 1 at 640x360: indirect G $beside"
check "the floor beside the column's foot has no spot ($beside < 0.32)" \
    awk "BEGIN { exit !($beside < 0.32) }"
rb render jobs/demo.yaml --integrator bdpt --size 640x360 --frames 0-1 -q --out "$T/d640p" \
    --set integrator.bdpt.vpl_spread=0
expect_exit 0 "bdpt renders the demo's frames 0-1 at 640x360 with the VPLs as points"
spot=$(row_mean "$T/d640p/frame.0001.exr" 316 0 408 411 414)
check "with the VPLs as points the spot is there, so the check can fail ($spot > 0.32)" \
    awk "BEGIN { exit !($spot > 0.32) }"

if have_scene cornell-box/CornellBox.glb; then
    box="$SCENES/cornell-box/CornellBox.glb"
    rb render "$box" --integrator bdpt --size 128x128 --frames 0-7 -q --out "$T/c"
    expect_exit 0 "bdpt renders the still Cornell box's frames 0-7"
    check "the steady state is the same bits from frame 6 to frame 7" \
        sh -c "\"$BUILD/tests/tools/samebits\" \"$T/c/frame.0006.exr\" \"$T/c/frame.0007.exr\" >/dev/null"
    # A quick look of one frame fills its caches first (warm-up frames before its start), so it
    # shows the steady state, not a quarter of it (relMSE 0.186 against the reference then).
    rb render "$box" --size 128x128 -q --out "$T/q"
    expect_exit 0 "a one-frame quick look of the Cornell box renders"
    check "the one-frame quick look has the steady state's bits" \
        sh -c "\"$BUILD/tests/tools/samebits\" \"$T/q/frame.0000.exr\" \"$T/c/frame.0007.exr\" >/dev/null"
    hm=$(sed -n 's/.*"hits": {"mean": \([0-9.e+-]*\).*/\1/p' "$T/q/frame.0000.timing.json")
    check "its mean cache hit ratio is above 0.99, every cache full ($hm; 0.33 with one of four)" \
        awk "BEGIN { exit !(\"$hm\" != \"\" && $hm > 0.99) }"
    for layer in "" direct indirect; do
        "$BUILD/tests/tools/pattern" "$T/c/frame.0007.exr" "$layer" 4 >"$T/pattern" 2>&1
        p=$(sed -n 's/^pattern \([0-9.e+-]*\)$/\1/p' "$T/pattern")
        sed 's/^/# /' "$T/pattern"
        if [ -z "$layer" ]; then
            check "the Cornell box's beauty shows no 4x4 grid above 0.5% ($p)" \
                awk "BEGIN { exit !(\"$p\" != \"\" && $p < 0.005) }"
        else
            check "the Cornell box's $layer light shows no 4x4 grid above 1% ($p)" \
                awk "BEGIN { exit !(\"$p\" != \"\" && $p < 0.01) }"
        fi
    done
    rb reference "$box" --size 128x128 --frames 7 --spp 2048 -q \
        --set integrator.reference.paths=bdpt --out "$T/cr"
    expect_exit 0 "the reference renders the Cornell box at 2048 samples a pixel"
    for layer in beauty direct indirect; do
        e=$(relmse "$T/c/frame.0007.exr" "$T/cr/frame.0007.exr" "$layer")
        echo "# Cornell box, caches full: $layer relMSE $e"
        [ "$layer" = beauty ] && eb=$e
        [ "$layer" = direct ] && ed=$e
    done
    check "the Cornell box is within relMSE 0.0064 of the reference ($eb)" \
        awk "BEGIN { exit !($eb != \"\" && $eb < 0.0064) }"
    # The short box's front face (28x28 pixels from (64, 88)).
    for im in c/frame.0007 cr/frame.0007; do
        oiiotool "$T/$im.exr" --cut 28x28+64+88 -o "$T/$im.face.exr"
    done
    ef=$(relmse "$T/c/frame.0007.face.exr" "$T/cr/frame.0007.face.exr")
    echo "# Cornell box, the short box's front face: relMSE $ef"
    check "the short box's front face is within relMSE 0.0025 of the reference ($ef)" \
        awk "BEGIN { exit !(\"$ef\" != \"\" && $ef < 0.0025) }"
    # Where a wall meets the ceiling, depth is continuous: reconstruct once took the wall's
    # cache sample for the ceiling's pixel beside it, and every concave edge of the room was
    # lined with its neighbour's light (direct relMSE 0.020; 0.011 once it tests normals).
    # A sub-image's one or two emitter points, spread over the interleave block by the direct
    # light's box, then blurred the boxes' contact shadows 2 pixels each way (0.011); each
    # pixel now takes every emitter point of the frame (0.003-0.004).
    # The light quad's points on its back light the ceiling beyond its edges through the 0.9-unit
    # gap; lifted off the ceiling by 4 texels' footprint, the ceiling farther than 58 units fell
    # behind their maps' hemispheres (0.0025; 0.0021 with the lift bounded by the gap).
    # The light quad's back lights the ceiling beside it, seen at a grazing angle, mostly
    # through the specular lobe: the points, a spot each, drew it at half the reference (relMSE
    # 0.0021, the row's pixels 61% off on average); the lobe's fitted closed form draws it whole
    # (0.0015, 22% off).
    # An emitter point's map lifts the point it looks up by two texels' footprint: at four, the
    # floor beside the short box saw past its bottom edge (0.0015; 0.0008 at two).
    check "the Cornell box's direct light is within relMSE 0.0012 of the reference ($ed)" \
        awk "BEGIN { exit !($ed != \"\" && $ed < 0.0012) }"
    for x in $(seq 52 75); do
        a=$("$BUILD/tests/tools/exrpixel" "$T/c/frame.0007.exr" "$x" 15 direct.G)
        b=$("$BUILD/tests/tools/exrpixel" "$T/cr/frame.0007.exr" "$x" 15 direct.G)
        echo "$a $b"
    done >"$T/beside"
    off=$(awk '$2 > 0 { d = $1 - $2; s += (d < 0 ? -d : d) / $2; k++ }
        END { if (k == 24) printf "%.3f\n", s / k }' "$T/beside")
    echo "# Cornell box, the ceiling beside the light quad (row 15): direct G off by $off on average"
    check "the ceiling beside the light quad is within 35% of the reference on average ($off)" \
        awk "BEGIN { exit !(\"$off\" != \"\" && $off < 0.35) }"
    # The ceiling's last row of pixels before the back wall (row 28, seen at a grazing angle):
    # its indirect light falls from 0.23 to 0.14 within that pixel. With the caches at subpixel
    # offsets (integrator.bdpt.subpixel spread) each read a point of the pixel's area, and their
    # mean read 0.25 (1.8 times the reference's centre); at the centre, 0.19.
    crease() {
        for x in 58 60 62 64 66 68 70 72 74; do
            "$BUILD/tests/tools/exrpixel" "$1" "$x" 28 indirect.G
        done | awk '{ s += $1 } END { if (NR == 9) printf "%.4f\n", s / NR }'
    }
    ca=$(crease "$T/c/frame.0007.exr") cr=$(crease "$T/cr/frame.0007.exr")
    echo "# Cornell box, the ceiling's last row before the back wall: indirect G $ca ($cr)"
    check "the ceiling's last row before the back wall is within 1.45 times the reference ($ca, $cr)" \
        awk "BEGIN { exit !(\"$ca\" != \"\" && \"$cr\" != \"\" && $ca < 1.45 * $cr) }"
    rb render "$box" --integrator bdpt --size 128x128 --frames 0-7 -q --out "$T/s" \
        --set integrator.bdpt.subpixel=spread
    expect_exit 0 "bdpt renders the Cornell box with its caches at subpixel offsets"
    cs=$(crease "$T/s/frame.0007.exr")
    echo "# ... at subpixel offsets: indirect G $cs"
    check "at subpixel offsets the caches' mean lights that row brighter ($cs > $ca)" \
        awk "BEGIN { exit !(\"$cs\" != \"\" && \"$ca\" != \"\" && $cs > $ca) }"
    # With fresh samples, frames 4-7 hold sample blocks 4 to 7, in which an emitter point's
    # bounce's bounce lands on the back of the light quad and lights the ceiling 0.9 units away
    # through a connection no bundle can balance (0.049 to 0.055 unbounded).
    rb render "$box" --integrator bdpt --size 128x128 --frames 0-75 -q --out "$T/f" \
        --set integrator.bdpt.samples=fresh
    expect_exit 0 "bdpt renders the Cornell box's frames 0-75 with fresh samples"
    for f in 4 5 6 7; do
        e=$(relmse "$T/f/frame.000$f.exr" "$T/cr/frame.0007.exr")
        check "fresh samples, frame $f: within relMSE 0.03 of the reference ($e)" \
            awk "BEGIN { exit !($e != \"\" && $e < 0.03) }"
    done
    # Every fourth frame has four new caches. Frames 70-73 once held a blotch of indirect 1.4 to
    # 3.0 on the ceiling beside the light quad (relMSE 0.054), from a bounce's bounce on the
    # quad's back lighting it as a point through the ceiling's own lobe at a grazing angle; the
    # others measured 0.0054 to 0.0106.
    worst=0
    for f in $(seq 7 4 75); do
        e=$(relmse "$T/f/frame.$(printf %04d "$f").exr" "$T/cr/frame.0007.exr")
        worst=$(awk "BEGIN { print ($e > $worst) ? $e : $worst }")
    done
    echo "# Cornell box, fresh samples, frames 7 to 75 by 4: worst relMSE $worst"
    check "no frame of fresh samples holds a blotch (worst relMSE $worst < 0.02)" \
        awk "BEGIN { exit !($worst < 0.02) }"
    # The classic view (make bench's camera), where the ceiling just behind the light quad's far
    # edge is seen at a grazing angle and its irradiance from the quad's back, 0.9 units below,
    # falls by two orders of magnitude within a pixel: the emitters' closed form taken at the
    # caches' subpixel samples read several times the reference's pixel centre there (direct
    # relMSE 0.051), and the points alone drew spots (0.0049); at the pixels' centres, 0.0043;
    # with every cache there, 0.0030; with the quad's back points seeing the ceiling, 0.0024;
    # with the emitters' specular light in closed form, 0.0020; with an emitter point's map
    # lifting the point by two texels, not four, 0.0013.
    # direct_check NAME SCENE LAST BOUND: SCENE at 128x128 rendered by bdpt (frames 0-LAST) into
    # $T/NAME and by the reference (frame LAST, 1024 samples a pixel), and the direct light's
    # relMSE between them checked against BOUND.
    direct_check() {
        _name=$1 _scene=$2 _last=$(printf %04d "$3") _bound=$4
        rb render "$_scene" --integrator bdpt --size 128x128 --frames "0-$3" -q --out "$T/$_name"
        expect_exit 0 "bdpt renders the $_name Cornell box"
        rb reference "$_scene" --size 128x128 --frames "$3" --spp 1024 -q \
            --set integrator.reference.paths=bdpt --out "$T/$_name-ref"
        expect_exit 0 "the reference renders the $_name Cornell box at 1024 samples a pixel"
        _e=$(relmse "$T/$_name/frame.$_last.exr" "$T/$_name-ref/frame.$_last.exr" direct)
        echo "# the $_name Cornell box: direct relMSE $_e"
        check "the $_name box's direct light is within relMSE $_bound of the reference ($_e)" \
            awk "BEGIN { exit !(\"$_e\" != \"\" && $_e < $_bound) }"
    }
    classic_cornell "$T/classic.yaml" "$box" 128x128 9 <<EOT
default_light: off
integrator: {name: bdpt}
EOT
    direct_check classic-view "$T/classic.yaml" 9 0.0017
    # metal_box ROUGHNESS NAME: the box in metal of that roughness (its materials' factors
    # rewritten in place, the same length) as $T/NAME.glb, its direct light checked against
    # 0.0007 (direct_check, frame 7).
    metal_box() {
        _r=$1
        perl -0777 -pe \
            "s/\"metallicFactor\":0,\"roughnessFactor\":0.5/\"metallicFactor\":1,\"roughnessFactor\":$_r/g" \
            "$box" >"$T/$2.glb"
        check "the $2 box differs from the box in its materials alone" \
            sh -c "[ \$(cmp -l \"$box\" \"$T/$2.glb\" | wc -l) -eq 10 ]"
        direct_check "$2" "$T/$2.glb" 7 0.0007
    }
    # In metal of roughness 0.1: glossy surfaces take the area light through a narrow lobe, which
    # the emitter points drew a point at a time (direct relMSE 0.0013) and the lobe's fitted
    # closed form draws whole (0.0004).
    metal_box 0.1 metal
    # As mirrors (roughness 0): the lobe's fit near a mirror once came out tens of times too wide
    # at some view angles, and the emitters' ratio divided the lobe's light at a point by that
    # fit's density there: 29 pixels of direct light above 100, up to 8971, where the reference's
    # highest is the quad's own 100 (relMSE 84775; 1.2e-6 since).
    metal_box 0.0 mirror
else
    skip "the Cornell box's quality" "$SCENES/cornell-box/CornellBox.glb is not there"
fi

done_testing
