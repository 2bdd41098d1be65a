#!/bin/sh
# The hybrid integrator's BVH chooses objects under its triangle budget by occlusion relevance
# from the camera against traversal cost, an object over its share by its coarser version (seed
# 003). On a generated scene with more triangles than the budget (tests/tools/crowd: a sky-lit
# floor, eight finely tessellated spheres around the view, 64 coarse boxes far away) the log
# names what is kept; relevance keeps every sphere and the error against the reference is smaller
# than with the camera-independent area score (and on the demo under a small budget its BVH
# agrees with the screen more often); and the choice follows the camera as it moves while chunks
# keep the whole run's bits.
. tests/integration/lib.sh

SAME="$BUILD/tests/tools/samebits"
same() { "$SAME" "$1" "$2" >/dev/null; }
below() { awk -v a="$1" -v b="$2" 'BEGIN { exit !(a + 0 < b + 0) }'; }
# kept LOG KIND WHAT: how many objects whose node's name starts with KIND the log says are WHAT
# (whole, coarser, left out) in the first BVH it lists
kept() {
    sed -n "s/.*the BVH of frame 0: object [0-9]* (node '$2[0-9]*'): \([a-z ]*\), .*/\1/p" "$1" |
        grep -c "^$3\$"
}

"$BUILD/tests/tools/crowd" "$T" || fail_all "cannot write the crowd scene"
triangles=$("$BUILD/tests/tools/triangles" "$T/crowd.gltf" | cut -d' ' -f1)
echo "# the crowd scene: $triangles triangles, a budget of 2800"
check "the scene has more triangles than the budget ($triangles > 2800)" test "$triangles" -gt 2800

# A still shot of 16 frames, each score under the budget.
for score in relevance area; do
    rb render "$T/crowd.yaml" --out "$T/$score" -v -v \
        --set integrator.hybrid.bvh_triangles=2800 --set integrator.hybrid.bvh_select=$score
    expect_exit 0 "16 frames of the crowd, bvh_select $score"
    cp "$T/stderr" "$T/$score.log"
    sed -n 's/.*info: hybrid: the BVH holds/# '"$score"': holds/p' "$T/$score.log"
    held=$(sed -n 's/.*the BVH holds [0-9]* of [0-9]* objects (\([0-9]*\) triangles).*/\1/p' \
        "$T/$score.log" | head -n 1)
    check "$score: the BVH holds no more than the budget (${held:-none} triangles)" \
        test "${held:-9999}" -le 2800
done
r_whole=$(kept "$T/relevance.log" near whole) r_coarse=$(kept "$T/relevance.log" near coarser)
a_whole=$(kept "$T/area.log" near whole) a_coarse=$(kept "$T/area.log" near coarser)
far=$(kept "$T/relevance.log" far whole)
echo "# near spheres kept: relevance $r_whole whole and $r_coarse coarser; area $a_whole whole" \
    "and $a_coarse coarser; far boxes whole with relevance: $far of 64"
check "relevance keeps all 8 spheres, each by its coarser version" \
    test "$r_coarse" -eq 8 -a "$r_whole" -eq 0
check "the area score keeps at most 2 spheres, spending the budget on far boxes" \
    test $((a_whole + a_coarse)) -le 2
check "the floor is whole with either" sh -c \
    "grep -q \"(node 'floor'): whole\" '$T/relevance.log' && grep -q \"(node 'floor'): whole\" '$T/area.log'"

# Against the reference (its default path space, 256 samples a pixel) at frame 15.
rb reference "$T/crowd.yaml" --frames 15 --spp 256 --out "$T/ref" -q
expect_exit 0 "the crowd's reference"
rel=$(relmse "$T/relevance/frame.0015.exr" "$T/ref/frame.0015.exr")
area=$(relmse "$T/area/frame.0015.exr" "$T/ref/frame.0015.exr")
echo "# relMSE against the reference at frame 15: relevance $rel, area $area"
check "relevance's error is smaller than the area score's ($rel < $area)" below "$rel" "$area"
check "and by more than half ($rel < $area / 2)" below "$rel" "$(awk -v a="$area" 'BEGIN { print a / 2 }')"

