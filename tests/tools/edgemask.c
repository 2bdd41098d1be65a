/* edgemask REF.exr MASK.exr RADIUS THRESHOLD: writes a mask (R = 1: compare, 0: skip) that
 * excludes every pixel within RADIUS pixels of a radiance discontinuity in REF's beauty: a pixel
 * whose luminance departs from the mean of its two neighbours along x or y by more than
 * THRESHOLD relative (a second difference, so smooth falloff is not an edge; a step is). Shadow-map
 * filtering (16-tap PCF) moves and softens exactly those edges, so GPU-versus-reference agreement
 * is measured away from them; the fraction excluded is printed so the bound is explicit. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "io/io.h"

int main(int argc, char **argv)
{
    if (argc != 5) {
        fprintf(stderr, "usage: edgemask REF.exr MASK.exr RADIUS THRESHOLD\n");
        return 2;
    }
    struct rb_io_image img = {0};
    struct rb_err err = RB_ERR_INIT;
    if (rb_io_image_read(argv[1], &img, &err)) {
        fprintf(stderr, "edgemask: %s\n", err.msg);
        return 1;
    }
    int radius = atoi(argv[3]);
    double thresh = atof(argv[4]);
    int w = (int)img.width_px, h = (int)img.height_px;
    int r = rb_io_image_channel(&img, "R"), g = rb_io_image_channel(&img, "G");
    int b = rb_io_image_channel(&img, "B");
    if (r < 0 || g < 0 || b < 0) {
        fprintf(stderr, "edgemask: '%s' has no R, G, B\n", argv[1]);
        return 1;
    }
    double *lum = malloc(sizeof(double) * (size_t)w * h);
    unsigned char *edge = calloc((size_t)w * h, 1);
    float *mask = malloc(sizeof(float) * (size_t)w * h);
    if (!lum || !edge || !mask)
        return 1;
    for (int i = 0; i < w * h; i++) {
        const float *p = &img.pixels[(size_t)i * img.channel_count];
        lum[i] = (p[r] + p[g] + p[b]) / 3.0;
    }
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double a = lum[y * w + x];
            int axes[2][2][2] = {{{x - 1, y}, {x + 1, y}}, {{x, y - 1}, {x, y + 1}}};
            for (int k = 0; k < 2; k++) {
                int x0 = axes[k][0][0], y0 = axes[k][0][1], x1 = axes[k][1][0], y1 = axes[k][1][1];
                /* at the image border, the missing neighbour mirrors the present one */
                if (x0 < 0 || y0 < 0)
                    x0 = x1, y0 = y1;
                if (x1 >= w || y1 >= h)
                    x1 = x0, y1 = y0;
                if (x0 < 0 || y0 < 0 || x1 >= w || y1 >= h)
                    continue;
                double l0 = lum[y0 * w + x0], l1 = lum[y1 * w + x1];
                double peak = fmax(fmax(a, l0), fmax(l1, 1e-3));
                if (fabs(a - 0.5 * (l0 + l1)) > thresh * peak)
                    edge[y * w + x] = 1;
            }
        }
    size_t excluded = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            int near = 0;
            for (int dy = -radius; dy <= radius && !near; dy++)
                for (int dx = -radius; dx <= radius && !near; dx++) {
                    int nx = x + dx, ny = y + dy;
                    near = nx >= 0 && ny >= 0 && nx < w && ny < h && edge[ny * w + nx];
                }
            mask[y * w + x] = near ? 0.0f : 1.0f;
            excluded += near;
        }
    static const char *const names[] = {"R"};
    /* One channel, "mask.R": the first channel is what `compare --mask` reads. */
    struct rb_io_layer layer = {
        .name = "mask", .channel_count = 1, .channel_names = names, .pixels = mask};
    if (rb_io_exr_write(argv[2], img.width_px, img.height_px, &layer, 1, NULL, 0, &err)) {
        fprintf(stderr, "edgemask: %s\n", err.msg);
        return 1;
    }
    printf("%.6f\n", (double)excluded / ((double)w * h));
    free(lum);
    free(edge);
    free(mask);
    rb_io_image_release(&img);
    return 0;
}
