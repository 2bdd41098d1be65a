#!/bin/sh
# The bdpt integrator's figures (make bench runs this after tests/bench.sh's own; a measurement,
# never a test). Speeds are ratios measured in this run, never asserted.
#  1. Per-pass GPU ms and frame time with 21 VPLs + 21 bundles at 640x360 on the demo, the
#     Cornell box and the largest scene (by triangles) in $RB_SCENES, beside the direct
#     integrator's frame over the same frames (goal: bdpt <= 2.5x direct on the demo).
#  2. bdpt's error there (frame 0) against the reference in bdpt's path space (paths=bdpt:
#     direct light and up to two indirect bounces) at 64 spp, whose own noise is in the figure.
#  3. Error against time on the Cornell box at 128x128: bdpt with K = 21, 64 and 256 VPLs and
#     bundles beside the reference at 4 to 256 spp, all against the reference at 4096 spp; the
#     reference's relMSE-against-time power law, fitted, gives the time it needs for each bdpt
#     error (goal: >= 20x bdpt's), and bdpt's error floor (its bias) is said when K finds one.
#  4. Quality at the budget (the defaults: 21 VPLs + 21 bundles, 4 caches): the demo at 320x180,
#     every frame from 3 to 23 against the reference at 512 spp (goal: each <= 0.03), and the
#     still Cornell box at 128x128 once its caches are full against the truth of 3., with the 4x4
#     grid the interleaved sub-images leave (tests/tools/pattern; goal: <= 0.5% of the local
#     brightness) and the error with each source turned off or up.
# Sizes are small so that make bench takes about 11 minutes on two shared cores.
#
#   BUILD=build sh tests/bench-bdpt.sh
#
# RB_SCENES: the shared scenes (default ../shared/scenes). RB_BENCH_DEVICE: the Vulkan device
# of the bdpt and direct frames (render --device; default lavapipe); on any other device the
# frame times are taken at 1920x1080 too. RB_BENCH_QUICK=1: tiny sizes, few frames, samples and
# VPLs, so that a test can check that every line is printed; its figures mean nothing.
set -eu
BUILD=${BUILD:-build}
SCENES=${RB_SCENES:-../shared/scenes}
. tests/bench-lib.sh
out=$(mktemp -d "${TMPDIR:-/tmp}/raybundle-bench-bdpt.XXXXXX")
trap 'rm -rf "$out"' EXIT
start=$(date +%s)
load=$(cut -d' ' -f1 /proc/loadavg)

if [ "${RB_BENCH_QUICK:-0}" = 1 ]; then
    k=2 size=32x18 frames=1 budget_spp=4 curve_size=16x16 truth_spp=16 curve_spp="1 4" ks="1 2"
    quality_size=32x18 quality_frames="3 4" quality_spp=4
else
    k=21 # VPLs and bundles of the frame-time budget
    size=640x360 frames=5 budget_spp=64 curve_size=128x128 truth_spp=4096 curve_spp="4 16 64 256"
    ks="21 64 256"
    quality_size=320x180 quality_frames=$(seq 3 23) quality_spp=512
fi
last=$((frames - 1))

# reference JOB DIR OPTION...: the reference in bdpt's path space into DIR.
reference() {
    reference_job=$1 reference_dir=$2
    shift 2
    "$BUILD/raybundle" reference "$reference_job" --set integrator.reference.paths=bdpt \
        --out "$reference_dir" -q "$@" </dev/null >/dev/null
}

# The Cornell box as the classic view frames it, lit by its emissive quad alone.
cornell="$SCENES/cornell-box/CornellBox.glb"
has_cornell=false
if [ -f "$cornell" ]; then
    has_cornell=true
    classic_cornell "$out/cornell.yaml" "$cornell" "$curve_size" 9 <<EOT
default_light: off
integrator: {name: bdpt}
EOT
fi

# The largest scene in $SCENES by triangles drawn, as a quick look (a camera fitted to its
# bounds, its lights or the default light).
largest=$(find -L "$SCENES" -name '*.glb' -o -name '*.gltf' 2>/dev/null | sort |
    xargs -r "$BUILD/tests/tools/triangles" | sort -k1,1nr -k2 | head -n 1)

