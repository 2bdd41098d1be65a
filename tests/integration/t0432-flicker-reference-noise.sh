#!/bin/sh
# flicker --reference without the reference's noise: the reference writes a variance layer
# (one channel, variance.Y) only when asked, and only the reference integrator does; against
# references of 64 and 512 samples with that layer, the demo's bdpt sequence has excess RMSs
# within 25% of each other, where the mean excess (which counts the reference's noise) is not;
# a reference without the layer is used as before, with a note that its noise is counted.
. tests/integration/lib.sh

job=jobs/demo.yaml
size=64x36
frames=0-11
rb render "$job" --integrator bdpt --size "$size" --frames "$frames" --out "$T/bdpt" -q
expect_exit 0 "the demo's bdpt sequence renders"
for spp in 64 512; do
    rb reference "$job" --size "$size" --frames "$frames" --spp "$spp" \
        --set integrator.reference.paths=bdpt --set 'layers=[motion, depth, variance]' \
        --out "$T/ref$spp" -q
    expect_exit 0 "the $spp-spp reference with a variance layer renders"
done
rb reference "$job" --size "$size" --frames 0-1 --spp 16 --set integrator.reference.paths=bdpt \
    --set 'layers=[motion, depth]' --out "$T/plain" -q
expect_exit 0 "a reference without the variance layer renders"

check "the variance layer is one channel, variance.Y" \
    sh -c "oiiotool --info -v '$T/ref64/frame.0003.exr' | grep -q 'channel list: R, G, B, A, depth.Z, motion.X, motion.Y, variance.Y\$'"
check "the variance is a number >= 0" \
    sh -c "oiiotool '$T/ref64/frame.0003.exr' --ch variance.Y --printstats |
        grep 'Stats Min' | awk '{ exit !(\$3 + 0 >= 0) }'"
check "a reference without the layer has no variance channel" \
    sh -c "! oiiotool --info -v '$T/plain/frame.0000.exr' | grep -q variance"

# json FILE KEY: the value of the summary's (or the top level's) KEY.
json() {
    sed -n "s/^ \{2,4\}\"$2\": \([^,]*\),*\$/\1/p" "$1" | head -n 1
}
for spp in 64 512; do
    rb flicker "$T/bdpt" --reference "$T/ref$spp" --json
    expect_exit 0 "flicker against the $spp-spp reference exits 0"
    cp "$T/stdout" "$T/f$spp.json"
    check "the $spp-spp JSON says the correction was applied" \
        test "$(json "$T/f$spp.json" reference_noise_corrected)" = true
done
rms64=$(json "$T/f64.json" excess_rms)
rms512=$(json "$T/f512.json" excess_rms)
mean64=$(json "$T/f64.json" excess_error_mean)
mean512=$(json "$T/f512.json" excess_error_mean)
check "the excess RMSs less the references' noise agree within 25% ($rms64, $rms512)" \
    awk -v a="$rms64" -v b="$rms512" 'BEGIN { r = a / b; exit !(a > 0 && r > 0.75 && r < 1.25) }'
check "the mean excesses, which count the noise, do not ($mean64, $mean512)" \
    awk -v a="$mean64" -v b="$mean512" 'BEGIN { r = a / b; exit !(r > 1.25 || r < 0.75) }'

rb flicker "$T/bdpt" --reference "$T/ref64"
expect_exit 0 "the text output exits 0"
stdout_has "less the reference's noise (its variance layer)" "the text says the noise is left out"
mkdir "$T/two"
cp "$T/bdpt/frame.0000.exr" "$T/bdpt/frame.0001.exr" "$T/two/"
rb flicker "$T/two" --reference "$T/plain" --json
expect_exit 0 "a reference without the layer is still used"
check "its JSON says the correction was not applied" \
    test "$(json "$T/stdout" reference_noise_corrected)" = false
rb flicker "$T/two" --reference "$T/plain"
stdout_has "count the reference's noise (it has no variance layer)" \
    "the text says the reference's noise is counted"

# Only the reference writes the layer, and it needs two samples a pixel.
rb render "$job" --integrator direct --size 16x9 --frames 0-0 --set 'layers=[variance]' \
    --out "$T/direct" -q
expect_exit 2 "the direct integrator refuses the variance layer"
stderr_has "layer 'variance' is written by the reference integrator only, and this job renders with 'direct'" \
    "the refusal names the layer and the integrator"
rb reference "$job" --size 16x9 --frames 0-0 --spp 1 --set 'layers=[variance]' --out "$T/one" -q
expect_exit 2 "one sample a pixel has no variance"
stderr_has "layer 'variance' needs at least 2 samples a pixel" "the refusal says why"

done_testing
