/* Loading: a glTF document (parsed by gltf_shim.cpp) validated and converted into the flat
 * arrays of struct rb_scene. Every index, byte range and count from the file is checked here;
 * errors name the glTF element. Evaluation lives in anim.c, the camera in camera.c. */
#include "scene/gltf_shim.h"
#include "scene/scene_int.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NONE RB_SCENE_NONE

/* glTF component types and tinygltf's accessor type codes. */
enum {
    CT_BYTE = 5120,
    CT_UBYTE = 5121,
    CT_SHORT = 5122,
    CT_USHORT = 5123,
    CT_UINT = 5125,
    CT_FLOAT = 5126,
};
enum {
    TYPE_VEC2 = 2,
    TYPE_VEC3 = 3,
    TYPE_VEC4 = 4,
    TYPE_MAT2 = 34,
    TYPE_MAT3 = 35,
    TYPE_MAT4 = 36,
    TYPE_SCALAR = 65,
};

/* Largest element count we accept in one accessor: far above any real scene, low enough that
 * sizes computed from it cannot overflow. */
#define MAX_ACCESSOR_COUNT ((size_t)1 << 28)

/* The vertex attributes we read, in geometry-key order. */
enum { A_POSITION, A_NORMAL, A_TANGENT, A_TEXCOORD, A_JOINTS, A_WEIGHTS, A_COUNT };
static const char *const attr_names[A_COUNT] = {"POSITION",   "NORMAL",   "TANGENT",
                                                "TEXCOORD_0", "JOINTS_0", "WEIGHTS_0"};

/* Identical geometry is converted once: MetalRoughSpheres has 123 primitives over 26 distinct
 * accessor sets. Primitives may therefore share vertex and index ranges. */
struct geom_key {
    const struct rb_gltf_primitive *gp;
    int32_t attr[A_COUNT];
    bool gen_tangents;
    uint32_t prim; /* scene primitive that holds the converted geometry */
};

struct conv {
    const struct rb_gltf_doc *doc;
    struct rb_scene *s;
    struct rb_err *err;
    bool is_lenient;   /* RB_SCENE_LOAD_LENIENT: violations are warnings */
    char prim_ptr[64]; /* JSON pointer of the primitive being converted */
    size_t vertex_cap, index_cap, morph_cap, prim_cap;
    uint32_t *image_texture; /* doc image -> scene texture, or NONE when unused */
    uint32_t *mesh_targets;  /* per doc mesh: morph target count */
    uint32_t *prim_joints;   /* per scene primitive: largest joint index + 1, 0 without skin */
    struct geom_key *keys;
    size_t key_count;
    uint32_t *table; /* open addressing into keys, NONE == empty */
    size_t table_size;
};

/* ---- small helpers ------------------------------------------------------------------------- */

const char *rb_scene_label(char *buf, size_t size, const char *kind, const char *name, size_t index)
{
    if (name && *name)
        snprintf(buf, size, "%s '%s'", kind, name);
    else
        snprintf(buf, size, "%s %zu", kind, index);
    return buf;
}

#define LABEL(buf, kind, name, index) rb_scene_label(buf, sizeof(buf), kind, name, index)

/* A value glTF 2.0 forbids, or one the renderer's float arithmetic cannot carry (msg names it by
 * its JSON pointer): an error, or with RB_SCENE_LOAD_LENIENT a warning, and the load goes on with
 * the value as read unless the caller repairs it. RB_OK when the load goes on. */
static enum rb_status violation(struct conv *c, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

static enum rb_status violation(struct conv *c, const char *fmt, ...)
{
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof(msg), fmt, ap);
    va_end(ap);
    if (!c->is_lenient)
        return rb_errf(c->err, RB_E_PARSE, "%s", msg);
    rb_log(RB_LOG_WARN, "scene '%s': %s", c->s->path, msg);
    return RB_OK;
}

/* Whether v[0..n) are all finite once converted to float; *at: the first that is not. */
static bool floats_finite(const double *v, size_t n, size_t *at)
{
    for (*at = 0; *at < n; (*at)++)
        if (!isfinite((float)v[*at]))
            return false;
    return true;
}

static bool grow(void **p, size_t *cap, size_t need, size_t elem)
{
    /* Always leave an allocation behind, even for need == 0: callers index past the current
     * count (array + count), which is undefined on a null pointer even with nothing to add. */
    if (need <= *cap && *p)
        return true;
    size_t n = *cap ? *cap : 256;
    while (n < need) {
        if (n > SIZE_MAX / 4 / elem)
            return false;
        n *= 2;
    }
    void *q = realloc(*p, n * elem);
    if (!q)
        return false;
    *p = q;
    *cap = n;
    return true;
}

static void shrink(void **p, size_t count, size_t elem)
{
    if (*p && count) {
        void *q = realloc(*p, count * elem);
        if (q)
            *p = q;
    }
}

static char *dup_name(const char *s)
{
    return rb_strdup(s ? s : "");
}

static bool valid_index(int32_t i, size_t count)
{
    return i >= 0 && (size_t)i < count;
}

static uint32_t type_components(int32_t type)
{
    switch (type) {
    case TYPE_SCALAR: return 1;
    case TYPE_VEC2: return 2;
    case TYPE_VEC3: return 3;
    case TYPE_VEC4: return 4;
    case TYPE_MAT2: return 4;
    case TYPE_MAT3: return 9;
    case TYPE_MAT4: return 16;
    }
    return 0;
}

static const char *type_name(int32_t type)
{
    switch (type) {
    case TYPE_SCALAR: return "SCALAR";
    case TYPE_VEC2: return "VEC2";
    case TYPE_VEC3: return "VEC3";
    case TYPE_VEC4: return "VEC4";
    case TYPE_MAT2: return "MAT2";
    case TYPE_MAT3: return "MAT3";
    case TYPE_MAT4: return "MAT4";
    }
    return "an unknown type";
}

static uint32_t component_size(int32_t ct)
{
    switch (ct) {
    case CT_BYTE:
    case CT_UBYTE: return 1;
    case CT_SHORT:
    case CT_USHORT: return 2;
    case CT_UINT:
    case CT_FLOAT: return 4;
    }
    return 0;
}

/* One component as a float: normalized integers map to [0,1] or [-1,1] (glTF 3.11); plain
 * integers keep their value (KHR_mesh_quantization style). */
static float read_float(const uint8_t *p, int32_t ct, bool normalized)
{
    switch (ct) {
    case CT_BYTE: {
        int8_t x;
        memcpy(&x, p, 1);
        return normalized ? fmaxf(x / 127.0f, -1.0f) : (float)x;
    }
    case CT_UBYTE: return normalized ? p[0] / 255.0f : (float)p[0];
    case CT_SHORT: {
        int16_t x;
        memcpy(&x, p, 2);
        return normalized ? fmaxf(x / 32767.0f, -1.0f) : (float)x;
    }
    case CT_USHORT: {
        uint16_t x;
        memcpy(&x, p, 2);
        return normalized ? x / 65535.0f : (float)x;
    }
    case CT_UINT: {
        uint32_t x;
        memcpy(&x, p, 4);
        return normalized ? (float)(x / 4294967295.0) : (float)x;
    }
    case CT_FLOAT: {
        float x;
        memcpy(&x, p, 4);
        return x;
    }
    }
    return 0.0f;
}

static uint32_t read_uint(const uint8_t *p, int32_t ct)
{
    switch (ct) {
    case CT_UBYTE: return p[0];
    case CT_USHORT: {
        uint16_t x;
        memcpy(&x, p, 2);
        return x;
    }
    case CT_UINT: {
        uint32_t x;
        memcpy(&x, p, 4);
        return x;
    }
    }
    return 0;
}

/* ---- accessors ----------------------------------------------------------------------------- */

/* A validated accessor: element i, component k is at base + i * stride + k * csize. */
struct acc {
    int32_t index;
    const struct rb_gltf_accessor *a;
    const uint8_t *base; /* NULL: no buffer view, all zeros */
    size_t stride, count;
    uint32_t comps, csize;
};

/* Checks that a view holds [offset, offset + size) and returns a pointer to it. */
static enum rb_status view_range(struct conv *c, int32_t view, size_t offset, size_t size,
                                 const uint8_t **out, const char *what)
{
    const struct rb_gltf_doc *d = c->doc;
    if (!valid_index(view, d->buffer_view_count))
        return rb_errf(c->err, RB_E_PARSE, "%sbuffer view %d does not exist", what, view);
    const struct rb_gltf_buffer_view *bv = &d->buffer_views[view];
    if (!valid_index(bv->buffer, d->buffer_count))
        return rb_errf(c->err, RB_E_PARSE, "buffer view %d: buffer %d does not exist", view,
                       bv->buffer);
    const struct rb_gltf_buffer *b = &d->buffers[bv->buffer];
    if (bv->byte_offset > b->size || bv->byte_length > b->size - bv->byte_offset)
        return rb_errf(c->err, RB_E_PARSE,
                       "buffer view %d: bytes %zu..%zu lie outside buffer %d (%zu bytes)", view,
                       bv->byte_offset, bv->byte_offset + bv->byte_length, bv->buffer, b->size);
    if (offset > bv->byte_length || size > bv->byte_length - offset)
        return rb_errf(c->err, RB_E_PARSE,
                       "%sbytes %zu..%zu lie outside buffer view %d (%zu bytes)", what, offset,
                       offset + size, view, bv->byte_length);
    *out = b->data + bv->byte_offset + offset;
    return RB_OK;
}

static enum rb_status acc_open(struct conv *c, int32_t index, int32_t want_type, struct acc *v)
{
    const struct rb_gltf_doc *d = c->doc;
    if (!valid_index(index, d->accessor_count))
        return rb_errf(c->err, RB_E_PARSE, "accessor %d does not exist", index);
    const struct rb_gltf_accessor *a = &d->accessors[index];
    *v = (struct acc){.index = index, .a = a, .count = a->count};
    v->comps = type_components(a->type);
    v->csize = component_size(a->component_type);
    if (!v->comps || !v->csize)
        return rb_errf(c->err, RB_E_PARSE, "accessor %d: invalid type %d or component type %d",
                       index, a->type, a->component_type);
    if (want_type && a->type != want_type)
        return rb_errf(c->err, RB_E_PARSE, "accessor %d: expected %s, found %s", index,
                       type_name(want_type), type_name(a->type));
    if (a->count > MAX_ACCESSOR_COUNT)
        return rb_errf(c->err, RB_E_PARSE, "accessor %d: count %zu is too large", index, a->count);
    size_t elem = (size_t)v->comps * v->csize;
    if (a->buffer_view < 0) {
        if (a->buffer_view != -1)
            return rb_errf(c->err, RB_E_PARSE, "accessor %d: buffer view %d does not exist", index,
                           a->buffer_view);
        v->stride = elem;
        return RB_OK;
    }
    if (!valid_index(a->buffer_view, d->buffer_view_count))
        return rb_errf(c->err, RB_E_PARSE, "accessor %d: buffer view %d does not exist", index,
                       a->buffer_view);
    size_t stride = d->buffer_views[a->buffer_view].byte_stride;
    v->stride = stride ? stride : elem;
    if (v->stride < elem && a->count > 1)
        return rb_errf(c->err, RB_E_PARSE, "accessor %d: byte stride %zu is smaller than one %s",
                       index, v->stride, type_name(a->type));
    /* The last element ends at offset + (count - 1) * stride + elem; count <= 2^28 and
     * stride < 2^32 keep this from overflowing. */
    size_t span = a->count ? (a->count - 1) * v->stride + elem : 0;
    char what[48];
    snprintf(what, sizeof(what), "accessor %d: ", index);
    return view_range(c, a->buffer_view, a->byte_offset, span, &v->base, what);
}

