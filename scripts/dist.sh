#!/bin/sh
# Makes the portable tarball of a built raybundle, one that runs on any recent x86-64 Linux with
# a Vulkan loader and driver: scripts/dist.sh BINARY OUTDIR VERSION writes
# OUTDIR/raybundle-VERSION-linux-x86_64.tar.xz (make dist calls it on a build with OIIO=0).
#
# The tarball holds one folder, raybundle-VERSION-linux-x86_64/:
#   bin/raybundle       a sh launcher: checks for the host's Vulkan loader, then runs libexec/
#   libexec/raybundle   the binary, its RUNPATH set to $ORIGIN/../lib
#   lib/                the shared libraries it needs that a host cannot be expected to have,
#                       under their SONAMEs, each with RUNPATH $ORIGIN (RUNPATH is not inherited
#                       by a library's own dependencies, so each one needs its own)
#   share/raybundle/ocio/config.ocio, share/man/, share/doc/raybundle/ (README, licenses)
#
# Left to the host: glibc, the C++ runtime, and every library a host Vulkan driver (Mesa's
# lavapipe, radv, anv; NVIDIA's) loads too. Bundling one of those would shadow the host's copy
# by SONAME inside the driver as well: a bundled Debian 12 libstdc++ made trixie's lavapipe fail
# with VK_ERROR_INITIALIZATION_FAILED, as Mesa 25 needs GLIBCXX_3.4.31.
#
# Deterministic for the same inputs: sorted names, owner 0, every mtime SOURCE_DATE_EPOCH (or the
# last commit's time), single-threaded xz. Fails, writing nothing, when a needed library is not
# found, when the binary cannot be given its RUNPATH, or when the tarball is over 48 MiB
# (RB_DIST_MAX_MIB overrides the limit, to look at an oversized bundle while developing).
set -eu

ARCH=x86_64
MAX_MIB=${RB_DIST_MAX_MIB:-48}
# xz -6 -T1. Measured on the OIIO=0 build (62 MiB unpacked), two cores: -6 gives 13.05 MiB in
# 26 s for the whole script, -9 12.84 MiB in 31 s and seven times the memory. -T1 because
# multi-threaded xz splits the stream into blocks by thread count: other bytes elsewhere.
XZ_LEVEL=${RB_DIST_XZ_LEVEL:--6}

die() {
    echo "dist: error: $*" >&2
    exit 1
}

