#!/bin/sh
# The limits that remain of the GPU integrators are the device's or the integrator's, not the
# job's: past them a render exits 1 ("the device cannot"), not 2 ("bad job"), before anything
# renders, with the limit named (raybundle-job(5), LIMITS; t0120 has the frame's). Lights are not
# such a limit: 70 lights (once refused past a fixed 64) render with every integrator, and as the
# one light they add up to; nor is one storage binding's range for the scene's vertices (t0069).
. tests/integration/lib.sh

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

done_testing
