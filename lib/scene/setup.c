/* What a job decides once for all its frames: the bounds of every pose its animation can take,
 * the light sources the scene has, whether a default light is needed and where it goes, and
 * where a fitted camera looks from. Deciding these per frame would make them follow the animated
 * bounds, a source of flicker; deciding them from the job's frame range would make a chunk of a
 * sequence differ from the whole. So they come from the animation's whole clip time instead. */
#include "scene/scene_int.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_CLIPS 64
#define MAX_BOUNDS_SAMPLES 1024 /* poses sampled over the longest clip */
#define COVER_GRID 24           /* cells per side when measuring how much of a box face is wall */
/* Below this irradiance at the centre of the bounds (the default light gives about 1 there),
 * emissive surfaces alone leave the view too dark to read, and default_light: auto adds a light
 * (see emitter_irradiance). */
#define EMITTER_IRRADIANCE_MIN 0.05

static void grow(struct rb_vec3 *lo, struct rb_vec3 *hi, struct rb_vec3 a, struct rb_vec3 b)
{
    *lo = rb_v3(fminf(lo->x, a.x), fminf(lo->y, a.y), fminf(lo->z, a.z));
    *hi = rb_v3(fmaxf(hi->x, b.x), fmaxf(hi->y, b.y), fmaxf(hi->z, b.z));
}

/* The union of the posed bounds over the selected clips' whole clip time: one loop at the
 * job's frame rate (at least two poses, at most MAX_BOUNDS_SAMPLES). Clip time is sampled
 * directly (offset 0, speed 1, clamped), so the result depends on neither the frame range nor
 * the animation offset, speed or looping. */
static void animation_bounds(const struct rb_scene *scene, const struct rb_job *job,
                             const uint32_t *clips, uint32_t clip_count, struct rb_scene_pose *pose,
                             struct rb_scene_setup *out)
{
    struct rb_anim_selection sel = {.clips = clips, .clip_count = clip_count, .speed = 1.0};
    double duration = 0.0;
    for (uint32_t i = 0; i < clip_count; i++)
        duration = fmax(duration, scene->animations[clips[i]].duration_s);
    double rate = job->rate_fps > 0.0 ? job->rate_fps : 24.0;
    uint32_t samples = 1;
    if (duration > 0.0) {
        double n = ceil(duration * rate) + 1.0;
        samples = n > MAX_BOUNDS_SAMPLES ? MAX_BOUNDS_SAMPLES : (uint32_t)n;
        if (samples < 2)
            samples = 2;
    }
    struct rb_vec3 lo = rb_v3(INFINITY, INFINITY, INFINITY);
    struct rb_vec3 hi = rb_v3(-INFINITY, -INFINITY, -INFINITY);
    for (uint32_t s = 0; s < samples; s++) {
        double t = samples > 1 ? duration * s / (samples - 1) : 0.0;
        rb_scene_evaluate(scene, &sel, t, pose);
        if (pose->bounds_min.x <= pose->bounds_max.x)
            grow(&lo, &hi, pose->bounds_min, pose->bounds_max);
    }
    if (!(lo.x <= hi.x) || !isfinite(lo.x) || !isfinite(hi.x)) {
        lo = rb_v3(0, 0, 0); /* nothing drawn */
        hi = rb_v3(0, 0, 0);
    }
    out->bounds_min = lo;
    out->bounds_max = hi;
    rb_scene_evaluate(scene, &sel, 0.0, pose); /* the rest pose, for the face coverage */
}

/* Whether any drawn primitive has an emissive material (factor x strength > 0). */
static bool has_emitters(const struct rb_scene *scene, const struct rb_scene_pose *pose)
{
    for (uint32_t i = 0; i < pose->instance_count; i++) {
        const struct rb_scene_material *m =
            &scene->materials[scene->primitives[pose->instances[i].primitive].material];
        if (m->emissive[0] > 0.0f || m->emissive[1] > 0.0f || m->emissive[2] > 0.0f)
            return true;
    }
    return false;
}

