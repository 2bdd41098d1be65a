#!/bin/sh
# Temporal interleaved sampling (seed 000, section A): bdpt's l temporal caches. A static shot is
# the same, bit for bit, from frame to frame once every cache is written (the demo with its
# animation stopped, and the Cornell box); the hit-ratio sidecar is near 1 away from moving
# objects and clearly lower in the ring around them; the caches flicker less than fresh samples
# every frame and come closer to the reference than one frame; a chunk (frames 10-15) and a SIGKILLed run
# resumed give a whole run's bits, beauty, layers and hits.
. tests/integration/lib.sh

SAME="$BUILD/tests/tools/samebits"
# same A B: A and B hold the same values, bit for bit (their metadata name different frames)
same() { "$SAME" "$1" "$2" >/dev/null; }
# below A B: A < B, as numbers
below() { awk -v a="$1" -v b="$2" 'BEGIN { exit !(a + 0 < b + 0) }'; }
json() { # json KEY FILE: the first number under KEY
    sed -n "s/.*\"$1\": \([0-9.e+-]*\).*/\1/p" "$2" | head -n 1
}

# The demo room, its animation stopped at 0.5 s and its camera still.
still_demo "$T/still.yaml" 96x54 7 "[direct, indirect, depth, motion]" \
    "{name: bdpt, bdpt: {vpls: 16, bundles: 16, vpl_size: 64, bundle_size: 64, rsm_size: 64}}"
# The same, its animation running three times as fast (the box spins and bobs, the column
# bends), at 160x90.
sed 's/speed: 0,/speed: 3,/; s/\[96, 54\]/[160, 90]/' "$T/still.yaml" >"$T/moving.yaml"

# ---- steady state --------------------------------------------------------------------------

rb render "$T/still.yaml" --out "$T/s" -q
expect_exit 0 "8 frames of the still demo render with 4 caches"
check "frame 0 has a hit-ratio sidecar" test -s "$T/s/frame.0000.hits.exr"
check "frame 2 differs from frame 3 (cache 3 is not written before frame 3)" \
    sh -c "! '$SAME' '$T/s/frame.0002.exr' '$T/s/frame.0003.exr' >/dev/null"
for f in 4 5 6 7; do
    check "still demo: frame $f has frame $((f - 1))'s bits (every cache written)" \
        same "$T/s/frame.000$((f - 1)).exr" "$T/s/frame.000$f.exr"
    check "still demo: frame $f's hits have frame $((f - 1))'s bits" \
        same "$T/s/frame.000$((f - 1)).hits.exr" "$T/s/frame.000$f.hits.exr"
done
rb render "$T/still.yaml" --out "$T/s1" -q --set integrator.bdpt.caches=1
expect_exit 0 "the still demo renders with 1 cache"
check "one cache: frame 1 has frame 0's bits" same "$T/s1/frame.0000.exr" "$T/s1/frame.0001.exr"
rb render "$T/still.yaml" --out "$T/sf" -q --frames 4-5 --set integrator.bdpt.samples=fresh
expect_exit 0 "the still demo renders with fresh samples"
check "fresh samples: frame 5 differs from frame 4 (new points every frame)" \
    sh -c "! '$SAME' '$T/sf/frame.0004.exr' '$T/sf/frame.0005.exr' >/dev/null"

if have_scene cornell-box/CornellBox.glb; then
    box="$SCENES/cornell-box/CornellBox.glb"
    # shellcheck disable=SC2086
    rb render "$box" --integrator bdpt --size 48x48 --frames 0-4 -q --out "$T/c" \
        --set integrator.bdpt.vpl_size=64 --set integrator.bdpt.bundle_size=64
    expect_exit 0 "5 frames of the Cornell box render with bdpt"
    check "Cornell box: frame 4 has frame 3's bits" same "$T/c/frame.0003.exr" "$T/c/frame.0004.exr"
    check "Cornell box: frame 3 hits above 0.95 on average, misses at edges alone ($(json mean "$T/c/frame.0003.timing.json"))" \
        below 0.95 "$(json mean "$T/c/frame.0003.timing.json")"
else
    skip "the Cornell box's steady state" "no $SCENES/cornell-box/CornellBox.glb"
fi

# ---- the hit ratio around a moving object --------------------------------------------------

