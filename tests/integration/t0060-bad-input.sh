#!/bin/sh
# Bad input: each class of mistake exits 2 with a message naming the culprit (file:line:column
# for job files), and leaves no output file behind.
. tests/integration/lib.sh

scene=$(pwd)/jobs/demo/room.gltf
bad() { # bad NAME EXPECTED-TEXT JOB-TEXT
    printf '%s\n' "$3" >"$T/$1.yaml"
    rb render "$T/$1.yaml" -q
    expect_exit 2 "$1: exits 2"
    stderr_has "$2" "$1: message names the culprit"
    check "$1: no output written" test ! -e "$T/out-$1"
}

bad malformed "malformed.yaml:" "scene: $scene
resolution: [640, 360
output: out-malformed/f.####.exr"
bad unknown-key "unknown-key.yaml:3:1: unknown key 'sampels'" "scene: $scene
output: out-unknown-key/f.####.exr
sampels: 4"
bad wrong-type "wrong-type.yaml:3:13:" "scene: $scene
output: out-wrong-type/f.####.exr
resolution: wide"
bad missing-scene "missing-scene.yaml:1:8:" "scene: nope/missing.glb
output: out-missing-scene/f.####.exr"

# A truncated .glb (its header promises 1000 bytes, a 500-byte JSON chunk; the file ends early):
# exit 2, the file named.
printf 'glTF\002\000\000\000\350\003\000\000\364\001\000\000JSON{"asset": {"version": "2.0"}, "me' \
    >"$T/corrupt.glb"
printf 'scene: corrupt.glb\noutput: out-corrupt/f.####.exr\n' >"$T/corrupt.yaml"
rb render "$T/corrupt.yaml" -q
expect_exit 2 "corrupt .glb: exits 2"
stderr_has "corrupt.glb" "corrupt .glb: the file is named"
check "corrupt .glb: no output written" test ! -e "$T/out-corrupt"

# A glTF whose texture file is missing: exit 2, the image named. One textured triangle, its
# positions and texture coordinates in a data: buffer.
cat >"$T/textured.gltf" <<'GLTF'
{"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
 "nodes": [{"mesh": 0}],
 "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "material": 0}]}],
 "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
 "textures": [{"source": 0}],
 "images": [{"uri": "missing-basecolor.png"}],
 "buffers": [{"byteLength": 60, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAAAAAAAAAAAAIA/AAAAAAAAAAAAAIA/"}],
 "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                 {"buffer": 0, "byteOffset": 36, "byteLength": 24}],
 "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                "min": [0, 0, 0], "max": [1, 1, 0]},
               {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}]}
GLTF
printf 'scene: textured.gltf\noutput: out-texture/f.####.exr\n' >"$T/texture.yaml"
rb render "$T/texture.yaml" -q
expect_exit 2 "missing texture: exits 2"
stderr_has "missing-basecolor.png" "missing texture: the image is named"
check "missing texture: no output written" test ! -e "$T/out-texture"

rb render "$T/does-not-exist.yaml" -q
expect_exit 2 "missing job file: exits 2"
stderr_has "does-not-exist.yaml" "missing job file: the file is named"
done_testing
