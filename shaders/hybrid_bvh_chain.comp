// hybrid_bvh_chain: shaders/common/hybrid_bvh_main.glsl, for counted paths (max_bounces 2 to 8).
#version 460
#extension GL_GOOGLE_include_directive : require
#define RB_HYBRID_CHAIN
#include "hybrid_bvh_main.glsl"
