#!/bin/sh
# Resume: a render killed (SIGKILL, at a fixed frame through RB_TEST_ABORT_AFTER_FRAME, and at
# seeded random moments of the run, mid-frame or mid-write) and restarted with --resume completes
# with output identical to an uninterrupted run and no temporary file left; complete frames of
# the same job are kept, frames rendered by another job (settings, resolution, scene contents,
# environment map) are rendered again, and the run says so.
. tests/integration/lib.sh

args="--size 160x90 --frames 0-11 -q"
t0=$(date +%s.%N)
rb render jobs/demo.yaml --out "$T/whole" $args
t1=$(date +%s.%N)
expect_exit 0 "uninterrupted run renders frames 0-11"
loop_s=$(sed -n 's/.*, \([0-9.]*\) s$/\1/p' "$T/stdout")

RB_TEST_ABORT_AFTER_FRAME=3 "$RB" render jobs/demo.yaml --out "$T/killed" $args 2>/dev/null
status=$?
check "the killed run died by SIGKILL after frame 3 (status $status)" test "$status" -eq 137
check "the killed run wrote frames 0-3" test -e "$T/killed/frame.0003.timing.json"
check "the killed run wrote nothing after frame 3" test ! -e "$T/killed/frame.0004.exr"

# A temporary file as a killed writer leaves it.
: >"$T/killed/frame.0009.exr.tmp.4242.exr"
touch -d '2000-01-01' "$T/killed"/frame.000[0-3].*
rb render jobs/demo.yaml --out "$T/killed" $args --resume
expect_exit 0 "--resume completes the sequence"
check "--resume removes temporary files of the interrupted run" \
    sh -c "! ls '$T/killed' | grep -q '\.tmp\.'"
check "--resume kept the 4 complete frames and rendered 8" grep -q "8 rendered, 4 kept" "$T/stdout"
check "the kept frames were not rewritten" \
    test "$(find "$T/killed" -name 'frame.000[0-3].*' -newermt 2001-01-01 | wc -l)" -eq 0
for f in 0000 0001 0002 0003 0004 0005 0006 0007 0008 0009 0010 0011; do
    check "frame $f identical to the uninterrupted run" cmp -s "$T/whole/frame.$f.exr" "$T/killed/frame.$f.exr"
done

# SIGKILL at seeded random moments: the uninterrupted run's start-up, then a fraction of its
# frame loop (its last line's seconds), drawn by an LCG from RB_TEST_SEED so a failure can be
# replayed; which frame or write the kill lands in varies with the machine, which is the point.
seed=${RB_TEST_SEED:-1207}
echo "# random kills: RB_TEST_SEED=$seed"
for k in 1 2 3 4; do
    seed=$(((seed * 1103515245 + 12345) % 2147483648))
    at=$(awk -v s="$seed" -v a="$t0" -v b="$t1" -v l="${loop_s:-0}" \
        'BEGIN { printf "%.3f", b - a - l + 0.8 * s / 2147483648 * l }')
    dir="$T/random$k"
    "$RB" render jobs/demo.yaml --out "$dir" $args >/dev/null 2>&1 &
    pid=$!
    sleep "$at"
    kill -KILL $pid 2>/dev/null
    wait $pid
    status=$?
    exrs=$(ls "$dir" 2>/dev/null | grep -c '^frame\.[0-9]*\.exr$')
    temps=$(ls -a "$dir" 2>/dev/null | grep -c '\.tmp\.')
    echo "# kill $k after $at s: status $status, $exrs frame(s) and $temps temporary file(s) left"
    rb render jobs/demo.yaml --out "$dir" $args --resume
    expect_exit 0 "kill $k (after $at s): --resume completes the sequence"
    check "kill $k: no temporary file remains" sh -c "! ls -a '$dir' | grep -q '\.tmp\.'"
    same=0
    for f in 0000 0001 0002 0003 0004 0005 0006 0007 0008 0009 0010 0011; do
        cmp -s "$T/whole/frame.$f.exr" "$dir/frame.$f.exr" && same=$((same + 1))
    done
    check "kill $k: all 12 frames identical to the uninterrupted run ($same)" test "$same" -eq 12
done

# A second --resume finds everything complete and renders nothing.
touch -d '2000-01-01' "$T/killed"/frame.*
rb render jobs/demo.yaml --out "$T/killed" $args --resume
expect_exit 0 "a second --resume exits 0"
check "a second --resume renders nothing" grep -q "0 rendered, 12 kept" "$T/stdout"
check "complete frames are not rewritten" \
    test "$(find "$T/killed" -name 'frame.*' -newermt 2001-01-01 | wc -l)" -eq 0

