/* Surfaces for the reference: a triangle hit turned into what shaders/gbuffer.frag writes to the
 * G-buffer (shading and geometric normals, diffuse albedo, F0, F90, roughness, emission), with
 * textures sampled bilinearly at their own resolution (repeat wrapping, no mipmaps; sRGB texels
 * decoded before filtering, as the GPU's sRGB formats do). */
#include "reference/reference_int.h"

#include <math.h>

/* Bilinear lookup of texture t at uv; srgb decodes the colour channels (never alpha). */
static void tex_sample(const struct rb_ref_world *w, uint32_t index, const float uv[2], bool srgb,
                       float out[4])
{
    const struct rb_scene_texture *t = &w->scene->textures[index];
    if (!t->rgba8 || t->width_px == 0 || t->height_px == 0) {
        out[0] = out[1] = out[2] = out[3] = 1.0f;
        return;
    }
    float tw = (float)t->width_px, th = (float)t->height_px;
    float x = uv[0] * tw - 0.5f, y = uv[1] * th - 0.5f;
    if (!isfinite(x) || !isfinite(y))
        x = y = 0.0f;
    /* wrap into [0, size) first, so the integer parts stay small */
    x -= tw * floorf(x / tw);
    y -= th * floorf(y / th);
    float fx = floorf(x), fy = floorf(y);
    float ax = x - fx, ay = y - fy;
    uint32_t x0 = (uint32_t)fx % t->width_px, y0 = (uint32_t)fy % t->height_px;
    uint32_t x1 = (x0 + 1) % t->width_px, y1 = (y0 + 1) % t->height_px;
    const uint8_t *p[4] = {
        t->rgba8 + ((size_t)y0 * t->width_px + x0) * 4,
        t->rgba8 + ((size_t)y0 * t->width_px + x1) * 4,
        t->rgba8 + ((size_t)y1 * t->width_px + x0) * 4,
        t->rgba8 + ((size_t)y1 * t->width_px + x1) * 4,
    };
    for (int c = 0; c < 4; c++) {
        float v[4];
        for (int k = 0; k < 4; k++)
            v[k] = srgb && c < 3 ? w->srgb_lut[p[k][c]] : (float)p[k][c] * (1.0f / 255.0f);
        float top = v[0] + (v[1] - v[0]) * ax;
        float bot = v[2] + (v[3] - v[2]) * ax;
        out[c] = top + (bot - top) * ay;
    }
}

static void interp_uv(const struct rb_ref_world *w, const uint32_t *tri, float b0, float b1,
                      float b2, float uv[2])
{
    for (int c = 0; c < 2; c++)
        uv[c] =
            b0 * w->uv[tri[0] * 2 + c] + b1 * w->uv[tri[1] * 2 + c] + b2 * w->uv[tri[2] * 2 + c];
}

void rb_ref_hit_point(const struct rb_ref_world *w, uint32_t prim, float u, float v, float out[3])
{
    const uint32_t *tri = &w->tris[(size_t)prim * 3];
    float b0 = 1.0f - u - v;
    for (int c = 0; c < 3; c++)
        out[c] =
            b0 * w->pos[tri[0] * 4 + c] + u * w->pos[tri[1] * 4 + c] + v * w->pos[tri[2] * 4 + c];
}

float rb_ref_alpha(const struct rb_ref_world *w, uint32_t prim, float u, float v)
{
    const struct rb_scene_material *m = &w->scene->materials[w->tri_material[prim]];
    float a = m->base_color[3];
    if (m->base_color_tex != RB_SCENE_NONE && m->base_color_tex < w->scene->texture_count) {
        float uv[2], texel[4];
        interp_uv(w, &w->tris[(size_t)prim * 3], 1.0f - u - v, u, v, uv);
        tex_sample(w, m->base_color_tex, uv, true, texel);
        a *= texel[3];
    }
    return a;
}

void rb_ref_emission(const struct rb_ref_world *w, uint32_t prim, float u, float v, float out[3])
{
    const struct rb_scene_material *m = &w->scene->materials[w->tri_material[prim]];
    for (int c = 0; c < 3; c++)
        out[c] = m->emissive[c];
    if (m->emissive_tex != RB_SCENE_NONE && m->emissive_tex < w->scene->texture_count &&
        (out[0] > 0.0f || out[1] > 0.0f || out[2] > 0.0f)) {
        float uv[2], texel[4];
        interp_uv(w, &w->tris[(size_t)prim * 3], 1.0f - u - v, u, v, uv);
        tex_sample(w, m->emissive_tex, uv, true, texel);
        for (int c = 0; c < 3; c++)
            out[c] *= texel[c];
    }
}

static bool normalize3(float v[3])
{
    float len = sqrtf(rb_f3_dot(v, v));
    if (!(len > 0.0f))
        return false;
    v[0] /= len;
    v[1] /= len;
    v[2] /= len;
    return true;
}