echo "bdpt bench: $k VPLs + $k bundles at $size, medians over frames 0-$last; error against" \
    "time on the Cornell box at $curve_size (sizes kept small: make bench takes about 11" \
    "minutes on two shared cores)"
if [ -n "$largest" ]; then
    echo "largest scene in $SCENES: ${largest#* "$SCENES"/} (${largest%% *} triangles)"
else
    echo "largest scene: skipped, no glTF in $SCENES (set RB_SCENES)"
fi
$has_cornell || echo "cornell-box: skipped, no $cornell (set RB_SCENES)"

# frame_times NAME JOB SIZE: bdpt over frames 0-$last between two runs of direct over the same
# frames (the machine's load drifts; the direct median is over both); per-pass medians of bdpt,
# both integrators' frame wall and GPU medians, and their ratio. direct renders without its
# emitter samples (integrator.direct.emitter_lights 0), punctual lights only, the frame the
# 2.5x goal was set against: eight shadowed samples of the demo's panel make a direct frame
# three times as long, which would flatter the ratio without bdpt getting any cheaper.
frame_times() {
    times_dir="$out/$1-$3"
    for run in direct bdpt direct-after; do
        render "$2" "$times_dir/$run" --integrator "${run%-after}" --size "$3" --frames "0-$last" \
            --set integrator.bdpt.vpls=$k --set integrator.bdpt.bundles=$k \
            --set integrator.direct.emitter_lights=0
    done
    pass_medians "bdpt $1 $3 " "$times_dir"/bdpt/frame.*.timing.json
    awk -v name="$1" -v size="$3" -v bw="$(field wall_ms "$times_dir"/bdpt/*.timing.json | median)" \
        -v bg="$(field gpu_total_ms "$times_dir"/bdpt/*.timing.json | median)" \
        -v dw="$(field wall_ms "$times_dir"/direct*/*.timing.json | median)" \
        -v dg="$(field gpu_total_ms "$times_dir"/direct*/*.timing.json | median)" 'BEGIN {
        printf "bdpt %s %s frame: wall %.1f ms, GPU passes %.1f ms; direct frame (no emitter samples): wall %.1f ms, GPU passes %.1f ms\n",
            name, size, bw, bg, dw, dg
        printf "bdpt %s %s bdpt / direct: %.2f wall, %.2f GPU passes%s\n", name, size, bw / dw,
            bg / dg, (name == "demo" ? " (goal: <= 2.5)" : "") }'
}

# The benched scenes, a line each: NAME JOB.
{
    echo "demo jobs/demo.yaml"
    if $has_cornell; then echo "cornell-box $out/cornell.yaml"; fi
    [ -z "$largest" ] || echo "$(basename "${largest#* }" | sed 's/\.[^.]*$//') ${largest#* }"
} >"$out/scenes"

while read -r name job; do
    frame_times "$name" "$job" "$size"
done <"$out/scenes"
device=$(sed -n 's/.*"device": "\([^"]*\)".*/\1/p' "$out/demo-$size/bdpt/frame.0000.timing.json")
type=$("$BUILD/raybundle" info </dev/null |
    awk -v d="$device" '/^\[[0-9]+\] / && index($0, "] " d) { f = 1; next } f && /type:/ { print $2; exit }')
echo "bdpt device: $device (${type:-type unknown})"
if [ "$type" = CPU ]; then
    echo "bdpt at 1920x1080: skipped, the device is a CPU (RB_BENCH_DEVICE picks another)"
else
    while read -r name job; do frame_times "$name" "$job" 1920x1080; done <"$out/scenes"
fi

# ---- 2. error at the budget ----------------------------------------------------------------

echo "bdpt error at the budget ($k VPLs + $k bundles, $size, frame 0) against the reference" \
    "in bdpt's path space at $budget_spp spp (the reference's own noise is part of each figure):"
while read -r name job; do
    dir="$out/$name-$size"
    reference "$job" "$dir/reference" --size "$size" --frames 0 --spp "$budget_spp"
    awk -v name="$name" -v e="$(relmse "$dir/bdpt/frame.0000.exr" "$dir/reference/frame.0000.exr")" \
        -v ei="$(relmse "$dir/bdpt/frame.0000.exr" "$dir/reference/frame.0000.exr" indirect)" \
        -v ms="$(field cpu_ms "$dir/reference/frame.0000.timing.json")" \
        -v bw="$(field wall_ms "$dir"/bdpt/*.timing.json | median)" \
        -v spp="$budget_spp" -v size="$size" 'BEGIN {
        printf "bdpt %s %s relMSE %.3e (indirect layer %.3e) in %.2f s; reference %d spp in %.1f s\n",
            name, size, e, ei, bw / 1000, spp, ms / 1000 }'
