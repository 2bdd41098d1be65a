// bdpt, filter (seed 000, A.1; Segovia et al. 2006): the geometry-aware filter that combines the
// neighbouring pixels' sample subsets. A pixel takes the gathered light of the pixels around it
// that saw samples (the first of the sub-images, as many as the frame has iterations) and lie
// on its surface: within the depth
// threshold (relative to its depth) of its tangent plane, so that a wall seen at a grazing angle
// keeps its whole kernel, and with normals whose cosine to its own is at least the normal
// threshold. It combines them sub-image by sub-image (the n x n classes of pixel positions mod
// n, each with its own VPLs and bundles), normalising each class's weights to one, and then
// averages the classes, each counting once: a plain mean counts a sub-image as often as its
// pixels fall in the kernel, which differs from class to class by position and wherever the
// surface test cuts the kernel, and the sub-images' differences stay in the image as a grid or
// as stripes. Indirect light, of low frequency, takes a tent of half-width h (a multiple of n):
// per class that is linear interpolation of the class's own lattice (h = n) or a smoother
// B-spline of it, which reproduces a class's gradient, so that its error's slope does not land
// differently on each class of pixels either; where an edge cuts the tent, the mean of what is
// left moves back to the pixel along the kernel's slope (at_pixel). Direct light (emitters'
// points and the environment through the bundles), which can change fast across a surface (a
// wall just below an area light), takes only a box of one interleave block, enough to hold a
// sample of every sub-image. The emitters' points, each at every pixel already (connect's
// emitters' dispatch), are added to the direct light unfiltered. The sums run in a fixed order,
// so the result does not depend on scheduling.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "bindings_shared.h"
#include "shared.h"
#include "bdpt_shared.h"
#include "encode.glsl"

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
layout(binding = RB_BIND_BDPT_FILTER_EMITTED + 0, rgba32f) uniform readonly image2D e0;
layout(binding = RB_BIND_BDPT_FILTER_EMITTED + 1, rgba32f) uniform readonly image2D e1;
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

// The taps' moments for the slope at an edge: over the indirect taps (weights wi, which sum to
// the class count), the sums of wi o, wi o o^T (xx, yy, xy) and wi^2 for offsets o, and per image
// the sums of wi o v and wi rb_luminance(v)^2.
struct moments {
    vec2 o;
    vec3 oo;
    float w2;
    vec3 ox[2], oy[2];
    float l2[2];
};

// Where an edge cuts the kernel, the pixels left lie to one side of the pixel: their weights'
// centroid c (the mean offset) is away from it, and their mean m is the light at c, not at the
// pixel. On a gradient into a concave corner it took the brighter interior's: the Cornell box's
// ceiling, whose indirect light falls from 0.23 to 0.15 in the last pixel before the back wall at
// 128x128, read 0.30 there. The taps give the slope b along c (weighted least squares), and the
// pixel takes m - b |c|, shrunk toward m where the slope is not clearly above its noise: by
// b^2 / (b^2 + 4 var(b)), var(b) from the fit's residuals over the taps' effective count.
// Inside a surface the tent is symmetric, c is 0, and m stands.
vec3 at_pixel(vec3 m, moments t, int i, float inv)
{
    vec2 c = t.o * inv;
    float len = length(c);
    if (!(len > 1e-2))
        return m;
    vec2 u = c / len;
    float var_o = (u.x * u.x * t.oo.x + u.y * u.y * t.oo.y + 2.0 * u.x * u.y * t.oo.z) * inv -
                  len * len;
    if (!(var_o > 1e-3))
        return m;
    vec3 b = ((u.x * t.ox[i] + u.y * t.oy[i]) * inv - len * m) / var_o;
    float bl = rb_luminance(b), ml = rb_luminance(m);
    float residual = max(t.l2[i] * inv - ml * ml - bl * bl * var_o, 0.0);
    float var_b = residual * t.w2 * inv * inv / var_o; // residual / (effective count var_o)
    float shrink = bl * bl / max(bl * bl + 4.0 * var_b, 1e-30);
    return m + clamp(-shrink * len * b, -m, m);
}

// The tent of half-width h at offset (dx, dy): (1 - |dx| / h)(1 - |dy| / h), 0 outside.
float tent(int dx, int dy, int h)
{
    return max(1.0 - float(abs(dx)) / float(h), 0.0) * max(1.0 - float(abs(dy)) / float(h), 0.0);
}