static bool has_tex(const struct rb_ref_world *w, uint32_t index)
{
    return index != RB_SCENE_NONE && index < w->scene->texture_count;
}

void rb_ref_surface_eval(const struct rb_ref_world *w, uint32_t prim, float u, float v,
                         const float dir[3], struct rb_ref_surface *s)
{
    const uint32_t *tri = &w->tris[(size_t)prim * 3];
    const struct rb_scene_material *m = &w->scene->materials[w->tri_material[prim]];
    float b0 = 1.0f - u - v;
    float nrm[3], tan[4], uv[2];
    for (int c = 0; c < 3; c++) {
        s->p[c] =
            b0 * w->pos[tri[0] * 4 + c] + u * w->pos[tri[1] * 4 + c] + v * w->pos[tri[2] * 4 + c];
        nrm[c] =
            b0 * w->nrm[tri[0] * 3 + c] + u * w->nrm[tri[1] * 3 + c] + v * w->nrm[tri[2] * 3 + c];
    }
    for (int c = 0; c < 4; c++)
        tan[c] =
            b0 * w->tan[tri[0] * 4 + c] + u * w->tan[tri[1] * 4 + c] + v * w->tan[tri[2] * 4 + c];
    interp_uv(w, tri, b0, u, v, uv);

    float base[4] = {m->base_color[0], m->base_color[1], m->base_color[2], m->base_color[3]};
    if (has_tex(w, m->base_color_tex)) {
        float t[4];
        tex_sample(w, m->base_color_tex, uv, true, t);
        for (int c = 0; c < 4; c++)
            base[c] *= t[c];
    }
    float metallic = m->metallic, roughness = m->roughness;
    if (has_tex(w, m->metallic_roughness_tex)) {
        float t[4];
        tex_sample(w, m->metallic_roughness_tex, uv, false, t);
        roughness *= t[1];
        metallic *= t[2];
    }
    metallic = rb_clampf(metallic, 0.0f, 1.0f);
    roughness = rb_clampf(roughness, 0.0f, 1.0f);

    /* The face normal of the world-space winding: counter-clockwise is the front, as the
     * rasterizer's VK_FRONT_FACE_COUNTER_CLOCKWISE with the y-flipping projection. */
    const float *p0 = &w->pos[tri[0] * 4], *p1 = &w->pos[tri[1] * 4], *p2 = &w->pos[tri[2] * 4];
    float e1[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
    float e2[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
    float ng[3];
    rb_f3_cross(e1, e2, ng);
    if (!normalize3(ng)) {
        ng[0] = -dir[0];
        ng[1] = -dir[1];
        ng[2] = -dir[2];
    }
    s->is_front = rb_f3_dot(ng, dir) < 0.0f;
    if (!normalize3(nrm))
        for (int c = 0; c < 3; c++)
            nrm[c] = s->is_front ? ng[c] : -ng[c];
    if (!s->is_front)
        for (int c = 0; c < 3; c++)
            nrm[c] = -nrm[c];
    if (rb_f3_dot(ng, nrm) < 0.0f)
        for (int c = 0; c < 3; c++)
            ng[c] = -ng[c];
    if (has_tex(w, m->normal_tex)) {
        float nt = rb_f3_dot(nrm, tan);
        float t[3] = {tan[0] - nrm[0] * nt, tan[1] - nrm[1] * nt, tan[2] - nrm[2] * nt};
        if (rb_f3_dot(t, t) > 1e-12f) {
            normalize3(t);
            float b[3];
            rb_f3_cross(nrm, t, b);
            float hand = tan[3] < 0.0f ? -1.0f : 1.0f;
            float tex[4];
            tex_sample(w, m->normal_tex, uv, false, tex);
            float tn[3] = {(tex[0] * 2.0f - 1.0f) * m->normal_scale,
                           (tex[1] * 2.0f - 1.0f) * m->normal_scale, tex[2] * 2.0f - 1.0f};
            float mapped[3];
            for (int c = 0; c < 3; c++)
                mapped[c] = t[c] * tn[0] + b[c] * hand * tn[1] + nrm[c] * tn[2];
            if (normalize3(mapped))
                for (int c = 0; c < 3; c++)
                    nrm[c] = mapped[c];
        }
    }
    for (int c = 0; c < 3; c++) {
        s->n[c] = nrm[c];
        s->ng[c] = ng[c];
    }

    float spec = m->specular_factor;
    for (int c = 0; c < 3; c++) {
        float f0_dielectric = rb_ref_minf(0.04f * m->specular_color[c], 1.0f) * spec;
        s->f0[c] = f0_dielectric * (1.0f - metallic) + base[c] * metallic;
        s->c_diff[c] = base[c] * (1.0f - metallic);
    }
    s->f90 = spec * (1.0f - metallic) + metallic;
    s->roughness = roughness;
    rb_ref_emission(w, prim, u, v, s->emission);
}
