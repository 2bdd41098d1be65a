#!/bin/sh
# The hybrid integrator (seed 003): its passes are the seed's table and its ray counts add up; its
# indirect light converges to the reference with one bounce as a still shot accumulates; rays per
# frame fall as tiles and pixels have their samples; and it is deterministic across runs, thread
# counts and chunks, bit for bit.
. tests/integration/lib.sh

# below A B: A < B, as numbers
below() { awk -v a="$1" -v b="$2" 'BEGIN { exit !(a + 0 < b + 0) }'; }
# counts FILE: the ray_counts of a timing sidecar, "requested screen queued bvh misses dropped"
counts() {
    sed -n 's/.*"ray_counts": {"requested": \([0-9]*\), "screen_hits": \([0-9]*\), "queued": \([0-9]*\), "bvh_hits": \([0-9]*\), "misses": \([0-9]*\), "dropped": \([0-9]*\)}.*/\1 \2 \3 \4 \5 \6/p' "$1"
}

# The demo room, its animation stopped and its camera still; its hits lit by direct light alone
# (feedback off), to be held to the reference with one bounce.
still_demo "$T/still.yaml" 96x54 63 "[direct, indirect, depth, motion, indirect_diffuse, indirect_specular]" \
    "{name: hybrid, hybrid: {history: 64, feedback: false}}"

# ---- passes and ray counts ------------------------------------------------------------------

rb render "$T/still.yaml" --out "$T/s"
expect_exit 0 "64 frames of the still demo render with the hybrid integrator"
tm="$T/s/frame.0005.timing.json"
for pass in gbuffer direct hiz diffuse_rays specular_rays ray_queue bvh_rays light_rays accumulate tiles \
    diffuse_filter specular_filter output; do
    check "the timing sidecar names the pass '$pass'" grep -q "\"name\": \"$pass\"" "$tm"
done
set -- $(counts "$tm")
check "ray counts are in the timing sidecar" test $# -eq 6
echo "# frame 5: requested $1, screen hits $2, queued $3, BVH hits $4, misses $5, dropped $6"
check "some rays hit in screen space, some go to the BVH and hit there" \
    test "$2" -gt 0 -a "$3" -gt 0 -a "$4" -gt 0
check "queued rays are BVH hits, misses or dropped" test "$3" -eq $(($4 + $5 + $6))
check "requested rays are screen hits, queued, or sampled below the surface" \
    test "$1" -ge $(($2 + $3))
check "the default queue drops no ray" test "$6" -eq 0

# ---- adaptivity: rays per frame fall as the accumulator fills -----------------------------------

curve=""
for f in 01 04 08 16 24 31 32; do
    set -- $(counts "$T/s/frame.00$f.timing.json")
    curve="$curve $f:$1"
    eval "r$f=$1"
done
echo "# rays requested by frame (frame:rays):$curve"
check "rays per frame fall as pixels meet their samples ($r31 < $r16 < $r01)" \
    test "$r31" -lt "$r16" -a "$r16" -lt "$r01"
check "the younger accumulator starting again at frame 32 asks for rays again" \
    test "$r32" -gt "$r31"
# The demo's glossy floor makes rare bright paths: the default target stops only some of its
# tiles (specular ones) by frame 31; a target of 10, which every tile meets, stops more.
rb render "$T/still.yaml" --out "$T/n" -q --frames 31 --set integrator.hybrid.noise=10
set -- $(counts "$T/n/frame.0031.timing.json")
check "with a noise target every tile meets, done tiles stop requesting at frame 31 ($1 < $r31)" \
    test "$1" -lt "$r31"

# ---- convergence to the reference with one bounce ---------------------------------------------

rb reference "$T/still.yaml" --frames 63 --spp 1024 --set integrator.reference.max_bounces=1 \
    --out "$T/r" -q
expect_exit 0 "the still demo's reference with one bounce, 1024 spp"
e0=$(relmse "$T/s/frame.0000.exr" "$T/r/frame.0063.exr" indirect)
e7=$(relmse "$T/s/frame.0007.exr" "$T/r/frame.0063.exr" indirect)
e63=$(relmse "$T/s/frame.0063.exr" "$T/r/frame.0063.exr" indirect)
echo "# indirect relMSE against the reference: frame 0 $e0, frame 7 $e7, frame 63 $e63"
check "the indirect light converges: relMSE falls from frame 0 to 7 to 63" \
    sh -c "awk -v a=$e63 -v b=$e7 -v c=$e0 'BEGIN { exit !(a < b && b < c) }'"
rb render "$T/still.yaml" --out "$T/s4" -q --frames 63 --set integrator.hybrid.rays=4 \
    --set integrator.hybrid.spp=256
expect_exit 0 "frame 63 with 4 rays a lobe and frame (256 samples)"
for layer in indirect indirect_diffuse indirect_specular direct; do
    e=$(relmse "$T/s4/frame.0063.exr" "$T/r/frame.0063.exr" $layer)
    echo "# $layer relMSE after 64 frames of 4 rays: $e"
    check "$layer after 64 frames of 4 rays is within relMSE 0.01 of the reference ($e)" \
        below "$e" 0.01
done

# ---- determinism: runs, threads, chunks ---------------------------------------------------------

args="--integrator hybrid --size 48x27 -q --set integrator.hybrid.history=4"
# shellcheck disable=SC2086
rb render jobs/demo.yaml $args --frames 0-9 --out "$T/whole"
expect_exit 0 "frames 0-9 of the moving demo"
# shellcheck disable=SC2086
rb render jobs/demo.yaml $args --frames 0-9 --out "$T/again"
# shellcheck disable=SC2086
LP_NUM_THREADS=1 rb render jobs/demo.yaml $args --frames 6-9 --out "$T/t1"
# shellcheck disable=SC2086
LP_NUM_THREADS=4 rb render jobs/demo.yaml $args --frames 6-9 --out "$T/t4"
for f in 6 7 8 9; do
    check "frame $f: a second run has the first's bits" \
        cmp -s "$T/whole/frame.000$f.exr" "$T/again/frame.000$f.exr"
    check "frame $f: the chunk 6-9 on 1 thread has the whole run's bits" \
        cmp -s "$T/whole/frame.000$f.exr" "$T/t1/frame.000$f.exr"
    check "frame $f: the chunk 6-9 on 4 threads has the whole run's bits" \
        cmp -s "$T/whole/frame.000$f.exr" "$T/t4/frame.000$f.exr"
done
check "the moving demo's frames differ" sh -c "! cmp -s '$T/whole/frame.0008.exr' '$T/whole/frame.0009.exr'"

# A small queue drops rays, and says so.
# shellcheck disable=SC2086
rb render jobs/demo.yaml $args --frames 0 --out "$T/q" --set integrator.hybrid.queue_rays=64
set -- $(counts "$T/q/frame.0000.timing.json")
check "a queue of 64 rays traces 64 and counts the rest as dropped ($6)" \
    test "$6" -gt 0 -a $(($4 + $5)) -eq 64

done_testing
