#!/bin/sh
# A scene the loader refuses is said of the file and of what is wrong in it: a GLB's header by
# its field and bytes (not "Invalid glTF binary."), a PNG that is only too large by its size and
# the decoder's limit (not "Unknown image format").
. tests/integration/lib.sh

floor_panel_gltf "$T/panel.gltf" "[0, 1]"
floor_panel_gltf "$T/big.gltf" "[0, 1]" big.png
floor_panel_gltf "$T/tall.gltf" "[0, 1]" tall.png
floor_panel_gltf "$T/bad.gltf" "[0, 1]" bad.png
python3 - "$T" <<'PY'
import struct, sys, zlib
t = sys.argv[1]

def chunk(kind, data):
    return struct.pack('>I', len(data)) + kind + data + struct.pack('>I', zlib.crc32(kind + data))

def png(w, h, color_type):  # a header that declares w x h, and a few bytes of pixels
    ihdr = struct.pack('>IIBBBBB', w, h, 8, color_type, 0, 0, 0)
    return (b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', ihdr) + chunk(b'IDAT', zlib.compress(b'\0' * 8))
            + chunk(b'IEND', b''))

open(t + '/big.png', 'wb').write(png(40000, 40000, 6))
open(t + '/tall.png', 'wb').write(png(1, (1 << 24) + 1, 0))
open(t + '/bad.png', 'wb').write(b'\x89PNG\r\n\x1a\n' + b'not a png' * 8)

text = open(t + '/panel.gltf', 'rb').read()
text += b' ' * (-len(text) % 4)

def glb(name, length_delta=0, json_length=None, kind=b'JSON', cut=None):
    n = len(text) if json_length is None else json_length
    data = b'glTF' + struct.pack('<II', 2, 20 + len(text) + length_delta) + struct.pack('<I', n)
    data += kind + text
    open(t + '/' + name + '.glb', 'wb').write(data[:cut] if cut else data)

glb('ok')
glb('short', cut=10)
glb('long', length_delta=100)
glb('chunk', json_length=len(text) + 8)
glb('kind', kind=b'BIN\0')
PY

args="--out $T/out --size 8x8 -q"
load() { # load NAME MESSAGE DESCRIPTION: rendering NAME exits 2 saying MESSAGE
    rb render "$T/$1" $args
    expect_exit 2 "$3: refused as bad input"
    stderr_has "raybundle: error: cannot load '$T/$1': $2" "$3: said of the file and the field"
}

rb render "$T/ok.glb" $args
expect_exit 0 "the same scene as a well-formed GLB renders"
load short.glb "invalid GLB: a GLB starts with a 12-byte header and the JSON chunk's 8-byte header, and the file has 10 bytes" \
    "a GLB of 10 bytes"
load long.glb "invalid GLB: the header's length (bytes 8 to 11) is " "a GLB whose length passes its end"
check "... with both sizes" grep -q "bytes, and the file has [0-9]* *\$" "$T/stderr"
load chunk.glb "invalid GLB: the JSON chunk's length (bytes 12 to 15) is " \
    "a JSON chunk that runs past the GLB's length"
check "... with both lengths" grep -q "past the end of the GLB ([0-9]* bytes, the header's length)" "$T/stderr"
load kind.glb "invalid GLB: the first chunk's type (bytes 16 to 19) is 0x004E4942, not JSON (0x4E4F534A)" \
    "a first chunk that is not JSON"

load big.gltf "image 0: the PNG is 40000 x 40000 pixels of 4 channels (6.4 GB), too large: the decoder takes at most 1.07 GB (width x height x channels)" \
    "a PNG too large to decode"
load tall.gltf "image 0: the PNG is 1 x 16777217 pixels, too large: the decoder takes at most 16777216 pixels a side" \
    "a PNG taller than the decoder's side"
load bad.gltf "Unknown image format" "a PNG that is broken, and not too large"
check "... is not called too large" sh -c "! grep -q 'too large' '$T/stderr'"

done_testing
