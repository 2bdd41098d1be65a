#!/bin/sh
# The limits that remain of the GPU integrators are the device's or the integrator's, not the
# job's: past them a render exits 1 ("the device cannot"), not 2 ("bad job"), before anything
# renders, with the limit named (raybundle-job(5), LIMITS). More lights than the GPU
# integrators take (said at the job's lights key), which the reference renders; a scene whose
# vertices pass lavapipe's 128 MiB storage-buffer range.
. tests/integration/lib.sh

cp -r jobs/demo "$T/demo"
{
    printf 'scene: demo/room.gltf\noutput: out/f.####.exr\nresolution: [16, 16]\nframes: {start: 0, end: 0}\nlights:\n'
    i=0
    while [ $i -lt 70 ]; do
        echo "  - {type: point, position: [0, 1.5, 0], intensity: 0.05}"
        i=$((i + 1))
    done
} >"$T/lights.yaml"
for integrator in direct bdpt; do
    rb render "$T/lights.yaml" -q --integrator $integrator
    expect_exit 1 "$integrator: 70 job lights past the 64 it takes exit 1"
    stderr_has "raybundle: error: $T/lights.yaml:6:3: " "$integrator: said at the job's lights key"
    stderr_has "(the job's 70, the scene's and the emissive surfaces' samples): the $integrator integrator takes at most 64 (the reference any number)" \
        "$integrator: the count, the integrator and its limit"
    check "$integrator: nothing written" test ! -e "$T/out/f.0000.exr"
done
rb render "$T/lights.yaml" -q --integrator reference --spp 1
expect_exit 0 "the reference renders the 70 lights"

# An N x N grid of triangles at y 0, indexed, without normals: the loader gives each triangle
# three vertices of its own (flat shading), 6 N^2 vertices.
python3 - "$T/grid.gltf" 708 <<'PY'
import array, json, sys
out, n = sys.argv[1], int(sys.argv[2])
v = n + 1
pos = array.array('f')
for j in range(v):
    for i in range(v):
        pos.extend((-1 + 2 * i / n, 0.0, -1 + 2 * j / n))
idx = array.array('I')
for j in range(n):
    for i in range(n):
        a = j * v + i
        idx.extend((a, a + v, a + 1, a + 1, a + v, a + v + 1))
data = pos.tobytes() + idx.tobytes()
open(out.replace('.gltf', '.bin'), 'wb').write(data)
P = len(pos) * 4
json.dump({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
           "buffers": [{"byteLength": len(data), "uri": "grid.bin"}],
           "bufferViews": [{"buffer": 0, "byteLength": P}, {"buffer": 0, "byteOffset": P, "byteLength": len(idx) * 4}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": v * v, "type": "VEC3",
                          "min": [-1, 0, -1], "max": [1, 0, 1]},
                         {"bufferView": 1, "componentType": 5125, "count": len(idx), "type": "SCALAR"}]},
          open(out, 'w'))
PY
rb render "$T/demo/room.gltf" --out "$T/probe" --frames 0 --size 8x8 --integrator direct -q
if grep -q llvmpipe "$T/probe/frame.0000.timing.json" 2>/dev/null; then
    rb render "$T/grid.gltf" --out "$T/grid" --size 16x16 --integrator direct -q
    expect_exit 1 "1 M triangles expanded to 3 M vertices on lavapipe exit 1"
    stderr_has "scene '$T/grid.gltf' (3007584 vertices, 3007584 as posed): pass 'animate': storage buffer 'vertices.source' binds 240606720 bytes, more than the device's maxStorageBufferRange (134217728 bytes)" \
        "the refusal names the scene, its vertices, the buffer, its size and the limit"
    check "nothing written" test ! -e "$T/grid/frame.0000.exr"
else
    skip "the storage-range refusal" "the device is not lavapipe, whose 128 MiB range it needs"
fi

done_testing
