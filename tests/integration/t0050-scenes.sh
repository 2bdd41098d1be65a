#!/bin/sh
# Every shared glTF scene loads and renders one frame with validation on and no messages.
. tests/integration/lib.sh

if [ ! -d "$SCENES" ]; then
    skip "every shared scene renders" "no sample scenes in '$SCENES' (set RB_SCENES)"
    done_testing
fi
S=$SCENES
found=0
for scene in "$S"/*/*.glb "$S"/*/*.gltf; do
    [ -f "$scene" ] || continue
    found=$((found + 1))
    name=$(basename "$scene")
    rb render "$scene" --frames 0 --size 160x120 --out "$T/$name" -q --validate
    expect_exit 0 "$name renders one frame"
    check "$name wrote its EXR" test -s "$T/$name/frame.0000.exr"
    check "$name: no NaN or Inf in the output (timing sidecar)" \
        grep -Eq '"nonfinite": 0([^0-9]|$)' "$T/$name/frame.0000.timing.json"
    if grep -q 'validation' "$T/stderr"; then
        not_ok "$name: no validation messages" "$(head -c 1500 "$T/stderr")"
    else
        ok "$name: no validation messages"
    fi
done
check "the shared scenes were found in $S" test "$found" -ge 8
done_testing
