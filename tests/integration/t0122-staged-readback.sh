#!/bin/sh
# Where the GPU has no memory that is both its own and host-cached (a discrete GPU), the output
# pass writes the frame into device memory and one copy takes it across the bus into the
# host-visible readback. lavapipe has unified memory and writes the readback directly; with
# RB_GPU_STAGED_READBACK=1 it takes the copy path too, which must be validation-clean, give the
# same bits for every integrator (banded 1920x1080 readback included), and be timed as its own
# pass, "readback", that the direct path does not have.
. tests/integration/lib.sh

for integrator in direct bdpt hybrid; do
    rb render jobs/demo.yaml --integrator "$integrator" --frames 1-2 --size 160x90 \
        --out "$T/direct-$integrator" --validate -q
    expect_exit 0 "$integrator renders with the readback written directly"
    RB_GPU_STAGED_READBACK=1 rb render jobs/demo.yaml --integrator "$integrator" \
        --frames 1-2 --size 160x90 --out "$T/staged-$integrator" --validate -q
    expect_exit 0 "$integrator renders with the staged readback, validation-clean"
    for f in "$T/direct-$integrator"/*.exr; do
        check "$integrator $(basename "$f"): the same bits either way" \
            cmp -s "$f" "$T/staged-$integrator/$(basename "$f")"
    done
    check "$integrator: the staged readback is timed as the pass 'readback'" \
        grep -q '"readback"' "$T/staged-$integrator/frame.0002.timing.json"
    check "$integrator: the direct path has no such pass" \
        sh -c "! grep -q '\"readback\"' '$T/direct-$integrator/frame.0002.timing.json'"
done

# A readback larger than one storage binding (written in bands of rows), copied in one piece.
for mode in direct staged; do
    if [ $mode = staged ]; then export RB_GPU_STAGED_READBACK=1; fi
    rb render jobs/demo.yaml --frames 0 --size 1920x1080 \
        --set integrator.direct.shadow_size=256 --out "$T/big-$mode" --validate -q
    expect_exit 0 "1920x1080 renders ($mode readback)"
    unset RB_GPU_STAGED_READBACK
done
check "1920x1080: the same bits with the staged readback" \
    cmp -s "$T/big-direct/frame.0000.exr" "$T/big-staged/frame.0000.exr"
done_testing
