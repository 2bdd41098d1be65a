#!/bin/bash
# tests/gpu/gpu-check.sh OUTDIR [--kit KITDIR] [--device NAME|INDEX] [--quick] [--budget S]
#                        [--scratch DIR] [--keep] [--kit-loader]
#
# The real-GPU check of a raybundle tarball, as one command (see tests/gpu/README.md): with the
# kit tests/gpu/kit.sh made (default: .gpu-kit in the repository), on the first device of
# `raybundle info` whose type is not CPU (or --device):
#   setup        unpack the tarball and the validation layer, find a Vulkan loader and driver
#   validate     the demo, the Cornell box and (where the kit has it) the blended-material
#                scene with direct, bdpt, hybrid and reference under
#                --validate, at 1920x1080, frames 0-2 (the reference at 8 spp on every core)
#   compare      the same jobs at the kit's size and frame against the kit's lavapipe frames
#   determinism  the demo rendered twice and as two chunks, every EXR compared byte for byte
#   bench        raybundle bench per pass at 1920x1080 and 3840x2160, direct, bdpt and hybrid
# Each step is timed and logged; a failed step is recorded and the next one runs. OUTDIR gets
# gpu-check.json, gpu-check.md and gpu-check.log, rewritten after every step, so that a check
# killed midway leaves what it had done. Renders go to a scratch folder outside OUTDIR, removed
# at the end unless --keep (--scratch DIR: a missing or empty DIR instead of a new one in
# TMPDIR). --quick: small sizes, few frames and runs, for lavapipe here.
# --budget S (default 420, quick 900): no step starts after S seconds, and none runs past them.
# --kit-loader: the kit's Vulkan loader even where the host has one (to test that path).
# Exit status: 0 every step passed, 1 a step failed or was skipped, 2 bad usage or no kit.
set -u
here=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$here/../.." && pwd)
report="$here/report.py"

usage() {
    sed -n '2,3p' "$0" | sed 's/^# //' >&2
    exit 2
}

out="" kit="$repo/.gpu-kit" device_sel="" quick=0 budget="" scratch="" keep=0 kit_loader=0
while [ $# -gt 0 ]; do
    case $1 in
    --kit) [ $# -ge 2 ] || usage; kit=$2; shift 2 ;;
    --device) [ $# -ge 2 ] || usage; device_sel=$2; shift 2 ;;
    --quick) quick=1; shift ;;
    --budget) [ $# -ge 2 ] || usage; budget=$2; shift 2 ;;
    --scratch) [ $# -ge 2 ] || usage; scratch=$2; shift 2 ;;
    --keep) keep=1; shift ;;
    --kit-loader) kit_loader=1; shift ;;
    -h | --help) usage ;;
    -*) echo "gpu-check.sh: unknown option $1" >&2; usage ;;
    *) [ -z "$out" ] || usage; out=$1; shift ;;
    esac
done
[ -n "$out" ] || usage
case $budget in '' | *[!0-9]*) [ -z "$budget" ] || usage ;; esac
command -v python3 >/dev/null || { echo "gpu-check.sh: python3 is needed" >&2; exit 2; }
if [ -z "$scratch" ]; then
    scratch=$(mktemp -d "${TMPDIR:-/tmp}/gpu-check.XXXXXX") || exit 2
else
    # Removed at the end: only a folder of this check's own.
    if [ -e "$scratch" ] && [ -n "$(ls -A "$scratch" 2>/dev/null)" ]; then
        echo "gpu-check.sh: --scratch $scratch must be missing or empty" >&2
        exit 2
    fi
    mkdir -p "$scratch" || exit 2
    scratch=$(cd "$scratch" && pwd)
fi
cleanup() {
    [ "$keep" = 1 ] || rm -rf "$scratch"
}
trap cleanup EXIT
mkdir -p "$out" || exit 2
out=$(cd "$out" && pwd)
rm -f "$out/gpu-check.json" "$out/gpu-check.md" "$out/gpu-check.log"
mkdir -p "$scratch/logs"
log="$out/gpu-check.log"
threads=$(nproc 2>/dev/null || getconf _NPROCESSORS_ONLN)

