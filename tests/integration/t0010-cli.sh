#!/bin/sh
# The command line: help, version, usage errors and their exit codes, `info`, and that every
# subcommand in the dispatch table is in raybundle(1).
. tests/integration/lib.sh

rb --version
expect_exit 0 "--version exits 0"
check "--version prints the version" grep -q '^raybundle [0-9]' "$T/stdout"

rb --help
expect_exit 0 "--help exits 0"
check "--help names --version" grep -q -- '--version' "$T/stdout"
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
stderr_has "--size '12': expected WxH" "bad --size is explained"
rb render jobs/demo.yaml --integrator nope
expect_exit 2 "unknown integrator exits 2"
stderr_has "--integrator 'nope': 'integrator.name' must be one of direct" \
    "unknown integrator is named with the choices"

# --frames and --size are sugar for --set: the key table's ranges and types apply (a frame list
# is checked first, t0075), and nothing is rendered (the output directory is not even created).
bad_option "--frames '5-2': '5-2': the range ends before it starts" --frames 5-2
bad_option "--frames '-3': '-3' is not a frame (a whole number, 0 or more)" --frames -3
bad_option "--frames '10-': '10-': the range's end is not a whole number" --frames 10-
bad_option "--frames '2.5': '2.5' is not a frame" --frames 2.5
bad_option "--frames '0x10': '0x10' is not a frame" --frames 0x10
bad_option "--frames '1-2-3': '1-2-3' is not a frame" --frames 1-2-3
bad_option "--size '64x36.5': 'resolution' expects a list of 2 integers" --size 64x36.5
bad_option "--size '0x36': 'resolution' must be between 1 and 16384" --size 0x36
bad_option "--size '99999x36': 'resolution' must be between 1 and 16384" --size 99999x36
# The output pattern: an .exr, with '#' for more than one frame.
bad_option "img.####' must name an .exr file" --output "$T/never/img.####"
bad_option "img.####.png' must name an .exr file" --output "$T/never/img.####.png" --frames 0
bad_option "has no '#' for the frame number, and frames 0 to 3 are more than one" \
    --output "$T/never/img.exr" --frames 0-3
# Options the job's integrator would ignore are refused.
bad_option "--spp applies to the reference integrator only" --spp 4
bad_option "--time-limit applies to the reference integrator only" --time-limit 3
bad_option "--threads applies to the reference integrator only" --threads 2
rb reference jobs/demo.yaml --integrator direct --out "$T/never" -q
expect_exit 2 "reference --integrator direct exits 2"
stderr_has "reference does not take '--integrator': it always renders with the CPU reference" \
    "reference --integrator: explained"
# An output directory that cannot be created is found before rendering.
: >"$T/file"
rb render jobs/demo.yaml --frames 0 --out "$T/file/sub" -q
expect_exit 2 "an output under a plain file exits 2"
stderr_has "cannot create directory" "an unwritable output is explained"
# One frame with a fixed name is fine, and the closing line says where it went.
rb render jobs/demo.yaml --frames 3 --size 32x18 --output "$T/one/still.exr" -q
expect_exit 0 "one frame to a pattern without '#' renders"
check "it is written under its number" test -s "$T/one/still.0003.exr"
check "the closing line says where the frames went" \
    grep -q "^1 frame (3) in $T/one/: 1 rendered, [0-9.]* s\$" "$T/stdout"
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
# Wrapped to 80 columns when stdout is no terminal, or to $COLUMNS; integer bounds whole.
check "help job: no line is longer than 80 columns (not a terminal)" \
    sh -c "! awk 'length > 80' '$T/stdout' | grep -q ."
check "help job prints integer bounds as integers" \
    sh -c "grep -q 'between 0 and 4294967295' '$T/stdout' && ! grep -q 'e+0' '$T/stdout'"
COLUMNS=60 "$RB" help job >"$T/narrow"
check "help job fits COLUMNS=60" sh -c "! awk 'length > 60' '$T/narrow' | grep -q ."
check "help job at 60 columns lists the same keys" \
    test "$(grep -c '^[a-z]' "$T/narrow")" -eq "$(grep -c '^[a-z]' "$T/stdout")"
rb help job camera
expect_exit 0 "help job camera exits 0"
check "help job camera lists only camera.* keys" \
    sh -c "grep -q '^camera.fov_y_deg ' '$T/stdout' && ! grep '^[a-z]' '$T/stdout' | grep -qv '^camera'"
rb help job integrator.bdpt.v
check "help job takes any prefix of a dotted path" \
    test "$(grep '^[a-z]' "$T/stdout" | cut -d' ' -f1 | sort | tr '\n' ' ')" = \
    "integrator.bdpt.view_triangles integrator.bdpt.vpl_bias integrator.bdpt.vpl_size integrator.bdpt.vpl_spread integrator.bdpt.vpls "
rb help job camra
expect_exit 2 "help job with a prefix no key has exits 2"
check "help job camra: did you mean 'camera'" \
    grep -qx "raybundle: error: no job key starts with 'camra'; did you mean 'camera'?" "$T/stderr"
check "help job camra prints no keys" test ! -s "$T/stdout"

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
