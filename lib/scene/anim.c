/* Animation evaluation: keyframe sampling (STEP, LINEAR, CUBICSPLINE per glTF 3.11), the pose
 * (node world matrices, skin joint matrices, morph weights) and its world bounds. Everything is
 * sized in rb_scene_pose_create so that rb_scene_evaluate never allocates. */
#include "scene/scene_int.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define NONE RB_SCENE_NONE

struct box {
    struct rb_vec3 lo, hi; /* empty when lo.x > hi.x */
};

/* The public pose plus the scratch that evaluation needs. */
struct pose_impl {
    struct rb_scene_pose pub; /* first: rb_scene_pose_destroy casts back */
    uint32_t *order;          /* nodes, parents first */
    struct rb_vec3 *t, *s;    /* per node: current local translation and scale */
    struct rb_quat *r;
    float *weights;         /* current morph weights of the nodes that have a slot */
    uint32_t *weight_slot;  /* per node: offset into weights, or NONE */
    uint32_t *weight_count; /* per node: its mesh's morph target count */
    uint32_t *joint_block;  /* per node: offset into pub.joint_matrices, or NONE */
    uint32_t *morph_block;  /* per node: offset into pub.morph_weights, or NONE */
    struct box *prim_box;   /* per primitive: bounds of its vertex positions */
    uint32_t *target_first; /* per primitive: into target_box */
    struct box *target_box; /* per primitive and target: bounds of the position deltas */
    uint32_t *joint_first;  /* per primitive: into joint_box, NONE when unskinned */
    uint32_t *joint_count;  /* per primitive: joints with a box */
    struct box *joint_box;  /* per primitive and joint: vertices that joint moves */
};

/* ---- sampling ------------------------------------------------------------------------------ */

/* The key interval [k, k+1] holding t and the position u in it; clamps outside the keys
 * (*k is then the first or last key and u is 0). */
static void find_key(const struct rb_scene_anim_sampler *s, float t, uint32_t *k, float *u)
{
    uint32_t n = s->key_count;
    *u = 0.0f;
    if (!(t > s->times[0])) { /* also catches NaN */
        *k = 0;
        return;
    }
    if (t >= s->times[n - 1]) {
        *k = n - 1;
        return;
    }
    uint32_t lo = 0, hi = n - 1; /* times[lo] < t < times[hi]... invariant times[lo] <= t */
    while (hi - lo > 1) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (s->times[mid] <= t)
            lo = mid;
        else
            hi = mid;
    }
    *k = lo;
    float dt = s->times[lo + 1] - s->times[lo];
    *u = dt > 0.0f ? (t - s->times[lo]) / dt : 0.0f;
}

/* The value of key k (for CUBICSPLINE the middle of in-tangent, value, out-tangent). */
static const float *key_value(const struct rb_scene_anim_sampler *s, uint32_t k)
{
    uint32_t stride = s->interpolation == RB_ANIM_CUBICSPLINE ? 3 : 1;
    return s->values + ((size_t)k * stride + (stride == 3 ? 1 : 0)) * s->components;
}

void rb_scene_sample(const struct rb_scene_anim_sampler *s, float t, float *out)
{
    uint32_t n = s->components, k;
    float u;
    if (!s->key_count || !n)
        return;
    find_key(s, t, &k, &u);
    const float *a = key_value(s, k);
    if (k + 1 >= s->key_count || s->interpolation == RB_ANIM_STEP || u <= 0.0f) {
        memcpy(out, a, n * sizeof(float));
        return;
    }
    const float *b = key_value(s, k + 1);
    if (s->interpolation == RB_ANIM_LINEAR) {
        for (uint32_t c = 0; c < n; c++)
            out[c] = a[c] + (b[c] - a[c]) * u;
        return;
    }
    /* glTF Appendix C: p(u) = (2u^3 - 3u^2 + 1) v_k + td (u^3 - 2u^2 + u) b_k
     *                       + (-2u^3 + 3u^2) v_k+1 + td (u^3 - u^2) a_k+1,
     * with b_k the out-tangent of key k and a_k+1 the in-tangent of key k+1. */
    float td = s->times[k + 1] - s->times[k];
    const float *out_tan = a + n, *in_tan = b - n;
    float u2 = u * u, u3 = u2 * u;
    float h00 = 2 * u3 - 3 * u2 + 1, h10 = u3 - 2 * u2 + u, h01 = -2 * u3 + 3 * u2;
    float h11 = u3 - u2;
    for (uint32_t c = 0; c < n; c++)
        out[c] = h00 * a[c] + td * h10 * out_tan[c] + h01 * b[c] + td * h11 * in_tan[c];
}

