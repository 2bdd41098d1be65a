#!/bin/sh
# Light sources and the fitted camera, decided once per job: a default point light only when a
# frame would otherwise be unlit (no punctual light, no emissive surface bright enough, a black
# environment), or as default_light says; the direct integrator warns about the environment's
# light, which it does not compute; the
# fitted camera and the default light do not follow the animated bounds; a room open on one side
# is looked into through that side.
. tests/integration/lib.sh

# A floor (Lambertian, white) and, in lit.gltf, a small emissive panel 1 m above it.
floor_panel_gltf "$T/lit.gltf" "[0, 1]"
floor_panel_gltf "$T/floor.gltf" "[0]"
# A job looking down at the floor's centre; the floor's centre is the image's centre.
write_job() { # write_job NAME SCENE [EXTRA-YAML]: a direct-light job
    printf 'scene: %s\noutput: %s/f.####.exr\nresolution: [64, 48]\nframes: {start: 0, end: 0}\n'         "$2" "$1" >"$T/$1.yaml"
    printf 'integrator: {name: direct}\n' >>"$T/$1.yaml"
    printf 'camera: {keys: [{t: 0, position: [0, 3, 0.01], look_at: [0, 0, 0]}]}\n%s\n'         "${3:-}" >>"$T/$1.yaml"
}
centre() { # centre EXR CHANNEL: the value at the image's centre
    "$BUILD/tests/tools/exrpixel" "$1" 32 24 "$2"
}
default_light_of() { # default_light_of EXR: the raybundle:defaultLight attribute
    oiiotool --info -v "$1" | sed -n 's/^ *raybundle:defaultLight: "\(.*\)"$/\1/p'
}
positive() { awk -v v="$1" 'BEGIN { exit !(v > 0) }'; }
zero() { awk -v v="$1" 'BEGIN { exit !(v == 0) }'; }

# Emissive surfaces only: no default light. direct lights the floor with the panel's point
# samples, without a warning; the reference lights the floor with the panel.
write_job emissive lit.gltf
rb render "$T/emissive.yaml"
expect_exit 0 "emissive-only: direct renders"
check "emissive-only: no warning" test "$(grep -c warning "$T/stderr")" -eq 0
check "emissive-only: no default light in the metadata" \
    test "$(default_light_of "$T/emissive/f.0000.exr")" = none
# The floor's centre is under the panel, so the camera sees the panel there: look beside it.
v=$("$BUILD/tests/tools/exrpixel" "$T/emissive/f.0000.exr" 12 24 R)
check "emissive-only: direct lights the floor with the panel ($v)" positive "$v"
rb reference "$T/emissive.yaml" --spp 4 --out "$T/emissive-ref" -q
expect_exit 0 "emissive-only: the reference renders"
v=$("$BUILD/tests/tools/exrpixel" "$T/emissive-ref/f.0000.exr" 12 24 R)
check "emissive-only: the reference lights the floor with the panel ($v)" positive "$v"
check "emissive-only: the reference adds no default light" \
    test "$(default_light_of "$T/emissive-ref/f.0000.exr")" = none

# The environment only: no default light, a warning naming the environment.
write_job env floor.gltf "environment: {color: [0.5, 0.5, 0.5]}"
rb render "$T/env.yaml"
expect_exit 0 "environment-only: direct renders"
stderr_has "lit by the environment" "environment-only: direct warns that the environment lights nothing"
check "environment-only: no default light" test "$(default_light_of "$T/env/f.0000.exr")" = none
rb reference "$T/env.yaml" --spp 4 --out "$T/env-ref" -q
v=$(centre "$T/env-ref/f.0000.exr" R)
check "environment-only: the reference lights the floor with the sky ($v)" positive "$v"

# Truly dark: the default light, logged once and recorded; the floor is lit.
write_job dark floor.gltf
rb render "$T/dark.yaml" -v
expect_exit 0 "dark: direct renders"
check "dark: the default light is logged once" test "$(grep -c 'default light' "$T/stderr")" -eq 1
note=$(default_light_of "$T/dark/f.0000.exr")
check "dark: the metadata records the default light ($note)" \
    sh -c "echo '$note' | grep -q '^point light at'"
v=$(centre "$T/dark/f.0000.exr" R)
check "dark: the default light lights the floor ($v)" positive "$v"
rb reference "$T/dark.yaml" --spp 1 --set integrator.reference.paths=direct --out "$T/dark-ref" -q
check "dark: the reference places the same default light" \
    test "$(default_light_of "$T/dark-ref/f.0000.exr")" = "$note"
