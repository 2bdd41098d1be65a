#!/bin/sh
# Values the renderer's float arithmetic cannot carry, and glTF 2.0 conformance. A NaN or Inf in
# an accessor, a node's transform or a material, a negative light, a colour times its intensity
# above 1e30 (in the scene, the job or the environment map), an asset that is not glTF 2.0, an
# accessor of no elements, a rotation of length 0, negative key times and a light range <= 0 each
# exit 2 naming the element (its JSON pointer, or file:line:col in a job); --lenient makes the
# glTF ones warnings. Zero-length normals are replaced, with a warning. --strict fails a frame
# whose output holds NaN or Inf. The glTF files are the demo room with one thing broken.
. tests/integration/lib.sh

cp jobs/demo/room.gltf jobs/demo/room.bin "$T/"
# The cases, written by python3 into $T: NAME.gltf (NAME.bin beside it when the binary changes).
python3 - "$T" <<'PY'
import json, math, struct, sys
t = sys.argv[1]
room = json.load(open(t + '/room.gltf'))
data = open(t + '/room.bin', 'rb').read()
nan, inf = math.nan, math.inf

def patch(accessor, index, values):  # room.bin with floats from float index of an accessor on
    a = room['accessors'][accessor]
    at = room['bufferViews'][a['bufferView']].get('byteOffset', 0) + 4 * index
    b = bytearray(data)
    b[at:at + 4 * len(values)] = struct.pack('<%df' % len(values), *values)
    return bytes(b)

def write(name, edit=None, binary=None, glb=None):
    d = json.loads(json.dumps(room))
    if edit:
        edit(d)
    if binary:
        open('%s/%s.bin' % (t, name), 'wb').write(binary)
        d['buffers'][0]['uri'] = name + '.bin'
    if glb is None:
        open('%s/%s.gltf' % (t, name), 'w').write(json.dumps(d, indent=1))
        return
    del d['buffers'][0]['uri']  # a .glb: the JSON chunk, then room.bin as the BIN chunk
    j = json.dumps(d).encode()
    j += b' ' * (-len(j) % 4)
    body = struct.pack('<II', len(j), 0x4E4F534A) + j + struct.pack('<II', len(data), 0x004E4942) + data
    open('%s/%s.glb' % (t, name), 'wb').write(struct.pack('<4sII', b'glTF', glb, 12 + len(body)) + body)

light = lambda **kv: lambda d: d['extensions']['KHR_lights_punctual']['lights'][0].update(kv)
node = lambda **kv: lambda d: d['nodes'][7].update(kv)
write('anim-nan', binary=patch(24, 3, [nan, nan, nan]))  # translation key 1
write('anim-inf', binary=patch(22, 4, [inf]))  # rotation key 1
write('ibm-nan', binary=patch(30, 5, [nan]))
write('emissive', lambda d: d['materials'][3]['extensions']['KHR_materials_emissive_strength']
      .update(emissiveStrength=3e38))
write('light-neg', light(intensity=-30))
write('light-color', light(color=[1, -1, 1]))
write('light-big', light(intensity=1e38, color=[10, 10, 10]))
write('spot-cone', light(type='spot', spot={'innerConeAngle': 0.2, 'outerConeAngle': 2.0}))
write('range0', light(range=0))
write('range-neg', light(range=-2))
write('matrix', lambda d: d['nodes'][7].pop('translation') and
      d['nodes'][7].update(matrix=[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 1e300, 0, 0, 1]))
write('translation', node(translation=[1e39, 0, 0]))
write('scale', node(scale=[1, 4e38, 1]))
write('quat-node', node(rotation=[0, 0, 0, 0]))
write('quat-anim', binary=patch(22, 4, [0, 0, 0, 0]))
write('version3', lambda d: d['asset'].update(version='3.0'))
write('minversion', lambda d: d['asset'].update(minVersion='3.0'))
write('count0', lambda d: d['accessors'].append(
    {'bufferView': 0, 'componentType': 5126, 'count': 0, 'type': 'VEC3'}))
write('neg-times', binary=patch(21, 0, [-0.5]))
write('normal-zero', binary=patch(1, 3, [0, 0, 0]))  # the floor's vertex 1
write('glb1', glb=1)
write('glb2', glb=2)
PY

