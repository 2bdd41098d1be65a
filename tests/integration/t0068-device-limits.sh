#!/bin/sh
# The limits that remain of the GPU integrators are the device's or the integrator's, not the
# job's: past them a render exits 1 ("the device cannot"), not 2 ("bad job"), before anything
# renders, with the limit named (raybundle-job(5), LIMITS): a scene whose vertices pass
# lavapipe's 128 MiB storage-buffer range. Lights are not such a limit: 70 lights (once refused
# past a fixed 64) render with every integrator, and as the one light they add up to.
. tests/integration/lib.sh

cp -r jobs/demo "$T/demo"
# A floor lit from above by 70 point lights at one place, and by the one light of their sum: with
# nothing to cast a shadow, the lights past the 64 shadow-map layers (the 11th point light on)
# light as the shadowed ones do, and the two jobs make the same image.
floor_panel_gltf "$T/floor.gltf" "[0]"
lights_job() { # FILE COUNT INTENSITY
    {
        printf 'scene: floor.gltf\noutput: %s/f.####.exr\nresolution: [48, 32]\n' "${1%.yaml}"
        printf 'frames: {start: 0, end: 0}\nenvironment: {color: [0, 0, 0]}\n'
        printf 'camera: {fov_y_deg: 60, keys: [{t: 0, position: [0, 1.2, 2], look_at: [0, 0, 0]}]}\n'
        printf 'lights:\n'
        i=0
        while [ $i -lt "$2" ]; do
            echo "  - {type: point, position: [0.2, 1.5, 0.1], intensity: $3}"
            i=$((i + 1))
        done
    } >"$1"
}
lights_job "$T/many.yaml" 70 0.05
lights_job "$T/one.yaml" 1 3.5
for integrator in direct bdpt hybrid reference; do
    extra=""
    [ $integrator = reference ] && extra="--spp 16 --set integrator.reference.paths=direct"
    rb render "$T/many.yaml" -q --integrator $integrator $extra
    expect_exit 0 "$integrator renders 70 job lights"
    rb render "$T/one.yaml" -q --integrator $integrator $extra
    expect_exit 0 "$integrator renders their sum as one light"
    e=$("$RB" compare "$T/many/f.0000.exr" "$T/one/f.0000.exr" --json |
        sed -n 's/.*"relmse": \([0-9.e+-]*\).*/\1/p')
    check "$integrator: 70 lights make the image of the one they add up to (relMSE $e)" \
        awk "BEGIN { exit !(\"$e\" != \"\" && $e < 1e-4) }"
    tap_run "$BUILD/tests/tools/exrstat" "$T/many/f.0000.exr" R 0.01
    rm -rf "$T/many" "$T/one"
done

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