/* Reads the sparse part of an accessor and calls back with (element, value pointer). */
static enum rb_status sparse_open(struct conv *c, const struct acc *v, const uint8_t **idx,
                                  uint32_t *isize, const uint8_t **val, uint32_t *count)
{
    const struct rb_gltf_accessor *a = v->a;
    char what[48];
    snprintf(what, sizeof(what), "accessor %d: sparse ", v->index);
    if (a->sparse_count < 0 || (size_t)a->sparse_count > v->count)
        return rb_errf(c->err, RB_E_PARSE, "accessor %d: sparse count %d out of range", v->index,
                       a->sparse_count);
    int32_t ict = a->sparse_indices_component_type;
    if (ict != CT_UBYTE && ict != CT_USHORT && ict != CT_UINT)
        return rb_errf(c->err, RB_E_PARSE, "accessor %d: sparse indices have component type %d",
                       v->index, ict);
    *isize = component_size(ict);
    *count = (uint32_t)a->sparse_count;
    if (a->sparse_indices_offset < 0 || a->sparse_values_offset < 0)
        return rb_errf(c->err, RB_E_PARSE, "accessor %d: negative sparse byte offset", v->index);
    enum rb_status st = view_range(c, a->sparse_indices_view, (size_t)a->sparse_indices_offset,
                                   (size_t)*count * *isize, idx, what);
    if (st)
        return st;
    return view_range(c, a->sparse_values_view, (size_t)a->sparse_values_offset,
                      (size_t)*count * v->comps * v->csize, val, what);
}

/* Decodes a whole accessor (sparse values applied) into count * comps floats. use: the JSON
 * pointer of the property that refers to it, for the message when a value is not finite. */
static enum rb_status acc_floats(struct conv *c, int32_t index, int32_t want_type, const char *use,
                                 float **out, struct acc *v)
{
    enum rb_status st = acc_open(c, index, want_type, v);
    if (st)
        return st;
    float *f = calloc(v->count ? v->count * v->comps : 1, sizeof(float));
    if (!f)
        return rb_errf(c->err, RB_E_NOMEM, "accessor %d: out of memory", index);
    const struct rb_gltf_accessor *a = v->a;
    if (v->base) {
        if (a->component_type == CT_FLOAT && v->stride == (size_t)v->comps * 4) {
            memcpy(f, v->base, v->count * v->comps * 4);
        } else {
            for (size_t i = 0; i < v->count; i++) {
                const uint8_t *p = v->base + i * v->stride;
                for (uint32_t k = 0; k < v->comps; k++)
                    f[i * v->comps + k] =
                        read_float(p + k * v->csize, a->component_type, a->normalized);
            }
        }
    }
    if (a->is_sparse) {
        const uint8_t *idx, *val;
        uint32_t isize, n;
        st = sparse_open(c, v, &idx, &isize, &val, &n);
        for (uint32_t i = 0; !st && i < n; i++) {
            uint32_t e = read_uint(idx + (size_t)i * isize, a->sparse_indices_component_type);
            if (e >= v->count) {
                st = rb_errf(c->err, RB_E_PARSE, "accessor %d: sparse index %u out of range", index,
                             e);
                break;
            }
            for (uint32_t k = 0; k < v->comps; k++)
                f[(size_t)e * v->comps + k] = read_float(
                    val + ((size_t)i * v->comps + k) * v->csize, a->component_type, a->normalized);
        }
        if (st) {
            free(f);
            return st;
        }
    }
    size_t total = v->count * v->comps, bad = 0, first = 0;
    for (size_t i = 0; i < total; i++)
        if (!isfinite(f[i]) && !bad++)
            first = i;
    if (bad && (st = violation(c,
                               "%s: accessor %d: %zu of %zu values are not finite (NaN or Inf), "
                               "the first in element %zu",
                               use, index, bad, total, first / v->comps))) {
        free(f);
        return st;
    }
    *out = f;
    return RB_OK;
}

/* Decodes an unsigned-integer accessor (indices, joints) into count * comps values. */
static enum rb_status acc_uints(struct conv *c, int32_t index, int32_t want_type, uint32_t **out,
                                struct acc *v)
{
    enum rb_status st = acc_open(c, index, want_type, v);
    if (st)
        return st;
    const struct rb_gltf_accessor *a = v->a;
    int32_t ct = a->component_type;
    if ((ct != CT_UBYTE && ct != CT_USHORT && ct != CT_UINT) || a->normalized)
        return rb_errf(c->err, RB_E_PARSE,
                       "accessor %d: expected unsigned integers, found component type %d%s", index,
                       ct, a->normalized ? " (normalized)" : "");
    uint32_t *u = calloc(v->count ? v->count * v->comps : 1, sizeof(uint32_t));
    if (!u)
        return rb_errf(c->err, RB_E_NOMEM, "accessor %d: out of memory", index);
    if (v->base)
        for (size_t i = 0; i < v->count; i++) {
            const uint8_t *p = v->base + i * v->stride;
            for (uint32_t k = 0; k < v->comps; k++)
                u[i * v->comps + k] = read_uint(p + k * v->csize, ct);
        }
    if (a->is_sparse) {
        const uint8_t *idx, *val;
        uint32_t isize, n;
        st = sparse_open(c, v, &idx, &isize, &val, &n);
        for (uint32_t i = 0; !st && i < n; i++) {
            uint32_t e = read_uint(idx + (size_t)i * isize, a->sparse_indices_component_type);
            if (e >= v->count) {
                st = rb_errf(c->err, RB_E_PARSE, "accessor %d: sparse index %u out of range", index,
                             e);
                break;
            }
            for (uint32_t k = 0; k < v->comps; k++)
                u[(size_t)e * v->comps + k] =
                    read_uint(val + ((size_t)i * v->comps + k) * v->csize, ct);
        }
        if (st) {
            free(u);
            return st;
        }
    }
    *out = u;
    return RB_OK;
}

/* ---- textures and materials ---------------------------------------------------------------- */

static void mark_texture(struct conv *c, const struct rb_gltf_texture_ref *r, bool *used)
{
    if (valid_index(r->index, c->doc->texture_count))
        used[r->index] = true;
}

/* One image as RGBA8: 1 channel -> grey, 2 -> grey + alpha, 3 -> opaque RGB; 16 bits are
 * rounded to 8. */
static enum rb_status convert_image(struct conv *c, int32_t index, struct rb_scene_texture *t)
{
    const struct rb_gltf_image *im = &c->doc->images[index];
    char what[160];
    LABEL(what, "image", im->name && *im->name ? im->name : im->uri, (size_t)index);
    t->name = rb_strdup(im->name && *im->name ? im->name : im->uri && *im->uri ? im->uri : what);
    if (!t->name)
        return rb_errf(c->err, RB_E_NOMEM, "%s: out of memory", what);
    if (!im->pixels || im->width < 1 || im->height < 1)
        return rb_errf(c->err, RB_E_IO, "%s: cannot be loaded (missing file or undecodable data)",
                       what);
    int comps = im->components, bits = im->bits;
    if (comps < 1 || comps > 4 || (bits != 8 && bits != 16))
        return rb_errf(c->err, RB_E_UNSUPPORTED, "%s: %d channels of %d bits are not supported",
                       what, comps, bits);
    size_t w = (size_t)im->width, h = (size_t)im->height, bpc = (size_t)bits / 8;
    if (w > 65536 || h > 65536 || im->size < w * h * (size_t)comps * bpc)
        return rb_errf(c->err, RB_E_PARSE, "%s: %zux%zu pixel data is truncated", what, w, h);
    t->width_px = (uint32_t)w;
    t->height_px = (uint32_t)h;
    t->rgba8 = malloc(w * h * 4);
    if (!t->rgba8)
        return rb_errf(c->err, RB_E_NOMEM, "%s: out of memory", what);
    for (size_t i = 0; i < w * h; i++) {
        uint8_t ch[4];
        for (int k = 0; k < comps; k++) {
            const uint8_t *p = im->pixels + (i * (size_t)comps + (size_t)k) * bpc;
            if (bpc == 1) {
                ch[k] = p[0];
            } else {
                uint16_t x;
                memcpy(&x, p, 2);
                ch[k] = (uint8_t)(((uint32_t)x * 255u + 32767u) / 65535u);
            }
        }
        uint8_t *o = t->rgba8 + i * 4;
        switch (comps) {
        case 1: o[0] = o[1] = o[2] = ch[0], o[3] = 255; break;
        case 2: o[0] = o[1] = o[2] = ch[0], o[3] = ch[1]; break;
        case 3: o[0] = ch[0], o[1] = ch[1], o[2] = ch[2], o[3] = 255; break;
        default: memcpy(o, ch, 4); break;
        }
    }
    return RB_OK;
}

/* Converts the images that materials use (through textures) into scene textures. */
static enum rb_status convert_textures(struct conv *c)
{
    const struct rb_gltf_doc *d = c->doc;
    enum rb_status st = RB_OK;
    bool *tex_used = calloc(d->texture_count + 1, sizeof(bool));
    c->image_texture = malloc((d->image_count + 1) * sizeof(uint32_t));
    if (!tex_used || !c->image_texture) {
        st = rb_errf(c->err, RB_E_NOMEM, "out of memory");
        goto out;
    }
    for (size_t i = 0; i < d->image_count; i++)
        c->image_texture[i] = NONE;
    for (size_t i = 0; i < d->material_count; i++) {
        const struct rb_gltf_material *m = &d->materials[i];
        mark_texture(c, &m->base_color_tex, tex_used);
        mark_texture(c, &m->metallic_roughness_tex, tex_used);
        mark_texture(c, &m->normal_tex, tex_used);
        mark_texture(c, &m->emissive_tex, tex_used);
    }
    uint32_t n = 0;
    for (size_t i = 0; i < d->texture_count; i++) {
        if (!tex_used[i])
            continue;
        int32_t src = d->textures[i].source;
        if (!valid_index(src, d->image_count)) {
            char what[160];
            LABEL(what, "texture", d->textures[i].name, i);
            if (src == -1)
                st = rb_errf(c->err, RB_E_UNSUPPORTED,
                             "%s: no image source (only PNG and JPEG images are supported)", what);
            else
                st = rb_errf(c->err, RB_E_PARSE, "%s: image %d does not exist", what, src);
            goto out;
        }
        if (c->image_texture[src] == NONE)
            c->image_texture[src] = n++;
    }
    c->s->textures = calloc(n + 1, sizeof(struct rb_scene_texture));
    if (!c->s->textures) {
        st = rb_errf(c->err, RB_E_NOMEM, "out of memory");
        goto out;
    }
    c->s->texture_count = n;
    for (size_t i = 0; i < d->image_count; i++)
        if (c->image_texture[i] != NONE) {
            st = convert_image(c, (int32_t)i, &c->s->textures[c->image_texture[i]]);
            if (st)
                goto out;
        }
out:
    free(tex_used);
    return st;
}

static enum rb_status texture_index(struct conv *c, const struct rb_gltf_texture_ref *r,
                                    const char *mat, const char *slot, uint32_t *out)
{
    *out = NONE;
    if (r->index == -1)
        return RB_OK;
    if (!valid_index(r->index, c->doc->texture_count))
        return rb_errf(c->err, RB_E_PARSE, "%s: %s texture %d does not exist", mat, slot, r->index);
    if (r->tex_coord != 0)
        rb_log(RB_LOG_WARN, "%s: %s texture uses TEXCOORD_%d; only TEXCOORD_0 is supported", mat,
               slot, r->tex_coord);
    if (r->has_transform)
        rb_log(RB_LOG_WARN, "%s: %s texture: KHR_texture_transform is ignored", mat, slot);
    /* convert_textures resolved every used texture to an image that has a scene texture. */
    *out = c->image_texture[c->doc->textures[r->index].source];
    return RB_OK;
}

