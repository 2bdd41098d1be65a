#!/bin/sh
# The demo scene (jobs/demo/room.gltf + room.bin) is what tools/mkdemo.c generates, byte for
# byte, every run; and it holds the objects the demo jobs rely on. Prints TAP.
# Run from the repository root; BUILD names the build directory (default "build").
# RB_TEST_NO_PYTHON=1 forces the grep-only checks that run where python3 is missing.

BUILD=${BUILD:-build}
MKDEMO=$BUILD/mkdemo
SCENE=jobs/demo
failed=0
n=0

tmp=$(mktemp -d "${TMPDIR:-/tmp}/t0100.XXXXXX") || {
    echo "1..0 # cannot create a temporary directory"
    exit 1
}
trap 'rm -rf "$tmp"' EXIT
trap 'exit 1' HUP INT TERM

ok()
{
    n=$((n + 1))
    echo "ok $n - $1"
}

not_ok()
{
    n=$((n + 1))
    failed=$((failed + 1))
    echo "not ok $n - $1"
    shift
    # Every diagnostic line starts with '#', multi-line messages included, to keep TAP valid.
    [ $# -eq 0 ] || printf '%s\n' "$@" | sed 's/^/#   /'
}

# check DESCRIPTION COMMAND...: ok if COMMAND succeeds, else its output is the diagnostic.
check()
{
    desc=$1
    shift
    if out=$("$@" 2>&1); then
        ok "$desc"
    else
        not_ok "$desc" "$out"
    fi
}

have_python=
if [ -z "$RB_TEST_NO_PYTHON" ] && command -v python3 >/dev/null 2>&1; then
    have_python=1
fi

echo "1..7"

mkdir "$tmp/a" "$tmp/b"
if [ ! -x "$MKDEMO" ]; then
    not_ok "mkdemo runs and writes room.gltf and room.bin" \
        "'$MKDEMO' not found: build it first (make BUILD=$BUILD $MKDEMO)"
elif out=$("$MKDEMO" "$tmp/a" 2>&1) && [ -s "$tmp/a/room.gltf" ] && [ -s "$tmp/a/room.bin" ]; then
    ok "mkdemo runs and writes room.gltf and room.bin"
else
    not_ok "mkdemo runs and writes room.gltf and room.bin" "$out"
fi

check "room.gltf matches the committed $SCENE/room.gltf" cmp "$SCENE/room.gltf" "$tmp/a/room.gltf"
check "room.bin matches the committed $SCENE/room.bin" cmp "$SCENE/room.bin" "$tmp/a/room.bin"

if [ -x "$MKDEMO" ] && "$MKDEMO" "$tmp/b" >/dev/null 2>&1 &&
    cmp -s "$tmp/a/room.gltf" "$tmp/b/room.gltf" && cmp -s "$tmp/a/room.bin" "$tmp/b/room.bin"; then
    ok "a second run gives the same bytes"
else
    not_ok "a second run gives the same bytes"
fi

# The remaining checks read the committed scene, which the demo jobs load.
gltf=$SCENE/room.gltf
bin=$SCENE/room.bin

if [ -n "$have_python" ]; then
    check "room.gltf parses as JSON" python3 -c 'import json, sys; json.load(open(sys.argv[1]))' \
        "$gltf"
    check "room.gltf names Camera, Light, SpinningBox, BendingColumn and animation Demo" \
        python3 -c '
import json, sys
g = json.load(open(sys.argv[1]))
nodes = {n.get("name") for n in g.get("nodes", [])}
anims = {a.get("name") for a in g.get("animations", [])}
missing = [n for n in ("Camera", "Light", "SpinningBox", "BendingColumn", "ColumnRoot",
                       "ColumnTip") if n not in nodes]
if "Demo" not in anims:
    missing.append("animation Demo")
if missing:
    sys.exit("missing: " + ", ".join(missing))
' "$gltf"
    check "the buffer byteLength equals the size of room.bin" python3 -c '
import json, os, sys
g = json.load(open(sys.argv[1]))
want, have = g["buffers"][0]["byteLength"], os.path.getsize(sys.argv[2])
if want != have:
    sys.exit("byteLength %d, room.bin has %d bytes" % (want, have))
' "$gltf" "$bin"
else
    # No python3: coarse checks with grep and sed.
    if [ "$(head -c 1 "$gltf")" = "{" ] && [ "$(tail -c 2 "$gltf")" = "}" ]; then
        ok "room.gltf looks like one JSON object (no python3: grep only)"
    else
        not_ok "room.gltf looks like one JSON object (no python3: grep only)"
    fi
    missing=
    for name in Camera Light SpinningBox BendingColumn ColumnRoot ColumnTip Demo; do
        grep -q "\"name\": *\"$name\"" "$gltf" || missing="$missing $name"
    done
    if [ -z "$missing" ]; then
        ok "room.gltf names Camera, Light, SpinningBox, BendingColumn and animation Demo"
    else
        not_ok "room.gltf names Camera, Light, SpinningBox, BendingColumn and animation Demo" \
            "missing:$missing"
    fi
    want=$(sed -n 's/.*"byteLength": *\([0-9]*\) *}\]$/\1/p' "$gltf")
    have=$(wc -c <"$bin" | tr -d ' ')
    if [ -n "$want" ] && [ "$want" = "$have" ]; then
        ok "the buffer byteLength equals the size of room.bin"
    else
        not_ok "the buffer byteLength equals the size of room.bin" \
            "byteLength '$want', room.bin has $have bytes"
    fi
fi

[ "$failed" -eq 0 ]
