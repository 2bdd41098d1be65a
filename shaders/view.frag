// view, depth output: the view depth (rb_view_depth) into an R32F layer. Shadow maps store this,
// so the direct pass can filter by hand (lavapipe cannot filter depth formats).
#version 460
#extension GL_GOOGLE_include_directive : require
#include "view_shared.h"
#include "view.glsl"

layout(std430, binding = RB_VIEW_BIND_VIEWS) readonly buffer Views { rb_gpu_view views[]; };
layout(push_constant) uniform Push { rb_gpu_view_push pc; };

layout(location = 0) in vec3 i_pos;
layout(location = 0) out float o_depth;

void main()
{
    o_depth = rb_view_depth(views[pc.index.x], pc.index.z, i_pos);
}
