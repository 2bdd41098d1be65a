#!/bin/sh
# Determinism: the same job gives the same bits run after run, whatever LP_NUM_THREADS, and a
# chunk of frames rendered alone equals the same frames of a whole run.
. tests/integration/lib.sh

args="--size 160x90 -q"
rb render jobs/demo.yaml --frames 0-7 --out "$T/a" $args
expect_exit 0 "demo frames 0-7 render"
rb render jobs/demo.yaml --frames 0-7 --out "$T/b" $args
expect_exit 0 "demo frames 0-7 render again"
LP_NUM_THREADS=1 "$RB" render jobs/demo.yaml --frames 0-3 --out "$T/t1" $args
check "renders with LP_NUM_THREADS=1" test $? -eq 0
LP_NUM_THREADS=2 "$RB" render jobs/demo.yaml --frames 0-3 --out "$T/t2" $args
check "renders with LP_NUM_THREADS=2" test $? -eq 0
rb render jobs/demo.yaml --frames 4-7 --out "$T/chunk" $args
expect_exit 0 "demo frames 4-7 render as a chunk"

for f in 0000 0001 0002 0003 0004 0005 0006 0007; do
    check "frame $f: identical bits on a second run" cmp -s "$T/a/frame.$f.exr" "$T/b/frame.$f.exr"
done
for f in 0000 0001 0002 0003; do
    check "frame $f: 1 thread gives the default thread count's bits" \
        cmp -s "$T/t1/frame.$f.exr" "$T/a/frame.$f.exr"
    check "frame $f: 2 threads give the default thread count's bits" \
        cmp -s "$T/t2/frame.$f.exr" "$T/a/frame.$f.exr"
done
for f in 0004 0005 0006 0007; do
    check "frame $f: chunk 4-7 equals the whole run" cmp -s "$T/chunk/frame.$f.exr" "$T/a/frame.$f.exr"
done
# Frames differ from each other: the scene is animated and the test is not vacuous.
check "frames 0 and 4 differ" sh -c "! cmp -s '$T/a/frame.0000.exr' '$T/a/frame.0004.exr'"
done_testing
