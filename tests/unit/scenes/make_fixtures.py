#!/usr/bin/env python3
"""Writes features.gltf, the hand-made fixture of tests/unit/test_scene.c: every loader feature
the shared sample scenes do not use (strips, fans, points, missing normals, generated tangents,
u8 indices, normalized texcoords, sparse accessors, morph targets, matrix nodes, cameras,
KHR_lights_punctual, emissive strength, a 16-bit PNG, STEP/CUBICSPLINE samplers).
Run it from this directory; the output is committed, so this only matters when it changes."""
import base64, json, math, struct, zlib

buf = bytearray()
views, accessors = [], []

def add(data, comp, typ, count, normalized=False, minmax=None):
    while len(buf) % 4:
        buf.append(0)
    views.append({"buffer": 0, "byteOffset": len(buf), "byteLength": len(data)})
    buf.extend(data)
    a = {"bufferView": len(views) - 1, "componentType": comp, "type": typ, "count": count}
    if normalized:
        a["normalized"] = True
    if minmax:
        a["min"], a["max"] = minmax
    accessors.append(a)
    return len(accessors) - 1

def f32(vals):
    return struct.pack("<%df" % len(vals), *vals)

def vec3(pts):
    flat = [c for p in pts for c in p]
    mn = [min(p[i] for p in pts) for i in range(3)]
    mx = [max(p[i] for p in pts) for i in range(3)]
    return add(f32(flat), 5126, "VEC3", len(pts), minmax=(mn, mx))

# mesh 0 "Strip": 4 vertices as a triangle strip, with normals, not indexed -> 2 triangles
strip_pos = vec3([(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0)])
strip_nrm = vec3([(0, 0, 1)] * 4)
# mesh 1 "Fan": centre + 4 rim vertices, u8 indices, no normals -> 3 flat triangles
fan_pos = vec3([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (-1, 1, 0)])
fan_idx = add(bytes([0, 1, 2, 3, 4]), 5121, "SCALAR", 5)
# mesh 2 "Mixed": a textured triangle (normal map, no tangents) and a points primitive
tri_pos = vec3([(0, 0, 0), (2, 0, 0), (0, 2, 0)])
tri_nrm = vec3([(0, 0, 1)] * 3)
tri_uv = add(bytes([0, 0, 255, 0, 0, 255, 0, 0]), 5121, "VEC2", 3, normalized=True)
# mesh 3 "Morph": a triangle with one target whose POSITION deltas are sparse (no bufferView)
morph_pos = vec3([(0, 0, 0), (1, 0, 0), (0, 1, 0)])
morph_nrm = vec3([(0, 0, 1)] * 3)
sp_idx_view = len(views)
add(struct.pack("<H", 2) + b"\0\0", 5123, "SCALAR", 1)
accessors.pop()
sp_val_view = len(views)
add(f32([0, 0, 3]), 5126, "VEC3", 1)
accessors.pop()
accessors.append({"componentType": 5126, "type": "VEC3", "count": 3,
                  "min": [0, 0, 0], "max": [0, 0, 3],
                  "sparse": {"count": 1,
                             "indices": {"bufferView": sp_idx_view, "componentType": 5123},
                             "values": {"bufferView": sp_val_view}}})
morph_delta = len(accessors) - 1

# animations: STEP translation of StripNode, CUBICSPLINE weights of MorphNode,
# LINEAR rotation of FanNode (0 -> 90 degrees about Y)
t3 = add(f32([0, 1, 2]), 5126, "SCALAR", 3, minmax=([0], [2]))
step_vals = add(f32([0, 0, 0, 5, 0, 0, 9, 0, 0]), 5126, "VEC3", 3)
t2 = add(f32([0, 1]), 5126, "SCALAR", 2, minmax=([0], [1]))
# per key: in-tangent, value, out-tangent
cubic_vals = add(f32([0, 0, 2, 0, 1, 0]), 5126, "SCALAR", 6)
s = math.sqrt(0.5)
rot_vals = add(f32([0, 0, 0, 1, 0, s, 0, s]), 5126, "VEC4", 2)

def png16_grey_alpha():
    """2x1 pixels, 16-bit grey + alpha: (0xffff, 0x8000) and (0x0000, 0xffff)."""
    raw = b"\0" + struct.pack(">4H", 0xFFFF, 0x8000, 0x0000, 0xFFFF)
    def chunk(t, d):
        return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d))
    ihdr = struct.pack(">IIBBBBB", 2, 1, 16, 4, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw))
            + chunk(b"IEND", b""))

