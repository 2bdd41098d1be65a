#!/bin/sh
# raybundle compare: metrics with known answers on images made by oiiotool (offset, outlier,
# masks, alpha, a depth step), text and JSON output, thresholds and exit codes, usage errors,
# missing layers, frame sequences of a tiny render, and the error image's channels.
# RB_TEST_NO_PYTHON=1 forces the grep-only JSON check that runs where python3 is missing.
. tests/integration/lib.sh

# value KEY: the value of a text-output line ("rmse       0.25" -> 0.25).
value() {
    sed -n "s/^$1  *\([^ ]*\).*/\1/p" "$T/stdout"
}
# ---- usage ---------------------------------------------------------------------------------

rb compare --help
expect_exit 0 "compare --help exits 0"
check "compare --help shows usage on stdout" grep -q 'usage: raybundle compare A B' "$T/stdout"
rb --help
check "raybundle --help lists compare" grep -q '^  compare ' "$T/stdout"
check "raybundle(1) documents compare" grep -q '^\.B compare$' man/raybundle.1
rb compare
expect_exit 2 "compare without images exits 2"
stderr_has "compare needs two images" "a missing image is explained"
rb compare a.exr
expect_exit 2 "compare with one image exits 2"
rb compare a.exr b.exr c.exr
expect_exit 2 "compare with three images exits 2"
rb compare a.exr b.exr --bogus
expect_exit 2 "unknown option exits 2"
rb compare a.exr b.exr --max-relmse lots
expect_exit 2 "a bad --max-relmse exits 2"
stderr_has "--max-relmse expects a number" "a bad --max-relmse is explained"
rb compare a.exr b.exr --epsilon 0
expect_exit 2 "--epsilon 0 exits 2"
rb compare a.exr b.exr --exclude-edges -1
expect_exit 2 "a negative --exclude-edges exits 2"

# ---- images with known answers -------------------------------------------------------------

mk() { # mk NAME OIIOTOOL-ARGS...: makes $T/NAME.exr as float
    name=$1
    shift
    oiiotool "$@" -d float -o "$T/$name.exr" >"$T/oiio.log" 2>&1 ||
        { cat "$T/oiio.log"; fail_all "oiiotool makes $name.exr"; }
}
mk a --pattern constant:color=0.5,0.5,0.5 16x16 3
mk c --pattern constant:color=0.75,0.75,0.75 16x16 3
mk out --pattern constant:color=0.5,0.5,0.5 16x16 3 --fill:color=1,1,1 1x1+3+5
mk small --pattern constant:color=0.5,0.5,0.5 8x8 3
mk mask --pattern constant:color=1 16x16 1 --fill:color=0 1x1+3+5
# Left half transparent black; an outlier at (2, 2) in the transparent half of alpha_out.
mk alpha --pattern constant:color=0.5,0.5,0.5,1 16x16 4 --fill:color=0,0,0,0 8x16+0+0
mk alpha_out --pattern constant:color=0.5,0.5,0.5,1 16x16 4 --fill:color=0,0,0,0 8x16+0+0 \
    --fill:color=1,1,1,0 1x1+2+2
# Depth 2 on the left, 4 from column 8 on; an outlier on the step at (8, 3).
mk depth --pattern constant:color=0.5,0.5,0.5,1,2 16x16 5 --chnames R,G,B,A,depth.Z \
    --fill:color=0.5,0.5,0.5,1,4 8x16+8+0
mk depth_out --pattern constant:color=0.5,0.5,0.5,1,2 16x16 5 --chnames R,G,B,A,depth.Z \
    --fill:color=0.5,0.5,0.5,1,4 8x16+8+0 --fill:color=1,1,1,1,4 1x1+8+3
mk depth_far --pattern constant:color=0.5,0.5,0.5,1,2.5 16x16 5 --chnames R,G,B,A,depth.Z \
    --fill:color=0.5,0.5,0.5,1,4 8x16+8+0

rb compare "$T/a.exr" "$T/a.exr"
expect_exit 0 "identical images exit 0"
for kv in "pixels 256" "rmse 0" "relmse 0" "mae 0" "psnr inf"; do
    check "identical images: ${kv% *} is ${kv#* }" test "$(value "${kv% *}")" = "${kv#* }"