/* A material's factors must be finite in float, and its emission (emissiveFactor times
 * KHR_materials_emissive_strength) not negative and at most RB_MAX_RADIANCE. */
static enum rb_status check_material(struct conv *c, const struct rb_gltf_material *g, size_t i,
                                     double strength)
{
    const double scalars[] = {g->metallic, g->roughness, g->normal_scale, g->alpha_cutoff,
                              g->has_specular ? g->specular_factor : 1.0};
    static const char *const names[] = {
        "pbrMetallicRoughness/metallicFactor", "pbrMetallicRoughness/roughnessFactor",
        "normalTexture/scale", "alphaCutoff", "extensions/KHR_materials_specular/specularFactor"};
    size_t at;
    enum rb_status st = RB_OK;
    if (!floats_finite(g->base_color, 4, &at))
        st = violation(c,
                       "/materials/%zu/pbrMetallicRoughness/baseColorFactor: value %zu (%g) "
                       "is not finite in float",
                       i, at, g->base_color[at]);
    if (!st && !floats_finite(scalars, 5, &at))
        st =
            violation(c, "/materials/%zu/%s: %g is not finite in float", i, names[at], scalars[at]);
    const char *strength_name = g->has_emissive_strength
                                    ? " x extensions/KHR_materials_emissive_strength/"
                                      "emissiveStrength"
                                    : "";
    double lo = 0, hi = 0; /* the least and the most of the three products */
    for (int k = 0; k < 3; k++) {
        double e = g->emissive[k] * strength;
        lo = k ? fmin(lo, e) : e;
        hi = k ? fmax(hi, e) : e;
    }
    if (!st && lo < 0)
        st =
            violation(c, "/materials/%zu: emissiveFactor%s is negative (%g)", i, strength_name, lo);
    else if (!st && !(hi <= RB_MAX_RADIANCE))
        st = violation(c, "/materials/%zu: emissiveFactor%s is %g, more than %g", i, strength_name,
                       hi, RB_MAX_RADIANCE);
    return st;
}

static enum rb_status convert_materials(struct conv *c)
{
    const struct rb_gltf_doc *d = c->doc;
    struct rb_scene *s = c->s;
    s->materials = calloc(d->material_count + 1, sizeof(struct rb_scene_material));
    if (!s->materials)
        return rb_errf(c->err, RB_E_NOMEM, "out of memory");
    s->material_count = (uint32_t)d->material_count + 1;
    for (size_t i = 0; i < d->material_count; i++) {
        const struct rb_gltf_material *g = &d->materials[i];
        struct rb_scene_material *m = &s->materials[i];
        char what[160];
        LABEL(what, "material", g->name, i);
        m->name = dup_name(g->name);
        if (!m->name)
            return rb_errf(c->err, RB_E_NOMEM, "out of memory");
        if (g->base_color_count != 4 || g->emissive_count != 3)
            return rb_errf(c->err, RB_E_PARSE,
                           "%s: baseColorFactor needs 4 values and emissiveFactor 3", what);
        for (int k = 0; k < 4; k++)
            m->base_color[k] = (float)g->base_color[k];
        double strength = g->has_emissive_strength ? g->emissive_strength : 1.0;
        enum rb_status st = check_material(c, g, i, strength);
        if (st)
            return st;
        for (int k = 0; k < 3; k++)
            m->emissive[k] = (float)(g->emissive[k] * strength);
        m->specular_factor = g->has_specular ? (float)g->specular_factor : 1.0f;
        for (int k = 0; k < 3; k++)
            m->specular_color[k] = g->has_specular ? (float)g->specular_color[k] : 1.0f;
        if (g->has_specular_textures)
            rb_log(RB_LOG_WARN, "%s: KHR_materials_specular textures are ignored", what);
        m->metallic = (float)g->metallic;
        m->roughness = (float)g->roughness;
        m->normal_scale = (float)g->normal_scale;
        m->double_sided = g->double_sided;
        m->alpha_cutoff = (float)g->alpha_cutoff;
        if (!strcmp(g->alpha_mode, "OPAQUE")) {
            m->alpha_mode = RB_ALPHA_OPAQUE;
        } else if (!strcmp(g->alpha_mode, "MASK")) {
            m->alpha_mode = RB_ALPHA_MASK;
        } else if (!strcmp(g->alpha_mode, "BLEND")) {
            m->alpha_mode = RB_ALPHA_BLEND;
        } else {
            rb_log(RB_LOG_WARN, "%s: unknown alphaMode '%s'; treated as OPAQUE", what,
                   g->alpha_mode);
            m->alpha_mode = RB_ALPHA_OPAQUE;
        }
        st = texture_index(c, &g->base_color_tex, what, "baseColor", &m->base_color_tex);
        if (!st)
            st = texture_index(c, &g->metallic_roughness_tex, what, "metallicRoughness",
                               &m->metallic_roughness_tex);
        if (!st)
            st = texture_index(c, &g->normal_tex, what, "normal", &m->normal_tex);
        if (!st)
            st = texture_index(c, &g->emissive_tex, what, "emissive", &m->emissive_tex);
        if (st)
            return st;
    }
    /* The default material (glTF 3.9.6): white, dielectric, fully rough. */
    struct rb_scene_material *m = &s->materials[d->material_count];
    *m = (struct rb_scene_material){
        .name = rb_strdup("default"),
        .base_color = {1, 1, 1, 1},
        .base_color_tex = NONE,
        .metallic = 0.0f,
        .roughness = 1.0f,
        .metallic_roughness_tex = NONE,
        .normal_tex = NONE,
        .normal_scale = 1.0f,
        .emissive_tex = NONE,
        .alpha_cutoff = 0.5f,
        .specular_factor = 1.0f,
        .specular_color = {1, 1, 1},
    };
    if (!m->name)
        return rb_errf(c->err, RB_E_NOMEM, "out of memory");
    return RB_OK;
}

/* ---- geometry ------------------------------------------------------------------------------ */

static int32_t find_attr(const struct rb_gltf_attribute *a, size_t n, const char *name)
{
    for (size_t i = 0; i < n; i++)
        if (!strcmp(a[i].name, name))
            return a[i].accessor;
    return -1;
}

static struct rb_vec3 any_perpendicular(struct rb_vec3 n)
{
    struct rb_vec3 a = fabsf(n.x) < 0.9f ? rb_v3(1, 0, 0) : rb_v3(0, 1, 0);
    struct rb_vec3 t = rb_v3_normalize(rb_v3_cross(a, n));
    return rb_v3_length(t) > 0.5f ? t : rb_v3(1, 0, 0);
}

static struct rb_vec3 v3f(const float *f)
{
    return rb_v3(f[0], f[1], f[2]);
}

/* Per-triangle UV derivatives accumulated per vertex, then Gram-Schmidt against the normal
 * (Lengyel, "Computing Tangent Space Basis Vectors"). bitan: vertex_count * 3 scratch floats. */
static void generate_tangents(struct rb_scene_vertex *v, uint32_t nv, const uint32_t *idx,
                              size_t ni, float *bitan)
{
    for (uint32_t i = 0; i < nv; i++)
        memset(v[i].tangent, 0, sizeof(v[i].tangent));
    memset(bitan, 0, (size_t)nv * 3 * sizeof(float));
    for (size_t t = 0; t + 2 < ni; t += 3) {
        uint32_t i0 = idx[t], i1 = idx[t + 1], i2 = idx[t + 2];
        struct rb_vec3 e1 = rb_v3_sub(v3f(v[i1].position), v3f(v[i0].position));
        struct rb_vec3 e2 = rb_v3_sub(v3f(v[i2].position), v3f(v[i0].position));
        float du1 = v[i1].uv[0] - v[i0].uv[0], dv1 = v[i1].uv[1] - v[i0].uv[1];
        float du2 = v[i2].uv[0] - v[i0].uv[0], dv2 = v[i2].uv[1] - v[i0].uv[1];
        float det = du1 * dv2 - du2 * dv1;
        if (fabsf(det) < 1e-20f || !isfinite(det))
            continue;
        float r = 1.0f / det;
        struct rb_vec3 sd = rb_v3_scale(rb_v3_sub(rb_v3_scale(e1, dv2), rb_v3_scale(e2, dv1)), r);
        struct rb_vec3 td = rb_v3_scale(rb_v3_sub(rb_v3_scale(e2, du1), rb_v3_scale(e1, du2)), r);
        uint32_t tri[3] = {i0, i1, i2};
        for (int k = 0; k < 3; k++) {
            float *tg = v[tri[k]].tangent, *bt = bitan + (size_t)tri[k] * 3;
            tg[0] += sd.x, tg[1] += sd.y, tg[2] += sd.z;
            bt[0] += td.x, bt[1] += td.y, bt[2] += td.z;
        }
    }
    for (uint32_t i = 0; i < nv; i++) {
        struct rb_vec3 n = rb_v3_normalize(v3f(v[i].normal));
        struct rb_vec3 t = v3f(v[i].tangent);
        t = rb_v3_normalize(rb_v3_sub(t, rb_v3_scale(n, rb_v3_dot(n, t))));
        if (!(rb_v3_length(t) > 0.5f))
            t = any_perpendicular(n);
        float w = rb_v3_dot(rb_v3_cross(n, t), v3f(bitan + (size_t)i * 3)) < 0.0f ? -1.0f : 1.0f;
        v[i].tangent[0] = t.x, v[i].tangent[1] = t.y, v[i].tangent[2] = t.z;
        v[i].tangent[3] = w;
    }
}

/* Normals of length 0 (glTF 3.7.2.1 wants unit ones) are replaced, with a warning, by the
 * area-weighted normal of the triangles around them; a vertex no proper triangle uses gets +Z. */
static void repair_normals(struct conv *c, int32_t index, const char *use, const float *pos,
                           float *nrm, size_t n, const uint32_t *tri, size_t ntri)
{
    size_t bad = 0;
    for (size_t i = 0; i < n; i++)
        if (!(rb_v3_length(v3f(nrm + i * 3)) > 0.0f))
            bad++;
    if (!bad)
        return;
    rb_log(RB_LOG_WARN,
           "scene '%s': %s: accessor %d: %zu of %zu normals have length 0; each is replaced by "
           "the normal of the faces around it",
           c->s->path, use, index, bad, n);
    bool *fix = calloc(n, sizeof(bool));
    if (!fix) /* the fallback alone, without the faces */
        for (size_t i = 0; i < n; i++)
            if (!(rb_v3_length(v3f(nrm + i * 3)) > 0.0f))
                nrm[i * 3 + 2] = 1.0f;
    for (size_t i = 0; fix && i < n; i++)
        fix[i] = !(rb_v3_length(v3f(nrm + i * 3)) > 0.0f);
    for (size_t t = 0; fix && t < ntri; t++) {
        const uint32_t *k = tri + 3 * t;
        struct rb_vec3 e1 = rb_v3_sub(v3f(pos + k[1] * 3), v3f(pos + k[0] * 3));
        struct rb_vec3 e2 = rb_v3_sub(v3f(pos + k[2] * 3), v3f(pos + k[0] * 3));
        struct rb_vec3 fn = rb_v3_cross(e1, e2); /* its length is twice the area */
        for (int j = 0; j < 3; j++)
            if (fix[k[j]]) {
                float *o = nrm + k[j] * 3;
                o[0] += fn.x, o[1] += fn.y, o[2] += fn.z;
            }
    }
    for (size_t i = 0; fix && i < n; i++) {
        if (!fix[i])
            continue;
        struct rb_vec3 m = rb_v3_normalize(v3f(nrm + i * 3));
        if (!(rb_v3_length(m) > 0.5f))
            m = rb_v3(0, 0, 1);
        nrm[i * 3] = m.x, nrm[i * 3 + 1] = m.y, nrm[i * 3 + 2] = m.z;
    }
    free(fix);
}

