#!/bin/sh
# Tests the portable tarball (scripts/dist.sh) on a system it was not built on:
#   tests/dist/check-dist.sh TARBALL REGULAR_BINARY      (make check-dist; as root)
#
# A Debian 13 trixie minbase chroot with only libvulkan1 and mesa-vulkan-drivers added, made
# once with debootstrap and cached in $RB_DIST_CHROOT (default /var/cache/raybundle/trixie-
# minbase), stands for "any recent Linux": a newer glibc, libstdc++ and Mesa than the Debian 12
# the tarball was built on, and none of its libraries. A copy made before Vulkan went in
# ($RB_DIST_CHROOT-noloader) is the machine without a Vulkan loader. In them, and on this host:
# - the tarball's layout, RUNPATHs and licenses;
# - ldd in the chroot resolves every library to the tarball, or to the short list the host
#   must provide (HOST_LIBS), and none of the bundled SONAMEs is one Mesa's drivers load;
# - the demo job rendered by the tarball in the chroot, by the tarball on this host and by
#   REGULAR_BINARY on this host: every EXR and PNG the same bytes (see the note above the
#   comparisons for why that holds for the GPU integrators across Mesa versions);
# - the launcher's messages without a Vulkan loader and without /proc, raybundle's without a
#   Vulkan driver.
# Prints "ok"/"FAIL" per check and "N passed, N failed" last; exits 1 on any failure.
# RB_DIST_MIRROR overrides the Debian mirror (default: the one this machine's apt uses).
set -u

