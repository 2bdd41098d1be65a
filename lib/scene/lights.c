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
        return rb_errf(err, RB_E_OVERFLOW, "%zu animation clips selected; at most %u can play",
                       job->animation.clip_count, cap);
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
            return rb_errf(err, RB_E_INVALID, "animation clip '%s' not found (scene has: %s)",
                           name ? name : "", scene->animation_count ? list : "none");
        }
        out[i] = a;
    }
    *count = (uint32_t)job->animation.clip_count;
    return RB_OK;
}