# Another setting: every frame is rendered again, and the run says so.
rb render jobs/demo.yaml --out "$T/killed" $args --resume --set integrator.direct.shadow_bias=0.004
expect_exit 0 "--resume with another shadow bias exits 0"
check "another setting: all 12 frames rendered again" grep -q "12 rendered, 0 kept, 12 rendered again" "$T/stdout"
check "frame 5 now differs from the first job's" \
    sh -c "! cmp -s '$T/whole/frame.0005.exr' '$T/killed/frame.0005.exr'"
rb render jobs/demo.yaml --out "$T/killed" --size 160x90 --frames 0-11 --resume \
    --set integrator.direct.shadow_bias=0.004
expect_exit 0 "--resume without -q"
stderr_has "frame 0 (1/12) already complete, skipped" "the progress says which frames are kept"
rb render jobs/demo.yaml --out "$T/killed" --size 160x90 --frames 0-11 --resume
stderr_has "frame 0 was rendered by another job or setting: rendering it again" \
    "the progress says which frames are rendered again"

# Another resolution of the same job: rendered again.
rb render jobs/demo.yaml --out "$T/killed" --size 128x72 --frames 0-1 -q --resume
check "another resolution: rendered again" grep -q "2 rendered, 0 kept, 2 rendered again" "$T/stdout"

# The scene's contents, not its path: a copy of the demo whose buffer changes under the same name.
mkdir -p "$T/scene"
cp jobs/demo/room.gltf jobs/demo/room.bin "$T/scene/"
sed "s#^scene: .*#scene: $T/scene/room.gltf#" jobs/demo.yaml >"$T/scene/job.yaml"
rb render "$T/scene/job.yaml" --out "$T/sc" --size 64x36 --frames 0-1 -q
expect_exit 0 "the copied scene renders"
rb render "$T/scene/job.yaml" --out "$T/sc" --size 64x36 --frames 0-1 -q --resume
check "the unchanged scene: frames kept" grep -q "0 rendered, 2 kept" "$T/stdout"
# The lowest byte of the first vertex position (the buffer starts with positions): a change far
# below what shows in a pixel, still a different scene.
printf '\177' | dd of="$T/scene/room.bin" bs=1 seek=0 conv=notrunc 2>/dev/null
rb render "$T/scene/job.yaml" --out "$T/sc" --size 64x36 --frames 0-1 -q --resume
expect_exit 0 "the changed scene renders"
check "a changed scene buffer: frames rendered again" grep -q "2 rendered, 0 kept, 2 rendered again" "$T/stdout"

# The environment map's pixels, not its path.
oiiotool --pattern constant:color=0.2,0.3,0.4 16x8 3 -d float -o "$T/scene/sky.exr"
printf 'environment: {map: sky.exr}\n' >>"$T/scene/job.yaml"
rb render "$T/scene/job.yaml" --out "$T/env" --size 64x36 --frames 0 -q
expect_exit 0 "the job with an environment map renders"
oiiotool --pattern constant:color=0.4,0.3,0.2 16x8 3 -d float -o "$T/scene/sky.exr"
rb render "$T/scene/job.yaml" --out "$T/env" --size 64x36 --frames 0 -q --resume
check "a changed environment map: the frame is rendered again" \
    grep -q "1 rendered, 0 kept, 1 rendered again" "$T/stdout"
# A frame's files are all of one render. A direct render over bdpt frames with previews removes
# their hit ratios and previews, which it does not write.
rb render jobs/demo.yaml --out "$T/sides" --size 64x36 --frames 1-2 -q --integrator bdpt --preview
expect_exit 0 "bdpt frames with previews render"
check "bdpt wrote hit ratios and previews" \
    test -f "$T/sides/frame.0002.hits.exr" -a -f "$T/sides/frame.0002.png"
rb render jobs/demo.yaml --out "$T/sides" --size 64x36 --frames 1-2 -q --integrator direct
expect_exit 0 "direct renders over them"
check "the old hit ratios are gone" sh -c "! ls '$T/sides'/*.hits.exr 2>/dev/null"
check "the old previews are gone" sh -c "! ls '$T/sides'/*.png 2>/dev/null"
check "the new frames and sidecars are there" \
    test -f "$T/sides/frame.0001.exr" -a -f "$T/sides/frame.0002.timing.json"
# A sidecar that does not parse does not mark its frame done: --resume renders it again.
echo garbage >"$T/sides/frame.0002.timing.json"
rb render jobs/demo.yaml --out "$T/sides" --size 64x36 --frames 1-2 -q --integrator direct --resume
expect_exit 0 "--resume over a garbage sidecar succeeds"
check "the frame with the garbage sidecar is rendered, the other kept" \
    grep -q "1 rendered, 1 kept" "$T/stdout"
check "its sidecar parses again" grep -q '"frame": 2' "$T/sides/frame.0002.timing.json"
done_testing
