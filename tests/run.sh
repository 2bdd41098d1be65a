#!/bin/sh
# Runs every test: the cmocka unit programs (TAP) and the integration scripts (TAP), or only the
# TAP scripts named as arguments, then prints the total as the last line: "N passed, N failed".
# Tests run with the Khronos validation layer (RB_VALIDATE=1): a validation message fails them.
set -u
BUILD=${BUILD:-build}
export BUILD
export RB_VALIDATE=1
export RB_SCENES="${RB_SCENES:-$(cd .. && pwd)/shared/scenes}"
TMPDIR=$(mktemp -d "${TMPDIR:-/tmp}/raybundle-test.XXXXXX")
export TMPDIR
export MESA_SHADER_CACHE_DIR="$TMPDIR/mesa-cache"
trap 'rm -rf "$TMPDIR"' EXIT INT TERM

passed=0
failed=0
skipped=0
failures=""

# run NAME COMMAND...: runs one TAP producer and adds up its ok / not ok lines.
run() {
    name=$1
    shift
    log="$TMPDIR/$(basename "$name").log"
    "$@" >"$log" 2>&1
    status=$?
    # A skip is "ok N - ... # SKIP why" (TAP), or "not ok N # SKIP name" (cmocka 1.1's TAP).
    s=$(grep -cE '^(not )?ok .*# SKIP' "$log")
    p=$(($(grep -c '^ok ' "$log") - $(grep -c '^ok .*# SKIP' "$log")))
    f=$(($(grep -c '^not ok ' "$log") - $(grep -c '^not ok .*# SKIP' "$log")))
    if [ "$status" -ne 0 ] && [ "$f" -eq 0 ]; then
        f=1
        echo "not ok - $name exited with status $status" >>"$log"
    fi
    passed=$((passed + p))
    skipped=$((skipped + s))
    failed=$((failed + f))
    if [ "$f" -ne 0 ]; then
        failures="$failures $name"
        echo "FAIL $name ($p passed, $f failed)"
        grep -v '^ok ' "$log" | grep -v '# SKIP' | sed 's/^/    /' | tail -n 60
    else
        if [ "$s" -gt 0 ]; then
            echo "ok   $name ($p passed, $s skipped)"
        else
            echo "ok   $name ($p passed)"
        fi
    fi
}

if [ $# -gt 0 ]; then # the scripts named (make check-farm)
    for t in "$@"; do
        run "$t" sh "$t"
    done
else
    for t in "$BUILD"/tests/test_*; do
        [ -x "$t" ] || continue
        CMOCKA_MESSAGE_OUTPUT=TAP run "$t" "$t"
    done
    for t in tests/integration/t[0-9]*.sh; do
        [ -f "$t" ] || continue
        run "$t" sh "$t"
    done
fi

[ -n "$failures" ] && echo "failed:$failures"
if [ "$skipped" -gt 0 ]; then
    echo "$passed passed, $failed failed, $skipped skipped"
else
    echo "$passed passed, $failed failed"
fi
[ "$failed" -eq 0 ]
