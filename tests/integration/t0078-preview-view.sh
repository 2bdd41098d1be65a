#!/bin/sh
# Previews: the bundled config's default view tone-maps (a bdpt frame's highlights are not
# clipped), --view picks another (an unknown one exits 2 with the nearest name, before any
# rendering), and --resume --preview writes a kept frame's missing preview, bit for bit the one
# a render writes.
. tests/integration/lib.sh

args="jobs/demo.yaml --size 64x36 --frames 0-1 --integrator bdpt -q"
# shellcheck disable=SC2086
rb render $args --out "$T/aces" --preview
expect_exit 0 "a bdpt render with previews"
check "ociocheck: the bundled config's default view is ACES 1.0 - SDR Video" \
    sh -c "ociocheck --iconfig share/ocio/config.ocio 2>&1 | grep -qx 'Default View: ACES 1.0 - SDR Video'"
# shellcheck disable=SC2086
rb render $args --out "$T/std" --preview --view Standard
expect_exit 0 "--view Standard renders"
check "--view Standard's previews differ from the default view's" \
    sh -c "! cmp -s '$T/aces/frame.0001.png' '$T/std/frame.0001.png'"
# shellcheck disable=SC2086
rb render $args --out "$T/set" --preview --set color.view=Standard
check "--view is color.view" cmp -s "$T/std/frame.0001.png" "$T/set/frame.0001.png"
# shellcheck disable=SC2086
rb render $args --out "$T/both" --preview --set color.view=Raw --view Standard
check "--view overrides the job's color.view" cmp -s "$T/std/frame.0001.png" "$T/both/frame.0001.png"
# Clipped pixels, per thousand: those with a channel at 255 (Standard clips about a quarter of
# this frame; the tone-mapping view only the lights themselves).
clipped() {
    oiiotool --dumpdata "$1" |
        awk '/Pixel/ {n++; if ($4 == 255 || $5 == 255 || $6 == 255) c++} END {print int(c * 1000 / n)}'
}
if command -v oiiotool >/dev/null; then
    std=$(clipped "$T/std/frame.0001.png")
    aces=$(clipped "$T/aces/frame.0001.png")
    check "Standard clips the bdpt frame (${std} per mille at 255)" test "$std" -gt 100
    check "the default view clips under 1% of it (${aces} per mille)" test "$aces" -lt 10
else
    skip "the default view does not clip" "no oiiotool"
fi

# An unknown view: the nearest name, and the config's views, before anything is written.
# shellcheck disable=SC2086
rb render $args --out "$T/never" --preview --view Standrd
expect_exit 2 "--view Standrd exits 2"
stderr_has "view 'Standrd' not found for display 'sRGB'" "the unknown view is named"
stderr_has "did you mean 'Standard'? (it has 'ACES 1.0 - SDR Video', 'Standard', 'Raw')" \
    "did you mean 'Standard', and the config's views"
check "nothing written for an unknown view" test ! -e "$T/never"
rb bench jobs/demo.yaml --out "$T/never" --view Standard
expect_exit 2 "bench --view exits 2"
stderr_has "bench does not take '--view'" "bench --view: why"

# --resume --preview over frames rendered without previews: the previews, and nothing else.
# shellcheck disable=SC2086
rb render $args --out "$T/late"
check "no preview without --preview" test ! -e "$T/late/frame.0001.png"
cp "$T/late/frame.0001.exr" "$T/exr-before"
rb render jobs/demo.yaml --size 64x36 --frames 0-1 --integrator bdpt --out "$T/late" --preview \
    --resume
expect_exit 0 "--resume --preview over complete frames"
stdout_has "0 rendered, 2 kept" "the frames are kept, not rendered again"
stderr_has "frame 1: wrote its missing preview" "the missing previews are reported"
for f in 0 1; do
    check "frame $f's missing preview is the one a render writes" \
        cmp -s "$T/aces/frame.000$f.png" "$T/late/frame.000$f.png"
done
check "the kept EXR is untouched" cmp -s "$T/exr-before" "$T/late/frame.0001.exr"

done_testing
