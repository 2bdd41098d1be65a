// many_bindings: nineteen storage buffers in, one out, so a test can check that a set with more
// bindings than the binding list once held (16) reaches each buffer at its own binding
// (tests/unit/test_gpu.c). Not a pass.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "bindings_shared.h"

layout(local_size_x = 1) in;

#define IN(i) layout(std430, binding = RB_BIND_MANY_BINDINGS_IN + i) readonly buffer In##i { uint v##i; }
IN(0); IN(1); IN(2); IN(3); IN(4); IN(5); IN(6); IN(7); IN(8); IN(9);
IN(10); IN(11); IN(12); IN(13); IN(14); IN(15); IN(16); IN(17); IN(18);
layout(std430, binding = RB_BIND_MANY_BINDINGS_OUT) writeonly buffer Out { uint o[]; };

void main()
{
    o[0] = v0; o[1] = v1; o[2] = v2; o[3] = v3; o[4] = v4; o[5] = v5; o[6] = v6; o[7] = v7;
    o[8] = v8; o[9] = v9; o[10] = v10; o[11] = v11; o[12] = v12; o[13] = v13; o[14] = v14;
    o[15] = v15; o[16] = v16; o[17] = v17; o[18] = v18;
}