# What each step renders. The comparison's size and frame are the kit's (kit.json).
if [ "$quick" = 1 ]; then
    mode=quick
    v_size=320x180 v_frames=0-1 spp=8
    d_size=320x180 d_frames=0-1
    b_sizes="320x180 640x360" b_runs=2 b_frames=0-1
    lim_v=300 lim_c=300 lim_d=300 lim_b=300
    : "${budget:=900}"
else
    mode=full
    v_size=1920x1080 v_frames=0-2 spp=8
    d_size=1920x1080 d_frames=0-3
    b_sizes="1920x1080 3840x2160" b_runs=3 b_frames=0-4
    lim_v=150 lim_c=60 lim_d=90 lim_b=150
    : "${budget:=420}"
fi
integrators="direct bdpt hybrid"
# The demo and the Cornell box; and the blended-material scene (the transparency pass) where the
# kit has it (tests/tools/blendscene, kits from kit.sh since it draws one).
scenes="demo cornell"
[ -f "$kit/jobs/blend.yaml" ] && scenes="$scenes blend"
scene_list=$(echo "$scenes" | sed 's/\([^ ]*\)/"\1"/g; s/ /, /g')

R() { python3 "$report" "$@"; }
t_start=$(date +%s.%N)
elapsed() { awk -v a="$t_start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }'; }
remaining() { awk -v a="$t_start" -v b="$(date +%s.%N)" -v g="$budget" 'BEGIN { printf "%d", g - (b - a) }'; }
say() { printf '[%6ss] %s\n' "$(elapsed)" "$*" | tee -a "$log" >&2; }
quote() { printf '%q ' "$@" | sed 's/ $//'; }

settings=$(
    cat <<EOF
{"validate": {"size": "$v_size", "frames": "$v_frames", "spp": $spp, "threads": $threads,
              "scenes": [$scene_list], "integrators": ["direct", "bdpt", "hybrid", "reference"]},
 "determinism": {"scene": "demo", "size": "$d_size", "frames": "$d_frames", "chunks": 2,
                 "integrators": ["direct", "bdpt", "hybrid"]},
 "bench": {"scene": "demo", "sizes": [$(echo "$b_sizes" | sed 's/\([^ ]*\)/"\1"/g; s/ /, /g')], "runs": $b_runs,
           "frames": "$b_frames", "integrators": ["direct", "bdpt", "hybrid"]},
 "compare": {}}
EOF
)
R init "$out" "$mode" "$budget" "$settings" || { echo "gpu-check.sh: cannot write $out" >&2; exit 2; }
say "gpu-check: $mode mode, budget $budget s, OUTDIR $out, scratch $scratch"

# ---- running steps -------------------------------------------------------------------------

child=""
watchdog=""
current=""
on_signal() {
    trap - INT TERM
    [ -z "$child" ] || kill -TERM "$child" "$watchdog" 2>/dev/null
    say "interrupted${current:+ during $current}"
    R finish "$out" interrupted
    exit 130
}
trap on_signal INT TERM
trap 'hung=1' USR1

# log_tail FILE N: the last N lines of FILE into the log, indented.
log_tail() {
    [ -s "$1" ] || return 0
    tail -n "$2" "$1" | sed 's/^/      /' >>"$log"
}

# run_step ID GROUP LIMIT CMD...: runs CMD (stdout and stderr into scratch/logs) with a time
# limit that the budget can shorten; sets rc (124 or 137 when the limit stopped it), wall, so
# and se. A step that would start past the budget is skipped (rc = skip), unless anyway=1.
# The caller ends it.
run_step() {
    local id=$1 group=$2 limit=$3 left
    shift 3
    current=$id
    so="$scratch/logs/${id//\//_}.out" se="$scratch/logs/${id//\//_}.err"
    : >"$so"
    : >"$se"
    left=$(remaining)
    [ "${anyway:-0}" = 0 ] || [ "$left" -ge "$limit" ] || left=$limit
    if [ "$left" -lt 5 ]; then
        rc=skip wall=0
        say "-- $id: skipped, the $budget s budget is spent"
        R skip "$out" "$id" "$group" "not started: the $budget s budget was spent"
        return
    fi
    budget_cut=0
    [ "$left" -ge "$limit" ] || { limit=$left; budget_cut=1; }
    say "== $id: $(quote "$@") (limit $limit s)"
    R start "$out" "$id" "$group" "$(quote "$@")"
    local t0
    t0=$(date +%s.%N)
    timeout -k 10 "$limit" "$@" </dev/null >"$so" 2>"$se" &
    child=$!
    # A process stuck in the driver outlives even SIGKILL: a watchdog gives up on it, so that
    # the steps after it still run.
    hung=0
    (
        trap 'kill "$sleeper" 2>/dev/null; exit 0' TERM
        sleep $((limit + 40)) &
        sleeper=$!
        wait "$sleeper" && kill -USR1 $$
    ) </dev/null >/dev/null 2>&1 &
    watchdog=$!
    wait "$child"
    rc=$?
    kill "$watchdog" 2>/dev/null
    if [ "$hung" = 1 ]; then
        kill -KILL "$child" 2>/dev/null
        rc=hung
        echo "did not end $((limit + 40)) s after it started, even killed; abandoned" >>"$se"
    fi
    child=""
    wall=$(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.3f", b - a }')
    if [ "$rc" = 124 ] || [ "$rc" = 137 ]; then
        if [ "$budget_cut" = 1 ]; then
            echo "stopped when the $budget s budget ran out, after $limit s (exit $rc)" >>"$se"
        else
            echo "stopped by the step's $limit s time limit (exit $rc)" >>"$se"
        fi
    fi
}

# end_step ID STATUS [NOTE] [FIGURES_FILE]: records the step run_step ran.
end_step() {
    local id=$1 status=$2 note=${3:-} fig=${4:-}
    [ "$rc" = skip ] && return
    # Cut short by the budget, not by a limit of its own: not done, rather than failed.
    if [ "${budget_cut:-0}" = 1 ] && { [ "$rc" = 124 ] || [ "$rc" = 137 ]; }; then
        status=skip note="stopped when the $budget s budget ran out"
    fi
    say "-- $id: $status, exit $rc, $wall s${note:+; $note}"
    if [ "$status" = pass ]; then log_tail "$se" 8; else log_tail "$se" 30; fi
    R end "$out" "$id" "$status" "$rc" "$wall" --stderr "$se" --note "$note" --figures "$fig"
    current="" budget_cut=0
}

# fn_step ID FUNCTION ARGS...: a setup step run in this shell (its exports stay), its stderr
# into scratch/logs; the function returns non-zero on failure and may set note.
fn_step() {
    local id=$1 t0 status
    shift
    current=$id
    se="$scratch/logs/${id//\//_}.err"
    say "== $id: $*"
    R start "$out" "$id" setup "$*"
    t0=$(date +%s.%N)
    note="" budget_cut=0
    "$@" >"$se" 2>&1
    rc=$?
    wall=$(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.3f", b - a }')
    if [ "$rc" = 0 ]; then status=pass; else status=fail; fi
    [ -n "$note" ] || [ "$rc" = 0 ] || note=$(grep . "$se" | tail -n 1)
    end_step "$id" "$status" "$note"
    return "$rc"
}

# figures ID KIND ARGS...: report.py KIND ARGS (a figures subcommand) into a file; sets
# fig_file, and fig_err to its complaint (empty when the figures are clean).
figures() {
    fig_file="$scratch/logs/${1//\//_}.fig.json"
    local kind=$2
    shift 2
    fig_err=$(R "$kind" "$@" 2>&1 >"$fig_file" | tr '\n' ';' | sed 's/;$//; s/;/; /g')
}

# end_figured ID: ends a step whose figures were taken: passed when it exited 0 with clean
# figures; a step that exited 0 with unclean figures fails with their complaint as its note.
end_figured() {
    if [ "$rc" = 0 ] && [ -z "$fig_err" ]; then
        end_step "$1" pass "" "$fig_file"
    elif [ "$rc" = 0 ]; then
        end_step "$1" fail "$fig_err" "$fig_file"
    else
        end_step "$1" fail "" "$fig_file"
    fi
}

# skip_rest GROUP REASON ID...: records steps that cannot run.
skip_rest() {
    local group=$1 reason=$2
    shift 2
    for id in "$@"; do R skip "$out" "$id" "$group" "$reason"; done
}

# ---- setup ---------------------------------------------------------------------------------

fatal() {
    say "gpu-check: $*; the remaining steps are skipped"
    R set "$out" fatal "$*"
    R finish "$out" "done"
    exit 1
}

host_facts() {
    R set "$out" host.uname "$(uname -a)"
    R set "$out" host.glibc "$(getconf GNU_LIBC_VERSION 2>/dev/null || ldd --version 2>&1 | head -n 1)"
    R set "$out" host.cpus "$threads"
    R set "$out" host.os "$(sed -n 's/^PRETTY_NAME="*\([^"]*\)"*$/\1/p' /etc/os-release 2>/dev/null)"
    if command -v nvidia-smi >/dev/null; then
        timeout 30 nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv \
            >"$scratch/smi" 2>&1
        R set "$out" host.nvidia_smi_csv "$(cat "$scratch/smi")"
        R set "$out" host.nvidia_smi "$(sed -n 2p "$scratch/smi")"
    else
        R set "$out" host.nvidia_smi "(no nvidia-smi)"
    fi
    R set "$out" host.ldconfig "$(ldconfig -p 2>/dev/null |
        grep -E 'libvulkan\.so|libGLX_nvidia|libnvidia-glcore|libGLdispatch|libEGL_nvidia' |
        sed 's/^[[:space:]]*//')"
    R set "$out" host.icd_files "$(ls -1 /usr/share/vulkan/icd.d /etc/vulkan/icd.d \
        /usr/local/share/vulkan/icd.d /usr/local/nvidia/share/vulkan/icd.d 2>/dev/null)"
}

use_kit() {
    [ -f "$kit/kit.json" ] || { echo "no kit at $kit (tests/gpu/kit.sh KITDIR, then --kit KITDIR)"; return 1; }
    kit=$(cd "$kit" && pwd)
    python3 - "$out/gpu-check.json" "$kit/kit.json" <<'EOF'
import json, sys
doc, kit = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
doc["kit"] = kit
doc["settings"]["compare"] = dict(kit["compare"], lavapipe=kit["lavapipe"])
open(sys.argv[1] + ".tmp", "w").write(json.dumps(doc, indent=1) + "\n")
EOF
    mv "$out/gpu-check.json.tmp" "$out/gpu-check.json" && R md "$out"
    tarball="$kit/$(R jget "$kit/kit.json" tarball)"
    [ -f "$tarball" ] || { echo "the kit has no $tarball"; return 1; }
    note="$(basename "$tarball"), kit of $(R jget "$kit/kit.json" created_utc)"
}

# untar_xz TARBALL DIR and unxz FILE (to standard output): with xz, or with Python's lzma where
# the host has no xz.
untar_xz() {
    if command -v xz >/dev/null; then
        tar -xJf "$1" -C "$2"
    else
        echo "no xz: unpacking with Python's tarfile"
        python3 -c 'import sys, tarfile
t = tarfile.open(sys.argv[1], "r:xz")
t.extractall(sys.argv[2], **({"filter": "tar"} if hasattr(tarfile, "tar_filter") else {}))' "$1" "$2"
    fi
}
unxz() {
    if command -v xz >/dev/null; then
        xz -dc "$1"
    else
        python3 -c 'import lzma, shutil, sys
shutil.copyfileobj(lzma.open(sys.argv[1]), sys.stdout.buffer)' "$1"
    fi
}

unpack() {
    mkdir -p "$scratch/dist"
    untar_xz "$tarball" "$scratch/dist" || return 1
    local top
    top=$(ls "$scratch/dist")
    if [ "$(echo "$top" | wc -l)" -ne 1 ]; then
        echo "the tarball holds more than one top folder: $top"
        return 1
    fi
    top="$scratch/dist/$top"
    rb="$top/bin/raybundle"
    [ -x "$rb" ] || { echo "no executable bin/raybundle in the tarball"; return 1; }
    elf="$top/libexec/raybundle"
    [ -f "$elf" ] || elf=$rb
    note="$top"
}

# The launcher runs, once a loader is visible (setup/loader).
run_version() {
    version=$(timeout 60 "$rb" --version) || return 1
    R set "$out" raybundle.version "$version"
    note="$version"
}

# The Vulkan loader: the host's if the binary finds one, else the kit's. For this check only, the
# kit's loader is made visible through LD_LIBRARY_PATH pointing at a folder that holds nothing
# but libvulkan.so.1 (the product itself never sets LD_LIBRARY_PATH).
loader() {
    local line
    line=$(ldd "$elf" 2>&1 | grep 'libvulkan\.so\.1')
    if [ "$kit_loader" = 0 ] && [ -n "$line" ] && ! echo "$line" | grep -q 'not found'; then
        R set "$out" host.loader "host: $(echo "$line" | sed 's/^[[:space:]]*//; s/ (0x.*//')"
        note="the host's"
        return 0
    fi
    mkdir -p "$scratch/loader"
    ln -sf "$kit/vulkan/libvulkan.so.1" "$scratch/loader/libvulkan.so.1"
    export LD_LIBRARY_PATH="$scratch/loader${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
    line=$(ldd "$elf" 2>&1 | grep 'libvulkan\.so\.1')
    R set "$out" host.loader "kit: $(R jget "$kit/kit.json" loader.package) ($([ "$kit_loader" = 1 ] &&
        echo "--kit-loader" || echo "the host has none")), through LD_LIBRARY_PATH: $(ldd "$elf" 2>&1 |
        grep 'libvulkan\.so\.1' | sed 's/^[[:space:]]*//; s/ (0x.*//')"
    note="the kit's ($(R jget "$kit/kit.json" loader.package))"
    if ! echo "$line" | grep -q "$scratch/loader/"; then
        echo "the binary does not take the kit's loader: $line"
        return 1
    fi
}

# The validation layer: unpacked, its manifest pointing at it by absolute path; VK_LAYER_PATH
# (explicit layers from there alone) and VK_ADD_LAYER_PATH (newer loaders).
layer() {
    mkdir -p "$scratch/layer"
    unxz "$kit/layer/libVkLayer_khronos_validation.so.xz" \
        >"$scratch/layer/libVkLayer_khronos_validation.so" || return 1
    python3 - "$kit/layer/VkLayer_khronos_validation.json" "$scratch/layer" <<'EOF' || return 1
import json, os, sys
m = json.load(open(sys.argv[1]))
m["layer"]["library_path"] = os.path.join(sys.argv[2], "libVkLayer_khronos_validation.so")
json.dump(m, open(os.path.join(sys.argv[2], "VkLayer_khronos_validation.json"), "w"), indent=4)
EOF
    export VK_LAYER_PATH="$scratch/layer" VK_ADD_LAYER_PATH="$scratch/layer"
    R set "$out" host.layer "kit: $(R jget "$kit/kit.json" layer.package)"
    note="$(R jget "$kit/kit.json" layer.package)"
}

# info NAME: raybundle info into scratch/NAME.
info() {
    timeout -k 5 90 "$rb" info >"$scratch/$1" 2>&1
    local st=$?
    cp "$scratch/$1" "$scratch/logs/$1.txt"
    R set-file "$out" raybundle.info "$scratch/$1"
    cat "$scratch/$1" >&2
    note="$(grep -c '^\[[0-9]*\] ' "$scratch/$1") device(s)$(sed -n 's/^validation layer:/; &/p' "$scratch/$1")"
    return $st
}

# info_probe FILE: the first `raybundle info`, with the loader's own driver search. Where it
# lists no device but an NVIDIA driver manifest is there, it is a probe, not a failure: the
# check lends that driver next (container images carry the driver without a loader or libglvnd).
info_probe() {
    info "$1" && return 0
    local icd
    icd=$(nvidia_icd) || return 1
    note="$note where the loader looks; next: the NVIDIA driver of $icd"
    return 0
}

# The NVIDIA Vulkan driver, when the loader found no GPU: the first nvidia_icd.json of the
# places container images put it, its library made findable (an absolute path in a copy of the
# manifest, its folder on LD_LIBRARY_PATH when ldconfig does not know it), and the libraries it
# needs that the host lacks taken from the kit (a folder of links to those alone).
nvidia_icd() {
    local f
    for f in /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json \
        /usr/share/vulkan/icd.d/nvidia_icd.json /etc/vulkan/icd.d/nvidia_icd.json \
        /usr/local/share/vulkan/icd.d/nvidia_icd.json /usr/local/nvidia/etc/vulkan/icd.d/nvidia_icd.json; do
        [ -f "$f" ] && { echo "$f"; return 0; }
    done
    return 1
}
nvidia_driver() {
    local icd lib libpath="" d missing m
    icd=$(nvidia_icd) || { echo "no nvidia_icd.json"; return 1; }
    lib=$(python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["ICD"]["library_path"])' "$icd") || return 1
    case $lib in
    /*) libpath=$lib ;;
    */*) libpath="$(dirname "$icd")/$lib" ;;
    *)
        libpath=$(ldconfig -p | awk -v l="$lib" '$1 == l && /x86-64/ { print $NF; exit }')
        if [ -z "$libpath" ]; then
            for d in /usr/local/nvidia/lib64 /usr/local/nvidia/lib /usr/lib/x86_64-linux-gnu /usr/lib64 /lib/x86_64-linux-gnu; do
                if [ -e "$d/$lib" ]; then
                    libpath="$d/$lib"
                    export LD_LIBRARY_PATH="${LD_LIBRARY_PATH:+$LD_LIBRARY_PATH:}$d"
                    break
                fi
            done
        fi
        ;;
    esac
    if [ -z "$libpath" ] || [ ! -e "$libpath" ]; then
        echo "$icd names $lib, which is nowhere to be found"
        note="driver library $lib missing"
        return 1
    fi
    mkdir -p "$scratch/icd"
    python3 - "$icd" "$libpath" "$scratch/icd/nvidia_icd.json" <<'EOF' || return 1
import json, sys
m = json.load(open(sys.argv[1]))
m["ICD"]["library_path"] = sys.argv[2]
json.dump(m, open(sys.argv[3], "w"), indent=4)
EOF
    export VK_DRIVER_FILES="$scratch/icd/nvidia_icd.json" VK_ICD_FILENAMES="$scratch/icd/nvidia_icd.json"
    f=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
    [ -f "$f" ] && export __EGL_VENDOR_LIBRARY_FILENAMES=$f
    missing=$(ldd "$libpath" 2>&1 | awk '/not found/ { print $1 }')
    # libglvnd's libraries the driver opens at run time (dlopen; ldd cannot see them).
    for m in libEGL.so.1 libGLX.so.0 libOpenGL.so.0 libGLdispatch.so.0; do
        ldconfig -p 2>/dev/null | awk -v l="$m" '$1 == l && /x86-64/ { f = 1 } END { exit !f }' ||
            missing="$missing $m"
    done
    for m in $missing; do
        if [ -f "$kit/hostlibs/$m" ]; then
            mkdir -p "$scratch/hostlibs"
            ln -sf "$kit/hostlibs/$m" "$scratch/hostlibs/$m"
        else
            echo "$libpath needs $m, which neither the host nor the kit has"
        fi
    done
    if [ -d "$scratch/hostlibs" ]; then
        export LD_LIBRARY_PATH="${LD_LIBRARY_PATH:+$LD_LIBRARY_PATH:}$scratch/hostlibs"
        # The kit's libraries may need each other; ldd again for what is still missing.
        missing=$(ldd "$libpath" 2>&1 | awk '/not found/ { print $1 }')
        [ -z "$missing" ] || echo "still missing for $libpath: $missing"
    fi
    R set "$out" host.icd "$icd -> $libpath$([ -d "$scratch/hostlibs" ] && echo " (with the kit's $(ls "$scratch/hostlibs" | tr '\n' ' '))")"
    note="$icd, $libpath"
}

loader_debug() {
    VK_LOADER_DEBUG=error,warn,driver timeout -k 5 90 "$rb" info >"$scratch/logs/loader-debug.txt" 2>&1
    tail -n 40 "$scratch/logs/loader-debug.txt" >&2
    note="VK_LOADER_DEBUG=error,warn,driver raybundle info, for the record"
    return 1 # a diagnosis, recorded as failed: the loader found no device to test
}

record_env() {
    local v
    for v in LD_LIBRARY_PATH VK_DRIVER_FILES VK_ICD_FILENAMES VK_LAYER_PATH VK_ADD_LAYER_PATH \
        __EGL_VENDOR_LIBRARY_FILENAMES __GL_SHADER_DISK_CACHE_PATH; do
        R set "$out" "host.env.$v" "${!v:-}"
    done
}

# The NVIDIA driver's shader cache in the scratch folder, wherever HOME is: the runs after the
# first of each pipeline then skip compiling it (timings are per pass, compiling is in none).
export __GL_SHADER_DISK_CACHE=1 __GL_SHADER_DISK_CACHE_PATH="$scratch/glcache" \
    __GL_SHADER_DISK_CACHE_SKIP_CLEANUP=1
mkdir -p "$scratch/glcache"

host_facts
fn_step setup/kit use_kit || fatal "no usable kit"
fn_step setup/unpack unpack || fatal "the tarball does not run"
fn_step setup/loader loader
fn_step setup/version run_version || fatal "the tarball does not run"
fn_step setup/layer layer
fn_step setup/info info_probe info.txt
if ! R pick "$scratch/info.txt" >/dev/null 2>&1; then
    # No GPU listed: the NVIDIA driver where container images put it, if it is there.
    if nvidia_icd >/dev/null && fn_step setup/nvidia-driver nvidia_driver; then
        fn_step setup/info-nvidia info info.txt
    fi
fi
[ -n "$(R get "$out" host.icd 2>/dev/null)" ] ||
    R set "$out" host.icd "as the loader finds them: ${VK_DRIVER_FILES:-its default places}$(
        nvidia_icd >/dev/null || echo "; no nvidia_icd.json in /usr/local/nvidia/share/vulkan/icd.d, /usr/share/vulkan/icd.d, /etc/vulkan/icd.d")"
