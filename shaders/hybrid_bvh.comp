// hybrid_bvh: shaders/common/hybrid_bvh_main.glsl.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "hybrid_bvh_main.glsl"