void rb_scene_sample_path(const struct rb_scene_anim_sampler *s, enum rb_anim_path path, float t,
                          float *out)
{
    if (path != RB_ANIM_ROTATION || s->components != 4 || !s->key_count) {
        rb_scene_sample(s, t, out);
        return;
    }
    struct rb_quat q;
    uint32_t k;
    float u;
    find_key(s, t, &k, &u);
    if (s->interpolation == RB_ANIM_LINEAR && k + 1 < s->key_count && u > 0.0f) {
        const float *a = key_value(s, k), *b = key_value(s, k + 1);
        q = rb_quat_slerp((struct rb_quat){a[0], a[1], a[2], a[3]},
                          (struct rb_quat){b[0], b[1], b[2], b[3]}, u);
    } else {
        float v[4];
        rb_scene_sample(s, t, v);
        q = rb_quat_normalize((struct rb_quat){v[0], v[1], v[2], v[3]});
    }
    out[0] = q.x, out[1] = q.y, out[2] = q.z, out[3] = q.w;
}

/* ---- pose ---------------------------------------------------------------------------------- */

static struct box box_empty(void)
{
    return (struct box){rb_v3(INFINITY, INFINITY, INFINITY),
                        rb_v3(-INFINITY, -INFINITY, -INFINITY)};
}

static void box_add(struct box *b, struct rb_vec3 p)
{
    b->lo = rb_v3_min(b->lo, p);
    b->hi = rb_v3_max(b->hi, p);
}

static bool box_is_empty(const struct box *b)
{
    return !(b->lo.x <= b->hi.x);
}

static bool prim_valid(const struct rb_scene *scene, const struct rb_scene_primitive *p)
{
    return (uint64_t)p->first_vertex + p->vertex_count <= scene->vertex_count &&
           (uint64_t)p->first_morph + (uint64_t)p->morph_target_count * p->vertex_count <=
               scene->morph_delta_count;
}

