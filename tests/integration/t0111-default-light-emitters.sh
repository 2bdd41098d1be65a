#!/bin/sh
# default_light: auto judges emissive surfaces by how much they light, not by whether they emit:
# an emitter too weak to light the view (a dim emissive texture) gets the default light, with a
# warning that says why; a bright one does not; default_light: off still leaves the weak scene
# dark. The WaterBottle's quick look (an emissive texture that is nearly black) is lit.
. tests/integration/lib.sh

# A floor (Lambertian, white) and a 0.5 m panel 1 m above it, emissive factor 1 times a texture
# (its one colour 1/255 in sRGB, 0.0003 linear: the weak panel; or 255, the bright one).
oiiotool --create 4x4 3 --fill:color=0.004,0.004,0.004 4x4 -d uint8 -o "$T/dim.png"
oiiotool --create 4x4 3 --fill:color=1,1,1 4x4 -d uint8 -o "$T/bright.png"
floor_panel_gltf "$T/weak.gltf" "[0, 1]" dim.png
floor_panel_gltf "$T/strong.gltf" "[0, 1]" bright.png
default_light_of() { # default_light_of EXR: the raybundle:defaultLight attribute
    oiiotool --info -v "$1" | sed -n 's/^ *raybundle:defaultLight: "\(.*\)"$/\1/p'
}
mean_of() { # mean_of EXR: the mean of R over the frame
    "$BUILD/tests/tools/exrstat" "$1" R -1 | sed -n 's/.*mean of R is \([^,]*\),.*/\1/p'
}
above() { awk -v v="$1" -v m="$2" 'BEGIN { exit !(v > m) }'; }
below() { awk -v v="$1" -v m="$2" 'BEGIN { exit !(v < m) }'; }

# The weak panel: a quick look adds the default light, warns once at the default log level
# saying why, and the frame is lit (the panel alone leaves a mean around 1e-5).
rb render "$T/weak.gltf" --frames 0 --size 64x48 --out "$T/weak"
expect_exit 0 "weak emitter: the quick look renders"
stderr_has "too weak to light the view" "weak emitter: the log says why a default light is added"
check "weak emitter: the note is one line" test "$(grep -c 'default light' "$T/stderr")" -eq 1
note=$(default_light_of "$T/weak/frame.0000.exr")
check "weak emitter: the metadata records the default light ($note)" \
    sh -c "echo '$note' | grep -q '^point light at'"
m=$(mean_of "$T/weak/frame.0000.exr")
check "weak emitter: the quick look is lit (mean R $m > 0.01)" above "$m" 0.01
rb render "$T/weak.gltf" --frames 0 --size 64x48 --out "$T/weak-v" -v
stderr_has "emissive surfaces give an irradiance of about" \
    "weak emitter: -v logs the emitters' irradiance"
rb render "$T/weak.gltf" --frames 0 --size 64x48 --out "$T/weak-off" -q --set default_light=off
expect_exit 0 "weak emitter, default_light off: renders"
check "weak emitter, default_light off: no default light" \
    test "$(default_light_of "$T/weak-off/frame.0000.exr")" = none
m=$(mean_of "$T/weak-off/frame.0000.exr")
check "weak emitter, default_light off: the frame stays dark (mean R $m < 0.001)" below "$m" 0.001

# The bright panel lights the floor itself: no default light, no warning.
rb render "$T/strong.gltf" --frames 0 --size 64x48 --out "$T/strong"
expect_exit 0 "bright emitter: the quick look renders"
check "bright emitter: no default light" \
    test "$(default_light_of "$T/strong/frame.0000.exr")" = none
check "bright emitter: nothing about a default light in the log" \
    test "$(grep -c 'default light' "$T/stderr")" -eq 0
rb render "$T/strong.gltf" --frames 0 --size 64x48 --out "$T/strong-v" -v
stderr_has "emissive surfaces give an irradiance of about" \
    "bright emitter: -v logs the irradiance that made a default light unneeded"

# The WaterBottle: its emissive texture is nearly black (a mean of 3e-7 without a light).
scene=WaterBottle/WaterBottle.gltf
if have_scene "$scene"; then
    rb render "$SCENES/$scene" --frames 0 --size 96x72 --out "$T/bottle" -q
    expect_exit 0 "$scene: a quick look renders"
    m=$(mean_of "$T/bottle/frame.0000.exr")
    check "$scene: the quick look is lit (mean R $m > 0.001)" above "$m" 0.001
else
    skip "$scene: a quick look is lit" "no '$scene' in '$SCENES'"
fi
done_testing
