#!/bin/sh
# One writer per frame of an output: a second render of frames another raybundle is rendering
# into the same folder exits 2 at once naming its pid, while renders of other frames (a farm's
# chunks) share the folder; an output folder removed during a run stops it with exit 1 instead
# of being created again. The first render is held with SIGSTOP once it has written a frame, so
# nothing depends on timing; every wait has a bound.
. tests/integration/lib.sh

args="--size 32x18 --integrator direct -q"
# start DIR FRAMES: a render in the background, stopped once its first frame is written.
start() {
    "$RB" render jobs/demo.yaml --out "$1" --frames "$2" $args >"$T/bg.out" 2>"$T/bg.err" &
    bg=$!
    i=0
    while [ ! -e "$1/frame.$3.timing.json" ] && [ $i -lt 600 ] && kill -0 $bg 2>/dev/null; do
        sleep 0.1
        i=$((i + 1))
    done
    kill -STOP $bg
}
finish() { # resumes the background render and waits for it; its status in bg_status
    kill -CONT $bg
    wait $bg
    bg_status=$?
}

start "$T/a" 0-23 0000
timeout 20 "$RB" render jobs/demo.yaml --out "$T/a" --frames 20-30 $args >"$T/stdout" 2>"$T/stderr"
status=$?
expect_exit 2 "a second render of overlapping frames exits 2"
stderr_has "frame 20 of '$T/a/frame.####.exr' is being rendered by another raybundle (pid $bg)" \
    "it names the frame and the other render's pid"
timeout 20 "$RB" render jobs/demo.yaml --out "$T/a" --frames 24-25 $args >"$T/stdout" 2>"$T/stderr"
status=$?
expect_exit 0 "a render of other frames into the same folder (a chunk) runs beside it"
finish
check "the first render completes (status $bg_status)" test "$bg_status" -eq 0
check "its frames are all there" test -e "$T/a/frame.0023.exr"
timeout 60 "$RB" render jobs/demo.yaml --out "$T/a" --frames 0-25 $args --resume >"$T/stdout" 2>"$T/stderr"
status=$?
expect_exit 0 "once it is done, the lock left behind does not stop a --resume"
check "--resume kept all 26 frames" grep -q "0 rendered, 26 kept" "$T/stdout"

start "$T/b" 0-23 0000
rm -rf "$T/b"
finish
check "a run whose output folder was removed exits 1 (status $bg_status)" test "$bg_status" -eq 1
check "it says the folder was removed" \
    grep -qF "raybundle: error: output directory '$T/b' was removed during the run" "$T/bg.err"
check "the run does not claim the frames were rendered" sh -c "! grep -q rendered '$T/bg.out'"

done_testing
