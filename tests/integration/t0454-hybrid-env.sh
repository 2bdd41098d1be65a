#!/bin/sh
# The hybrid integrator's light samples of the environment: the demo room with its emissive
# panel off and no punctual light, lit through its open side by a rotated equirectangular sky
# (as t0405 lights it for bdpt). Each traced ray takes a light sample of the sky by the
# importance of its texels (the reference's table) with a shadow ray through the BVH, weighed
# against the rays that miss; the direct layer converges to the reference's, its mean is right,
# and a second run has the same bits.
. tests/integration/lib.sh

below() { awk -v a="$1" -v b="$2" 'BEGIN { exit !(a + 0 <= b + 0) }'; }
mean() { # mean EXR CHANNEL
    oiiotool "$1" --ch "$2" --printstats 2>/dev/null | sed -n 's/^ *Stats Avg: \(.*\) (float)$/\1/p'
}
mkdir "$T/s"
sed 's/"emissiveFactor": \[1, 1, 1\]/"emissiveFactor": [0, 0, 0]/' jobs/demo/room.gltf \
    >"$T/s/room.gltf"
cp jobs/demo/room.bin "$T/s/"
sky=topleft=1.2,1.1,0.9:topright=0.5,0.7,1.2:bottomleft=0.2,0.15,0.1:bottomright=0.1,0.1,0.15
oiiotool --pattern "fill:$sky" 64x32 3 -d float -o "$T/s/sky.exr"
cat >"$T/s/sky.yaml" <<YAML
scene: room.gltf
output: frame.####.exr
resolution: [96, 54]
frames: {start: 0, end: 31, rate: 24}
camera:
  fov_y_deg: 40
  keys:
    - {t: 0, position: [0, 1.0, 3.6], look_at: [0, 0.9, 0]}
animation: {speed: 0}
scene_lights: false
environment: {map: sky.exr, intensity: 1, rotation_deg: 30}
layers: [direct, indirect]
integrator: {name: hybrid}
YAML

rb reference "$T/s/sky.yaml" --frames 0 --spp 512 --out "$T/r" -q
expect_exit 0 "the sky-lit room's reference, 512 spp"
rb render "$T/s/sky.yaml" --out "$T/h" -q
expect_exit 0 "32 frames of the sky-lit room with the hybrid integrator"
rb render "$T/s/sky.yaml" --frames 31 --out "$T/again" -q
check "frame 31 alone (its warm-up) has the whole run's bits" \
    cmp -s "$T/h/frame.0031.exr" "$T/again/frame.0031.exr"
light=$(sed -n 's/.*"name": "light_rays", "gpu_ms": \([0-9.eE+-]*\).*/\1/p' "$T/h/frame.0031.timing.json")
check "the light_rays pass runs for the sky alone (${light:-none} ms)" \
    awk -v a="${light:-0}" 'BEGIN { exit !(a + 0 > 0.05) }'
d=$(relmse "$T/h/frame.0031.exr" "$T/r/frame.0000.exr" direct)
echo "# direct relMSE at frame 31: $d"
check "the sky's direct light at frame 31 is within relMSE 0.005 of the reference ($d)" \
    below "$d" 0.005
mh=$(mean "$T/h/frame.0031.exr" direct.G)
mr=$(mean "$T/r/frame.0000.exr" direct.G)
echo "# direct.G mean: hybrid $mh, reference $mr"
check "the direct light's mean is within 1% of the reference's ($mh, $mr)" \
    awk -v a="$mh" -v b="$mr" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(b > 0 && d <= 0.01 * b) }'

done_testing
