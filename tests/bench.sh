#!/bin/sh
# Benchmark (not a test): renders the demo at 640x360 for 24 frames and prints each pass's
# median GPU milliseconds, frames per second and peak resident memory; the timing compare of
# the build against itself; the same frames as a Slurm array against one process; then the CPU
# reference's speed, and its error on the Cornell box at 64 to 1024 spp; last, the bdpt
# integrator's figures (tests/bench-bdpt.sh, which says what they are), its temporal caches'
# (tests/bench-temporal.sh) and the hybrid integrator's (tests/bench-hybrid.sh); and the CPU time
# of HDR-FLIP on a 1920x1080 pair, on one core (tests/bench-flip.sh); then each integrator's time
# and peak memory on a generated scene of 1 M triangles, and of 10 M (tests/bench-scale.sh;
# RB_BENCH_10M=0 leaves that out).
set -eu
BUILD=${BUILD:-build}
. tests/bench-lib.sh
out=$(mktemp -d "${TMPDIR:-/tmp}/raybundle-bench.XXXXXX")
trap 'rm -rf "$out"' EXIT
start=$(date +%s.%N)
/usr/bin/time -f '%M' -o "$out/rss" "$BUILD/raybundle" render jobs/demo.yaml --integrator direct \
    --size 640x360 --frames 0-23 --out "$out" -q
end=$(date +%s.%N)
frames=24
echo "raybundle bench: demo, 640x360, $frames frames, direct integrator"
sed -n 's/.*"device": "\([^"]*\)".*/device: \1/p' "$out/frame.0000.timing.json" | head -n 1
sed -n 's/.*"driver": "\([^"]*\)".*/driver: \1/p' "$out/frame.0000.timing.json" | head -n 1
pass_medians "" "$out"/frame.*.timing.json
wall=$(field wall_ms "$out"/frame.*.timing.json | median)
gpu=$(field gpu_total_ms "$out"/frame.*.timing.json | median)
# wall_ms: rendering the frame and handing it to the writer thread, which compresses and writes
# the previous frame meanwhile; the ratio is the frame's cost over its GPU passes (goal <= 1.3).
awk -v w="$wall" -v g="$gpu" 'BEGIN { printf "frame wall median %.1f ms, GPU passes median %.1f ms: wall / GPU %.2f\n", w, g, w / g }'
awk -v s="$start" -v e="$end" -v f="$frames" 'BEGIN { printf "frames per second (whole run, incl. start-up and EXR writes): %.2f\n", f / (e - s) }'
echo "peak resident memory: $(cat "$out/rss") KiB"

# The build against itself: two bench sets of the demo (9 runs each, 160x90, 4 frames),
# compared pass by pass; expect "same" everywhere (a verdict otherwise is the machine's drift
# between the sets, beyond the 5% threshold).
for set in base new; do
    "$BUILD/raybundle" bench jobs/demo.yaml --integrator direct --size 160x90 --frames 0-3 --runs 9 \
        --out "$out/bench-$set" -q >/dev/null
done
echo "timing compare of this build against itself (demo 160x90, 4 frames, 9 runs a set):"
status=0
"$BUILD/raybundle" timing compare "$out/bench-base" "$out/bench-new" || status=$?
echo "timing compare exit status: $status"

# The same frames as a Slurm array of 4 tasks on a one-node cluster (make check-farm's, which
# checks the bits too) against one process: only where Slurm is installed and this is root.
if [ "$(id -u)" = 0 ] && command -v slurmctld >/dev/null && command -v slurmd >/dev/null &&
    command -v sbatch >/dev/null && command -v munged >/dev/null; then
    RB_FARM_SIZE=640x360 RB_FARM_FRAMES=0-23 sh tests/farm/slurm.sh >"$out/farm.tap" 2>&1 &&
        farm=ok || farm="FAILED (make check-farm says why)"
    sed -n 's/^# wall /slurm array wall time: /p' "$out/farm.tap"
    echo "slurm array frames identical to one process's: $farm"
