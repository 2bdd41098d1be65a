// bdpt, filter (seed 000, A.1; Segovia et al. 2006): the geometry-aware filter that combines the
// neighbouring pixels' sample subsets. A pixel averages the gathered light of the pixels within
// the radius that saw samples (w of the indirect diffuse image: 1) and lie on the same surface:
// their view depths differ by at most the depth threshold (relative) and their normals by an
// angle whose cosine is at least the normal threshold. Indirect light, of low frequency, takes
// the whole radius; direct light (emitters' points and the environment through the bundles),
// which can change fast across a surface (a wall just below an area light), only one interleave
// block's, enough to gather every sub-image's samples (on the Cornell box with 256 VPLs and
// bundles its relMSE falls from 0.070 to 0.036). Every weight is 0 or 1, and the sums run in a
// fixed order, so the result does not depend on scheduling.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "bindings_shared.h"
#include "shared.h"
#include "bdpt_shared.h"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = RB_BIND_BDPT_FILTER_GB_POSITION, rgba32f) uniform readonly image2D gb_position;
layout(binding = RB_BIND_BDPT_FILTER_GB_NORMAL, rgba32f) uniform readonly image2D gb_normal;
layout(binding = RB_BIND_BDPT_FILTER_IN + 0, rgba32f) uniform readonly image2D i0;
layout(binding = RB_BIND_BDPT_FILTER_IN + 1, rgba32f) uniform readonly image2D i1;
layout(binding = RB_BIND_BDPT_FILTER_IN + 2, rgba32f) uniform readonly image2D i2;
layout(binding = RB_BIND_BDPT_FILTER_IN + 3, rgba32f) uniform readonly image2D i3;
layout(binding = RB_BIND_BDPT_FILTER_OUT + 0, rgba32f) uniform writeonly image2D o0;
layout(binding = RB_BIND_BDPT_FILTER_OUT + 1, rgba32f) uniform writeonly image2D o1;
layout(binding = RB_BIND_BDPT_FILTER_OUT + 2, rgba32f) uniform writeonly image2D o2;
layout(binding = RB_BIND_BDPT_FILTER_OUT + 3, rgba32f) uniform writeonly image2D o3;
layout(push_constant) uniform Push { rb_gpu_bdpt_image_push pc; };

// The change of 1 / z to the next pixel along each axis: of the two neighbours' differences, the
// smaller (the one on the same surface, at an edge); 0 where neither neighbour has a surface.
vec2 inverse_depth_slope(ivec2 px, ivec2 size, float w)
{
    vec2 slope = vec2(0.0);
    for (int axis = 0; axis < 2; axis++) {
        float best = 0.0;
        bool found = false;
        for (int side = -1; side <= 1; side += 2) {
            ivec2 q = px;
            q[axis] += side;
            if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size)))
                continue;
            float z = imageLoad(gb_position, q).w;
            if (!(z > 0.0))
                continue;
            float d = (1.0 / z - w) * float(side);
            if (!found || abs(d) < abs(best))
                best = d;
            found = true;
        }
        slope[axis] = best;
    }
    return slope;
}

void main()
{
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(gb_position);
    if (any(greaterThanEqual(px, size)))
        return;
    vec4 p = imageLoad(gb_position, px);
    vec3 s0 = vec3(0.0), s1 = vec3(0.0), s2 = vec3(0.0), s3 = vec3(0.0);
    float count = 0.0, count_d = 0.0;
    int rd = int(pc.stops.z);
    if (p.w > 0.0) {
        vec3 n = imageLoad(gb_normal, px).xyz;
        int r = int(pc.split.w);
        for (int dy = -r; dy <= r; dy++)
            for (int dx = -r; dx <= r; dx++) {
                ivec2 q = px + ivec2(dx, dy);
                if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size)))
                    continue;
                vec4 c2 = imageLoad(i2, q);
                if (c2.w <= 0.0)
                    continue;
                float z = imageLoad(gb_position, q).w;
                if (!(abs(z - p.w) <= pc.stops.x * p.w) ||
                    dot(imageLoad(gb_normal, q).xyz, n) < pc.stops.y)
                    continue;
                if (abs(dx) <= rd && abs(dy) <= rd) {
                    s0 += imageLoad(i0, q).rgb;
                    s1 += imageLoad(i1, q).rgb;
                    count_d += 1.0;
                }
                s2 += c2.rgb;
                s3 += imageLoad(i3, q).rgb;
                count += 1.0;
            }
    }
    float inv = count > 0.0 ? 1.0 / count : 0.0, inv_d = count_d > 0.0 ? 1.0 / count_d : 0.0;
    // The outputs are the temporal cache's: its depth z_c, and the slope of 1 / z across the
    // image (affine in the image for a plane seen in perspective), with which reconstruct moves
    // z_c from this sample to where a pixel's surface lands.
    vec2 slope = p.w > 0.0 ? inverse_depth_slope(px, size, 1.0 / p.w) : vec2(0.0);
    imageStore(o0, px, vec4(s0 * inv_d, p.w));
    imageStore(o1, px, vec4(s1 * inv_d, slope.x));
    imageStore(o2, px, vec4(s2 * inv, count));
    imageStore(o3, px, vec4(s3 * inv, slope.y));
}
