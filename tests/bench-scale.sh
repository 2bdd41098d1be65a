#!/bin/sh
# Scale figures (make bench runs this last; a measurement, never a test): a generated terrain of
# 1 M triangles (tests/tools/triangles write, with normals) rendered once by each integrator,
# one frame at the job's 64x48, and each run's whole wall time (loading, building, the frame,
# writing), the frame's own wall time (its timing sidecar) and the process's peak resident
# memory (/usr/bin/time's maximum resident set). The GPU's memory is the process's on a CPU
# device. hybrid runs with integrator.hybrid.history=2: a frame pre-rolls W frames (128 by
# default), and this is one frame's cost; the reference takes 4 samples a pixel.
#
#   BUILD=build sh tests/bench-scale.sh
#
# Then the same at 10 M triangles (about 70 s, and 3.2 GiB at most, on two cores); RB_BENCH_10M=0
# leaves it out.
# RB_BENCH_QUICK=1: 10,000 triangles (100,000 for the 10 M row), so that a test can check that
# every line is printed; its figures mean nothing.
set -eu
BUILD=${BUILD:-build}
out=$(mktemp -d "${TMPDIR:-/tmp}/raybundle-bench-scale.XXXXXX")
trap 'rm -rf "$out"' EXIT

if [ "${RB_BENCH_QUICK:-0}" = 1 ]; then
    sizes="1M:10000"
    [ "${RB_BENCH_10M:-1}" = 0 ] || sizes="$sizes 10M:100000"
else
    sizes="1M:1000000"
    [ "${RB_BENCH_10M:-1}" = 0 ] || sizes="$sizes 10M:10000000"
fi
[ -x /usr/bin/time ] || {
    echo "scale bench: skipped, no /usr/bin/time (Debian: time) for the peak memory"
    exit 0
}

echo "scale bench: a generated terrain (tests/tools/triangles write, with normals), one frame at" \
    "64x48 a run; hybrid with history 2, the reference at 4 spp"
printf '%-5s %10s %10s %-10s %9s %9s %10s\n' scene triangles vertices integrator "run s" \
    "frame s" "peak MiB"
for size in $sizes; do
    name=${size%%:*} count=${size#*:}
    mkdir -p "$out/$name"
    counts=$("$BUILD/tests/tools/triangles" write "$out/$name" "$count")
    for integrator in direct bdpt hybrid reference; do
        dir="$out/$name/$integrator"
        set -- render "$out/$name/terrain.yaml" --integrator "$integrator" --out "$dir" -q \
            --set integrator.hybrid.history=2
        [ "$integrator" != reference ] || set -- "$@" --spp 4
        start=$(date +%s.%N)
        /usr/bin/time -f '%M' -o "$out/rss" "$BUILD/raybundle" "$@" </dev/null >/dev/null
        end=$(date +%s.%N)
        frame=$(sed -n 's/.*"wall_ms": \([0-9.eE+-]*\).*/\1/p' "$dir/frame.0000.timing.json" |
            head -n 1)
        awk -v n="$name" -v c="$counts" -v i="$integrator" -v s="$start" -v e="$end" \
            -v f="$frame" -v k="$(tail -n 1 "$out/rss")" 'BEGIN { split(c, t, " ");
            printf "%-5s %10d %10d %-10s %9.2f %9.2f %10.0f\n", n, t[1], t[2], i, e - s,
                f / 1000, k / 1024 }'
        rm -rf "$dir"
    done
done
[ "${RB_BENCH_10M:-1}" != 0 ] || echo "10M: skipped (RB_BENCH_10M=0)"
