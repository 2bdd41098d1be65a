// hybrid_filter: one lobe's light for the output pass, from the older accumulator (the one that
// spans more frames), through a bilateral filter whose radius shrinks as the pixel's samples
// grow (seed 003's variable kernel): radius / samples^(1/4), nothing once that is under a pixel.
// The fourth root lets both errors fall as samples grow: the filtered variance goes as
// 1 / (samples x radius^2), so ~ samples^(-1/2), and the blur's bias as radius^2, the same. (A
// radius over the square root would hold the filtered noise level flat until the kernel is gone:
// the Cornell box's indirect relMSE after 64 one-ray frames was 0.077 that way, 0.015 this way.)
// Neighbours weigh by a Gaussian of distance, stop at depth and normal edges, and count by their
// samples (the filter averages sums over sample counts). The specular lobe's radius also scales
// with the roughness, so a mirror stays sharp. With the diffuse lobe, writes what the samples
// and tiles layers show: each lobe's samples in the accumulator the output reads (rg), and
// whether its tile mask, as the next frame's requests read it, stops its rays (ba: 1 or 0).
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
    uint lobe = pc.frame.z;
    uint layer = 4u * (pc.history.z & 1u) + 2u * lobe;
    vec4 pos = imageLoad(gb_position, px);
    vec4 d0 = imageLoad(acc, ivec3(px, layer));
    vec3 dsum = vec3(0.0), isum = vec3(0.0);
    float wsum = 0.0, dwsum = 0.0;
    if (pos.w > 0.0) {
        vec3 n = imageLoad(gb_normal, px).xyz;
        float radius = float(pc.more.w) * pow(max(d0.w, 1.0), -0.25);
        // The direct light's samples are light samples (next-event estimation): their noise is
        // low and falls fast, and a blur's bias (light spread into a shadow, or down a wall
        // toward a grazing ceiling) is what would be left, so its radius falls as the samples
        // (the Cornell box's direct relMSE at frame 31: 0.007 as their square root, 0.0013
        // unfiltered).
        float radius_d = float(pc.more.w) / max(d0.w, 1.0);
        if (lobe == RB_HYBRID_SPECULAR) {
            float k = clamp(2.0 * imageLoad(gb_specular, px).a, 0.0, 1.0);
            radius *= k;
            radius_d *= k;
        }
        int r = radius < 1.0 ? 0 : int(radius);
        int rd = radius_d < 1.0 ? 0 : int(radius_d);
        float inv2s2 = 1.0 / (2.0 * max(radius * 0.5, 0.5) * max(radius * 0.5, 0.5));
        float inv2s2_d = 1.0 / (2.0 * max(radius_d * 0.5, 0.5) * max(radius_d * 0.5, 0.5));
        r = max(r, rd);
        for (int y = -r; y <= r; y++)
            for (int x = -r; x <= r; x++) {
                ivec2 q = px + ivec2(x, y);
                if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, ivec2(g.size.xy))))
                    continue;
                vec4 pq = imageLoad(gb_position, q);
                if (!(pq.w > 0.0) || abs(pq.w - pos.w) > pc.params.z * pos.w ||
                    dot(imageLoad(gb_normal, q).xyz, n) < pc.params.w)
                    continue;
                vec4 dq = imageLoad(acc, ivec3(q, layer));
                vec4 iq = imageLoad(acc, ivec3(q, layer + 1u));
                float d2 = float(x * x + y * y);
                if (abs(x) <= rd && abs(y) <= rd) {
                    float w = exp(-d2 * inv2s2_d);
                    dsum += w * dq.rgb;
                    dwsum += w * dq.w;
                }
                float w = exp(-d2 * inv2s2);
                isum += w * iq.rgb;
                wsum += w * dq.w;
            }
    }
    vec4 dl = vec4(dwsum > 0.0 ? dsum / dwsum : vec3(0.0), 0.0);
    vec4 il = vec4(wsum > 0.0 ? isum / wsum : vec3(0.0), 0.0);
    if (lobe == RB_HYBRID_DIFFUSE) {
        imageStore(o_direct_diffuse, px, dl);
        imageStore(o_indirect_diffuse, px, il);
        vec4 sp = imageLoad(acc, ivec3(px, 4u * (pc.history.z & 1u) + 2u));
        // The tiles pass has just written the mask the next frame's rays follow (unless that
        // frame starts the younger accumulator again); a target of 0 marks no tile done.
        bool on = pc.params.x > 0.0;
        float done_d = on && rb_hybrid_tile_done(px, true) >= 0.5 ? 1.0 : 0.0;
        float done_s = on && rb_hybrid_tile_done(px, false) >= 0.5 ? 1.0 : 0.0;
        imageStore(stats, px, vec4(d0.w, sp.w, done_d, done_s));
    } else {
        imageStore(o_direct_specular, px, dl);
        imageStore(o_indirect_specular, px, il);
    }
}