/* Reads one vertex attribute with a count check against POSITION. use: its JSON pointer. */
static enum rb_status read_attr(struct conv *c, int32_t index, int32_t type, size_t n,
                                const char *name, const char *use, float **out)
{
    struct acc v;
    enum rb_status st = acc_floats(c, index, type, use, out, &v);
    if (st)
        return st;
    if (v.count != n) {
        free(*out);
        *out = NULL;
        return rb_errf(c->err, RB_E_PARSE, "%s has %zu elements but POSITION has %zu", name,
                       v.count, n);
    }
    return RB_OK;
}

/* Converts the geometry of one primitive (topology already known to be triangles) into the
 * scene's vertex, index and morph arrays. */
static enum rb_status convert_geometry(struct conv *c, const struct rb_gltf_primitive *gp,
                                       const int32_t *attr, bool gen_tangents, const char *what,
                                       struct rb_scene_primitive *p, uint32_t *max_joint)
{
    struct rb_scene *s = c->s;
    enum rb_status st = RB_OK;
    float *pos = NULL, *nrm = NULL, *tan = NULL, *uv = NULL, *wgt = NULL, *scratch = NULL;
    float *dpos = NULL, *dnrm = NULL;
    uint32_t *src = NULL, *tri = NULL, *jnt = NULL;
    struct acc v;
    int mode = gp->mode == -1 ? 4 : gp->mode;

    char use[A_COUNT][96];
    for (int a = 0; a < A_COUNT; a++)
        snprintf(use[a], sizeof(use[a]), "%s/attributes/%s", c->prim_ptr, attr_names[a]);
    st = acc_floats(c, attr[A_POSITION], TYPE_VEC3, use[A_POSITION], &pos, &v);
    if (st)
        goto out;
    size_t n = v.count;
    if (attr[A_NORMAL] != -1 &&
        (st = read_attr(c, attr[A_NORMAL], TYPE_VEC3, n, "NORMAL", use[A_NORMAL], &nrm)))
        goto out;
    if (attr[A_TANGENT] != -1 &&
        (st = read_attr(c, attr[A_TANGENT], TYPE_VEC4, n, "TANGENT", use[A_TANGENT], &tan)))
        goto out;
    if (attr[A_TEXCOORD] != -1 &&
        (st = read_attr(c, attr[A_TEXCOORD], TYPE_VEC2, n, "TEXCOORD_0", use[A_TEXCOORD], &uv)))
        goto out;
    if (attr[A_JOINTS] != -1 && attr[A_WEIGHTS] != -1) {
        if ((st = read_attr(c, attr[A_WEIGHTS], TYPE_VEC4, n, "WEIGHTS_0", use[A_WEIGHTS], &wgt)))
            goto out;
        if ((st = acc_uints(c, attr[A_JOINTS], TYPE_VEC4, &jnt, &v)))
            goto out;
        if (v.count != n) {
            st = rb_errf(c->err, RB_E_PARSE, "JOINTS_0 has %zu elements but POSITION has %zu",
                         v.count, n);
            goto out;
        }
    } else if (attr[A_JOINTS] != -1 || attr[A_WEIGHTS] != -1) {
        rb_log(RB_LOG_WARN, "%s: JOINTS_0 without WEIGHTS_0 (or the reverse); not skinned", what);
    }

    /* Indices, then the topology as a triangle list. */
    size_t ni = n;
    if (gp->indices != -1) {
        if ((st = acc_uints(c, gp->indices, TYPE_SCALAR, &src, &v)))
            goto out;
        ni = v.count;
        for (size_t i = 0; i < ni; i++)
            if (src[i] >= n) {
                st = rb_errf(c->err, RB_E_PARSE, "index %u out of range (%zu vertices)", src[i], n);
                goto out;
            }
    }
    size_t ntri = mode == 4 ? ni / 3 : (ni >= 3 ? ni - 2 : 0);
    if (mode == 4 && ni % 3)
        rb_log(RB_LOG_WARN, "%s: %zu indices is not a multiple of 3; the rest is ignored", what,
               ni);
    size_t nt = ntri * 3;
    if (nt > UINT32_MAX - s->index_count || n > UINT32_MAX - s->vertex_count ||
        nt > UINT32_MAX - s->vertex_count) {
        st = rb_errf(c->err, RB_E_UNSUPPORTED, "more than 2^32 vertices or indices in all");
        goto out;
    }
    tri = malloc((nt ? nt : 1) * sizeof(uint32_t));
    if (!tri) {
        st = rb_errf(c->err, RB_E_NOMEM, "out of memory");
        goto out;
    }
    for (size_t t = 0; t < ntri; t++) {
        size_t a, b, cc;
        if (mode == 4) { /* glTF 3.7.2.1: list, strip, fan */
            a = 3 * t, b = 3 * t + 1, cc = 3 * t + 2;
        } else if (mode == 5) {
            a = t, b = t + 1 + t % 2, cc = t + 2 - t % 2;
        } else {
            a = t + 1, b = t + 2, cc = 0;
        }
        tri[3 * t] = src ? src[a] : (uint32_t)a;
        tri[3 * t + 1] = src ? src[b] : (uint32_t)b;
        tri[3 * t + 2] = src ? src[cc] : (uint32_t)cc;
    }

    if (nrm)
        repair_normals(c, attr[A_NORMAL], use[A_NORMAL], pos, nrm, n, tri, ntri);

    /* Without normals every triangle gets its own three vertices and a flat normal. */
    bool flat = nrm == NULL;
    size_t nv = flat ? nt : n;
    if (!grow((void **)&s->vertices, &c->vertex_cap, s->vertex_count + nv,
              sizeof(struct rb_scene_vertex)) ||
        !grow((void **)&s->indices, &c->index_cap, s->index_count + nt, sizeof(uint32_t))) {
        st = rb_errf(c->err, RB_E_NOMEM, "out of memory");
        goto out;
    }
    struct rb_scene_vertex *out = s->vertices + s->vertex_count;
    uint32_t mj = 0;
    for (size_t i = 0; i < nv; i++) {
        size_t k = flat ? tri[i] : i;
        struct rb_scene_vertex *o = &out[i];
        memset(o, 0, sizeof(*o));
        memcpy(o->position, pos + k * 3, 3 * sizeof(float));
        if (nrm)
            memcpy(o->normal, nrm + k * 3, 3 * sizeof(float));
        if (tan)
            memcpy(o->tangent, tan + k * 4, 4 * sizeof(float));
        if (uv)
            memcpy(o->uv, uv + k * 2, 2 * sizeof(float));
        if (jnt) {
            for (int j = 0; j < 4; j++) {
                o->joints[j] = jnt[k * 4 + j];
                o->weights[j] = wgt[k * 4 + j];
                if (o->weights[j] != 0.0f && o->joints[j] + 1 > mj)
                    mj = o->joints[j] + 1;
            }
        }
    }
    uint32_t *oi = s->indices + s->index_count;
    for (size_t i = 0; i < nt; i++)
        oi[i] = flat ? (uint32_t)i : tri[i];
    if (flat)
        for (size_t t = 0; t < ntri; t++) {
            struct rb_scene_vertex *a = &out[3 * t];
            struct rb_vec3 e1 = rb_v3_sub(v3f(a[1].position), v3f(a[0].position));
            struct rb_vec3 e2 = rb_v3_sub(v3f(a[2].position), v3f(a[0].position));
            struct rb_vec3 fn = rb_v3_normalize(rb_v3_cross(e1, e2));
            if (!(rb_v3_length(fn) > 0.5f))
                fn = rb_v3(0, 0, 1); /* degenerate triangle */
            for (int k = 0; k < 3; k++)
                a[k].normal[0] = fn.x, a[k].normal[1] = fn.y, a[k].normal[2] = fn.z;
        }
    if (!tan) {
        if (gen_tangents && uv) {
            scratch = malloc((nv ? nv : 1) * 3 * sizeof(float));
            if (!scratch) {
                st = rb_errf(c->err, RB_E_NOMEM, "out of memory");
                goto out;
            }
            generate_tangents(out, (uint32_t)nv, oi, nt, scratch);
        } else {
            /* Unused by the shading without a normal map, but always a valid frame. */
            if (gen_tangents)
                rb_log(RB_LOG_WARN, "%s: normal map without TEXCOORD_0; tangents are arbitrary",
                       what);
            for (size_t i = 0; i < nv; i++) {
                struct rb_vec3 t = any_perpendicular(rb_v3_normalize(v3f(out[i].normal)));
                out[i].tangent[0] = t.x, out[i].tangent[1] = t.y, out[i].tangent[2] = t.z;
                out[i].tangent[3] = 1.0f;
            }
        }
    }

    /* Morph targets: POSITION and NORMAL deltas (TANGENT deltas are ignored). */
    size_t nm = gp->target_count;
    if (nm && nv > (UINT32_MAX - s->morph_delta_count) / nm) {
        st = rb_errf(c->err, RB_E_UNSUPPORTED, "too many morph target deltas");
        goto out;
    }
    if (!grow((void **)&s->morph_deltas, &c->morph_cap, s->morph_delta_count + nm * nv,
              sizeof(struct rb_scene_morph_delta))) {
        st = rb_errf(c->err, RB_E_NOMEM, "out of memory");
        goto out;
    }
    struct rb_scene_morph_delta *md = s->morph_deltas + s->morph_delta_count;
    for (size_t t = 0; t < nm; t++) {
        const struct rb_gltf_target *tg = &gp->targets[t];
        int32_t ap = find_attr(tg->attributes, tg->attribute_count, "POSITION");
        int32_t an = find_attr(tg->attributes, tg->attribute_count, "NORMAL");
        char tuse[2][128];
        snprintf(tuse[0], sizeof(tuse[0]), "%s/targets/%zu/POSITION", c->prim_ptr, t);
        snprintf(tuse[1], sizeof(tuse[1]), "%s/targets/%zu/NORMAL", c->prim_ptr, t);
        if (ap != -1 && (st = read_attr(c, ap, TYPE_VEC3, n, "target POSITION", tuse[0], &dpos)))
            goto target_fail;
        if (an != -1 && (st = read_attr(c, an, TYPE_VEC3, n, "target NORMAL", tuse[1], &dnrm)))
            goto target_fail;
        for (size_t i = 0; i < nv; i++) {
            size_t k = flat ? tri[i] : i;
            struct rb_scene_morph_delta *o = &md[t * nv + i];
            memset(o, 0, sizeof(*o));
            if (dpos)
                memcpy(o->position, dpos + k * 3, 3 * sizeof(float));
            if (dnrm && !flat)
                memcpy(o->normal, dnrm + k * 3, 3 * sizeof(float));
        }
        free(dpos);
        free(dnrm);
        dpos = dnrm = NULL;
        continue;
    target_fail:
        rb_err_prefix(c->err, "target %zu", t);
        goto out;
    }

    p->first_vertex = s->vertex_count;
    p->vertex_count = (uint32_t)nv;
    p->first_index = s->index_count;
    p->index_count = (uint32_t)nt;
    p->first_morph = s->morph_delta_count;
    p->morph_target_count = (uint32_t)nm;
    s->vertex_count += (uint32_t)nv;
    s->index_count += (uint32_t)nt;
    s->morph_delta_count += (uint32_t)(nm * nv);
    *max_joint = mj;
out:
    free(pos);
    free(nrm);
    free(tan);
    free(uv);
    free(wgt);
    free(jnt);
    free(src);
    free(tri);
    free(scratch);
    free(dpos);
    free(dnrm);
    return st;
}

