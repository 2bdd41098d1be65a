#!/bin/sh
# Frames whose readback is larger than one storage-buffer binding may be (maxStorageBufferRange,
# 128 MiB on lavapipe; a 1920x1080 readback is 166 MB) render validation-clean and complete: the
# output pass writes the readback one band of rows at a time. Each large frame, downscaled,
# matches a 480x270 render of the same frame, and its middle column is opaque and lit in every
# row down to the floor's edge (a band left unwritten would read as zeros there). A frame too
# large for the device fails before anything is allocated, naming the limit.
. tests/integration/lib.sh

# render WxH DIR: frame 0 of the demo, with small shadow maps to keep it quick.
render() {
    rb render jobs/demo.yaml --integrator direct --frames 0 --size "$1" \
        --set integrator.direct.shadow_size=256 \
        --out "$T/$2" --validate -q
}

render 480x270 small
expect_exit 0 "the 480x270 reference frame renders"

for size in 1920x1080 3840x2160; do
    w=${size%x*}
    h=${size#*x}
    render "$size" "f$w"
    expect_exit 0 "$size renders with --validate"
    check "$size: no validation message" sh -c "! grep -qi validation '$T/stderr'"
    # One read of the large file: the minimum R, G, B, A of the middle column over the rows
    # the room covers (the floor ends 8 rows of 270 above the bottom), then the whole frame
    # downscaled to 480x270.
    rows=$((h * 26 / 27))
    oiiotool "$T/f$w/frame.0000.exr" --ch R,G,B,A --dup --cut "1x$rows+$((w / 2))+0" \
        --printstats --pop --resize 480x270 -o "$T/f$w.small.exr" >"$T/stats" 2>&1
    min=$(sed -n 's/^ *Stats Min: //p' "$T/stats")
    if echo "$min" | awk '{ exit !($1 > 0 && $4 == 1) }'; then
        ok "$size: the middle column is opaque and lit in rows 0 to $((rows - 1))"
    else
        not_ok "$size: the middle column is opaque and lit in rows 0 to $((rows - 1))" \
            "minimum R G B A: ${min:-none (oiiotool failed)}"
    fi
    rb compare "$T/f$w.small.exr" "$T/small/frame.0000.exr" --max-relmse 0.015
    expect_exit 0 "$size downscaled matches the 480x270 frame (relMSE <= 0.015)"
done

# The bound sees a missing band: 16 black rows of 270 (128 rows at 3840x2160) exceed it.
oiiotool "$T/f3840.small.exr" --fill:color=0,0,0,0 480x16+0+200 -o "$T/holed.exr" >/dev/null 2>&1
rb compare "$T/holed.exr" "$T/small/frame.0000.exr" --max-relmse 0.015
expect_exit 1 "a frame with 16 black rows exceeds the bound"

# The largest size a job allows needs a 21 GB readback: no device here can hold that in one
# buffer, and the check says so before allocating (or rendering) anything.
rb render jobs/demo.yaml --frames 0 --size 16384x16384 --out "$T/huge" -q
expect_exit 1 "16384x16384 is refused (the device cannot)"
stderr_has "resolution 16384x16384: pass 'output': buffer 'readback' needs $((16384 * 16384 * 80)) bytes, more than the device's max" \
    "the refusal names the frame, the pass, the buffer, its size and the limit"
check "no frame is written" test ! -e "$T/huge/frame.0000.exr"
done_testing
