#!/bin/sh
# The fuzz targets' committed corpora, replayed: every input parses or fails cleanly, once with
# the normal build and once under ASan and UBSan ($BUILD/asan, built by make check), where any
# report (a bad access, a leak, undefined behaviour) aborts the replay and fails the test. make
# fuzz runs the same targets under libFuzzer.
. tests/integration/lib.sh
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=0:halt_on_error=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
for target in "$BUILD"/tests/fuzz/fuzz_* "$BUILD"/asan/tests/fuzz/fuzz_*; do
    [ -f "$target" ] && [ -x "$target" ] || continue
    name=$(basename "$target")
    tap_run "$target" tests/fuzz/corpus/"${name#fuzz_}"
done
check "the job parser's fuzz target was built" test -x "$BUILD/tests/fuzz/fuzz_job"
check "the job parser's sanitized replay was built" test -x "$BUILD/asan/tests/fuzz/fuzz_job"
check "the glTF loader's sanitized replay was built" test -x "$BUILD/asan/tests/fuzz/fuzz_scene"
check "the timing readers' sanitized replay was built" test -x "$BUILD/asan/tests/fuzz/fuzz_timing"
check "the sequence readers' sanitized replay was built" test -x "$BUILD/asan/tests/fuzz/fuzz_sequence"
done_testing
