#!/bin/sh
# Farm conventions: frame lists (1-3,5,7-11:2), --chunk I/N and --chunk slurm give the same bits
# as the same frames of one whole run (a gap in a list gets its warm-up frames); chunks are even
# and contiguous; --progress=openjd prints OpenJD's progress lines; bad lists and chunks exit 2
# naming what is wrong, before anything is written.
. tests/integration/lib.sh

args="--size 160x90 -q"
rb render jobs/demo.yaml --out "$T/whole" --frames 0-11 $args
expect_exit 0 "the whole run renders frames 0-11"

# same_as_whole DIR FRAME...: DIR holds exactly these frames, each identical to the whole run's.
same_as_whole() {
    dir=$1
    shift
    want=$(for f in "$@"; do printf 'frame.%04d.exr\n' "$f"; done)
    have=$(cd "$dir" && ls 2>/dev/null | grep -E '^frame\.[0-9]+\.exr$')
    check "$dir: frames $*" test "$want" = "$have"
    for f in "$@"; do
        name=$(printf 'frame.%04d.exr' "$f")
        check "$(basename "$dir") $name is identical to the whole run's" \
            cmp -s "$T/whole/$name" "$dir/$name"
    done
}

# Four chunks of 0-11 make the whole run, bit for bit.
for i in 0 1 2 3; do
    rb render jobs/demo.yaml --out "$T/chunks" --frames 0-11 --chunk $i/4 $args
    expect_exit 0 "--chunk $i/4 renders"
    a=$((3 * i))
    check "--chunk $i/4 is frames $a-$((a + 2))" \
        grep -q "^3 frames ($a-$((a + 2)), chunk $i/4) in " "$T/stdout"
done
same_as_whole "$T/chunks" 0 1 2 3 4 5 6 7 8 9 10 11
rb render jobs/demo.yaml --out "$T/chunks" --frames 0-11 --chunk 1/4 $args --resume
check "--resume in a chunk keeps its complete frames" grep -q "0 rendered, 3 kept" "$T/stdout"

# Uneven: 12 frames in 5 chunks are 3, 3, 2, 2, 2 frames.
rb render jobs/demo.yaml --out "$T/five" --frames 0-11 --chunk 4/5 $args
expect_exit 0 "--chunk 4/5 renders"
check "--chunk 4/5 of 12 frames is the last 2" grep -q "^2 frames (10-11, chunk 4/5)" "$T/stdout"
same_as_whole "$T/five" 10 11

# A list with gaps: each frame after a gap is warmed up, so it equals the whole run's.
rb render jobs/demo.yaml --out "$T/list" --frames 9,1-3,5,7-11:2 $args
expect_exit 0 "a frame list renders"
check "the list's frames are counted once each, and listed" grep -q "^7 frames (1-3,5-11:2) in " "$T/stdout"
same_as_whole "$T/list" 1 2 3 5 7 9 11
# A chunk of a list: its 7 frames in 2 chunks are 4 and 3.
rb render jobs/demo.yaml --out "$T/listchunk" --frames 1-3,5,7-11:2 --chunk 1/2 $args
expect_exit 0 "a chunk of a list renders"
same_as_whole "$T/listchunk" 7 9 11

# A Slurm array task's chunk, with OpenJD progress: --array=1-4 makes task 3 chunk 2 of 4.
# (Exported and unset around the call: an assignment before a shell function may outlive it.)
export SLURM_ARRAY_TASK_ID=3 SLURM_ARRAY_TASK_COUNT=4 SLURM_ARRAY_TASK_MIN=1
rb render jobs/demo.yaml --out "$T/slurm" --frames 0-11 --chunk slurm --progress=openjd \
    --size 160x90
unset SLURM_ARRAY_TASK_ID SLURM_ARRAY_TASK_COUNT SLURM_ARRAY_TASK_MIN
expect_exit 0 "--chunk slurm renders"
same_as_whole "$T/slurm" 6 7 8
check "openjd: a status line when the chunk starts" \
    grep -qx "openjd_status: rendering 3 frames (6-8, chunk 2/4)" "$T/stdout"
check "openjd: a status line for each frame" \
    grep -qx "openjd_status: frame 7 rendered (2/3)" "$T/stdout"
check "openjd: progress 0, 33, 66, 100 in order" \
    test "$(sed -n 's/^openjd_progress: //p' "$T/stdout" | tr '\n' ' ')" = "0 33 66 100 "
check "openjd: no progress lines on stderr" sh -c "! grep -q 'frame 7 (2/3)' '$T/stderr'"

# Without --frames, the chunk is of the job's range (the demo's 0-47).
rb render jobs/demo.yaml --out "$T/jobrange" --size 32x18 --chunk 3/4 -q
expect_exit 0 "--chunk 3/4 of the job's range renders"
check "--chunk 3/4 of the job's 48 frames is 36-47" \
    grep -q "^12 frames (36-47, chunk 3/4) in " "$T/stdout"

# More chunks than frames: the last chunks are empty, and succeed.
rb render jobs/demo.yaml --out "$T/empty" --frames 0-1 --chunk 3/4 $args
expect_exit 0 "an empty chunk exits 0"
check "an empty chunk says so" grep -q "nothing to render" "$T/stdout"
check "an empty chunk writes nothing" test ! -e "$T/empty"

# A failure under --progress=openjd ends with openjd_fail, and keeps its exit status.
: >"$T/file"
rb render jobs/demo.yaml --out "$T/file/sub" --frames 0 --progress=openjd -q
expect_exit 2 "an unwritable output exits 2 under --progress=openjd"
check "openjd_fail names the cause" grep -q "^openjd_fail: cannot create directory" "$T/stdout"

# Bad usage under --progress=openjd ends with openjd_fail too.
rb render jobs/demo.yaml --progress=openjd --frames 1,,2
expect_exit 2 "a bad list under --progress=openjd exits 2"
check "openjd_fail names the bad list" grep -q "^openjd_fail: --frames '1,,2': an empty entry" \
    "$T/stdout"

# Bad lists and chunks: status 2, the bad entry named, nothing written.
bad_option "--frames '1-3,x,5': 'x' is not a frame" --frames 1-3,x,5
bad_option "--frames '1,9-4': '9-4': the range ends before it starts" --frames 1,9-4
bad_option "--frames '0-10:0': '0-10:0': the step must be 1 or more" --frames 0-10:0
bad_option "--frames '1,,2': an empty entry" --frames 1,,2
bad_option "--frames '4:2': '4:2': a step needs a range" --frames 4:2
bad_option "--chunk I/N: '4/4': there is no chunk 4 of 4 (chunks are numbered from 0 to 3)" --chunk 4/4
bad_option "--chunk I/N: '2' is not a chunk: expected I/N" --chunk 2
bad_option "--chunk slurm: SLURM_ARRAY_TASK_ID is not set" --chunk slurm
export SLURM_ARRAY_TASK_ID=2 SLURM_ARRAY_TASK_COUNT=two
bad_option "--chunk slurm: SLURM_ARRAY_TASK_COUNT 'two' is not a whole number" --chunk slurm
export SLURM_ARRAY_TASK_ID=4 SLURM_ARRAY_TASK_COUNT=4
bad_option "SLURM_ARRAY_TASK_ID 4 is not one of the 4 tasks from 0 by 1" --chunk slurm
unset SLURM_ARRAY_TASK_ID SLURM_ARRAY_TASK_COUNT
bad_option "--progress expects auto or openjd, got 'json'" --progress json
done_testing
