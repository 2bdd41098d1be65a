#!/bin/sh
# SIGINT and SIGTERM finish the frame in flight and stop with status 1, leaving only complete
# files; an interrupted reference frame is not written;
# `make install` honours PREFIX and DESTDIR.
. tests/integration/lib.sh

# stop_render SIGNAL: a demo render gets SIGNAL once its second frame is written; it must
# stop early with status 1, say so, and leave only complete files.
stop_render() {
    dir="$T/$1"
    "$RB" render jobs/demo.yaml --size 160x90 --frames 0-47 --out "$dir" -q 2>"$T/stderr" &
    pid=$!
    i=0
    while [ ! -e "$dir/frame.0001.timing.json" ] && [ $i -lt 600 ]; do
        sleep 0.1
        i=$((i + 1))
    done
    kill -"$1" $pid
    wait $pid
    status=$?
    expect_exit 1 "$1 stops the render with status 1"
    stderr_has "interrupted" "$1: the interruption is reported"
    check "$1: the render stopped early" test ! -e "$dir/frame.0047.exr"
    check "$1: no temporary file is left" sh -c "! ls '$dir' | grep -q tmp"
    for exr in "$dir"/*.exr; do
        check "$1: $(basename "$exr") is complete" sh -c "oiiotool --info '$exr' >/dev/null"
    done
}
stop_render INT
stop_render TERM # a scheduler's stop is handled like ^C

# SIGINT during a reference frame: sampling stops, and the partial frame is not written under
# the frame's name, so --resume renders it again.
"$RB" reference jobs/demo.yaml --size 96x54 --frames 0 --spp 65536 --out "$T/ref" -q \
    2>"$T/stderr" &
pid=$!
sleep 2
kill -INT $pid
wait $pid
status=$?
expect_exit 1 "SIGINT stops a reference frame with status 1"
stderr_has "was not written" "the partial reference frame is reported as not written"
check "no reference frame was written" test ! -e "$T/ref/frame.0000.exr"
check "no reference timing sidecar was written" test ! -e "$T/ref/frame.0000.timing.json"

stamp() { ls -l --time-style=+%s.%N "$BUILD/raybundle" "$BUILD/libraybundle.a" "$BUILD/.flags"; }
stamp >"$T/before"
make -s install BUILD="$BUILD" PREFIX=/opt/rb DESTDIR="$T/stage" >"$T/install.log" 2>&1
check "make install succeeds" test $? -eq 0
stamp >"$T/after"
check "make install with another PREFIX rebuilds nothing" cmp -s "$T/before" "$T/after"
for f in opt/rb/bin/raybundle opt/rb/share/man/man1/raybundle.1 \
    opt/rb/share/man/man1/raybundle-report.1 \
    opt/rb/share/man/man5/raybundle-job.5 opt/rb/share/raybundle/ocio/config.ocio; do
    check "installs $f" test -f "$T/stage/$f"
done
check "the installed binary runs" sh -c "'$T/stage/opt/rb/bin/raybundle' --version >/dev/null"
# It finds its OpenColorIO config beside itself, wherever the prefix put it.
"$T/stage/opt/rb/bin/raybundle" info >"$T/info" 2>&1
check "the installed binary uses the installed OCIO config" \
    grep -qF "$T/stage/opt/rb/share/raybundle/ocio/config.ocio" "$T/info"
done_testing
