/* Lights in world space (the scene's KHR_lights_punctual lights through their nodes, then the
 * job's, then the setup's default light) and the job's animation clip names resolved to indices. */
#include "scene/scene_int.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define NONE RB_SCENE_NONE

static void put(struct rb_world_light *out, uint32_t cap, uint32_t *n,
                const struct rb_world_light *l)
{
    if (*n < cap)
        out[*n] = *l;
    (*n)++;
}

uint32_t rb_scene_world_lights(const struct rb_job *job, const struct rb_scene *scene,
                               const struct rb_scene_setup *setup, const struct rb_scene_pose *pose,
                               struct rb_world_light *out, uint32_t cap)
{
    uint32_t n = 0;
    if (job->use_scene_lights) {
        for (uint32_t i = 0; i < scene->node_count; i++) {
            const struct rb_scene_node *node = &scene->nodes[i];
            if (!node->in_scene || node->light >= scene->light_count)
                continue;
            const struct rb_scene_light *sl = &scene->lights[node->light];
            const struct rb_mat4 *w = &pose->node_world[i];
            struct rb_world_light l = {
                .type = sl->type,
                .position = rb_v3(w->m[3][0], w->m[3][1], w->m[3][2]),
                .direction = rb_v3_normalize(rb_mat4_dir(w, rb_v3(0, 0, -1))),
                .color = {sl->color[0] * sl->intensity, sl->color[1] * sl->intensity,
                          sl->color[2] * sl->intensity},
                .range = sl->range,
                .inner_cone_rad = sl->inner_cone_rad,
                .outer_cone_rad = sl->outer_cone_rad,
            };
            if (!(rb_v3_length(l.direction) > 0.5f))
                l.direction = rb_v3(0, 0, -1);
            put(out, cap, &n, &l);
        }
    }
    for (size_t i = 0; job->lights && i < job->light_count; i++) {
        const struct rb_job_light *jl = &job->lights[i];
        float deg = RB_PI / 180.0f;
        struct rb_world_light l = {
            .type = jl->type,
            .position = rb_v3(jl->position[0], jl->position[1], jl->position[2]),
            .direction =
                rb_v3_normalize(rb_v3(jl->direction[0], jl->direction[1], jl->direction[2])),
            .color = {jl->color[0] * jl->intensity, jl->color[1] * jl->intensity,
                      jl->color[2] * jl->intensity},
            .range = jl->range,
            .inner_cone_rad = jl->inner_cone_deg * deg,
            .outer_cone_rad = (jl->outer_cone_deg > 0.0f ? jl->outer_cone_deg : 45.0f) * deg,
        };
        if (!(rb_v3_length(l.direction) > 0.5f))
            l.direction = rb_v3(0, -1, 0); /* none given: straight down */
        if (l.inner_cone_rad > l.outer_cone_rad)
            l.inner_cone_rad = l.outer_cone_rad;
        put(out, cap, &n, &l);
    }
    if (setup->has_default_light)
        put(out, cap, &n, &setup->default_light);
    return n;
}

static double srgb_to_linear(double c)
{
    return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}

void rb_scene_texture_average(const struct rb_scene *scene, uint32_t tex, double out[3])
{
    out[0] = out[1] = out[2] = 1.0;
    if (tex >= scene->texture_count)
        return;
    const struct rb_scene_texture *t = &scene->textures[tex];
    size_t n = (size_t)t->width_px * t->height_px;
    if (!t->rgba8 || n == 0)
        return;
    double lut[256], sum[3] = {0, 0, 0};
    for (int v = 0; v < 256; v++)
        lut[v] = srgb_to_linear(v / 255.0);
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++)
            sum[c] += lut[t->rgba8[i * 4 + c]];
    for (int c = 0; c < 3; c++)
        out[c] = sum[c] / (double)n;
}

/* A walk over the emissive triangles of the pose in a fixed order (instances, then triangles):
 * next_emitter gives each one's corners, emitted radiance, its luminance and its weight
 * (luminance x area), so that two walks see the same numbers in the same order. */
struct emitter_walk {
    const struct rb_scene *scene;
    const struct rb_scene_pose *pose;
    uint32_t instance, tri; /* the next triangle */
    uint32_t cached_tex;
    double avg[3];
};

static bool next_emitter(struct emitter_walk *w, struct rb_vec3 v[3], double le[3], double *lum,
                         double *weight)
{
    const struct rb_scene *scene = w->scene;
    for (; w->instance < w->pose->instance_count; w->instance++, w->tri = 0) {
        const struct rb_scene_instance *in = &w->pose->instances[w->instance];
        const struct rb_scene_primitive *p = &scene->primitives[in->primitive];
        const struct rb_scene_material *m = &scene->materials[p->material];
        if (!(m->emissive[0] > 0.0f || m->emissive[1] > 0.0f || m->emissive[2] > 0.0f))
            continue;
        if (w->tri + 2 >= p->index_count)
            continue;
        if (m->emissive_tex != w->cached_tex) {
            rb_scene_texture_average(scene, m->emissive_tex, w->avg);
            w->cached_tex = m->emissive_tex;
        }
        for (int c = 0; c < 3; c++)
            le[c] = (double)m->emissive[c] * w->avg[c];
        *lum = 0.2126 * le[0] + 0.7152 * le[1] + 0.0722 * le[2];
        const struct rb_mat4 *world = &w->pose->node_world[in->node];
        for (int k = 0; k < 3; k++) {
            const float *pos =
                scene->vertices[p->first_vertex + scene->indices[p->first_index + w->tri + k]]
                    .position;
            v[k] = rb_mat4_point(world, rb_v3(pos[0], pos[1], pos[2]));
        }
        w->tri += 3;
        double area = 0.5 * rb_v3_length(rb_v3_cross(rb_v3_sub(v[1], v[0]), rb_v3_sub(v[2], v[0])));
        *weight = *lum > 0.0 && isfinite(*lum) && isfinite(area) ? *lum * area : 0.0;
        return true;
    }
    return false;
}