if [ $# -ne 2 ]; then
    echo "usage: tests/dist/check-dist.sh TARBALL REGULAR_BINARY" >&2
    exit 2
fi
if [ "$(id -u)" != 0 ]; then
    echo "check-dist: must run as root (debootstrap, chroot and mount)" >&2
    exit 2
fi
for tool in debootstrap chroot mount umount flock xz tar readelf; do
    if ! command -v "$tool" >/dev/null 2>&1; then
        echo "check-dist: '$tool' not found (scripts/install-deps.sh installs debootstrap)" >&2
        exit 2
    fi
done
[ -f "$1" ] || { echo "check-dist: tarball '$1' not found" >&2; exit 2; }
[ -x "$2" ] || { echo "check-dist: binary '$2' not found" >&2; exit 2; }

root=$(cd "$(dirname "$0")/../.." && pwd)
tarball=$(readlink -f "$1")
regular=$(readlink -f "$2")
name=$(basename "$tarball" .tar.xz)
SUITE=trixie
CHROOT=${RB_DIST_CHROOT:-/var/cache/raybundle/trixie-minbase}
NOLOADER=$CHROOT-noloader
STAMP=.raybundle-chroot-complete
MAX_MIB=48
# The libraries the tarball leaves to the host, by SONAME: glibc's, the C++ runtime, zlib and
# expat (which a Vulkan driver loads too, so a bundled copy would shadow the driver's), and the
# Vulkan loader. Anything else the binary needs must come from the tarball.
HOST_LIBS="linux-vdso.so.1 ld-linux-x86-64.so.2 libc.so.6 libm.so.6 libpthread.so.0 libdl.so.2
librt.so.1 libstdc++.so.6 libgcc_s.so.1 libz.so.1 libexpat.so.1 libvulkan.so.1"
# The demo at a small size: two frames, so that bdpt's and hybrid's temporal state is used.
RENDER_ARGS="jobs/demo.yaml --size 160x90 --frames 1-2 --preview -q"
INTEGRATORS="direct bdpt hybrid reference"

started=$(date +%s)
passed=0
failed=0
ok() {
    passed=$((passed + 1))
    echo "ok   $1"
}
not_ok() {
    failed=$((failed + 1))
    echo "FAIL $1"
    shift
    for line in "$@"; do printf '%s\n' "$line" | sed 's/^/    /'; done
}
check() { # check DESCRIPTION COMMAND...
    d=$1
    shift
    if "$@"; then ok "$d"; else not_ok "$d"; fi
}
finish() {
    echo "# $(($(date +%s) - started)) s in all"
    echo "$passed passed, $failed failed"
    [ "$failed" -eq 0 ] && exit 0
    exit 1
}

T=$(mktemp -d "${TMPDIR:-/tmp}/raybundle-check-dist.XXXXXX")
mounted=""
chroot_tmps=""
# shellcheck disable=SC2317 # called by the trap
cleanup() {
    for m in $mounted; do
        umount "$m" 2>/dev/null || umount -l "$m" || echo "check-dist: cannot unmount '$m'" >&2
    done
    for d in $chroot_tmps; do rm -rf --one-file-system "$d"; done
    rm -rf "$T"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# mount_proc DIR: lavapipe reads /proc for its thread count. Unmounted by cleanup, always.
mount_proc() {
    if ! mountpoint -q "$1/proc"; then
        mount -t proc proc "$1/proc" || return 1
    fi
    mounted="$1/proc $mounted"
}

# remove_tree DIR: a half-made chroot from an interrupted run; refuses while anything under it
# is still mounted (rm -rf through a mount would reach outside).
remove_tree() {
    [ -e "$1" ] || return 0
    awk -v d="$1/" 'index($2 "/", d) == 1 { print $2 }' /proc/self/mounts | sort -r |
        while read -r m; do umount "$m" || umount -l "$m"; done
    if awk -v d="$1/" 'index($2 "/", d) == 1 { found = 1 } END { exit !found }' /proc/self/mounts; then
        echo "check-dist: '$1' still has mounts under it; not removing it" >&2
        return 1
    fi
    rm -rf --one-file-system "$1"
}

# The Debian mirror this machine's apt uses (deb822 or one-line sources), else deb.debian.org.
host_mirror() {
    m=$(cat /etc/apt/sources.list.d/*.sources 2>/dev/null |
        sed -n 's/^URIs:.*[[:space:]]\(https\{0,1\}:\/\/[^[:space:]]*\/debian\)\/\{0,1\}\([[:space:]].*\)\{0,1\}$/\1/p' |
        head -n 1)
    if [ -z "$m" ]; then
        m=$(cat /etc/apt/sources.list /etc/apt/sources.list.d/*.list 2>/dev/null |
            sed -n 's/^deb\([[:space:]]\{1,\}\[[^]]*\]\)\{0,1\}[[:space:]]\{1,\}\(https\{0,1\}:\/\/[^[:space:]]*\/debian\)\/\{0,1\}[[:space:]].*$/\2/p' |
            head -n 1)
    fi
    echo "${m:-http://deb.debian.org/debian}"
}
MIRROR=${RB_DIST_MIRROR:-$(host_mirror)}

# in DIR COMMAND...: runs COMMAND in the chroot DIR with a clean environment.
in_chroot() {
    d=$1
    shift
    chroot "$d" /usr/bin/env -i PATH=/usr/local/bin:/usr/bin:/bin:/usr/sbin:/sbin HOME=/root \
        LANG=C.UTF-8 "$@"
}

# make_chroots: the trixie minbase chroot with the Vulkan loader and Mesa, and its copy from
# before they went in. Made under .partial names and renamed when complete, so an interrupted
# run leaves nothing that looks finished; a stamp marks each complete one.
make_chroots() {
    if [ -f "$CHROOT/$STAMP" ] && [ -f "$NOLOADER/$STAMP" ]; then
        echo "# using the cached $SUITE chroot $CHROOT ($(cat "$CHROOT/$STAMP"))"
        return 0
    fi
    t0=$(date +%s)
    echo "# making the $SUITE minbase chroot $CHROOT from $MIRROR (once; it is kept)"
    for d in "$CHROOT" "$NOLOADER" "$CHROOT.partial" "$NOLOADER.partial"; do
        remove_tree "$d" || return 1
    done
    part=$CHROOT.partial
    if ! debootstrap --variant=minbase "$SUITE" "$part" "$MIRROR" >"$T/debootstrap.log" 2>&1; then
        not_ok "debootstrap $SUITE from $MIRROR" "$(tail -n 5 "$T/debootstrap.log")"
        return 1
    fi
    # The same system before the Vulkan loader goes in: the launcher's missing-loader case.
    cp -a "$part" "$NOLOADER.partial" || return 1
    mount_proc "$part" || return 1
    if ! in_chroot "$part" sh -c 'apt-get update -q && DEBIAN_FRONTEND=noninteractive \
            apt-get install -y -q --no-install-recommends libvulkan1 mesa-vulkan-drivers &&
            apt-get clean' >"$T/apt.log" 2>&1; then
        not_ok "install libvulkan1 mesa-vulkan-drivers in the $SUITE chroot" "$(tail -n 5 "$T/apt.log")"
        return 1
    fi
    umount "$part/proc" && mounted=$(echo "$mounted" | sed "s|$part/proc ||")
    versions=$(in_chroot "$part" dpkg-query -W -f='${Package} ${Version}, ' libc6 libstdc++6 \
        libvulkan1 mesa-vulkan-drivers)
    echo "made $(date -u +%Y-%m-%dT%H:%MZ) from $MIRROR: ${versions%, }" >"$part/$STAMP"
    echo "made $(date -u +%Y-%m-%dT%H:%MZ) from $MIRROR, without Vulkan" >"$NOLOADER.partial/$STAMP"
    mv "$NOLOADER.partial" "$NOLOADER" && mv "$part" "$CHROOT" || return 1
    echo "# made the chroots in $(($(date +%s) - t0)) s: $(cat "$CHROOT/$STAMP")"
}

# ---- the tarball itself, on this host ---------------------------------------------------------

size=$(stat -c %s "$tarball")
check "tarball is at most $MAX_MIB MiB ($((size / 1024)) KiB)" \
    test "$size" -le $((MAX_MIB * 1024 * 1024))

tar -tJf "$tarball" >"$T/list" || { not_ok "tarball lists"; finish; }
tops=$(sed 's|/.*||' "$T/list" | sort -u)
check "one top folder, $name/ (found: $(echo "$tops" | tr '\n' ' ' | sed 's/ $//'))" test "$tops" = "$name"

mkdir -p "$T/host"
tar -xJf "$tarball" -C "$T/host" || { not_ok "tarball unpacks"; finish; }
top=$T/host/$name
missing=""
for f in bin/raybundle libexec/raybundle share/raybundle/ocio/config.ocio \
    share/man/man1/raybundle.1 share/man/man5/raybundle-job.5 README \
    share/doc/raybundle/licenses/LIBRARIES; do
    [ -f "$top/$f" ] || missing="$missing $f"
done
check "the tree has bin/, libexec/, the OCIO config, man pages, README, licenses${missing:+ (missing:$missing)}" \
    test -z "$missing"
check "bin/raybundle and libexec/raybundle are executable" \
    test -x "$top/bin/raybundle" -a -x "$top/libexec/raybundle"
check "lib/ holds libraries" test -n "$(ls "$top/lib" 2>/dev/null)"

runpath() { readelf -d "$1" | sed -n 's/^.*(RUNPATH).*\[\(.*\)\]$/\1/p'; }
check "libexec/raybundle's RUNPATH is \$ORIGIN/../lib" \
    test "$(runpath "$top/libexec/raybundle")" = '$ORIGIN/../lib'
bad=""
for f in "$top"/lib/*; do
    [ "$(runpath "$f")" = '$ORIGIN' ] || bad="$bad $(basename "$f")"
    readelf -d "$f" | grep -q '(RPATH)' && bad="$bad $(basename "$f")(RPATH)"
done
check "every bundled library's RUNPATH is \$ORIGIN, none has an RPATH${bad:+ (wrong:$bad)}" test -z "$bad"

# The measured failure this guards against: a bundled libstdc++ shadowed the host's inside
# trixie's lavapipe (VK_ERROR_INITIALIZATION_FAILED). None of these may be in lib/.
bad=""
for f in "$top"/lib/*; do
    case ${f##*/} in
    libc.so.* | libm.so.* | libpthread.so.* | libdl.so.* | librt.so.* | ld-linux* | \
        libstdc++.so.* | libgcc_s.so.* | libvulkan.so.* | libz.so.* | libexpat.so.*)
        bad="$bad ${f##*/}"
        ;;
    esac
done
check "lib/ has no glibc, libstdc++, libgcc_s, libvulkan, zlib or expat${bad:+ (found:$bad)}" test -z "$bad"

bad=""
for f in "$top"/lib/*; do
    so=$(basename "$f")
    pkg=$(awk -v s="$so" '$1 == s { print $2 }' "$top/share/doc/raybundle/licenses/LIBRARIES")
    if [ -z "$pkg" ]; then
        bad="$bad $so(unlisted)"
    elif [ ! -s "$top/share/doc/raybundle/licenses/$pkg/copyright" ]; then
        bad="$bad $so($pkg/copyright)"
    fi
done
check "every bundled library has its package's copyright file${bad:+ (missing:$bad)}" test -z "$bad"

# The launcher sets no library path: the bundle is found through RUNPATH alone.
check "the launcher does not set LD_LIBRARY_PATH" \
    sh -c '! grep -Eq "(export[[:space:]]+|^|[[:space:]])LD_LIBRARY_PATH=" "$1"' sh "$top/bin/raybundle"

# ---- the chroots -----------------------------------------------------------------------------

mkdir -p "$(dirname "$CHROOT")"
exec 9>"$CHROOT.lock"
flock 9 # one check-dist at a time on a cache
make_chroots || finish
ok "$SUITE chroot ready ($(sed 's/^made [^ ]* from [^ ]* //' "$CHROOT/$STAMP"))"

ct=$(mktemp -d "$CHROOT/tmp/raybundle-dist.XXXXXX")
chroot_tmps="$ct"
cin=${ct#"$CHROOT"} # the same directory, as the chroot sees it
ctop=$cin/$name
if ! xz -dc "$tarball" | in_chroot "$CHROOT" tar -x -C "$cin"; then
    not_ok "tarball unpacks in the chroot"
    finish
fi
cp -r "$root/jobs" "$ct/jobs"

# Without /proc the dynamic loader cannot expand the binary's $ORIGIN: the launcher says so.
# (A /proc left mounted by an interrupted run is ours to unmount: the lock is held.)
mountpoint -q "$CHROOT/proc" && umount "$CHROOT/proc"
in_chroot "$CHROOT" "$ctop/bin/raybundle" --version >"$T/noproc" 2>&1
status=$?
if [ "$status" -eq 1 ] && grep -q '^raybundle: /proc is not mounted' "$T/noproc"; then
    ok "no /proc: the launcher exits 1 and says so"
else
    not_ok "no /proc: the launcher exits 1 and says so (exit $status)" "$(head -c 1000 "$T/noproc")"
fi
mount_proc "$CHROOT" || { not_ok "mount /proc in $CHROOT"; finish; }

# ldd in the chroot: each library from the tarball, or one HOST_LIBS names; none "not found".
# Bundled ones show as .../libexec/../lib/NAME (the RUNPATH, $ORIGIN expanded).
in_chroot "$CHROOT" ldd "$ctop/libexec/raybundle" >"$T/ldd" 2>&1
ldd_status=$?
bad=""
host_used=""
while read -r so arrow path rest; do
    case $so in /*) path=$so so=$(basename "$so") ;; esac # the dynamic loader's own line
    [ "$so" = linux-vdso.so.1 ] && continue               # the kernel's, no file
    [ "$arrow" = "=>" ] || [ -n "$path" ] || continue
    case $path in
    "$ctop"/lib/* | "$ctop"/libexec/../lib/*) continue ;;
    not) bad="$bad $so(not found)" ;;
    *)
        host_used="$host_used $so"
        case " $HOST_LIBS " in *[[:space:]]"$so"[[:space:]]*) ;; *) bad="$bad $so=$path" ;; esac
        ;;
    esac
done <"$T/ldd"
if [ "$ldd_status" -eq 0 ] && [ -z "$bad" ] && [ -n "$host_used" ]; then
    ok "ldd in the chroot: everything from the tarball but$host_used"
else
    not_ok "ldd in the chroot: everything from the tarball but HOST_LIBS (ldd exit $ldd_status)" \
        "not from the tarball, not in HOST_LIBS:$bad"
fi

# No bundled SONAME may be one a Mesa driver in the chroot loads: it would be loaded first and
# used by the driver too.
for drv in "$CHROOT"/usr/lib/x86_64-linux-gnu/libvulkan_*.so; do
    in_chroot "$CHROOT" ldd "${drv#"$CHROOT"}"
done 2>&1 | awk '$2 == "=>" { print $1 }' | sort -u >"$T/driver-libs"
for f in "$top"/lib/*; do echo "${f##*/}"; done | sort >"$T/bundled"
shadow=$(comm -12 "$T/driver-libs" "$T/bundled" | tr '\n' ' ')
check "no bundled library is one the chroot's Mesa drivers load ($(wc -l <"$T/driver-libs") checked)${shadow:+ (shadowed: $shadow)}" \
    test -z "$shadow" -a -s "$T/driver-libs"

# info through a symlink to the launcher: it finds its own tree, the loader, lavapipe, and the
# OCIO config relative to libexec/raybundle.
ln -s "$ctop/bin/raybundle" "$ct/raybundle-link"
in_chroot "$CHROOT" "$cin/raybundle-link" info >"$T/info" 2>&1
status=$?
if [ "$status" -eq 0 ] && grep -q 'usable: yes' "$T/info"; then
    ok "info in the chroot, through a symlink to bin/raybundle: $(grep -m 1 'driver:' "$T/info" | sed 's/^ *//')"
else
    not_ok "info in the chroot, through a symlink to bin/raybundle (exit $status)" "$(head -c 2000 "$T/info")"
fi
check "info in the chroot finds the tarball's OCIO config" \
    grep -qxF "OpenColorIO config: $ctop/share/raybundle/ocio/config.ocio" "$T/info"

# No driver: the loader is there, but it finds no driver manifest.
in_chroot "$CHROOT" VK_DRIVER_FILES=/nonexistent.json VK_ICD_FILENAMES=/nonexistent.json \
    MESA_SHADER_CACHE_DIR="$cin/mesa-cache" sh -c "cd '$cin' && '$ctop/bin/raybundle' render \
    $RENDER_ARGS --out '$cin/never'" >"$T/nodriver" 2>&1
status=$?
if [ "$status" -eq 3 ] && grep -q 'no Vulkan 1.3 driver found' "$T/nodriver"; then
    ok "no Vulkan driver: render exits 3 and says so ($(head -n 1 "$T/nodriver"))"
else
    not_ok "no Vulkan driver: render exits 3 and says so (exit $status)" "$(head -c 2000 "$T/nodriver")"
fi

# ---- renders: chroot, this host, the regular build ---------------------------------------------

# render_set WHERE OUTDIR: the demo with each integrator; WHERE is chroot, host or regular.
# shellcheck disable=SC2086 # RENDER_ARGS and extra are lists of words
render_set() {
    for i in $INTEGRATORS; do
        extra=""
        [ "$i" = reference ] && extra="--spp 4"
        case $1 in
        chroot)
            in_chroot "$CHROOT" MESA_SHADER_CACHE_DIR="$cin/mesa-cache" sh -c "cd '$cin' && \
                '$ctop/bin/raybundle' render $RENDER_ARGS --integrator $i $extra --out '$2/$i'"
            ;;
        host)
            (cd "$root" && MESA_SHADER_CACHE_DIR="$T/mesa-cache" \
                "$top/bin/raybundle" render $RENDER_ARGS --integrator $i $extra --out "$2/$i")
            ;;
        regular) # RB_DATADIR: the repository's OCIO config, the file the tarball carries
            (cd "$root" && MESA_SHADER_CACHE_DIR="$T/mesa-cache" RB_DATADIR="$root/share" \
                "$regular" render $RENDER_ARGS --integrator $i $extra --out "$2/$i")
            ;;
        esac >"$T/render-$1-$i.log" 2>&1
        status=$?
        if [ "$status" -eq 0 ]; then
            ok "$1: render --integrator $i"
        else
            not_ok "$1: render --integrator $i (exit $status)" "$(tail -n 5 "$T/render-$1-$i.log")"
        fi
    done
}

