#!/bin/sh
# The fuzz targets' committed corpora, replayed: every input parses or fails cleanly (make fuzz
# runs the same targets under libFuzzer with ASan and UBSan).
. tests/integration/lib.sh
for target in "$BUILD"/tests/fuzz/fuzz_*; do
    [ -x "$target" ] || continue
    name=$(basename "$target")
    tap_run "$target" tests/fuzz/corpus/"${name#fuzz_}"/*
done
check "the job parser's fuzz target was built" test -x "$BUILD/tests/fuzz/fuzz_job"
done_testing
