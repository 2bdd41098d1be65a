/* Descriptor binding numbers, named once for GLSL and C. A shader declares
 * `layout(binding = RB_BIND_OUTPUT_BEAUTY)`; its pass's C binding table is indexed by the same
 * names (lib/passes/passes_int.h) and checks its length against the _COUNT, so the two cannot
 * drift apart. Every pass uses one push-descriptor set (set 0) with bindings 0 to _COUNT - 1. */
#ifndef RB_SHADERS_BINDINGS_SHARED_H
#define RB_SHADERS_BINDINGS_SHARED_H

/* animate.comp */
#define RB_BIND_ANIMATE_GEOMETRY 0 /* the slot's record: its vertices written, the source read */
#define RB_BIND_ANIMATE_INSTANCES 1
#define RB_BIND_ANIMATE_JOINTS 2
#define RB_BIND_ANIMATE_WEIGHTS 3
#define RB_BIND_ANIMATE_COUNT 4

/* gbuffer.vert and gbuffer.frag */
#define RB_BIND_GBUFFER_GLOBALS 0
#define RB_BIND_GBUFFER_VERTICES 1      /* the slot's geometry record (geometry_shared.h) */
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
#define RB_BIND_OUTPUT_SPECULAR 9  /* the G-buffer's F0: the gray specular map */
#define RB_BIND_OUTPUT_LIGHT 10    /* RB_BDPT_LIGHT_COUNT images: bdpt's gathered light */
#define RB_BIND_OUTPUT_STATS 14    /* the hybrid's samples and tile masks (RB_BIND_HYBRID_STATS) */
#define RB_BIND_OUTPUT_TRANSPARENCY 15 /* the transparency pass's light and transmittance */
#define RB_BIND_OUTPUT_COUNT 16

/* transparency.vert and transparency.frag: blended materials, lit as direct.comp lights a pixel */
#define RB_BIND_TRANSPARENCY_GLOBALS 0
#define RB_BIND_TRANSPARENCY_VERTICES 1 /* the slot's geometry record */
#define RB_BIND_TRANSPARENCY_MATERIALS 2
#define RB_BIND_TRANSPARENCY_SRGB_TEXTURES 3
#define RB_BIND_TRANSPARENCY_LINEAR_TEXTURES 4
#define RB_BIND_TRANSPARENCY_LIGHTS 5
#define RB_BIND_TRANSPARENCY_SHADOW_VIEWS 6
#define RB_BIND_TRANSPARENCY_SHADOW_MAPS 7
#define RB_BIND_TRANSPARENCY_COUNT 8

/* bdpt_bounds.comp: the bounding box of the points the G-buffer sees */
#define RB_BIND_BDPT_BOUNDS_POSITION 0
#define RB_BIND_BDPT_BOUNDS_OUT 1 /* written: lo[3] and hi[3], order-preserving uint floats */
#define RB_BIND_BDPT_BOUNDS_COUNT 2

