#!/bin/sh
# The hybrid integrator's figures (make bench runs this after tests/bench-temporal.sh; a
# measurement, never a test). Speeds are ratios measured in this run, never asserted.
#  1. Per-pass GPU ms at 640x360 on the demo and every scene in $RB_SCENES (the Cornell box in
#     its classic view, the rest with a camera fitted to their bounds), medians over frames 0-4,
#     as a table of passes by scene and as the seed's table (its rows, our passes summed under
#     each, beside the seed's own figures at 1920x1080 on a GTX 1080).
#  2. Rays a frame and BVH rays per second there: rays traced through the BVH (bvh_hits +
#     misses, which is queued - dropped) over the bvh_rays pass's GPU ms, median over frames.
#  3. The frame's wall and GPU time beside the direct and bdpt integrators' over the same frames
#     of the same run, and their ratios.
#  4. Error on the still demo (t0450's: animation stopped, camera still) at 160x90: relMSE of
#     the indirect layer and of the beauty after 1, 8 and 64 frames (frames 0, 7, 63) against
#     the reference with one bounce (max_bounces=1) at 4096 spp, with the default rays (1 a lobe,
#     64 samples a pixel) and with 4 rays a lobe (256), feedback off; the reference's own noise
#     is said.
#  5. Error on the still Cornell box at 160x90 with the defaults: relMSE of the beauty, direct
#     and indirect layers after 1, 8, 32 and 128 frames against the reference's default path
#     space at 4096 spp, and the rays requested every 8th frame over the shot.
#  6. The moving demo's (jobs/demo-hybrid.yaml) frame wall time over its GPU passes' sum,
#     medians over frames 4-11: what the BVH's thread leaves on the frame's critical path.
# Sizes are small so that this takes about 4 minutes on two shared cores.
#
#   BUILD=build sh tests/bench-hybrid.sh
#
# RB_SCENES: the shared scenes (default ../shared/scenes). RB_BENCH_DEVICE: the Vulkan device
# of the rendered frames (render --device; default lavapipe); on any other device the frame
# times are taken at 1920x1080 too. RB_BENCH_QUICK=1: tiny sizes, few frames and samples, so
# that a test can check that every line is printed; its figures mean nothing.
set -eu
BUILD=${BUILD:-build}
SCENES=${RB_SCENES:-../shared/scenes}
. tests/bench-lib.sh
out=$(mktemp -d "${TMPDIR:-/tmp}/raybundle-bench-hybrid.XXXXXX")
trap 'rm -rf "$out"' EXIT
start=$(date +%s)
load=$(cut -d' ' -f1 /proc/loadavg)

if [ "${RB_BENCH_QUICK:-0}" = 1 ]; then
    size=32x18 frames=1 still_size=32x18 truth_spp=16
else
    size=640x360 frames=5 still_size=160x90 truth_spp=4096
fi
last=$((frames - 1))

# counts SIDECAR: "requested screen_hits queued bvh_hits misses dropped bvh_rays_gpu_ms" of a
# hybrid frame's timing sidecar.
counts() {
    sed -n 's/.*"ray_counts": {"requested": \([0-9]*\), "screen_hits": \([0-9]*\), "queued": \([0-9]*\), "bvh_hits": \([0-9]*\), "misses": \([0-9]*\), "dropped": \([0-9]*\)}.*/\1 \2 \3 \4 \5 \6/p' "$1" |
        tr '\n' ' '
    sed -n 's/.*"name": "bvh_rays", "gpu_ms": \([0-9.eE+-]*\).*/\1/p' "$1"
}

# The Cornell box as the classic view frames it, lit by its emissive quad alone (as
# tests/bench-bdpt.sh has it).
cornell="$SCENES/cornell-box/CornellBox.glb"
if [ -f "$cornell" ]; then
    classic_cornell "$out/cornell.yaml" "$cornell" 640x360 9 <<EOT
