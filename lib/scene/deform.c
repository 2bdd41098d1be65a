/* CPU deformation: shaders/animate.comp transcribed, so the reference traces (and the hybrid
 * integrator's BVH holds) the vertices the rasterizer draws. Morph deltas weighted in; then the
 * weighted joint matrices divided by the weight sum for a skinned vertex, else the node's world
 * matrix; normals through the inverse transpose, tangents through the upper 3x3. Single precision,
 * like the shader. */
#include "scene/scene.h"

#include <math.h>

/* GLSL's mat4 * vec4 for column-major m: sum of columns times components. */
static void mat_vec4(const struct rb_mat4 *m, const float v[4], float out[4])
{
    for (int r = 0; r < 4; r++)
        out[r] = m->m[0][r] * v[0] + m->m[1][r] * v[1] + m->m[2][r] * v[2] + m->m[3][r] * v[3];
}

/* A 3x3 as three columns. */
struct mat3 {
    float c[3][3];
};

static struct mat3 upper3(const struct rb_mat4 *m)
{
    struct mat3 r;
    for (int c = 0; c < 3; c++)
        for (int k = 0; k < 3; k++)
            r.c[c][k] = m->m[c][k];
    return r;
}

static void mat3_vec(const struct mat3 *m, const float v[3], float out[3])
{
    for (int r = 0; r < 3; r++)
        out[r] = m->c[0][r] * v[0] + m->c[1][r] * v[1] + m->c[2][r] * v[2];
}

/* transpose(inverse(a)): the cofactor columns over the determinant (a singular matrix gives
 * non-finite values, as GLSL's inverse does, which safe_normalize turns into its fallback). */
static struct mat3 inverse_transpose3(const struct mat3 *a)
{
    struct mat3 r;
    rb_f3_cross(a->c[1], a->c[2], r.c[0]);
    rb_f3_cross(a->c[2], a->c[0], r.c[1]);
    rb_f3_cross(a->c[0], a->c[1], r.c[2]);
    float det = rb_f3_dot(a->c[0], r.c[0]);
    for (int c = 0; c < 3; c++)
        for (int k = 0; k < 3; k++)
            r.c[c][k] /= det;
    return r;
}

static void safe_normalize(const float v[3], const float fallback[3], float out[3])
{
    float l = sqrtf(rb_f3_dot(v, v));
    for (int i = 0; i < 3; i++)
        out[i] = l > 1e-20f ? v[i] / l : fallback[i];
}

/* w.x * J[x] + w.y * J[y] + w.z * J[z] + w.w * J[w], then divided by the weight sum; a joint
 * index past the pose's matrices (a broken file) contributes nothing rather than reading out of
 * bounds. */
static struct rb_mat4 skin_matrix(const struct rb_scene_pose *pose, uint32_t first,
                                  const uint32_t j[4], const float w[4], float wsum)
{
    struct rb_mat4 m = {{{0}}};
    for (int k = 0; k < 4; k++) {
        if ((uint64_t)first + j[k] >= pose->joint_matrix_count)
            continue;
        const struct rb_mat4 *J = &pose->joint_matrices[first + j[k]];
        for (int c = 0; c < 4; c++)
            for (int r = 0; r < 4; r++)
                m.m[c][r] += w[k] * J->m[c][r];
    }
    for (int c = 0; c < 4; c++)
        for (int r = 0; r < 4; r++)
            m.m[c][r] /= wsum;
    return m;
}

void rb_scene_deform(const struct rb_scene *scene, const struct rb_scene_pose *pose, float *pos,
                     size_t pos_stride, float *nrm, float *tan, float *uv)
{
    static const float up[3] = {0.0f, 1.0f, 0.0f}, right[3] = {1.0f, 0.0f, 0.0f};
    size_t dst = 0;
    for (uint32_t i = 0; i < pose->instance_count; i++) {
        const struct rb_scene_instance *in = &pose->instances[i];
        const struct rb_scene_primitive *prim = &scene->primitives[in->primitive];
        const struct rb_mat4 *world = &pose->node_world[in->node];
        struct rb_mat4 inv = rb_mat4_inverse(world, NULL);
        struct rb_mat4 nm4 = rb_mat4_transpose(&inv);
        struct mat3 node_n = upper3(&nm4);
        uint32_t morphs = in->first_weight == RB_SCENE_NONE ? 0 : prim->morph_target_count;
        bool skinned = in->first_joint != RB_SCENE_NONE;
        for (uint32_t v = 0; v < prim->vertex_count; v++, dst++) {
            const struct rb_scene_vertex *sv = &scene->vertices[prim->first_vertex + v];
            float p[4] = {sv->position[0], sv->position[1], sv->position[2], 1.0f};
            float n[3] = {sv->normal[0], sv->normal[1], sv->normal[2]};
            for (uint32_t k = 0; k < morphs; k++) {
                size_t wi = (size_t)in->first_weight + k;
                size_t mi = (size_t)prim->first_morph + (size_t)k * prim->vertex_count + v;
                if (wi >= pose->morph_weight_count || mi >= scene->morph_delta_count)
                    continue;
                float wk = pose->morph_weights[wi];
                const struct rb_scene_morph_delta *md = &scene->morph_deltas[mi];
                for (int c = 0; c < 3; c++) {
                    p[c] += wk * md->position[c];
                    n[c] += wk * md->normal[c];
                }
            }
            const struct rb_mat4 *M = world;
            struct mat3 N = node_n;
            struct rb_mat4 skin;
            const float *w = sv->weights;
            float wsum = w[0] + w[1] + w[2] + w[3];
            if (skinned && wsum > 0.0f) {
                skin = skin_matrix(pose, in->first_joint, sv->joints, w, wsum);
                M = &skin;
                struct mat3 m3 = upper3(M);
                N = inverse_transpose3(&m3);
            }
            float out[4];
            mat_vec4(M, p, out);
            float *po = pos + dst * pos_stride;
            po[0] = out[0];
            po[1] = out[1];
            po[2] = out[2];
            if (pos_stride > 3)
                po[3] = 0.0f;
            if (nrm) {
                float tn[3];
                mat3_vec(&N, n, tn);
                safe_normalize(tn, up, nrm + dst * 3);
            }
            if (tan) {
                struct mat3 m3 = upper3(M);
                float tt[3];
                mat3_vec(&m3, sv->tangent, tt);
                safe_normalize(tt, right, tan + dst * 4);
                tan[dst * 4 + 3] = sv->tangent[3] < 0.0f ? -1.0f : 1.0f;
            }
            if (uv) {
                uv[dst * 2 + 0] = sv->uv[0];
                uv[dst * 2 + 1] = sv->uv[1];
            }
        }
    }
}