static uint64_t key_hash(const struct geom_key *k)
{
    uint64_t h = rb_hash64(k->attr, sizeof(k->attr), RB_HASH_SEED);
    h = rb_hash64(&k->gp->mode, sizeof(k->gp->mode), h);
    h = rb_hash64(&k->gp->indices, sizeof(k->gp->indices), h);
    return rb_hash64(&k->gen_tangents, sizeof(k->gen_tangents), h);
}

static bool key_equal(const struct geom_key *a, const struct geom_key *b)
{
    if (memcmp(a->attr, b->attr, sizeof(a->attr)) || a->gen_tangents != b->gen_tangents ||
        a->gp->mode != b->gp->mode || a->gp->indices != b->gp->indices ||
        a->gp->target_count != b->gp->target_count)
        return false;
    for (size_t t = 0; t < a->gp->target_count; t++) {
        const struct rb_gltf_target *x = &a->gp->targets[t], *y = &b->gp->targets[t];
        static const char *const names[] = {"POSITION", "NORMAL"};
        for (int k = 0; k < 2; k++)
            if (find_attr(x->attributes, x->attribute_count, names[k]) !=
                find_attr(y->attributes, y->attribute_count, names[k]))
                return false;
    }
    return true;
}

static enum rb_status convert_primitive(struct conv *c, size_t mesh_index, size_t prim_index,
                                        const struct rb_gltf_primitive *gp, bool *skipped)
{
    const struct rb_gltf_doc *d = c->doc;
    struct rb_scene *s = c->s;
    char what[200], mesh_label[160];
    LABEL(mesh_label, "mesh", d->meshes[mesh_index].name, mesh_index);
    snprintf(what, sizeof(what), "%s primitive %zu", mesh_label, prim_index);
    snprintf(c->prim_ptr, sizeof(c->prim_ptr), "/meshes/%zu/primitives/%zu", mesh_index,
             prim_index);
    *skipped = false;

    int mode = gp->mode == -1 ? 4 : gp->mode;
    if (mode >= 0 && mode <= 3) {
        static const char *const names[] = {"points", "lines", "line loop", "line strip"};
        rb_log(RB_LOG_WARN, "%s: %s are not supported; skipped", what, names[mode]);
        *skipped = true;
        return RB_OK;
    }
    if (mode < 4 || mode > 6)
        return rb_errf(c->err, RB_E_PARSE, "%s: unknown mode %d", what, mode);
    if (gp->material != -1 && !valid_index(gp->material, d->material_count))
        return rb_errf(c->err, RB_E_PARSE, "%s: material %d does not exist", what, gp->material);
    uint32_t material = gp->material == -1 ? (uint32_t)d->material_count : (uint32_t)gp->material;

    struct geom_key key = {.gp = gp, .prim = s->primitive_count};
    for (int a = 0; a < A_COUNT; a++)
        key.attr[a] = find_attr(gp->attributes, gp->attribute_count, attr_names[a]);
    if (key.attr[A_POSITION] == -1)
        return rb_errf(c->err, RB_E_PARSE, "%s: no POSITION attribute", what);
    if (find_attr(gp->attributes, gp->attribute_count, "JOINTS_1") != -1)
        rb_log(RB_LOG_WARN, "%s: JOINTS_1/WEIGHTS_1 are ignored (4 influences at most)", what);
    key.gen_tangents = key.attr[A_TANGENT] == -1 && s->materials[material].normal_tex != NONE;
    if (gp->target_count != c->mesh_targets[mesh_index])
        return rb_errf(c->err, RB_E_PARSE,
                       "%s: %zu morph targets, but the mesh's first primitive has %u", what,
                       gp->target_count, c->mesh_targets[mesh_index]);

    if (!grow((void **)&s->primitives, &c->prim_cap, s->primitive_count + 1,
              sizeof(struct rb_scene_primitive))) {
        return rb_errf(c->err, RB_E_NOMEM, "out of memory");
    }
    struct rb_scene_primitive *p = &s->primitives[s->primitive_count];
    memset(p, 0, sizeof(*p));
    p->material = material;

    uint64_t h = key_hash(&key);
    size_t mask = c->table_size - 1, slot = (size_t)h & mask;
    while (c->table[slot] != NONE) {
        const struct geom_key *k = &c->keys[c->table[slot]];
        if (key_equal(k, &key)) {
            const struct rb_scene_primitive *q = &s->primitives[k->prim];
            *p = *q;
            p->material = material;
            c->prim_joints[s->primitive_count] = c->prim_joints[k->prim];
            s->primitive_count++;
            return RB_OK;
        }
        slot = (slot + 1) & mask;
    }
    uint32_t mj = 0;
    enum rb_status st = convert_geometry(c, gp, key.attr, key.gen_tangents, what, p, &mj);
    if (st) {
        rb_err_prefix(c->err, "%s", what);
        return st;
    }
    c->prim_joints[s->primitive_count] = mj;
    c->keys[c->key_count] = key;
    c->table[slot] = (uint32_t)c->key_count++;
    s->primitive_count++;
    return RB_OK;
}

static enum rb_status convert_meshes(struct conv *c)
{
    const struct rb_gltf_doc *d = c->doc;
    struct rb_scene *s = c->s;
    size_t total = 0;
    for (size_t m = 0; m < d->mesh_count; m++)
        total += d->meshes[m].primitive_count;
    if (total > UINT32_MAX / 4)
        return rb_errf(c->err, RB_E_UNSUPPORTED, "too many primitives (%zu)", total);
    c->table_size = 16;
    while (c->table_size < 2 * total)
        c->table_size *= 2;
    c->keys = calloc(total + 1, sizeof(*c->keys));
    c->table = malloc(c->table_size * sizeof(uint32_t));
    c->prim_joints = calloc(total + 1, sizeof(uint32_t));
    c->mesh_targets = calloc(d->mesh_count + 1, sizeof(uint32_t));
    s->meshes = calloc(d->mesh_count + 1, sizeof(struct rb_scene_mesh));
    if (!c->keys || !c->table || !c->prim_joints || !c->mesh_targets || !s->meshes)
        return rb_errf(c->err, RB_E_NOMEM, "out of memory");
    for (size_t i = 0; i < c->table_size; i++)
        c->table[i] = NONE;
    s->mesh_count = (uint32_t)d->mesh_count;

    for (size_t m = 0; m < d->mesh_count; m++) {
        const struct rb_gltf_mesh *gm = &d->meshes[m];
        struct rb_scene_mesh *sm = &s->meshes[m];
        char what[160];
        LABEL(what, "mesh", gm->name, m);
        sm->name = dup_name(gm->name);
        if (!sm->name)
            return rb_errf(c->err, RB_E_NOMEM, "out of memory");
        uint32_t targets = gm->primitive_count ? (uint32_t)gm->primitives[0].target_count : 0;
        c->mesh_targets[m] = targets;
        if (gm->weight_count && gm->weight_count != targets)
            return rb_errf(c->err, RB_E_PARSE, "%s: %zu weights for %u morph targets", what,
                           gm->weight_count, targets);
        sm->weight_count = targets;
        if (targets) {
            sm->default_weights = calloc(targets, sizeof(float));
            if (!sm->default_weights)
                return rb_errf(c->err, RB_E_NOMEM, "out of memory");
            for (size_t k = 0; k < gm->weight_count; k++)
                sm->default_weights[k] = (float)gm->weights[k];
        }
        sm->first_primitive = s->primitive_count;
        for (size_t p = 0; p < gm->primitive_count; p++) {
            bool skipped;
            enum rb_status st = convert_primitive(c, m, p, &gm->primitives[p], &skipped);
            if (st)
                return st;
        }
        sm->primitive_count = s->primitive_count - sm->first_primitive;
    }
    return RB_OK;
}

/* ---- nodes, skins, cameras, lights --------------------------------------------------------- */

/* Splits a column-major affine matrix into T, R, S (glTF 5.25: matrices must be decomposable).
 * Returns false when the upper 3x3 has shear or the bottom row is not (0, 0, 0, 1). */
static bool decompose(const double *m, struct rb_vec3 *t, struct rb_quat *r, struct rb_vec3 *s)
{
    *t = rb_v3((float)m[12], (float)m[13], (float)m[14]);
    double col[3][3];
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++)
            col[i][k] = m[i * 4 + k];
    double len[3];
    for (int i = 0; i < 3; i++)
        len[i] = sqrt(col[i][0] * col[i][0] + col[i][1] * col[i][1] + col[i][2] * col[i][2]);
    double det = col[0][0] * (col[1][1] * col[2][2] - col[1][2] * col[2][1]) -
                 col[1][0] * (col[0][1] * col[2][2] - col[0][2] * col[2][1]) +
                 col[2][0] * (col[0][1] * col[1][2] - col[0][2] * col[1][1]);
    if (det < 0)
        len[0] = -len[0]; /* a mirror: put the flip into scale x */
    *s = rb_v3((float)len[0], (float)len[1], (float)len[2]);

    bool affine = m[3] == 0 && m[7] == 0 && m[11] == 0 && m[15] == 1;
    bool shear = false;
    for (int i = 0; i < 3; i++)
        for (int j = i + 1; j < 3; j++) {
            double dp = col[i][0] * col[j][0] + col[i][1] * col[j][1] + col[i][2] * col[j][2];
            if (len[i] != 0 && len[j] != 0 && fabs(dp / (len[i] * len[j])) > 1e-4)
                shear = true;
        }

    /* Gram-Schmidt keeps R a rotation even for degenerate or sheared input. */
    struct rb_vec3 x = rb_v3((float)col[0][0], (float)col[0][1], (float)col[0][2]);
    struct rb_vec3 y = rb_v3((float)col[1][0], (float)col[1][1], (float)col[1][2]);
    if (det < 0)
        x = rb_v3_scale(x, -1.0f);
    x = rb_v3_normalize(x);
    if (!(rb_v3_length(x) > 0.5f))
        x = rb_v3(1, 0, 0);
    y = rb_v3_sub(y, rb_v3_scale(x, rb_v3_dot(x, y)));
    y = rb_v3_normalize(y);
    if (!(rb_v3_length(y) > 0.5f))
        y = any_perpendicular(x);
    struct rb_vec3 z = rb_v3_cross(x, y);
    /* Rotation matrix (columns x, y, z) to quaternion (Shepperd). R[row][col]. */
    float r00 = x.x, r10 = x.y, r20 = x.z, r01 = y.x, r11 = y.y, r21 = y.z;
    float r02 = z.x, r12 = z.y, r22 = z.z;
    float tr = r00 + r11 + r22;
    struct rb_quat q;
    if (tr > 0) {
        float k = sqrtf(tr + 1.0f) * 2.0f;
        q = (struct rb_quat){(r21 - r12) / k, (r02 - r20) / k, (r10 - r01) / k, 0.25f * k};
    } else if (r00 > r11 && r00 > r22) {
        float k = sqrtf(1.0f + r00 - r11 - r22) * 2.0f;
        q = (struct rb_quat){0.25f * k, (r01 + r10) / k, (r02 + r20) / k, (r21 - r12) / k};
    } else if (r11 > r22) {
        float k = sqrtf(1.0f + r11 - r00 - r22) * 2.0f;
        q = (struct rb_quat){(r01 + r10) / k, 0.25f * k, (r12 + r21) / k, (r02 - r20) / k};
    } else {
        float k = sqrtf(1.0f + r22 - r00 - r11) * 2.0f;
        q = (struct rb_quat){(r02 + r20) / k, (r12 + r21) / k, 0.25f * k, (r10 - r01) / k};
    }
    *r = rb_quat_normalize(q);
    return affine && !shear;
}

/* A node's matrix and TRS must be finite in float, and its rotation not 0 (which
 * rb_quat_normalize turns into the identity). */
