#!/bin/sh
# raybundle bench and timing compare: two benches of the demo at a tiny size (sidecars only,
# bench.json's record), compared with each other (exit 0, every pass listed, the few-runs
# warning); a hand-written set against a copy whose gpu_ms are tripled (exit 1, slower); sets
# of different jobs refused without --force; usage errors and broken sets.
. tests/integration/lib.sh

# ---- usage ---------------------------------------------------------------------------------

rb bench --help
expect_exit 0 "bench --help exits 0"
check "bench --help shows its usage" grep -q 'usage: raybundle bench JOB --out DIR' "$T/stdout"
rb timing compare --help
expect_exit 0 "timing compare --help exits 0"
check "timing compare --help shows its usage" grep -q 'usage: raybundle timing compare' \
    "$T/stdout"
check "raybundle-bench(1) documents bench" grep -q '^\.B bench$' man/raybundle-bench.1
check "raybundle-bench(1) documents timing compare" grep -q '^\.B timing compare$' \
    man/raybundle-bench.1
check "raybundle-bench(1) documents bench.json's job_hash" grep -q '^\.B job_hash$' \
    man/raybundle-bench.1
rb bench jobs/demo.yaml
expect_exit 2 "bench without --out exits 2"
stderr_has "bench needs --out DIR" "a missing --out is explained"
rb bench jobs/demo.yaml --out "$T/x" --runs 0
expect_exit 2 "bench --runs 0 exits 2"
stderr_has "--runs expects 1..99, got '0'" "a bad --runs is explained"
rb bench jobs/demo.yaml --out "$T/x" --resume
expect_exit 2 "bench --resume exits 2"
stderr_has "bench does not take '--resume': it renders every frame afresh and writes no images" \
    "bench --resume is explained"
rb render jobs/demo.yaml --runs 3
expect_exit 2 "render --runs exits 2"
stderr_has "render does not take '--runs': only bench renders a job several times" \
    "render --runs is explained"
rb timing compare "$T/x"
expect_exit 2 "timing compare with one set exits 2"
rb timing frobnicate
expect_exit 2 "an unknown timing command exits 2"
rb timing compare "$T/nowhere" "$T/nowhere"
expect_exit 2 "timing compare of a missing set exits 2"
stderr_has "cannot open '$T/nowhere/bench.json'" "a missing set is named"
rb timing compare --alpha 2 "$T/a" "$T/b"
expect_exit 2 "a bad --alpha exits 2"

# ---- two benches of the demo ---------------------------------------------------------------

for set in a b; do
    rb bench jobs/demo.yaml --size 64x36 --frames 0-1 --runs 3 --out "$T/$set" -q
    expect_exit 0 "bench of the demo into $set"
done
stdout_has "^3 runs of 2 frames (0-1) on .* in $T/b/" "bench says what it measured"
check "bench keeps each run's sidecars" test -f "$T/a/run-01/frame.0000.timing.json" -a \
    -f "$T/a/run-03/frame.0001.timing.json"
check "bench writes no images" test -z "$(find "$T/a" -name '*.exr' -o -name '*.png')"
check "bench.json records 3 runs" grep -q '"runs": 3' "$T/a/bench.json"
check "bench.json records the job hash" grep -q '"job_hash": "[0-9a-f]\{16\}"' "$T/a/bench.json"
hash=$(sed -n 's/.*"job_hash": "\([0-9a-f]*\)".*/\1/p' "$T/a/bench.json")
check "every run's sidecars record bench.json's job hash" test "$(grep -l "\"job_hash\": \"$hash\"" \
    "$T"/a/run-0[1-3]/frame.000[01].timing.json | wc -l)" -eq 6
for key in device driver build job integrator width height order frames options; do
    check "bench.json records $key" grep -q "\"$key\": " "$T/a/bench.json"
done
device=$(sed -n 's/.*"device": "\([^"]*\)".*/\1/p' "$T/a/run-02/frame.0001.timing.json")
check "bench.json's device is the sidecars'" grep -qF "\"device\": \"$device\"" "$T/a/bench.json"
rb bench jobs/demo.yaml --size 64x36 --frames 0 --runs 1 --out "$T/a" -q
expect_exit 2 "bench into a set's directory exits 2"
stderr_has "is not an empty directory" "a used directory is explained"

rb timing compare "$T/a" "$T/b"
expect_exit 0 "timing compare of two benches of the same build exits 0"
passes=$(sed -n 's/.*{"name": "\([^"]*\)".*/\1/p' "$T/a/run-01/frame.0000.timing.json")
check "the demo's sidecars list passes" test -n "$passes"
for p in $passes; do
    stdout_has "^$p  *[0-9.]* ms  *[0-9.]* ms .*too few runs$" "pass '$p' is in the table"
done
stdout_has "^frame wall  *[0-9.]* ms" "the frame wall time is in the table"
stderr_has "has 3 runs: 9 or more are recommended" "fewer than 9 runs are warned about"
rb timing compare --json "$T/a" "$T/b"
expect_exit 0 "timing compare --json exits 0"
stdout_has '"regression": false' "--json says there is no regression"
if command -v python3 >/dev/null && python3 -c 'import json' 2>/dev/null; then
    check "--json is JSON with a row a series" python3 -c "