/* bdpt_generate.comp: VPLs, their paraboloid views and the bundles' orthographic views */
#define RB_BIND_BDPT_GENERATE_BOUNDS 0
#define RB_BIND_BDPT_GENERATE_SAMPLES 1
#define RB_BIND_BDPT_GENERATE_LIGHTS 2
#define RB_BIND_BDPT_GENERATE_BDPT_LIGHTS 3
#define RB_BIND_BDPT_GENERATE_RSM_VIEWS 4
#define RB_BIND_BDPT_GENERATE_RSM_POSITION 5
#define RB_BIND_BDPT_GENERATE_RSM_NORMAL 6
#define RB_BIND_BDPT_GENERATE_RSM_MATERIAL 7
#define RB_BIND_BDPT_GENERATE_VPLS 8         /* written */
#define RB_BIND_BDPT_GENERATE_VPL_VIEWS 9    /* written */
#define RB_BIND_BDPT_GENERATE_BUNDLE_VIEWS 10 /* written */
#define RB_BIND_BDPT_GENERATE_VERTICES 11     /* the frame's slot's geometry record */
#define RB_BIND_BDPT_GENERATE_EMITTERS 12     /* rb_gpu_bdpt_emitter */
#define RB_BIND_BDPT_GENERATE_MATERIALS 13
#define RB_BIND_BDPT_GENERATE_SRGB_TEXTURES 14
#define RB_BIND_BDPT_GENERATE_LINEAR_TEXTURES 15
#define RB_BIND_BDPT_GENERATE_EMIT_INFO 16 /* written: rb_gpu_bdpt_emit_info */
#define RB_BIND_BDPT_GENERATE_PROBE_VIEWS 17 /* written: an emitter VPL's probe, perspective */
#define RB_BIND_BDPT_GENERATE_VPL_DRAWS 18   /* written: instance counts, VPLs 0..K_v - 1 */
#define RB_BIND_BDPT_GENERATE_PROBE_DRAWS 19 /* written: instance counts */
#define RB_BIND_BDPT_GENERATE_EMITTER_CDF 20 /* bdpt_emitters.comp's */
#define RB_BIND_BDPT_GENERATE_COUNT 21

/* bdpt_emitters.comp: the emissive triangles' CDF by power */
#define RB_BIND_BDPT_EMITTERS_VERTICES 0 /* the slot's geometry record */
#define RB_BIND_BDPT_EMITTERS_EMITTERS 1
#define RB_BIND_BDPT_EMITTERS_MATERIALS 2
#define RB_BIND_BDPT_EMITTERS_CDF 3 /* written */
#define RB_BIND_BDPT_EMITTERS_COUNT 4

/* bdpt_bounce.comp: the bounces of the VPLs, from their probes */
#define RB_BIND_BDPT_BOUNCE_VPLS 0 /* read (VPL src + i), written (VPL dst + i) */
#define RB_BIND_BDPT_BOUNCE_VPL_VIEWS 1 /* written */
#define RB_BIND_BDPT_BOUNCE_PROBE_VIEWS 2 /* read; written for the next round */
#define RB_BIND_BDPT_BOUNCE_PROBE_POSITION 3
#define RB_BIND_BDPT_BOUNCE_PROBE_NORMAL 4
#define RB_BIND_BDPT_BOUNCE_PROBE_MATERIAL 5
#define RB_BIND_BDPT_BOUNCE_VPL_DRAWS 6 /* written: instance counts of VPLs dst..dst + K_v - 1 */
#define RB_BIND_BDPT_BOUNCE_SAMPLES 7   /* the slot's block of the sampling table */
#define RB_BIND_BDPT_BOUNCE_PROBE_DRAWS 8 /* written for the next round */
#define RB_BIND_BDPT_BOUNCE_COUNT 9

/* bdpt_split.comp: the G-buffer into n x n sub-images */
#define RB_BIND_BDPT_SPLIT_GB_POSITION 0
#define RB_BIND_BDPT_SPLIT_GB_NORMAL 1
#define RB_BIND_BDPT_SPLIT_GB_SPECULAR 2
#define RB_BIND_BDPT_SPLIT_GB_EMISSION 3
#define RB_BIND_BDPT_SPLIT_GB_MOTION 4
#define RB_BIND_BDPT_SPLIT_OUT 5 /* written: 4 images from here on */
#define RB_BIND_BDPT_SPLIT_COUNT 9

/* bdpt_mark.comp: the texels of bundle k that sub-image k mod n^2 reads */
#define RB_BIND_BDPT_MARK_POSITION 0     /* the split position image */
#define RB_BIND_BDPT_MARK_BUNDLE_VIEWS 1
#define RB_BIND_BDPT_MARK_HEADS 2        /* written: RB_NONE where a point of the sub-image lands */
#define RB_BIND_BDPT_MARK_COUNT 3

