#!/bin/sh
# Command-line conventions: "did you mean" for a mistyped command, option or integrator; every
# error on a line that starts with "raybundle:", a missing argument in one line with a pointer
# to the help; -o for --output; Deadline's frame step A-BxS; and each command's --help listing
# exactly the options its parser takes.
. tests/integration/lib.sh

# stderr_is TEXT DESCRIPTION: stderr is exactly the one line TEXT.
stderr_is() {
    if [ "$(cat "$T/stderr")" = "$1" ]; then
        ok "$2"
    else
        not_ok "$2" "want: $1" "stderr: $(head -c 2000 "$T/stderr")"
    fi
}

# stderr_lines N DESCRIPTION: stderr has N lines.
stderr_lines() {
    have=$(wc -l <"$T/stderr")
    if [ "$have" -eq "$1" ]; then
        ok "$2"
    else
        not_ok "$2" "$have lines, want $1" "stderr: $(head -c 2000 "$T/stderr")"
    fi
}

# all_lines_raybundle DESCRIPTION: stderr is not empty and every line starts with "raybundle:".
all_lines_raybundle() {
    if [ -s "$T/stderr" ] && ! grep -qv '^raybundle: ' "$T/stderr"; then
        ok "$1"
    else
        not_ok "$1" "stderr: $(head -c 2000 "$T/stderr")"
    fi
}

# ---- did you mean ----------------------------------------------------------------------------

rb rendr
expect_exit 2 "a mistyped command exits 2"
check "a mistyped command gets the nearest one" \
    grep -qx "raybundle: error: unknown command 'rendr'; did you mean 'render'?" "$T/stderr"
check "and a line pointing to raybundle --help" \
    grep -qx "raybundle: 'raybundle --help' lists the commands" "$T/stderr"
stderr_lines 2 "a mistyped command gets two lines, not the whole usage"
rb frobnicate
expect_exit 2 "an unknown command exits 2"
check "a command far from every other gets no suggestion" \
    grep -qx "raybundle: error: unknown command 'frobnicate'" "$T/stderr"

rb render jobs/demo.yaml --preveiw
expect_exit 2 "render --preveiw exits 2"
stderr_is "raybundle: error: unknown option '--preveiw'; did you mean '--preview'?" \
    "render --preveiw: did you mean '--preview'"
check "getopt's own message is not printed" \
    sh -c "! grep -q 'unrecognized option\|invalid option' '$T/stderr'"