# The light samples' shadow rays march the screen for the surfaces the budget leaves out (the
# area score leaves most spheres out): their shadows on the floor come back, and the direct
# layer is nearer the reference than with the BVH's occluders alone.
rb render "$T/crowd.yaml" --out "$T/area-bvh" -q --set integrator.hybrid.bvh_triangles=2800 \
    --set integrator.hybrid.bvh_select=area --set integrator.hybrid.screen_shadows=false
expect_exit 0 "the crowd, bvh_select area, screen_shadows false"
d_screen=$(relmse "$T/area/frame.0015.exr" "$T/ref/frame.0015.exr" direct)
d_bvh=$(relmse "$T/area-bvh/frame.0015.exr" "$T/ref/frame.0015.exr" direct)
echo "# area score, direct layer against the reference: screen shadows $d_screen, BVH alone $d_bvh"
check "screen shadows bring the direct layer nearer the reference ($d_screen < 0.8 x $d_bvh)" \
    below "$d_screen" "$(awk -v a="$d_bvh" 'BEGIN { print 0.8 * a }')"

# The demo (754 triangles) under a budget of 300, every screen hit traced again through the BVH
# (check_screen): the BVH that relevance chooses finds the surface the screen saw more often.
agreed() { sed -n 's/.*"agreed": \([0-9]*\).*/\1/p' "$1"; }
for score in relevance area; do
    rb render jobs/demo.yaml --integrator hybrid --size 96x54 --frames 0-1 --out "$T/d$score" -q \
        --set integrator.hybrid.bvh_triangles=300 --set integrator.hybrid.check_screen=true \
        --set integrator.hybrid.bvh_select=$score
    expect_exit 0 "the demo under a budget of 300, bvh_select $score"
done
dr=$(agreed "$T/drelevance/frame.0001.timing.json") da=$(agreed "$T/darea/frame.0001.timing.json")
echo "# the demo, budget 300: the BVH agrees with $dr screen hits with relevance, $da with area"
check "the demo: relevance's BVH agrees with more screen hits ($dr > $da)" \
    test "${dr:-0}" -gt "${da:-0}"

# No budget: every object whole, nothing logged as coarser or left out.
rb render "$T/crowd.yaml" --out "$T/all" --frames 0-3 -v -v --set integrator.hybrid.bvh_triangles=0
expect_exit 0 "the crowd without a budget"
check "without a budget nothing is coarser or left out" \
    sh -c "! grep -q 'coarser, \\|left out, ' '$T/stderr'"

# The camera moving left and closer (crowd-moving.yaml), under a budget of 1500: the choice
# follows the camera at the epochs' poses, and a chunk that starts late has the whole run's bits.
set -- --set integrator.hybrid.bvh_triangles=1500 --set integrator.hybrid.history=4
rb render "$T/crowd-moving.yaml" --out "$T/mv" -v -v "$@"
expect_exit 0 "the moving crowd, frames 0-11"
changes=$(sed -n 's/.*the BVH of frame \([0-9]*\): object 0 .*/\1/p' "$T/stderr" | tr '\n' ' ')
echo "# the choice of objects changed at frames: $changes"
check "the choice changes as the camera moves (at frames $changes)" \
    test "$(echo "$changes" | wc -w)" -ge 2
check "the budget leaves triangles out, so the light samples march the screen too" \
    grep -q 'triangles left out by the budget' "$T/stderr"
check "and the log counts them" sh -c \
    "! grep -q ' 0 triangles left out by the budget' '$T/stderr'"
rb render "$T/crowd-moving.yaml" --out "$T/mvc" --frames 8-11 -q "$@"
expect_exit 0 "the moving crowd, the chunk 8-11"
for f in 08 11; do
    check "the chunk 8-11: frame $f has the whole run's bits" \
        same "$T/mv/frame.00$f.exr" "$T/mvc/frame.00$f.exr"
done

done_testing