/* How strongly the scene's emissive surfaces light it, as an irradiance at the centre of the
 * bounds comparable with the default light's (about 1 there): each emissive triangle's power,
 * the luminance of its emission (factor x strength x the emissive texture's average) times its
 * area, over its squared distance from the centre, that distance at least half the bounding
 * radius (an emitter at the centre lights what is around it, not the centre itself). Facing is
 * ignored: emission leaves both sides in the reference, and an emissive surface wrapped round
 * the centre (a bottle's label) faces away from it yet lights the view. Taken at the rest pose,
 * summed in a fixed order in double: a function of the scene alone. */
static double emitter_irradiance(const struct rb_scene *scene, const struct rb_scene_pose *pose,
                                 struct rb_vec3 lo, struct rb_vec3 hi)
{
    struct rb_vec3 c = rb_v3_scale(rb_v3_add(lo, hi), 0.5f);
    double radius = 0.5 * rb_v3_length(rb_v3_sub(hi, lo));
    double near2 = radius > 0.0 ? 0.25 * radius * radius : 1e-12;
    double total = 0.0;
    uint32_t cached_tex = RB_SCENE_NONE; /* no texture: white, avg's first value */
    double avg[3] = {1.0, 1.0, 1.0};
    for (uint32_t i = 0; i < pose->instance_count; i++) {
        const struct rb_scene_instance *in = &pose->instances[i];
        const struct rb_scene_primitive *p = &scene->primitives[in->primitive];
        const struct rb_scene_material *m = &scene->materials[p->material];
        if (!(m->emissive[0] > 0.0f || m->emissive[1] > 0.0f || m->emissive[2] > 0.0f))
            continue;
        if (m->emissive_tex != cached_tex) {
            rb_scene_texture_average(scene, m->emissive_tex, avg);
            cached_tex = m->emissive_tex;
        }
        double lum = 0.2126 * m->emissive[0] * avg[0] + 0.7152 * m->emissive[1] * avg[1] +
                     0.0722 * m->emissive[2] * avg[2];
        if (!(lum > 0.0) || !isfinite(lum))
            continue;
        const struct rb_mat4 *w = &pose->node_world[in->node];
        for (uint32_t t = 0; t + 2 < p->index_count; t += 3) {
            struct rb_vec3 v[3];
            for (int k = 0; k < 3; k++) {
                const float *pos =
                    scene->vertices[p->first_vertex + scene->indices[p->first_index + t + k]]
                        .position;
                v[k] = rb_mat4_point(w, rb_v3(pos[0], pos[1], pos[2]));
            }
            struct rb_vec3 e1 = rb_v3_sub(v[1], v[0]), e2 = rb_v3_sub(v[2], v[0]);
            struct rb_vec3 x = rb_v3_cross(e1, e2);
            double area = 0.5 * rb_v3_length(x);
            struct rb_vec3 mid = rb_v3_scale(rb_v3_add(rb_v3_add(v[0], v[1]), v[2]), 1.0f / 3.0f);
            struct rb_vec3 d = rb_v3_sub(mid, c);
            double d2 = fmax((double)d.x * d.x + (double)d.y * d.y + (double)d.z * d.z, near2);
            if (isfinite(area) && isfinite(d2))
                total += lum * area / d2;
        }
    }
    return total;
}

static bool env_is_black(const struct rb_job *job, const float *env_rgba, uint32_t w, uint32_t h)
{
    if (!(job->environment.intensity > 0.0f))
        return true;
    if (env_rgba) {
        for (size_t i = 0; i < (size_t)w * h; i++)
            if (env_rgba[i * 4] > 0.0f || env_rgba[i * 4 + 1] > 0.0f || env_rgba[i * 4 + 2] > 0.0f)
                return false;
        return true;
    }
    if (job->environment.map)
        return false; /* a map the caller did not load: assume it lights the scene */
    return !(job->environment.color[0] > 0.0f || job->environment.color[1] > 0.0f ||
             job->environment.color[2] > 0.0f);
}

