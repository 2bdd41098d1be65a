#!/bin/sh
# Analytic light: a Lambertian floor under a point light renders I cos(theta)/r^2 albedo/pi
# within 1%; the occluder's shadow and a spot light's cone edges land where geometry says.
. tests/integration/lib.sh

"$BUILD/tests/tools/analytic" scene "$T" || fail_all "cannot write the analytic scene"
cat >"$T/point.yaml" <<YAML
scene: plane.gltf
output: point/frame.####.exr
resolution: [320, 200]
frames: {start: 0, end: 0}
camera:
  fov_y_deg: 60
  keys: [{t: 0, position: [0, 6, 4], look_at: [0, 0, 0]}]
lights:
  - {type: point, position: [0, 2, 0], color: [1, 1, 1], intensity: 10}
YAML
cat >"$T/spot.yaml" <<YAML
scene: plane.gltf
output: spot/frame.####.exr
resolution: [320, 200]
frames: {start: 0, end: 0}
camera:
  fov_y_deg: 60
  keys: [{t: 0, position: [0, 6, 4], look_at: [0, 0, 0]}]
lights:
  - {type: spot, position: [-2, 2, 0], direction: [0, -1, 0], intensity: 20,
     inner_cone_deg: 20, outer_cone_deg: 30}
YAML

rb render "$T/point.yaml" -q
expect_exit 0 "point-light job renders"
tap_run "$BUILD/tests/tools/analytic" point "$T/point/frame.0000.exr"

rb render "$T/spot.yaml" -q
expect_exit 0 "spot-light job renders"
tap_run "$BUILD/tests/tools/analytic" spot "$T/spot/frame.0000.exr"

# The same light over glossy floors: the glTF BRDF (GGX, Smith, Schlick) within 1%.
for m in glossy metal; do
    sed -e "s/plane.gltf/$m.gltf/" -e "s/output: point/output: $m/" "$T/point.yaml" >"$T/$m.yaml"
    rb render "$T/$m.yaml" -q
    expect_exit 0 "$m floor renders"
    tap_run "$BUILD/tests/tools/analytic" $m "$T/$m/frame.0000.exr"
done

done_testing
