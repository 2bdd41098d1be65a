#!/bin/sh
# flicker --baseline, the CI gate without a reference: a still bdpt shot against a rerun of
# itself is the same (exit 0); the same shot with fresh samples every frame (a change that
# makes it flicker) fails the gate (exit 1) and, the other way round, flickers less; the JSON
# carries the verdict; too few paired frames and option clashes are usage errors.
. tests/integration/lib.sh

still_demo "$T/still.yaml" 64x36 11 "[motion, depth]" "{name: bdpt}"
still_demo "$T/fresh.yaml" 64x36 11 "[motion, depth]" "{name: bdpt, bdpt: {samples: fresh}}"
for run in base:still rerun:still fresh:fresh; do
    rb render "$T/${run#*:}.yaml" --out "$T/${run%:*}" -q
    expect_exit 0 "the still shot renders (${run%:*})"
done

rb flicker "$T/rerun" --baseline "$T/base"
expect_exit 0 "a rerun of the baseline passes the gate"
stdout_has "^verdict: the same as the baseline$" "a rerun is the same"
stdout_has "^11 paired frames: " "frames 1-11 are paired (frame 0 has no previous frame)"

rb flicker "$T/fresh" --baseline "$T/base"
expect_exit 1 "fresh samples every frame fail the gate"
stdout_has "^verdict: flickers more than the baseline$" "fresh samples flicker more"
stderr_has "flickers more than the baseline" "the failure is explained on stderr"

rb flicker "$T/base" --baseline "$T/fresh"
expect_exit 0 "flickering less passes the gate"
stdout_has "^verdict: flickers less than the baseline$" "the other way round it flickers less"

rb flicker "$T/fresh" --baseline "$T/base" --json
expect_exit 1 "the gate fails with --json too"
check "the JSON's gate says more" grep -q '"verdict": "more"' "$T/stdout"
check "the JSON's frames carry the baseline's error" grep -q '"baseline_warped_error": ' "$T/stdout"

rb flicker "$T/fresh" --baseline "$T/base" --min-effect 1000%
expect_exit 0 "a least effect above the rise passes"
stdout_has "^verdict: the same as the baseline$" "below the least effect it is the same"

rb flicker "$T/fresh" --baseline "$T/base" --csv
expect_exit 1 "the gate fails with --csv too"
stdout_has ",baseline_warped_error$" "the CSV has the baseline's column"

# Too few frames to decide, and options that need or exclude each other.
mkdir "$T/few"
cp "$T/base/frame.0000.exr" "$T/base/frame.0001.exr" "$T/base/frame.0002.exr" "$T/few/"
rb flicker "$T/few" --baseline "$T/base"
expect_exit 2 "two paired frames cannot decide"
stderr_has "the gate needs at least 6" "too few frames are explained"
rb flicker "$T/fresh" --alpha 0.05
expect_exit 2 "--alpha without --baseline is a usage error"
stderr_has "--alpha and --min-effect need --baseline" "--alpha alone is explained"
rb flicker "$T/fresh" --baseline "$T/base" --reference "$T/base"
expect_exit 2 "--baseline with --reference is a usage error"
rb flicker "$T/fresh" --baseline "$T/base" --alpha 1.5
expect_exit 2 "--alpha 1.5 is refused"

done_testing
