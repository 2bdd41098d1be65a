// bdpt, mark: the texels of bundle k that connect's searches will read, before the bundle is
// drawn. The caller clears the heads to RB_VIEW_LIST_SKIP; each point of sub-image k mod n^2
// marks its texel (rb_bundle_texel, as rb_bundle_search finds it) RB_NONE, an empty list, and
// view_list.frag appends fragments to those lists alone. Only a sub-image's points search a
// bundle, a small part of its grid, so most fragments skip the material, the atomics and the
// node. Points marking one texel all write the same value: the order does not matter.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "bindings_shared.h"
#include "shared.h"
#include "view_shared.h"
#include "bdpt_shared.h"
#include "view.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = RB_BIND_BDPT_MARK_POSITION, rgba32f) uniform readonly image2D s_position;
layout(std430, binding = RB_BIND_BDPT_MARK_BUNDLE_VIEWS) readonly buffer BundleViews { rb_gpu_view bundle_views[]; };
layout(binding = RB_BIND_BDPT_MARK_HEADS, r32ui) uniform writeonly uimage2DArray heads;
layout(push_constant) uniform Push { rb_gpu_bdpt_mark_push pc; };

void main()
{
    uvec2 local = gl_GlobalInvocationID.xy;
    if (any(greaterThanEqual(local, pc.region.zw)))
        return;
    vec4 pos = imageLoad(s_position, ivec2(pc.region.xy + local));
    if (pos.w <= 0.0)
        return;
    int size = int(pc.index.y);
    ivec2 t = rb_bundle_texel(bundle_views[pc.index.x], size, pos.xyz);
    if (all(greaterThanEqual(t, ivec2(0))) && all(lessThan(t, ivec2(size))))
        imageStore(heads, ivec3(t, 0), uvec4(RB_NONE));
}
