/* Small vector, quaternion and matrix helpers (column-major, right-handed, glTF conventions). */
#include "core/core.h"

#include <math.h>

struct rb_vec3 rb_v3_add(struct rb_vec3 a, struct rb_vec3 b)
{
    return rb_v3(a.x + b.x, a.y + b.y, a.z + b.z);
}

struct rb_vec3 rb_v3_sub(struct rb_vec3 a, struct rb_vec3 b)
{
    return rb_v3(a.x - b.x, a.y - b.y, a.z - b.z);
}

struct rb_vec3 rb_v3_scale(struct rb_vec3 a, float s)
{
    return rb_v3(a.x * s, a.y * s, a.z * s);
}

struct rb_vec3 rb_v3_lerp(struct rb_vec3 a, struct rb_vec3 b, float t)
{
    return rb_v3(a.x + (b.x - a.x) * t, a.y + (b.y - a.y) * t, a.z + (b.z - a.z) * t);
}

float rb_v3_dot(struct rb_vec3 a, struct rb_vec3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

struct rb_vec3 rb_v3_cross(struct rb_vec3 a, struct rb_vec3 b)
{
    return rb_v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

float rb_v3_length(struct rb_vec3 a)
{
    return sqrtf(rb_v3_dot(a, a));
}

struct rb_vec3 rb_v3_normalize(struct rb_vec3 a)
{
    float l = rb_v3_length(a);
    return l > 0.0f ? rb_v3_scale(a, 1.0f / l) : a;
}

struct rb_vec3 rb_v3_min(struct rb_vec3 a, struct rb_vec3 b)
{
    return rb_v3(fminf(a.x, b.x), fminf(a.y, b.y), fminf(a.z, b.z));
}

struct rb_vec3 rb_v3_max(struct rb_vec3 a, struct rb_vec3 b)
{
    return rb_v3(fmaxf(a.x, b.x), fmaxf(a.y, b.y), fmaxf(a.z, b.z));
}

struct rb_quat rb_quat_identity(void)
{
    return (struct rb_quat){0, 0, 0, 1};
}

struct rb_quat rb_quat_normalize(struct rb_quat q)
{
    float l = sqrtf(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
    if (l <= 0.0f)
        return rb_quat_identity();
    return (struct rb_quat){q.x / l, q.y / l, q.z / l, q.w / l};
}

struct rb_quat rb_quat_slerp(struct rb_quat a, struct rb_quat b, float t)
{
    float d = a.x * b.x + a.y * b.y + a.z * b.z + a.w * b.w;
    if (d < 0.0f) { /* shortest arc */
        d = -d;
        b = (struct rb_quat){-b.x, -b.y, -b.z, -b.w};
    }
    float wa, wb;
    if (d > 0.9995f) {
        wa = 1.0f - t;
        wb = t;
    } else {
        float th = acosf(d), s = sinf(th);
        wa = sinf((1.0f - t) * th) / s;
        wb = sinf(t * th) / s;
    }
    struct rb_quat r = {wa * a.x + wb * b.x, wa * a.y + wb * b.y, wa * a.z + wb * b.z,
                        wa * a.w + wb * b.w};
    return rb_quat_normalize(r);
}

struct rb_quat rb_quat_mul(struct rb_quat a, struct rb_quat b)
{
    return (struct rb_quat){
        a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
        a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
        a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w,
        a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z,
    };
}

struct rb_vec3 rb_quat_rotate(struct rb_quat q, struct rb_vec3 v)
{
    struct rb_vec3 u = rb_v3(q.x, q.y, q.z);
    struct rb_vec3 t = rb_v3_scale(rb_v3_cross(u, v), 2.0f);
    return rb_v3_add(rb_v3_add(v, rb_v3_scale(t, q.w)), rb_v3_cross(u, t));
}

struct rb_mat4 rb_mat4_identity(void)
{
    struct rb_mat4 r = {{{0}}};
    for (int i = 0; i < 4; i++)
        r.m[i][i] = 1.0f;
    return r;
}

struct rb_mat4 rb_mat4_mul(const struct rb_mat4 *a, const struct rb_mat4 *b)
{
    struct rb_mat4 r;
    for (int c = 0; c < 4; c++)
        for (int row = 0; row < 4; row++) {
            float s = 0.0f;
            for (int k = 0; k < 4; k++)
                s += a->m[k][row] * b->m[c][k];
            r.m[c][row] = s;
        }
    return r;
}

struct rb_mat4 rb_mat4_trs(struct rb_vec3 t, struct rb_quat q, struct rb_vec3 s)
{
    q = rb_quat_normalize(q);
    float x = q.x, y = q.y, z = q.z, w = q.w;
    struct rb_mat4 r = rb_mat4_identity();
    r.m[0][0] = (1 - 2 * (y * y + z * z)) * s.x;
    r.m[0][1] = (2 * (x * y + z * w)) * s.x;
    r.m[0][2] = (2 * (x * z - y * w)) * s.x;
    r.m[1][0] = (2 * (x * y - z * w)) * s.y;
    r.m[1][1] = (1 - 2 * (x * x + z * z)) * s.y;
    r.m[1][2] = (2 * (y * z + x * w)) * s.y;
    r.m[2][0] = (2 * (x * z + y * w)) * s.z;
    r.m[2][1] = (2 * (y * z - x * w)) * s.z;
    r.m[2][2] = (1 - 2 * (x * x + y * y)) * s.z;
    r.m[3][0] = t.x;
    r.m[3][1] = t.y;
    r.m[3][2] = t.z;
    return r;
}

struct rb_mat4 rb_mat4_transpose(const struct rb_mat4 *a)
{
    struct rb_mat4 r;
    for (int c = 0; c < 4; c++)
        for (int row = 0; row < 4; row++)
            r.m[c][row] = a->m[row][c];
    return r;
}

struct rb_mat4 rb_mat4_inverse(const struct rb_mat4 *a, bool *ok)
{
    /* Gauss-Jordan with partial pivoting, in double for stability. */
    double m[4][8];
    for (int r = 0; r < 4; r++)
        for (int c = 0; c < 4; c++) {
            m[r][c] = a->m[c][r];
            m[r][c + 4] = r == c;
        }
    for (int c = 0; c < 4; c++) {
        int p = c;
        for (int r = c + 1; r < 4; r++)
            if (fabs(m[r][c]) > fabs(m[p][c]))
                p = r;
        if (fabs(m[p][c]) < 1e-30) {
            if (ok)
                *ok = false;
            return rb_mat4_identity();
        }
        if (p != c)
            for (int k = 0; k < 8; k++) {
                double t = m[c][k];
                m[c][k] = m[p][k];
                m[p][k] = t;
            }
        double inv = 1.0 / m[c][c];
        for (int k = 0; k < 8; k++)
            m[c][k] *= inv;
        for (int r = 0; r < 4; r++)
            if (r != c) {
                double f = m[r][c];
                for (int k = 0; k < 8; k++)
                    m[r][k] -= f * m[c][k];
            }
    }
    struct rb_mat4 out;
    for (int r = 0; r < 4; r++)
        for (int c = 0; c < 4; c++)
            out.m[c][r] = (float)m[r][c + 4];
    if (ok)
        *ok = true;
    return out;
}

struct rb_vec3 rb_mat4_point(const struct rb_mat4 *a, struct rb_vec3 p)
{
    return rb_v3(a->m[0][0] * p.x + a->m[1][0] * p.y + a->m[2][0] * p.z + a->m[3][0],
                 a->m[0][1] * p.x + a->m[1][1] * p.y + a->m[2][1] * p.z + a->m[3][1],
                 a->m[0][2] * p.x + a->m[1][2] * p.y + a->m[2][2] * p.z + a->m[3][2]);
}

struct rb_vec3 rb_mat4_dir(const struct rb_mat4 *a, struct rb_vec3 d)
{
    return rb_v3(a->m[0][0] * d.x + a->m[1][0] * d.y + a->m[2][0] * d.z,
                 a->m[0][1] * d.x + a->m[1][1] * d.y + a->m[2][1] * d.z,
                 a->m[0][2] * d.x + a->m[1][2] * d.y + a->m[2][2] * d.z);
}

struct rb_vec4 rb_mat4_vec4(const struct rb_mat4 *a, struct rb_vec4 v)
{
    float in[4] = {v.x, v.y, v.z, v.w}, o[4];
    for (int r = 0; r < 4; r++)
        o[r] = a->m[0][r] * in[0] + a->m[1][r] * in[1] + a->m[2][r] * in[2] + a->m[3][r] * in[3];
    return (struct rb_vec4){o[0], o[1], o[2], o[3]};
}

struct rb_mat4 rb_mat4_look_at(struct rb_vec3 eye, struct rb_vec3 target, struct rb_vec3 up)
{
    struct rb_vec3 f = rb_v3_normalize(rb_v3_sub(target, eye));
    if (fabsf(rb_v3_dot(f, rb_v3_normalize(up))) > 0.9999f)
        up = fabsf(f.y) < 0.9f ? rb_v3(0, 1, 0) : rb_v3(0, 0, 1);
    struct rb_vec3 s = rb_v3_normalize(rb_v3_cross(f, up));
    struct rb_vec3 u = rb_v3_cross(s, f);
    struct rb_mat4 r = rb_mat4_identity();
    r.m[0][0] = s.x;
    r.m[1][0] = s.y;
    r.m[2][0] = s.z;
    r.m[0][1] = u.x;
    r.m[1][1] = u.y;
    r.m[2][1] = u.z;
    r.m[0][2] = -f.x;
    r.m[1][2] = -f.y;
    r.m[2][2] = -f.z;
    r.m[3][0] = -rb_v3_dot(s, eye);
    r.m[3][1] = -rb_v3_dot(u, eye);
    r.m[3][2] = rb_v3_dot(f, eye);
    return r;
}

struct rb_mat4 rb_mat4_perspective(float fov_y_rad, float aspect, float n, float f)
{
    float t = 1.0f / tanf(fov_y_rad * 0.5f);
    struct rb_mat4 r = {{{0}}};
    r.m[0][0] = t / aspect;
    r.m[1][1] = -t; /* Vulkan NDC has +y down: flip so +Y in view space is up in the image */
    r.m[2][2] = f / (n - f);
    r.m[2][3] = -1.0f;
    r.m[3][2] = n * f / (n - f);
    return r;
}

struct rb_mat4 rb_mat4_ortho(float l, float rt, float b, float t, float n, float f)
{
    struct rb_mat4 r = rb_mat4_identity();
    r.m[0][0] = 2.0f / (rt - l);
    r.m[3][0] = -(rt + l) / (rt - l);
    r.m[1][1] = -2.0f / (t - b);
    r.m[3][1] = (t + b) / (t - b);
    r.m[2][2] = -1.0f / (f - n);
    r.m[3][2] = -n / (f - n);
    return r;
}