default_light: off
integrator: {name: hybrid}
EOT
fi

# The benched scenes, a line each: NAME JOB; a shared scene is named after its folder.
{
    echo "demo jobs/demo.yaml"
    find -L "$SCENES" -name '*.glb' -o -name '*.gltf' 2>/dev/null | sort | while read -r f; do
        name=$(basename "$(dirname "$f")")
        if [ "$f" = "$cornell" ]; then f="$out/cornell.yaml"; fi
        echo "$name $f"
    done
} >"$out/scenes"
count=$(wc -l <"$out/scenes")

echo "hybrid bench: the hybrid integrator (defaults) at $size, medians over frames 0-$last," \
    "beside direct and bdpt over the same frames; error after 1, 8 and 64 frames on the still" \
    "demo at $still_size (sizes kept small: about 4 minutes on two shared cores)"
[ "$count" -gt 1 ] || echo "hybrid shared scenes: skipped, no glTF in $SCENES (set RB_SCENES)"

# frame_times SIZE: direct, bdpt and hybrid over frames 0-$last of every scene at SIZE; the
# per-pass table, the seed's table, rays and BVH rays per second, and the frame times.
frame_times() {
    i=0
    while read -r name job; do
        i=$((i + 1))
        dir="$out/$1/$name"
        for integrator in direct bdpt hybrid; do
            # (direct without its emitter samples, punctual lights only: see bench-bdpt.sh)
            render "$job" "$dir/$integrator" --integrator "$integrator" --size "$1" \
                --frames "0-$last" --set integrator.direct.emitter_lights=0
        done
        pass_medians "" "$dir"/hybrid/frame.*.timing.json | awk -v i="$i" '{ print i, $2, $4 }'
        for integrator in hybrid direct bdpt; do
            echo "$i total_$integrator $(field gpu_total_ms "$dir/$integrator"/*.timing.json | median)"
            echo "$i wall_$integrator $(field wall_ms "$dir/$integrator"/*.timing.json | median)"
        done
    done <"$out/scenes" >"$out/$1.medians"

    # Passes by scene: the scenes' numbers head the columns (a long name would not fit).
    echo "hybrid per-pass GPU ms at $1, medians over frames 0-$last; scenes:" \
        "$(awk '{ printf "%s[%d] %s", (NR > 1 ? ", " : ""), NR, $1 }' "$out/scenes")"
    awk -v n="$count" '{ if (!($2 in seen)) { seen[$2] = 1; order[++k] = $2 } v[$1, $2] = $3 }
        END {
            printf "  %-16s", "pass"
            for (s = 1; s <= n; s++) printf " %8s", "[" s "]"
            printf "\n"
            for (r = 1; r <= k; r++) {
                p = order[r]
                if (p ~ /^(total|wall)_/ && p != "total_hybrid" && p != "wall_hybrid") continue
                printf "  %-16s", (p == "total_hybrid" ? "GPU total" : p == "wall_hybrid" ? "frame wall" : p)
                for (s = 1; s <= n; s++)
                    printf " %8s", ((s, p) in v) ? sprintf("%.2f", v[s, p]) : "-"
                printf "\n"
            }
        }' "$out/$1.medians"

    # The seed's table (seed 003, "Average Timings @1080p on GTX1080"): its rows with our passes
    # summed under each; the passes that serve both lobes and the accumulation have no row of
    # their own there, and a pass this table does not know is summed under "other".
    echo "hybrid as the seed's table at $1 (GPU ms; the seed's own figures: 1920x1080 on a" \
        "GTX 1080, its own scene; the rows add up to the GPU total):"
    awk -v n="$count" 'BEGIN {
            rows = 11
            split("GBuffer|Direct Light|Transparency|Diffuse Rays|Specular Rays|" \
                  "Tracing, both lobes|Accumulation|Diffuse Filtering|Specular Filtering|" \
                  "Post Processing|other", label, "|")
            split("animate gbuffer|shadow direct|transparency|diffuse_rays|specular_rays|" \
                  "hiz ray_queue bvh_rays light_rays|accumulate tiles|diffuse_filter|specular_filter|" \
                  "output|", passes, "|")
            split("0.7|0.6|1.8|1.4|1.6|-|-|2.5|0.3|1.6|-", seed, "|")
            for (r = 1; r <= rows; r++) {
                m = split(passes[r], p, " ")
                for (j = 1; j <= m; j++) row_of[p[j]] = r
            }
        }
        $2 ~ /^(total|wall)_/ { if ($2 == "total_hybrid") total[$1] = $3; next }
        { r = ($2 in row_of) ? row_of[$2] : rows; v[$1, r] += $3; has[$1, r] = 1
          if (r == rows && !(($2) in other)) { other[$2] = 1; others = others " " $2 } }
        END {
            passes[rows] = substr(others, 2)
            printf "  %-44s %6s", "row (passes)", "seed"
            for (s = 1; s <= n; s++) printf " %8s", "[" s "]"
            printf "\n"
            for (r = 1; r <= rows; r++) {
                if (r == rows && others == "") continue
                names = passes[r]
                gsub(/ /, "+", names)
                printf "  %-44s %6s", label[r] " (" names ")", seed[r]
                for (s = 1; s <= n; s++)
                    printf " %8s", has[s, r] ? sprintf("%.2f", v[s, r]) : "-"
                printf "\n"
            }
            printf "  %-44s %6s", "Total", "10.5"
            for (s = 1; s <= n; s++) printf " %8.2f", total[s]
            printf "\n"
        }' "$out/$1.medians"

    # Rays and BVH rays per second, and the frame times beside direct's and bdpt's.
    i=0
    while read -r name job; do
        i=$((i + 1))
        dir="$out/$1/$name"
        for f in "$dir"/hybrid/frame.*.timing.json; do counts "$f"; done | awk '
            { for (j = 1; j <= 6; j++) c[j, NR] = $j
              r[NR] = $7 > 0 ? ($4 + $5) / ($7 / 1000) : -1 }
            function med(a, col,   t, j, k, x) {
                for (j = 1; j <= NR; j++) t[j] = (col ? c[col, j] : a[j])
                for (j = 2; j <= NR; j++) { x = t[j]; k = j - 1
                    while (k >= 1 && t[k] > x) { t[k + 1] = t[k]; k-- } t[k + 1] = x }
                return (NR % 2) ? t[(NR + 1) / 2] : (t[NR / 2] + t[NR / 2 + 1]) / 2 }
            END { print med(r, 0); for (j = 1; j <= 6; j++) print med(r, j) }' >"$out/rays"
        awk -v name="$name" -v size="$1" '{ v[NR] = $1 } END {
            printf "hybrid %s %s rays a frame (medians): requested %d, screen hits %d, queued %d (BVH hits %d, misses %d, dropped %d); ",
                name, size, v[2], v[3], v[4], v[5], v[6], v[7]
            if (v[1] < 0) printf "BVH rays per second: none traced\n"
            else printf "BVH rays per second %.2f M (BVH hits + misses over the bvh_rays pass'"'"'s GPU ms)\n", v[1] / 1e6 }' "$out/rays"
        awk -v name="$name" -v size="$1" -v i="$i" '$1 == i { v[$2] = $3 } END {
            printf "hybrid %s %s frame: wall %.1f ms, GPU passes %.1f ms; direct frame: wall %.1f ms, GPU passes %.1f ms; bdpt frame: wall %.1f ms, GPU passes %.1f ms\n",
                name, size, v["wall_hybrid"], v["total_hybrid"], v["wall_direct"], v["total_direct"], v["wall_bdpt"], v["total_bdpt"]
            printf "hybrid %s %s hybrid / direct: %.2f wall, %.2f GPU passes; hybrid / bdpt: %.2f wall, %.2f GPU passes\n",
                name, size, v["wall_hybrid"] / v["wall_direct"], v["total_hybrid"] / v["total_direct"],
                v["wall_hybrid"] / v["wall_bdpt"], v["total_hybrid"] / v["total_bdpt"] }' "$out/$1.medians"
    done <"$out/scenes"
}

