#!/bin/sh
# The lines a person and a farm read: the closing line names the exact frames and a normalised
# directory; each frame's time is its sidecar's wall_ms; a "Saved: PATH" line on stdout per frame
# written when stdout is no terminal; warm-up frames are named; the bar fits the terminal.
. tests/integration/lib.sh

# A job in a subdirectory whose output goes through "..": the closing line shows the directory
# without it.
mkdir -p "$T/jobs"
sed "s#^scene: .*#scene: $PWD/jobs/demo/room.gltf#; s#^output: .*#output: ../out/frame.\#\#\#\#.exr#" \
    jobs/demo.yaml >"$T/jobs/demo.yaml"
rb render "$T/jobs/demo.yaml" --size 32x18 --integrator bdpt --frames 0-11 --chunk 1/4 \
    --set frames.start=0 --set frames.end=11
expect_exit 0 "a job writing to ../out renders"
stdout_has "^3 frames (3-5, chunk 1/4) in $T/out/: 3 rendered" \
    "the closing line names the output directory without 'jobs/..'"

# Frames 5, 7, 9 of a bdpt run: the exact list, a warm-up before each (each follows a gap).
rb render jobs/demo.yaml --size 32x18 --integrator bdpt --frames 5,7,9 --out "$T/gap"
expect_exit 0 "frames 5,7,9 render"
stdout_has "^3 frames (5-9:2) in $T/gap/: 3 rendered" "the closing line gives the exact frames"
for f in 5 7 9; do
    side="$T/gap/frame.000$f.timing.json"
    ms=$(sed -n 's/^  "wall_ms": \([0-9.e+-]*\),$/\1/p' "$side")
    check "frame $f's sidecar has a wall_ms ($ms)" test -n "$ms"
    want=$(printf '%.1f' "$ms")
    check "one 'Saved:' line for frame $f, with its sidecar's wall_ms ($want ms)" \
        test "$(grep -c "^Saved: $T/gap/frame.000$f.exr ($want ms)\$" "$T/stdout")" -eq 1
    stderr_has "raybundle: frame $f (" "frame $f has a progress line"
    check "frame $f's progress line shows its sidecar's wall_ms ($want ms)" \
        grep -q "^raybundle: frame $f ([0-9]/3) $want ms\$" "$T/stderr"
    stderr_has "raybundle: warming up on frames $((f - 3)) to $((f - 1)) for frame $f (not written)" \
        "the warm-up before frame $f is named"
done
check "exactly three 'Saved:' lines" test "$(grep -c '^Saved: ' "$T/stdout")" -eq 3
check "no warm-up frame is written" test ! -e "$T/gap/frame.0006.exr"

# Consecutive frames warm up once, before the first.
rb render jobs/demo.yaml --size 32x18 --integrator bdpt --frames 2-4 --out "$T/run"
check "a contiguous run warms up once" test "$(grep -c 'warming up' "$T/stderr")" -eq 1
# -q: no progress, no warm-up and no Saved lines; the closing line stays.
rb render jobs/demo.yaml --size 32x18 --integrator direct --frames 0-1 --out "$T/quiet" -q
expect_exit 0 "-q renders"
check "-q prints no 'Saved:' lines" sh -c "! grep -q '^Saved:' '$T/stdout'"
check "-q keeps the closing line" grep -q '^2 frames (0-1) in ' "$T/stdout"

# On a terminal: no Saved lines (stdout is one) and the bar fits COLUMNS.
if command -v script >/dev/null; then
    COLUMNS=50 script -qc "'$RB' render jobs/demo.yaml --size 32x18 --integrator direct \
        --frames 0-3 --out '$T/tty'" /dev/null >"$T/tty.log" 2>&1
    tr '\r' '\n' <"$T/tty.log" >"$T/tty.lines"
    check "the bar shows on a terminal" grep -q '4/4 frames' "$T/tty.lines"
    # (The closing line, on stdout, is a result and is not cut.)
    check "no state of the bar is wider than COLUMNS - 1" \
        sh -c "! grep -v ' in $T/tty/: ' '$T/tty.lines' | awk 'length > 49' | grep -q ."
    check "a terminal gets no 'Saved:' lines" sh -c "! grep -q '^Saved:' '$T/tty.lines'"
else
    skip "the bar fits the terminal" "no script(1) to make a terminal"
fi

done_testing