else
    echo "slurm array wall time: skipped (needs root and slurm-wlm: scripts/install-deps.sh --farm)"
fi

# The CPU reference: the demo at 320x180, 64 spp, with 1 and 2 threads.
for threads in 1 2; do
    "$BUILD/raybundle" reference jobs/demo.yaml --size 320x180 --frames 0 --spp 64 \
        --threads "$threads" --out "$out/ref$threads" -q
    json="$out/ref$threads/frame.0000.timing.json"
    rays=$(sed -n 's/.*"rays": \([0-9]*\).*/\1/p' "$json")
    ms=$(sed -n 's/.*"cpu_ms": \([0-9.eE+-]*\).*/\1/p' "$json")
    awk -v r="$rays" -v ms="$ms" -v t="$threads" 'BEGIN {
        printf "reference 320x180 64 spp, %d thread(s): %.2f s/frame, %.2f Mrays/s (%d rays)\n",
               t, ms / 1000, r / (ms / 1000) / 1e6, r }'
done

# The CPU reference's error against its own long render, on the Cornell box from the shared
# scenes: relMSE at 64, 256 and 1024 spp against 16384 spp, each the mean over frames 0-3 (one
# frame's relMSE is dominated by a few fireflies). At 64x64, because the long render takes
# about two minutes on two cores. The long render is frame 4, whose random numbers are
# independent of the others'; its own error (1/16 of the 1024-spp figure's for plain Monte
# Carlo, less for the Sobol sampler) is part of each figure.
SCENES=${RB_SCENES:-../shared/scenes}
cornell="$SCENES/cornell-box/CornellBox.glb"
if [ -f "$cornell" ]; then
    classic_cornell "$out/cornell.yaml" "$cornell" 64x64 4 <<EOT
lights: [{type: point, position: [-278, 10000, 0], intensity: 0}]
integrator: {name: reference, reference: {spp: 64, max_bounces: 8}}
EOT
    truth="$out/truth/frame.0004.exr"
    "$BUILD/raybundle" reference "$out/cornell.yaml" --frames 4 --spp 16384 --out "$out/truth" -q
    ms=$(sed -n 's/.*"cpu_ms": \([0-9.eE+-]*\).*/\1/p' "$out/truth/frame.0004.timing.json")
    awk -v ms="$ms" 'BEGIN { printf "reference cornell-box 64x64 (small: 16384 spp take %.0f s), relMSE against 16384 spp, mean of 4 frames:\n", ms / 1000 }'
    for spp in 64 256 1024; do
        "$BUILD/raybundle" reference "$out/cornell.yaml" --frames 0-3 --spp "$spp" \
            --out "$out/cornell$spp" -q
        for f in 0000 0001 0002 0003; do
            relmse=$("$BUILD/raybundle" compare "$out/cornell$spp/frame.$f.exr" "$truth" |
                sed -n 's/^relmse *//p')
            ms=$(sed -n 's/.*"cpu_ms": \([0-9.eE+-]*\).*/\1/p' "$out/cornell$spp/frame.$f.timing.json")
            echo "$relmse $ms"
        done | awk -v s="$spp" '{ e += $1; ms += $2; v = v sprintf(" %.2e", $1) }
            END { printf "  %5d spp: relMSE %.3e (frames:%s), %.2f s/frame\n", s, e / NR, v, ms / NR / 1000 }'
    done
else
    echo "reference cornell-box relMSE: skipped, no $cornell (set RB_SCENES)"
fi

BUILD=$BUILD sh tests/bench-bdpt.sh
BUILD=$BUILD sh tests/bench-temporal.sh
BUILD=$BUILD sh tests/bench-hybrid.sh
BUILD=$BUILD sh tests/bench-flip.sh
BUILD=$BUILD sh tests/bench-scale.sh