frame_times "$size"
device=$(sed -n 's/.*"device": "\([^"]*\)".*/\1/p' "$out/$size/demo/hybrid/frame.0000.timing.json")
type=$("$BUILD/raybundle" info </dev/null |
    awk -v d="$device" '/^\[[0-9]+\] / && index($0, "] " d) { f = 1; next } f && /type:/ { print $2; exit }')
echo "hybrid device: $device (${type:-type unknown})"
if [ "$type" = CPU ]; then
    echo "hybrid at 1920x1080: skipped, the device is a CPU (RB_BENCH_DEVICE picks another)"
else
    frame_times 1920x1080
fi

# ---- error after 1, 8 and 64 frames -------------------------------------------------------

# The demo room, its animation stopped and its camera still (tests/integration/t0450-hybrid.sh).
still_demo "$out/still.yaml" "$still_size" 63 "[direct, indirect]" \
    "{name: hybrid, hybrid: {history: 64, feedback: false}}"
# The truth is frame 63 of the reference; frame 62, with independent random numbers, says its
# own noise: the relMSE between the two is about twice either's.
"$BUILD/raybundle" reference "$out/still.yaml" --frames 62-63 --spp "$truth_spp" \
    --set integrator.reference.max_bounces=1 --out "$out/truth" -q </dev/null >/dev/null
