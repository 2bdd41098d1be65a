#!/bin/sh
# The README's tour runs as written, in order, from a checkout: every indented line of its
# "## A tour" section, run by sh in a copy of the checkout's layout whose demo job renders at
# 64x36 instead of 640x360 (the commands' text is not touched). Each exits 0 (timing compare may
# exit 1: it says a pass got slower, which two runs on a shared machine may show), and each
# writes into its own folder under out/.
. tests/integration/lib.sh

tour="$T/tour"
sed -n '/^## A tour$/,/^## /p' README.md | sed -n 's/^    //p' >"$T/commands"
count=$(wc -l <"$T/commands")
check "the README's tour has its commands ($count)" test "$count" -ge 10
for what in "render jobs/demo.yaml --preview" "--integrator direct" "--integrator hybrid" \
    "raybundle reference" "raybundle compare" "raybundle flicker" "raybundle report" \
    "raybundle bench" "raybundle timing compare" "--chunk"; do
    check "the tour shows '$what'" grep -qF -- "$what" "$T/commands"
done

mkdir -p "$tour"
ln -s "$(cd "$BUILD" && pwd)" "$tour/build"
cp -R jobs "$tour/jobs"
sed 's/^resolution: \[640, 360\]$/resolution: [64, 36]/' jobs/demo.yaml >"$tour/jobs/demo.yaml"
check "the tour's copy of the demo job renders at 64x36" \
    grep -q '^resolution: \[64, 36\]$' "$tour/jobs/demo.yaml"

i=0
while IFS= read -r cmd; do
    i=$((i + 1))
    (cd "$tour" && sh -c "$cmd") >"$T/out.$i" 2>&1 </dev/null
    st=$?
    case $cmd in
    *"timing compare"*) want="0 or 1" ok_status=$([ "$st" -le 1 ] && echo y) ;;
    *) want=0 ok_status=$([ "$st" -eq 0 ] && echo y) ;;
    esac
    if [ -n "$ok_status" ]; then
        ok "tour $i exits $st: $cmd"
    else
        not_ok "tour $i exits $st (want $want): $cmd" "$(tail -n 5 "$T/out.$i")"
    fi
done <"$T/commands"

for dir in demo hybrid direct reference chunks; do
    check "out/$dir has the sequence's last frame" test -f "$tour/out/$dir/frame.0047.exr"
done
check "out/bench-before and out/bench-after hold their runs" \
    test -f "$tour/out/bench-before/bench.json" -a -f "$tour/out/bench-after/bench.json"
check "out/demo.html is written" test -s "$tour/out/demo.html"
check "nothing is written outside out/" \
    sh -c "cd '$tour' && [ \"\$(ls | sort | tr '\n' ' ')\" = 'build jobs out ' ]"

done_testing