/* Precomputes the per-primitive boxes the bounds need (one pass over the vertices). */
static enum rb_status prim_boxes(const struct rb_scene *scene, struct pose_impl *pi,
                                 struct rb_err *err)
{
    uint32_t np = scene->primitive_count;
    size_t targets = 0, joints = 0;
    for (uint32_t p = 0; p < np; p++) {
        const struct rb_scene_primitive *pr = &scene->primitives[p];
        if (!prim_valid(scene, pr))
            return rb_errf(err, RB_E_INVALID, "primitive %u: vertex or morph range out of bounds",
                           p);
        pi->target_first[p] = (uint32_t)targets;
        targets += pr->morph_target_count;
        uint32_t mj = 0;
        for (uint32_t v = 0; v < pr->vertex_count; v++) {
            const struct rb_scene_vertex *x = &scene->vertices[pr->first_vertex + v];
            for (int j = 0; j < 4; j++)
                if (x->weights[j] != 0.0f && x->joints[j] < 65536 && x->joints[j] + 1 > mj)
                    mj = x->joints[j] + 1;
        }
        pi->joint_first[p] = mj ? (uint32_t)joints : NONE;
        pi->joint_count[p] = mj;
        joints += mj;
    }
    pi->target_box = malloc((targets + 1) * sizeof(struct box));
    pi->joint_box = malloc((joints + 1) * sizeof(struct box));
    if (!pi->target_box || !pi->joint_box)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    for (size_t i = 0; i < joints; i++)
        pi->joint_box[i] = box_empty();
    for (uint32_t p = 0; p < np; p++) {
        const struct rb_scene_primitive *pr = &scene->primitives[p];
        struct box b = box_empty();
        for (uint32_t v = 0; v < pr->vertex_count; v++) {
            const struct rb_scene_vertex *x = &scene->vertices[pr->first_vertex + v];
            struct rb_vec3 pos = rb_v3(x->position[0], x->position[1], x->position[2]);
            box_add(&b, pos);
            if (pi->joint_first[p] == NONE)
                continue;
            for (int j = 0; j < 4; j++)
                if (x->weights[j] != 0.0f && x->joints[j] < pi->joint_count[p])
                    box_add(&pi->joint_box[pi->joint_first[p] + x->joints[j]], pos);
        }
        pi->prim_box[p] = b;
        for (uint32_t t = 0; t < pr->morph_target_count; t++) {
            struct box d = box_empty();
            const struct rb_scene_morph_delta *md =
                &scene->morph_deltas[pr->first_morph + (size_t)t * pr->vertex_count];
            for (uint32_t v = 0; v < pr->vertex_count; v++)
                box_add(&d, rb_v3(md[v].position[0], md[v].position[1], md[v].position[2]));
            if (box_is_empty(&d))
                d = (struct box){rb_v3(0, 0, 0), rb_v3(0, 0, 0)};
            pi->target_box[pi->target_first[p] + t] = d;
        }
    }
    return RB_OK;
}

enum rb_status rb_scene_pose_create(const struct rb_scene *scene, struct rb_scene_pose **out,
                                    struct rb_err *err)
{
    enum rb_status st = RB_OK;
    uint32_t n = scene->node_count, np = scene->primitive_count;
    struct pose_impl *pi = calloc(1, sizeof(*pi));
    if (!pi)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    struct rb_scene_pose *pose = &pi->pub;
    pi->order = malloc((n + 1) * sizeof(uint32_t));
    pi->t = malloc((n + 1) * sizeof(struct rb_vec3));
    pi->s = malloc((n + 1) * sizeof(struct rb_vec3));
    pi->r = malloc((n + 1) * sizeof(struct rb_quat));
    pi->weight_slot = malloc((n + 1) * sizeof(uint32_t));
    pi->weight_count = calloc(n + 1, sizeof(uint32_t));
    pi->joint_block = malloc((n + 1) * sizeof(uint32_t));
    pi->morph_block = malloc((n + 1) * sizeof(uint32_t));
    pi->prim_box = malloc((np + 1) * sizeof(struct box));
    pi->target_first = malloc((np + 1) * sizeof(uint32_t));
    pi->joint_first = malloc((np + 1) * sizeof(uint32_t));
    pi->joint_count = malloc((np + 1) * sizeof(uint32_t));
    pose->node_world = malloc((n + 1) * sizeof(struct rb_mat4));
    if (!pi->order || !pi->t || !pi->s || !pi->r || !pi->weight_slot || !pi->weight_count ||
        !pi->joint_block || !pi->morph_block || !pi->prim_box || !pi->target_first ||
        !pi->joint_first || !pi->joint_count || !pose->node_world) {
        st = rb_errf(err, RB_E_NOMEM, "out of memory");
        goto out;
    }
    if ((st = rb_scene_node_order(scene, pi->order, err)) || (st = prim_boxes(scene, pi, err)))
        goto out;

