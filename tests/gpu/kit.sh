#!/bin/bash
# tests/gpu/kit.sh KITDIR [--tarball PATH] [--device NAME|INDEX] [--max-mib N]
#
# Assembles, on this Debian 12 machine, what tests/gpu/gpu-check.sh needs on a GPU machine where
# nothing of ours is installed (see tests/gpu/README.md):
#   KITDIR/raybundle-*-linux-x86_64.tar.xz   the product under test (default: the newest in dist/)
#   KITDIR/layer/                            the Khronos validation layer of Debian's
#                                            vulkan-validationlayers, xz-compressed, and its manifest
#   KITDIR/vulkan/libvulkan.so.1             Debian's Vulkan loader (libvulkan1), for a host without one
#   KITDIR/hostlibs/                         what the NVIDIA driver's Vulkan library needs beside
#                                            the driver (libGLdispatch of libglvnd0, libX11, ...),
#                                            exposed there only if the host lacks them
#   KITDIR/scenes/, KITDIR/jobs/             the demo room, the Cornell box and the blended-material
#                                            scene of tests/tools/blendscene (built in BUILD,
#                                            default build, when it is not there), with their jobs
#   KITDIR/lavapipe/SCENE-INTEGRATOR/        the tarball's own frames on lavapipe (beauty only, at
#                                            the comparison size), the GPU's frames are held to
#   KITDIR/kit.json                          what is in the kit, and the comparison's settings
# The kit must travel (with the repository) within 64 MiB: above --max-mib (default 45) this
# fails. RB_SCENES: the shared scenes (default ../shared/scenes), for cornell-box/.
set -u
here=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$here/../.." && pwd)

usage() {
    sed -n '2,3p' "$0" | sed 's/^# //' >&2
    exit 2
}
die() {
    echo "kit.sh: $*" >&2
    exit 1
}

kit="" tarball="" device=llvmpipe max_mib=45
while [ $# -gt 0 ]; do
    case $1 in
    --tarball) [ $# -ge 2 ] || usage; tarball=$2; shift 2 ;;
    --device) [ $# -ge 2 ] || usage; device=$2; shift 2 ;;
    --max-mib) [ $# -ge 2 ] || usage; max_mib=$2; shift 2 ;;
    -h | --help) usage ;;
    -*) echo "kit.sh: unknown option $1" >&2; usage ;;
    *) [ -z "$kit" ] || usage; kit=$1; shift ;;
    esac
done
[ -n "$kit" ] || usage

# The comparison against lavapipe: gpu-check.sh reads these from kit.json, so both sides render
# the same job, frame and size.
compare_size=640x360
compare_frame=2
compare_scenes="demo cornell blend"
compare_integrators="direct bdpt hybrid"

layer_so=/usr/lib/x86_64-linux-gnu/libVkLayer_khronos_validation.so
layer_json=/usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json
loader_so=/usr/lib/x86_64-linux-gnu/libvulkan.so.1
# The NVIDIA Vulkan driver (libGLX_nvidia.so.0) links libGLdispatch (libglvnd) and, in some
# versions, libX11 and libXext; a bare container image may have none of them. It also opens
# libglvnd's EGL and GLX libraries at run time (no ldd shows that): on an H200 image without
# them, the loader could not get vkCreateInstance from the driver until they were there.
hostlibs="libGLdispatch.so.0 libX11.so.6 libXext.so.6 libxcb.so.1 libXau.so.6 libXdmcp.so.6
libbsd.so.0 libmd.so.0 libEGL.so.1 libGLX.so.0 libOpenGL.so.0 libGL.so.1 libGLESv2.so.2"
scenes=${RB_SCENES:-$repo/../shared/scenes}

if [ -z "$tarball" ]; then
    tarball=$(ls -t "$repo"/dist/raybundle-*-linux-x86_64.tar.xz 2>/dev/null | head -n 1)
    [ -n "$tarball" ] || die "no dist/raybundle-*-linux-x86_64.tar.xz (make dist, or --tarball PATH)"
fi
[ -f "$tarball" ] || die "no tarball $tarball"
if [ ! -f "$layer_so" ] || [ ! -f "$layer_json" ]; then
    die "no Khronos validation layer at $layer_so (apt-get install vulkan-validationlayers)"
fi
[ -e "$loader_so" ] || die "no Vulkan loader at $loader_so (apt-get install libvulkan1)"
[ -f "$scenes/cornell-box/CornellBox.glb" ] ||
    die "no $scenes/cornell-box/CornellBox.glb (set RB_SCENES to the shared scenes)"
for tool in xz python3 tar; do
    command -v "$tool" >/dev/null || die "$tool is needed"
done