# Each command's parser suggests from its own options.
for probe in "reference jobs/demo.yaml --tiem-limit 3|--tiem-limit|--time-limit" \
    "bench jobs/demo.yaml --rnus 3|--rnus|--runs" \
    "compare a.exr b.exr --jsno|--jsno|--json" \
    "flicker out --cvs|--cvs|--csv" \
    "report out --refrence x|--refrence|--reference" \
    "timing compare a b --alpah 0.1|--alpah|--alpha" \
    "info --hlep|--hlep|--help"; do
    args=${probe%%|*}
    rest=${probe#*|}
    typo=${rest%%|*}
    want=${rest#*|}
    # shellcheck disable=SC2086 # the words of args are the arguments
    rb $args
    expect_exit 2 "$args exits 2"
    stderr_is "raybundle: error: unknown option '$typo'; did you mean '$want'?" \
        "${args%% *} $typo: did you mean '$want'"
done
rb render jobs/demo.yaml --bogus
expect_exit 2 "an unknown option exits 2"
stderr_is "raybundle: error: unknown option '--bogus'; see 'raybundle render --help'" \
    "an option far from every other gets a pointer to the help"
rb render jobs/demo.yaml -x
expect_exit 2 "an unknown short option exits 2"
stderr_is "raybundle: error: unknown option '-x'; see 'raybundle render --help'" \
    "an unknown short option is named"
rb render jobs/demo.yaml --s 3
expect_exit 2 "an ambiguous abbreviation exits 2"
check "an ambiguous abbreviation is named with what it could be" \
    grep -qx "raybundle: error: option '--s' is ambiguous: it could be '--size', '--set', .*'--spp'" \
    "$T/stderr"
rb render jobs/demo.yaml --si 32x18 --frames 0 --integrator direct --out "$T/abbrev" -q
expect_exit 0 "an unambiguous abbreviation is taken (--si is --size)"
rb render jobs/demo.yaml --frames
expect_exit 2 "an option without its value exits 2"
stderr_is "raybundle: error: option '--frames' needs a value; see 'raybundle render --help'" \
    "a missing value is named"
rb render jobs/demo.yaml -o
expect_exit 2 "-o without its value exits 2"
stderr_is "raybundle: error: option '-o' needs a value; see 'raybundle render --help'" \
    "-o's missing value is named"
rb render jobs/demo.yaml --resume=yes
expect_exit 2 "a value given to an option that takes none exits 2"
stderr_is "raybundle: error: option '--resume' takes no value; see 'raybundle render --help'" \
    "a value given to a flag is named"
# The options of render, reference and bench are one table: one command's refusal says why.
rb bench jobs/demo.yaml --out "$T/never" --preview
expect_exit 2 "bench --preview exits 2"
stderr_is "raybundle: error: bench does not take '--preview': it renders every frame afresh and \
writes no images; see 'raybundle bench --help'" "bench --preview: why"
rb reference jobs/demo.yaml --device 0
expect_exit 2 "reference --device exits 2"
stderr_has "reference does not take '--device': it renders on the CPU" "reference --device: why"

# Integrator names: any case on the command line, and the nearest one for a typo.
rb render jobs/demo.yaml --integrator bdtp --out "$T/never"
expect_exit 2 "--integrator bdtp exits 2"
stderr_is "raybundle: error: --integrator 'bdtp': 'integrator.name' must be one of direct, bdpt, \
hybrid, reference, not 'bdtp'; did you mean 'bdpt'?" "--integrator bdtp: did you mean 'bdpt'"
check "nothing written for a bad integrator" test ! -e "$T/never"
tiny="jobs/demo.yaml --size 32x18 --frames 0 -q"
# shellcheck disable=SC2086
rb render $tiny --integrator BDPT --out "$T/upper"
expect_exit 0 "--integrator BDPT renders"
check "--integrator BDPT renders with bdpt" \
    grep -q '"integrator": "bdpt"' "$T/upper/frame.0000.timing.json"
# shellcheck disable=SC2086
rb render $tiny --integrator bdpt --out "$T/lower"
check "--integrator BDPT is the same job as --integrator bdpt" \
    test "$(grep '"job_hash"' "$T/upper/frame.0000.timing.json")" = \
    "$(grep '"job_hash"' "$T/lower/frame.0000.timing.json")"
# shellcheck disable=SC2086
rb render $tiny --set integrator.name=Direct --out "$T/set"
expect_exit 0 "--set integrator.name=Direct renders"
check "--set takes the name in any case" \
    grep -q '"integrator": "direct"' "$T/set/frame.0000.timing.json"
rb render jobs/demo.yaml --progress OpenJD --frames 0 --size 32x18 --integrator direct \
    --out "$T/openjd"
expect_exit 0 "--progress OpenJD renders"
stdout_has '^openjd_progress: 100$' "--progress takes the name in any case"
rb render jobs/demo.yaml --progress opnejd
expect_exit 2 "--progress opnejd exits 2"
stderr_is "raybundle: error: --progress expects auto or openjd, got 'opnejd'; did you mean \
'openjd'?" "--progress opnejd: did you mean 'openjd'"

# ---- one line for a missing argument, and every error line starts with raybundle: ----------

for probe in "render|render needs a job file; see 'raybundle render --help'" \
    "reference|reference needs a job file; see 'raybundle reference --help'" \
    "bench|bench needs a job file; see 'raybundle bench --help'" \
    "bench jobs/demo.yaml|bench needs --out DIR, the directory of the set; see 'raybundle bench --help'" \
    "compare a.exr|compare needs two images, A and B; see 'raybundle compare --help'" \
    "flicker|flicker needs a sequence, SEQ; see 'raybundle flicker --help'" \
    "report out|report needs -o REPORT.html; see 'raybundle report --help'" \
    "timing compare a|timing compare needs BASE and NEW, two bench directories; see 'raybundle timing compare --help'" \
    "timing|timing needs a command: 'timing compare BASE NEW'; see 'raybundle timing --help'" \
    "|raybundle needs a command, such as 'render'; see 'raybundle --help'"; do
    args=${probe%%|*}
    # shellcheck disable=SC2086
    rb $args
    expect_exit 2 "'raybundle $args' exits 2"
    stderr_is "raybundle: error: ${probe#*|}" "'raybundle $args': one line says what is missing"
done
rb render jobs/demo.yaml jobs/demo.yaml
expect_exit 2 "render with two jobs exits 2"
stderr_is "raybundle: error: render takes one job file, and 'jobs/demo.yaml' is a second; see \
'raybundle render --help'" "a second job is named"
rb timing compre
stderr_is "raybundle: error: unknown timing command 'compre'; did you mean 'compare'?" \
    "timing compre: did you mean 'compare'"

# Errors of every kind, usage and job alike: each line of stderr starts with "raybundle:".
: >"$T/empty.yaml"
for args in "rendr" "render --preveiw" "render jobs/demo.yaml --frames 5-2" \
    "render jobs/demo.yaml --size 12" "render $T/empty.yaml" "render $T/missing.yaml" \
    "render jobs/demo.yaml --set frames.strat=1" "render jobs/demo.yaml --chunk 5/4" \
    "reference jobs/demo.yaml --integrator direct" "compare a.exr b.exr --max-rmse x" \
    "compare $T/missing.exr $T/missing.exr" "flicker $T/missing" "report $T/missing -o $T/r.html" \
    "timing compare $T/missing $T/missing" "timing frob" "info --bogus" "help bogus"; do
    # shellcheck disable=SC2086
    rb $args
    expect_exit 2 "'raybundle $args' exits 2"
    all_lines_raybundle "'raybundle $args': every line of stderr starts with 'raybundle:'"
    check "'raybundle $args': no usage text on stderr" sh -c "! grep -q 'usage:' '$T/stderr'"
done

# ---- -o and A-BxS --------------------------------------------------------------------------

rb render jobs/demo.yaml --size 32x18 --frames 0 --integrator direct -q -o "$T/o/shot.####.exr"
expect_exit 0 "render -o renders"
check "render -o is --output" test -s "$T/o/shot.0000.exr"
rb reference jobs/demo.yaml --size 32x18 --frames 0 --spp 1 -q -o "$T/ref/shot.####.exr"
expect_exit 0 "reference -o renders"
check "reference -o is --output" test -s "$T/ref/shot.0000.exr"
rb bench jobs/demo.yaml --size 32x18 --frames 0-4x2 --integrator direct --runs 1 -q \
    --out "$T/bench" -o "anywhere/shot.####.exr"
expect_exit 0 "bench -o and --frames 0-4x2 run"
check "bench -o names the sidecars, --out holds the set" \
    test "$(cd "$T/bench/run-01" && echo *)" = \
    "shot.0000.timing.json shot.0002.timing.json shot.0004.timing.json"

frames_in() { # frames_in DIR: the frame numbers of DIR's EXRs, on one line
    (cd "$1" && ls -- *.exr | sed 's/^frame\.0*\([0-9]\)/\1/; s/\.exr$//' | sort -n | tr '\n' ' ')
}
rb render jobs/demo.yaml --size 32x18 --integrator direct -q --frames 1-10x2 --out "$T/x"
expect_exit 0 "--frames 1-10x2 renders"
check "--frames 1-10x2 says it rendered 5 frames" grep -q '^5 frames (1-9:2) in ' "$T/stdout"
rb render jobs/demo.yaml --size 32x18 --integrator direct -q --frames 1-10:2 --out "$T/colon"
expect_exit 0 "--frames 1-10:2 renders"
check "--frames 1-10x2 renders frames 1 3 5 7 9" test "$(frames_in "$T/x")" = "1 3 5 7 9 "
check "--frames 1-10x2 renders the frames of 1-10:2" \
    test "$(frames_in "$T/x")" = "$(frames_in "$T/colon")"
bad_option "--frames '1-10x0': '1-10x0': the step must be 1 or more" --frames 1-10x0
bad_option "--frames '4x2': '4x2' is not a frame" --frames 4x2

# ---- each command's --help lists exactly the options its parser takes ---------------------

# The commands of the dispatch table; 'timing' parses its options as 'timing compare', and
# 'help' takes none.
commands=$(sed -n "s/^    {\"\([a-z]*\)\", cmd_.*/\1/p" cmd/main.c)
check "the dispatch table lists at least 8 commands" test "$(echo $commands | wc -w)" -ge 8
for c in $commands; do
    case $c in
    help) continue ;;
    timing) c="timing compare" ;;
    esac
    # shellcheck disable=SC2086
    rb $c --help
    if [ "$status" -ne 0 ]; then
        not_ok "$c --help exits 0" "exit $status"
        continue
    fi
    # Option lines: "  --name", "  --name VALUE" or "  -o, --name VALUE", then the text.
    sed -n 's/^  \(-[a-zA-Z]\), \(--[a-z][a-z-]*\).*/\1\n\2/p; s/^  \(--[a-z][a-z-]*\).*/\1/p' \
        "$T/stdout" | sort >"$T/help-options"
    # The options with a value: an upper-case word one space after the name.
    sed -n 's/^  \(-[a-zA-Z], \)\{0,1\}\(--[a-z][a-z-]*\) [A-Z].*/\2/p' "$T/stdout" \
        >"$T/help-values"
    check "$c --help lists options" test -s "$T/help-options"
    # shellcheck disable=SC2086
    RB_TEST_LIST_OPTIONS=1 "$RB" $c >"$T/parser-options" 2>/dev/null
    sort -o "$T/parser-options" "$T/parser-options"
    if cmp -s "$T/help-options" "$T/parser-options"; then
        ok "$c --help lists exactly the options its parser takes"
    else
        not_ok "$c --help lists exactly the options its parser takes" \
            "$(diff "$T/help-options" "$T/parser-options" | grep '^[<>]' |
                sed 's/^</only in --help:/; s/^>/only in the parser:/' | tr '\n' ' ')"
    fi
    # And the parser itself takes each one. Given alone, with no arguments, a flag leaves only
    # the missing argument to complain of (or --help, or info, succeeds); an option with a value
    # may find the value bad, but must not be refused as an option.
    refused=""
    for o in $(grep '^--' "$T/help-options"); do
        if grep -qx -- "$o" "$T/help-values"; then
            # shellcheck disable=SC2086
            rb $c "$o=1"
            if grep -q "unknown option\|does not take\|is ambiguous\|needs a value\|takes no value\|is an option of" \
                "$T/stderr"; then
                refused="$refused $o"
            fi
        else
            # shellcheck disable=SC2086
            rb $c "$o"
            if [ "$status" -ne 0 ] && ! grep -qx "raybundle: error: $c needs .*" "$T/stderr"; then
                refused="$refused $o"
            fi
        fi
    done
    check "$c's parser takes every option its --help lists${refused:+ (refused:$refused)}" \
        test -z "$refused"
done
# The help of the commands that share a parser is their own.
rb bench --help
check "bench --help does not list --resume or --preview" \
    sh -c "! grep -q -- '--resume\|--preview' '$T/stdout'"
rb reference --help
check "reference --help does not list --integrator" sh -c "! grep -q -- '--integrator' '$T/stdout'"
rb render --help
check "render --help does not list --runs" sh -c "! grep -q -- '--runs' '$T/stdout'"
check "render --help shows -o and A-BxS" \
    sh -c "grep -q -- '-o, --output PATTERN' '$T/stdout' && grep -q 'A-BxS' '$T/stdout'"

done_testing
