#!/bin/sh
# make bench's scale figures (tests/bench-scale.sh) in their quick mode: the script runs to the
# end and prints its table, a row for each integrator and scene, each figure a number. The
# figures themselves are measurements and are never checked.
. tests/integration/lib.sh

RB_BENCH_QUICK=1 RB_BENCH_10M=0 sh tests/bench-scale.sh >"$T/stdout" 2>"$T/stderr"
status=$?
expect_exit 0 "the scale bench's quick mode exits 0, without 10 M"
check "it writes nothing on stderr" test ! -s "$T/stderr"
x='[0-9][0-9.]*'
stdout_has "^scene  *triangles  *vertices  *integrator  *run s  *frame s  *peak MiB$" \
    "the table has its header"
for integrator in direct bdpt hybrid reference; do
    stdout_has "^1M  *10082  *5184  *$integrator  *$x  *$x  *$x$" "1M: a row for $integrator"
done
stdout_has "^10M: skipped (RB_BENCH_10M=0)$" "10M is said to be skipped"

RB_BENCH_QUICK=1 sh tests/bench-scale.sh >"$T/stdout" 2>"$T/stderr"
status=$?
expect_exit 0 "by default it renders 10 M too and exits 0"
for integrator in direct bdpt hybrid reference; do
    stdout_has "^10M  *100352  *50625  *$integrator  *$x  *$x  *$x$" "10M: a row for $integrator"
done

done_testing