if [ $# -ne 3 ]; then
    echo "usage: scripts/dist.sh BINARY OUTDIR VERSION" >&2
    exit 2
fi
bin=$1
outdir=$2
version=$3
case $version in
'' | */* | *[[:space:]]*) die "version '$version' must be non-empty, without '/' or spaces" ;;
esac
case $MAX_MIB in
'' | *[!0-9]*) die "RB_DIST_MAX_MIB '$MAX_MIB' is not a whole number of MiB" ;;
esac

root=$(cd "$(dirname "$0")/.." && pwd)
name=raybundle-$version-linux-$ARCH
tarball=$outdir/$name.tar.xz

for tool in readelf patchelf tar xz dpkg dpkg-query; do
    command -v "$tool" >/dev/null 2>&1 ||
        die "'$tool' not found (scripts/install-deps.sh installs binutils, patchelf, xz-utils)"
done

[ -f "$bin" ] || die "binary '$bin' not found"
if ! readelf -h "$bin" >/dev/null 2>&1; then
    die "'$bin' is not an ELF file"
fi
readelf -h "$bin" | grep -q 'Machine:.*X86-64' || die "'$bin' is not an x86-64 binary"
# A binary without a dynamic section has no RUNPATH to set (and raybundle cannot be static: the
# Vulkan loader is always the host's).
readelf -d "$bin" | grep -q '(NEEDED)' || die "'$bin' is not dynamically linked: no RUNPATH fix-up possible"

work=$(mktemp -d "${TMPDIR:-/tmp}/raybundle-dist.XXXXXX")
trap 'rm -rf "$work"' EXIT
trap 'exit 130' INT TERM
stage=$work/$name

# ---- the library closure -------------------------------------------------------------------

# is_host_lib SONAME: a library the host must provide. glibc's own; the C++ runtime; the Vulkan
# loader; and what Mesa's and NVIDIA's drivers load themselves (ldd libvulkan_lvp.so): a bundled
# copy would be found first, by SONAME, by the driver too.
is_host_lib() {
    case $1 in
    libc.so.* | libm.so.* | libmvec.so.* | libpthread.so.* | libdl.so.* | librt.so.* | \
        libutil.so.* | libresolv.so.* | libanl.so.* | libnsl.so.* | libnss_* | \
        libthread_db.so.* | libBrokenLocale.so.* | libc_malloc_debug.so.* | ld-linux*) return 0 ;;
    libstdc++.so.* | libgcc_s.so.* | libvulkan.so.*) return 0 ;;
    libz.so.* | libzstd.so.* | liblzma.so.* | libexpat.so.* | libdrm* | libLLVM* | libz3.so.* | \
        libxml2.so.* | libffi.so.* | libX* | libxcb* | libxshmfence* | libwayland* | \
        libelf.so.* | libsensors.so.* | libtinfo.so.* | libedit.so.* | libbsd.so.* | \
        libmd.so.* | libicu*) return 0 ;;
    esac
    return 1
}

# dlopened SONAME: libraries a bundled one loads with dlopen, so no DT_NEEDED names them. oneTBB
# loads its scalable allocator from its own directory when present (LD_DEBUG=files on a reference
# render); bundling it keeps the tarball's binary running as the regular build does.
dlopened() {
    case $1 in
    libtbb.so.*) echo libtbbmalloc.so.2 ;;
    esac
}

needed() { # needed FILE: its DT_NEEDED names
    readelf -d "$1" | sed -n 's/^.*(NEEDED).*\[\(.*\)\]$/\1/p'
}

# The linker cache, as "SONAME PATH" lines, 64-bit x86 entries only.
ldconfig_bin=
for l in ldconfig /sbin/ldconfig /usr/sbin/ldconfig; do
    if "$l" -p >/dev/null 2>&1; then
        ldconfig_bin=$l
        break
    fi
done
[ -n "$ldconfig_bin" ] || die "ldconfig not found (tried PATH, /sbin, /usr/sbin)"
"$ldconfig_bin" -p | sed -n 's/^[[:space:]]*\([^ ]*\) (libc6,x86-64[^)]*) => \(.*\)$/\1 \2/p' \
    >"$work/ldcache"

# resolve SONAME REQUESTER: the file the dynamic loader would use. The requester's own RPATH or
# RUNPATH ($ORIGIN expanded), then the linker cache, then the default directories.
resolve() {
    origin=$(dirname "$(readlink -f "$2")")
    dirs=$(readelf -d "$2" | sed -n 's/^.*(R[UN]*PATH).*\[\(.*\)\]$/\1/p' | tr ':' ' ')
    for d in $dirs; do
        d=$(echo "$d" | sed "s|\\\$ORIGIN|$origin|; s|\\\${ORIGIN}|$origin|")
        [ -f "$d/$1" ] && { echo "$d/$1"; return 0; }
    done
    p=$(awk -v n="$1" '$1 == n { print $2; exit }' "$work/ldcache")
    [ -n "$p" ] && [ -f "$p" ] && { echo "$p"; return 0; }
    for d in /lib/$ARCH-linux-gnu /usr/lib/$ARCH-linux-gnu /lib64 /usr/lib64 /lib /usr/lib; do
        if [ -f "$d/$1" ] && readelf -h "$d/$1" 2>/dev/null | grep -q 'Machine:.*X86-64'; then
            echo "$d/$1"
            return 0
        fi
    done
    return 1
}

# Breadth-first over DT_NEEDED from the binary. "todo" holds "SONAME FILE" lines still to read.
: >"$work/seen"
: >"$work/bundle"
: >"$work/host"
printf -- '- %s\n' "$bin" >"$work/todo"
while [ -s "$work/todo" ]; do
    read -r soname file <"$work/todo"
    tail -n +2 "$work/todo" >"$work/todo.next" && mv "$work/todo.next" "$work/todo"
    for so in $(needed "$file") $(dlopened "$soname"); do
        grep -qxF "$so" "$work/seen" && continue
        echo "$so" >>"$work/seen"
        if is_host_lib "$so"; then
            echo "$so" >>"$work/host"
            continue
        fi
        path=$(resolve "$so" "$file") ||
            die "library '$so' (needed by '$(basename "$file")') not found on this machine"
        echo "$so $path" >>"$work/bundle"
        echo "$so $path" >>"$work/todo"
    done
done
LC_ALL=C sort -o "$work/bundle" "$work/bundle"
LC_ALL=C sort -o "$work/host" "$work/host"

# ---- the tree ------------------------------------------------------------------------------

umask 022
mkdir -p "$stage/bin" "$stage/libexec" "$stage/lib" "$stage/share/raybundle/ocio" \
    "$stage/share/man/man1" "$stage/share/man/man5" "$stage/share/doc/raybundle/licenses"

cp "$bin" "$stage/libexec/raybundle"
chmod 0755 "$stage/libexec/raybundle"
patchelf --set-rpath '$ORIGIN/../lib' "$stage/libexec/raybundle" ||
    die "patchelf cannot set the RUNPATH of '$bin'"

while read -r so path; do
    cp -L "$path" "$stage/lib/$so"
    chmod 0644 "$stage/lib/$so"
    patchelf --set-rpath '$ORIGIN' "$stage/lib/$so" ||
        die "patchelf cannot set the RUNPATH of '$path'"
done <"$work/bundle"

# Every ELF file must now search the bundle by RUNPATH, not RPATH (which would also apply to its
# dependencies and outrank LD_LIBRARY_PATH), and the binary must find lib/ from libexec/.
runpath() { readelf -d "$1" | sed -n 's/^.*(RUNPATH).*\[\(.*\)\]$/\1/p'; }
[ "$(runpath "$stage/libexec/raybundle")" = '$ORIGIN/../lib' ] ||
    die "'$bin': RUNPATH is '$(runpath "$stage/libexec/raybundle")' after patchelf, want \$ORIGIN/../lib"
for f in "$stage/libexec/raybundle" "$stage"/lib/*; do
    [ -e "$f" ] || continue
    if readelf -d "$f" | grep -q '(RPATH)'; then
        die "'$f' still has a DT_RPATH after patchelf"
    fi
done
while read -r so path; do
    [ "$(runpath "$stage/lib/$so")" = '$ORIGIN' ] ||
        die "'$so': RUNPATH is '$(runpath "$stage/lib/$so")' after patchelf, want \$ORIGIN"
done <"$work/bundle"

# The launcher. POSIX sh, as it must run before anything is known about the host.
cat >"$stage/bin/raybundle" <<'EOF'
#!/bin/sh
# raybundle's launcher in the portable tarball. The one thing the tarball cannot carry is the
# Vulkan loader (it has to be the host's, which knows the host's drivers), so this checks for it
# and says what to install, then runs ../libexec/raybundle, which finds its bundled libraries
# through its RUNPATH ($ORIGIN/../lib) and its colour config through /proc/self/exe.
set -eu

# The real location, through any symlink (say ~/bin/raybundle -> .../bin/raybundle).
self=$(readlink -f -- "$0")
top=$(dirname -- "$(dirname -- "$self")")

has_vulkan_loader() {
    for ldconfig in ldconfig /sbin/ldconfig /usr/sbin/ldconfig; do
        if cache=$("$ldconfig" -p 2>/dev/null); then
            case $cache in *"libvulkan.so.1 (libc6,x86-64"*) return 0 ;; esac
            break
        fi
    done
    # No ldconfig to ask, or a cache that lacks it: the dynamic loader also searches the default
    # directories, and the user's own LD_LIBRARY_PATH (read here, never set).
    dirs=$(printf '%s' "${LD_LIBRARY_PATH:-}" | tr ':' ' ')
    for dir in $dirs /lib/x86_64-linux-gnu /usr/lib/x86_64-linux-gnu /lib64 /usr/lib64 /lib /usr/lib; do
        [ -e "$dir/libvulkan.so.1" ] && return 0
    done
    return 1
}

if ! has_vulkan_loader; then
    echo "raybundle: no Vulkan loader (libvulkan.so.1) on this machine; install your distribution's Vulkan loader package (Debian/Ubuntu: libvulkan1) and a Vulkan driver (e.g. mesa-vulkan-drivers for lavapipe, or your GPU vendor's)" >&2
    exit 3 # raybundle's own code for "no usable device"
fi
# The dynamic loader expands the binary's $ORIGIN through /proc/self/exe, as raybundle finds its
# data; without /proc (a bare chroot) all it would say is that some library is missing.
if [ ! -e /proc/self/exe ]; then
    echo "raybundle: /proc is not mounted; raybundle finds its libraries and data through /proc/self/exe (mount -t proc proc /proc)" >&2
    exit 1
fi
exec "$top/libexec/raybundle" "$@"
EOF
chmod 0755 "$stage/bin/raybundle"

cp "$root/share/ocio/config.ocio" "$stage/share/raybundle/ocio/config.ocio"
for m in "$root"/man/*.1; do cp "$m" "$stage/share/man/man1/"; done
for m in "$root"/man/*.5; do cp "$m" "$stage/share/man/man5/"; done
cp "$root/README.md" "$stage/share/doc/raybundle/README.md"
for f in LICENSE LICENSE.md COPYING; do
    [ -f "$root/$f" ] && cp "$root/$f" "$stage/share/doc/raybundle/$f"
done

# Licenses: each bundled library's Debian copyright file, by the package that owns it, and a
# list of which library came from which package version.
owner() { # owner PATH: the Debian package that installed PATH (with or without /usr merged)
    for p in "$1" "$(readlink -f "$1")"; do
        for q in "$p" "/usr$p" "${p#/usr}"; do
            pkg=$(dpkg -S "$q" 2>/dev/null | sed -n '1s/^\([^:,]*\).*: .*$/\1/p')
            [ -n "$pkg" ] && { echo "$pkg"; return 0; }
        done
    done
    return 1
}
: >"$work/libraries"
while read -r so path; do
    pkg=$(owner "$path") || die "'$path' ($so) belongs to no Debian package: its license is unknown"
    copyright=/usr/share/doc/$pkg/copyright
    [ -f "$copyright" ] || die "'$so': '$copyright' not found (package $pkg)"
    mkdir -p "$stage/share/doc/raybundle/licenses/$pkg"
    cp -L "$copyright" "$stage/share/doc/raybundle/licenses/$pkg/copyright"
    printf '%s %s %s\n' "$so" "$pkg" "$(dpkg-query -W -f='${Version}' "$pkg")" >>"$work/libraries"
done <"$work/bundle"
cp "$work/libraries" "$stage/share/doc/raybundle/licenses/LIBRARIES"

# The newest glibc and libstdc++ symbol versions anything in the bundle asks for: the host needs
# at least these (glibc's and GCC's, not Debian's, version numbers).
newest() { # newest PREFIX: the highest PREFIX<version> any ELF file here requires
    for f in "$stage/libexec/raybundle" "$stage"/lib/*; do
        readelf -V "$f" 2>/dev/null
    done | sed -n "s/^.*Name: $1\([0-9.]*\).*$/\1/p" | sort -uV | tail -n 1
}
glibc=$(newest GLIBC_)
glibcxx=$(newest GLIBCXX_)
case $glibcxx in # the GCC release that first shipped each (libstdc++'s ABI policy)
3.4.26) gcc=9 ;;
3.4.28) gcc=10 ;;
3.4.29) gcc=11 ;;
3.4.30) gcc=12 ;;
3.4.31) gcc=13.1 ;;
3.4.32) gcc=13.2 ;;
3.4.33) gcc=14 ;;
*) gcc="" ;;
esac
# shellcheck source=/dev/null
built_on="$(. /etc/os-release 2>/dev/null && echo "${PRETTY_NAME:-}")"
built_on="${built_on:-Linux}, $(getconf GNU_LIBC_VERSION 2>/dev/null || echo 'glibc ?')"
libstdcxx="libstdc++ with GLIBCXX_$glibcxx"
[ -n "$gcc" ] && libstdcxx="$libstdcxx (GCC $gcc's or newer)"

{
    cat <<EOF
raybundle $version for x86-64 Linux: a portable build

Run bin/raybundle (a symlink to it anywhere works), e.g.

    bin/raybundle info
    bin/raybundle render job.yaml --out out/

The manual pages are in share/man (man -l share/man/man1/raybundle.1); the project's README is
share/doc/raybundle/README.md.

What the host must have (the libraries left out are those a Vulkan driver loads too, so that
the driver and raybundle share one copy):
- glibc $glibc or newer
- $libstdcxx, and libgcc_s
- zlib and expat
- a Vulkan loader, libvulkan.so.1 (Debian/Ubuntu: libvulkan1), and a Vulkan driver
  (mesa-vulkan-drivers for lavapipe, which renders on the CPU, or the GPU vendor's)
- /proc mounted: the binary finds lib/ and share/ through /proc/self/exe

Those versions are the newest symbol versions anything here uses.
Built on $built_on; the source tree's make check-dist runs it there and in a
Debian 13 chroot. bin/raybundle says what to install, and exits 3, when the Vulkan loader is
missing.

Libraries in lib/ (the Debian 12 packages they came from; their copyright files are in
share/doc/raybundle/licenses/):
EOF
    sed 's/^/    /' "$work/libraries"
    echo
    echo "Left to the host: $(tr '\n' ' ' <"$work/host" | sed 's/ $//')"
} >"$stage/README"

# ---- the tarball ---------------------------------------------------------------------------

if [ -n "${SOURCE_DATE_EPOCH:-}" ]; then
    mtime=$SOURCE_DATE_EPOCH
elif mtime=$(git -C "$root" log -1 --format=%ct 2>/dev/null) && [ -n "$mtime" ]; then
    :
else
    mtime=$(stat -c %Y "$bin")
    echo "dist: no SOURCE_DATE_EPOCH and no git history: dating files by the binary" >&2
fi

echo "dist: bundled libraries:"
while read -r so path; do
    printf '  %-28s %6s KiB  %s\n' "$so" "$(($(stat -c %s "$stage/lib/$so") / 1024))" "$path"
done <"$work/bundle"
echo "dist: left to the host: $(tr '\n' ' ' <"$work/host")"
echo "dist: the host needs glibc >= $glibc, GLIBCXX >= $glibcxx${gcc:+ (GCC $gcc)}"
echo "dist: $(du -sk "$stage" | cut -f1) KiB unpacked, compressing (xz $XZ_LEVEL)"

mkdir -p "$outdir"
tmp=$outdir/.$name.tar.xz.tmp.$$
trap 'rm -rf "$work" "$tmp"' EXIT
max_bytes=$((MAX_MIB * 1024 * 1024))
# head stops reading one byte past the limit, so an oversized bundle fails without being
# compressed whole. No pipefail in sh: each stage records its own failure.
{
    (cd "$work" && find "$name" -print0 | LC_ALL=C sort -z |
        tar --create --no-recursion --null --files-from=- --format=gnu --owner=0 --group=0 \
            --numeric-owner --mtime="@$mtime" --mode='u+rw,go-w,go+rX') ||
        echo tar >>"$work/failed"
} | { xz -T1 "$XZ_LEVEL" -c || echo xz >>"$work/failed"; } |
    head -c $((max_bytes + 1)) >"$tmp"
size=$(stat -c %s "$tmp")
if [ "$size" -gt "$max_bytes" ]; then
    die "'$tarball' would be over $MAX_MIB MiB (the bundle is $(du -sm "$stage" | cut -f1) MiB unpacked); nothing written"
fi
[ -s "$work/failed" ] && die "$(tr '\n' ' ' <"$work/failed")failed while writing '$tarball'"
xz -t "$tmp" || die "'$tmp' does not decompress"
mv "$tmp" "$tarball"
echo "dist: wrote $tarball ($((size / 1024)) KiB)"
