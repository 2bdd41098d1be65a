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

# glTF properties of the wrong type, which tinygltf would skip: exit 2, the file and the JSON
# pointer named. One triangle; the node's and the mesh's members are spliced in.
typed() { # typed NAME NODE-MEMBERS MESH-MEMBERS POINTER-AND-PROBLEM
    cat >"$T/$1.gltf" <<GLTF
{"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
 "nodes": [{$2}], "meshes": [{$3}],
 "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}],
 "bufferViews": [{"buffer": 0, "byteLength": 36}],
 "buffers": [{"byteLength": 36, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}]}
GLTF
    rb render "$T/$1.gltf" --out "$T/out-$1" -q
    expect_exit 2 "$1: exits 2"
    stderr_has "raybundle: error: scene '$T/$1.gltf': $4" "$1: names the file and the pointer"
    check "$1: no output written" test ! -e "$T/out-$1"
}
prim='"primitives": [{"attributes": {"POSITION": 0}}]'
typed primitives-object '"mesh": 0' '"primitives": {}' \
    '/meshes/0/primitives: expected array, found object'
typed scale-string '"mesh": 0, "scale": "not a number"' "$prim" \
    '/nodes/0/scale: expected array of 3 numbers, found string'
typed mesh-string '"mesh": "0"' "$prim" \
    '/nodes/0/mesh: expected non-negative integer, found string'
typed no-attributes '"mesh": 0' '"primitives": [{"mode": 4}]' \
    '/meshes/0/primitives/0/attributes: expected object, found nothing'
typed short-translation '"mesh": 0, "translation": [1, 2]' "$prim" \
    '/nodes/0/translation: expected array of 3 numbers, found array of 2'
typed indices-string '"mesh": 0' '"primitives": [{"attributes": {"POSITION": 0}, "indices": "0"}]' \
    '/meshes/0/primitives/0/indices: expected non-negative integer, found string'
typed negative-material '"mesh": 0' '"primitives": [{"attributes": {"POSITION": 0}, "material": -1}]' \
    '/meshes/0/primitives/0/material: expected non-negative integer, found -1'
typed name-object '"mesh": 0, "name": {"first": "Box"}' "$prim" \
    '/nodes/0/name: expected string, found object'

# --lenient (render and reference) loads such a file as tinygltf reads it, with a warning.
sloppy=$T/scale-string.gltf
warning="raybundle: warning: scene '$sloppy': /nodes/0/scale: expected array of 3 numbers, found string"
rb render "$sloppy" --lenient --size 16x16 --out "$T/out-lenient"
expect_exit 0 "--lenient: render exits 0"
stderr_has "$warning" "--lenient: render warns, naming the pointer"
check "--lenient: render writes the frame" test -f "$T/out-lenient/frame.0000.exr"
rb reference "$sloppy" --lenient --size 8x8 --spp 1 --out "$T/out-lenient-ref"
expect_exit 0 "--lenient: reference exits 0"
stderr_has "$warning" "--lenient: reference warns, naming the pointer"
rb reference "$sloppy" --size 8x8 --spp 1 --out "$T/out-strict-ref" -q
expect_exit 2 "without --lenient: reference exits 2"
done_testing