truth="$out/truth/frame.0063.exr"
echo "hybrid error on the still demo at $still_size (history 64: an accumulator spans the 64" \
    "frames; feedback off: hits lit by direct light) against the reference with one bounce" \
    "(max_bounces=1) at $truth_spp spp ($(field cpu_ms "$out/truth/frame.0063.timing.json" |
        awk '{ printf "%.0f", $1 / 1000 }') s a frame; its own noise, half the relMSE" \
    "between two of its frames: indirect $(relmse "$out/truth/frame.0062.exr" "$truth" indirect |
        awk '{ printf "%.2e", $1 / 2 }'), beauty $(relmse "$out/truth/frame.0062.exr" "$truth" |
        awk '{ printf "%.2e", $1 / 2 }')):"
for run in default:1:64 4-rays:4:256; do
    label=${run%%:*} rays=${run#*:}
    spp=${rays#*:} rays=${rays%:*}
    render "$out/still.yaml" "$out/still-$label" --frames 0-63 \
        --set integrator.hybrid.rays="$rays" --set integrator.hybrid.spp="$spp"
    wall=$(field wall_ms "$out/still-$label"/frame.*.timing.json | median)
    for f in 0 7 63; do
        frame="$out/still-$label/frame.$(printf %04d $f).exr"
        echo "$((f + 1)) $(relmse "$frame" "$truth" indirect) $(relmse "$frame" "$truth")" \
            "$(counts "${frame%.exr}.timing.json" | cut -d' ' -f1)"
    done | awk -v rays="$rays" -v spp="$spp" -v w="$wall" '{
        printf "  %d ray%s a lobe and frame (spp %d), after %2d frame%s: relMSE indirect %.3e, beauty %.3e; rays requested %d\n",
            rays, (rays > 1 ? "s" : ""), spp, $1, ($1 > 1 ? "s" : " "), $2, $3, $4 }
        END { printf "  %d ray%s a lobe: frame wall median %.1f ms\n", rays, (rays > 1 ? "s" : ""), w }'
done

# ---- the still Cornell box, defaults, against the reference's default path space -----------

if [ -f "$cornell" ]; then
    sed -e "s/resolution: \[640, 360\]/resolution: [${still_size%x*}, ${still_size#*x}]/" \
        -e 's/end: 9,/end: 127,/' -e 's/^integrator: .*/layers: [direct, indirect]\nintegrator: {name: hybrid}/' \
        "$out/cornell.yaml" >"$out/box.yaml"
    box_last=127
    [ "${RB_BENCH_QUICK:-0}" = 1 ] && box_last=7
    "$BUILD/raybundle" reference "$out/box.yaml" --frames 0 --spp "$truth_spp" --out "$out/btruth" \
        -q </dev/null >/dev/null
    render "$out/box.yaml" "$out/box" --frames 0-$box_last
    echo "hybrid error on the still Cornell box at $still_size (defaults) against the reference" \
        "(default path space) at $truth_spp spp:"
    for f in 1 8 32 128; do
        [ $((f - 1)) -le $box_last ] || continue
        frame="$out/box/frame.$(printf %04d $((f - 1))).exr"
        echo "$f $(relmse "$frame" "$out/btruth/frame.0000.exr") $(relmse "$frame" \
            "$out/btruth/frame.0000.exr" direct) $(relmse "$frame" "$out/btruth/frame.0000.exr" \
            indirect) $(counts "${frame%.exr}.timing.json" | cut -d' ' -f1)"
    done | awk '{ printf "  after %3d frame%s: relMSE beauty %.3e, direct %.3e, indirect %.3e; rays requested %d\n",
        $1, ($1 > 1 ? "s" : " "), $2, $3, $4, $5 }'
    printf "hybrid rays requested a frame over the still Cornell box (frame:rays):"
    f=0
    while [ $f -le $box_last ]; do
        printf " %d:%s" $f "$(counts "$out/box/frame.$(printf %04d $f).timing.json" | cut -d' ' -f1)"
        f=$((f + 8))
    done
    echo
