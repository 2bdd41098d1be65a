#!/bin/sh
# A write error is said once, and a full disk is said in words naming the file. The disk is made
# full without mounting anything: the render's temporary name for a frame
# ('<file>.tmp.<pid>[.exr]') is made a link to /dev/full beforehand, the pid known by starting
# raybundle with exec from the shell that made the link.
. tests/integration/lib.sh

args="--size 32x18 --integrator direct"
# full DIR TEMP FRAMES: renders FRAMES into DIR with DIR/TEMP (PID replaced) linked to /dev/full.
full() {
    mkdir -p "$1"
    D=$1 F=$2 sh -c 'ln -s /dev/full "$D/$(echo "$F" | sed "s/PID/$$/")"
        exec "$0" "$@"' "$RB" render jobs/demo.yaml --out "$1" --frames "$3" $args \
        >"$T/stdout" 2>"$T/stderr"
    status=$?
}
errors_once() { # errors_once DESCRIPTION: stderr holds exactly one error line
    c=$(grep -c "raybundle: error:" "$T/stderr")
    if [ "$c" -eq 1 ]; then ok "$1"; else not_ok "$1" "$c error lines" "$(cat "$T/stderr")"; fi
}

if [ ! -c /dev/full ]; then
    skip "a full disk is said in words" "no /dev/full on this system"
    done_testing
    exit 0
fi

full "$T/a" frame.0001.exr.tmp.PID.exr 0-3
expect_exit 1 "a frame that meets a full disk fails the run"
stderr_has "raybundle: error: frame 1: cannot write '$T/a/frame.0001.exr': the disk is full (no space left on the device that holds '$T/a')" \
    "the error says the disk is full and names the frame's file, not OpenEXR's temporary one"
errors_once "the writer's failure, met again when the run ends, is said once"
check "frame 1 is not there" test ! -e "$T/a/frame.0001.exr"
check "nor its temporary file" sh -c "! ls '$T/a' | grep -q tmp"
check "frame 0, written before, is" test -e "$T/a/frame.0000.exr"

full "$T/b" frame.0002.timing.json.tmp.PID 0-2
expect_exit 1 "a sidecar that meets a full disk fails the run"
stderr_has "frame 2: cannot write '$T/b/frame.0002.timing.json': the disk is full" \
    "the sidecar's error says so and names it"
errors_once "a failure of the last frame, met only when the run ends, is said once too"

# Standard output behind a full disk: the command fails instead of losing its output.
"$RB" --version >/dev/full 2>"$T/stderr"
status=$?
expect_exit 1 "--version into a full disk exits 1"
stderr_has "raybundle: error: cannot write to standard output: the disk is full" "and says so"
"$RB" render jobs/demo.yaml --out "$T/c" --frames 0 $args -q >/dev/full 2>"$T/stderr"
status=$?
expect_exit 1 "a render whose summary meets a full disk exits 1"
errors_once "it says so once"
stderr_has "cannot write to standard output" "naming standard output"

done_testing
