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
    png_set_interlace_handling(png);
    png_read_update_info(png, info);

    uint32_t w = png_get_image_width(png, info), h = png_get_image_height(png, info);
    uint32_t n = png_get_channels(png, info);
    int depth = png_get_bit_depth(png, info);
    size_t row_bytes = png_get_rowbytes(png, info);
    if (!w || !h || n < 1 || n > 4 || (depth != 8 && depth != 16)) {
        snprintf(msg, msg_size, "unsupported PNG layout (%u channels, %d bits)", n, depth);
        goto out;
    }
    raw = malloc(row_bytes * h);
    rows = malloc(h * sizeof(png_bytep));
    values = malloc((size_t)w * h * n * sizeof(float));
    if (!raw || !rows || !values) {
        snprintf(msg, msg_size, "out of memory");
        goto out;
    }
    for (uint32_t y = 0; y < h; y++)
        rows[y] = raw + y * row_bytes;
    png_read_image(png, rows);
    png_read_end(png, NULL);
    for (uint32_t y = 0; y < h; y++) {
        const unsigned char *r = rows[y];
        for (size_t i = 0; i < (size_t)w * n; i++) {
            float v = depth == 8 ? r[i] / 255.0f : ((r[2 * i] << 8) | r[2 * i + 1]) / 65535.0f;
            values[(size_t)y * w * n + i] = v;
        }
    }
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
