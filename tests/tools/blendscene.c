/* blendscene: the transparency test's scene writer and checker, after Khronos'
 * AlphaBlendModeTest: an opaque floor and back wall, four quads side by side in front of them
 * (red, green and blue with base colour alpha 0.25, 0.5 and 0.75; white with an alpha texture
 * that rises from 0.1 on the left to 0.9 on the right) and a yellow quad with alpha 0.5 behind
 * the first two, which it overlaps in part, lit by one point light.
 *   blendscene scene DIR       writes DIR/alpha.png, DIR/blend.gltf (the four quads BLEND),
 *                              DIR/opaque.gltf (the four OPAQUE), DIR/none.gltf (the four
 *                              absent), the yellow quad BLEND in all three; DIR/plain.gltf
 *                              (every material OPAQUE); and a job for each (blend.yaml,
 *                              opaque.yaml, none.yaml, plain.yaml; the integrator is the
 *                              command line's)
 *   blendscene area DIR        writes DIR/area.gltf and DIR/area.yaml: the blended scene with
 *                              no punctual light, lit by an emissive quad above the front quads
 *                              and a uniform sky-blue environment; area-opaque.gltf and
 *                              area-opaque.yaml the same with the four front quads OPAQUE
 *   blendscene mask OPAQUE OUT writes the PNG mask of the four front quads' interior pixels
 *                              (as show finds them in OPAQUE) for raybundle compare --mask
 *   blendscene show|exact BLEND OPAQUE NONE
 *                              checks three renders of the same integrator: where OPAQUE's
 *                              albedo is a quad's colour (its interior: the four neighbours
 *                              too), BLEND differs from both OPAQUE and NONE (the quads show,
 *                              and are not drawn opaque); exact adds, for the direct
 *                              integrator, whose light at a pixel depends on the surface there
 *                              alone: BLEND = a OPAQUE + (1 - a) NONE within 1% per quad (the
 *                              blended quads cast no shadow, and the light behind them passes
 *                              by 1 - a), and the textured quad's alpha, solved per column from
 *                              that relation, rising from left to right.
 * Prints TAP. */
#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/io.h"

#define QUADS 7
#define EMITTER QUADS /* the area light's quad, in the area-lit scene alone */
#define FRONT_FIRST 2 /* quads 2..5 are the four in front */
#define FRONT_COUNT 4
#define TEXTURED 5
#define TEX_SIZE 8

/* Each quad: corners a (bottom left), b (bottom right), c (top right), d (top left), its normal,
 * base colour and alpha. */
struct quad {
    float p[4][3];
    float n[3];
    float color[3];
    float alpha;
};

static const struct quad quads[QUADS + 1] = {
    {{{-4, 0, 3}, {4, 0, 3}, {4, 0, -3}, {-4, 0, -3}},
     {0, 1, 0},
     {0.6f, 0.6f, 0.6f},
     1}, /* floor */
    {{{-4, 0, -2}, {4, 0, -2}, {4, 3, -2}, {-4, 3, -2}}, {0, 0, 1}, {0.5f, 0.55f, 0.6f}, 1},
    {{{-1.7f, 0.3f, 0}, {-1.0f, 0.3f, 0}, {-1.0f, 1.3f, 0}, {-1.7f, 1.3f, 0}},
     {0, 0, 1},
     {0.8f, 0.1f, 0.1f},
     0.25f},
    {{{-0.8f, 0.3f, 0}, {-0.1f, 0.3f, 0}, {-0.1f, 1.3f, 0}, {-0.8f, 1.3f, 0}},
     {0, 0, 1},
     {0.1f, 0.8f, 0.1f},
     0.5f},
    {{{0.1f, 0.3f, 0}, {0.8f, 0.3f, 0}, {0.8f, 1.3f, 0}, {0.1f, 1.3f, 0}},
     {0, 0, 1},
     {0.1f, 0.1f, 0.8f},
     0.75f},
    {{{1.0f, 0.3f, 0}, {1.7f, 0.3f, 0}, {1.7f, 1.3f, 0}, {1.0f, 1.3f, 0}},
     {0, 0, 1},
     {0.9f, 0.9f, 0.9f},
     1}, /* the alpha texture's */
    {{{-1.2f, 0.9f, -0.8f}, {-0.6f, 0.9f, -0.8f}, {-0.6f, 1.6f, -0.8f}, {-1.2f, 1.6f, -0.8f}},
     {0, 0, 1},
     {0.8f, 0.8f, 0.1f},
     0.5f},
    {{{-1.0f, 2.6f, 1.4f}, {1.0f, 2.6f, 1.4f}, {1.0f, 2.6f, 0.4f}, {-1.0f, 2.6f, 0.4f}},
     {0, -1, 0},
     {1, 1, 1},
     1}, /* the area light: emissive, facing down */
};

