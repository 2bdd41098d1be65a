// hybrid_trace: shaders/common/hybrid_trace_main.glsl.
#version 460
#extension GL_GOOGLE_include_directive : require
#include "hybrid_trace_main.glsl"