// Whether the pixel q (position and view depth, normal) lies on the surface of the pixel at p
// (normal n, direct light guide): near p's tangent plane, relative to p's depth, with a normal
// close to n's, and on the same side of a shadow's edge: their punctual lights' direct light
// (connect's guide, in the emitted image's alpha) within a factor of each other, the lesser at
// least pc.light.x of the greater. A contact shadow cuts off the indirect light with the direct (the floor under the
// demo's hovering box, 0.04 in the reference, read 0.28 when the floor in front of it joined its
// kernel); the test is on the same pixels for every class, and the classes' weights stay 1.
bool same_surface(ivec2 q, vec4 p, vec3 n, float guide)
{
    vec4 pq = imageLoad(gb_position, q);
    if (!(pq.w > 0.0 && abs(dot(n, pq.xyz - p.xyz)) <= pc.stops.x * p.w &&
          dot(imageLoad(gb_normal, q).xyz, n) >= pc.stops.y))
        return false;
    if (!(pc.light.x > 0.0))
        return true;
    float gq = imageLoad(e0, q).w;
    return min(gq, guide) >= pc.light.x * max(gq, guide);
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
    moments t;
    t.o = vec2(0.0);
    t.oo = vec3(0.0);
    t.w2 = 0.0;
    for (int i = 0; i < 2; i++) {
        t.ox[i] = vec3(0.0);
        t.oy[i] = vec3(0.0);
        t.l2[i] = 0.0;
    }
    int h = int(pc.split.w), rd = int(pc.stops.z), n = int(pc.split.x), sampled = int(pc.stops.w);
    // Per sub-image (class), the sum of its pixels' weights: the tent's for indirect light, the
    // count of those in the inner box for direct light.
    float per[RB_BDPT_MAX_INTERLEAVE * RB_BDPT_MAX_INTERLEAVE];
    float per_d[RB_BDPT_MAX_INTERLEAVE * RB_BDPT_MAX_INTERLEAVE];
    for (int c = 0; c < n * n; c++) {
        per[c] = 0.0;
        per_d[c] = 0.0;
    }
    // The kernel's rows as bit masks of the pixels on the surface (at most 2 x 16 - 1 wide:
    // the job's largest radius), so the second sweep reads no G-buffer again.
    uint rows[2 * RB_BDPT_MAX_FILTER - 1];
    vec3 nrm = imageLoad(gb_normal, px).xyz;
    float guide = imageLoad(e0, px).w;
    if (p.w > 0.0) {
        for (int dy = 1 - h; dy < h; dy++) {
            uint bits = 0u;
            for (int dx = 1 - h; dx < h; dx++) {
                ivec2 q = px + ivec2(dx, dy);
                // (the first `sampled` sub-images saw samples, every pixel of them)
                int c = (q.y % n) * n + q.x % n;
                if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size)) ||
                    c >= sampled || !same_surface(q, p, nrm, guide))
                    continue;
                bits |= 1u << uint(dx + h - 1);
                per[c] += tent(dx, dy, h);
                per_d[c] += abs(dx) <= rd && abs(dy) <= rd ? 1.0 : 0.0;
            }
            rows[dy + h - 1] = bits;
        }
        for (int c = 0; c < n * n; c++) {
            count += per[c] > 0.0 ? 1.0 : 0.0;
            count_d += per_d[c] > 0.0 ? 1.0 : 0.0;
        }
        for (int dy = 1 - h; dy < h; dy++)
            for (uint bits = rows[dy + h - 1]; bits != 0u; bits &= bits - 1u) {
                int dx = findLSB(bits) - (h - 1);
                ivec2 q = px + ivec2(dx, dy);
                int c = (q.y % n) * n + q.x % n;
                if (abs(dx) <= rd && abs(dy) <= rd) {
                    s0 += imageLoad(i0, q).rgb / per_d[c];
                    s1 += imageLoad(i1, q).rgb / per_d[c];
                }
                float wi = tent(dx, dy, h) / per[c];
                vec3 v2 = imageLoad(i2, q).rgb, v3 = imageLoad(i3, q).rgb;
                s2 += v2 * wi;
                s3 += v3 * wi;
                vec2 o = vec2(dx, dy);
                t.o += wi * o;
                t.oo += wi * vec3(o.x * o.x, o.y * o.y, o.x * o.y);
                t.w2 += wi * wi;
                t.ox[0] += wi * o.x * v2;
                t.oy[0] += wi * o.y * v2;
                t.ox[1] += wi * o.x * v3;
                t.oy[1] += wi * o.y * v3;
                t.l2[0] += wi * rb_luminance(v2) * rb_luminance(v2);
                t.l2[1] += wi * rb_luminance(v3) * rb_luminance(v3);
            }
    }
    float inv = count > 0.0 ? 1.0 / count : 0.0, inv_d = count_d > 0.0 ? 1.0 / count_d : 0.0;
    // The outputs are the temporal cache's: its depth z_c, and the slope of 1 / z across the
    // image (affine in the image for a plane seen in perspective), with which reconstruct moves
    // z_c from this sample to where a pixel's surface lands; and its normal, with which
    // reconstruct tells two surfaces apart where depth cannot (a room's concave corner, where a
    // wall and the ceiling meet at the same depth).
    vec2 slope = p.w > 0.0 ? inverse_depth_slope(px, size, 1.0 / p.w) : vec2(0.0);
    imageStore(o0, px, vec4(s0 * inv_d + imageLoad(e0, px).rgb, p.w));
    imageStore(o1, px, vec4(s1 * inv_d + imageLoad(e1, px).rgb, slope.x));
    imageStore(o2, px,
               vec4(at_pixel(s2 * inv, t, 0, inv), p.w > 0.0 ? rb_normal_pack(nrm) : 0.0));
    imageStore(o3, px, vec4(at_pixel(s3 * inv, t, 1, inv), slope.y));
}