static enum rb_status check_trs(struct conv *c, const struct rb_gltf_node *g, size_t i)
{
    const struct {
        const char *name;
        const double *v;
        size_t count;
    } props[] = {{"matrix", g->matrix, g->matrix_count},
                 {"translation", g->translation, g->translation_count},
                 {"rotation", g->rotation, g->rotation_count},
                 {"scale", g->scale, g->scale_count}};
    enum rb_status st = RB_OK;
    for (size_t p = 0; !st && p < sizeof(props) / sizeof(props[0]); p++) {
        size_t at;
        if (!floats_finite(props[p].v, props[p].count, &at))
            st = violation(c, "/nodes/%zu/%s: value %zu (%g) is not finite in float", i,
                           props[p].name, at, props[p].v[at]);
    }
    if (!st && g->rotation_count == 4 && g->rotation[0] == 0 && g->rotation[1] == 0 &&
        g->rotation[2] == 0 && g->rotation[3] == 0)
        st = violation(c,
                       "/nodes/%zu/rotation: [0, 0, 0, 0] has length 0, and a rotation is a "
                       "unit quaternion",
                       i);
    return st;
}

static enum rb_status convert_nodes(struct conv *c)
{
    const struct rb_gltf_doc *d = c->doc;
    struct rb_scene *s = c->s;
    s->nodes = calloc(d->node_count + 1, sizeof(struct rb_scene_node));
    if (!s->nodes)
        return rb_errf(c->err, RB_E_NOMEM, "out of memory");
    s->node_count = (uint32_t)d->node_count;
    for (size_t i = 0; i < d->node_count; i++)
        s->nodes[i].parent = NONE;

    for (size_t i = 0; i < d->node_count; i++) {
        const struct rb_gltf_node *g = &d->nodes[i];
        struct rb_scene_node *n = &s->nodes[i];
        char what[160];
        LABEL(what, "node", g->name, i);
        n->name = dup_name(g->name);
        if (!n->name)
            return rb_errf(c->err, RB_E_NOMEM, "out of memory");
        n->translation = rb_v3(0, 0, 0);
        n->rotation = rb_quat_identity();
        n->scale = rb_v3(1, 1, 1);
        enum rb_status st = check_trs(c, g, i);
        if (st)
            return st;
        if (g->matrix_count) {
            if (g->matrix_count != 16)
                return rb_errf(c->err, RB_E_PARSE, "%s: matrix has %zu values", what,
                               g->matrix_count);
            if (!decompose(g->matrix, &n->translation, &n->rotation, &n->scale))
                rb_log(RB_LOG_WARN, "%s: matrix has shear or projection; approximated by TRS",
                       what);
        }
        if (g->translation_count) {
            if (g->translation_count != 3)
                return rb_errf(c->err, RB_E_PARSE, "%s: translation needs 3 values", what);
            n->translation =
                rb_v3((float)g->translation[0], (float)g->translation[1], (float)g->translation[2]);
        }
        if (g->rotation_count) {
            if (g->rotation_count != 4)
                return rb_errf(c->err, RB_E_PARSE, "%s: rotation needs 4 values", what);
            n->rotation =
                rb_quat_normalize((struct rb_quat){(float)g->rotation[0], (float)g->rotation[1],
                                                   (float)g->rotation[2], (float)g->rotation[3]});
        }
        if (g->scale_count) {
            if (g->scale_count != 3)
                return rb_errf(c->err, RB_E_PARSE, "%s: scale needs 3 values", what);
            n->scale = rb_v3((float)g->scale[0], (float)g->scale[1], (float)g->scale[2]);
        }
        n->mesh = n->skin = n->camera = n->light = NONE;
        if (g->mesh != -1) {
            if (!valid_index(g->mesh, d->mesh_count))
                return rb_errf(c->err, RB_E_PARSE, "%s: mesh %d does not exist", what, g->mesh);
            n->mesh = (uint32_t)g->mesh;
        }
        if (g->skin != -1) {
            if (!valid_index(g->skin, d->skin_count))
                return rb_errf(c->err, RB_E_PARSE, "%s: skin %d does not exist", what, g->skin);
            n->skin = (uint32_t)g->skin;
        }
        if (g->camera != -1) {
            if (!valid_index(g->camera, d->camera_count))
                return rb_errf(c->err, RB_E_PARSE, "%s: camera %d does not exist", what, g->camera);
            n->camera = (uint32_t)g->camera;
        }
        if (g->light != -1) {
            if (!valid_index(g->light, d->light_count))
                return rb_errf(c->err, RB_E_PARSE,
                               "%s: KHR_lights_punctual light %d does not exist", what, g->light);
            n->light = (uint32_t)g->light;
        }
        if (g->weight_count) {
            uint32_t want = n->mesh != NONE ? s->meshes[n->mesh].weight_count : 0;
            if (g->weight_count != want)
                return rb_errf(c->err, RB_E_PARSE, "%s: %zu weights for %u morph targets", what,
                               g->weight_count, want);
            n->weights = malloc(want * sizeof(float));
            if (!n->weights)
                return rb_errf(c->err, RB_E_NOMEM, "out of memory");
            for (uint32_t k = 0; k < want; k++)
                n->weights[k] = (float)g->weights[k];
        }
        for (size_t k = 0; k < g->child_count; k++) {
            int32_t ch = g->children[k];
            if (!valid_index(ch, d->node_count))
                return rb_errf(c->err, RB_E_PARSE, "%s: child %d does not exist", what, ch);
            if ((size_t)ch == i)
                return rb_errf(c->err, RB_E_PARSE, "%s: lists itself among its children", what);
            if (s->nodes[ch].parent != NONE)
                return rb_errf(c->err, RB_E_PARSE, "%s: node %d has more than one parent", what,
                               ch);
            s->nodes[ch].parent = (uint32_t)i;
        }
    }
    return RB_OK;
}

static enum rb_status mark_in_scene(struct conv *c)
{
    const struct rb_gltf_doc *d = c->doc;
    struct rb_scene *s = c->s;
    enum rb_status st = RB_OK;
    uint32_t *order = malloc((s->node_count + 1) * sizeof(uint32_t));
    if (!order)
        return rb_errf(c->err, RB_E_NOMEM, "out of memory");
    st = rb_scene_node_order(s, order, c->err);
    if (st)
        goto out;
    int32_t sc = d->default_scene;
    if (sc != -1 && !valid_index(sc, d->scene_count)) {
        st = rb_errf(c->err, RB_E_PARSE, "default scene %d does not exist", sc);
        goto out;
    }
    if (sc == -1 && d->scene_count)
        sc = 0;
    if (sc == -1) { /* no scenes at all: every root */
        for (uint32_t i = 0; i < s->node_count; i++)
            s->nodes[i].in_scene = s->nodes[i].parent == NONE;
    } else {
        const struct rb_gltf_scene *gs = &d->scenes[sc];
        for (size_t k = 0; k < gs->node_count; k++) {
            int32_t n = gs->nodes[k];
            if (!valid_index(n, s->node_count)) {
                char what[160];
                st = rb_errf(c->err, RB_E_PARSE, "%s: node %d does not exist",
                             LABEL(what, "scene", gs->name, (size_t)sc), n);
                goto out;
            }
            s->nodes[n].in_scene = true;
        }
    }
    /* Parents come first in order, so one pass propagates reachability. */
    for (uint32_t k = 0; k < s->node_count; k++) {
        struct rb_scene_node *n = &s->nodes[order[k]];
        if (n->parent != NONE && s->nodes[n->parent].in_scene)
            n->in_scene = true;
    }
out:
    free(order);
    return st;
}

static enum rb_status convert_skins(struct conv *c)
{
    const struct rb_gltf_doc *d = c->doc;
    struct rb_scene *s = c->s;
    s->skins = calloc(d->skin_count + 1, sizeof(struct rb_scene_skin));
    if (!s->skins)
        return rb_errf(c->err, RB_E_NOMEM, "out of memory");
    s->skin_count = (uint32_t)d->skin_count;
    for (size_t i = 0; i < d->skin_count; i++) {
        const struct rb_gltf_skin *g = &d->skins[i];
        struct rb_scene_skin *k = &s->skins[i];
        char what[160];
        LABEL(what, "skin", g->name, i);
        k->name = dup_name(g->name);
        size_t n = g->joint_count;
        k->joints = malloc((n + 1) * sizeof(uint32_t));
        k->inverse_bind = malloc((n + 1) * sizeof(struct rb_mat4));
        if (!k->name || !k->joints || !k->inverse_bind)
            return rb_errf(c->err, RB_E_NOMEM, "out of memory");
        k->joint_count = (uint32_t)n;
        for (size_t j = 0; j < n; j++) {
            if (!valid_index(g->joints[j], s->node_count))
                return rb_errf(c->err, RB_E_PARSE, "%s: joint node %d does not exist", what,
                               g->joints[j]);
            k->joints[j] = (uint32_t)g->joints[j];
            k->inverse_bind[j] = rb_mat4_identity();
        }
        if (g->inverse_bind_matrices != -1) {
            float *f = NULL;
            struct acc v;
            char use[64];
            snprintf(use, sizeof(use), "/skins/%zu/inverseBindMatrices", i);
            enum rb_status st = acc_floats(c, g->inverse_bind_matrices, TYPE_MAT4, use, &f, &v);
            if (!st && v.count < n)
                st = rb_errf(c->err, RB_E_PARSE, "%zu inverse bind matrices for %zu joints",
                             v.count, n);
            if (st) {
                free(f);
                rb_err_prefix(c->err, "%s", what);
                return st;
            }
            memcpy(k->inverse_bind, f, n * sizeof(struct rb_mat4));
            free(f);
        }
    }
    /* Every skinned instance must only use joints its skin has. */
    for (uint32_t i = 0; i < s->node_count; i++) {
        const struct rb_scene_node *n = &s->nodes[i];
        if (n->skin == NONE || n->mesh == NONE)
            continue;
        const struct rb_scene_mesh *m = &s->meshes[n->mesh];
        for (uint32_t p = m->first_primitive; p < m->first_primitive + m->primitive_count; p++)
            if (c->prim_joints[p] > s->skins[n->skin].joint_count) {
                char a[160], b[160], e[160];
                return rb_errf(c->err, RB_E_PARSE, "%s: %s uses joint %u but %s has %u joints",
                               LABEL(a, "node", n->name, i), LABEL(b, "mesh", m->name, n->mesh),
                               c->prim_joints[p] - 1,
                               LABEL(e, "skin", s->skins[n->skin].name, n->skin),
                               s->skins[n->skin].joint_count);
            }
    }
    return RB_OK;
}

/* KHR_lights_punctual: a colour of finite components >= 0, an intensity >= 0, their product
 * at most RB_MAX_RADIANCE, and a range > 0 when there is one. */
static enum rb_status check_light(struct conv *c, const struct rb_gltf_light *g, size_t i)
{
    enum rb_status st = RB_OK;
    double peak = 1.0; /* the colour's largest component */
    for (size_t k = 0; k < g->color_count; k++) {
        if (!(g->color[k] >= 0) || !isfinite((float)g->color[k])) {
            st = violation(c,
                           "/extensions/KHR_lights_punctual/lights/%zu/color: value %zu (%g) "
                           "is not a finite number >= 0",
                           i, k, g->color[k]);
            break;
        }
        peak = k ? fmax(peak, g->color[k]) : g->color[k];
    }
    if (!st && !(g->intensity >= 0))
        st = violation(c, "/extensions/KHR_lights_punctual/lights/%zu/intensity: %g is negative", i,
                       g->intensity);
    else if (!st && !(peak * g->intensity <= RB_MAX_RADIANCE))
        st = violation(c,
                       "/extensions/KHR_lights_punctual/lights/%zu: color x intensity is %g, "
                       "more than %g",
                       i, peak * g->intensity, RB_MAX_RADIANCE);
    if (!st && g->has_range && !(g->range > 0 && isfinite((float)g->range)))
        st = violation(c,
                       "/extensions/KHR_lights_punctual/lights/%zu/range: %g, and a range "
                       "must be > 0 (and finite in float)",
                       i, g->range);
    return st;
}

