#!/bin/sh
# The command line: help, version, usage errors and their exit codes, `info`, and that every
# subcommand in the dispatch table is in raybundle(1).
. tests/integration/lib.sh

rb --version
expect_exit 0 "--version exits 0"
check "--version prints the version" grep -q '^raybundle [0-9]' "$T/stdout"

rb --help
expect_exit 0 "--help exits 0"
commands=$(sed -n "s/^    {\"\([a-z]*\)\", cmd_.*/\1/p" cmd/main.c)
check "the dispatch table lists at least 5 commands" test "$(echo $commands | wc -w)" -ge 5
for c in $commands; do
    check "help lists '$c'" grep -q "^  $c " "$T/stdout"
    check "raybundle(1) documents '$c'" grep -q "^\.B $c\( \|\$\)" man/raybundle.1
done

rb
expect_exit 2 "no command exits 2"
rb frobnicate
expect_exit 2 "unknown command exits 2"
stderr_has "unknown command 'frobnicate'" "unknown command is named"

rb render --help
expect_exit 0 "render --help exits 0"
check "render --help shows usage on stdout" grep -q 'usage: raybundle render JOB' "$T/stdout"
rb render
expect_exit 2 "render without a job exits 2"
rb render jobs/demo.yaml --bogus
expect_exit 2 "unknown option exits 2"
rb render jobs/demo.yaml --size 12
expect_exit 2 "bad --size exits 2"
stderr_has "--size expects WxH" "bad --size is explained"
rb render jobs/demo.yaml --frames 5-2
expect_exit 2 "backwards --frames exits 2"
rb render jobs/demo.yaml --integrator nope
expect_exit 2 "unknown integrator exits 2"
stderr_has "unknown integrator 'nope'" "unknown integrator is named"
rb render jobs/demo.yaml --device no-such-device --frames 0 --out "$T/dev"
expect_exit 3 "a device that does not exist exits 3"
stderr_has "no device matches 'no-such-device'" "missing device is named"

rb info
expect_exit 0 "info exits 0"
check "info lists lavapipe" grep -q 'llvmpipe' "$T/stdout"
check "info reports the driver" grep -q 'driver:' "$T/stdout"
check "info reports the library versions" grep -q '^libraries: OpenImageIO [0-9].*, OpenColorIO [0-9].*, Embree [0-9].*, libyaml [0-9]' "$T/stdout"
check "info says whether a device is usable" grep -q 'usable: yes' "$T/stdout"

rb help job
expect_exit 0 "help job exits 0"
check "help job lists integrator.direct.shadow_size" grep -q 'integrator.direct.shadow_size' "$T/stdout"

if command -v mandoc >/dev/null; then
    for page in man/raybundle.1 man/raybundle-job.5; do
        if out=$(mandoc -T lint -W warning "$page" 2>&1) && [ -z "$out" ]; then
            ok "mandoc lint is clean on $page"
        else
            not_ok "mandoc lint is clean on $page" "$out"
        fi
    done
fi

done_testing