done
stdout_has '^max_error  *0 at (0, 0)$' "identical images: max_error 0 at (0, 0)"
stdout_has '^layer  *beauty (R, G, B)$' "the layer line names the channels"

# 0.75 against 0.5: (a-b)^2 = 1/16, relMSE = (1/16) / (1/4 + 1/100), PSNR = 10 log10(1 / (1/16))
# with the default peak 1.
rb compare "$T/c.exr" "$T/a.exr"
expect_exit 0 "a constant offset exits 0"
for kv in "rmse 0.25" "relmse 0.240384615" "mae 0.25" "psnr 12.0411998"; do
    check "constant offset: ${kv% *} is ${kv#* }" test "$(value "${kv% *}")" = "${kv#* }"
done
stdout_has '^psnr  *12.0411998 dB (peak 1)$' "psnr is in dB, with the peak it used"
rb compare "$T/c.exr" "$T/a.exr" --epsilon 0.75
check "--epsilon 0.75 gives relmse 1/16" test "$(value relmse)" = "0.0625"

# PSNR's peak is 1 whatever the reference holds: a pixel of 40 in both images (an emitter) does
# not change it. 765 of 768 values differ by 1/4: PSNR = 10 log10(768 / (765 / 16)).
mk c_bright --pattern constant:color=0.75,0.75,0.75 16x16 3 --fill:color=40,40,40 1x1+9+9
mk a_bright --pattern constant:color=0.5,0.5,0.5 16x16 3 --fill:color=40,40,40 1x1+9+9
rb compare "$T/c_bright.exr" "$T/a_bright.exr" --json
expect_exit 0 "a bright reference exits 0"
check "a bright reference: the peak is still 1" grep -qF '"peak": 1,' "$T/stdout"
check "a bright reference: psnr is 10 log10(768 / (765 / 16))" \
    grep -qF '"psnr": 12.0581977,' "$T/stdout"
rb compare "$T/c.exr" "$T/a.exr" --peak 0.5
expect_exit 0 "--peak 0.5 exits 0"
check "--peak 0.5: psnr is 10 log10(0.25 / (1/16))" test "$(value psnr)" = 6.02059991
stdout_has '^psnr  *6.02059991 dB (peak 0.5)$' "--peak 0.5: the peak is printed"
rb compare "$T/c.exr" "$T/a.exr" --peak 40 --json
check "--peak 40: JSON has the peak" grep -qF '"peak": 40,' "$T/stdout"
check "--peak 40: psnr is 10 log10(1600 * 16)" grep -qF '"psnr": 44.0823997,' "$T/stdout"
rb compare --help
check "compare --help states the peak 1.0" grep -q 'PSNR is computed with peak 1.0' "$T/stdout"
check "compare --help lists --peak" grep -q '^  --peak V ' "$T/stdout"
check "raybundle(1) documents --peak" grep -q '^\.BI \\-\\-peak " V"$' man/raybundle.1
for bad in 0 -1 x inf; do
    rb compare "$T/c.exr" "$T/a.exr" --peak "$bad"
    expect_exit 2 "--peak $bad exits 2"
    stderr_has "--peak expects a number > 0, got '$bad'" "--peak $bad is explained"
done

rb compare "$T/out.exr" "$T/a.exr"
stdout_has '^max_error  *0.5 at (3, 5)$' "one outlier: max_error 0.5 at (3, 5)"
rb compare "$T/out.exr" "$T/a.exr" --mask "$T/mask.exr"
expect_exit 0 "--mask exits 0"
check "--mask leaves 255 pixels" test "$(value pixels)" = 255
check "--mask hides the outlier" test "$(value rmse)" = 0

rb compare "$T/out.exr" "$T/a.exr" --json
expect_exit 0 "--json exits 0"
for kv in '"a": "'"$T/out.exr"'"' '"b": "'"$T/a.exr"'"' '"layer": "beauty"' '"pixels": 256' \
    '"max_error": 0.5' '"max_error_pixel": [3, 5]' '"epsilon": 0.01'; do
    check "JSON has $kv" grep -qF "$kv" "$T/stdout"
