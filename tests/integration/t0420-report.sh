#!/bin/sh
# raybundle report: a tiny render of the demo and its reference make a page that holds everything
# itself (no script, nothing fetched, every image a data: URI) and agrees with raybundle compare;
# usage errors and sequences that do not match are named; hit-ratio images, where a sequence has
# them, are plotted and shown: synthetic ones, and a real bdpt sequence's, whose plotted means are
# its sidecars' hits.mean; each frame's FLIP against the reference is raybundle compare's, and
# its FLIP map in the filmstrip is compare's --flip-map PNG; --filmstrip N shows N frames evenly spaced. Then, where Debian's chromium runs, the page is loaded headless:
# a copy with a probe script in its <head> records every error event, console.error and image
# that did not decode into the DOM that --dump-dom prints (Chromium's own log lines change from
# release to release; the DOM does not), and a screenshot is checked pixel by pixel: the plots
# hold their series' colours, each frame's bar has, at the height the sidecars put its largest
# pass, that pass's colour, and each bdpt frame's hit-ratio point is where its sidecar puts it.
. tests/integration/lib.sh
PIXELS="$BUILD/tests/tools/pixels"

# ---- usage ---------------------------------------------------------------------------------

rb report --help
expect_exit 0 "report --help exits 0"
check "report --help shows its usage" grep -q 'usage: raybundle report SEQ' "$T/stdout"
check "raybundle-report(1) documents --reference" grep -q '^\.BI \\-\\-reference ' \
    man/raybundle-report.1
rb report "$T/nowhere"
expect_exit 2 "report without -o exits 2"
stderr_has "report needs -o REPORT.html" "a missing -o is explained"
rb report -o "$T/r.html"
expect_exit 2 "report without SEQ exits 2"
rb report "$T/nowhere" -o "$T/r.html"
expect_exit 2 "report of a missing directory exits 2"
stderr_has "cannot open '$T/nowhere'" "a missing directory is named"
mkdir -p "$T/empty"
rb report "$T/empty" -o "$T/r.html"
expect_exit 2 "report of an empty directory exits 2"
stderr_has "'$T/empty' holds no frames" "an empty directory is explained"
check "a failed report writes nothing" test ! -e "$T/r.html"

# ---- a sequence and its reference ----------------------------------------------------------

rb render jobs/demo.yaml --integrator direct --size 64x36 --frames 0-3 --out "$T/seq" --preview -q
expect_exit 0 "render 4 frames of the demo"
rb reference jobs/demo.yaml --size 64x36 --frames 0-3 --spp 4 --out "$T/ref" -q
expect_exit 0 "render their reference"
rb report "$T/seq" --reference "$T/ref" -o "$T/out/report.html"
expect_exit 0 "report of the sequence against its reference exits 0"
stdout_has "^4 frames of $T/seq/frame.####.exr against $T/ref in $T/out/report.html$" \
    "report says what it wrote"
page="$T/out/report.html"
check "only the page is left in its directory (no temporary file)" \
    test "$(ls "$T/out")" = report.html
