# Shared helpers for the integration scripts (sourced). Each script prints TAP; run from the
# repository root with BUILD set. rb runs the renderer and keeps its status, stdout and stderr.
set -u
. tests/still-demo.sh
. tests/classic-cornell.sh
BUILD=${BUILD:-build}
RB="$BUILD/raybundle"
T=$(mktemp -d "${TMPDIR:-/tmp}/rbt.XXXXXX")
trap 'rm -rf "$T"' EXIT
n=0
nfail=0
# The external sample scenes (../shared/scenes beside a checkout, $RB_SCENES in CI). A fresh
# clone without them still passes: tests that need them report themselves skipped.
SCENES=${RB_SCENES:-../shared/scenes}

ok() {
    n=$((n + 1))
    echo "ok $n - $1"
}

not_ok() {
    n=$((n + 1))
    nfail=$((nfail + 1))
    echo "not ok $n - $1"
    shift
    for line in "$@"; do echo "#   $line"; done
}

check() { # check DESCRIPTION COMMAND...
    d=$1
    shift
    if "$@"; then ok "$d"; else not_ok "$d"; fi
}

rb() {
    "$RB" "$@" >"$T/stdout" 2>"$T/stderr"
    status=$?
}

expect_exit() { # expect_exit CODE DESCRIPTION (after rb)
    if [ "$status" -eq "$1" ]; then
        ok "$2"
    else
        not_ok "$2" "exit $status, want $1" "stderr: $(head -c 2000 "$T/stderr")"
    fi
}

stderr_has() { # stderr_has TEXT DESCRIPTION
    if grep -qF -- "$1" "$T/stderr"; then
        ok "$2"
    else
        not_ok "$2" "stderr lacks '$1'" "stderr: $(head -c 2000 "$T/stderr")"
    fi
}

stdout_has() { # stdout_has REGEX DESCRIPTION (grep's basic regular expression)
    if grep -q -- "$1" "$T/stdout"; then
        ok "$2"
    else
        not_ok "$2" "stdout lacks /$1/" "stdout: $(head -c 3000 "$T/stdout")"
    fi
}

# bad_option MESSAGE OPTION...: rendering the demo with OPTION... exits 2, says MESSAGE on
# stderr, and writes nothing (the output directory is not even created).
bad_option() {
    msg=$1
    shift
    rb render jobs/demo.yaml --out "$T/never" -q "$@"
    expect_exit 2 "$* exits 2"
    stderr_has "$msg" "$*: explained"
    check "$*: nothing written" test ! -e "$T/never"
}

# tap_run COMMAND...: runs another TAP producer and renumbers its lines into this script's
# count; a non-zero exit without a failing line is a failure of its own.
tap_run() {
    "$@" >"$T/tap" 2>&1
    tap_status=$?
    before=$nfail
    while IFS= read -r line; do
        case $line in
        "ok "*) ok "${line#ok [0-9]* - }" ;;
        "not ok "*) not_ok "${line#not ok [0-9]* - }" ;;
        "1.."*) ;;
        *) echo "# $line" ;;
        esac
    done <"$T/tap"
    if [ "$tap_status" -ne 0 ] && [ "$nfail" -eq "$before" ]; then
        not_ok "$* exited with status $tap_status"
    fi
}

skip() { # skip DESCRIPTION REASON: a test that cannot apply here, counted apart
    n=$((n + 1))
    echo "ok $n - $1 # SKIP $2"
}

# have_scene REL: the external scene file exists (under $SCENES).
have_scene() {
    [ -f "$SCENES/$1" ]
}

# floor_panel_gltf FILE NODES [TEXTURE]: a glTF of a floor (Lambertian, white, 2 x 2 m at y 0)
# and a 0.5 m panel 1 m above it whose material emits 1 (times the image TEXTURE when given),
# the scene holding the nodes NODES ([0] the floor alone, [0, 1] both).
floor_panel_gltf() {
    images="" glow=""
    if [ -n "${3:-}" ]; then
        images=' "images": [{"uri": "'"$3"'"}], "textures": [{"source": 0}],
'
        glow=' "emissiveTexture": {"index": 0},'
    fi
    cat >"$1" <<GLTF
{"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": $2}],
 "nodes": [{"name": "Floor", "mesh": 0}, {"name": "Panel", "mesh": 1}],