done
check "JSON has no frames for single images" sh -c "! grep -q '\"frames\"' '$T/stdout'"
rb compare "$T/a.exr" "$T/a.exr" --json
check "JSON: infinite psnr is null" grep -qF '"psnr": null' "$T/stdout"
if [ -z "${RB_TEST_NO_PYTHON:-}" ] && command -v python3 >/dev/null 2>&1; then
    check "--json prints one valid JSON object" python3 -c '
import json, sys
d = json.load(open(sys.argv[1]))
assert d["rmse"] == 0 and d["psnr"] is None and d["channels"] == ["R", "G", "B"], d' "$T/stdout"
else
    check "--json prints one object (no python3: grep only)" sh -c \
        "head -n 1 '$T/stdout' | grep -qx '{' && tail -n 1 '$T/stdout' | grep -qx '}'"
fi

# ---- thresholds ----------------------------------------------------------------------------

rb compare "$T/c.exr" "$T/a.exr" --max-relmse 0.25
expect_exit 0 "relmse under --max-relmse exits 0"
rb compare "$T/c.exr" "$T/a.exr" --max-relmse 0.2
expect_exit 1 "relmse over --max-relmse exits 1"
stderr_has "relmse 0.240384615 exceeds --max-relmse 0.2" "the failed threshold is named"
check "the metrics are still printed" test "$(value rmse)" = 0.25
rb compare "$T/c.exr" "$T/a.exr" --max-rmse 0.25
expect_exit 0 "rmse equal to --max-rmse exits 0"
rb compare "$T/c.exr" "$T/a.exr" --max-rmse 0.1 --max-relmse 1
expect_exit 1 "rmse over --max-rmse exits 1"
stderr_has "rmse 0.25 exceeds --max-rmse 0.1" "the failed rmse threshold is named"
check "a passed threshold is not reported" sh -c "! grep -q 'max-relmse' '$T/stderr'"

# A NaN in the red channel of pixel (2, 2): skipped and counted; it fails any threshold.
mk nan --pattern constant:color=0.5,0.5,0.5 16x16 3 --fill:color=nan,0.5,0.5 1x1+2+2
rb compare "$T/nan.exr" "$T/a.exr"
expect_exit 0 "a NaN pixel without a threshold exits 0"
check "the NaN pixel is skipped" test "$(value pixels)" = 255
stdout_has '^nonfinite  *1 pixels skipped$' "the NaN pixel is counted"
stderr_has "warning: 1 pixels hold NaN or infinite values" "the NaN pixel is warned about"
rb compare "$T/nan.exr" "$T/a.exr" --max-rmse 1
expect_exit 1 "a NaN pixel fails a threshold"
stderr_has "1 pixels hold NaN or infinite values, which fails any threshold" \
    "the NaN failure is explained"

# ---- bad inputs ----------------------------------------------------------------------------

rb compare "$T/a.exr" "$T/small.exr"
expect_exit 2 "mismatched sizes exit 2"
stderr_has "size mismatch: '$T/a.exr' is 16x16, '$T/small.exr' is 8x8" "the sizes are named"
rb compare "$T/a.exr" "$T/nope.exr"
expect_exit 2 "an unreadable file exits 2"
stderr_has "'$T/nope.exr'" "the unreadable file is named"
rb compare "$T/a.exr" "$T/a.exr" --layer direct
expect_exit 2 "a missing layer exits 2"
stderr_has "'$T/a.exr' has no layer 'direct'; its layers: beauty" \
    "the missing layer and file are named, with the layers the file has"
# A layer there in part: the missing channel is named.
mk half_normal --pattern constant:color=0.5,0.5,0.5,1 16x16 4 --chnames R,G,B,normal.X
rb compare "$T/half_normal.exr" "$T/half_normal.exr" --layer normal
expect_exit 2 "a layer with a missing channel exits 2"
stderr_has "'$T/half_normal.exr' has no layer 'normal': channel 'normal.Y' is missing" \
    "the missing channel is named"
# Layer names match whatever their case, the file's or the option's.
mk custom --pattern constant:color=0.5,0.5,0.5,0.25,0.75,1 16x16 6 \
    --chnames R,G,B,Diffuse.R,Diffuse.G,Diffuse.B