else
    echo "hybrid still Cornell box: skipped, no cornell-box/CornellBox.glb in $SCENES"
fi

# ---- wall against GPU on the moving demo --------------------------------------------------

# jobs/demo-hybrid.yaml as it is: camera and animation moving, so a BVH is built and baked every
# frame, on the BVH's thread while the frames before it render. The frame's wall time over the
# sum of its GPU passes, medians over frames 4-11 (frames 0-3 build the first BVH and compile the
# shaders). On a CPU device (lavapipe) the thread and the "GPU" share the cores, so its work
# shows in the GPU passes' times too.
if [ "${RB_BENCH_QUICK:-0}" = 1 ]; then
    m_size=32x18 m_first=1 m_last=2
else
    m_size=640x360 m_first=4 m_last=11
fi
render jobs/demo-hybrid.yaml "$out/moving" --size "$m_size" --frames "0-$m_last"
m_frames=$(seq "$m_first" "$m_last" | while read -r f; do printf '%s ' "$out/moving/frame.$(printf %04d "$f").timing.json"; done)
# shellcheck disable=SC2086 # the sidecars' paths, without spaces
m_wall=$(field wall_ms $m_frames | median) m_gpu=$(field gpu_total_ms $m_frames | median)
awk -v w="$m_wall" -v g="$m_gpu" -v size="$m_size" -v a="$m_first" -v b="$m_last" 'BEGIN {
    printf "hybrid moving demo (jobs/demo-hybrid.yaml) at %s, medians over frames %d-%d: frame wall %.1f ms, GPU passes %.1f ms, wall / GPU %.2f\n",
        size, a, b, w, g, w / g }'

awk -v s="$start" -v e="$(date +%s)" -v l0="$load" -v l1="$(cut -d' ' -f1 /proc/loadavg)" \
    -v cpus="$(nproc)" 'BEGIN { printf "hybrid bench took %.1f min; load average %s at the start, %s at the end, on %d cores\n",
        (e - s) / 60, l0, l1, cpus }'