rb compare "$T/dark/f.0000.exr" "$T/dark-ref/f.0000.exr" --layer direct --max-relmse 1e-4
expect_exit 0 "dark: GPU and reference agree under the default light"

# default_light: off leaves the dark floor black; on adds the light beside emitters.
rb render "$T/dark.yaml" --set default_light=off --out "$T/off" -q
expect_exit 0 "default_light off renders"
v=$(centre "$T/off/f.0000.exr" R)
check "default_light off: the floor stays black ($v)" zero "$v"
check "default_light off: none in the metadata" test "$(default_light_of "$T/off/f.0000.exr")" = none
rb render "$T/emissive.yaml" --set default_light=on --out "$T/on" -q
v=$("$BUILD/tests/tools/exrpixel" "$T/on/f.0000.exr" 12 24 R)
check "default_light on: the floor is lit beside the emitter ($v)" positive "$v"
rb render "$T/dark.yaml" --set default_light=sometimes -q
expect_exit 2 "default_light: a bad value is refused"
stderr_has "default_light" "default_light: the message names the key"

# Decided once per job: the demo without its camera track and lights gets a fitted camera and a
# default light that stay put while the box spins and the column bends; the demo's room is
# looked into through its open side.
sed -e '/^camera:/,/^[a-z]/{/^camera:/d;/^  /d}' jobs/demo.yaml >"$T/demo-fit.yaml"
sed -i -e "s#^scene: .*#scene: $PWD/jobs/demo/room.gltf#" "$T/demo-fit.yaml"
check "the fitted-camera job has no camera keys" sh -c "! grep -q 'keys' '$T/demo-fit.yaml'"
rb render "$T/demo-fit.yaml" --frames 0-20 --size 96x54 --out "$T/fit" -q \
    --set scene_lights=false --set lights=[] --set default_light=on
expect_exit 0 "the demo renders with a fitted camera and the default light"
for key in worldToCamera worldToNDC raybundle:defaultLight; do
    a=$(oiiotool --info -v "$T/fit/frame.0000.exr" | grep "$key")
    b=$(oiiotool --info -v "$T/fit/frame.0020.exr" | grep "$key")
    check "$key is the same in frames 0 and 20 of an animated scene" test -n "$a" -a "$a" = "$b"
done
check "the animation moved: frames 0 and 20 differ" \
    sh -c "! cmp -s '$T/fit/frame.0000.exr' '$T/fit/frame.0020.exr'"

# A room open on one side is looked into through it: both side walls from inside (red left,
# green right across the middle row) and the ceiling from below, not the roof from above.
looks_into_room() { # looks_into_room EXR W H
    exr=$1 w=$2 h=$3
    red=0
    green=0
    for k in 1 2 3 4 5 6 7 9 10 11 12 13 14 15; do
        rg=$("$BUILD/tests/tools/exrpixel" "$exr" $((w * k / 16)) $((h / 2)) albedo.R albedo.G)
        side=$([ "$k" -lt 8 ] && echo left || echo right)
        case $side:$(echo $rg | awk '{ print ($1 > 2 * $2) ? "red" : ($2 > 2 * $1) ? "green" : "-" }') in
        left:red) red=$((red + 1)) ;;
        right:green) green=$((green + 1)) ;;
        esac
    done
    [ "$red" -ge 1 ] && [ "$green" -ge 1 ] || return 1
    # The ceiling seen from below, in the top quarter (from above the roof, nothing faces down).
    for k in 1 2 3 4 5 6 7 8; do
        ny=$("$BUILD/tests/tools/exrpixel" "$exr" $((w / 3)) $((h * k / 32)) normal.Y)
        if awk -v n="$ny" 'BEGIN { exit !(n < -0.5) }'; then return 0; fi
    done
    return 1
}
check "the demo room is looked into through its open side" \
    looks_into_room "$T/fit/frame.0000.exr" 96 54
for scene in cornell-box/CornellBox.glb cornell-box-suzanne/cornell-box.glb; do
    if have_scene "$scene"; then
        rb render "$SCENES/$scene" --frames 0 --size 160x120 --out "$T/$scene" -q
        expect_exit 0 "$scene: a quick look renders"
        check "$scene: the quick look looks into the room through its open side" \
            looks_into_room "$T/$scene/frame.0000.exr" 160 120
    else
        skip "$scene: a quick look looks into the room" "no '$scene' in '$SCENES'"
    fi
done
done_testing