/* ---- rooms ---------------------------------------------------------------------------------- */

/* The fraction of each face of the bounds (0: -X, 1: +X, 2: -Y, 3: +Y, 4: -Z, 5: +Z) covered by
 * triangles lying in that face's plane (within 2% of the extent, facing along its axis): a
 * COVER_GRID^2 grid of cell centres, each tested against the triangles projected on the face.
 * Skinned and morphed geometry is taken at its bind shape. */
static void face_coverage(const struct rb_scene *scene, const struct rb_scene_pose *pose,
                          struct rb_vec3 lo, struct rb_vec3 hi, float cover[6])
{
    static uint8_t hit[6][COVER_GRID * COVER_GRID];
    memset(hit, 0, sizeof(hit));
    float lo3[3] = {lo.x, lo.y, lo.z}, hi3[3] = {hi.x, hi.y, hi.z};
    float ext[3] = {hi.x - lo.x, hi.y - lo.y, hi.z - lo.z};
    float tol = 0.02f * fmaxf(ext[0], fmaxf(ext[1], ext[2]));
    for (uint32_t i = 0; i < pose->instance_count; i++) {
        const struct rb_scene_instance *in = &pose->instances[i];
        const struct rb_scene_primitive *p = &scene->primitives[in->primitive];
        const struct rb_mat4 *w = &pose->node_world[in->node];
        for (uint32_t t = 0; t + 2 < p->index_count; t += 3) {
            float v[3][3];
            for (int k = 0; k < 3; k++) {
                const float *pos =
                    scene->vertices[p->first_vertex + scene->indices[p->first_index + t + k]]
                        .position;
                struct rb_vec3 q = rb_mat4_point(w, rb_v3(pos[0], pos[1], pos[2]));
                v[k][0] = q.x, v[k][1] = q.y, v[k][2] = q.z;
            }
            for (int face = 0; face < 6; face++) {
                int a = face / 2, u = (a + 1) % 3, vv = (a + 2) % 3;
                float plane = face & 1 ? hi3[a] : lo3[a];
                if (!(ext[u] > 0.0f) || !(ext[vv] > 0.0f) || fabsf(v[0][a] - plane) > tol ||
                    fabsf(v[1][a] - plane) > tol || fabsf(v[2][a] - plane) > tol)
                    continue;
                /* 2D triangle in the face's (u, v) coordinates, normalized to [0, 1]. */
                float x[3], y[3];
                for (int k = 0; k < 3; k++) {
                    x[k] = (v[k][u] - lo3[u]) / ext[u];
                    y[k] = (v[k][vv] - lo3[vv]) / ext[vv];
                }
                float area = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
                if (area == 0.0f)
                    continue;
                for (int cy = 0; cy < COVER_GRID; cy++)
                    for (int cx = 0; cx < COVER_GRID; cx++) {
                        float px = (cx + 0.5f) / COVER_GRID, py = (cy + 0.5f) / COVER_GRID;
                        float e0 = (x[1] - x[0]) * (py - y[0]) - (px - x[0]) * (y[1] - y[0]);
                        float e1 = (x[2] - x[1]) * (py - y[1]) - (px - x[1]) * (y[2] - y[1]);
                        float e2 = (x[0] - x[2]) * (py - y[2]) - (px - x[2]) * (y[0] - y[2]);
                        if (area < 0.0f)
                            e0 = -e0, e1 = -e1, e2 = -e2;
                        if (e0 >= 0.0f && e1 >= 0.0f && e2 >= 0.0f)
                            hit[face][cy * COVER_GRID + cx] = 1;
                    }
            }
        }
    }
    for (int face = 0; face < 6; face++) {
        unsigned n = 0;
        for (int c = 0; c < COVER_GRID * COVER_GRID; c++)
            n += hit[face][c];
        cover[face] = (float)n / (COVER_GRID * COVER_GRID);
    }
}

