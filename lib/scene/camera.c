/* The camera at a time: a glTF camera node, the job's keyframe track, or a view fitted to the
 * job's bounds (struct rb_scene_setup: every pose of the animation, so neither the fitted view
 * nor the clip planes move with the animated bounds). Clip planes not given by the job or the
 * file come from those bounds. */
#include "scene/scene_int.h"

#include <math.h>

#define NONE RB_SCENE_NONE
#define DEFAULT_FOV_DEG 40.0f

static float job_fov_rad(const struct rb_job *job)
{
    float deg = job->camera.fov_y_deg > 0.0f ? job->camera.fov_y_deg : DEFAULT_FOV_DEG;
    return deg * RB_PI / 180.0f;
}

/* Clip planes from the bounds as seen from eye: near halfway to the bounding sphere (at least
 * 1e-4 of the diagonal and 1e-3 of the distance to the center), far 1.5 times the distance to
 * the farthest box corner. The job's near_m/far_m, when non-zero, win. */
static void clip_planes(const struct rb_job *job, const struct rb_scene_setup *setup,
                        struct rb_vec3 eye, float file_near, float file_far, struct rb_camera *out)
{
    struct rb_vec3 lo = setup->bounds_min, hi = setup->bounds_max;
    struct rb_vec3 c = rb_v3_scale(rb_v3_add(lo, hi), 0.5f);
    float diag = rb_v3_length(rb_v3_sub(hi, lo)), r = 0.5f * diag;
    float dc = rb_v3_length(rb_v3_sub(eye, c)), dfar = 0.0f;
    for (int i = 0; i < 8; i++) {
        struct rb_vec3 p = rb_v3(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z);
        dfar = fmaxf(dfar, rb_v3_length(rb_v3_sub(eye, p)));
    }
    float n = (dc - r) * 0.5f, floor_n = fmaxf(diag * 1e-4f, dc * 1e-3f);
    if (!(n > floor_n))
        n = floor_n;
    if (!(n > 0.0f))
        n = 1e-3f; /* empty scene seen from its own center */
    float f = fmaxf(dfar * 1.5f, n * 10.0f);
    if (file_near > 0.0f)
        n = file_near;
    if (file_far > 0.0f)
        f = file_far;
    if (job->camera.near_m > 0.0f)
        n = job->camera.near_m;
    if (job->camera.far_m > 0.0f)
        f = job->camera.far_m;
    else if (!(f > n))
        f = n * 10.0f;
    out->z_near = n;
    out->z_far = f;
}

/* A glTF camera node: its world matrix without scale, inverted. The camera looks down -Z. */
static void node_camera(const struct rb_job *job, const struct rb_scene *scene,
                        const struct rb_scene_setup *setup, const struct rb_scene_pose *pose,
                        uint32_t index, struct rb_camera *out)
{
    const struct rb_mat4 *w = &pose->node_world[index];
    const struct rb_scene_camera *cam = &scene->cameras[scene->nodes[index].camera];
    struct rb_vec3 p = rb_v3(w->m[3][0], w->m[3][1], w->m[3][2]);
    struct rb_vec3 x = rb_v3_normalize(rb_v3(w->m[0][0], w->m[0][1], w->m[0][2]));
    struct rb_vec3 y = rb_v3(w->m[1][0], w->m[1][1], w->m[1][2]);
    if (!(rb_v3_length(x) > 0.5f))
        x = rb_v3(1, 0, 0);
    y = rb_v3_normalize(rb_v3_sub(y, rb_v3_scale(x, rb_v3_dot(x, y))));
    if (!(rb_v3_length(y) > 0.5f))
        y = fabsf(x.y) < 0.9f ? rb_v3_normalize(rb_v3_cross(rb_v3(0, 0, 1), x))
                              : rb_v3_normalize(rb_v3_cross(x, rb_v3(1, 0, 0)));
    struct rb_vec3 z = rb_v3_cross(x, y);
    struct rb_mat4 v = rb_mat4_identity();
    v.m[0][0] = x.x, v.m[1][0] = x.y, v.m[2][0] = x.z;
    v.m[0][1] = y.x, v.m[1][1] = y.y, v.m[2][1] = y.z;
    v.m[0][2] = z.x, v.m[1][2] = z.y, v.m[2][2] = z.z;
    v.m[3][0] = -rb_v3_dot(x, p);
    v.m[3][1] = -rb_v3_dot(y, p);
    v.m[3][2] = -rb_v3_dot(z, p);
    out->world_to_camera = v;
    out->position = p;
    if (cam->is_perspective) {
        out->fov_y_rad = cam->yfov_rad;
    } else {
        char what[160];
        rb_log(RB_LOG_WARN, "%s is orthographic; rendered as a perspective camera",
               rb_scene_label(what, sizeof(what), "camera", cam->name, scene->nodes[index].camera));
        out->fov_y_rad = job_fov_rad(job);
    }
    clip_planes(job, setup, p, cam->is_perspective ? cam->znear : 0.0f,
                cam->is_perspective ? cam->zfar : 0.0f, out);
}

