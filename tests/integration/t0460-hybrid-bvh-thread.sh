#!/bin/sh
# The hybrid integrator's BVH on its own thread (seed 003's "async BVH construction"): built and
# baked ahead of the frames that trace it, on a fixed schedule, so the bits never depend on
# timing: chunks (one starting late in the shot, one after a gap that drops the build made
# ahead) equal the whole run, LP_NUM_THREADS 1 and 4 give the same bits, and a signal or the
# end of the run joins the thread with nothing left behind.
. tests/integration/lib.sh

SAME="$BUILD/tests/tools/samebits"
same() { "$SAME" "$1" "$2" >/dev/null; }

# The moving demo (animated: every epoch moves vertices, so every epoch builds and bakes), a BVH
# every 2 frames, short accumulators so that a chunk's warm-ups are few.
job=jobs/demo-hybrid.yaml
set -- --size 64x36 --set integrator.hybrid.bvh_interval=2 --set integrator.hybrid.history=4
rb render "$job" --frames 0-9 --out "$T/whole" -v -v "$@"
expect_exit 0 "the moving demo, frames 0-9, a BVH every 2 frames"
cp "$T/stderr" "$T/whole.log"
built=$(sed -n 's/.*hybrid: the BVH of frame \([0-9]*\): built in .* on its thread.*/\1/p' \
    "$T/whole.log" | tr '\n' ' ')
check "the BVHs of frames 0 2 4 6 8 were built on the thread, in order ($built)" \
    test "$built" = "0 2 4 6 8 "
# Once the first is built, each next one is built while the frames before it render: what is
# printed is when it was waited for, which timing decides, so only that it is said is checked.
check "the log says how long each frame waited for its BVH" \
    grep -q "ms of it waited for" "$T/whole.log"

# A chunk late in the shot: warm-ups from frame 2 build the BVH of frame 2 first.
rb render "$job" --frames 6-9 --out "$T/late" -q "$@"
expect_exit 0 "the chunk 6-9"
# After a gap: frames 0-1, then 8-9. The thread builds frame 2's BVH ahead after frame 0's; the
# warm-ups of frame 8 (frames 4-7) need frame 4's, so that build is dropped.
rb render "$job" --frames 0-1,8-9 --out "$T/gap" -v -v "$@"
expect_exit 0 "frames 0-1 and 8-9"
stderr_has "dropped the BVH built ahead for frame 2: frame 4 needs frame 4's" \
    "after the gap, the BVH built ahead is dropped and frame 4's built"
for f in 6 7 8 9; do
    check "the chunk 6-9: frame $f has the whole run's bits" \
        same "$T/whole/frame.000$f.exr" "$T/late/frame.000$f.exr"
done
for f in 0 1 8 9; do
    check "frames 0-1,8-9: frame $f has the whole run's bits" \
        same "$T/whole/frame.000$f.exr" "$T/gap/frame.000$f.exr"
done

# Thread counts: lavapipe's, which the BVH's thread shares the cores with.
for n in 1 4; do
    LP_NUM_THREADS=$n "$RB" render "$job" --frames 0-5 --out "$T/lp$n" -q "$@" \
        >/dev/null 2>"$T/stderr"
    status=$?
    expect_exit 0 "frames 0-5 with LP_NUM_THREADS=$n"
done
for f in 3 5; do
    check "LP_NUM_THREADS 1 and 4: frame $f has the same bits" \
        same "$T/lp1/frame.000$f.exr" "$T/lp4/frame.000$f.exr"
done

# SIGINT while the thread builds ahead: the render finishes the frame in flight, joins the
# thread and stops with status 1, leaving only complete files.
dir="$T/int"
"$RB" render "$job" --size 160x90 --frames 0-47 --out "$dir" -q 2>"$T/stderr" &
pid=$!
i=0
while [ ! -e "$dir/frame.0001.timing.json" ] && [ $i -lt 600 ]; do
    sleep 0.1
    i=$((i + 1))
done
kill -INT $pid
wait $pid
status=$?
expect_exit 1 "SIGINT stops the hybrid render with status 1"
stderr_has "interrupted" "the interruption is reported"
check "the render stopped early" test ! -e "$dir/frame.0047.exr"
check "no temporary file is left" sh -c "! ls '$dir' | grep -q tmp"
for exr in "$dir"/*.exr; do
    check "$(basename "$exr") is complete" sh -c "oiiotool --info '$exr' >/dev/null"
done

done_testing