    /* Count instances and the per-node weight slots, joint blocks and morph blocks. */
    size_t instances = 0, slots = 0, joints = 0, morphs = 0;
    for (uint32_t i = 0; i < n; i++) {
        const struct rb_scene_node *node = &scene->nodes[i];
        pi->weight_slot[i] = pi->joint_block[i] = pi->morph_block[i] = NONE;
        if (node->mesh == NONE)
            continue;
        if (node->mesh >= scene->mesh_count) {
            st = rb_errf(err, RB_E_INVALID, "node %u: mesh %u does not exist", i, node->mesh);
            goto out;
        }
        const struct rb_scene_mesh *m = &scene->meshes[node->mesh];
        if ((uint64_t)m->first_primitive + m->primitive_count > np) {
            st = rb_errf(err, RB_E_INVALID, "mesh %u: primitives out of range", node->mesh);
            goto out;
        }
        if (m->weight_count) {
            pi->weight_slot[i] = (uint32_t)slots;
            pi->weight_count[i] = m->weight_count;
            slots += m->weight_count;
        }
        if (!node->in_scene)
            continue;
        bool skinned = false, morphed = false;
        for (uint32_t p = m->first_primitive; p < m->first_primitive + m->primitive_count; p++) {
            if (scene->primitives[p].morph_target_count > m->weight_count) {
                st = rb_errf(err, RB_E_INVALID,
                             "mesh %u: primitive %u has more morph targets "
                             "than the mesh has weights",
                             node->mesh, p);
                goto out;
            }
            skinned |= pi->joint_first[p] != NONE;
            morphed |= scene->primitives[p].morph_target_count > 0;
        }
        instances += m->primitive_count;
        if (skinned && node->skin != NONE && node->skin < scene->skin_count) {
            pi->joint_block[i] = (uint32_t)joints;
            joints += scene->skins[node->skin].joint_count;
        }
        if (morphed) {
            pi->morph_block[i] = (uint32_t)morphs;
            morphs += m->weight_count;
        }
    }
    if (instances >= UINT32_MAX || joints >= UINT32_MAX || morphs >= UINT32_MAX) {
        st = rb_errf(err, RB_E_UNSUPPORTED, "too many instances");
        goto out;
    }
    pi->weights = malloc((slots + 1) * sizeof(float));
    pose->instances = malloc((instances + 1) * sizeof(struct rb_scene_instance));
    pose->joint_matrices = malloc((joints + 1) * sizeof(struct rb_mat4));
    pose->morph_weights = malloc((morphs + 1) * sizeof(float));
    if (!pi->weights || !pose->instances || !pose->joint_matrices || !pose->morph_weights) {
        st = rb_errf(err, RB_E_NOMEM, "out of memory");
        goto out;
    }
    pose->instance_count = (uint32_t)instances;
    pose->joint_matrix_count = (uint32_t)joints;
    pose->morph_weight_count = (uint32_t)morphs;
    size_t k = 0;
    for (uint32_t i = 0; i < n; i++) {
        const struct rb_scene_node *node = &scene->nodes[i];
        if (node->mesh == NONE || !node->in_scene)
            continue;
        const struct rb_scene_mesh *m = &scene->meshes[node->mesh];
        for (uint32_t p = m->first_primitive; p < m->first_primitive + m->primitive_count; p++) {
            struct rb_scene_instance *in = &pose->instances[k++];
            in->node = i;
            in->primitive = p;
            in->first_joint = pi->joint_first[p] != NONE ? pi->joint_block[i] : NONE;
            in->first_weight = scene->primitives[p].morph_target_count ? pi->morph_block[i] : NONE;
        }
    }
    rb_scene_evaluate(scene, NULL, 0.0, pose);
    *out = pose;
    pi = NULL;
out:
    if (pi)
        rb_scene_pose_destroy(&pi->pub);
    return st;
}

