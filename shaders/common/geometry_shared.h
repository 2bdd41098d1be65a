/* The scene's geometry as the shaders reach it: by device address (GL_EXT_buffer_reference),
 * not by storage-buffer binding. A binding may span at most maxStorageBufferRange bytes (128 MiB
 * on lavapipe, 1.6 M of the loader's 80-byte vertices), and lavapipe has no descriptor indexing
 * to pick one of several bindings by a vertex's index; an address has no range limit, so the
 * vertex and index arrays grow with the scene up to maxMemoryAllocationSize, one allocation each
 * (raybundle-job(5), LIMITS). A frame slot holds one record (a small uniform buffer) with the
 * addresses of its world vertices and of the frame's static arrays; a pass binds the record
 * where it bound the vertices, and a shader reads `geo.vertices.v[i]`.
 *
 * A shader that includes this enables GL_EXT_buffer_reference first, and includes shared.h. */
#ifndef RB_SHADERS_GEOMETRY_SHARED_H
#define RB_SHADERS_GEOMETRY_SHARED_H

#ifdef VULKAN
layout(buffer_reference, std430, buffer_reference_align = 16) buffer rb_vertex_array
{
    rb_gpu_vertex v[];
};
layout(buffer_reference, std430, buffer_reference_align = 4) buffer rb_float_array
{
    float f[];
};
layout(buffer_reference, std430, buffer_reference_align = 4) buffer rb_uint_array
{
    uint u[];
};
layout(buffer_reference, std430, buffer_reference_align = 16) buffer rb_vec4_array
{
    vec4 v[];
};
#define RB_ADDRESS(type, n) type n
#else
#define RB_ADDRESS(type, n) uint64_t n
#endif

/* std140 (a uniform buffer); 0 where the frame has no such array. */
struct rb_gpu_geometry {
    RB_ADDRESS(rb_vertex_array, vertices);    /* struct rb_gpu_vertex: the slot's, world space */
    RB_ADDRESS(rb_float_array, src_vertices); /* struct rb_scene_vertex, RB_SRC_VERTEX_FLOATS */
    RB_ADDRESS(rb_float_array, morph_deltas); /* struct rb_scene_morph_delta, as floats */
    RB_ADDRESS(rb_uint_array, indices);       /* uint32, into vertices: the frame's draw */
};

/* The hybrid integrator's own arrays that grow with the scene (std140, a uniform buffer):
 * bake and bake_words are its BVH buffer (RB_BIND_HYBRID_BVH_TRIS, bound only as far as its
 * triangles) whole, as vec4s and as words, for the baked points and words after the triangles. */
struct rb_gpu_hybrid_table {
    RB_ADDRESS(rb_uint_array, indices);    /* the triangles' indices, the emitters, the sky */
    RB_ADDRESS(rb_vec4_array, bake);       /* the BVH buffer as vec4s */
    RB_ADDRESS(rb_uint_array, bake_words); /* the BVH buffer as words */
    RB_ADDRESS(rb_uint_array, unused);     /* 0 */
};

#endif
