// hybrid_accumulate: adds this frame's samples to both accumulators (seed 003, "sample
// accumulation"). Each holds, per pixel and lobe, the sums of the samples of the frames since it
// last started again, carried along with the motion vectors and dropped where the previous frame
// saw another surface (depth and normal tests). The two start again every W frames, W / 2
// apart, so the state of a frame depends on the last W frames only, and the older one always
// spans at least W / 2 of them. Writes the frame's geometry for the next frame's tests.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_buffer_reference : require

layout(local_size_x = 8, local_size_y = 8) in;

#include "hybrid.glsl"

void main()
{
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(uvec2(px), g.size.xy)))
        return;
    vec4 pos = imageLoad(gb_position, px);
    bool surface = pos.w > 0.0;
    vec3 n = surface ? imageLoad(gb_normal, px).xyz : vec3(0.0);
    ivec2 q = surface ? rb_hybrid_reproject(px, pos.w, n) : ivec2(-1);
    // This frame's samples, lobe by lobe, in slot order.
    vec4 direct[2], indirect[2];
    for (uint lobe = 0u; lobe < 2u; lobe++) {
        direct[lobe] = vec4(0.0);
        indirect[lobe] = vec4(0.0);
        for (uint r = 0u; surface && r < pc.frame.y; r++) {
            rb_gpu_hybrid_slot s = slots[rb_hybrid_slot(lobe, r, px)];
            uint state = floatBitsToUint(s.a.w);
            if (state == RB_HYBRID_NONE || state == RB_HYBRID_DROPPED || state == RB_HYBRID_QUEUED)
                continue;
            float x = rb_luminance(s.a.rgb + s.b.rgb);
            direct[lobe] += vec4(s.a.rgb, 1.0);
            indirect[lobe] += vec4(s.b.rgb, x * x);
        }
    }
    for (uint set = 0u; set < 2u; set++) {
        bool reset = (set == 0u ? pc.history.x : pc.history.y) != 0u;
        for (uint k = 0u; k < 4u; k++) {
            uint layer = 4u * set + k;
            vec4 old = surface && !reset && q.x >= 0 ? imageLoad(acc_prev, ivec3(q, layer)) : vec4(0.0);
            uint lobe = k / 2u;
            vec4 add = (k & 1u) == 0u ? direct[lobe] : indirect[lobe];
            imageStore(acc, ivec3(px, layer), surface ? old + add : vec4(0.0));
        }
    }
    imageStore(acc, ivec3(px, RB_HYBRID_ACC_GEOMETRY), vec4(n, surface ? pos.w : 0.0));
}
