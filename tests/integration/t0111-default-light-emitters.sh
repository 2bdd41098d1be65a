#!/bin/sh
# default_light: auto judges emissive surfaces by how much they light, not by whether they emit:
# an emitter too weak to light the view (a dim emissive texture) gets the default light, with a
# warning that says why; a bright one does not; default_light: off still leaves the weak scene
# dark. The WaterBottle's quick look (an emissive texture that is nearly black) is lit.
. tests/integration/lib.sh

# A floor (Lambertian, white) and a 0.5 m panel 1 m above it, emissive factor 1 times a texture
# GLOW (its one colour 1/255 in sRGB, 0.0003 linear: the weak panel; or 255, the bright one).
write_scene() { # write_scene FILE TEXTURE
    cat >"$1" <<GLTF
{"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 1]}],
 "nodes": [{"name": "Floor", "mesh": 0}, {"name": "Panel", "mesh": 1}],
 "meshes": [{"name": "Floor", "primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2, "material": 0}]},
            {"name": "Panel", "primitives": [{"attributes": {"POSITION": 3, "NORMAL": 4}, "indices": 5, "material": 1}]}],
 "images": [{"uri": "$2"}], "textures": [{"source": 0}],
 "materials": [{"name": "White", "doubleSided": true, "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1], "metallicFactor": 0, "roughnessFactor": 1}},
               {"name": "Glow", "doubleSided": true, "emissiveFactor": [1, 1, 1], "emissiveTexture": {"index": 0}, "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0}}],
 "buffers": [{"byteLength": 216, "uri": "data:application/octet-stream;base64,AACAvwAAAAAAAIC/AACAPwAAAAAAAIC/AACAPwAAAAAAAIA/AACAvwAAAAAAAIA/AAAAAAAAgD8AAAAAAAAAAAAAgD8AAAAAAAAAAAAAgD8AAAAAAAAAAAAAgD8AAAAAAAACAAEAAAADAAIAAACAvgAAgD8AAIC+AACAPgAAgD8AAIC+AACAPgAAgD8AAIA+AACAvgAAgD8AAIA+AAAAAAAAgL8AAAAAAAAAAAAAgL8AAAAAAAAAAAAAgL8AAAAAAAAAAAAAgL8AAAAAAAABAAIAAAACAAMA"}],
 "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 48},
                 {"buffer": 0, "byteOffset": 96, "byteLength": 12}, {"buffer": 0, "byteOffset": 108, "byteLength": 48},
                 {"buffer": 0, "byteOffset": 156, "byteLength": 48}, {"buffer": 0, "byteOffset": 204, "byteLength": 12}],
 "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, 0, -1], "max": [1, 0, 1]},
               {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
               {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"},
               {"bufferView": 3, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-0.25, 1, -0.25], "max": [0.25, 1, 0.25]},
               {"bufferView": 4, "componentType": 5126, "count": 4, "type": "VEC3"},
               {"bufferView": 5, "componentType": 5123, "count": 6, "type": "SCALAR"}]}
GLTF
}
oiiotool --create 4x4 3 --fill:color=0.004,0.004,0.004 4x4 -d uint8 -o "$T/dim.png"
oiiotool --create 4x4 3 --fill:color=1,1,1 4x4 -d uint8 -o "$T/bright.png"
write_scene "$T/weak.gltf" dim.png
write_scene "$T/strong.gltf" bright.png
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