import json, sys
d = json.load(open(sys.argv[1]))
assert len(d['rows']) == $(echo $passes | wc -w) + 1, d['rows']
assert all(r['verdict'] == 'too few runs' for r in d['rows'])" "$T/stdout"
else
    skip "--json is JSON with a row a series" "no python3"
fi

# A set whose bench.json names another job than its sidecars: refused, the sidecar named.
cp -R "$T/b" "$T/c"
hash=$(sed -n 's/.*"job_hash": "\([0-9a-f]*\)".*/\1/p' "$T/b/bench.json")
sed -i "s/\"job_hash\": \"$hash\"/\"job_hash\": \"00000000deadbeef\"/" "$T/c/bench.json"
rb timing compare --force "$T/a" "$T/c"
expect_exit 2 "a set whose sidecars are of another job than its bench.json is refused"
stderr_has "/c/run-01/frame.0000.timing.json': rendered from job $hash, and bench.json says job 00000000deadbeef" \
    "the sidecar and both hashes are named"
# A set of another job (every file of it): refused, both hashes named; compared with --force.
for f in "$T"/c/run-*/*.timing.json; do
    sed -i "s/\"job_hash\": \"$hash\"/\"job_hash\": \"00000000deadbeef\"/" "$f"
done
rb timing compare "$T/a" "$T/c"
expect_exit 2 "sets of different jobs are refused"
stderr_has "different job hashes (the job, scene or options differ): '$hash' and '00000000deadbeef'" \
    "the refusal names both hashes"
rb timing compare --force "$T/a" "$T/c"
expect_exit 0 "--force compares them anyway"
stderr_has "compared anyway (--force)" "--force warns"

# ---- a known regression, by hand -----------------------------------------------------------

# mkset DIR FACTOR: 9 runs of 2 frames, pass i of run r, frame f taking
# FACTOR * i * (1 + r/100 + f/1000) ms; wall time 20 + r ms whatever the factor.
mkset() {
    mkdir -p "$1"
    cat >"$1/bench.json" <<EOT
{"device": "test device", "driver": "test driver 1.0", "build": "raybundle test",
 "job": "jobs/demo.yaml", "job_hash": "0123456789abcdef", "integrator": "direct",
 "width": 64, "height": 36, "runs": 9, "order": "run-by-run", "frames": [0, 1],
 "options": ["jobs/demo.yaml", "--runs", "9"]}
EOT
    for r in 1 2 3 4 5 6 7 8 9; do
        mkdir -p "$1/run-0$r"
        for f in 0 1; do
            awk -v k="$2" -v r="$r" -v f="$f" 'BEGIN {
                printf "{\"frame\": %d, \"time_s\": 0, \"passes\": [", f
                split("gbuffer shadow direct", name, " ")
                for (i = 1; i <= 3; i++)
                    printf "%s{\"name\": \"%s\", \"gpu_ms\": %.9g, \"count\": 1}", (i > 1 ? ", " : ""),
                        name[i], k * i * (1 + r / 100 + f / 1000)
                printf "], \"wall_ms\": %d, \"device\": \"test device\", ", 20 + r
                printf "\"driver\": \"test driver 1.0\", \"integrator\": \"direct\", "
                printf "\"width\": 64, \"height\": 36, \"nonfinite\": 0}\n" }' \
                >"$1/run-0$r/frame.000$f.timing.json"
        done
    done
}
mkset "$T/base" 1
cp -R "$T/base" "$T/slow"
for j in "$T"/slow/run-*/*.timing.json; do
    awk '{ while (match($0, /"gpu_ms": [0-9.e+-]+/)) {
               printf "%s\"gpu_ms\": %.9g", substr($0, 1, RSTART - 1), 3 * substr($0, RSTART + 10, RLENGTH - 10)
               $0 = substr($0, RSTART + RLENGTH) }
           print }' "$j" >"$j.new" && mv "$j.new" "$j"
done
check "the doctored copy tripled gpu_ms" grep -q '"gpu_ms": 6.0' "$T/slow/run-01/frame.0000.timing.json"
rb timing compare "$T/base" "$T/slow"
expect_exit 1 "tripled pass times exit 1"
for p in gbuffer shadow direct; do
    stdout_has "^$p .* +200.0% .* slower$" "pass '$p' is slower by 200%"
done
stdout_has "^frame wall .* same$" "the unchanged wall time is the same"
check "9 runs earn no warning" sh -c "! grep -q recommended '$T/stderr'"
rb timing compare "$T/slow" "$T/base"
expect_exit 0 "the other way round, faster, exits 0"
stdout_has "^shadow .* -66.7% .* faster$" "the other way round is faster"
rb timing compare --threshold 250% "$T/base" "$T/slow"
expect_exit 0 "a threshold above the change exits 0"
stdout_has "^direct .* same$" "within the threshold is the same"
rb timing compare "$T/base" "$T/base"
expect_exit 0 "a set against itself exits 0"

# A broken sidecar is named.
printf '{"frame": 1, "passes": [}\n' >"$T/slow/run-04/frame.0001.timing.json"
rb timing compare "$T/base" "$T/slow"
expect_exit 2 "a broken sidecar exits 2"
stderr_has "run-04/frame.0001.timing.json:1:" "the broken sidecar is named with its position"

done_testing