# same_files A B INTEGRATOR: every image (EXR and PNG preview) in A/I equals B/I byte for byte,
# and the two hold the same images. Prints raybundle compare's figures for a frame that differs.
images() { # images DIR: the EXR and PNG files in DIR, by name
    for f in "$1"/*.exr "$1"/*.png; do [ -f "$f" ] && printf '%s ' "${f##*/}"; done
}
same_files() {
    a=$1/$3
    b=$2/$3
    la=$(images "$a")
    lb=$(images "$b")
    if [ -z "$la" ] || [ "$la" != "$lb" ]; then
        echo "images differ: '$la' vs '$lb'"
        return 1
    fi
    differ=""
    for f in $la; do
        cmp -s "$a/$f" "$b/$f" && continue
        differ="$differ $f"
        case $f in
        *.hits.exr | *.png) ;;
        *) echo "$f: $("$regular" compare "$a/$f" "$b/$f" 2>&1 |
            awk '$1 ~ /^(rmse|relmse|psnr|max_error)$/ { $1 = $1; printf "%s; ", $0 }')" ;;
        esac
    done
    [ -z "$differ" ] && return 0
    echo "differ:$differ"
    return 1
}

render_set chroot "$cin/out"
render_set host "$T/out-host"
render_set regular "$T/out-regular"