check "the page has no script" test "$(grep -ci '<script' "$page")" -eq 0
check "the page links nothing" test "$(grep -Eci '<link|@import|url\(' "$page")" -eq 0
check "the page fetches nothing" test "$(grep -Eci '(src|href)="?(https?:|//|file:)' "$page")" -eq 0
check "every src is an inline PNG" \
    test "$(grep -o 'src="[^"]*' "$page" | grep -vc '^src="data:image/png;base64,')" -eq 0
check "12 thumbnails: the sequence's, the reference's and the FLIP maps" \
    test "$(grep -o '<img src="data:image/png;base64,' "$page" | wc -l)" -eq 12
check "a FLIP map a frame in the filmstrip" \
    test "$(grep -o 'alt="FLIP of frame [0-3]"' "$page" | tr -dc '0-9')" = 0123
for id in passes frame-time temporal warped reference-error reference-flip; do
    check "the page plots '$id'" grep -q "<section id=\"$id\".*" "$page"
done
check "the page says there are no hit ratios" grep -q 'No hit-ratio images' "$page"
# The warped and excess errors are raybundle flicker's, to the page's 4 digits.
rb flicker "$T/seq" --reference "$T/ref" --csv
for f in 1 2 3; do
    for col in "2 sequence" "7 excess" "8 reference"; do
        want=$(awk -F, -v f=$f -v c="${col% *}" '$1 == f { printf "%.4g", $c }' "$T/stdout")
        check "frame $f's warped-chart '${col#* }' is flicker's ($want)" \
            grep -q "<title>frame $f: ${col#* } $want</title>" "$page"
    done
done
# The relMSE under each thumbnail is raybundle compare's, to the page's 4 digits.
rb compare "$T/seq/frame.####.exr" "$T/ref/frame.####.exr" --frames 0-3 --json
expect_exit 0 "compare the same sequences"
for f in 0 1 2 3; do
    want=$(sed -n "s/.*{\"frame\": $f, .*\"relmse\": \([^,]*\),.*/\1/p" "$T/stdout")
    want=$(printf '%.4g' "$want")
    check "frame $f's relMSE is compare's ($want)" grep -q "^<tr><td>$f<br>relMSE $want<br>" "$page"
done
# So is its FLIP (HDR-FLIP, the frames being EXRs), under the thumbnail and in the chart.
for f in 0 1 2 3; do
    want=$(sed -n "s/.*{\"frame\": $f, .*\"flip\": {\"kind\": \"hdr\", \"mean\": \([^,]*\),.*/\1/p" \
        "$T/stdout")
    want=$(printf '%.4g' "$want")
    check "frame $f's FLIP is compare's ($want)" grep -q "^<tr><td>$f<br>.*<br>FLIP $want</td>" "$page"
    check "frame $f's FLIP is plotted ($want)" grep -q "<title>frame $f: FLIP $want</title>" "$page"
done
for f in 1 2 3; do
    check "the sidecar's passes of frame $f are in its bar's tooltip" \
        grep -q "<g><title>frame $f: .*; animate .*, shadow .*, output" "$page"
done
# thumb PAGE ALT: the PNG of the image with that alt text, decoded into $T/thumb.png.
thumb() {
    sed -n "s/.*<img src=\"data:image\/png;base64,\([^\"]*\)\"[^>]*alt=\"$2\".*/\1/p" "$1" |
        base64 -d >"$T/thumb.png"
}
thumb "$page" "sequence of frame 2"
check "a full-size thumbnail has the pixels of render --preview's PNG" \
    sh -c "oiiotool --diff '$T/thumb.png' '$T/seq/frame.0002.png' >/dev/null"
rb compare "$T/seq/frame.0002.exr" "$T/ref/frame.0002.exr" --flip-map "$T/flip2.png"
expect_exit 0 "compare --flip-map of frame 2"
thumb "$page" "FLIP of frame 2"
check "frame 2's full-size FLIP map has the pixels of compare's --flip-map PNG" \
    sh -c "oiiotool --diff '$T/thumb.png' '$T/flip2.png' >/dev/null"
rb report "$T/seq" -o "$T/small.html" --thumb-width 32
expect_exit 0 "report --thumb-width 32 exits 0"
check "without a reference, no FLIP map" sh -c "! grep -q 'alt=\"FLIP of' '$T/small.html'"
check "and the FLIP chart says how to get one" \
    grep -q '<section id="reference-flip".*' "$T/small.html"
thumb "$T/small.html" "sequence of frame 1"
check "its thumbnails are 32x18" sh -c "oiiotool --info '$T/thumb.png' | grep -q ' 32 x   18,'"
rb report "$T/seq" -o "$T/small.html" --thumb-width 0
expect_exit 2 "--thumb-width 0 exits 2"

# ---- what does not match -------------------------------------------------------------------

cp -r "$T/ref" "$T/ref-gap" && rm "$T/ref-gap/frame.0002.exr"
rb report "$T/seq" --reference "$T/ref-gap" -o "$T/r.html"
expect_exit 2 "a reference without frame 2 exits 2"
stderr_has "the reference '$T/ref-gap' has no frame 2 (for '$T/seq/frame.0002.exr')" \
    "the missing reference frame is named"
cp -r "$T/seq" "$T/seq-notiming" && rm "$T/seq-notiming/frame.0001.timing.json"
rb report "$T/seq-notiming" -o "$T/r.html"
expect_exit 2 "a frame without its timing sidecar exits 2"
stderr_has "cannot open '$T/seq-notiming/frame.0001.timing.json'" "the missing sidecar is named"
cp -r "$T/seq" "$T/seq-two" && cp "$T/seq/frame.0000.exr" "$T/seq-two/take2.0000.exr"
rb report "$T/seq-two" -o "$T/r.html"
expect_exit 2 "a directory with two sequences exits 2"
stderr_has "holds frames of two sequences, 'frame.####.exr' and 'take2.####.exr'" \
    "both sequences are named"
rb reference jobs/demo.yaml --size 32x18 --frames 0-3 --spp 1 --out "$T/ref-small" -q
rb report "$T/seq" --reference "$T/ref-small" -o "$T/r.html"
expect_exit 2 "a reference of another size exits 2"
stderr_has "size mismatch: '$T/ref-small/frame.0000.exr' is 32x18" "the size mismatch is named"
check "no page is written for a mismatch" test ! -e "$T/r.html"

# ---- hit ratios, where a sequence has them --------------------------------------------------

cp -r "$T/seq" "$T/hits"
for f in 0 1 2 3; do
    oiiotool --pattern constant:color=0.$((f + 2))5 64x36 1 -o "$T/hits/frame.000$f.hits.exr"
done
rb report "$T/hits" -o "$T/hits.html"
expect_exit 0 "report of a sequence with hit-ratio images exits 0"
check "the hit ratio is plotted" grep -q '<section id="hit-ratio"' "$T/hits.html"
check "frame 2's hit ratio is its image's mean" grep -q '<title>frame 2: hit ratio 0.45</title>' \
    "$T/hits.html"
check "the hit-ratio images are shown beside the frames" \
    test "$(grep -o 'alt="hit ratio of frame' "$T/hits.html" | wc -l)" -eq 4
rm "$T/hits/frame.0003.hits.exr"
rb report "$T/hits" -o "$T/hits2.html"
expect_exit 2 "a hit-ratio image missing from one frame exits 2"
stderr_has "'$T/hits/frame.0003.hits.exr' is missing" "the missing hit-ratio image is named"

# ---- a real bdpt sequence: hit ratios, warped and excess error, the filmstrip's stride ------

# bdpt writes NAME.####.hits.exr (channel Y) and the sidecar's "hits" summary; the demo's default
# layers hold depth and motion, so the warped and excess errors are computed too. 64x36 and six
# frames (a second of the first cache cycle and the next) keep it to a few seconds.
rb render jobs/demo.yaml --integrator bdpt --size 64x36 --frames 0-5 --out "$T/bdpt" -q
expect_exit 0 "render 6 frames of the demo with bdpt"
rb reference jobs/demo.yaml --size 64x36 --frames 0-5 --spp 4 --out "$T/bref" -q
expect_exit 0 "render their reference"
rb report "$T/bdpt" --reference "$T/bref" -o "$T/bdpt.html"
expect_exit 0 "report of the bdpt sequence exits 0"
bpage="$T/bdpt.html"
check "the bdpt report plots the hit ratio" grep -q '<section id="hit-ratio"' "$bpage"
check "the hit-ratio chart has one point a frame" \
    test "$(grep -c '<title>frame [0-9]*: hit ratio ' "$bpage")" -eq 6
# hits_mean F: the "hits" object's mean in frame F's sidecar, as written.
hits_mean() {
    sed -n 's/.*"hits": {"mean": \([^,]*\),.*/\1/p' "$T/bdpt/frame.000$1.timing.json"
}
for f in 0 1 2 3 4 5; do
    mean=$(hits_mean $f)
    want=$(printf '%.4g' "$mean")
    check "frame $f's plotted hit ratio is its sidecar's hits.mean ($want)" \
        grep -q "<title>frame $f: hit ratio $want</title>" "$bpage"
    # The report averages the EXR; OpenImageIO's own average of it is the sidecar's number too.
    avg=$(oiiotool --stats "$T/bdpt/frame.000$f.hits.exr" | sed -n 's/.*Stats Avg: \([^ ]*\).*/\1/p')
    check "frame $f's hits.exr averages to its sidecar's mean (oiiotool $avg, sidecar $mean)" \
        awk -v a="$avg" -v m="$mean" 'BEGIN { d = a - m; exit !(m > 0 && m <= 1 && d * d < 1e-10) }'
done
check "the hit ratio rises as the caches fill (frame 3 above frame 0)" \
    awk -v a="$(hits_mean 0)" -v b="$(hits_mean 3)" 'BEGIN { exit !(b > a) }'
check "the filmstrip shows a hit-ratio image a frame" \
    test "$(grep -o 'alt="hit ratio of frame [0-5]"' "$bpage" | wc -l)" -eq 6
thumb "$bpage" "hit ratio of frame 4"
check "frame 4's hit-ratio thumbnail is its hits.exr as grey (to 8 bits), not frame 1's" \
    sh -c "oiiotool --fail 0.0025 --warn 0.0025 '$T/thumb.png' --ch R \
        '$T/bdpt/frame.0004.hits.exr' --ch Y --diff >/dev/null &&
    ! oiiotool --fail 0.0025 --warn 0.0025 '$T/thumb.png' --ch R \
        '$T/bdpt/frame.0001.hits.exr' --ch Y --diff >/dev/null"
for id in warped reference-error temporal; do
    check "the bdpt report plots '$id'" grep -q "<section id=\"$id\"" "$bpage"
done
rb flicker "$T/bdpt" --reference "$T/bref" --csv
expect_exit 0 "flicker of the bdpt sequence"
for f in 1 2 3 4 5; do
    for col in "2 sequence" "7 excess"; do
        want=$(awk -F, -v f=$f -v c="${col% *}" '$1 == f { printf "%.4g", $c }' "$T/stdout")
        check "bdpt frame $f's warped-chart '${col#* }' is flicker's ($want)" \
            grep -q "<title>frame $f: ${col#* } $want</title>" "$bpage"
    done
done
rb report "$T/bdpt" -o "$T/stride.html" --filmstrip 3
expect_exit 0 "report --filmstrip 3 exits 0"
check "--filmstrip 3 shows frames 0, 3 and 5 (2.5 rounds up)" test "$(grep -o \
    'alt="sequence of frame [0-9]*"' "$T/stride.html" | tr -dc '0-9')" = 035
check "--filmstrip 3 shows their hit-ratio images alone" test "$(grep -o \
    'alt="hit ratio of frame [0-9]*"' "$T/stride.html" | tr -dc '0-9')" = 035
check "--filmstrip 3 says it shows 3 of 6 frames" grep -q '>3 of the 6 frames, evenly spaced' \
    "$T/stride.html"
check "--filmstrip 3 still plots every frame" \
    test "$(grep -c '<title>frame [0-9]*: hit ratio ' "$T/stride.html")" -eq 6
rb report "$T/bdpt" -o "$T/all.html" --filmstrip 0
expect_exit 0 "report --filmstrip 0 exits 0"
check "--filmstrip 0 shows every frame, and says nothing of a stride" sh -c \
    "test \$(grep -o 'alt=\"sequence of frame' '$T/all.html' | wc -l) -eq 6 &&
     ! grep -q 'evenly spaced' '$T/all.html'"
rb report "$T/bdpt" -o "$T/r.html" --filmstrip 1
expect_exit 2 "--filmstrip 1 exits 2"
stderr_has "--filmstrip expects 0 (every frame) or 2..100000 frames, got '1'" \
    "--filmstrip 1 is explained"
check "raybundle-report(1) documents --filmstrip" grep -q '^\.BI \\-\\-filmstrip ' \
    man/raybundle-report.1

# ---- in a browser --------------------------------------------------------------------------

# browser ARGS...: headless Chromium with a profile of its own; output in $T/browser.out.
browser() {
    timeout 120 chromium --headless --no-sandbox --disable-gpu --hide-scrollbars \
        --user-data-dir="$T/chromium" --force-device-scale-factor=1 "$@" \
        >"$T/browser.out" 2>"$T/browser.err"
}

if ! command -v chromium >/dev/null; then
    skip "the page loads in Chromium" "chromium is not installed (scripts/install-deps.sh)"
    done_testing
fi
printf '<!DOCTYPE html><html><body><p id="x">ok</p></body></html>\n' >"$T/blank.html"
if ! browser --dump-dom "file://$T/blank.html" || ! grep -q '<p id="x">ok</p>' "$T/browser.out"
then
    skip "the page loads in Chromium" \
        "chromium cannot run here: $(grep -v dbus "$T/browser.err" | tail -n 1)"
    done_testing
fi

cat >"$T/probe.js" <<'EOF'
<script>
var probeErrors = [];
addEventListener("error", function (e) {
    probeErrors.push(e.message || "cannot load " + (e.target.src || e.target.href || e.target));
}, true);
addEventListener("unhandledrejection", function (e) { probeErrors.push("rejected: " + e.reason); });
(function () {
    var error = console.error;
    console.error = function () {
        probeErrors.push(Array.prototype.join.call(arguments, " "));
        error.apply(console, arguments);
    };
})();
addEventListener("load", function () {
    for (var i = 0; i < document.images.length; i++)
        if (!document.images[i].complete || !document.images[i].naturalWidth)
            probeErrors.push("image '" + document.images[i].alt + "' did not decode");
    document.body.setAttribute("data-probe", probeErrors.length ? probeErrors.join(" | ") : "clean");
});
</script>
EOF
sed '/^<head>$/r '"$T/probe.js" "$page" >"$T/out/probe.html"
check "the probe went into the copy" grep -q 'probeErrors' "$T/out/probe.html"
browser --dump-dom --virtual-time-budget=5000 "file://$T/out/probe.html"
if grep -q 'data-probe="clean"' "$T/browser.out"; then
    ok "the page loads in Chromium with no error"
else
    not_ok "the page loads in Chromium with no error" \
        "probe: $(grep -o 'data-probe="[^"]*"' "$T/browser.out")" \
        "stderr: $(grep -v dbus "$T/browser.err" | tail -n 5)"
fi

browser --window-size=960,1950 --screenshot="$T/shot.png" "file://$page"
check "Chromium takes a screenshot of the page" test -s "$T/shot.png"

# section ID: the page's lines of that chart's section.
section() {
    sed -n "/^<section id=\"$1\"/,/^<\/section>/p" "$page"
}
# color ID SERIES: the colour of a series in a chart's legend, as rrggbb.
color() {
    section "$1" | sed -n "s/.* fill=\"#\([0-9a-f]*\)\" data-series=\"$2\".*/\1/p"
}
# plot ID: the plot area "x y width height max slots" in page pixels.
plot() {
    section "$1" | sed -n 's/.* data-plot="\([^"]*\)".*/\1/p'
}
# drawn SCREENSHOT CHART...: each CHART ("ID SERIES") has 60 pixels or more of the series'
# colour in its plot area on the screenshot.
drawn() {
    shot=$1
    shift
    for chart in "$@"; do
        id=${chart%% *}
        series=${chart#* }
        c=$(color "$id" "$series")
        area=$(plot "$id" | cut -d' ' -f1-4)
        count=$("$PIXELS" "$shot" $area "$c")
        check "the '$id' plot is drawn: $count pixels of '$series' ($c)" test "${count:-0}" -ge 60
    done
}
drawn "$T/shot.png" "passes shadow" "frame-time frame wall" "temporal sequence" "warped excess" \
    "reference-error relMSE" "reference-flip FLIP"

# Each frame's largest pass, from its sidecar: the middle of its segment of the stack, mapped
# through the plot area and axis the page declares, is that pass's colour on the screenshot; the
# bar's top is where the frame's sum puts it, to 4 pixels: some pass below, none above.
set -- $(plot passes)
px=$1 py=$2 pw=$3 ph=$4 pmax=$5 pn=$6
check "the pass chart has a slot a frame" test "$pn" = 4
for f in 0 1 2 3; do
    want=$(awk -v px="$px" -v py="$py" -v pw="$pw" -v ph="$ph" -v max="$pmax" -v n="$pn" -v i="$f" '
        /"name":/ {
            name = $0; sub(/.*"name": "/, "", name); sub(/".*/, "", name)
            ms = $0; sub(/.*"gpu_ms": /, "", ms); sub(/[,}].*/, "", ms)
            if (ms + 0 > best) { best = ms + 0; lo = sum; top = name }
            sum += ms
        }
        END {
            y = py + ph - sum / max * ph
            printf "%d %d %s %d %d\n", px + (i + 0.5) * pw / n,
                py + ph - (lo + best / 2) / max * ph, top, y - 4, y + 4
        }' "$T/seq/frame.000$f.timing.json")
    set -- $want
    got=$("$PIXELS" "$T/shot.png" "$1" "$2")
    check "frame $f's bar at ($1, $2) has its largest pass '$3' ($got)" \
        test "$got" = "$(color passes "$3")"
    above=$("$PIXELS" "$T/shot.png" "$1" "$4")
    check "4 pixels above frame $f's bar, at ($1, $4), is no pass ($above)" \
        test -z "$(section passes | grep "fill=\"#$above\" data-series")"
    below=$("$PIXELS" "$T/shot.png" "$1" "$5")
    check "4 pixels below the top of frame $f's bar, at ($1, $5), is a pass ($below)" \
        test -n "$(section passes | grep "fill=\"#$below\" data-series")"
done

# The bdpt sequence's page: each frame's hit-ratio point is where its sidecar's hits.mean puts
# it, through the plot area and axis the page declares: the hit ratio's colour there, and not 8
# pixels above or below it (the line between points is nearly flat there, a slot being 107
# pixels wide).
page=$bpage
browser --window-size=960,1950 --screenshot="$T/bshot.png" "file://$page"
check "Chromium takes a screenshot of the bdpt page" test -s "$T/bshot.png"
hc=$(color hit-ratio "hit ratio")
check "the hit-ratio chart's legend names its colour ($hc)" test -n "$hc"
set -- $(plot hit-ratio)
px=$1 py=$2 pw=$3 ph=$4 pmax=$5 pn=$6
check "the hit-ratio chart runs from 0 to 1 with a slot a frame" test "$pmax $pn" = "1 6"
drawn "$T/bshot.png" "hit-ratio hit ratio" "warped excess" "warped sequence" \
    "reference-error relMSE" "reference-flip FLIP"
for f in 0 1 2 3 4 5; do
    set -- $(awk -v px="$px" -v py="$py" -v pw="$pw" -v ph="$ph" -v max="$pmax" -v n="$pn" \
        -v i="$f" -v v="$(hits_mean $f)" 'BEGIN {
            x = int(px + (i + 0.5) * pw / n); y = int(py + ph - v / max * ph)
            printf "%d %d %d %d\n", x, y, y - 8, y + 8 }')
    got=$("$PIXELS" "$T/bshot.png" "$1" "$2")
    check "frame $f's hit-ratio point at ($1, $2) has the series' colour ($got)" test "$got" = "$hc"
    above=$("$PIXELS" "$T/bshot.png" "$1" "$3")
    below=$("$PIXELS" "$T/bshot.png" "$1" "$4")
    check "8 pixels above and below frame $f's point are not the series' ($above, $below)" \
        test "$above" != "$hc" -a "$below" != "$hc"
done

done_testing