mk custom2 --pattern constant:color=0.5,0.5,0.5,0.25,0.75,0.5 16x16 6 \
    --chnames R,G,B,diffuse.R,diffuse.G,diffuse.B
rb compare "$T/custom2.exr" "$T/custom.exr" --layer DIFFUSE
expect_exit 0 "--layer DIFFUSE finds Diffuse.* and diffuse.* (exit 0)"
check "--layer DIFFUSE compares the layer: rmse is sqrt(1/12)" test "$(value rmse)" = 0.288675135
rb compare "$T/a.exr" "$T/a.exr" --mask "$T/small.exr"
expect_exit 2 "a mask of another size exits 2"
rb compare "$T/a.exr" "$T/a.exr" --mask-alpha
expect_exit 2 "--mask-alpha without alpha exits 2"
stderr_has "--mask-alpha needs channel 'A', which '$T/a.exr' does not have" \
    "the file without alpha is named"
rb compare "$T/a.exr" "$T/a.exr" --exclude-edges 1
expect_exit 2 "--exclude-edges without depth exits 2"
stderr_has "--exclude-edges needs channel 'depth.Z'" "the missing depth is named"
rb compare "$T/a.exr" "$T/a.exr" --frames 0-1
expect_exit 2 "--frames with single images exits 2"
rb compare "$T/a.####.exr" "$T/a.exr" --frames 0-1
expect_exit 2 "a pattern against a single image exits 2"

# ---- alpha, depth and edges ----------------------------------------------------------------

rb compare "$T/alpha_out.exr" "$T/alpha.exr"
check "the transparent outlier counts without a mask" test "$(value rmse)" != 0
rb compare "$T/alpha_out.exr" "$T/alpha.exr" --mask-alpha
expect_exit 0 "--mask-alpha exits 0"
check "--mask-alpha keeps the 128 opaque pixels" test "$(value pixels)" = 128
check "--mask-alpha hides the transparent outlier" test "$(value rmse)" = 0

rb compare "$T/depth_out.exr" "$T/depth.exr"
stdout_has '^max_error  *0.5 at (8, 3)$' "the outlier on the depth step is found"
rb compare "$T/depth_out.exr" "$T/depth.exr" --exclude-edges 1
expect_exit 0 "--exclude-edges exits 0"
check "--exclude-edges 1 drops the two columns at the step" test "$(value pixels)" = 224
check "--exclude-edges hides the outlier on the step" test "$(value rmse)" = 0
rb compare "$T/depth_out.exr" "$T/depth.exr" --exclude-edges 2
check "--exclude-edges 2 drops four columns" test "$(value pixels)" = 192
rb compare "$T/depth_far.exr" "$T/depth.exr" --layer depth --json
expect_exit 0 "--layer depth exits 0"
check "--layer depth compares depth.Z" grep -qF '"channels": ["depth.Z"]' "$T/stdout"
check "--layer depth: rmse is sqrt(1/8)" grep -qF '"rmse": 0.353553391' "$T/stdout"

# ---- error image ---------------------------------------------------------------------------

rb compare "$T/out.exr" "$T/a.exr" --error-image "$T/err/diff.exr"
expect_exit 0 "--error-image exits 0"
oiiotool --info -v "$T/err/diff.exr" >"$T/info" 2>&1
check "oiiotool reads the error image" test $? -eq 0
check "the error image has R, G, B and relmse.Y" \
    grep -q 'channel list: R, G, B, relmse.Y$' "$T/info"
oiiotool "$T/err/diff.exr" --ch R --printstats >"$T/stats" 2>&1
check "the error image's R peaks at the outlier's 0.5" grep -q 'Stats Max: 0.500000' "$T/stats"
check "no temporary files are left" sh -c "! ls '$T/err' | grep -q tmp"

# ---- frame sequences of a tiny render ------------------------------------------------------

rb render jobs/quick.yaml --frames 0-1 --size 64x36 --out "$T/r" -q
expect_exit 0 "two tiny frames render"
seq="$T/r/frame.####.exr"