# The device asked for (or a GPU) is still missing: what the loader says, for the record.
R pick "$scratch/info.txt" "$device_sel" >/dev/null 2>&1 || fn_step setup/loader-debug loader_debug
record_env

pick_device() {
    R pick "$scratch/info.txt" "$device_sel" >"$scratch/device.json" || return 1
    R set-json "$out" device "$(cat "$scratch/device.json")"
    device_index=$(R jget "$scratch/device.json" index)
    device_name=$(R jget "$scratch/device.json" name)
    note="[$device_index] $device_name ($(R jget "$scratch/device.json" type))"
    R set "$out" device.selector "${device_sel:-first non-CPU device}"
}
fn_step setup/device pick_device || fatal "no device to test${device_sel:+ matches --device $device_sel}"
dev=(--device "$device_index")

job() { echo "$kit/jobs/$1.yaml"; }

# ---- a. validation -------------------------------------------------------------------------

for scene in $scenes; do
    for integ in $integrators reference; do
        id="validate/$scene/$integ"
        dir="$scratch/validate/$scene-$integ"
        extra=()
        expect=$device_name
        if [ "$integ" = reference ]; then
            extra=(--spp "$spp" --threads "$threads")
            expect="cpu ($threads threads)"
        fi
        run_step "$id" validate "$lim_v" "$rb" render "$(job "$scene")" --integrator "$integ" \
            --size "$v_size" --frames "$v_frames" "${dev[@]}" --validate "${extra[@]}" --out "$dir" -q
        [ "$rc" = skip ] && continue
        figures "$id" render-figures "$dir" "$v_frames" "$expect"
        end_figured "$id"
    done
