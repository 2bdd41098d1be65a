/* PNG through libpng (png_codec.h). libpng reports errors by longjmp from its error callback;
 * each entry point sets the jump with setjmp and keeps the message the callback wrote. */
#include "io/png_codec.h"

#include <png.h>
#include <setjmp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct codec_error {
    char text[200];
};

static void on_error(png_structp png, png_const_charp text)
{
    struct codec_error *e = png_get_error_ptr(png);
    snprintf(e->text, sizeof(e->text), "%s", text ? text : "unknown libpng error");
    png_longjmp(png, 1);
}

static void on_warning(png_structp png, png_const_charp text)
{
    (void)png;
    (void)text; /* libpng's warnings (e.g. a known-incorrect sRGB profile) do not stop us */
}

bool rb_png_is_png(const char *path)
{
    unsigned char sig[8];
    FILE *f = path ? fopen(path, "rb") : NULL;
    if (!f)
        return false;
    bool is = fread(sig, 1, sizeof(sig), f) == sizeof(sig) && !png_sig_cmp(sig, 0, sizeof(sig));
    fclose(f);
    return is;
}

const char *rb_png_version(void)
{
    return PNG_LIBPNG_VER_STRING;
}

/* ---- encoding --------------------------------------------------------------------------- */

struct growing {
    unsigned char *bytes;
    size_t size, cap;
    bool is_oom;
};

static void write_bytes(png_structp png, png_bytep data, size_t n)
{
    struct growing *g = png_get_io_ptr(png);
    if (g->is_oom)
        return;
    if (g->size + n > g->cap) {
        size_t cap = g->cap ? g->cap : 4096;
        while (cap < g->size + n)
            cap *= 2;
        unsigned char *b = realloc(g->bytes, cap);
        if (!b) {
            g->is_oom = true;
            return;
        }
        g->bytes = b;
        g->cap = cap;
    }
    memcpy(g->bytes + g->size, data, n);
    g->size += n;
}

static void flush_bytes(png_structp png)
{
    (void)png;
}

bool rb_png_encode(const uint8_t *rgba, uint32_t width_px, uint32_t height_px, const char *software,
                   void **out, size_t *size, char *msg, size_t msg_size)
{
    struct codec_error e = {{0}};
    /* volatile: changed between setjmp and a longjmp back to it. */
    struct growing *volatile g = calloc(1, sizeof(*g));
    png_bytep *volatile rows = calloc(height_px ? height_px : 1, sizeof(png_bytep));
    png_structp png = NULL;
    png_infop info = NULL;
    volatile bool ok = false;

    if (!g || !rows) {
        snprintf(msg, msg_size, "out of memory");
        goto out;
    }
    png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &e, on_error, on_warning);
    info = png ? png_create_info_struct(png) : NULL;
    if (!info) {
        snprintf(msg, msg_size, "out of memory");
        goto out;
    }
    if (setjmp(png_jmpbuf(png))) {
        snprintf(msg, msg_size, "%s", e.text);
        goto out;
    }
    png_set_write_fn(png, g, write_bytes, flush_bytes);
    png_set_IHDR(png, info, width_px, height_px, 8, PNG_COLOR_TYPE_RGBA, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_text text = {.compression = PNG_TEXT_COMPRESSION_NONE,
                     .key = "Software",
                     .text = (png_charp)(software ? software : "")};
    png_set_text(png, info, &text, 1);
    for (uint32_t y = 0; y < height_px; y++)
        rows[y] = (png_bytep)rgba + (size_t)y * width_px * 4;
    png_set_rows(png, info, rows);
    png_write_png(png, info, PNG_TRANSFORM_IDENTITY, NULL);
    if (g->is_oom) {
        snprintf(msg, msg_size, "out of memory for the encoded image");
        goto out;
    }
    *out = g->bytes;
    *size = g->size;
    g->bytes = NULL;
    ok = true;
out:
    if (png)
        png_destroy_write_struct(&png, info ? &info : NULL);
    if (g)
        free(g->bytes);
    free(g);
    free(rows);
    return ok;
}

/* ---- decoding --------------------------------------------------------------------------- */

/* A byte count in powers of 1000 to three figures: "6.4 GB", "1.07 GB", "512 kB". */
static void bytes_text(uint64_t n, char *out, size_t size)
{
    static const char *const units[] = {"bytes", "kB", "MB", "GB", "TB"};
    double v = (double)n;
    int u = 0;
    while (v >= 1000.0 && u < 4) {
        v /= 1000.0;
        u++;
    }
    snprintf(out, size, u ? "%.3g %s" : "%.0f %s", v, units[u]);
}

/* One row of n-channel samples of depth bits as floats. */
static void row_to_floats(const unsigned char *r, size_t count, int depth, float *out)
{
    for (size_t i = 0; i < count; i++)
        out[i] = depth == 8 ? r[i] / 255.0f : ((r[2 * i] << 8) | r[2 * i + 1]) / 65535.0f;
}

