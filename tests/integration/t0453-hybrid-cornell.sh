#!/bin/sh
# The hybrid integrator on the area-lit Cornell box (issue 24's measure): a still camera, the
# default settings, against the reference with its default path space. Next-event estimation
# at the camera vertex makes the direct layer converge like the reference's.
. tests/integration/lib.sh

scene=cornell-box/CornellBox.glb
if ! have_scene "$scene"; then
    skip "the hybrid integrator on the Cornell box" "no $scene under $SCENES"
    done_testing
fi
below() { awk -v a="$1" -v b="$2" 'BEGIN { exit !(a + 0 <= b + 0) }'; }
relmse() { # relmse A B LAYER
    "$RB" compare "$1" "$2" --layer "$3" --json | sed -n 's/.*"relmse": \([0-9.e+-]*\).*/\1/p' |
        head -n 1
}
cat >"$T/box.yaml" <<EOT
scene: $(cd "$SCENES/cornell-box" && pwd)/CornellBox.glb
output: frame.####.exr
resolution: [160, 90]
frames: {start: 0, end: 127, rate: 24}
camera: {fov_y_deg: 39.3, keys: [{t: 0, position: [-278, 273, 800], look_at: [-278, 273, 0]}]}
default_light: off
layers: [direct, indirect]
integrator: {name: hybrid}
EOT

# The reference, converged enough to judge by (at 1024 samples its own relMSE, from 256 against
# 1024, is about 4e-5 direct, 6e-4 beauty).
rb reference "$T/box.yaml" --frames 0 --spp 1024 --out "$T/r" -q
expect_exit 0 "the Cornell box's reference, 1024 spp, default path space"
ref="$T/r/frame.0000.exr"

rb render "$T/box.yaml" --frames 0-31 --out "$T/h" -q
expect_exit 0 "32 frames of the still Cornell box with the hybrid integrator's defaults"
check "its sidecar names the light_rays pass" \
    grep -q '"name": "light_rays"' "$T/h/frame.0031.timing.json"
d0=$(relmse "$T/h/frame.0000.exr" "$ref" direct)
d31=$(relmse "$T/h/frame.0031.exr" "$ref" direct)
echo "# direct relMSE: frame 0 $d0, frame 31 $d31"
check "next-event estimation: the direct layer at frame 31 is within relMSE 0.003 ($d31)" \
    below "$d31" 0.003

done_testing
