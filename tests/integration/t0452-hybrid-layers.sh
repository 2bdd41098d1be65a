#!/bin/sh
# The samples and tiles layers: the hybrid integrator's per-lobe sample counts (of the
# accumulator the output reads) and tile masks (where the next frame's rays stop). On a still
# shot every surface pixel gains a sample a lobe a frame until it has what it wants, capped by
# spp; pixels whose tile is done do not gain any in the next frame; a noise target every tile
# meets stops them all, 0 stops none. The reference writes its spp and no done tile; direct and
# bdpt, which keep no counts, are refused with the file, line and column.
. tests/integration/lib.sh

S=samples.diffuse,samples.specular
M=tiles.diffuse,tiles.specular
# chstat EXR CHANNELS WHAT: oiiotool's "Stats WHAT" (Min, Max or Avg) of those channels
chstat() {
    oiiotool "$1" --ch "$2" --printstats 2>/dev/null | sed -n "s/^ *Stats $3: \(.*\) (float)$/\1/p"
}
frame() { printf '%s/frame.%04d.exr' "$1" "$2"; }
# grows DIR N: per lobe, frame N+1's samples minus frame N's minus alpha (1 on a surface): "0 0"
# in Min and Max when every surface pixel gained exactly one sample and no other pixel any
grows() {
    a=$(frame "$1" "$2")
    b=$(frame "$1" $(($2 + 1)))
    oiiotool "$b" --ch "$S" "$a" --ch "$S" --sub "$b" --ch "d=A,s=A" --sub --printstats \
        2>/dev/null | sed -n 's/^ *Stats M[a-z]*: \(.*\) (float)$/\1/p' | tr '\n' ' '
}
# gain_where_done DIR N: per lobe, the most samples a pixel gained from frame N to N+1 where
# frame N's tile mask says its rays stop
gain_where_done() {
    a=$(frame "$1" "$2")
    b=$(frame "$1" $(($2 + 1)))
    oiiotool "$b" --ch "$S" "$a" --ch "$S" --sub "$a" --ch "$M" --mul --printstats 2>/dev/null |
        sed -n 's/^ *Stats Max: \(.*\) (float)$/\1/p'
}
# alpha_times EXR K: the largest |samples - K alpha| of each lobe: "0.000000 0.000000" when
# every surface pixel (alpha 1) has K samples a lobe and every other pixel none
alpha_times() {
    oiiotool "$1" --ch "$S" "$1" --ch "d=A,s=A" --mulc "$2" --sub --abs --printstats 2>/dev/null |
        sed -n 's/^ *Stats Max: \(.*\) (float)$/\1/p'
}
# same_samples A B: the samples layers of two frames hold the same values
same_samples() {
    test "$(oiiotool "$2" --ch "$S" "$1" --ch "$S" --sub --abs --printstats 2>/dev/null |
        sed -n 's/^ *Stats Max: \(.*\) (float)$/\1/p')" = "0.000000 0.000000"
}
requested() { sed -n 's/.*"ray_counts": {"requested": \([0-9]*\).*/\1/p' "$1"; }

# The demo room, its animation stopped and its camera still (as t0450); W = 64, so the
# accumulators start again at frames 0 and 32 only, and every frame here reads the one of frame 0.
still_demo "$T/still.yaml" 96x54 15 "[direct, samples, tiles]" "{name: hybrid, hybrid: {history: 64}}"
small="-q --validate"

# ---- the layers, and growth with no noise target ----------------------------------------------

# shellcheck disable=SC2086
rb render "$T/still.yaml" $small --frames 0-9 --set integrator.hybrid.noise=0 --out "$T/n0"
expect_exit 0 "ten frames with samples and tiles render, validation-clean"
check "the EXR holds samples and tiles, a channel a lobe, after the other layers" sh -c \
    "oiiotool --info -v '$(frame "$T/n0" 0)' | grep -qx '    channel list: R, G, B, A, direct.R, direct.G, direct.B, samples.diffuse, samples.specular, tiles.diffuse, tiles.specular'"