# All of them must match bit for bit. For reference (Embree on the CPU, deterministic whatever
# the thread count) and for the tarball on this host (the same Mesa) that is by construction.
# For the GPU integrators in the chroot it is by measurement: trixie's lavapipe (Mesa 25.0.7,
# LLVM 19) wrote the same bytes as Debian 12's (Mesa 22.3.6, LLVM 15) for direct, bdpt and
# hybrid, here and at the demo's full 640x360 (frames 0-2). A later Mesa that rounds differently
# fails this with the compare figures printed; then decide from them, do not loosen it blindly.

for i in $INTEGRATORS; do
    if out=$(same_files "$T/out-host" "$T/out-regular" "$i"); then
        ok "$i: the tarball on this host (Debian 12) = the regular build, bit for bit"
    else
        not_ok "$i: the tarball on this host (Debian 12) = the regular build, bit for bit" "$out"
    fi
    if out=$(same_files "$ct/out" "$T/out-regular" "$i"); then
        ok "$i: the tarball in $SUITE = the regular build on Debian 12, bit for bit"
    else
        not_ok "$i: the tarball in $SUITE = the regular build on Debian 12, bit for bit" "$out"
    fi
done

# ---- no Vulkan loader at all -----------------------------------------------------------------

nt=$(mktemp -d "$NOLOADER/tmp/raybundle-dist.XXXXXX")
chroot_tmps="$chroot_tmps $nt"
nin=${nt#"$NOLOADER"}
# The precondition, so the check below cannot pass by accident on a system that has one.
if in_chroot "$NOLOADER" sh -c 'ldconfig -p | grep -q libvulkan.so.1 ||
        ls /lib/*/libvulkan.so.1 /usr/lib/*/libvulkan.so.1 >/dev/null 2>&1'; then
    not_ok "the -noloader chroot has no libvulkan.so.1"
elif ! xz -dc "$tarball" | in_chroot "$NOLOADER" tar -x -C "$nin"; then
    not_ok "tarball unpacks in the -noloader chroot"
else
    in_chroot "$NOLOADER" "$nin/$name/bin/raybundle" info >"$T/noloader.out" 2>"$T/noloader.err"
    status=$?
    if [ "$status" -eq 3 ] && grep -q 'no Vulkan loader (libvulkan.so.1) on this machine; install' \
        "$T/noloader.err" && [ ! -s "$T/noloader.out" ]; then
        ok "no Vulkan loader: the launcher exits 3 and names libvulkan1"
    else
        not_ok "no Vulkan loader: the launcher exits 3 and names libvulkan1 (exit $status)" \
            "stdout: $(head -c 500 "$T/noloader.out")" "stderr: $(head -c 1000 "$T/noloader.err")"
    fi
fi

finish