static struct rb_vec3 v3a(const float *f)
{
    return rb_v3(f[0], f[1], f[2]);
}

/* Hermite segment between p1 (time t1) and p2 (t2) with Catmull-Rom tangents taken in time:
 * m = (next - prev) / (t_next - t_prev). With evenly spaced keys this is the uniform
 * Catmull-Rom spline; with uneven spacing it stays C1 in time. */
static struct rb_vec3 catmull_rom(struct rb_vec3 p0, double t0, struct rb_vec3 p1, double t1,
                                  struct rb_vec3 p2, double t2, struct rb_vec3 p3, double t3,
                                  float u)
{
    float dt = (float)(t2 - t1);
    struct rb_vec3 m1 =
        t2 > t0 ? rb_v3_scale(rb_v3_sub(p2, p0), (float)(1.0 / (t2 - t0))) : rb_v3(0, 0, 0);
    struct rb_vec3 m2 =
        t3 > t1 ? rb_v3_scale(rb_v3_sub(p3, p1), (float)(1.0 / (t3 - t1))) : rb_v3(0, 0, 0);
    float u2 = u * u, u3 = u2 * u;
    float h00 = 2 * u3 - 3 * u2 + 1, h10 = u3 - 2 * u2 + u, h01 = -2 * u3 + 3 * u2;
    float h11 = u3 - u2;
    struct rb_vec3 r = rb_v3_add(rb_v3_scale(p1, h00), rb_v3_scale(p2, h01));
    r = rb_v3_add(r, rb_v3_scale(m1, h10 * dt));
    return rb_v3_add(r, rb_v3_scale(m2, h11 * dt));
}

/* The job's keyframe track, clamped at both ends; the end keys act as their own phantom
 * neighbours (one key interval beyond the end). */
static void key_camera(const struct rb_job *job, const struct rb_scene_setup *setup, double time_s,
                       struct rb_camera *out)
{
    const struct rb_job_camera_key *k = job->camera.keys;
    size_t n = job->camera.key_count, i = 0;
    float u = 0.0f;
    if (n > 1 && time_s > k[0].t_s) {
        if (time_s >= k[n - 1].t_s) {
            i = n - 1;
        } else {
            while (i + 2 < n && k[i + 1].t_s <= time_s)
                i++;
            double dt = k[i + 1].t_s - k[i].t_s;
            u = dt > 0.0 ? (float)((time_s - k[i].t_s) / dt) : 0.0f;
        }
    }
    float fov_default = job_fov_rad(job);
    struct rb_vec3 eye = v3a(k[i].position), at = v3a(k[i].look_at);
    float fov = k[i].fov_y_deg > 0.0f ? k[i].fov_y_deg * RB_PI / 180.0f : fov_default;
    if (u > 0.0f && i + 1 < n) {
        const struct rb_job_camera_key *a = &k[i], *b = &k[i + 1];
        float fb = b->fov_y_deg > 0.0f ? b->fov_y_deg * RB_PI / 180.0f : fov_default;
        fov += (fb - fov) * u;
        if (job->camera.interpolation == RB_INTERP_LINEAR) {
            eye = rb_v3_lerp(eye, v3a(b->position), u);
            at = rb_v3_lerp(at, v3a(b->look_at), u);
        } else {
            double dt = b->t_s - a->t_s;
            const struct rb_job_camera_key *p = i > 0 ? &k[i - 1] : a;
            const struct rb_job_camera_key *q = i + 2 < n ? &k[i + 2] : b;
            double tp = i > 0 ? p->t_s : a->t_s - dt, tq = i + 2 < n ? q->t_s : b->t_s + dt;
            eye = catmull_rom(v3a(p->position), tp, v3a(a->position), a->t_s, v3a(b->position),
                              b->t_s, v3a(q->position), tq, u);
            at = catmull_rom(v3a(p->look_at), tp, v3a(a->look_at), a->t_s, v3a(b->look_at), b->t_s,
                             v3a(q->look_at), tq, u);
        }
    }
    if (!(rb_v3_length(rb_v3_sub(at, eye)) > 1e-12f))
        at = rb_v3_add(eye, rb_v3(0, 0, -1)); /* no direction: look down -Z */
    out->world_to_camera = rb_mat4_look_at(eye, at, rb_v3(0, 1, 0));
    out->position = eye;
    out->fov_y_rad = fov;
    clip_planes(job, setup, eye, 0.0f, 0.0f, out);
}

