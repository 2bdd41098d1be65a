// bdpt, split (seed 000, A.1; Segovia et al. 2006): the G-buffer rearranged into n x n
// sub-images, pixel (x, y) into sub-image (x mod n, y mod n) at (x / n, y / n), so that each
// connect dispatch reads one contiguous block of the pixels that share its VPL and bundle.
// Four images: position and view depth (w = 0: no surface), shading normal and roughness, F0
// and F90, the octahedral geometric normal. It runs over the split images, whose sub-images are
// rounded up to whole pixels: texels no pixel maps to get w = 0. The four light accumulators
// that the connect passes add to are cleared before it (a transfer clear, a memset on a CPU
// device, costs less than storing zeros here).
#version 460
#extension GL_GOOGLE_include_directive : require
#include "bindings_shared.h"
#include "shared.h"
#include "bdpt_shared.h"

layout(local_size_x = 8, local_size_y = 8) in;

layout(binding = RB_BIND_BDPT_SPLIT_GB_POSITION, rgba32f) uniform readonly image2D gb_position;
layout(binding = RB_BIND_BDPT_SPLIT_GB_NORMAL, rgba32f) uniform readonly image2D gb_normal;
layout(binding = RB_BIND_BDPT_SPLIT_GB_SPECULAR, rgba32f) uniform readonly image2D gb_specular;
layout(binding = RB_BIND_BDPT_SPLIT_GB_EMISSION, rgba32f) uniform readonly image2D gb_emission;
layout(binding = RB_BIND_BDPT_SPLIT_GB_MOTION, rgba32f) uniform readonly image2D gb_motion;
layout(binding = RB_BIND_BDPT_SPLIT_OUT + 0, rgba32f) uniform writeonly image2D o_position;
layout(binding = RB_BIND_BDPT_SPLIT_OUT + 1, rgba32f) uniform writeonly image2D o_normal;
layout(binding = RB_BIND_BDPT_SPLIT_OUT + 2, rgba32f) uniform writeonly image2D o_fresnel;
layout(binding = RB_BIND_BDPT_SPLIT_OUT + 3, rgba32f) uniform writeonly image2D o_geometric;
layout(push_constant) uniform Push { rb_gpu_bdpt_image_push pc; };

void main()
{
    ivec2 sp = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(sp, imageSize(o_position))))
        return;
    int n = int(pc.split.x);
    ivec2 sub = ivec2(pc.split.yz);
    ivec2 px = (sp % sub) * n + sp / sub;
    if (any(greaterThanEqual(px, imageSize(gb_position)))) {
        imageStore(o_position, sp, vec4(0.0));
        imageStore(o_normal, sp, vec4(0.0));
        imageStore(o_fresnel, sp, vec4(0.0));
        imageStore(o_geometric, sp, vec4(0.0));
        return;
    }
    vec4 spec = imageLoad(gb_specular, px);
    imageStore(o_position, sp, imageLoad(gb_position, px));
    imageStore(o_normal, sp, vec4(imageLoad(gb_normal, px).xyz, spec.a));
    imageStore(o_fresnel, sp, vec4(spec.rgb, imageLoad(gb_emission, px).a));
    imageStore(o_geometric, sp, vec4(imageLoad(gb_motion, px).zw, 0.0, 0.0));
}
