#!/bin/sh
# make lint as a test: man pages clean under mandoc and man, module include rules, formatting.
. tests/integration/lib.sh
if sh tests/lint.sh >"$T/lint" 2>&1; then
    ok "lint is clean"
else
    not_ok "lint is clean" "$(head -n 30 "$T/lint")"
fi
done_testing