# KITDIR: missing, empty, or an earlier kit (which is replaced).
if [ -e "$kit" ]; then
    [ -d "$kit" ] || die "$kit is not a directory"
    if [ -n "$(ls -A "$kit")" ]; then
        [ -f "$kit/kit.json" ] || die "$kit is neither empty nor an earlier kit (no kit.json)"
        rm -rf "${kit:?}"/*
    fi
fi
mkdir -p "$kit" || die "cannot create $kit"
kit=$(cd "$kit" && pwd)
work=$(mktemp -d "${TMPDIR:-/tmp}/gpu-kit.XXXXXX") || die "mktemp failed"
trap 'rm -rf "$work"' EXIT
start=$(date +%s)

# The tarball, and its binary for the lavapipe frames.
tb_name=$(basename "$tarball")
cp "$tarball" "$kit/$tb_name" || die "cannot copy $tarball"
tar -xJf "$tarball" -C "$work" || die "cannot unpack $tarball"
top=$(ls "$work")
if [ "$(echo "$top" | wc -l)" -ne 1 ] || [ ! -d "$work/$top" ]; then
    die "$tb_name must hold one top folder, not: $(echo "$top" | tr '\n' ' ')"
fi
rb="$work/$top/bin/raybundle"
[ -x "$rb" ] || die "$tb_name has no executable $top/bin/raybundle"
version=$("$rb" --version 2>&1) || die "$top/bin/raybundle --version failed: $version"
echo "kit: $tb_name ($version)"

# The validation layer, compressed; gpu-check.sh unpacks it and points the manifest at it.
mkdir -p "$kit/layer" "$kit/vulkan" "$kit/hostlibs"
xz -T0 -6 -c "$layer_so" >"$kit/layer/libVkLayer_khronos_validation.so.xz" ||
    die "xz of $layer_so failed"
python3 - "$layer_json" "$kit/layer/VkLayer_khronos_validation.json" <<'EOF' || die "bad $layer_json"
import json, sys
m = json.load(open(sys.argv[1]))
m["layer"]["library_path"] = "./libVkLayer_khronos_validation.so"
json.dump(m, open(sys.argv[2], "w"), indent=4)
EOF
cp -L "$loader_so" "$kit/vulkan/libvulkan.so.1" || die "cannot copy $loader_so"
carried=""
for lib in $hostlibs; do
    path=$(ldconfig -p | awk -v l="$lib" '$1 == l && /x86-64/ { print $NF; exit }')
    if [ -n "$path" ] && cp -L "$path" "$kit/hostlibs/$lib"; then
        carried="$carried $lib"
    else
        echo "kit: warning: $lib is not on this machine; the kit carries no fallback for it" >&2
    fi
done
pkgver() { dpkg-query -W -f '${Package} ${Version}' "$1" 2>/dev/null || echo "$1 (version unknown)"; }

# The scenes and the jobs, paths relative to each job file.
mkdir -p "$kit/scenes/demo" "$kit/scenes/cornell-box" "$kit/jobs"
cp "$repo"/jobs/demo/* "$kit/scenes/demo/" || die "cannot copy jobs/demo"
cp "$scenes"/cornell-box/* "$kit/scenes/cornell-box/" || die "cannot copy $scenes/cornell-box"
sed -e 's|^scene: .*|scene: ../scenes/demo/room.gltf|' -e 's|^output: .*|output: frame.####.exr|' \
    "$repo/jobs/demo.yaml" >"$kit/jobs/demo.yaml"
grep -q '^scene: ../scenes/demo/room.gltf$' "$kit/jobs/demo.yaml" || die "jobs/demo.yaml has no scene: line"
cat >"$kit/jobs/cornell.yaml" <<'EOF'
# The Cornell box (cornell-box/CornellBox.glb of the shared scenes) as the classic view frames
# it: its emissive ceiling quad, and the default point light below the ceiling (on) beside it.
scene: ../scenes/cornell-box/CornellBox.glb
output: frame.####.exr
resolution: [640, 360]
frames: {start: 0, end: 9, rate: 24}
camera: {fov_y_deg: 39.3, keys: [{t: 0, position: [-278, 273, 800], look_at: [-278, 273, 0]}]}
default_light: on
integrator: {name: bdpt}
EOF

# The blended-material scene (alphaMode BLEND quads over an opaque floor and wall: the
# transparency pass), written by the repository's own tool.
blendscene="$repo/${BUILD:-build}/tests/tools/blendscene"
if [ ! -x "$blendscene" ]; then
    make -C "$repo" -s "${BUILD:-build}/tests/tools/blendscene" >&2 ||
        die "cannot build $blendscene"
fi
mkdir -p "$kit/scenes/blend" "$work/blend"
"$blendscene" scene "$work/blend" >/dev/null || die "$blendscene scene failed"
cp "$work/blend/blend.gltf" "$work/blend/alpha.png" "$kit/scenes/blend/" ||
    die "cannot copy the blended scene"
sed -e 's|^scene: .*|scene: ../scenes/blend/blend.gltf|' -e 's|^output: .*|output: frame.####.exr|' \
    -e 's|^frames: .*|frames: {start: 0, end: 9, rate: 24}|' "$work/blend/blend.yaml" >"$kit/jobs/blend.yaml"
grep -q '^scene: ../scenes/blend/blend.gltf$' "$kit/jobs/blend.yaml" ||
    die "the blended scene's job has no scene: line"

# The lavapipe frames: beauty only, at the comparison size, one frame (bdpt and hybrid warm
# their caches up before it).
for scene in $compare_scenes; do
    for integ in $compare_integrators; do
        dir="$kit/lavapipe/$scene-$integ"
        t0=$(date +%s.%N)
        if ! "$rb" render "$kit/jobs/$scene.yaml" --integrator "$integ" --size "$compare_size" \
            --frames "$compare_frame" --set 'layers=[]' --device "$device" --out "$dir" -q \
            </dev/null >"$work/render.out" 2>"$work/render.err"; then
            tail -n 20 "$work/render.err" >&2
            die "the lavapipe frame of $scene with $integ failed"
        fi
        rm -f "$dir"/*.hits.exr
        f=$(printf 'frame.%04d' "$compare_frame")
        python3 "$here/report.py" render-figures "$dir" "$compare_frame" >"$work/fig.json" ||
            die "the lavapipe frame of $scene with $integ is not clean"
        dev=$(python3 "$here/report.py" jget "$work/fig.json" device)
        case $dev in
        *llvmpipe* | *lavapipe*) ;;
        *) die "the $scene $integ frame was rendered on '$dev', not on lavapipe (--device)" ;;
        esac
        awk -v s="$scene" -v i="$integ" -v f="$f.exr" -v a="$t0" -v b="$(date +%s.%N)" \
            'BEGIN { printf "kit: lavapipe %-7s %-6s %s in %.1f s\n", s, i, f, b - a }'
    done
done
lava_device=$(python3 "$here/report.py" jget "$work/fig.json" device)
lava_driver=$(python3 "$here/report.py" jget "$work/fig.json" driver)

K_TARBALL=$tb_name K_SHA=$(sha256sum "$tarball" | cut -d' ' -f1) K_VERSION=$version \
    K_LAYER_PKG=$(pkgver vulkan-validationlayers) K_LOADER_PKG=$(pkgver libvulkan1) \
    K_HOSTLIBS=$carried K_LAVA_DEVICE=$lava_device K_LAVA_DRIVER=$lava_driver \
    K_SIZE=$compare_size K_FRAME=$compare_frame K_SCENES=$compare_scenes \
    K_INTEGRATORS=$compare_integrators \
    K_HOST="$(uname -srm), $(sed -n 's/^PRETTY_NAME="*\([^"]*\)"*$/\1/p' /etc/os-release)" \
    python3 - "$kit/kit.json" <<'EOF' || die "cannot write kit.json"
import datetime, json, os, sys
e = os.environ
kit = {
    "format": "raybundle-gpu-kit 1",
    "created_utc": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
    "created_on": e["K_HOST"],
    "tarball": e["K_TARBALL"],
    "tarball_sha256": e["K_SHA"],
    "version": e["K_VERSION"],
    "layer": {"file": "layer/libVkLayer_khronos_validation.so.xz",
              "manifest": "layer/VkLayer_khronos_validation.json", "package": e["K_LAYER_PKG"]},
    "loader": {"file": "vulkan/libvulkan.so.1", "package": e["K_LOADER_PKG"]},
    "hostlibs": e["K_HOSTLIBS"].split(),
    "lavapipe": {"device": e["K_LAVA_DEVICE"], "driver": e["K_LAVA_DRIVER"]},
    "compare": {"size": e["K_SIZE"], "frame": int(e["K_FRAME"]), "layers": [],
                "scenes": e["K_SCENES"].split(), "integrators": e["K_INTEGRATORS"].split(),
                "dir": "lavapipe"},
    "jobs": {"demo": "jobs/demo.yaml", "cornell": "jobs/cornell.yaml"},
}
with open(sys.argv[1], "w") as f:
    json.dump(kit, f, indent=1)
    f.write("\n")
EOF

# Sizes: the kit travels with the repository within 64 MiB.
echo "kit: $kit, made in $(($(date +%s) - start)) s:"
(cd "$kit" && du -sb "$tb_name" layer vulkan hostlibs scenes jobs lavapipe kit.json) |
    awk '{ printf "  %8.2f MiB  %s\n", $1 / 1048576, $2 }'
total=$(du -sb "$kit" | cut -f1)
awk -v t="$total" -v m="$max_mib" 'BEGIN { printf "  %8.2f MiB  total (limit %s MiB)\n", t / 1048576, m }'
if [ "$total" -gt $((max_mib * 1048576)) ]; then
    die "the kit is $((total / 1048576)) MiB, above --max-mib $max_mib"
fi