void rb_scene_pose_destroy(struct rb_scene_pose *pose)
{
    if (!pose)
        return;
    struct pose_impl *pi = (struct pose_impl *)pose;
    free(pose->node_world);
    free(pose->instances);
    free(pose->joint_matrices);
    free(pose->morph_weights);
    free(pi->order);
    free(pi->t);
    free(pi->s);
    free(pi->r);
    free(pi->weights);
    free(pi->weight_slot);
    free(pi->weight_count);
    free(pi->joint_block);
    free(pi->morph_block);
    free(pi->prim_box);
    free(pi->target_first);
    free(pi->target_box);
    free(pi->joint_first);
    free(pi->joint_count);
    free(pi->joint_box);
    free(pi);
}

/* Clip time for a sequence time: offset + time * speed, wrapped (loop) or clamped. */
static float clip_time(const struct rb_anim_selection *sel, double duration, double time_s)
{
    double t = sel->offset_s + time_s * sel->speed;
    if (sel->loop && duration > 0.0) {
        t = fmod(t, duration);
        if (t < 0.0)
            t += duration;
    } else {
        t = t < 0.0 ? 0.0 : (t > duration ? duration : t);
    }
    return (float)t;
}

static void apply_clip(const struct rb_scene *scene, const struct rb_scene_animation *a, float t,
                       struct pose_impl *pi)
{
    for (uint32_t c = 0; c < a->channel_count; c++) {
        const struct rb_scene_anim_channel *ch = &a->channels[c];
        if (ch->sampler >= a->sampler_count || ch->node >= scene->node_count)
            continue;
        const struct rb_scene_anim_sampler *s = &a->samplers[ch->sampler];
        float v[4];
        switch (ch->path) {
        case RB_ANIM_TRANSLATION:
        case RB_ANIM_SCALE:
            if (s->components != 3)
                break;
            rb_scene_sample(s, t, v);
            if (ch->path == RB_ANIM_TRANSLATION)
                pi->t[ch->node] = rb_v3(v[0], v[1], v[2]);
            else
                pi->s[ch->node] = rb_v3(v[0], v[1], v[2]);
            break;
        case RB_ANIM_ROTATION:
            if (s->components != 4)
                break;
            rb_scene_sample_path(s, RB_ANIM_ROTATION, t, v);
            pi->r[ch->node] = (struct rb_quat){v[0], v[1], v[2], v[3]};
            break;
        case RB_ANIM_WEIGHTS:
            if (pi->weight_slot[ch->node] == NONE || s->components != pi->weight_count[ch->node])
                break;
            rb_scene_sample(s, t, pi->weights + pi->weight_slot[ch->node]);
            break;
        }
    }
}

static struct box transform_box(const struct box *b, const struct rb_mat4 *m)
{
    struct box o = box_empty();
    for (int i = 0; i < 8; i++) {
        struct rb_vec3 p =
            rb_v3(i & 1 ? b->hi.x : b->lo.x, i & 2 ? b->hi.y : b->lo.y, i & 4 ? b->hi.z : b->lo.z);
        box_add(&o, rb_mat4_point(m, p));
    }
    return o;
}

/* Grows a box by the weighted morph deltas: each target moves a vertex by w * delta, and delta
 * lies in the target's delta box. */
static struct box morph_box(struct box b, const struct box *targets, const float *w, uint32_t n)
{
    for (uint32_t t = 0; w && t < n; t++) {
        struct rb_vec3 a = rb_v3_scale(targets[t].lo, w[t]), c = rb_v3_scale(targets[t].hi, w[t]);
        b.lo = rb_v3_add(b.lo, rb_v3_min(a, c));
        b.hi = rb_v3_add(b.hi, rb_v3_max(a, c));
    }
    return b;
}

