#!/bin/sh
# Resume: a render killed with SIGKILL mid-sequence and restarted with --resume completes with
# output identical to an uninterrupted run; complete frames are skipped, not re-rendered.
. tests/integration/lib.sh

args="--size 160x90 --frames 0-11 -q"
rb render jobs/demo.yaml --out "$T/whole" $args
expect_exit 0 "uninterrupted run renders frames 0-11"

"$RB" render jobs/demo.yaml --out "$T/killed" $args 2>/dev/null &
pid=$!
i=0
while [ ! -e "$T/killed/frame.0003.timing.json" ] && [ $i -lt 1200 ]; do
    sleep 0.05
    i=$((i + 1))
done
kill -KILL $pid 2>/dev/null
wait $pid 2>/dev/null
check "the killed run did not finish" test ! -e "$T/killed/frame.0011.timing.json"
before=$(ls "$T/killed"/*.exr 2>/dev/null | wc -l)
check "the killed run left some complete frames" test "$before" -ge 1

# A temporary file as a killed writer leaves it (whether or not this kill left one).
: >"$T/killed/frame.0009.exr.tmp.4242.exr"
rb render jobs/demo.yaml --out "$T/killed" $args --resume
expect_exit 0 "--resume completes the sequence"
check "--resume removes temporary files of the interrupted run" \
    sh -c "! ls '$T/killed' | grep -q '\.tmp\.'"
for f in 0000 0001 0002 0003 0004 0005 0006 0007 0008 0009 0010 0011; do
    check "frame $f identical to the uninterrupted run" cmp -s "$T/whole/frame.$f.exr" "$T/killed/frame.$f.exr"
done

# A second --resume finds everything complete and renders nothing.
touch -d '2000-01-01' "$T/killed/frame.0005.exr"
rb render jobs/demo.yaml --out "$T/killed" $args --resume
expect_exit 0 "a second --resume exits 0"
check "complete frames are not rewritten" test "$(find "$T/killed/frame.0005.exr" -newermt 2001-01-01 | wc -l)" -eq 0
done_testing