/* bdpt_connect.comp: one iteration's connections over one sub-image */
#define RB_BIND_BDPT_CONNECT_GLOBALS 0
#define RB_BIND_BDPT_CONNECT_SPLIT 1 /* 4 images */
#define RB_BIND_BDPT_CONNECT_VPLS 5
#define RB_BIND_BDPT_CONNECT_VPL_VIEWS 6
#define RB_BIND_BDPT_CONNECT_VPL_MAPS 7
#define RB_BIND_BDPT_CONNECT_BUNDLE_VIEWS 8
#define RB_BIND_BDPT_CONNECT_HEADS 9
#define RB_BIND_BDPT_CONNECT_NODES 10
#define RB_BIND_BDPT_CONNECT_LIGHTS 11
#define RB_BIND_BDPT_CONNECT_BDPT_LIGHTS 12
#define RB_BIND_BDPT_CONNECT_SHADOW_VIEWS 13
#define RB_BIND_BDPT_CONNECT_SHADOW_MAPS 14
#define RB_BIND_BDPT_CONNECT_ENV_MAP 15
#define RB_BIND_BDPT_CONNECT_LIGHT 16 /* read and written: RB_BDPT_LIGHT_COUNT images */
#define RB_BIND_BDPT_CONNECT_EMIT_INFO 20 /* rb_gpu_bdpt_emit_info */
#define RB_BIND_BDPT_CONNECT_EMITTED 21 /* written by the emitters' dispatch: 2 images */
#define RB_BIND_BDPT_CONNECT_LTC 23     /* the specular lobe's fits (RB_LTC_SIZE^2 vec4) */
#define RB_BIND_BDPT_CONNECT_COUNT 24

/* bdpt_gather.comp: the sub-images' light back to the image */
#define RB_BIND_BDPT_GATHER_IN 0  /* RB_BDPT_LIGHT_COUNT images */
#define RB_BIND_BDPT_GATHER_OUT 4 /* written: RB_BDPT_LIGHT_COUNT images */
#define RB_BIND_BDPT_GATHER_COUNT 8

/* bdpt_filter.comp: the geometry-aware filter */
#define RB_BIND_BDPT_FILTER_GB_POSITION 0
#define RB_BIND_BDPT_FILTER_GB_NORMAL 1
#define RB_BIND_BDPT_FILTER_IN 2  /* RB_BDPT_LIGHT_COUNT images */
#define RB_BIND_BDPT_FILTER_OUT 6 /* written: RB_BDPT_LIGHT_COUNT images */
#define RB_BIND_BDPT_FILTER_EMITTED 10 /* RB_BDPT_EMITTED_COUNT images */
#define RB_BIND_BDPT_FILTER_COUNT 12

/* reproject.vert and reproject.frag: each pixel's surface moved back to the caches' frames */
#define RB_BIND_REPROJECT_GLOBALS 0
#define RB_BIND_REPROJECT_HISTORY 1  /* rb_gpu_bdpt_history */
#define RB_BIND_REPROJECT_OUT 2      /* written: a layer per age */
#define RB_BIND_REPROJECT_VERTICES 3 /* RB_BDPT_MAX_CACHES: frame f - a's geometry record */
#define RB_BIND_REPROJECT_COUNT 11

/* bdpt_reconstruct.comp: equation (1) over the caches */
#define RB_BIND_BDPT_RECONSTRUCT_HISTORY 0
#define RB_BIND_BDPT_RECONSTRUCT_GB_POSITION 1
#define RB_BIND_BDPT_RECONSTRUCT_REPROJECT 2
#define RB_BIND_BDPT_RECONSTRUCT_CACHE 3 /* RB_BDPT_LIGHT_COUNT arrays, a layer per slot */
#define RB_BIND_BDPT_RECONSTRUCT_OUT 7   /* written: RB_BDPT_LIGHT_COUNT images */
#define RB_BIND_BDPT_RECONSTRUCT_HITS 11 /* written: a float per pixel, host-visible */
#define RB_BIND_BDPT_RECONSTRUCT_GB_NORMAL 12
#define RB_BIND_BDPT_RECONSTRUCT_COUNT 13

