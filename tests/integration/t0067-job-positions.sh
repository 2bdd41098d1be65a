#!/bin/sh
# A job that the scene or the disk refuses after the job file parsed (a clip or camera node the
# scene lacks, an environment map that cannot be read, an OpenColorIO config whose transform
# does not build) is said at the file, line and column of the job key that asked for it, as the
# parser's own errors are; an override at its --set. The config is checked before any frame.
. tests/integration/lib.sh

cp -r jobs/demo "$T/demo"
# job NAME LINE: a job of the demo's room at 16x16, one frame, with LINE added as its line 5.
job() {
    printf 'scene: demo/room.gltf\noutput: out/f.####.exr\nresolution: [16, 16]\nframes: {start: 0, end: 0}\n%s\n' \
        "$2" >"$T/$1.yaml"
}
refused() { # refused NAME MESSAGE DESCRIPTION [OPTION...]
    name=$1 msg=$2 what=$3
    shift 3
    rb render "$T/$name.yaml" -q --integrator direct "$@"
    expect_exit 2 "$what: refused as a bad job"
    stderr_has "raybundle: error: $msg" "$what: said at the job key"
}

job clip 'animation: {clips: ["Nope"]}'
refused clip "$T/clip.yaml:5:20: animation clip 'Nope' not found (scene has: Demo)" "a missing clip"
job cam 'camera: {node: "NoCam"}'
refused cam "$T/cam.yaml:5:16: camera node 'NoCam' not found in the scene" "a missing camera node"
job floor 'camera:
  node: Floor'
refused floor "$T/floor.yaml:6:9: camera node 'Floor' has no camera" "a camera node without a camera"
job env 'environment: {map: demo/room.gltf}'
refused env "$T/env.yaml:5:20: environment map: cannot read '$T/demo/room.gltf'" \
    "an environment map that cannot be read"
# The bundled config with a LUT file that is not there in its default view's transform: it
# loads and validates, and fails only when the transform is built.
awk '{print} /^view_transforms:/ {vt=1} vt && /name: ACES 1.0 - SDR Video$/ {a=1}
     a && /children:/ {print "        - !<FileTransform> {src: missing.spi1d, interpolation: linear}"; a=0}' \
    share/ocio/config.ocio | sed 's/^search_path: ""/search_path: luts/' >"$T/broken.ocio"
check "the broken config names the missing LUT" grep -q "missing.spi1d" "$T/broken.ocio"
job ocio 'color: {config: broken.ocio, preview: true}'
refused ocio "$T/ocio.yaml:5:17: ocio: config '$T/broken.ocio': The specified file reference 'missing.spi1d' could not be located" \
    "an OpenColorIO config whose view cannot be built"
check "... found before any frame was rendered" test ! -e "$T/out"
job plain ''
refused plain "--set:2:13: camera node 'Nope' not found in the scene" "a missing camera node set by --set" \
    --set resolution=[16,16] --set camera.node=Nope
rb render "$T/plain.yaml" -q --integrator direct --frames 0 --size 8x8
expect_exit 0 "the same job without those keys renders"

done_testing