/* The radical inverse of i in base 2: the second coordinate of a Hammersley set. */
static double radical_inverse2(uint32_t i)
{
    double r = 0.0, f = 0.5;
    for (; i; i >>= 1, f *= 0.5)
        if (i & 1)
            r += f;
    return r;
}

uint32_t rb_scene_emitter_lights(const struct rb_scene *scene, const struct rb_scene_pose *pose,
                                 uint32_t count, struct rb_world_light *out, uint32_t cap)
{
    const uint32_t K = count < RB_SCENE_EMITTER_LIGHTS_MAX ? count : RB_SCENE_EMITTER_LIGHTS_MAX;
    if (!K)
        return 0;
    struct rb_vec3 v[3];
    double le[3], lum, weight, total = 0.0;
    bool any = false;
    struct emitter_walk w = {.scene = scene, .pose = pose, .cached_tex = RB_SCENE_NONE};
    w.avg[0] = w.avg[1] = w.avg[2] = 1.0;
    while (next_emitter(&w, v, le, &lum, &weight)) {
        any = true;
        total += weight;
    }
    if (!any)
        return 0;
    /* Sample k sits at (k + 1/2) / K along the power's running sum (which triangle, and the
     * first coordinate within it) and at the radical inverse of k across it: a Hammersley set,
     * so the samples spread over the emitters by power and over each triangle. */
    struct rb_world_light samples[RB_SCENE_EMITTER_LIGHTS_MAX];
    for (uint32_t k = 0; k < K; k++)
        samples[k] =
            (struct rb_world_light){.type = RB_LIGHT_EMITTER, .direction = rb_v3(0, -1, 0)};
    if (total > 0.0 && isfinite(total)) {
        w = (struct emitter_walk){.scene = scene, .pose = pose, .cached_tex = RB_SCENE_NONE};
        w.avg[0] = w.avg[1] = w.avg[2] = 1.0;
        double cum = 0.0;
        uint32_t k = 0;
        while (k < K && next_emitter(&w, v, le, &lum, &weight)) {
            if (!(weight > 0.0))
                continue;
            struct rb_vec3 n =
                rb_v3_normalize(rb_v3_cross(rb_v3_sub(v[1], v[0]), rb_v3_sub(v[2], v[0])));
            for (; k < K; k++) {
                double target = (k + 0.5) / K * total;
                if (target >= cum + weight)
                    break;
                double rest = fmin(fmax((target - cum) / weight, 0.0), 1.0);
                double su = sqrt(rest), t = radical_inverse2(k);
                double b1 = su * (1.0 - t), b2 = su * t, b0 = 1.0 - b1 - b2;
                struct rb_world_light *l = &samples[k];
                l->position =
                    rb_v3_add(rb_v3_add(rb_v3_scale(v[0], (float)b0), rb_v3_scale(v[1], (float)b1)),
                              rb_v3_scale(v[2], (float)b2));
                l->direction = n;
                /* Le / p_A / K, p_A = lum / total: this sample's share of the power. */
                for (int c = 0; c < 3; c++)
                    l->color[c] = (float)(le[c] * total / (lum * K));
            }
            cum += weight;
        }
    }
    for (uint32_t k = 0; k < K && k < cap; k++)
        out[k] = samples[k];
    return K;
}

enum rb_status rb_scene_select_clips(const struct rb_scene *scene, const struct rb_job *job,
                                     uint32_t *out, uint32_t cap, uint32_t *count,
                                     struct rb_err *err)
{
    *count = 0;
    if (!job->animation.clip_count || !job->animation.clips) {
        if (scene->animation_count) {
            if (cap < 1)
                return rb_errf(err, RB_E_OVERFLOW, "no room for one animation clip");
            out[0] = 0;
            *count = 1;
        }
        return RB_OK;
    }
    if (job->animation.clip_count > cap)
        return rb_errf(err, RB_E_OVERFLOW, "%s%s%zu animation clips selected; at most %u can play",
                       RB_JOB_AT(job->at.animation_clips), job->animation.clip_count, cap);
    for (size_t i = 0; i < job->animation.clip_count; i++) {
        const char *name = job->animation.clips[i];
        uint32_t a = rb_scene_find_animation(scene, name);
        if (a == NONE) {
            char list[384] = "";
            size_t len = 0;
            for (uint32_t k = 0; k < scene->animation_count && len < sizeof(list); k++) {
                const char *an = scene->animations[k].name;
                int w = an && *an
                            ? snprintf(list + len, sizeof(list) - len, "%s%s", k ? ", " : "", an)
                            : snprintf(list + len, sizeof(list) - len, "%s#%u", k ? ", " : "", k);
                len += w > 0 ? (size_t)w : 0;
            }
            return rb_errf(err, RB_E_INVALID, "%s%sanimation clip '%s' not found (scene has: %s)",
                           RB_JOB_AT(job->at.animation_clips), name ? name : "",
                           scene->animation_count ? list : "none");
        }
        out[i] = a;
    }
    *count = (uint32_t)job->animation.clip_count;
    return RB_OK;
}