/* A room open on one side: the face of the bounds least covered is mostly open (< 50% wall;
 * things standing in a room can poke out of its open side), its opposite face and at least
 * three of the other four are mostly wall (> 60%), and no other face is nearly as open.
 * Returns the open face (as face_coverage numbers them), or -1. */
static int open_face(const float cover[6])
{
    int open = 0;
    for (int f = 1; f < 6; f++)
        if (cover[f] < cover[open])
            open = f;
    if (!(cover[open] < 0.5f) || !(cover[open ^ 1] > 0.6f))
        return -1;
    int walls = 0;
    for (int f = 0; f < 6; f++) {
        if (f / 2 == open / 2)
            continue;
        if (cover[f] > 0.6f)
            walls++;
        else if (cover[f] < cover[open] + 0.25f)
            return -1; /* two sides about as open: not a room */
    }
    return walls >= 3 ? open : -1;
}

/* ---- the default light ---------------------------------------------------------------------- */

static const char *const mode_names[] = {"auto", "auto", "on", "off"};

/* A key light above, right of and in front of the bounds (the side a fitted camera looks from),
 * two bounding radii from the centre, with an intensity that gives an irradiance of about 1 at
 * the centre. Inside a room it hangs below the ceiling's middle instead, where it lights the
 * room rather than its roof. */
static struct rb_world_light default_light(const struct rb_scene_setup *s)
{
    struct rb_vec3 lo = s->bounds_min, hi = s->bounds_max;
    struct rb_vec3 c = rb_v3_scale(rb_v3_add(lo, hi), 0.5f);
    float radius = 0.5f * rb_v3_length(rb_v3_sub(hi, lo));
    if (!(radius > 0.0f))
        radius = 1.0f;
    struct rb_vec3 p;
    if (s->room_open_side != RB_SIDE_NONE) {
        p = rb_v3(c.x, lo.y + 0.8f * (hi.y - lo.y), c.z);
    } else {
        p = rb_v3_add(c, rb_v3_scale(rb_v3_normalize(rb_v3(0.5f, 1.0f, 0.8f)), 2.0f * radius));
    }
    float d = rb_v3_length(rb_v3_sub(p, c)), i = d * d;
    if (!(i > 0.0f))
        i = 1.0f;
    return (struct rb_world_light){
        .type = RB_LIGHT_POINT,
        .position = p,
        .direction = rb_v3(0, -1, 0),
        .color = {i, i, i},
    };
}

enum rb_status rb_scene_setup_init(const struct rb_job *job, const struct rb_scene *scene,
                                   const float *env_rgba, uint32_t env_width_px,
                                   uint32_t env_height_px, struct rb_scene_setup *out,
                                   struct rb_err *err)
{
    uint32_t clips[MAX_CLIPS], clip_count = 0;
    struct rb_scene_pose *pose = NULL;
    enum rb_status st = rb_scene_select_clips(scene, job, clips, MAX_CLIPS, &clip_count, err);
    if (st == RB_OK)
        st = rb_scene_pose_create(scene, &pose, err);
    if (st)
        return st;
    struct rb_scene_setup s = {0};
    animation_bounds(scene, job, clips, clip_count, pose, &s);
    /* The scene's and the job's lights, counted as the frames will gather them (s has no
     * default light yet). */
    s.punctual_count = rb_scene_world_lights(job, scene, &s, pose, NULL, 0);
    s.has_emitters = has_emitters(scene, pose);
    s.emitter_irradiance =
        s.has_emitters ? emitter_irradiance(scene, pose, s.bounds_min, s.bounds_max) : 0.0;
    s.has_environment = !env_is_black(job, env_rgba, env_width_px, env_height_px);
    float cover[6];
    face_coverage(scene, pose, s.bounds_min, s.bounds_max, cover);
    int open = open_face(cover);
    rb_log(RB_LOG_DEBUG,
           "bounds (%g, %g, %g) to (%g, %g, %g); wall on their faces: -X %.2f, +X %.2f, "
           "-Y %.2f, +Y %.2f, -Z %.2f, +Z %.2f",
           s.bounds_min.x, s.bounds_min.y, s.bounds_min.z, s.bounds_max.x, s.bounds_max.y,
           s.bounds_max.z, cover[0], cover[1], cover[2], cover[3], cover[4], cover[5]);
    rb_scene_pose_destroy(pose);

