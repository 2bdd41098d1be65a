// reproject: for each pixel of the G-buffer and each age a < l, where its surface was in frame
// f - a: the pixel position there (continuous, pixel centres at + 0.5) and the view depth, w = 1;
// w = 0 where it was behind that frame's camera. Early depth tests (EQUAL against the
// G-buffer's depth) run this only for the surface the G-buffer holds.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "bindings_shared.h"
#include "shared.h"
#include "bdpt_shared.h"

layout(early_fragment_tests) in;

layout(std140, binding = RB_BIND_REPROJECT_GLOBALS) uniform Globals { rb_gpu_globals g; };
layout(std140, binding = RB_BIND_REPROJECT_HISTORY) uniform History { rb_gpu_bdpt_history h; };
layout(binding = RB_BIND_REPROJECT_OUT, rgba32f) uniform writeonly image2DArray o_where;

layout(location = 0) in vec4 i_then[RB_BDPT_MAX_CACHES];

void main()
{
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec2 size = vec2(g.size.xy);
    for (uint a = 0u; a < h.info.x; a++) {
        vec4 c = i_then[a];
        vec4 w = vec4(0.0);
        if (c.z > 0.0 && c.w > 0.0)
            w = vec4((c.xy / c.z * 0.5 + 0.5) * size, c.w, 1.0);
        imageStore(o_where, ivec3(px, int(a)), w);
    }
}