# load NAME [EXT] [OPTION...]: renders frame 0 of $T/NAME.EXT at 16x16 into $T/out-NAME.
load() {
    name=$1 ext=${2:-gltf}
    shift
    [ $# -gt 0 ] && shift
    rm -rf "$T/out-$name"
    timeout 60 "$RB" render "$T/$name.$ext" --frames 0 --size 16x16 --integrator direct \
        --out "$T/out-$name" "$@" >"$T/stdout" 2>"$T/stderr"
    status=$?
}
# refused NAME [EXT] MESSAGE: exits 2 naming the element, nothing written; --lenient warns.
refused() {
    name=$1 ext=gltf
    [ $# -eq 3 ] && ext=$2 && shift
    load "$name" "$ext" -q
    expect_exit 2 "$name: exits 2"
    stderr_has "raybundle: error: scene '$T/$name.$ext': $2" "$name: the element named"
    check "$name: nothing written" test ! -e "$T/out-$name/frame.0000.exr"
}
lenient() { # lenient NAME [EXT] MESSAGE: with --lenient, exit 0 and MESSAGE as a warning
    name=$1 ext=gltf
    [ $# -eq 3 ] && ext=$2 && shift
    load "$name" "$ext" --lenient
    expect_exit 0 "$name, --lenient: renders"
    stderr_has "raybundle: warning: scene '$T/$name.$ext': $2" "$name, --lenient: a warning"
}

# Part 1: nothing non-finite, negative or overflowing from the scene.
refused anim-nan "animation 'Demo' sampler 1: /animations/0/samplers/1/output: accessor 24: 3 of 9 values are not finite (NaN or Inf), the first in element 1"
refused anim-inf "animation 'Demo' sampler 0: /animations/0/samplers/0/output: accessor 22: 1 of 36 values are not finite (NaN or Inf), the first in element 1"
refused ibm-nan "skin 'ColumnSkin': /skins/0/inverseBindMatrices: accessor 30: 1 of 32 values are not finite (NaN or Inf), the first in element 0"
refused emissive "/materials/3: emissiveFactor x extensions/KHR_materials_emissive_strength/emissiveStrength is 3e+38, more than 1e+30"
refused light-neg "/extensions/KHR_lights_punctual/lights/0/intensity: -30 is negative"
refused light-color "/extensions/KHR_lights_punctual/lights/0/color: value 1 (-1) is not a finite number >= 0"
refused light-big "/extensions/KHR_lights_punctual/lights/0: color x intensity is 1e+39, more than 1e+30"
refused spot-cone "light 'Light': need 0 <= innerConeAngle < outerConeAngle <= pi/2"
refused matrix "/nodes/7/matrix: value 12 (1e+300) is not finite in float"
refused translation "/nodes/7/translation: value 0 (1e+39) is not finite in float"
refused scale "/nodes/7/scale: value 1 (4e+38) is not finite in float"

# Part 2: glTF 2.0 conformance, each a warning with --lenient.
refused version3 "/asset/version: '3.0' is not a glTF 2.x version"
lenient version3 "/asset/version: '3.0' is not a glTF 2.x version"
refused minversion "/asset/minVersion: the file needs glTF '3.0', and raybundle reads glTF 2.0"
refused glb1 glb "GLB header: container version 1, and glTF 2.0 binary files are version 2"
lenient glb1 glb "GLB header: container version 1"
load glb2 glb -q
expect_exit 0 "a GLB of container version 2 renders"
refused count0 "/accessors/33/count: 0, and an accessor has at least 1 element"
lenient count0 "/accessors/33/count: 0"
refused quat-node "/nodes/7/rotation: [0, 0, 0, 0] has length 0, and a rotation is a unit quaternion"
lenient quat-node "/nodes/7/rotation: [0, 0, 0, 0] has length 0"
refused quat-anim "/animations/0/samplers/0/output: accessor 22: 1 of 9 keys are [0, 0, 0, 0] (the first: key 1), and the rotations of /animations/0/channels/0 are unit quaternions"
refused neg-times "/animations/0/samplers/0/input: accessor 21: key 0 is at -0.5 s, and key times are >= 0"
lenient neg-times "/animations/0/samplers/0/input: accessor 21: key 0 is at -0.5 s"
refused range0 "/extensions/KHR_lights_punctual/lights/0/range: 0, and a range must be > 0"
refused range-neg "/extensions/KHR_lights_punctual/lights/0/range: -2, and a range must be > 0"
lenient range0 "/extensions/KHR_lights_punctual/lights/0/range: 0"

load normal-zero
expect_exit 0 "zero-length normals: renders"
stderr_has "raybundle: warning: scene '$T/normal-zero.gltf': /meshes/0/primitives/0/attributes/NORMAL: accessor 1: 1 of 81 normals have length 0; each is replaced by the normal of the faces around it" \
    "zero-length normals: a warning names the accessor and the count"

# The job: a colour times its intensity above 1e30, and an environment map's values.
job() { # job NAME YAML: a one-frame job of the room, rendered; exit 2, nothing written
    printf 'scene: room.gltf\noutput: out-%s/f.####.exr\nresolution: [16, 16]\nframes: {start: 0, end: 0}\n%s\n' \
        "$1" "$2" >"$T/$1.yaml"
    rb render "$T/$1.yaml" -q
    expect_exit 2 "$1: exits 2"
    check "$1: nothing written" test ! -e "$T/out-$1"
}
job env "environment: {color: [1e38, 1e38, 1e38], intensity: 1e10}"
stderr_has "env.yaml:5:53: 'environment.color' x 'environment.intensity' is 1e+48, more than 1e+30" \
    "env: the job key named"
job light "lights:
  - {type: point, color: [1e20, 1, 1], intensity: 1e20}"
stderr_has "light.yaml:6:51: 'lights[0].color' x 'lights[0].intensity' is 1e+40, more than 1e+30" \
    "light: the job key named"
# A 2x1 Radiance HDR (flat RGBE) whose first pixel is about 1e38.
printf '#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X 2\n\377\377\377\376\200\200\200\201' >"$T/hot.hdr"
job envmap "environment: {map: hot.hdr}"
stderr_has "environment map '$T/hot.hdr': pixel (0, 0) channel 0 is " "envmap: the pixel named"
stderr_has "which times 'environment.intensity' (1) is more than 1e+30" "envmap: the bound named"

# --strict: an overflowing emitter loaded with --lenient renders Inf (under bdpt, the default);
# --strict fails that frame.
strict() {
    rm -rf "$T/out-emissive"
    rb render "$T/emissive.gltf" --frames 0 --size 16x16 --out "$T/out-emissive" --lenient "$@"
}
strict -q --strict
expect_exit 1 "--strict, a frame with Inf values: exits 1"
stderr_has "raybundle: error: frame 0: " "--strict: the frame named"
stderr_has " non-finite values (NaN or Inf) in the output, and --strict makes that an error" \
    "--strict: the count given"
check "--strict: the frame is not written" test ! -e "$T/out-emissive/frame.0000.exr"
strict
expect_exit 0 "without --strict: the frame is written, with warnings"
stderr_has "non-finite values (NaN or Inf) in the output" "without --strict: the count is a warning"
done_testing