/* brdf_table.comp (tests/unit/test_brdf_parity.c) */
#define RB_BIND_BRDF_TABLE_IN 0
#define RB_BIND_BRDF_TABLE_OUT 1
#define RB_BIND_BRDF_TABLE_COUNT 2

/* bundle_probe.comp (tests/unit/test_bundle_search.c) */
#define RB_BIND_BUNDLE_PROBE_POSITION 0 /* the G-buffer's position */
#define RB_BIND_BUNDLE_PROBE_MOTION 1   /* the G-buffer's motion: zw, the octahedral Ng */
#define RB_BIND_BUNDLE_PROBE_VIEWS 2
#define RB_BIND_BUNDLE_PROBE_HEADS 3
#define RB_BIND_BUNDLE_PROBE_NODES 4
#define RB_BIND_BUNDLE_PROBE_OUT 5
#define RB_BIND_BUNDLE_PROBE_COUNT 6

/* hybrid_*.comp: one table for every pass of the hybrid integrator (each shader declares what it
 * uses through hybrid.glsl; lib/passes/hybrid.c binds them all) */
#define RB_BIND_HYBRID_GLOBALS 0
#define RB_BIND_HYBRID_GB_POSITION 1
#define RB_BIND_HYBRID_GB_NORMAL 2
#define RB_BIND_HYBRID_GB_ALBEDO 3
#define RB_BIND_HYBRID_GB_SPECULAR 4
#define RB_BIND_HYBRID_GB_EMISSION 5
#define RB_BIND_HYBRID_GB_MOTION 6
#define RB_BIND_HYBRID_LIGHTS 7
#define RB_BIND_HYBRID_SHADOW_VIEWS 8
#define RB_BIND_HYBRID_SHADOW_MAPS 9
#define RB_BIND_HYBRID_ENV_MAP 10
#define RB_BIND_HYBRID_DIRECT 11   /* the direct pass's light */
#define RB_BIND_HYBRID_HIZ 12      /* min and max depth, every level */
#define RB_BIND_HYBRID_SLOTS 13    /* rb_gpu_hybrid_slot per ray */
#define RB_BIND_HYBRID_COUNTERS 14 /* rb_gpu_hybrid_counters, host-visible */
#define RB_BIND_HYBRID_QUEUE 15    /* slot indices for the BVH */
#define RB_BIND_HYBRID_BLOCKS 16   /* queued rays per block of slots, then their prefix sums */
#define RB_BIND_HYBRID_BVH_NODES 17
#define RB_BIND_HYBRID_BVH_TRIS 18 /* the triangles, then the baked points (hybrid_shared.h) */
#define RB_BIND_HYBRID_VERTICES 19 /* this frame's slot's geometry record */
#define RB_BIND_HYBRID_INDICES 20 /* a geometry record: .indices the triangles, emitters, sky */
#define RB_BIND_HYBRID_MATERIALS 21
#define RB_BIND_HYBRID_SRGB_TEXTURES 22
#define RB_BIND_HYBRID_LINEAR_TEXTURES 23
#define RB_BIND_HYBRID_ACC_PREV 24 /* RB_HYBRID_ACC_LAYERS layers, the previous frame's */
#define RB_BIND_HYBRID_ACC 25      /* the same, this frame's */
#define RB_BIND_HYBRID_TILES 26    /* a float per noise tile: 1 where it is done */
#define RB_BIND_HYBRID_STATS 27    /* samples and tile mask per pixel (the EXR layers) */
#define RB_BIND_HYBRID_LIGHT 28    /* written: RB_BDPT_LIGHT_COUNT images for the output pass */
#define RB_BIND_HYBRID_COUNT 32

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