done

# ---- d. against lavapipe -------------------------------------------------------------------

c_size=$(R jget "$kit/kit.json" compare.size)
c_frame=$(R jget "$kit/kit.json" compare.frame)
c_name=$(printf 'frame.%04d' "$c_frame")
for scene in $scenes; do
    for integ in $integrators; do
        id="compare-render/$scene/$integ"
        dir="$scratch/compare/$scene-$integ"
        lava="$kit/lavapipe/$scene-$integ"
        run_step "$id" compare "$lim_c" "$rb" render "$(job "$scene")" --integrator "$integ" \
            --size "$c_size" --frames "$c_frame" --set 'layers=[]' "${dev[@]}" --out "$dir" -q
        [ "$rc" = skip ] && continue
        figures "$id" render-figures "$dir" "$c_frame" "$device_name"
        end_figured "$id"
        if [ "$rc" != 0 ] || [ -n "$fig_err" ]; then
            skip_rest compare "its render failed" "compare/$scene/$integ"
            continue
        fi
        id="compare/$scene/$integ"
        run_step "$id" compare 60 "$rb" compare "$dir/$c_name.exr" "$lava/$c_name.exr" --json
        [ "$rc" = skip ] && continue
        fig_file="" fig_err=""
        [ "$rc" != 0 ] ||
            figures "$id" compare-figures "$so" "$dir/$c_name.timing.json" "$lava/$c_name.timing.json"
        end_figured "$id"
    done