check "frame 0: every surface pixel has one sample a lobe, every other pixel none" \
    test "$(alpha_times "$(frame "$T/n0" 0)" 1)" = "0.000000 0.000000"
for f in 0 4 8; do
    g=$(grows "$T/n0" $f)
    check "no noise target: from frame $f to $((f + 1)) every surface pixel gains one sample a lobe ($g)" \
        test "$g" = "0.000000 0.000000 0.000000 0.000000 "
done
check "no noise target: no tile is ever done" \
    test "$(chstat "$(frame "$T/n0" 9)" "$M" Max)" = "0.000000 0.000000"

# ---- capped by the samples a lobe wants -------------------------------------------------------

rb render "$T/still.yaml" -q --frames 0-15 --set integrator.hybrid.noise=0 \
    --set integrator.hybrid.spp=8 --out "$T/s8"
expect_exit 0 "sixteen frames with spp 8"
most=0
f=0
while [ $f -le 15 ]; do
    # shellcheck disable=SC2046 # the two lobes' maxima, as $1 and $2
    set -- $(chstat "$(frame "$T/s8" $f)" "$S" Max)
    most=$(awk -v a="$most" -v b="$1" -v c="$2" \
        'BEGIN { m = a + 0; if (b + 0 > m) m = b + 0; if (c + 0 > m) m = c + 0; print m }')
    f=$((f + 1))
done
check "spp 8: the most samples a lobe of a pixel has in frames 0-15 is 8 ($most)" \
    test "$most" = "8"
check "spp 8: by frame 12 every lobe has what it wants: frame 15's samples are frame 12's" \
    same_samples "$(frame "$T/s8" 12)" "$(frame "$T/s8" 15)"
check "spp 8: the rays stop too: frame 15 requests none" \
    test "$(requested "$T/s8/frame.0015.timing.json")" -eq 0

# ---- a noise target every tile meets ----------------------------------------------------------

# shellcheck disable=SC2086
rb render "$T/still.yaml" $small --frames 0-6 --set integrator.hybrid.noise=1000 --out "$T/big"
expect_exit 0 "seven frames with a noise target of 1000"
check "noise 1000: at frame 2 (3 samples, fewer than a tile needs) some tile is not done" \
    test "$(chstat "$(frame "$T/big" 2)" "$M" Min)" = "0.000000 0.000000"
check "noise 1000: from frame 3 (4 samples) every tile is done, in both lobes" \
    test "$(chstat "$(frame "$T/big" 3)" "$M" Min)" = "1.000000 1.000000"
check "noise 1000: done tiles stop their counts: frame 6's samples are frame 3's" \
    same_samples "$(frame "$T/big" 3)" "$(frame "$T/big" 6)"
check "noise 1000: frames 4 to 6 request no ray" test "$(requested "$T/big/frame.0004.timing.json")" \
    -eq 0 -a "$(requested "$T/big/frame.0006.timing.json")" -eq 0

# A frame that starts the younger accumulator again ignores the mask: with W = 8, frame 4.
rb render "$T/still.yaml" -q --frames 0-4 --set integrator.hybrid.noise=1000 \
    --set integrator.hybrid.history=8 --out "$T/w8"
expect_exit 0 "five frames with W = 8"
g=$(grows "$T/w8" 3)
check "W = 8: frame 4 starts accumulator B and asks again where frame 3 was done ($g)" \
    test "$(chstat "$(frame "$T/w8" 3)" "$M" Min)" = "1.000000 1.000000" -a \
    "$g" = "0.000000 0.000000 0.000000 0.000000 "

# ---- a target some tiles meet: done tiles do not grow -----------------------------------------

# shellcheck disable=SC2086
rb render "$T/still.yaml" $small --frames 0-15 --set integrator.hybrid.noise=0.1 --out "$T/mid"
expect_exit 0 "sixteen frames with a noise target of 0.1"
# shellcheck disable=SC2046 # the two lobes' means, as $1 and $2
set -- $(chstat "$(frame "$T/mid" 8)" "$M" Avg)
echo "# noise 0.1, frame 8: done fraction diffuse $1, specular $2"
check "noise 0.1, frame 8: some pixels are done and some are not, in each lobe ($1, $2)" \
    sh -c "awk -v d=$1 -v s=$2 'BEGIN { exit !(d > 0 && d < 1 && s > 0 && s < 1) }'"