bool rb_png_decode(const char *path, uint32_t *width_px, uint32_t *height_px,
                   uint32_t *channel_count, float **pixels, char *msg, size_t msg_size)
{
    struct codec_error e = {{0}};
    FILE *f = fopen(path, "rb");
    png_structp png = NULL;
    png_infop info = NULL;
    unsigned char *volatile raw = NULL;
    png_bytep *volatile rows = NULL;
    float *volatile values = NULL;
    volatile bool ok = false;

    if (!f) {
        snprintf(msg, msg_size, "cannot open");
        return false;
    }
    png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &e, on_error, on_warning);
    info = png ? png_create_info_struct(png) : NULL;
    if (!info) {
        snprintf(msg, msg_size, "out of memory");
        goto out;
    }
    if (setjmp(png_jmpbuf(png))) {
        snprintf(msg, msg_size, "%s", e.text);
        goto out;
    }
    png_init_io(png, f);
    png_read_info(png, info);
    /* Palettes become RGB(A), low-bit gray becomes 8 bits, tRNS becomes alpha; 16-bit samples
     * come most significant byte first, as stored. */
    png_set_expand(png);
    int passes = png_set_interlace_handling(png);
    png_read_update_info(png, info);

    uint32_t w = png_get_image_width(png, info), h = png_get_image_height(png, info);
    uint32_t n = png_get_channels(png, info);
    int depth = png_get_bit_depth(png, info);
    size_t row_bytes = png_get_rowbytes(png, info);
    if (!w || !h || n < 1 || n > 4 || (depth != 8 && depth != 16)) {
        snprintf(msg, msg_size, "unsupported PNG layout (%u channels, %d bits)", n, depth);
        goto out;
    }
    /* Bounded by the size the header declares, before anything is allocated or inflated: the
     * limit of the glTF loader's decoder (stb_image's, lib/scene/gltf_shim.cpp), 2^30 samples
     * (width x height x channels), a 4.3 GB image of floats at most. */
    uint64_t samples = (uint64_t)w * h * n;
    if (samples > RB_PNG_MAX_SAMPLES) {
        char size_text[32], limit_text[32];
        bytes_text(samples, size_text, sizeof(size_text));
        bytes_text(RB_PNG_MAX_SAMPLES, limit_text, sizeof(limit_text));
        if (strcmp(size_text, limit_text) == 0) { /* just past it: the exact counts */
            snprintf(size_text, sizeof(size_text), "%llu bytes", (unsigned long long)samples);
            snprintf(limit_text, sizeof(limit_text), "%llu bytes", RB_PNG_MAX_SAMPLES);
        }
        snprintf(msg, msg_size,
                 "the PNG is %u x %u pixels of %u channel%s (%s), too large: the decoder takes "
                 "at most %s (width x height x channels)",
                 w, h, n, n == 1 ? "" : "s", size_text, limit_text);
        goto out;
    }
    values = malloc(samples * sizeof(float));
    /* An interlaced image is read whole, in its passes; any other a row at a time into one row's
     * bytes, so that the bytes as stored are never held beside the floats. */
    raw = malloc(passes > 1 ? row_bytes * h : row_bytes);
    rows = passes > 1 ? malloc(h * sizeof(png_bytep)) : NULL;
    if (!raw || !values || (passes > 1 && !rows)) {
        snprintf(msg, msg_size, "out of memory for %u x %u pixels of %u channels", w, h, n);
        goto out;
    }
    if (passes > 1) {
        for (uint32_t y = 0; y < h; y++)
            rows[y] = raw + y * row_bytes;
        png_read_image(png, rows);
        for (uint32_t y = 0; y < h; y++)
            row_to_floats(rows[y], (size_t)w * n, depth, values + (size_t)y * w * n);
    } else {
        for (uint32_t y = 0; y < h; y++) {
            png_read_row(png, raw, NULL);
            row_to_floats(raw, (size_t)w * n, depth, values + (size_t)y * w * n);
        }
    }
    png_read_end(png, NULL);
    *width_px = w;
    *height_px = h;
    *channel_count = n;
    *pixels = values;
    values = NULL;
    ok = true;
out:
    if (png)
        png_destroy_read_struct(&png, info ? &info : NULL, NULL);
    fclose(f);
    free(raw);
    free(rows);
    free(values);
    return ok;
}

const char *rb_png_channel_name(uint32_t channel_count, uint32_t i)
{
    static const char *const gray[2] = {"Y", "A"}, *const color[4] = {"R", "G", "B", "A"};
    if (channel_count <= 2)
        return i < channel_count ? gray[i] : "";
    return i < channel_count ? color[i] : "";
}
