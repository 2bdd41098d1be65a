#!/bin/sh
# The direct integrator lights an area-lit scene by its emitters (fixed point samples of the
# emissive triangles, each with a cube of shadow maps), as the reference's direct path space
# does with the same samples: the Cornell box's direct render against the reference's direct
# path space, and against the direct light of the quad itself (the reference's bdpt path space
# samples the quad: its direct layer). Before the emitters lit direct, its room was black: a
# relMSE of 0.35 against the quad's direct light.
. tests/integration/lib.sh

scene=cornell-box/CornellBox.glb
if ! have_scene "$scene"; then
    skip "$scene: direct lights the room by its emitters" "no '$scene' in '$SCENES'"
    done_testing
    exit
fi
set -- --frames 0 --size 128x128 -q
rb render "$SCENES/$scene" --integrator direct "$@" --out "$T/gpu" --validate
expect_exit 0 "$scene: direct renders, validation-clean"
rb render "$SCENES/$scene" --integrator direct "$@" --out "$T/gpu2"
check "$scene: direct renders the same bits twice" \
    "$BUILD/tests/tools/samebits" "$T/gpu/frame.0000.exr" "$T/gpu2/frame.0000.exr"
# The point samples' light, exact visibility in place of the shadow maps (measured: 2.9e-4).
rb reference "$SCENES/$scene" "$@" --spp 1 --set integrator.reference.paths=direct --out "$T/ref"
expect_exit 0 "$scene: the reference's direct path space renders"
rb compare "$T/gpu/frame.0000.exr" "$T/ref/frame.0000.exr" --max-relmse 2e-3
expect_exit 0 "$scene: direct and the reference's direct path space agree within relMSE 2e-3"
# The quad's own direct light, 64 samples per pixel (measured: 0.027; 0.35 with a black room).
rb reference "$SCENES/$scene" "$@" --spp 64 --set integrator.reference.paths=bdpt --out "$T/quad"
expect_exit 0 "$scene: the reference's bdpt path space renders"
rb compare "$T/gpu/frame.0000.exr" "$T/quad/frame.0000.exr" --layer direct --max-relmse 0.06
expect_exit 0 "$scene: direct's light is the quad's direct light within relMSE 0.06"
# integrator.direct.emitter_lights 0: the emitters light nothing again (the quad's own emission
# stays), and the reference's direct path space follows the same setting.
rb render "$SCENES/$scene" --integrator direct "$@" --out "$T/none" \
    --set integrator.direct.emitter_lights=0
expect_exit 0 "$scene: direct renders without emitter samples"
rb compare "$T/none/frame.0000.exr" "$T/quad/frame.0000.exr" --layer direct --max-relmse 0.06
expect_exit 1 "$scene: without emitter samples the room is not the quad's direct light"
rb reference "$SCENES/$scene" "$@" --spp 1 --set integrator.reference.paths=direct \
    --set integrator.direct.emitter_lights=0 --out "$T/ref0"
rb compare "$T/none/frame.0000.exr" "$T/ref0/frame.0000.exr" --max-relmse 2e-3
expect_exit 0 "$scene: the reference's direct path space without emitter samples agrees"
done_testing