bad=""
for f in 3 4 5 6 7 8 9 10 11 12 13 14; do
    gain=$(gain_where_done "$T/mid" $f)
    test "$gain" = "0.000000 0.000000" || bad="$bad $f:($gain)"
done
check "noise 0.1: a pixel whose lobe is done in frame N gains no sample in N+1 (N = 3..14)$bad" \
    test -z "$bad"
g=$(oiiotool "$(frame "$T/mid" 9)" --ch "$S" "$(frame "$T/mid" 8)" --ch "$S" --sub --printstats \
    2>/dev/null | sed -n 's/^ *Stats Max: \(.*\) (float)$/\1/p')
check "noise 0.1: the pixels that are not done still gain samples from frame 8 to 9 ($g)" \
    test "$g" = "1.000000 1.000000"
rb compare "$(frame "$T/mid" 8)" "$(frame "$T/n0" 8)" --layer samples --json
check "compare reads the samples layer by its lobes' channels" \
    grep -q '"channels": \["samples.diffuse", "samples.specular"\]' "$T/stdout"
check "noise 0.1 has fewer samples than no target at frame 8 (compare's rmse is not 0)" \
    sh -c "! grep -q '\"rmse\": 0,' '$T/stdout'"

# ---- determinism: a chunk that pre-rolls W frames has the whole run's counts and masks -------

args="--integrator hybrid --size 48x27 -q --set integrator.hybrid.history=4"
args="$args --set integrator.hybrid.noise=1"
# shellcheck disable=SC2086
rb render jobs/demo.yaml $args --set 'layers=[samples, tiles]' --frames 0-7 --out "$T/whole"
expect_exit 0 "frames 0-7 of the moving demo with samples and tiles"
# shellcheck disable=SC2086
rb render jobs/demo.yaml $args --set 'layers=[samples, tiles]' --frames 5-7 --out "$T/chunk"
for f in 5 6 7; do
    check "moving demo, frame $f: the chunk 5-7 has the whole run's bits" \
        cmp -s "$(frame "$T/whole" $f)" "$(frame "$T/chunk" $f)"
done

# ---- the other integrators ---------------------------------------------------------------------

sed 's/name: hybrid/name: bdpt/' "$T/still.yaml" >"$T/bdpt.yaml"
rb render "$T/bdpt.yaml" -q --frames 0 --out "$T/never"
expect_exit 2 "bdpt asked for samples is refused"
stderr_has "$T/bdpt.yaml:13:20: layer 'samples' is written by the hybrid and reference integrators only, and this job renders with 'bdpt'" \
    "the error names the file, line and column, the layer and the integrator"
rb render "$T/still.yaml" -q --frames 0 --integrator direct --out "$T/never"
expect_exit 2 "--integrator direct on a job with samples is refused"
stderr_has "--integrator 'direct': layer 'samples' is written by the hybrid and reference integrators only, and this job renders with 'direct'" \
    "the error names the option"
rb render "$T/bdpt.yaml" -q --frames 0 --out "$T/never" --set 'layers=[direct, tiles]'
expect_exit 2 "bdpt asked for tiles alone is refused"
stderr_has "layer 'tiles' is written by the hybrid and reference integrators only" "tiles is named"
check "nothing written" test ! -e "$T/never"

rb reference "$T/bdpt.yaml" -q --frames 0 --size 32x18 --spp 3 --out "$T/ref"
expect_exit 0 "the reference renders the same job (its integrator named bdpt) with both layers"
r=$(frame "$T/ref" 0)
check "the reference: both lobes count its 3 samples on every surface pixel, 0 elsewhere" \
    test "$(alpha_times "$r" 3)" = "0.000000 0.000000" -a \
    "$(chstat "$r" "$S" Max)" = "3.000000 3.000000"
check "the reference: no tile stops early" test "$(chstat "$r" "$M" Max)" = "0.000000 0.000000"

done_testing