/* Looks at the bounds' centre from setup->fit_direction. Into a room open on one side, the eye
 * sits level with the centre, out in front of the opening, far enough that the opening fills
 * the view (the back wall in the middle); otherwise (direction (0, 0.35, 1)) far enough that
 * the bounding sphere fits the narrower of the vertical and horizontal fov, plus 10%. */
static void fit_camera(const struct rb_job *job, const struct rb_scene_setup *setup,
                       struct rb_camera *out)
{
    struct rb_vec3 lo = setup->bounds_min, hi = setup->bounds_max;
    struct rb_vec3 c = rb_v3_scale(rb_v3_add(lo, hi), 0.5f);
    float r = 0.5f * rb_v3_length(rb_v3_sub(hi, lo));
    if (!(r > 0.0f) || !isfinite(r))
        r = 1.0f;
    float fov = job_fov_rad(job);
    float aspect = job->width_px && job->height_px ? (float)job->width_px / job->height_px : 1.0f;
    float tan_y = tanf(0.5f * fov), tan_x = tan_y * aspect;
    struct rb_vec3 dir = setup->fit_direction;
    if (!(rb_v3_length(dir) > 0.5f))
        dir = rb_v3_normalize(rb_v3(0, 0.35f, 1));
    float d;
    struct rb_vec3 up = rb_v3(0, 1, 0);
    if (setup->room_open_side != RB_SIDE_NONE) {
        /* The opening's half extents across the view (up is +Y unless looking along Y). */
        int a = (int)(setup->room_open_side - RB_SIDE_NEG_X) / 2;
        float ext[3] = {hi.x - lo.x, hi.y - lo.y, hi.z - lo.z};
        if (a == 1)
            up = rb_v3(0, 0, -1);
        int vert = a == 1 ? 2 : 1, horiz = a == 0 ? 2 : 0;
        float half_depth = 0.5f * ext[a];
        d = half_depth + fmaxf(0.5f * ext[vert] / tan_y, 0.5f * ext[horiz] / tan_x) * 1.05f;
    } else {
        float fit = aspect < 1.0f ? 2.0f * atanf(tan_x) : fov;
        d = r / sinf(0.5f * fit) * 1.1f;
    }
    struct rb_vec3 eye = rb_v3_add(c, rb_v3_scale(dir, d));
    out->world_to_camera = rb_mat4_look_at(eye, c, up);
    out->position = eye;
    out->fov_y_rad = fov;
    clip_planes(job, setup, eye, 0.0f, 0.0f, out);
}

enum rb_status rb_camera_evaluate(const struct rb_job *job, const struct rb_scene *scene,
                                  const struct rb_scene_setup *setup,
                                  const struct rb_scene_pose *pose, double time_s,
                                  struct rb_camera *out, struct rb_err *err)
{
    if (job->camera.node) {
        uint32_t i = rb_scene_find_node(scene, job->camera.node);
        if (i == NONE)
            return rb_errf(err, RB_E_INVALID, "%s%scamera node '%s' not found in the scene",
                           RB_JOB_AT(job->at.camera_node), job->camera.node);
        if (scene->nodes[i].camera == NONE || scene->nodes[i].camera >= scene->camera_count)
            return rb_errf(err, RB_E_INVALID, "%s%scamera node '%s' has no camera",
                           RB_JOB_AT(job->at.camera_node), job->camera.node);
        node_camera(job, scene, setup, pose, i, out);
        return RB_OK;
    }
    if (job->camera.key_count && job->camera.keys) {
        key_camera(job, setup, time_s, out);
        return RB_OK;
    }
    for (uint32_t i = 0; i < scene->node_count; i++)
        if (scene->nodes[i].in_scene && scene->nodes[i].camera < scene->camera_count) {
            node_camera(job, scene, setup, pose, i, out);
            return RB_OK;
        }
    fit_camera(job, setup, out);
    return RB_OK;
}