done <"$out/scenes"

# ---- 3. error against time on the Cornell box ----------------------------------------------

if $has_cornell; then
    # The truth is frame 9, whose random numbers are independent of frames 0 and 1's.
    reference "$out/cornell.yaml" "$out/truth" --frames 9 --spp "$truth_spp"
    truth="$out/truth/frame.0009.exr"
    truth_ms=$(field cpu_ms "$out/truth/frame.0009.timing.json")
    echo "bdpt error against time, cornell-box $curve_size: truth = the reference in bdpt's" \
        "path space at $truth_spp spp ($(awk -v ms="$truth_ms" 'BEGIN { printf "%.0f", ms / 1000 }') s);" \
        "time = the reference's trace (cpu_ms, all cores), bdpt's frame wall_ms (median of" \
        "frames 0-$last); relMSE of the reference: mean of frames 0-1, of bdpt: frame 0"
    for spp in $curve_spp; do
        reference "$out/cornell.yaml" "$out/ref$spp" --frames 0-1 --spp "$spp"
        for f in 0000 0001; do
            echo "$(relmse "$out/ref$spp/frame.$f.exr" "$truth") $(field cpu_ms "$out/ref$spp/frame.$f.timing.json")"
        done | awk -v spp="$spp" '{ e += $1; ms += $2 } END { print spp, e / NR, ms / NR / 1000 }'
    done >"$out/reference.txt"
    for kk in $ks; do
        render "$out/cornell.yaml" "$out/bdpt$kk" --frames "0-$last" \
            --set integrator.bdpt.vpls="$kk" --set integrator.bdpt.bundles="$kk"
        echo "$kk $(relmse "$out/bdpt$kk/frame.0000.exr" "$truth")" \
            "$(field wall_ms "$out/bdpt$kk"/*.timing.json | median)" \
            "$(relmse "$out/bdpt$kk/frame.$(printf %04d "$last").exr" "$truth")"
    done >"$out/bdpt.txt"
    # A power law fitted to the reference's points in log-log space (relMSE ~ 1/time for plain
    # Monte Carlo) gives the time it needs for each bdpt relMSE: interpolated within its points,
    # extrapolated (said) outside them. Without bias bdpt's relMSE would fall as 1/K; when the
    # last step of K falls it by less than the square root of that, its bias dominates.
    awk -v truth_s="$(awk -v ms="$truth_ms" 'BEGIN { print ms / 1000 }')" -v last="$last" '
        FNR == NR { spp[++n] = $1; e[n] = $2; t[n] = $3; next }
        { kk[++m] = $1; be[m] = $2; bt[m] = $3 / 1000; bl[m] = $4 }
        END {
            for (i = 1; i <= n; i++) {
                printf "  reference %5d spp: relMSE %.3e in %.3f s\n", spp[i], e[i], t[i]
                x = log(t[i]); y = log(e[i]); sx += x; sy += y; sxx += x * x; sxy += x * y
                if (i == 1 || e[i] < emin) emin = e[i]
                if (i == 1 || e[i] > emax) emax = e[i]
            }
            d = n * sxx - sx * sx; s = d > 0 ? (n * sxy - sx * sy) / d : 0; c = (sy - s * sx) / n
            printf "  reference fit: relMSE = %.3e * (time / 1 s)^%.2f (plain Monte Carlo: ^-1); at the truth'"'"'s %.0f s: %.1e\n",
                exp(c), s, truth_s, exp(c + s * log(truth_s))
            for (j = 1; j <= m; j++) {
                printf "  bdpt K=%d: relMSE %.3e in %.3f s", kk[j], be[j], bt[j]
                if (bl[j] != be[j])
                    printf " (frame %d, every temporal cache written: relMSE %.3e)", last, bl[j]
                if (s < -0.1 && be[j] > 0) {
                    tr = exp((log(be[j]) - c) / s)
                    printf "; the reference needs %.3f s%s: %.1fx bdpt'"'"'s time (goal: >= 20x)\n", tr,
                        (be[j] < emin || be[j] > emax ? " (extrapolated)" : ""), tr / bt[j]
                } else
                    printf "; the reference'"'"'s error does not fall with time: no ratio\n"
            }
            if (m > 1) {
                f = be[m] / be[m - 1]; g = kk[m - 1] / kk[m]
                printf "  bdpt relMSE from K=%d to K=%d: x%.2f (1/K: x%.2f): ", kk[m - 1], kk[m], f, g
                if (f > sqrt(g))
                    printf "slower than 1/sqrt(K), its bias dominates (in this path space: 8-bit materials, the filter, shadow-map and bundle resolution): bdpt levels off near %.2e, and the ratios above are at bdpt'"'"'s own errors\n", be[m]
                else
                    printf "still falling, no floor in sight at K=%d\n", kk[m]
            }
        }' "$out/reference.txt" "$out/bdpt.txt"