done

# ---- b. determinism ------------------------------------------------------------------------

for integ in $integrators; do
    base="$scratch/determinism/$integ"
    ok=1
    for run in run1 run2 chunk0 chunk1; do
        id="determinism/$integ/$run"
        chunk=()
        case $run in chunk*) chunk=(--chunk "${run#chunk}/2") ;; esac
        run_step "$id" determinism "$lim_d" "$rb" render "$(job demo)" --integrator "$integ" \
            --size "$d_size" --frames "$d_frames" "${chunk[@]}" "${dev[@]}" --out "$base/$run" -q
        if [ "$rc" = skip ]; then ok=0; continue; fi
        if [ "$rc" = 0 ]; then end_step "$id" pass; else end_step "$id" fail; ok=0; fi
    done
    if [ "$ok" = 0 ]; then
        skip_rest determinism "a render of $integ failed or did not run" \
            "determinism/$integ/twice" "determinism/$integ/chunks"
        continue
    fi
    for what in twice chunks; do
        id="determinism/$integ/$what"
        if [ "$what" = twice ]; then others=("$base/run2"); else others=("$base/chunk0" "$base/chunk1"); fi
        # Seconds at most, so it runs even past the budget: the renders are done.
        anyway=1 run_step "$id" determinism 60 python3 "$report" samebits "$base/run1" "${others[@]}"
        [ "$rc" = skip ] && continue
        cp "$so" "$scratch/logs/${id//\//_}.fig.json"
        if [ "$rc" = 0 ]; then
            end_step "$id" pass "" "$scratch/logs/${id//\//_}.fig.json"
        else
            end_step "$id" fail "$(tr '\n' ' ' <"$se")" "$scratch/logs/${id//\//_}.fig.json"
        fi
    done
done

# ---- c. per-pass GPU time ------------------------------------------------------------------

for size in $b_sizes; do
    for integ in $integrators; do
        id="bench/$size/$integ"
        dir="$scratch/bench/$size-$integ"
        run_step "$id" bench "$lim_b" "$rb" bench "$(job demo)" --out "$dir" --runs "$b_runs" \
            --frames "$b_frames" --size "$size" --integrator "$integ" "${dev[@]}" -q
        [ "$rc" = skip ] && continue
        figures "$id" bench-figures "$dir" "$device_name"
        end_figured "$id"
    done
done

R finish "$out" "done"
failed=$(R get "$out" summary.fail)
skipped=$(R get "$out" summary.skip)
passed=$(R get "$out" summary.pass)
say "gpu-check: done in $(elapsed) s: $passed passed, $failed failed, $skipped skipped; $out/gpu-check.md"
[ "$failed" = 0 ] && [ "$skipped" = 0 ]