void rb_scene_evaluate(const struct rb_scene *scene, const struct rb_anim_selection *sel,
                       double time_s, struct rb_scene_pose *pose)
{
    struct pose_impl *pi = (struct pose_impl *)pose;
    uint32_t n = scene->node_count;

    /* Rest pose, then every selected clip's channels on top (later clips win). */
    for (uint32_t i = 0; i < n; i++) {
        const struct rb_scene_node *node = &scene->nodes[i];
        pi->t[i] = node->translation;
        pi->r[i] = node->rotation;
        pi->s[i] = node->scale;
        if (pi->weight_slot[i] != NONE) {
            const float *rest =
                node->weights ? node->weights : scene->meshes[node->mesh].default_weights;
            float *w = pi->weights + pi->weight_slot[i];
            for (uint32_t k = 0; k < pi->weight_count[i]; k++)
                w[k] = rest ? rest[k] : 0.0f;
        }
    }
    for (uint32_t c = 0; sel && c < sel->clip_count; c++) {
        if (sel->clips[c] >= scene->animation_count)
            continue;
        const struct rb_scene_animation *a = &scene->animations[sel->clips[c]];
        apply_clip(scene, a, clip_time(sel, a->duration_s, time_s), pi);
    }

    for (uint32_t k = 0; k < n; k++) {
        uint32_t i = pi->order[k], p = scene->nodes[i].parent;
        struct rb_mat4 local = rb_mat4_trs(pi->t[i], pi->r[i], pi->s[i]);
        pose->node_world[i] = p == NONE ? local : rb_mat4_mul(&pose->node_world[p], &local);
    }

    /* Joint matrices and morph weights per node block (shared by the node's primitives). */
    for (uint32_t i = 0; i < n; i++) {
        const struct rb_scene_node *node = &scene->nodes[i];
        if (pi->joint_block[i] != NONE) {
            const struct rb_scene_skin *sk = &scene->skins[node->skin];
            for (uint32_t j = 0; j < sk->joint_count; j++) {
                uint32_t jn = sk->joints[j];
                struct rb_mat4 w = jn < n ? pose->node_world[jn] : rb_mat4_identity();
                pose->joint_matrices[pi->joint_block[i] + j] =
                    rb_mat4_mul(&w, &sk->inverse_bind[j]);
            }
        }
        if (pi->morph_block[i] != NONE)
            memcpy(pose->morph_weights + pi->morph_block[i], pi->weights + pi->weight_slot[i],
                   pi->weight_count[i] * sizeof(float));
    }

    /* Bounds: each instance's box (grown by its morph deltas) through its node's world matrix,
     * or for a skinned one, each joint's box through that joint's matrix. A skinned vertex is a
     * convex combination of its joints' transforms of it, so this is conservative. */
    struct box all = box_empty();
    for (uint32_t k = 0; k < pose->instance_count; k++) {
        const struct rb_scene_instance *in = &pose->instances[k];
        const struct rb_scene_primitive *pr = &scene->primitives[in->primitive];
        const struct box *tb = pi->target_box + pi->target_first[in->primitive];
        const float *w = in->first_weight != NONE ? pose->morph_weights + in->first_weight : NULL;
        if (in->first_joint == NONE) {
            struct box b = pi->prim_box[in->primitive];
            if (box_is_empty(&b))
                continue;
            b = morph_box(b, tb, w, pr->morph_target_count);
            b = transform_box(&b, &pose->node_world[in->node]);
            box_add(&all, b.lo);
            box_add(&all, b.hi);
            continue;
        }
        uint32_t skin_joints = scene->skins[scene->nodes[in->node].skin].joint_count;
        for (uint32_t j = 0; j < pi->joint_count[in->primitive] && j < skin_joints; j++) {
            struct box b = pi->joint_box[pi->joint_first[in->primitive] + j];
            if (box_is_empty(&b))
                continue;
            b = morph_box(b, tb, w, pr->morph_target_count);
            b = transform_box(&b, &pose->joint_matrices[in->first_joint + j]);
            box_add(&all, b.lo);
            box_add(&all, b.hi);
        }
    }
    if (box_is_empty(&all))
        all = (struct box){rb_v3(0, 0, 0), rb_v3(0, 0, 0)};
    pose->bounds_min = all.lo;
    pose->bounds_max = all.hi;
}