fi

# ---- 4. quality at the budget --------------------------------------------------------------

first=$(echo $quality_frames | cut -d' ' -f1)
final=$(echo $quality_frames | tr ' ' '\n' | tail -n 1)
render jobs/demo.yaml "$out/quality" --integrator bdpt --size "$quality_size" --frames "0-$final"
list=$(echo $quality_frames | tr ' ' ',')
reference jobs/demo.yaml "$out/quality-ref" --size "$quality_size" --frames "$list" \
    --spp "$quality_spp"
echo "bdpt quality, demo $quality_size at the defaults, frames $first-$final against the reference" \
    "at $quality_spp spp (goal: each <= 0.03):"
for f in $quality_frames; do
    name=$(printf 'frame.%04d.exr' "$f")
    echo "$f $(relmse "$out/quality/$name" "$out/quality-ref/$name")" \
        "$(relmse "$out/quality/$name" "$out/quality-ref/$name" indirect)"
done | awk '{ printf "  demo frame %d: relMSE %.4f (indirect layer %.4f)\n", $1, $2, $3
              if ($2 > worst) { worst = $2; at = $1 } }
            END { printf "  demo worst frame: %d, relMSE %.4f\n", at, worst }'
if $has_cornell; then
    # The Cornell box's still frame once every cache is written, against the truth of 3.
    # ($truth, frame 9 of the same job), and with each source of error turned off or up.
    cornell_last=9
    echo "bdpt quality, cornell-box $curve_size, frame $cornell_last (every cache full), against" \
        "the truth of 3.:"
    while read -r label options; do
        # shellcheck disable=SC2086
        render "$out/cornell.yaml" "$out/q-$label" --frames "0-$cornell_last" $options
        image="$out/q-$label/frame.000$cornell_last.exr"
        # (an image too small to hold a surface's interior has no grid figure)
        grid=$("$BUILD/tests/tools/pattern" "$image" "" 4 2>/dev/null | sed -n 's/^pattern //p')
        grid=$(awk -v p="$grid" 'BEGIN { if (p == "") print "none"; else printf "%.2f%%", 100 * p }')
        printf '  %-20s relMSE %.4f (direct %.4f, indirect %.4f); 4x4 grid %s\n' "$label" \
            "$(relmse "$image" "$truth")" "$(relmse "$image" "$truth" direct)" \
            "$(relmse "$image" "$truth" indirect)" "$grid"
    done <<EOT
defaults
x4-VPLs-and-bundles --set integrator.bdpt.vpls=84 --set integrator.bdpt.bundles=84
no-interleave --set integrator.bdpt.interleave=1
no-filter --set integrator.bdpt.filter_radius=0
bundle-grid-1024 --set integrator.bdpt.bundle_size=1024
vpl-maps-1024 --set integrator.bdpt.vpl_size=1024
EOT
fi

awk -v s="$start" -v e="$(date +%s)" -v l0="$load" -v l1="$(cut -d' ' -f1 /proc/loadavg)" \
    -v cpus="$(nproc)" 'BEGIN { printf "bdpt bench took %.1f min; load average %s at the start, %s at the end, on %d cores\n",
        (e - s) / 60, l0, l1, cpus }'