def matrix_trs(t, angle_y, sc):
    c, s_ = math.cos(angle_y), math.sin(angle_y)
    # column-major T * R_y * S
    return [c * sc, 0, -s_ * sc, 0, 0, sc, 0, 0, s_ * sc, 0, c * sc, 0, t[0], t[1], t[2], 1]

gltf = {
    "asset": {"version": "2.0", "generator": "raybundle make_fixtures.py"},
    "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength",
                       "KHR_texture_transform"],
    "extensionsRequired": ["KHR_lights_punctual"],
    "extensions": {"KHR_lights_punctual": {"lights": [
        {"name": "Bulb", "type": "point", "color": [1, 0, 0], "intensity": 2, "range": 5},
        {"name": "Cone", "type": "spot", "spot": {}},
        {"name": "Sun", "type": "directional", "intensity": 3}]}},
    "scene": 0,
    "scenes": [{"name": "Main", "nodes": [0]}],
    "nodes": [
        {"name": "Root", "translation": [1, 0, 0], "children": [1, 2, 3, 4, 5, 6, 7, 8]},
        {"name": "StripNode", "mesh": 0, "matrix": matrix_trs((0, 2, 0), math.pi / 2, 2)},
        {"name": "FanNode", "mesh": 1},
        {"name": "MixedNode", "mesh": 2},
        {"name": "MorphNode", "mesh": 3, "weights": [0.25]},
        {"name": "Cam", "camera": 0, "translation": [0, 0, 10]},
        {"name": "SunNode", "rotation": [-s, 0, 0, s],
         "extensions": {"KHR_lights_punctual": {"light": 2}}},
        {"name": "ConeNode", "translation": [0, 3, 0],
         "extensions": {"KHR_lights_punctual": {"light": 1}}},
        {"name": "BulbNode", "translation": [0, 0, 2],
         "extensions": {"KHR_lights_punctual": {"light": 0}}},
        {"name": "Orphan", "mesh": 0},
    ],
    "cameras": [{"name": "Lens", "type": "perspective",
                 "perspective": {"yfov": 0.8, "znear": 0.1, "zfar": 100}}],
    "meshes": [
        {"name": "Strip", "primitives": [
            {"mode": 5, "attributes": {"POSITION": strip_pos, "NORMAL": strip_nrm}}]},
        {"name": "Fan", "primitives": [
            {"mode": 6, "indices": fan_idx, "attributes": {"POSITION": fan_pos}}]},
        {"name": "Mixed", "primitives": [
            {"material": 0,
             "attributes": {"POSITION": tri_pos, "NORMAL": tri_nrm, "TEXCOORD_0": tri_uv}},
            {"mode": 0, "attributes": {"POSITION": tri_pos}}]},
        {"name": "Morph", "weights": [0.5], "primitives": [
            {"attributes": {"POSITION": morph_pos, "NORMAL": morph_nrm},
             "targets": [{"POSITION": morph_delta}]}]},
    ],
    "materials": [{
        "name": "Bumpy",
        "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.25, 1, 1],
                                 "baseColorTexture": {"index": 0, "texCoord": 1},
                                 "metallicFactor": 0.75, "roughnessFactor": 0.125},
        "normalTexture": {"index": 0, "scale": 0.5},
        "emissiveFactor": [1, 0.5, 0.25],
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4}},
        "alphaMode": "MASK", "alphaCutoff": 0.3, "doubleSided": True}],
    "textures": [{"source": 0}],
    "images": [{"name": "grey16",
                "uri": "data:image/png;base64," + base64.b64encode(png16_grey_alpha()).decode()}],
    "animations": [
        {"name": "Steps", "samplers": [{"input": t3, "output": step_vals,
                                        "interpolation": "STEP"}],
         "channels": [{"sampler": 0, "target": {"node": 1, "path": "translation"}}]},
        {"name": "Cubic", "samplers": [{"input": t2, "output": cubic_vals,
                                        "interpolation": "CUBICSPLINE"}],
         "channels": [{"sampler": 0, "target": {"node": 4, "path": "weights"}}]},
        {"name": "Turn", "samplers": [{"input": t2, "output": rot_vals}],
         "channels": [{"sampler": 0, "target": {"node": 2, "path": "rotation"}}]},
    ],
    "accessors": accessors,
    "bufferViews": views,
    "buffers": [{"byteLength": len(buf),
                 "uri": "data:application/octet-stream;base64," + base64.b64encode(buf).decode()}],
}
with open("features.gltf", "w") as f:
    json.dump(gltf, f, indent=1)
    f.write("\n")
