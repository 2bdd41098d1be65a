#!/bin/sh
# Hostile input: nesting deep enough to overflow a recursive parser, files that are not regular
# files (a FIFO would block the read, a device has no end, a directory is no data) and a buffer
# file longer than its declared byteLength. Each exits 2 at once with a message that names the
# file and what is wrong. Every run has a timeout, so a hang fails instead of blocking.
. tests/integration/lib.sh

rbt() {
    timeout 20 "$RB" "$@" >"$T/stdout" 2>"$T/stderr"
    status=$?
}
cp jobs/demo/room.gltf jobs/demo/room.bin "$T/"
# job NAME SCENE [MORE-YAML]: a one-frame, 16x16 job in $T rendering SCENE.
job() {
    printf 'scene: %s\noutput: out-%s/f.####.exr\nresolution: [16, 16]\nframes: {start: 0, end: 0}\n%s\n' \
        "$2" "$1" "${3:-}" >"$T/$1.yaml"
}
# nested N: the demo room with an "extras" of N nested arrays.
nested() {
    sed -n 1,2p "$T/room.gltf"
    printf '  "extras": '
    awk -v n="$1" 'BEGIN { for (i = 0; i < n; i++) printf "["; for (i = 0; i < n; i++) printf "]"; print "," }'
    sed -n '3,$p' "$T/room.gltf"
}
refused() { # refused NAME MESSAGE: after rbt, exit 2, MESSAGE on stderr, nothing written
    expect_exit 2 "$1: exits 2"
    stderr_has "$2" "$1: explained"
    check "$1: nothing written" test ! -e "$T/out-$1"
}

nested 15000 >"$T/deep.gltf"
job deep deep.gltf
rbt render "$T/deep.yaml" -q
refused deep "cannot load '$T/deep.gltf': JSON nests deeper than 512 levels at line 3, column 524"
rbt render "$T/deep.yaml" -q --lenient
expect_exit 2 "deep, --lenient: exits 2 too"

nested 500 >"$T/ok500.gltf"
job ok500 ok500.gltf
rbt render "$T/ok500.yaml" -q --integrator direct
expect_exit 0 "extras 500 deep, under the cap: renders"

mkfifo "$T/fifo.gltf"
job fifo fifo.gltf
rbt render "$T/fifo.yaml" -q
refused fifo "cannot read '$T/fifo.gltf': it is a FIFO, not a regular file"

job zero /dev/zero
rbt render "$T/zero.yaml" -q
refused zero "cannot read '/dev/zero': it is a character device, not a regular file"

job env room.gltf "environment: {map: /dev/zero}"
rbt render "$T/env.yaml" -q
refused env "environment map: cannot read '/dev/zero': it is a character device, not a regular file"

mkfifo "$T/sky.exr"
job envfifo room.gltf "environment: {map: sky.exr}"
rbt render "$T/envfifo.yaml" -q
refused envfifo "it is a FIFO, not a regular file"

mkdir "$T/bindir"
sed 's/"uri": "room.bin"/"uri": "bindir"/' "$T/room.gltf" >"$T/dirbuf.gltf"
job dirbuf dirbuf.gltf
rbt render "$T/dirbuf.yaml" -q
refused dirbuf "bindir': it is a directory, not a regular file"

# A buffer file longer than its byteLength is refused unread.
cp "$T/room.bin" "$T/big.bin"
head -c 100 /dev/zero >>"$T/big.bin"
sed 's/"uri": "room.bin"/"uri": "big.bin"/' "$T/room.gltf" >"$T/bigbuf.gltf"
job bigbuf bigbuf.gltf
rbt render "$T/bigbuf.yaml" -q
refused bigbuf "big.bin : 20400 bytes, more than the byteLength 20300 its buffer declares"

mkfifo "$T/fifo-job.yaml"
rbt render "$T/fifo-job.yaml" -q
expect_exit 2 "a FIFO as the job: exits 2"
stderr_has "cannot read '$T/fifo-job.yaml': it is a FIFO, not a regular file" "a FIFO job: explained"
rbt render "$T" -q
expect_exit 2 "a directory as the job: exits 2"
stderr_has "cannot read '$T': it is a directory, not a regular file" "a directory job: explained"

# 200,000 nested flow sequences: refused at the 65th level, where it passes the cap, without
# first scanning the rest (libyaml's cost grows with the square of the depth it has open).
{
    printf 'scene: room.gltf\nextra: '
    awk 'BEGIN { for (i = 0; i < 200000; i++) printf "["; for (i = 0; i < 200000; i++) printf "]"; print "" }'
} >"$T/deepjob.yaml"
rbt render "$T/deepjob.yaml" -q
expect_exit 2 "a job nested 200,000 deep: exits 2"
stderr_has "deepjob.yaml:2:71: nested deeper than 64 levels" "a deep job: file:line:col named"
{
    printf 'scene: room.gltf\nextra:\n'
    awk 'BEGIN { for (i = 1; i <= 70; i++) printf "%*s- k:\n", 2 * i, "" }'
} >"$T/deepblock.yaml"
rbt render "$T/deepblock.yaml" -q
expect_exit 2 "block-style nesting past the cap: exits 2"
stderr_has "deepblock.yaml:" "block-style nesting: file named"
stderr_has "nested deeper than 64 levels" "block-style nesting: explained"

done_testing
