/* Buffer layouts shared by C and GLSL (std140 for the globals UBO, std430 for the rest).
 * glslang defines VULKAN; C checks each size with _Static_assert in lib/passes/passes.h. */
#ifndef RB_SHADERS_SHARED_H
#define RB_SHADERS_SHARED_H

#ifdef VULKAN
#define RB_MAT4(n) mat4 n
#define RB_VEC4(n) vec4 n
#define RB_UVEC4(n) uvec4 n
#define RB_IVEC4(n) ivec4 n
#else
#include <stdint.h>
#define RB_MAT4(n) float n[16]
#define RB_VEC4(n) float n[4]
#define RB_UVEC4(n) uint32_t n[4]
#define RB_IVEC4(n) int32_t n[4]
#endif

#define RB_NONE 0xffffffffu

/* Floats per source vertex (struct rb_scene_vertex) and per morph delta. */
#define RB_SRC_VERTEX_FLOATS 20
#define RB_MORPH_DELTA_FLOATS 6

/* Light kinds, as in enum rb_light_type. */
#define RB_KIND_POINT 1
#define RB_KIND_SPOT 2
#define RB_KIND_DIRECTIONAL 3
/* A point sample of the emissive surfaces (the direct integrator's): intensity color x |cos|
 * against direction, both sides. 7, not 4: bdpt's VPL kinds (bdpt_shared.h) follow 1 to 3. */
#define RB_KIND_EMITTER 7

/* Per frame: camera, sizes, environment and shadow settings. */
struct rb_gpu_globals {
    RB_MAT4(view);
    RB_MAT4(proj);
    RB_MAT4(view_proj);
    RB_MAT4(inv_view_proj);
    RB_MAT4(prev_view_proj);
    RB_VEC4(camera_pos);  /* xyz; w = vertical fov in radians */
    RB_UVEC4(size);       /* width, height, light count, frame */
    RB_VEC4(env);         /* intensity, rotation (rad), has map (0/1), unused */
    RB_VEC4(env_color);   /* rgb radiance without a map */
    RB_VEC4(shadow);      /* bias (fraction of distance), pcf radius (texels), map size, layer
                           * lights: after size.z, for the blended layers alone */
};

/* The animate pass's output and the raster passes' input: world space. */
struct rb_gpu_vertex {
    RB_VEC4(position); /* xyz; w unused */
    RB_VEC4(normal);   /* xyz */
    RB_VEC4(tangent);  /* xyz, w handedness */
    RB_VEC4(uv);       /* xy; z = material index (as float bits) */
};

/* One drawable (node x primitive) per frame. */
struct rb_gpu_instance {
    RB_MAT4(world);
    RB_MAT4(normal_matrix); /* inverse transpose of world */
    RB_UVEC4(range);        /* src first vertex, vertex count, dst first vertex, material */
    RB_UVEC4(deform);       /* first morph delta, morph target count, first weight, first joint */
};

struct rb_gpu_material {
    RB_VEC4(base_color);
    RB_VEC4(emissive);       /* rgb; w = normal scale */
    RB_VEC4(params);         /* metallic, roughness, alpha cutoff (0: opaque; RB_ALPHA_BLENDED:
                              * blended, drawn by the transparency pass alone), specular factor */
    RB_VEC4(specular_color); /* rgb; w = double-sided (0/1) */
    RB_IVEC4(textures);      /* base color, metallic-roughness, normal, emissive layer or -1 */
};

/* The alpha cutoff of a material with alphaMode BLEND: the deferred passes and every raster
 * view leave its triangles out (they are no occluders for shadows or global illumination); the
 * transparency pass draws them over the frame. */
#define RB_ALPHA_BLENDED (-1.0)

struct rb_gpu_light {
    RB_VEC4(position);  /* xyz; w = kind */
    RB_VEC4(direction); /* xyz, the direction light travels; w = range (0: infinite) */
    RB_VEC4(color);     /* rgb = color * intensity; w = first shadow layer (-1: none) */
    RB_VEC4(cone);      /* cos inner, cos outer, unused, unused */
};

/* One shadow-map layer: the light's view-projection for it. */
struct rb_gpu_shadow_view {
    RB_MAT4(view_proj);
    RB_VEC4(light); /* xyz: position (point, spot) or the map's origin (directional); w = kind */
    RB_VEC4(axis);  /* xyz: direction (directional); w: texel size, an angle (perspective, in
                     * radians) or a length (directional, in world units) */
};

#ifdef VULKAN
/* Bits of a job's layer mask: enum rb_layer in lib/core/core.h (C has the enum). */
#define RB_LAYER_DIRECT 0u
#define RB_LAYER_INDIRECT 1u
#define RB_LAYER_ALBEDO 2u
#define RB_LAYER_NORMAL 3u
#define RB_LAYER_DEPTH 4u
#define RB_LAYER_MOTION 5u
#define RB_LAYER_INDIRECT_DIFFUSE 6u
#define RB_LAYER_INDIRECT_SPECULAR 7u
#define RB_LAYER_SAMPLES 8u
#define RB_LAYER_TILES 9u
#define RB_LAYER_VARIANCE 10u

/* Luminance with the Rec. 709 weights that lib/ and the reference use too. */
float rb_luminance(vec3 c)
{
    return dot(c, vec3(0.2126, 0.7152, 0.0722));
}
#endif

/* A frame's result with every layer: these floats per pixel, in this order (the reference's
 * result; the GPU's readback when the job writes every layer: rb_layer_offset). */
#define RB_OUT_BEAUTY 0    /* RGBA */
#define RB_OUT_DIRECT 4    /* RGB */
#define RB_OUT_INDIRECT 7  /* RGB */
#define RB_OUT_ALBEDO 10   /* RGB */
#define RB_OUT_NORMAL 13   /* XYZ */
#define RB_OUT_DEPTH 16    /* Z */
#define RB_OUT_MOTION 17   /* XY */
#define RB_OUT_INDIRECT_DIFFUSE 19  /* RGB */
#define RB_OUT_INDIRECT_SPECULAR 22 /* RGB */
#define RB_OUT_SAMPLES 25           /* diffuse, specular */
#define RB_OUT_TILES 27             /* diffuse, specular */
#define RB_OUT_VARIANCE 29          /* Y: the reference's only */
#define RB_OUT_FLOATS 32            /* the last two are padding */

#endif