static enum rb_status convert_cameras_lights(struct conv *c)
{
    const struct rb_gltf_doc *d = c->doc;
    struct rb_scene *s = c->s;
    s->cameras = calloc(d->camera_count + 1, sizeof(struct rb_scene_camera));
    s->lights = calloc(d->light_count + 1, sizeof(struct rb_scene_light));
    if (!s->cameras || !s->lights)
        return rb_errf(c->err, RB_E_NOMEM, "out of memory");
    s->camera_count = (uint32_t)d->camera_count;
    s->light_count = (uint32_t)d->light_count;
    for (size_t i = 0; i < d->camera_count; i++) {
        const struct rb_gltf_camera *g = &d->cameras[i];
        struct rb_scene_camera *k = &s->cameras[i];
        char what[160];
        LABEL(what, "camera", g->name, i);
        if (!(k->name = dup_name(g->name)))
            return rb_errf(c->err, RB_E_NOMEM, "out of memory");
        if (!strcmp(g->type, "perspective")) {
            k->is_perspective = true;
            k->yfov_rad = (float)g->yfov;
            k->aspect = (float)g->aspect;
            k->znear = (float)g->znear;
            k->zfar = (float)g->zfar;
            if (!(k->yfov_rad > 0.0f && k->yfov_rad < RB_PI))
                return rb_errf(c->err, RB_E_PARSE, "%s: yfov %g is out of range", what, g->yfov);
            if (!(k->znear > 0.0f) || (k->zfar != 0.0f && !(k->zfar > k->znear)))
                return rb_errf(c->err, RB_E_PARSE, "%s: bad znear %g / zfar %g", what, g->znear,
                               g->zfar);
        } else if (!strcmp(g->type, "orthographic")) {
            k->xmag = (float)g->xmag;
            k->ymag = (float)g->ymag;
            k->znear = (float)g->ortho_znear;
            k->zfar = (float)g->ortho_zfar;
        } else {
            return rb_errf(c->err, RB_E_PARSE, "%s: unknown type '%s'", what, g->type);
        }
    }
    for (size_t i = 0; i < d->light_count; i++) {
        const struct rb_gltf_light *g = &d->lights[i];
        struct rb_scene_light *l = &s->lights[i];
        char what[160];
        LABEL(what, "light", g->name, i);
        if (!(l->name = dup_name(g->name)))
            return rb_errf(c->err, RB_E_NOMEM, "out of memory");
        if (!strcmp(g->type, "point"))
            l->type = RB_LIGHT_POINT;
        else if (!strcmp(g->type, "spot"))
            l->type = RB_LIGHT_SPOT;
        else if (!strcmp(g->type, "directional"))
            l->type = RB_LIGHT_DIRECTIONAL;
        else
            return rb_errf(c->err, RB_E_PARSE, "%s: unknown type '%s'", what, g->type);
        if (g->color_count && g->color_count != 3)
            return rb_errf(c->err, RB_E_PARSE, "%s: color needs 3 values", what);
        for (int k = 0; k < 3; k++)
            l->color[k] = g->color_count ? (float)g->color[k] : 1.0f;
        l->intensity = (float)g->intensity;
        l->range = (float)g->range;
        l->inner_cone_rad = (float)g->inner_cone;
        l->outer_cone_rad = (float)g->outer_cone;
        if (l->type == RB_LIGHT_SPOT &&
            !(l->inner_cone_rad >= 0 && l->inner_cone_rad < l->outer_cone_rad &&
              l->outer_cone_rad <= RB_PI / 2 + 1e-6f))
            return rb_errf(c->err, RB_E_PARSE,
                           "%s: need 0 <= innerConeAngle < outerConeAngle <= pi/2", what);
        enum rb_status st = check_light(c, g, i);
        if (st)
            return st;
        if (g->has_range && !(g->range > 0 && isfinite(l->range)))
            l->range = 0.0f; /* lenient: no range, as if it were absent */
    }
    return RB_OK;
}

/* ---- animations ---------------------------------------------------------------------------- */

/* ptr: the sampler's JSON pointer. */
static enum rb_status convert_sampler(struct conv *c, const struct rb_gltf_anim_sampler *g,
                                      const char *ptr, struct rb_scene_anim_sampler *o)
{
    char use[2][96];
    snprintf(use[0], sizeof(use[0]), "%s/input", ptr);
    snprintf(use[1], sizeof(use[1]), "%s/output", ptr);
    if (!strcmp(g->interpolation, "LINEAR"))
        o->interpolation = RB_ANIM_LINEAR;
    else if (!strcmp(g->interpolation, "STEP"))
        o->interpolation = RB_ANIM_STEP;
    else if (!strcmp(g->interpolation, "CUBICSPLINE"))
        o->interpolation = RB_ANIM_CUBICSPLINE;
    else
        return rb_errf(c->err, RB_E_PARSE, "unknown interpolation '%s'", g->interpolation);
    struct acc in, out;
    enum rb_status st = acc_floats(c, g->input, TYPE_SCALAR, use[0], &o->times, &in);
    if (st)
        return st;
    if (in.count == 0)
        return rb_errf(c->err, RB_E_PARSE, "input accessor %d has no keys", g->input);
    for (size_t k = 0; k < in.count; k++)
        if (!isfinite(o->times[k]) || (k && o->times[k] < o->times[k - 1]))
            return rb_errf(c->err, RB_E_PARSE, "input accessor %d: key times must increase",
                           g->input);
    o->key_count = (uint32_t)in.count;
    if ((st = acc_floats(c, g->output, 0, use[1], &o->values, &out)))
        return st;
    size_t mult = o->interpolation == RB_ANIM_CUBICSPLINE ? 3 : 1;
    size_t elems = out.count * out.comps, per = in.count * mult;
    if (elems == 0 || elems % per)
        return rb_errf(c->err, RB_E_PARSE,
                       "output accessor %d has %zu values, not a multiple of %zu keys%s", g->output,
                       elems, in.count, mult == 3 ? " x 3" : "");
    o->components = (uint32_t)(elems / per);
    return RB_OK;
}

/* The keys of a rotation sampler (the values, not a cubic spline's tangents) must not be 0,
 * which no slerp can normalize; lenient, they become the identity. */
static enum rb_status check_rotations(struct conv *c, struct rb_scene_anim_sampler *sm, size_t anim,
                                      size_t sampler, int32_t output, size_t channel)
{
    size_t per = sm->interpolation == RB_ANIM_CUBICSPLINE ? 3 : 1, bad = 0, first = 0;
    for (size_t k = 0; k < sm->key_count; k++) {
        float *q = sm->values + (k * per + (per == 3)) * 4;
        if (q[0] == 0 && q[1] == 0 && q[2] == 0 && q[3] == 0) {
            if (!bad++)
                first = k;
            q[3] = 1.0f;
        }
    }
    if (!bad)
        return RB_OK;
    return violation(c,
                     "/animations/%zu/samplers/%zu/output: accessor %d: %zu of %u keys are "
                     "[0, 0, 0, 0] (the first: key %zu), and the rotations of "
                     "/animations/%zu/channels/%zu are unit quaternions",
                     anim, sampler, output, bad, sm->key_count, first, anim, channel);
}

static enum rb_status convert_animations(struct conv *c)
{
    const struct rb_gltf_doc *d = c->doc;
    struct rb_scene *s = c->s;
    s->animations = calloc(d->animation_count + 1, sizeof(struct rb_scene_animation));
    if (!s->animations)
        return rb_errf(c->err, RB_E_NOMEM, "out of memory");
    s->animation_count = (uint32_t)d->animation_count;
    for (size_t i = 0; i < d->animation_count; i++) {
        const struct rb_gltf_animation *g = &d->animations[i];
        struct rb_scene_animation *a = &s->animations[i];
        char what[160];
        LABEL(what, "animation", g->name, i);
        a->name = dup_name(g->name);
        a->samplers = calloc(g->sampler_count + 1, sizeof(*a->samplers));
        a->channels = calloc(g->channel_count + 1, sizeof(*a->channels));
        if (!a->name || !a->samplers || !a->channels)
            return rb_errf(c->err, RB_E_NOMEM, "out of memory");
        a->sampler_count = (uint32_t)g->sampler_count;
        for (size_t k = 0; k < g->sampler_count; k++) {
            char ptr[64];
            snprintf(ptr, sizeof(ptr), "/animations/%zu/samplers/%zu", i, k);
            enum rb_status st = convert_sampler(c, &g->samplers[k], ptr, &a->samplers[k]);
            if (st) {
                rb_err_prefix(c->err, "%s sampler %zu", what, k);
                return st;
            }
            const struct rb_scene_anim_sampler *sm = &a->samplers[k];
            if (sm->times[0] < 0 &&
                (st = violation(c,
                                "%s/input: accessor %d: key 0 is at %g s, and key times are "
                                ">= 0",
                                ptr, g->samplers[k].input, sm->times[0])))
                return st;
            if (sm->times[sm->key_count - 1] > a->duration_s)
                a->duration_s = sm->times[sm->key_count - 1];
        }
        for (size_t k = 0; k < g->channel_count; k++) {
            const struct rb_gltf_anim_channel *gc = &g->channels[k];
            enum rb_anim_path path;
            if (!strcmp(gc->path, "translation")) {
                path = RB_ANIM_TRANSLATION;
            } else if (!strcmp(gc->path, "rotation")) {
                path = RB_ANIM_ROTATION;
            } else if (!strcmp(gc->path, "scale")) {
                path = RB_ANIM_SCALE;
            } else if (!strcmp(gc->path, "weights")) {
                path = RB_ANIM_WEIGHTS;
            } else {
                rb_log(RB_LOG_WARN, "%s channel %zu: path '%s' is not supported; ignored", what, k,
                       gc->path);
                continue;
            }
            if (gc->node == -1) /* targeted by an extension we do not know */
                continue;
            if (!valid_index(gc->node, s->node_count) ||
                !valid_index(gc->sampler, g->sampler_count))
                return rb_errf(c->err, RB_E_PARSE,
                               "%s channel %zu: node %d or sampler %d does not exist", what, k,
                               gc->node, gc->sampler);
            uint32_t comps = a->samplers[gc->sampler].components, want = 3;
            if (path == RB_ANIM_ROTATION)
                want = 4;
            if (path == RB_ANIM_WEIGHTS) {
                uint32_t mesh = s->nodes[gc->node].mesh;
                want = mesh != NONE ? s->meshes[mesh].weight_count : 0;
                if (!want) {
                    rb_log(RB_LOG_WARN,
                           "%s channel %zu: weights of a node without morph targets; ignored", what,
                           k);
                    continue;
                }
            }
            if (comps != want)
                return rb_errf(c->err, RB_E_PARSE,
                               "%s channel %zu: %s needs %u values per key, sampler %d has %u",
                               what, k, gc->path, want, gc->sampler, comps);
            enum rb_status st = RB_OK;
            if (path == RB_ANIM_ROTATION &&
                (st = check_rotations(c, &a->samplers[gc->sampler], i, (size_t)gc->sampler,
                                      g->samplers[gc->sampler].output, k)))
                return st;
            a->channels[a->channel_count++] = (struct rb_scene_anim_channel){
                .sampler = (uint32_t)gc->sampler, .node = (uint32_t)gc->node, .path = path};
        }
    }
    return RB_OK;
}

/* ---- the whole load ------------------------------------------------------------------------ */

