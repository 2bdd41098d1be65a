#!/bin/sh
# bdpt's indirect light in its two textured parts, the layers indirect_diffuse and
# indirect_specular: asked for, they are in the EXR, validation-clean, add up to indirect pixel
# by pixel, and leave every other layer's bits alone; on the demo the specular part is there and
# the diffuse part carries most of the light. The direct integrator, which has no indirect
# light, writes them as zero; the reference splits its paths by the lobe of the first surface;
# a misspelt layer is refused with its file, line and column.
. tests/integration/lib.sh

small="--frames 0 --size 64x36 -q --validate"
all='layers=[direct, indirect, albedo, normal, depth, motion, indirect_diffuse, indirect_specular]'
parts='layers=[indirect, indirect_diffuse, indirect_specular]'
sum() { # sum EXR TOLERANCE: the parts against indirect; the totals in $T/sum
    "$BUILD/tests/tools/layersum" "$1" "$2" indirect indirect_diffuse indirect_specular \
        >"$T/sum" 2>&1
}
total() { # total LAYER: its total over the image, from $T/sum
    awk -v l="$1" '$1 == l && $2 == "total" { print $3 }' "$T/sum"
}

rb render jobs/demo.yaml $small --integrator bdpt --out "$T/b"
expect_exit 0 "bdpt renders the demo with the default layers"
rb render jobs/demo.yaml $small --integrator bdpt --out "$T/p" --set "$parts"
expect_exit 0 "bdpt renders the demo with indirect and its parts, validation-clean"
exr="$T/p/frame.0000.exr"
check "the EXR holds the beauty, indirect and its two parts" sh -c \
    "oiiotool --info -v '$exr' | grep -qx '    channel list: R, G, B, A, indirect.R, indirect.G, indirect.B, indirect_diffuse.R, indirect_diffuse.G, indirect_diffuse.B, indirect_specular.R, indirect_specular.G, indirect_specular.B'"
check "indirect_diffuse + indirect_specular == indirect, every pixel within 1e-6" sum "$exr" 1e-6
sed 's/^/# /' "$T/sum"
ind=$(total indirect)
diffuse=$(total indirect_diffuse)
specular=$(total indirect_specular)
check "the demo has indirect light ($ind)" awk -v i="$ind" 'BEGIN { exit !(i > 0) }'
check "the specular part is not zero ($specular)" awk -v s="$specular" 'BEGIN { exit !(s > 0) }'
check "the diffuse part carries most of it ($diffuse of $ind)" \
    awk -v d="$diffuse" -v i="$ind" 'BEGIN { exit !(d > 0.5 * i) }'
check "the sum check can fail: the diffuse part alone is not indirect" sh -c \
    "! '$BUILD/tests/tools/layersum' '$exr' 1e-6 indirect indirect_diffuse >/dev/null 2>&1"

same_channels() { # same_channels A B CHANNELS: those channels of A and B are the same bits
    oiiotool "$1" --ch "$3" -o "$T/a.exr" && oiiotool "$2" --ch "$3" -o "$T/b.exr" &&
        idiff -fail 0 -failpercent 0 -warn 0 "$T/a.exr" "$T/b.exr" >"$T/idiff" 2>&1
}
check "the parts change no other layer: beauty and indirect as without them" \
    same_channels "$T/b/frame.0000.exr" "$exr" R,G,B,A,indirect.R,indirect.G,indirect.B
rb render jobs/demo.yaml $small --integrator bdpt --out "$T/all" --set "$all"
expect_exit 0 "bdpt renders the demo with every layer"
check "with every layer, the default layers keep their bits" same_channels "$T/b/frame.0000.exr" \
    "$T/all/frame.0000.exr" \
    R,G,B,A,direct.R,direct.G,direct.B,indirect.R,indirect.G,indirect.B,albedo.R,albedo.G,albedo.B,normal.X,normal.Y,normal.Z,depth.Z,motion.X,motion.Y
check "with every layer, the parts still add up to indirect" sum "$T/all/frame.0000.exr" 1e-6

rb render jobs/demo.yaml $small --integrator direct --out "$T/d" --set "$parts"
expect_exit 0 "the direct integrator writes the parts too"
sum "$T/d/frame.0000.exr" 0
check "the direct integrator has no indirect light: both parts are zero" sh -c \
    "grep -qx 'indirect_diffuse total 0 nonzero 0' '$T/sum' && grep -qx 'indirect_specular total 0 nonzero 0' '$T/sum'"

rb reference jobs/demo.yaml --frames 0 --size 32x18 --spp 4 -q --out "$T/r" --set "$parts"
expect_exit 0 "the reference writes the parts"
# Its parts are summed apart from indirect, sample by sample: equal up to that rounding.
check "the reference's parts add up to its indirect within 1e-5" sum "$T/r/frame.0000.exr" 1e-5
check "the reference's specular part is not zero" \
    awk -v s="$(total indirect_specular)" 'BEGIN { exit !(s > 0) }'

cat >"$T/bad.yaml" <<EOF
scene: $PWD/jobs/demo/room.gltf
integrator: {name: bdpt}
layers:
  - indirect
  - indirect_difuse
EOF
rb render "$T/bad.yaml" --out "$T/never" -q
expect_exit 2 "a misspelt layer is refused"
stderr_has "$T/bad.yaml:4:3: unknown layer 'indirect_difuse' (direct, indirect, albedo, normal, depth, motion, indirect_diffuse, indirect_specular, samples, tiles, variance)" \
    "the error names the file, line and column, the layer, and the layers there are"
check "nothing written" test ! -e "$T/never"
done_testing
