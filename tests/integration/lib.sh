# Shared helpers for the integration scripts (sourced). Each script prints TAP; run from the
# repository root with BUILD set. rb runs the renderer and keeps its status, stdout and stderr.
set -u
. tests/still-demo.sh
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

fail_all() {
    not_ok "$1"
    done_testing
}

done_testing() {
    echo "1..$n"
    [ "$nfail" -eq 0 ] && exit 0
    exit 1
}