static enum rb_status check_extensions(struct conv *c)
{
    const struct rb_gltf_doc *d = c->doc;
    for (size_t i = 0; i < d->extensions_required_count; i++) {
        const char *e = d->extensions_required[i];
        if (!strcmp(e, "KHR_lights_punctual") || !strcmp(e, "KHR_materials_emissive_strength") ||
            !strcmp(e, "KHR_materials_specular"))
            continue;
        if (!strcmp(e, "KHR_texture_transform")) {
            rb_log(RB_LOG_WARN, "'%s': required extension KHR_texture_transform is ignored",
                   c->s->path);
            continue;
        }
        return rb_errf(c->err, RB_E_UNSUPPORTED, "required extension '%s' is not supported", e);
    }
    return RB_OK;
}

/* "<major>.<minor>", as glTF writes a version, into its two numbers. */
static bool parse_version(const char *s, unsigned long *major, unsigned long *minor)
{
    char *end;
    if (*s < '0' || *s > '9')
        return false;
    *major = strtoul(s, &end, 10);
    if (*end != '.' || end[1] < '0' || end[1] > '9')
        return false;
    *minor = strtoul(end + 1, &end, 10);
    return *end == '\0';
}

/* What glTF 2.0 asks of the document as a whole: a 2.x version that needs no more than 2.0, a
 * binary container of version 2, and accessors of at least one element (unused ones too). */
static enum rb_status check_document(struct conv *c)
{
    const struct rb_gltf_doc *d = c->doc;
    unsigned long major = 0, minor = 0;
    enum rb_status st = RB_OK;
    if (d->glb_version && d->glb_version != 2)
        st = violation(c,
                       "GLB header: container version %u, and glTF 2.0 binary files are "
                       "version 2",
                       d->glb_version);
    if (!st && !(parse_version(d->version, &major, &minor) && major == 2))
        st = violation(c, "/asset/version: '%s' is not a glTF 2.x version", d->version);
    if (!st && *d->min_version &&
        !(parse_version(d->min_version, &major, &minor) && major == 2 && minor == 0))
        st = violation(c,
                       "/asset/minVersion: the file needs glTF '%s', and raybundle reads "
                       "glTF 2.0",
                       d->min_version);
    for (size_t i = 0; !st && i < d->accessor_count; i++)
        if (d->accessors[i].count == 0)
            st = violation(c, "/accessors/%zu/count: 0, and an accessor has at least 1 element", i);
    return st;
}

static void log_warnings(const char *path, const char *text)
{
    while (text && *text) {
        const char *end = strchr(text, '\n');
        int len = end ? (int)(end - text) : (int)strlen(text);
        if (len > 0)
            rb_log(RB_LOG_WARN, "scene '%s': %.*s", path, len, text);
        text += len + (end ? 1 : 0);
    }
}

/* The file's bytes (the JSON or the whole .glb), then each buffer and each decoded image, each
 * length-prefixed: external .bin and texture files count through what was read from them. */
static enum rb_status content_hash(const char *path, const struct rb_gltf_doc *doc, uint64_t *out,
                                   struct rb_err *err)
{
    char *bytes = NULL;
    size_t size = 0;
    enum rb_status st = rb_read_file(path, &bytes, &size, err);
    if (st)
        return st;
    uint64_t h = rb_hash_bulk(bytes, size, RB_HASH_SEED);
    free(bytes);
    for (size_t i = 0; i < doc->buffer_count; i++) {
        uint64_t n = doc->buffers[i].size;
        h = rb_hash_bulk(&n, sizeof(n), h);
        h = rb_hash_bulk(doc->buffers[i].data, doc->buffers[i].size, h);
    }
    for (size_t i = 0; i < doc->image_count; i++) {
        const struct rb_gltf_image *im = &doc->images[i];
        uint64_t n = im->pixels ? im->size : UINT64_MAX;
        h = rb_hash_bulk(&n, sizeof(n), h);
        if (im->pixels)
            h = rb_hash_bulk(im->pixels, im->size, h);
    }
    *out = h;
    return RB_OK;
}

struct load_policy {
    const char *path;
    bool is_lenient;
};

/* A JSON type issue: strict, it stops the load (the shim turns it into the error); lenient, it
 * is a warning and tinygltf reads the file as it can. */
static bool on_json_issue(void *user, const char *pointer, const char *problem)
{
    const struct load_policy *p = user;
    if (p->is_lenient)
        rb_log(RB_LOG_WARN, "scene '%s': %s: %s", p->path, pointer, problem);
    return p->is_lenient;
}

enum rb_status rb_scene_load(const char *path, unsigned flags, struct rb_scene **out,
                             struct rb_err *err)
{
    struct rb_gltf_doc *doc = NULL;
    struct conv c = {.err = err};
    struct load_policy policy = {path, (flags & RB_SCENE_LOAD_LENIENT) != 0};
    struct rb_gltf_check check = {rb_scene_json_rules, rb_scene_json_rule_count, on_json_issue,
                                  &policy};
    enum rb_status st = rb_gltf_shim_load(path, &check, &doc, err);
    if (st)
        goto out;
    if (*doc->errors && !policy.is_lenient) {
        /* tinygltf loaded it but found it broken: a primitive it dropped, a misaligned chunk */
        const char *nl = strchr(doc->errors, '\n');
        int len = nl ? (int)(nl - doc->errors) : (int)strlen(doc->errors);
        st = rb_errf(err, RB_E_PARSE, "%.*s", len, doc->errors);
        goto out;
    }
    log_warnings(path, doc->errors);
    log_warnings(path, doc->warnings);
    c.doc = doc;
    c.s = calloc(1, sizeof(struct rb_scene));
    if (!c.s || !(c.s->path = rb_strdup(path))) {
        st = rb_errf(err, RB_E_NOMEM, "out of memory");
        goto out;
    }
    /* Order matters: materials need textures, primitives need materials, nodes need meshes,
     * skins need nodes and per-primitive joint ranges, channels need nodes and meshes. */
    c.is_lenient = policy.is_lenient;
    if ((st = check_document(&c)) || (st = check_extensions(&c)) || (st = convert_textures(&c)) ||
        (st = convert_materials(&c)) || (st = convert_meshes(&c)) || (st = convert_nodes(&c)) ||
        (st = mark_in_scene(&c)) || (st = convert_skins(&c)) || (st = convert_cameras_lights(&c)) ||
        (st = convert_animations(&c)) || (st = content_hash(path, doc, &c.s->content_hash, err)))
        goto out;
    /* The growth slack can be half the arrays: give it back (a failed shrink keeps them). */
    shrink((void **)&c.s->vertices, c.s->vertex_count, sizeof(struct rb_scene_vertex));
    shrink((void **)&c.s->indices, c.s->index_count, sizeof(uint32_t));
    shrink((void **)&c.s->morph_deltas, c.s->morph_delta_count,
           sizeof(struct rb_scene_morph_delta));
    shrink((void **)&c.s->primitives, c.s->primitive_count, sizeof(struct rb_scene_primitive));
    if (!c.s->vertices) { /* keep every array non-NULL for the GPU upload's sake */
        c.s->vertices = calloc(1, sizeof(struct rb_scene_vertex));
        c.s->indices = calloc(1, sizeof(uint32_t));
    }
    if (!c.s->morph_deltas)
        c.s->morph_deltas = calloc(1, sizeof(struct rb_scene_morph_delta));
    if (!c.s->primitives)
        c.s->primitives = calloc(1, sizeof(struct rb_scene_primitive));
    if (!c.s->vertices || !c.s->indices || !c.s->morph_deltas || !c.s->primitives) {
        st = rb_errf(err, RB_E_NOMEM, "out of memory");
        goto out;
    }
    *out = c.s;
    c.s = NULL;
out:
    if (st && err && !strstr(err->msg, path))
        rb_err_prefix(err, "scene '%s'", path);
    rb_scene_destroy(c.s);
    free(c.image_texture);
    free(c.mesh_targets);
    free(c.prim_joints);
    free(c.keys);
    free(c.table);
    rb_gltf_shim_free(doc);
    return st;
}

void rb_scene_destroy(struct rb_scene *s)
{
    if (!s)
        return;
    free(s->path);
    free(s->vertices);
    free(s->indices);
    free(s->morph_deltas);
    free(s->primitives);
    for (uint32_t i = 0; s->meshes && i < s->mesh_count; i++) {
        free(s->meshes[i].name);
        free(s->meshes[i].default_weights);
    }
    free(s->meshes);
    for (uint32_t i = 0; s->materials && i < s->material_count; i++)
        free(s->materials[i].name);
    free(s->materials);
    for (uint32_t i = 0; s->textures && i < s->texture_count; i++) {
        free(s->textures[i].name);
        free(s->textures[i].rgba8);
    }
    free(s->textures);
    for (uint32_t i = 0; s->nodes && i < s->node_count; i++) {
        free(s->nodes[i].name);
        free(s->nodes[i].weights);
    }
    free(s->nodes);
    for (uint32_t i = 0; s->skins && i < s->skin_count; i++) {
        free(s->skins[i].name);
        free(s->skins[i].joints);
        free(s->skins[i].inverse_bind);
    }
    free(s->skins);
    for (uint32_t i = 0; s->cameras && i < s->camera_count; i++)
        free(s->cameras[i].name);
    free(s->cameras);
    for (uint32_t i = 0; s->lights && i < s->light_count; i++)
        free(s->lights[i].name);
    free(s->lights);
    for (uint32_t i = 0; s->animations && i < s->animation_count; i++) {
        struct rb_scene_animation *a = &s->animations[i];
        free(a->name);
        for (uint32_t k = 0; a->samplers && k < a->sampler_count; k++) {
            free(a->samplers[k].times);
            free(a->samplers[k].values);
        }
        free(a->samplers);
        free(a->channels);
    }
    free(s->animations);
    free(s);
}

uint32_t rb_scene_find_node(const struct rb_scene *scene, const char *name)
{
    for (uint32_t i = 0; name && i < scene->node_count; i++)
        if (scene->nodes[i].name && !strcmp(scene->nodes[i].name, name))
            return i;
    return NONE;
}

uint32_t rb_scene_find_animation(const struct rb_scene *scene, const char *name)
{
    for (uint32_t i = 0; name && i < scene->animation_count; i++)
        if (scene->animations[i].name && !strcmp(scene->animations[i].name, name))
            return i;
    return NONE;
}

enum rb_status rb_scene_node_order(const struct rb_scene *scene, uint32_t *order,
                                   struct rb_err *err)
{
    /* Breadth-first from the roots over child lists built from the parent indices; a node
     * that is never reached lies on a cycle. */
    uint32_t n = scene->node_count, count = 0;
    enum rb_status st = RB_OK;
    uint32_t *head = malloc((n + 1) * sizeof(uint32_t)), *next = malloc((n + 1) * sizeof(uint32_t));
    if (!head || !next) {
        st = rb_errf(err, RB_E_NOMEM, "out of memory");
        goto out;
    }
    for (uint32_t i = 0; i < n; i++)
        head[i] = NONE;
    for (uint32_t i = n; i-- > 0;) { /* backwards, so each list is in ascending order */
        uint32_t p = scene->nodes[i].parent;
        if (p == NONE) {
            continue;
        } else if (p >= n) {
            st = rb_errf(err, RB_E_INVALID, "node %u: parent %u does not exist", i, p);
            goto out;
        }
        next[i] = head[p];
        head[p] = i;
    }
    for (uint32_t i = 0; i < n; i++)
        if (scene->nodes[i].parent == NONE)
            order[count++] = i;
    for (uint32_t k = 0; k < count; k++)
        for (uint32_t ch = head[order[k]]; ch != NONE; ch = next[ch])
            order[count++] = ch;
    if (count != n)
        st = rb_errf(err, RB_E_INVALID, "the node hierarchy has a cycle");
out:
    free(head);
    free(next);
    return st;
}