$images"meshes": [{"name": "Floor", "primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2, "material": 0}]},
            {"name": "Panel", "primitives": [{"attributes": {"POSITION": 3, "NORMAL": 4}, "indices": 5, "material": 1}]}],
 "materials": [{"name": "White", "doubleSided": true, "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1], "metallicFactor": 0, "roughnessFactor": 1}},
               {"name": "Glow", "doubleSided": true, "emissiveFactor": [1, 1, 1],$glow "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0}}],
 "buffers": [{"byteLength": 216, "uri": "data:application/octet-stream;base64,AACAvwAAAAAAAIC/AACAPwAAAAAAAIC/AACAPwAAAAAAAIA/AACAvwAAAAAAAIA/AAAAAAAAgD8AAAAAAAAAAAAAgD8AAAAAAAAAAAAAgD8AAAAAAAAAAAAAgD8AAAAAAAACAAEAAAADAAIAAACAvgAAgD8AAIC+AACAPgAAgD8AAIC+AACAPgAAgD8AAIA+AACAvgAAgD8AAIA+AAAAAAAAgL8AAAAAAAAAAAAAgL8AAAAAAAAAAAAAgL8AAAAAAAAAAAAAgL8AAAAAAAABAAIAAAACAAMA"}],
 "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 48},
                 {"buffer": 0, "byteOffset": 96, "byteLength": 12}, {"buffer": 0, "byteOffset": 108, "byteLength": 48},
                 {"buffer": 0, "byteOffset": 156, "byteLength": 48}, {"buffer": 0, "byteOffset": 204, "byteLength": 12}],
 "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, 0, -1], "max": [1, 0, 1]},
               {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
               {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"},
               {"bufferView": 3, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-0.25, 1, -0.25], "max": [0.25, 1, 0.25]},
               {"bufferView": 4, "componentType": 5126, "count": 4, "type": "VEC3"},
               {"bufferView": 5, "componentType": 5123, "count": 6, "type": "SCALAR"}]}
GLTF
}

# relmse A B [LAYER]: raybundle compare's relMSE of A against B (LAYER's, or the beauty's).
relmse() {
    "$RB" compare "$1" "$2" ${3:+--layer "$3"} --json |
        sed -n 's/.*"relmse": \([0-9.e+-]*\).*/\1/p' | head -n 1
}

# late_chunk_same JOB LAST WHAT [ARGS...]: the frames LAST-4 to LAST rendered alone on one
# thread have the bits of the same frames of a whole run 0-LAST on four (checked at LAST-4, LAST-2
# and LAST): a chunk's warm-up rebuilds all the state its frames read. WHAT names the shot.
late_chunk_same() {
    _job=$1 _last=$2 _what=$3
    shift 3
    _first=$((_last - 4))
    LP_NUM_THREADS=4 rb render "$_job" -q "$@" --frames "0-$_last" --out "$T/whole"
    expect_exit 0 "frames 0-$_last of $_what"
    LP_NUM_THREADS=1 rb render "$_job" -q "$@" --frames "$_first-$_last" --out "$T/late"
    expect_exit 0 "the chunk $_first-$_last alone, on one thread"
    for _f in "$_first" $((_first + 2)) "$_last"; do
        _name=$(printf 'frame.%04d.exr' "$_f")
        check "frame $_f of the late chunk has the whole run's bits (1 and 4 threads)" \
            cmp -s "$T/whole/$_name" "$T/late/$_name"
    done
}

fail_all() {
    not_ok "$1"
    done_testing
}

done_testing() {
    echo "1..$n"
    [ "$nfail" -eq 0 ] && exit 0
    exit 1
}
