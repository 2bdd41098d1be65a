#!/bin/sh
# make lint: man pages (mandoc and man warnings), and the module include rules of STYLE.md:
# data flows job -> scene -> passes (on gpu) -> integrators -> render (the run: integrators or
# reference, then io), io beside; the CPU reference sits below integrators, whose hybrid bakes
# light with it (it includes none of them); nothing includes
# another module's private _int.h header.
set -u
status=0
for page in man/*.1 man/*.5; do
    out=$(mandoc -T lint -W warning "$page" 2>&1) || status=1
    [ -n "$out" ] && { echo "$out"; status=1; }
    out=$(man --warnings -E UTF-8 -l -Tutf8 -Z "$page" 2>&1 >/dev/null)
    [ -n "$out" ] && { echo "$page: $out"; status=1; }
done

allowed() { # module -> modules it may include
    case $1 in
    core) echo "core" ;;
    job | gpu | io | bvh) echo "core $1" ;;
    reference) echo "core job scene reference" ;;
    scene) echo "core job scene" ;;
    passes) echo "core gpu scene job bvh passes" ;;
    integrators) echo "core gpu scene job bvh passes reference integrators" ;;
    analysis) echo "core io analysis" ;;
    render) echo "core gpu scene job integrators reference io render" ;;
    *) echo "" ;;
    esac
}
for f in lib/*/*.c lib/*/*.cpp lib/*/*.h; do
    mod=$(echo "$f" | cut -d/ -f2)
    ok=$(allowed "$mod")
    incs=$(sed -n 's/^#include "\([a-z_]*\)\/[a-z_.]*".*/\1/p' "$f")
    for inc in $incs; do
        case " $ok " in
        *" $inc "*) ;;
        *) echo "$f: module '$mod' may not include '$inc'"; status=1 ;;
        esac
    done
    for inc in $(sed -n 's/^#include "\([a-z_]*\)\/[a-z_]*_int\.h"/\1/p' "$f"); do
        [ "$inc" = "$mod" ] || { echo "$f: includes $inc's private header"; status=1; }
    done
done
for f in cmd/*.c; do
    if grep -q '^#include "[a-z_]*/[a-z_]*_int\.h"' "$f"; then
        echo "$f: includes a private header"
        status=1
    fi
done
# Formatting: .clang-format, as `make format` applies it.
if [ -z "${FORMAT_SRC:-}" ]; then
    FORMAT_SRC=$(ls lib/*/*.c lib/*/*.cpp lib/*/*.h cmd/*.c cmd/*.h tests/unit/*.c tests/tools/*.c tests/fuzz/*.c \
        tools/mkdemo.c tools/ltcfit.c 2>/dev/null)
fi
# shellcheck disable=SC2086
if ! out=$(clang-format --dry-run --Werror $FORMAT_SRC 2>&1); then
    echo "$out" | grep 'error:' | head -n 20
    echo "lint: run 'make format'"
    status=1
fi
[ $status -eq 0 ] && echo "lint: clean"
exit $status