    static const float axes[6][3] = {{-1, 0, 0}, {1, 0, 0},  {0, -1, 0},
                                     {0, 1, 0},  {0, 0, -1}, {0, 0, 1}};
    s.room_open_side = open >= 0 ? (enum rb_scene_side)(RB_SIDE_NEG_X + open) : RB_SIDE_NONE;
    s.fit_direction = open >= 0 ? rb_v3(axes[open][0], axes[open][1], axes[open][2])
                                : rb_v3_normalize(rb_v3(0, 0.35f, 1));
    if (open >= 0)
        rb_log(RB_LOG_DEBUG, "the scene is a room open on its %c%c side", open & 1 ? '+' : '-',
               "XYZ"[open / 2]);

    enum rb_default_light mode = job->default_light;
    bool weak_emitters = s.has_emitters && s.emitter_irradiance < EMITTER_IRRADIANCE_MIN;
    /* At info level where the figure decides (auto, and no other light), else at debug. */
    bool emitters_decide = mode != RB_DEFAULT_LIGHT_ON && mode != RB_DEFAULT_LIGHT_OFF &&
                           s.punctual_count == 0 && !s.has_environment;
    if (s.has_emitters)
        rb_log(emitters_decide ? RB_LOG_INFO : RB_LOG_DEBUG,
               "emissive surfaces give an irradiance of about %.3g at the centre of the bounds "
               "(the default light about 1; below %g they count as too weak to light the view)",
               s.emitter_irradiance, EMITTER_IRRADIANCE_MIN);
    s.has_default_light =
        mode == RB_DEFAULT_LIGHT_ON || (mode != RB_DEFAULT_LIGHT_OFF && s.punctual_count == 0 &&
                                        (!s.has_emitters || weak_emitters) && !s.has_environment);
    if (s.has_default_light) {
        s.default_light = default_light(&s);
        const struct rb_world_light *l = &s.default_light;
        snprintf(s.default_light_note, sizeof(s.default_light_note),
                 "point light at (%g, %g, %g), intensity %g", l->position.x, l->position.y,
                 l->position.z, l->color[0]);
        /* Adding a light to a scene that has its own is a surprise worth a line at the
         * default log level; the other cases are what the job asked for or had no choice. */
        if (weak_emitters && mode != RB_DEFAULT_LIGHT_ON)
            rb_log(RB_LOG_WARN,
                   "default light (default_light: auto, the scene's emissive surfaces are too "
                   "weak to light the view: irradiance %.3g at its centre, below %g): %s",
                   s.emitter_irradiance, EMITTER_IRRADIANCE_MIN, s.default_light_note);
        else
            rb_log(RB_LOG_INFO, "default light (default_light: %s%s): %s", mode_names[mode],
                   mode == RB_DEFAULT_LIGHT_ON ? "" : ", the frame would be unlit without it",
                   s.default_light_note);
    } else {
        rb_strlcpy(s.default_light_note, "none", sizeof(s.default_light_note));
    }
    uint64_t h = rb_hash_bulk(&job->hash, sizeof(job->hash), RB_HASH_SEED);
    h = rb_hash_bulk(&scene->content_hash, sizeof(scene->content_hash), h);
    if (env_rgba)
        h = rb_hash_bulk(env_rgba, (size_t)env_width_px * env_height_px * 4 * sizeof(float), h);
    s.job_hash = h;
    *out = s;
    return RB_OK;
}
