#!/bin/sh
# Analytic light: a Lambertian floor under a point light renders I cos(theta)/r^2 albedo/pi
# within 1%; the occluder's shadow and a spot light's cone edges land where geometry says.
. tests/integration/lib.sh

"$BUILD/tests/tools/analytic" scene "$T" || fail_all "cannot write the analytic scene"
# The tool writes the scenes and the jobs (point, spot, sun, glossy, metal) from the same
# camera and light constants its checks use.
rb render "$T/point.yaml" -q
expect_exit 0 "point-light job renders"
tap_run "$BUILD/tests/tools/analytic" point "$T/point/frame.0000.exr"

rb render "$T/spot.yaml" -q
expect_exit 0 "spot-light job renders"
tap_run "$BUILD/tests/tools/analytic" spot "$T/spot/frame.0000.exr"

# A directional light straight down: E albedo/pi, and a shadow right under the occluder.
rb render "$T/sun.yaml" -q
expect_exit 0 "directional-light job renders"
tap_run "$BUILD/tests/tools/analytic" sun "$T/sun/frame.0000.exr"

# An environment map seen as the background: looking up at a constant sky.
oiiotool --pattern constant:color=0.2,0.4,0.8 64x32 3 -d float -o "$T/sky.exr"
cat >"$T/sky.yaml" <<YAML
scene: plane.gltf
output: sky/frame.####.exr
resolution: [64, 48]
frames: {start: 0, end: 0}
camera:
  fov_y_deg: 60
  keys: [{t: 0, position: [0, 1, 0], look_at: [0.3, 5, 0.2]}]
environment: {map: sky.exr, intensity: 2, rotation_deg: 30}
YAML
rb render "$T/sky.yaml" -q
expect_exit 0 "environment-map job renders"
tap_run "$BUILD/tests/tools/analytic" sky "$T/sky/frame.0000.exr"

# The same light over glossy floors: the glTF BRDF (GGX, Smith, Schlick) within 1%.
for m in glossy metal; do
    rb render "$T/$m.yaml" -q
    expect_exit 0 "$m floor renders"
    tap_run "$BUILD/tests/tools/analytic" $m "$T/$m/frame.0000.exr"
done

done_testing
