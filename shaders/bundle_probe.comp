// bundle_probe: the bundle search (shaders/common/bundle_search.glsl) from every G-buffer point,
// started as bdpt_connect.comp starts it, both ways along the bundle, so that a test can hold it
// to Embree (tests/unit/test_bundle_search.c). Not a pass.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "bindings_shared.h"
#include "shared.h"
#include "view_shared.h"
#include "encode.glsl"
#include "view.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = RB_BIND_BUNDLE_PROBE_POSITION, rgba32f) uniform readonly image2D gb_position;
layout(binding = RB_BIND_BUNDLE_PROBE_MOTION, rgba32f) uniform readonly image2D gb_motion;
layout(std430, binding = RB_BIND_BUNDLE_PROBE_VIEWS) readonly buffer BundleViews { rb_gpu_view bundle_views[]; };
layout(binding = RB_BIND_BUNDLE_PROBE_HEADS, r32ui) uniform readonly uimage2DArray heads;
layout(std430, binding = RB_BIND_BUNDLE_PROBE_NODES) readonly buffer Nodes { rb_gpu_list_node nodes[]; };

// One entry per pixel, in rows, after a copy of the bundle's view.
struct entry {
    vec4 origin; // x1 and s, the side connect leaves by (0: no surface at the pixel)
    vec4 t;      // the distance to the hit along s d, then along -s d (-1: none); along s d on
                 // x1's own line (rb_bundle_on_own_line, connect's distance); unused
    uvec4 node;  // the hits' normal words (s d, -s d), then their node indices
};
layout(std430, binding = RB_BIND_BUNDLE_PROBE_OUT) writeonly buffer Out
{
    rb_gpu_view view;
    entry entries[];
};
layout(push_constant) uniform Push { uint k, size, capacity; } pc; // bundle, grid size, nodes

#include "bundle_search.glsl"

void main()
{
    ivec2 px = ivec2(gl_GlobalInvocationID.xy), dim = imageSize(gb_position);
    if (any(greaterThanEqual(px, dim)))
        return;
    uint e = uint(px.y * dim.x + px.x);
    rb_gpu_view v = bundle_views[pc.k];
    if (e == 0u)
        view = v;
    vec4 pos = imageLoad(gb_position, px);
    entry o;
    o.t = vec4(-1.0);
    o.node = uvec4(0u);
    if (pos.w <= 0.0) {
        o.origin = vec4(0.0);
        entries[e] = o;
        return;
    }
    // x1 and the side its bundle ray leaves by, as connect takes them from the split G-buffer.
    vec3 x1 = pos.xyz, ng1 = rb_oct_decode(imageLoad(gb_motion, px).zw);
    float s = dot(ng1, v.axis.xyz) >= 0.0 ? 1.0 : -1.0;
    o.origin = vec4(x1, s);
    for (int i = 0; i < 2; i++) {
        rb_bundle_hit h = rb_bundle_search(v, int(pc.size), pc.capacity, x1, i == 0 ? s : -s);
        if (h.found) {
            o.t[i] = h.t;
            if (i == 0)
                o.t[2] = rb_bundle_on_own_line(v, int(pc.size), x1, s, h);
            o.node[i] = nodes[h.node].normal;
            o.node[2 + i] = h.node;
        }
    }
    entries[e] = o;
}
