#!/bin/sh
# raybundle flicker: a short render of the demo and its reference from `raybundle reference
# --frames A-B` (which must write every frame of the range under the names flicker reads); the
# JSON, CSV and text agree, the excess matches oiiotool's own arithmetic on the same files, and
# --max-excess gates on it; the rendered motion layer points where flicker reads it (the
# sequence reprojects better through it than through no motion or the reverse); usage errors,
# missing sequences and frames, mismatched sizes and a missing motion layer are named.
. tests/integration/lib.sh

# ---- usage ---------------------------------------------------------------------------------

rb flicker --help
expect_exit 0 "flicker --help exits 0"
check "flicker --help shows its usage" grep -q 'usage: raybundle flicker SEQ' "$T/stdout"
# documented OPTION: raybundle-flicker(1) has a .TP entry for it (written as roff writes '-').
documented() {
    O=$(printf '%s' "$1" | sed 's/-/\\-/g') awk '
        prev == ".TP" { sub(/ ".*$/, ""); if ($0 == ".BI " ENVIRON["O"] || $0 == ".B " ENVIRON["O"]) f = 1 }
        { prev = $0 }
        END { exit !f }' man/raybundle-flicker.1
}
for opt in --reference --max-excess --depth-tolerance --log-epsilon --json --csv; do
    check "raybundle-flicker(1) documents $opt" documented "$opt"
done
if documented --bogus; then not_ok "the man-page check finds no --bogus"; else ok "the man-page check finds no --bogus"; fi
rb flicker
expect_exit 2 "flicker without SEQ exits 2"
stderr_has "flicker needs a sequence, SEQ" "a missing SEQ is explained"
rb flicker "$T/a" "$T/b"
expect_exit 2 "flicker of two sequences exits 2"
rb flicker "$T/a" --json --csv
expect_exit 2 "--json with --csv exits 2"
stderr_has "--json and --csv exclude each other" "--json with --csv is explained"
rb flicker "$T/a" --max-excess 0.1
expect_exit 2 "--max-excess without --reference exits 2"
stderr_has "--max-excess needs --reference REFSEQ" "--max-excess without a reference is explained"
rb flicker "$T/a" --reference "$T/b" --max-excess -1
expect_exit 2 "--max-excess -1 exits 2"
stderr_has "--max-excess expects a number >= 0, got '-1'" "a negative --max-excess is named"
rb flicker "$T/a" --depth-tolerance 0
expect_exit 2 "--depth-tolerance 0 exits 2"
rb flicker "$T/a" --log-epsilon nope
expect_exit 2 "--log-epsilon nope exits 2"

# ---- a sequence and its reference ----------------------------------------------------------

rb render jobs/demo.yaml --size 64x36 --frames 0-4 --out "$T/seq" -q
expect_exit 0 "render 5 frames of the demo"
rb reference jobs/demo.yaml --size 64x36 --frames 0-4 --spp 4 --out "$T/ref" -q
expect_exit 0 "render their reference with raybundle reference --frames 0-4"
check "the reference wrote each frame of the range, and only those" \
    test "$(cd "$T/ref" && ls ./*.exr | tr '\n' ' ')" = \
    "./frame.0000.exr ./frame.0001.exr ./frame.0002.exr ./frame.0003.exr ./frame.0004.exr "
check "the reference's frames have motion and depth layers" \
    sh -c "oiiotool --info -v '$T/ref/frame.0003.exr' | grep -q 'depth.Z, .*motion.X, motion.Y'"

rb flicker "$T/seq" --reference "$T/ref" --json
expect_exit 0 "flicker --json of the sequence against its reference exits 0"
cp "$T/stdout" "$T/flicker.json"
check "the JSON names the sequence" grep -q "^  \"sequence\": \"$T/seq/frame.####.exr\",\$" \
    "$T/flicker.json"
check "the JSON has the 5 frames, by their own numbers" \
    test "$(grep '^      "frame": ' "$T/flicker.json" | tr -d ' \n')" = \
    '"frame":0,"frame":1,"frame":2,"frame":3,"frame":4,'
check "frame 0 has no warped error (no frame before it)" \
    sh -c "sed -n '/\"frame\": 0,/,/}/p' '$T/flicker.json' | grep -q '\"warped_error\": null'"
# json KEY: the value of the summary's KEY.
json() {
    sed -n "s/^    \"$1\": \([^,]*\),*\$/\1/p" "$T/flicker.json"
}
excess=$(json excess_error_mean)
check "the mean excess error is a number above 0 ($excess)" \
    awk -v e="$excess" 'BEGIN { exit !(e + 0 > 0) }'
warped=$(json warped_error_mean)
check "the mean warped error is a number above 0 ($warped)" \
    awk -v e="$warped" 'BEGIN { exit !(e + 0 > 0) }'
check "the reference's own metrics are there" grep -q '^    "reference": {$' "$T/flicker.json"

rb flicker "$T/seq/frame.####.exr" --reference "$T/ref/frame.####.exr" --csv
expect_exit 0 "flicker --csv with patterns exits 0"
cp "$T/stdout" "$T/flicker.csv"
check "the CSV has its header" test "$(head -n 1 "$T/flicker.csv")" = \
    "frame,warped_error,compared,disoccluded,offscreen,static_deviation,excess_error,reference_warped_error,reference_static_deviation,excess_rms"
check "the CSV has a row a frame and the row 'all'" \
    test "$(cut -d, -f1 "$T/flicker.csv" | tr '\n' ' ')" = "frame 0 1 2 3 4 all "
check "the CSV's mean excess is the JSON's" \
    test "$(sed -n 's/^all,\([^,]*,\)\{5\}\([^,]*\),.*/\2/p' "$T/flicker.csv")" = "$excess"
check "the row 'all' holds the mean of the frames' excess" awk -F, '
    $1 ~ /^[0-9]+$/ && $7 != "" { sum += $7; n++ }
    $1 == "all" { all = $7 }
    END { exit !(n == 4 && (all - sum / n) ^ 2 < 1e-16) }' "$T/flicker.csv"
# Each frame's excess, recomputed by oiiotool from the same files: luminance of
# (I_t - I_t-1) - (R_t - R_t-1), its absolute value's mean.
for f in 1 2 3 4; do
    p=$((f - 1))
    want=$(oiiotool "$T/seq/frame.000$f.exr" --ch R,G,B "$T/seq/frame.000$p.exr" --ch R,G,B --sub \
        "$T/ref/frame.000$f.exr" --ch R,G,B "$T/ref/frame.000$p.exr" --ch R,G,B --sub --sub \
        --chsum:weight=0.2126,0.7152,0.0722 --abs --printstats | sed -n 's/.*Stats Avg: \([^ ]*\).*/\1/p')
    got=$(awk -F, -v f="$f" '$1 == f { print $7 }' "$T/flicker.csv")
    check "frame $f's excess ($got) is oiiotool's ($want)" \
        awk -v a="$got" -v b="$want" 'BEGIN { exit !(b > 0 && (a - b) ^ 2 < 1e-11) }'
done

rb flicker "$T/seq" --reference "$T/ref"
expect_exit 0 "flicker as text exits 0"
stdout_has "^sequence   $T/seq/frame.####.exr: 5 frames, 0 to 4, 64x36\$" "the text names the sequence"
stdout_has "^excess temporal error  *mean $excess, max " "the text has the JSON's mean excess"

# ---- --max-excess --------------------------------------------------------------------------

above=$(awk -v e="$excess" 'BEGIN { printf "%.9g", 2 * e }')
below=$(awk -v e="$excess" 'BEGIN { printf "%.9g", e / 2 }')
rb flicker "$T/seq" --reference "$T/ref" --max-excess "$above"
expect_exit 0 "--max-excess twice the excess ($above) exits 0"
rb flicker "$T/seq" --reference "$T/ref" --max-excess "$below" --csv
expect_exit 1 "--max-excess half the excess ($below) exits 1"
stderr_has "excess temporal error $excess exceeds --max-excess $below" "the gate says why"
check "the metrics are printed when the gate fails" grep -q '^all,' "$T/stdout"
rb flicker "$T/seq" --reference "$T/seq" --max-excess 0
expect_exit 0 "a sequence against itself has no excess (--max-excess 0 exits 0)"

# ---- the motion layer's direction ----------------------------------------------------------

# Reprojected through its own motion, the sequence matches its previous frame better than with
# no motion, or with the motion reversed (a camera move of about 1 pixel a frame at 320x180).
rb render jobs/demo.yaml --size 320x180 --frames 30-32 --out "$T/move" -q
expect_exit 0 "render 3 moving frames at 320x180"
mkdir -p "$T/still" "$T/reversed"
for f in 30 31 32; do
    oiiotool "$T/move/frame.00$f.exr" --ch "R,G,B,A,depth.Z,motion.X=0,motion.Y=0" \
        -o "$T/still/frame.00$f.exr"
    oiiotool "$T/move/frame.00$f.exr" --ch "R,G,B,A,depth.Z,motion.X,motion.Y" \
        --mulc 1,1,1,1,1,-1,-1 -o "$T/reversed/frame.00$f.exr"
done
for d in move still reversed; do
    rb flicker "$T/$d" --csv
    eval "w_$d=\$(sed -n 's/^all,\([^,]*\),.*/\1/p' '$T/stdout')"
done
check "the motion layer helps: warped error $w_move < $w_still without motion" \
    awk -v a="$w_move" -v b="$w_still" 'BEGIN { exit !(a + 0 > 0 && a + 0 < b + 0) }'
check "reversed, it hurts: $w_still without motion < $w_reversed reversed" \
    awk -v a="$w_still" -v b="$w_reversed" 'BEGIN { exit !(a + 0 < b + 0) }'

# ---- static pixels -------------------------------------------------------------------------

# The quick job's camera stands still, so the walls are static; the demo's moves.
rb render jobs/quick.yaml --size 64x36 --out "$T/quick" -q
expect_exit 0 "render the quick job (a still camera)"
rb flicker "$T/quick" --json
cp "$T/stdout" "$T/flicker.json"
static=$(json static_pixels)
check "a still camera leaves static pixels ($static)" test "${static:-0}" -gt 0
check "their variance is a number ($(json static_variance))" \
    awk -v v="$(json static_variance)" 'BEGIN { exit !(v != "null" && v + 0 >= 0) }'
check "a moving camera leaves none" \
    sh -c "'$RB' flicker '$T/move' --json | grep -q '^    \"static_pixels\": 0,'"

# ---- what does not match -------------------------------------------------------------------

rb flicker "$T/nowhere"
expect_exit 2 "flicker of a missing directory exits 2"
stderr_has "cannot open '$T/nowhere'" "the missing directory is named"
rb flicker "$T/seq/take.####.exr"
expect_exit 2 "a pattern no frame matches exits 2"
stderr_has "no frames match '$T/seq/take.####.exr'" "the pattern is named"
rb reference jobs/demo.yaml --size 32x18 --frames 0-4 --spp 1 --out "$T/ref-small" -q
rb flicker "$T/seq" --reference "$T/ref-small"
expect_exit 2 "a reference of another size exits 2"
stderr_has "size mismatch: '$T/ref-small/frame.0000.exr' is 32x18, '$T/seq/frame.0000.exr' is 64x36" \
    "the size mismatch is named"
cp -r "$T/ref" "$T/ref-gap" && rm "$T/ref-gap/frame.0003.exr"
rb flicker "$T/seq" --reference "$T/ref-gap"
expect_exit 2 "a reference without frame 3 exits 2"
stderr_has "the reference '$T/ref-gap' has no frame 3 (for '$T/seq/frame.0003.exr')" \
    "the missing reference frame is named"
cp -r "$T/seq" "$T/nomotion"
oiiotool "$T/seq/frame.0002.exr" --ch R,G,B,A,depth.Z -o "$T/nomotion/frame.0002.exr"
rb flicker "$T/nomotion"
expect_exit 2 "a frame without the motion layer exits 2"
stderr_has "'$T/nomotion/frame.0002.exr' has no layer 'motion'; its layers: beauty, depth" \
    "the frame without motion is named, with the layers it has"
check "nothing went to stdout" test ! -s "$T/stdout"

done_testing
