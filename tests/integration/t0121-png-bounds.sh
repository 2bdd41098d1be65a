#!/bin/sh
# A PNG's decode is bounded by the size its header declares (issue 26: every read bounded by the
# declared sizes): past the decoder's limit of 2^30 samples (width x height x channels, as the
# glTF loader's decoder takes) it is refused before anything is allocated or inflated, with its
# size and the limit, not "out of memory"; just under it, it decodes in full.
. tests/integration/lib.sh

# png OUT W H [TINY]: a gray 8-bit PNG of W x H, black but for its last row (200) and last pixel
# (77), written a row at a time; with TINY only a few bytes of pixel data follow the header.
png() {
    python3 - "$@" <<'PY'
import struct, sys, zlib
out, w, h = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
def chunk(t, d):
    return struct.pack('>I', len(d)) + t + d + struct.pack('>I', zlib.crc32(t + d) & 0xffffffff)
c = zlib.compressobj(1)
if len(sys.argv) > 4:
    data = zlib.compress(b'\0' * 8)
else:
    zero = b'\0' * (w + 1)
    data = b''.join(c.compress(zero) for y in range(h - 1))
    data += c.compress(b'\0' + b'\xc8' * (w - 1) + b'\x4d') + c.flush()
with open(out, 'wb') as f:
    f.write(b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, 8, 0, 0, 0, 0)))
    f.write(chunk(b'IDAT', data) + chunk(b'IEND', b''))
PY
}

png "$T/huge.png" 1000000 1000000 tiny
rb info "$T/huge.png"
expect_exit 2 "a PNG declaring 10^12 pixels is refused"
stderr_has "cannot read '$T/huge.png': the PNG is 1000000 x 1000000 pixels of 1 channel (1 TB), too large: the decoder takes at most 1.07 GB (width x height x channels)" \
    "with its size and the limit"
png "$T/over.png" 32768 32769 tiny
rb info "$T/over.png"
expect_exit 2 "a PNG one row past the limit is refused"
stderr_has "the PNG is 32768 x 32769 pixels of 1 channel (1073774592 bytes), too large: the decoder takes at most 1073741824 bytes (width x height x channels)" \
    "with the exact counts where they round alike"

# 32768 x 32767 samples, 1,073,709,056: 32,768 under the limit, 4.3 GB of floats.
png "$T/under.png" 32768 32767
for at in "0 32765 0" "32767 32766 0.301960796" "0 32766 0.784313738"; do
    set -- $at
    v=$("$BUILD/tests/tools/exrpixel" "$T/under.png" "$1" "$2" Y 2>"$T/stderr")
    check "just under the limit it decodes in full: pixel ($1, $2) is $v, want $3" test "$v" = "$3"
done

done_testing