static int test_no, failures;

static void check(int ok, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void check(int ok, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    printf("%s %d - ", ok ? "ok" : "not ok", ++test_no);
    vprintf(fmt, ap);
    printf("\n");
    va_end(ap);
    if (!ok)
        failures++;
}

static void base64(const unsigned char *in, size_t n, char *out)
{
    static const char b64[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    size_t e = 0;
    for (size_t i = 0; i < n; i += 3) {
        unsigned v = (unsigned)in[i] << 16;
        if (i + 1 < n)
            v |= (unsigned)in[i + 1] << 8;
        if (i + 2 < n)
            v |= in[i + 2];
        out[e++] = b64[(v >> 18) & 63];
        out[e++] = b64[(v >> 12) & 63];
        out[e++] = i + 1 < n ? b64[(v >> 6) & 63] : '=';
        out[e++] = i + 2 < n ? b64[v & 63] : '=';
    }
    out[e] = '\0';
}

/* mode: "BLEND", "OPAQUE" or NULL (the four front quads absent); is_plain: the yellow quad
 * OPAQUE too, so that no material blends. */
static int write_scene(const char *dir, const char *name, const char *mode, bool is_plain,
                       bool is_area)
{
    /* Per quad: 4 positions, 4 normals, 4 uvs, 6 indices (uint16), in four bufferViews. */
    const int n = is_area ? QUADS + 1 : QUADS;
    const int POS = n * 4 * 12, NRM = POS, UV = n * 4 * 8, IDX = n * 12;
    static unsigned char buf[(QUADS + 1) * (4 * 12 * 2 + 4 * 8 + 12)];
    static char enc[4 * ((sizeof(buf) + 2) / 3) + 1];
    const size_t bytes = (size_t)(POS + NRM + UV + IDX);
    for (int q = 0; q < n; q++) {
        for (int v = 0; v < 4; v++) {
            memcpy(buf + (size_t)(q * 4 + v) * 12, quads[q].p[v], 12);
            memcpy(buf + POS + (size_t)(q * 4 + v) * 12, quads[q].n, 12);
            float uv[2] = {v == 1 || v == 2 ? 1.0f : 0.0f, v >= 2 ? 0.0f : 1.0f};
            memcpy(buf + POS + NRM + (size_t)(q * 4 + v) * 8, uv, 8);
        }
        static const uint16_t idx[6] = {0, 1, 2, 0, 2, 3};
        memcpy(buf + POS + NRM + UV + (size_t)q * 12, idx, 12);
    }
    base64(buf, bytes, enc);
    char path[4096];
    snprintf(path, sizeof(path), "%s/%s", dir, name);
    FILE *f = fopen(path, "w");
    if (!f) {
        perror(path);
        return 1;
    }
    fprintf(f, "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[");
    for (int q = 0, first = 1; q < n; q++) {
        if (!mode && q >= FRONT_FIRST && q < FRONT_FIRST + FRONT_COUNT)
            continue;
        fprintf(f, "%s%d", first ? "" : ",", q);
        first = 0;
    }
    fprintf(f, "]}],\"nodes\":[");
    for (int q = 0; q < n; q++)
        fprintf(f, "%s{\"mesh\":%d,\"name\":\"Quad%d\"}", q ? "," : "", q, q);
    fprintf(f, "],\"meshes\":[");
    for (int q = 0; q < n; q++)
        fprintf(f,
                "%s{\"primitives\":[{\"attributes\":{\"POSITION\":%d,\"NORMAL\":%d,"
                "\"TEXCOORD_0\":%d},\"indices\":%d,\"material\":%d}]}",
                q ? "," : "", q * 4, q * 4 + 1, q * 4 + 2, q * 4 + 3, q);
    fprintf(f, "],\"materials\":[");
    for (int q = 0; q < n; q++) {
        const struct quad *s = &quads[q];
        bool front = q >= FRONT_FIRST && q < FRONT_FIRST + FRONT_COUNT;
        const char *alpha_mode = q == QUADS - 1 && !is_plain ? "BLEND"
                                 : front && mode             ? mode
                                                             : "OPAQUE";
        fprintf(f,
                "%s{\"name\":\"M%d\",\"doubleSided\":true,\"alphaMode\":\"%s\","
                "\"pbrMetallicRoughness\":{\"baseColorFactor\":[%g,%g,%g,%g],"
                "\"metallicFactor\":0,\"roughnessFactor\":0.6%s}%s}",
                q ? "," : "", q, alpha_mode, (double)s->color[0], (double)s->color[1],
                (double)s->color[2], (double)s->alpha,
                q == TEXTURED ? ",\"baseColorTexture\":{\"index\":0}" : "",
                q == EMITTER ? ",\"emissiveFactor\":[1,0.9,0.8],\"extensions\":"
                               "{\"KHR_materials_emissive_strength\":{\"emissiveStrength\":6}}"
                             : "");
    }
    fprintf(
        f,
        "],\"textures\":[{\"source\":0,\"sampler\":0}],"
        "\"samplers\":[{\"magFilter\":9729,\"minFilter\":9987}],"
        "\"images\":[{\"uri\":\"alpha.png\"}],"
        "\"buffers\":[{\"byteLength\":%zu,\"uri\":\"data:application/octet-stream;base64,%s\"}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":%d},"
        "{\"buffer\":0,\"byteOffset\":%d,\"byteLength\":%d},"
        "{\"buffer\":0,\"byteOffset\":%d,\"byteLength\":%d},"
        "{\"buffer\":0,\"byteOffset\":%d,\"byteLength\":%d}],\"accessors\":[",
        bytes, enc, POS, POS, NRM, POS + NRM, UV, POS + NRM + UV, IDX);
    for (int q = 0; q < n; q++) {
        float lo[3], hi[3];
        for (int a = 0; a < 3; a++) {
            lo[a] = hi[a] = quads[q].p[0][a];
            for (int v = 1; v < 4; v++) {
                lo[a] = fminf(lo[a], quads[q].p[v][a]);
                hi[a] = fmaxf(hi[a], quads[q].p[v][a]);
            }
        }
        fprintf(f,
                "%s{\"bufferView\":0,\"byteOffset\":%d,\"componentType\":5126,\"count\":4,"
                "\"type\":\"VEC3\",\"min\":[%g,%g,%g],\"max\":[%g,%g,%g]},"
                "{\"bufferView\":1,\"byteOffset\":%d,\"componentType\":5126,\"count\":4,"
                "\"type\":\"VEC3\"},"
                "{\"bufferView\":2,\"byteOffset\":%d,\"componentType\":5126,\"count\":4,"
                "\"type\":\"VEC2\"},"
                "{\"bufferView\":3,\"byteOffset\":%d,\"componentType\":5123,\"count\":6,"
                "\"type\":\"SCALAR\"}",
                q ? "," : "", q * 48, (double)lo[0], (double)lo[1], (double)lo[2], (double)hi[0],
                (double)hi[1], (double)hi[2], q * 48, q * 32, q * 12);
    }
    fprintf(f, "]%s}\n",
            is_area ? ",\"extensionsUsed\":[\"KHR_materials_emissive_strength\"]" : "");
    return fclose(f) != 0;
}

/* The job of scene NAME: the same camera, and LIGHTING (the job's lights and environment): the
 * point light of the plain variants, or, for the area-lit one, none but the emissive quad and a
 * sky-blue environment. */
static const char *const POINT_LIT =
    "lights:\n"
    "  - {type: point, position: [0.5, 2.6, 2.2], color: [1, 1, 1], intensity: 15}\n"
    "environment: {color: [0, 0, 0]}\n";
static const char *const AREA_LIT = "environment: {color: [0.1, 0.13, 0.18]}\n";

static int write_job(const char *dir, const char *name, const char *lighting)
{
    char path[4096];
    snprintf(path, sizeof(path), "%s/%s.yaml", dir, name);
    FILE *f = fopen(path, "w");
    if (!f) {
        perror(path);
        return 1;
    }
    fprintf(f,
            "scene: %s.gltf\n"
            "output: %s/frame.####.exr\n"
            "resolution: [160, 100]\n"
            "frames: {start: 0, end: 0}\n"
            "camera:\n"
            "  fov_y_deg: 40\n"
            "  keys: [{t: 0, position: [0, 1.2, 4.5], look_at: [0, 0.8, -0.5]}]\n"
            "%s",
            name, name, lighting);
    return fclose(f) != 0;
}

static int write_alpha(const char *dir)
{
    uint8_t rgba[TEX_SIZE * TEX_SIZE * 4];
    for (int y = 0; y < TEX_SIZE; y++)
        for (int x = 0; x < TEX_SIZE; x++) {
            uint8_t *p = &rgba[(y * TEX_SIZE + x) * 4];
            p[0] = p[1] = p[2] = 255;
            p[3] = (uint8_t)lround(255.0 * (0.1 + 0.8 * (x + 0.5) / TEX_SIZE));
        }
    char path[4096];
    snprintf(path, sizeof(path), "%s/alpha.png", dir);
    struct rb_err err = RB_ERR_INIT;
    if (rb_io_png_write(path, TEX_SIZE, TEX_SIZE, rgba, &err)) {
        fprintf(stderr, "blendscene: %s\n", err.msg);
        return 1;
    }
    return 0;
}

static int write_all(const char *dir)
{
    return write_alpha(dir) || write_scene(dir, "blend.gltf", "BLEND", false, false) ||
           write_scene(dir, "opaque.gltf", "OPAQUE", false, false) ||
           write_scene(dir, "none.gltf", NULL, false, false) ||
           write_scene(dir, "plain.gltf", "OPAQUE", true, false) ||
           write_job(dir, "blend", POINT_LIT) || write_job(dir, "opaque", POINT_LIT) ||
           write_job(dir, "none", POINT_LIT) || write_job(dir, "plain", POINT_LIT);
}

static int write_area(const char *dir)
{
    return write_alpha(dir) || write_scene(dir, "area.gltf", "BLEND", false, true) ||
           write_scene(dir, "area-opaque.gltf", "OPAQUE", false, true) ||
           write_job(dir, "area", AREA_LIT) || write_job(dir, "area-opaque", AREA_LIT);
}

struct img {
    struct rb_io_image im;
    int r, g, b, albedo;
};

static int load(const char *path, struct img *out)
{
    struct rb_err err = RB_ERR_INIT;
    if (rb_io_image_read(path, &out->im, &err)) {
        fprintf(stderr, "blendscene: %s\n", err.msg);
        return 1;
    }
    out->r = rb_io_image_channel(&out->im, "R");
    out->g = rb_io_image_channel(&out->im, "G");
    out->b = rb_io_image_channel(&out->im, "B");
    out->albedo = rb_io_image_channel(&out->im, "albedo.R");
    if (out->r < 0 || out->g < 0 || out->b < 0) {
        fprintf(stderr, "blendscene: %s has no R, G, B\n", path);
        return 1;
    }
    return 0;
}

static float px(const struct img *m, uint32_t x, uint32_t y, int ch)
{
    return m->im.pixels[((size_t)y * m->im.width_px + x) * m->im.channel_count + (size_t)ch];
}

/* Whether pixel (x, y) of the opaque render shows quad q: its albedo is the quad's colour (the
 * white quad's texture is white), as the G-buffer writes it. */
static bool shows(const struct img *m, int x, int y, int q)
{
    if (x < 0 || y < 0 || x >= (int)m->im.width_px || y >= (int)m->im.height_px)
        return false;
    for (int c = 0; c < 3; c++)
        if (fabsf(px(m, (uint32_t)x, (uint32_t)y, m->albedo + c) - quads[q].color[c]) > 1e-3f)
            return false;
    return true;
}

static bool interior(const struct img *m, int x, int y, int q)
{
    return shows(m, x, y, q) && shows(m, x - 1, y, q) && shows(m, x + 1, y, q) &&
           shows(m, x, y - 1, q) && shows(m, x, y + 1, q);
}

static float lum(const struct img *m, uint32_t x, uint32_t y)
{
    return 0.2126f * px(m, x, y, m->r) + 0.7152f * px(m, x, y, m->g) + 0.0722f * px(m, x, y, m->b);
}

static int run_checks(bool exact, const char *bp, const char *op, const char *np)
{
    struct img b = {0}, o = {0}, n = {0};
    if (load(bp, &b) || load(op, &o) || load(np, &n))
        return 1;
    uint32_t w = o.im.width_px, h = o.im.height_px;
    if (o.albedo < 0 || b.im.width_px != w || n.im.width_px != w || b.im.height_px != h ||
        n.im.height_px != h) {
        fprintf(stderr, "blendscene: the renders differ in size, or %s has no albedo\n", op);
        return 1;
    }
    for (int q = FRONT_FIRST; q < FRONT_FIRST + FRONT_COUNT; q++) {
        double sb[3] = {0}, so[3] = {0}, sn[3] = {0};
        uint32_t count = 0, cx0 = w, cx1 = 0;
        for (uint32_t y = 0; y < h; y++)
            for (uint32_t x = 0; x < w; x++) {
                if (!interior(&o, (int)x, (int)y, q))
                    continue;
                count++;
                cx0 = x < cx0 ? x : cx0;
                cx1 = x > cx1 ? x : cx1;
                int ch[3] = {b.r, b.g, b.b};
                for (int c = 0; c < 3; c++) {
                    sb[c] += px(&b, x, y, ch[c]);
                    so[c] += px(&o, x, y, o.r + c);
                    sn[c] += px(&n, x, y, n.r + c);
                }
            }
        check(count >= 50, "quad %d covers %u interior pixels", q - FRONT_FIRST, count);
        if (count < 50)
            continue;
        double db = 0, dn = 0, dd = 0;
        for (int c = 0; c < 3; c++) {
            db += fabs(sb[c] - so[c]);
            dn += fabs(sb[c] - sn[c]);
            dd += sb[c];
        }
        printf("# quad %d: blended %.4g %.4g %.4g, opaque %.4g %.4g %.4g, absent %.4g %.4g %.4g "
               "(means)\n",
               q - FRONT_FIRST, sb[0] / count, sb[1] / count, sb[2] / count, so[0] / count,
               so[1] / count, so[2] / count, sn[0] / count, sn[1] / count, sn[2] / count);
        check(dn > 0.05 * dd, "quad %d shows: blended differs from absent by %.3g of its light",
              q - FRONT_FIRST, dn / dd);
        check(db > 0.05 * dd, "quad %d is not opaque: blended differs from opaque by %.3g",
              q - FRONT_FIRST, db / dd);
        if (!exact)
            continue;
        if (q != TEXTURED) {
            double a = quads[q].alpha, worst = 0;
            for (int c = 0; c < 3; c++) {
                double want = a * so[c] + (1 - a) * sn[c];
                double e = fabs(sb[c] - want) / (want > 1e-6 ? want : 1e-6);
                worst = e > worst ? e : worst;
            }
            check(worst < 0.01, "quad %d: blended = %g opaque + %g absent within 1%% (%.3g)",
                  q - FRONT_FIRST, a, 1 - a, worst);
            continue;
        }
        /* The alpha texture: a = (blended - absent) / (opaque - absent) in the left and the
         * right third of the quad. */
        double al[2] = {0, 0};
        for (int side = 0; side < 2; side++) {
            double nb = 0, no = 0, nn = 0;
            uint32_t third = (cx1 - cx0) / 3;
            uint32_t x0 = side ? cx1 - third : cx0, x1 = side ? cx1 : cx0 + third;
            for (uint32_t y = 0; y < h; y++)
                for (uint32_t x = x0; x <= x1; x++)
                    if (interior(&o, (int)x, (int)y, q)) {
                        nb += lum(&b, x, y);
                        no += lum(&o, x, y);
                        nn += lum(&n, x, y);
                    }
            al[side] = fabs(no - nn) > 0 ? (nb - nn) / (no - nn) : -1;
        }
        check(al[0] > 0.05 && al[0] < 0.5 && al[1] > 0.5 && al[1] < 0.95 && al[1] > al[0] + 0.3,
              "the textured quad's alpha rises from %.3g (left third) to %.3g (right third)", al[0],
              al[1]);
    }
    rb_io_image_release(&b.im);
    rb_io_image_release(&o.im);
    rb_io_image_release(&n.im);
    return 0;
}

/* A mask of the four front quads' interior pixels in the opaque render op (white; black
 * elsewhere), for raybundle compare --mask: the error of the blended layers alone. */
static int write_mask(const char *op, const char *out)
{
    struct img o = {0};
    if (load(op, &o))
        return 1;
    if (o.albedo < 0) {
        fprintf(stderr, "blendscene: %s has no albedo\n", op);
        return 1;
    }
    uint32_t w = o.im.width_px, h = o.im.height_px, count = 0;
    uint8_t *rgba = calloc((size_t)w * h, 4);
    if (!rgba)
        return 1;
    for (uint32_t y = 0; y < h; y++)
        for (uint32_t x = 0; x < w; x++) {
            uint8_t *p = &rgba[((size_t)y * w + x) * 4];
            p[3] = 255;
            for (int q = FRONT_FIRST; q < FRONT_FIRST + FRONT_COUNT; q++)
                if (interior(&o, (int)x, (int)y, q)) {
                    p[0] = p[1] = p[2] = 255;
                    count++;
                }
        }
    struct rb_err err = RB_ERR_INIT;
    int rc = 0;
    if (count < 200) {
        fprintf(stderr, "blendscene: only %u quad pixels in %s\n", count, op);
        rc = 1;
    } else if (rb_io_png_write(out, w, h, rgba, &err)) {
        fprintf(stderr, "blendscene: %s\n", err.msg);
        rc = 1;
    }
    free(rgba);
    rb_io_image_release(&o.im);
    return rc;
}

int main(int argc, char **argv)
{
    if (argc == 3 && !strcmp(argv[1], "scene"))
        return write_all(argv[2]);
    if (argc == 3 && !strcmp(argv[1], "area"))
        return write_area(argv[2]);
    if (argc == 4 && !strcmp(argv[1], "mask"))
        return write_mask(argv[2], argv[3]);
    if (argc == 5 && (!strcmp(argv[1], "show") || !strcmp(argv[1], "exact"))) {
        if (run_checks(!strcmp(argv[1], "exact"), argv[2], argv[3], argv[4]))
            return 1;
        printf("1..%d\n", test_no);
        return failures ? 1 : 0;
    }
    fprintf(stderr, "usage: blendscene scene|area DIR\n"
                    "       blendscene show|exact BLEND.exr OPAQUE.exr NONE.exr\n"
                    "       blendscene mask OPAQUE.exr OUT.png\n");
    return 2;
}
