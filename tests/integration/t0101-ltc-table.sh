#!/bin/sh
# The specular lobe's fitted cosines that the renderer compiles in (lib/passes/ltc_ggx.inc) are
# what tools/ltcfit.c fits, number for number as printed: a refit of four of its 64 roughness
# columns (the normal-incidence column, which each starts from, and then each column's rows)
# matches, and a table with one number changed does not, the check naming where.
. tests/integration/lib.sh

table=lib/passes/ltc_ggx.inc
"$BUILD/ltcfit" --check "$table" 0 21 42 63 >"$T/out" 2>&1
check "a refit of columns 0, 21, 42 and 63 matches $table ($(tail -n 1 "$T/out"))" \
    grep -q "columns match (4)" "$T/out"
# Row 5, column 21: its line is the comment's two, then 5 * 64 + 21 + 1.
awk 'NR == 2 + 5 * 64 + 21 + 1 { sub(/^[^,]*,/, "0.5,") } { print }' "$table" >"$T/changed.inc"
check "the changed copy differs from the table in one line" \
    sh -c "[ \$(diff \"$table\" \"$T/changed.inc\" | grep -c '^>') -eq 1 ]"
"$BUILD/ltcfit" --check "$T/changed.inc" 21 >"$T/out" 2>&1
status=$?
check "a refit of column 21 does not match a table with its row 5 changed (exit $status)" \
    [ "$status" -eq 1 ]
check "the check names the row and column that differ" grep -q "row 5 column 21 number 0" "$T/out"
"$BUILD/ltcfit" --check "$T/missing.inc" 21 >"$T/out" 2>&1
status=$?
check "a missing table is an error that names it (exit $status)" \
    sh -c "[ $status -eq 1 ] && grep -q 'missing.inc' \"$T/out\""
done_testing
