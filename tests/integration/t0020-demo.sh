#!/bin/sh
# The demo scene renders end to end: per-frame EXRs with every layer and the metadata, timing
# sidecars with every pass, PNG previews; OpenImageIO's own tool reads the files back.
. tests/integration/lib.sh

rb render jobs/demo.yaml --frames 0-3 --size 160x90 --out "$T/demo" --preview -q
expect_exit 0 "demo renders 4 frames"
for f in 0000 0001 0002 0003; do
    check "frame $f EXR exists" test -s "$T/demo/frame.$f.exr"
    check "frame $f timing sidecar exists" test -s "$T/demo/frame.$f.timing.json"
    check "frame $f preview exists" test -s "$T/demo/frame.$f.png"
done
check "no temporary files are left" sh -c "! ls '$T/demo' | grep -q tmp"

oiiotool --info -v "$T/demo/frame.0002.exr" >"$T/info" 2>&1
check "oiiotool reads the EXR" test $? -eq 0
for ch in R G B A direct.R direct.G direct.B indirect.R indirect.G indirect.B albedo.R normal.X normal.Y normal.Z depth.Z \
    motion.X motion.Y; do
    check "channel $ch is present" grep -q "[ ,]$ch[,\" ]\|[ ,]$ch\$" "$T/info"
done
for attr in worldToCamera worldToNDC chromaticities 'raybundle:integrator: "bdpt"' \
    'raybundle:frame: 2' 'raybundle:jobHash'; do
    check "attribute '$attr' is present" grep -qF "$attr" "$T/info"
done
check "compression is lossless (zip)" grep -qi 'compression: "zip' "$T/info"
check "no DateTime in the header" sh -c "! grep -q DateTime '$T/info'"

json="$T/demo/frame.0002.timing.json"
for key in '"frame": 2' '"time_s"' '"passes"' '"wall_ms"' '"device"' '"driver"'; do
    check "timing has $key" grep -qF "$key" "$json"
done
for pass in animate gbuffer shadow direct output; do
    check "timing lists pass '$pass' with gpu_ms" \
        grep -q "\"name\": \"$pass\", \"gpu_ms\": [0-9]" "$json"
done

if ociocheck --iconfig share/ocio/config.ocio >"$T/ociocheck" 2>&1 && grep -q '^passed' "$T/ociocheck"; then
    ok "ociocheck passes on the bundled config"
else
    not_ok "ociocheck passes on the bundled config" "$(tail -n 20 "$T/ociocheck")"
fi

# Previews are opaque: they show what the camera sees, background included.
tap_run "$BUILD/tests/tools/exrstat" "$T/demo/frame.0000.png" A 0.999

# The picture is not empty: the room is lit.
tap_run "$BUILD/tests/tools/exrstat" "$T/demo/frame.0000.exr" R 0.01

# The demo is the seeds' system: bdpt by its own lights, no fill light added by the job, and
# its global illumination shows (the faces turned from both lights get the walls' light).
check "the demo job renders with bdpt" grep -qx 'integrator: {name: bdpt}' jobs/demo.yaml
check "the demo job adds no light of its own" sh -c "! grep -q '^lights:' jobs/demo.yaml"
tap_run "$BUILD/tests/tools/exrstat" "$T/demo/frame.0002.exr" indirect.R 0.01
# The same shot with hybrid, a shipped job of its own.
rb render jobs/demo-hybrid.yaml --frames 0-1 --size 64x36 --out "$T/hybrid" -q
expect_exit 0 "jobs/demo-hybrid.yaml renders"
check "jobs/demo-hybrid.yaml renders with hybrid" sh -c \
    "oiiotool --info -v '$T/hybrid/frame.0001.exr' | grep -qF 'raybundle:integrator: \"hybrid\"'"
tap_run "$BUILD/tests/tools/exrstat" "$T/hybrid/frame.0001.exr" indirect.R 0.01
done_testing
