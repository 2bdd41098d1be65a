#!/bin/sh
# raybundle info FILE...: a frame's size, layers and channels, and its header's metadata (the
# integrator, the job hash, the frame; the device from its sidecar), checked against what
# oiiotool and the timing sidecar say; the reference's frames say they are the CPU reference; a missing file and a file
# that is not an image fail naming it, with exit status 2.
. tests/integration/lib.sh

# attr FILE NAME: the value of the header attribute NAME as oiiotool prints it, quotes removed.
attr() {
    oiiotool --info -v "$1" 2>/dev/null | sed -n "s/^ *$2: \"\{0,1\}\([^\"]*\)\"\{0,1\}\$/\1/p"
}
# sidecar FILE KEY: a string field of a timing sidecar.
sidecar() {
    sed -n "s/^  \"$2\": \"\(.*\)\",\{0,1\}\$/\1/p" "$1"
}

rb info --help
expect_exit 0 "info --help exits 0"
check "info --help names FILE..." grep -q '^usage: raybundle info \[FILE\.\.\.\]$' "$T/stdout"
check "raybundle(1) gives info's FILE" grep -q '^\.RI \[ FILE \\ \.\.\.\]$' man/raybundle.1
rb info
expect_exit 0 "info without files exits 0"
check "info without files still lists the devices" grep -q '^devices: [1-9]' "$T/stdout"

rb render jobs/demo.yaml --frames 1 --size 64x36 --integrator bdpt --out "$T/a" -q
expect_exit 0 "a small bdpt frame of the demo renders"
f="$T/a/frame.0001.exr"
rb info "$f"
expect_exit 0 "info FILE exits 0"
cp "$T/stdout" "$T/info"
check "info names the file" grep -qxF "path: $f" "$T/info"
check "info gives the size" grep -qx 'size: 64x36' "$T/info"
check "info lists every layer with its channels, in raybundle's order" grep -qxF \
    'layers: beauty (R, G, B, A), direct (R, G, B), indirect (R, G, B), albedo (R, G, B), normal (X, Y, Z), depth (Z), motion (X, Y)' \
    "$T/info"
# The layers line holds exactly the file's channels, as oiiotool lists them.
sed -n 's/^layers: //p' "$T/info" | tr -d ' ' | sed 's/),/)\n/g' |
    sed 's/^\([^(]*\)(\(.*\))$/\1 \2/' | while read -r layer channels; do
    for c in $(echo "$channels" | tr ',' ' '); do
        if [ "$layer" = beauty ]; then echo "$c"; else echo "$layer.$c"; fi
    done
done | sort >"$T/info-channels"
oiiotool --info -v "$f" | sed -n 's/^ *channel list: //p' | tr -d ' ' | tr ',' '\n' |
    sort >"$T/oiio-channels"
check "the layers hold the channels oiiotool finds (19)" \
    sh -c "cmp -s '$T/info-channels' '$T/oiio-channels' && test \$(wc -l <'$T/oiio-channels') -eq 19"
check "info gives the integrator" grep -qx 'raybundle:integrator: bdpt' "$T/info"
hash=$(attr "$f" 'raybundle:jobHash')
check "the frame has a 16-digit job hash" sh -c "echo '$hash' | grep -qx '[0-9a-f]\{16\}'"
check "info gives the job hash the header holds" grep -qxF "raybundle:jobHash: $hash" "$T/info"
check "... which is the sidecar's job_hash" \
    test "$hash" = "$(sidecar "$T/a/frame.0001.timing.json" job_hash)"
check "info gives the frame number" grep -qx 'raybundle:frame: 1' "$T/info"
device=$(sidecar "$T/a/frame.0001.timing.json" device)
driver=$(sidecar "$T/a/frame.0001.timing.json" driver)
check "the sidecar names the device and the driver" test -n "$device" -a -n "$driver"
check "info gives the device that rendered the frame (the sidecar's)" \
    grep -qxF "device: $device" "$T/info"
check "and its driver" grep -qxF "driver: $driver" "$T/info"
check "the header does not name the device (other drivers, the same bytes)" \
    sh -c "! oiiotool --info -v '$f' | grep -qi 'raybundle:device'"
check "info gives the camera matrix" grep -q '^worldToCamera: [-0-9.e]*, ' "$T/info"
check "raybundle's metadata comes before OpenEXR's" \
    sh -c "grep -n '' '$T/info' | grep -A1 '^[0-9]*:raybundle:version' | tail -n 1 | grep -q ':chromaticities: '"

# The hit ratios beside a bdpt frame are an image with one channel.
rb info "$T/a/frame.0001.hits.exr"
expect_exit 0 "info on the hit ratios exits 0"
check "the hit ratios have one channel, Y" grep -qx 'layers: beauty (Y)' "$T/stdout"

rb reference jobs/demo.yaml --frames 1 --size 32x18 --spp 2 --out "$T/ref" -q
expect_exit 0 "a tiny reference frame renders"
rb info "$T/ref/frame.0001.exr" "$f"
expect_exit 0 "info on two files exits 0"
check "info names both files" test "$(grep -c '^path: ' "$T/stdout")" -eq 2
check "a blank line separates them" test "$(grep -c '^$' "$T/stdout")" -eq 1
check "the reference frame says it is the CPU reference" grep -qx \
    "driver: raybundle reference [0-9.]* (Embree 3)" "$T/stdout"
check "the reference frame's integrator is the reference" \
    grep -qx 'raybundle:integrator: reference' "$T/stdout"
check "the reference frame gives its samples per pixel" grep -qx 'raybundle:spp: 2' "$T/stdout"
check "the reference frame is 32x18" grep -qx 'size: 32x18' "$T/stdout"

# Files that are not there or are not images.
rb info "$T/nope.exr"
expect_exit 2 "a missing file exits 2"
stderr_has "cannot open '$T/nope.exr': No such file or directory" "the missing file is named"
check "nothing went to stdout for the missing file" test ! -s "$T/stdout"
printf 'notes, not an image\n' >"$T/notes.txt"
rb info "$T/notes.txt"
expect_exit 2 "a file that is not an image exits 2"
stderr_has "cannot read '$T/notes.txt'" "the file that is not an image is named"
printf 'v/1 not really an EXR\n' >"$T/fake.exr"
rb info "$T/fake.exr"
expect_exit 2 "a text file named .exr exits 2"
stderr_has "cannot read '$T/fake.exr'" "the false EXR is named"
rb info "$f" "$T/nope.exr" "$T/ref/frame.0001.exr"
expect_exit 2 "a missing file among good ones exits 2"
stderr_has "cannot open '$T/nope.exr'" "the missing one is named"
check "the good files are still printed" test "$(grep -c '^path: ' "$T/stdout")" -eq 2

done_testing