rb render "$T/moving.yaml" --out "$T/m" -q --frames 0-5
expect_exit 0 "the demo with its animation running renders"
"$BUILD/tests/tools/hitband" "$T/m/frame.0005.hits.exr" "$T/m/frame.0005.exr" 1 >"$T/band"
read -r _ band nband _ away naway <"$T/band"
echo "# hit ratio, frame 5: $band in the ring around what moves ($nband pixels), $away away ($naway)"
check "the hit ratio away from the moving objects is at least 0.99 ($away)" below 0.99 "$away"
check "the hit ratio around them is clearly lower ($band, against $away)" \
    below "$band" "$(awk -v a="$away" 'BEGIN { print a - 0.1 }')"
check "the timing sidecar summarizes the hits" \
    grep -q '"p95": ' "$T/m/frame.0005.timing.json"

# ---- caches against fresh samples: flicker, and error ---------------------------------------

rb render jobs/demo.yaml --integrator bdpt --size 64x36 --frames 3-11 -q --out "$T/f4"
expect_exit 0 "9 frames of the moving demo with 4 caches"
rb render jobs/demo.yaml --integrator bdpt --size 64x36 --frames 3-11 -q --out "$T/f1" \
    --set integrator.bdpt.caches=1 --set integrator.bdpt.samples=fresh
expect_exit 0 "the same frames with 1 cache and fresh samples every frame"
rb flicker "$T/f4" --json
cp "$T/stdout" "$T/f4.json"
rb flicker "$T/f1" --json
cp "$T/stdout" "$T/f1.json"
w4=$(sed -n 's/^    "warped_error_mean": \([^,]*\),*$/\1/p' "$T/f4.json")
w1=$(sed -n 's/^    "warped_error_mean": \([^,]*\),*$/\1/p' "$T/f1.json")
echo "# warped temporal error: 4 caches $w4, 1 cache with fresh samples $w1 (ratio $(awk -v a="$w4" -v b="$w1" 'BEGIN { printf "%.2f", a / b }'))"
check "4 caches flicker less than fresh samples every frame ($w4 < $w1)" below "$w4" "$w1"

rb reference "$T/still.yaml" --frames 3 --spp 256 --set integrator.reference.paths=bdpt \
    --out "$T/r" -q
expect_exit 0 "the still demo's reference, frame 3"
rb render "$T/still.yaml" --out "$T/one" -q --frames 0 --set integrator.bdpt.caches=1
e1=$("$RB" compare "$T/one/frame.0000.exr" "$T/r/frame.0003.exr" --json |
    sed -n 's/.*"relmse": \([0-9.e+-]*\).*/\1/p' | head -n 1)
e4=$("$RB" compare "$T/s/frame.0003.exr" "$T/r/frame.0003.exr" --json |
    sed -n 's/.*"relmse": \([0-9.e+-]*\).*/\1/p' | head -n 1)
echo "# relMSE against the reference: 1 cache after 1 frame $e1, 4 caches after 4 frames $e4"
check "4 caches after 4 frames are closer to the reference than 1 after 1 ($e4 < $e1)" \
    below "$e4" "$e1"

# ---- chunks and resume -----------------------------------------------------------------------

args="--integrator bdpt --size 48x27 -q"
# shellcheck disable=SC2086
rb render jobs/demo.yaml $args --frames 0-15 --out "$T/whole"
expect_exit 0 "frames 0-15 of the moving demo"
# shellcheck disable=SC2086
rb render jobs/demo.yaml $args --frames 10-15 --out "$T/chunk"
expect_exit 0 "frames 10-15 alone"
for f in 10 11 12 13 14 15; do
    check "frame $f of the chunk has the whole run's bits" \
        cmp -s "$T/whole/frame.00$f.exr" "$T/chunk/frame.00$f.exr"
    check "frame $f of the chunk has the whole run's hits" \
        cmp -s "$T/whole/frame.00$f.hits.exr" "$T/chunk/frame.00$f.hits.exr"
done
# shellcheck disable=SC2086
RB_TEST_ABORT_AFTER_FRAME=11 "$RB" render jobs/demo.yaml $args --frames 0-15 --out "$T/killed" \
    2>/dev/null
status=$?
check "the killed bdpt run died by SIGKILL after frame 11 (status $status)" test "$status" -eq 137
# shellcheck disable=SC2086
rb render jobs/demo.yaml $args --frames 0-15 --out "$T/killed" --resume
expect_exit 0 "--resume completes the bdpt run"
for f in 12 13 14 15; do
    check "resumed frame $f has the uninterrupted run's bits" \
        cmp -s "$T/whole/frame.00$f.exr" "$T/killed/frame.00$f.exr"
    check "resumed frame $f has the uninterrupted run's hits" \
        cmp -s "$T/whole/frame.00$f.hits.exr" "$T/killed/frame.00$f.hits.exr"
done

done_testing
