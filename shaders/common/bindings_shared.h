/* Descriptor binding numbers, named once for GLSL and C. A shader declares
 * `layout(binding = RB_BIND_OUTPUT_BEAUTY)`; its pass's C binding table is indexed by the same
 * names (lib/passes/passes_int.h) and checks its length against the _COUNT, so the two cannot
 * drift apart. Every pass uses one push-descriptor set (set 0) with bindings 0 to _COUNT - 1. */
#ifndef RB_SHADERS_BINDINGS_SHARED_H
#define RB_SHADERS_BINDINGS_SHARED_H

/* animate.comp */
#define RB_BIND_ANIMATE_SRC_VERTICES 0 /* struct rb_scene_vertex, as floats */
#define RB_BIND_ANIMATE_MORPH_DELTAS 1 /* struct rb_scene_morph_delta, as floats */
#define RB_BIND_ANIMATE_INSTANCES 2
#define RB_BIND_ANIMATE_JOINTS 3
#define RB_BIND_ANIMATE_WEIGHTS 4
#define RB_BIND_ANIMATE_VERTICES 5 /* written */
#define RB_BIND_ANIMATE_COUNT 6

/* gbuffer.vert and gbuffer.frag */
#define RB_BIND_GBUFFER_GLOBALS 0
#define RB_BIND_GBUFFER_VERTICES 1
#define RB_BIND_GBUFFER_PREV_VERTICES 2 /* the previous frame's, for motion vectors */
#define RB_BIND_GBUFFER_MATERIALS 3
#define RB_BIND_GBUFFER_SRGB_TEXTURES 4
#define RB_BIND_GBUFFER_LINEAR_TEXTURES 5
#define RB_BIND_GBUFFER_COUNT 6

/* direct.comp */
#define RB_BIND_DIRECT_GLOBALS 0
#define RB_BIND_DIRECT_GB_POSITION 1
#define RB_BIND_DIRECT_GB_NORMAL 2
#define RB_BIND_DIRECT_GB_ALBEDO 3
#define RB_BIND_DIRECT_GB_SPECULAR 4
#define RB_BIND_DIRECT_GB_EMISSION 5
#define RB_BIND_DIRECT_GB_MOTION 6
#define RB_BIND_DIRECT_LIGHTS 7
#define RB_BIND_DIRECT_SHADOW_VIEWS 8
#define RB_BIND_DIRECT_SHADOW_MAPS 9
#define RB_BIND_DIRECT_ENV_MAP 10
#define RB_BIND_DIRECT_OUT 11 /* written */
#define RB_BIND_DIRECT_COUNT 12

/* output.comp */
#define RB_BIND_OUTPUT_GLOBALS 0
#define RB_BIND_OUTPUT_BEAUTY 1
#define RB_BIND_OUTPUT_DIRECT 2
#define RB_BIND_OUTPUT_ALBEDO 3
#define RB_BIND_OUTPUT_NORMAL 4
#define RB_BIND_OUTPUT_POSITION 5
#define RB_BIND_OUTPUT_MOTION 6
#define RB_BIND_OUTPUT_READBACK 7  /* written: RB_OUT_FLOATS per pixel */
#define RB_BIND_OUTPUT_NONFINITE 8 /* one uint, added to */
#define RB_BIND_OUTPUT_COUNT 9

/* brdf_table.comp (tests/unit/test_brdf_parity.c) */
#define RB_BIND_BRDF_TABLE_IN 0
#define RB_BIND_BRDF_TABLE_OUT 1
#define RB_BIND_BRDF_TABLE_COUNT 2

/* light_table.comp (tests/unit/test_light_parity.c) */
#define RB_BIND_LIGHT_TABLE_LIGHTS 0
#define RB_BIND_LIGHT_TABLE_POINTS 1
#define RB_BIND_LIGHT_TABLE_DIRS 2
#define RB_BIND_LIGHT_TABLE_ENV_MAP 3
#define RB_BIND_LIGHT_TABLE_OUT 4
#define RB_BIND_LIGHT_TABLE_COUNT 5

/* many_bindings.comp (tests/unit/test_gpu.c): more bindings than the binding list once held */
#define RB_BIND_MANY_BINDINGS_IN 0 /* to 18: RB_BIND_MANY_BINDINGS_IN + i for input i */
#define RB_BIND_MANY_BINDINGS_OUT 19
#define RB_BIND_MANY_BINDINGS_COUNT 20

#endif