rb compare "$seq" "$seq" --frames 0-1
expect_exit 0 "a sequence against itself exits 0"
check "a sequence against itself: relmse 0" test "$(value relmse)" = 0
check "a sequence counts the pixels of both frames" test "$(value pixels)" = 4608
stdout_has '^frames  *0-1$' "the text names the frame range"
check "the per-frame table has one row a frame" test "$(grep -c '^  *[01]  *2304 ' "$T/stdout")" = 2
rb compare "$seq" "$seq" --frames 0-1 --max-relmse 0
expect_exit 0 "relmse 0 passes --max-relmse 0"

rb compare "$T/r/frame.0001.exr" "$T/r/frame.0000.exr"
expect_exit 0 "two different frames exit 0"
check "two different frames: relmse > 0" awk '/^relmse/ { exit !($2 > 0) }' "$T/stdout"
rb compare "$T/r/frame.0001.exr" "$T/r/frame.0000.exr" --max-relmse 0
expect_exit 1 "two different frames fail --max-relmse 0"

rb compare "$seq" "$seq" --frames 0-1 --json --error-image "$T/seqerr/e.####.exr"
expect_exit 0 "a sequence with --json and error images exits 0"
check "JSON lists frame 0" grep -qF '{"frame": 0, "a": "'"$T/r/frame.0000.exr"'"' "$T/stdout"
check "JSON lists frame 1" grep -qF '{"frame": 1, ' "$T/stdout"
check "JSON names the frame of the largest error" grep -qF '"max_error_frame": 0' "$T/stdout"
check "one error image a frame" test -s "$T/seqerr/e.0000.exr" -a -s "$T/seqerr/e.0001.exr"
cp "$T/stdout" "$T/json1"
rb compare "$seq" "$seq" --frames 0-1 --json
check "the output is the same bytes on a second run" cmp -s "$T/stdout" "$T/json1"

rb compare "$seq" "$seq" --frames 0-2
expect_exit 2 "a missing frame exits 2"
stderr_has "frame 2: cannot read '$T/r/frame.0002.exr'" "the missing frame is named"
rb compare "$seq" "$seq"
expect_exit 2 "patterns without --frames exit 2"
stderr_has "need --frames" "--frames is asked for"
rb compare "$seq" "$seq" --frames 0-1 --error-image "$T/one.exr"
expect_exit 2 "a sequence's --error-image needs a '#' run"

rb compare "$seq" "$seq" --frames 0-1 --layer direct
expect_exit 0 "--layer direct on rendered frames exits 0"
stdout_has '^layer  *direct (direct.R, direct.G, direct.B)$' "--layer direct compares direct.R/G/B"
rb compare "$T/r/frame.0001.exr" "$T/r/frame.0000.exr" --layer Normal --json
expect_exit 0 "--layer Normal on rendered frames exits 0"
check "--layer Normal compares normal.X/Y/Z" \
    grep -qF '"channels": ["normal.X", "normal.Y", "normal.Z"]' "$T/stdout"
cp "$T/stdout" "$T/normal-mixed"
rb compare "$T/r/frame.0001.exr" "$T/r/frame.0000.exr" --layer normal --json
check "--layer Normal gives --layer normal's numbers" cmp -s "$T/stdout" "$T/normal-mixed"
check "the normals of the two frames differ (rmse > 0)" \
    awk -F': ' '/"rmse"/ { sub(/,$/, "", $2); exit !($2 > 0) }' "$T/stdout"
rb compare "$T/r/frame.0001.exr" "$T/r/frame.0000.exr" --layer foo
expect_exit 2 "a layer the frame does not have exits 2"
stderr_has "'$T/r/frame.0001.exr' has no layer 'foo'; its layers: beauty, direct, indirect, albedo, normal, depth, motion" \
    "the missing layer is named with the frame's layers"
rb compare "$T/r/frame.0001.exr" "$T/r/frame.0000.exr" --layer depth --mask-alpha
expect_exit 0 "--layer depth --mask-alpha on rendered frames exits 0"
geometry=$(value pixels)
check "--mask-alpha keeps some but not all pixels" test "$geometry" -gt 0 -a "$geometry" -lt 2304
rb compare "$T/r/frame.0001.exr" "$T/r/frame.0000.exr" --layer depth --mask-alpha \
    --exclude-edges 1
expect_exit 0 "--exclude-edges on rendered frames exits 0"
check "--exclude-edges drops silhouette pixels" test "$(value pixels)" -lt "$geometry"

done_testing
