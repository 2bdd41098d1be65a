#!/bin/sh
# No NaN or Inf in the output: the whole demo renders without one (its timing sidecars count
# none and every EXR value is finite), and a frame that really holds infinite values is counted,
# in the sidecar and in a warning, by the GPU integrator and by the CPU reference alike.
. tests/integration/lib.sh

# nonfinite JSON: the sidecar's count, or nothing when the key is missing.
nonfinite() {
    sed -n 's/^ *"nonfinite": \([0-9][0-9]*\).*/\1/p' "$1"
}

# bad_values EXR: how many values of the file exrstat finds NaN or infinite (read back through
# OpenImageIO, apart from the renderer's own count).
bad_values() {
    "$BUILD/tests/tools/exrstat" "$1" R -1 2>&1 | sed -n 's/.*finite (\([0-9]*\) are not).*/\1/p'
}

# All 48 frames of the demo. Before the BRDF's half-vector clamp, a NaN showed on the ceiling
# (where the fill light sits on the camera's line of sight) at its own 640x360 in 10 frames;
# 192x108 is the smallest size tried where it still showed (frame 7).
rb render jobs/demo.yaml --size 192x108 --out "$T/demo"
expect_exit 0 "the whole demo renders"
frames=0
dirty=""
for json in "$T"/demo/frame.*.timing.json; do
    [ -f "$json" ] || continue
    frames=$((frames + 1))
    c=$(nonfinite "$json")
    [ "$c" = 0 ] || dirty="$dirty $(basename "$json" .timing.json): ${c:-no count}"
done
check "the demo wrote 48 timing sidecars" test "$frames" -eq 48
if [ -z "$dirty" ]; then
    ok "no demo frame has a non-finite value (timing sidecars)"
else
    not_ok "no demo frame has a non-finite value (timing sidecars)" "$dirty"
fi
dirty=""
for exr in "$T"/demo/frame.*.exr; do
    [ -f "$exr" ] || continue
    c=$(bad_values "$exr")
    [ "$c" = 0 ] || dirty="$dirty $(basename "$exr" .exr): ${c:-unreadable}"
done
if [ -z "$dirty" ]; then
    ok "every value of every demo EXR is finite"
else
    not_ok "every value of every demo EXR is finite" "$dirty"
fi
if grep -q 'non-finite' "$T/stderr"; then
    not_ok "the demo logs no non-finite warning" "$(grep 'non-finite' "$T/stderr" | head -n 5)"
else
    ok "the demo logs no non-finite warning"
fi

# The counter can fail: an emissive triangle whose emissive factor times its
# KHR_materials_emissive_strength overflows float (1e39 > 3.4e38), so its pixels are infinite.
# The loader refuses such an emitter; --lenient loads it with a warning.
# Positions (0,0,0) (1,0,0) (0,1,0), u16 indices 0 1 2, facing +Z, the camera in front of it.
cat >"$T/inf.gltf" <<'GLTF'
{"asset": {"version": "2.0"},
 "extensionsUsed": ["KHR_materials_emissive_strength"],
 "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
 "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
 "materials": [{"emissiveFactor": [1, 1, 1],
                "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 1e39}}}],
 "accessors": [{"bufferView": 0, "componentType": 5126, "type": "VEC3", "count": 3,
                "min": [0, 0, 0], "max": [1, 1, 0]},
               {"bufferView": 1, "componentType": 5123, "type": "SCALAR", "count": 3}],
 "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                 {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
 "buffers": [{"byteLength": 44, "uri":
   "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAABAAIAAAA="}]}
GLTF
cat >"$T/inf.yaml" <<'YAML'
scene: inf.gltf
output: inf/frame.####.exr
resolution: [16, 16]
frames: {start: 0, end: 0}
camera:
  fov_y_deg: 40
  keys: [{t: 0, position: [0.3, 0.3, 2], look_at: [0.3, 0.3, 0]}]
YAML
for how in render reference; do
    extra=""
    [ "$how" = reference ] && extra="--spp 1"
    rb "$how" "$T/inf.yaml" $extra --out "$T/inf-$how"
    expect_exit 2 "$how: the overflowing emitter is refused"
    stderr_has "/materials/0: emissiveFactor x extensions/KHR_materials_emissive_strength/emissiveStrength is 1e+39, more than 1e+30" \
        "$how: the material named"
    rb "$how" "$T/inf.yaml" $extra --lenient --out "$T/inf-$how"
    expect_exit 0 "$how: with --lenient the overflowing emitter renders (a warning, not an error)"
    c=$(nonfinite "$T/inf-$how/frame.0000.timing.json")
    e=$(bad_values "$T/inf-$how/frame.0000.exr")
    check "$how: the sidecar counts non-finite values (${c:-none})" test "${c:-0}" -gt 0
    check "$how: the count (${c:-none}) is the EXR's (${e:-unreadable})" test "${c:-x}" = "${e:-y}"
    stderr_has "frame 0: $c non-finite values (NaN or Inf) in the output" \
        "$how: the warning names the frame and the count"
done

done_testing
