/* layersum EXR TOLERANCE SUM PART...: checks that RGB layer SUM is the sum of the PART layers,
 * channel by channel and pixel by pixel, within TOLERANCE relative to SUM (the sum is formed in
 * double). Prints each layer's total over every pixel and channel and how many of its values are
 * non-zero, then the largest relative error, so shell tests can weigh the parts. Exit 1 when a
 * pixel is off, or the file or a channel is missing; 2 on bad usage. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "io/io.h"

#define MAX_LAYERS 8

int main(int argc, char **argv)
{
    if (argc < 5 || argc - 3 > MAX_LAYERS) {
        fprintf(stderr, "usage: layersum EXR TOLERANCE SUM PART...\n");
        return 2;
    }
    double tol = atof(argv[2]);
    struct rb_io_image img = {0};
    struct rb_err err = RB_ERR_INIT;
    if (rb_io_image_read(argv[1], &img, &err)) {
        fprintf(stderr, "layersum: %s\n", err.msg);
        return 1;
    }
    int layer_count = argc - 3, ch[MAX_LAYERS][3];
    for (int l = 0; l < layer_count; l++) {
        for (int c = 0; c < 3; c++) {
            char name[256];
            snprintf(name, sizeof(name), "%s.%c", argv[3 + l], "RGB"[c]);
            ch[l][c] = rb_io_image_channel(&img, name);
            if (ch[l][c] < 0) {
                fprintf(stderr, "layersum: no channel '%s' in %s\n", name, argv[1]);
                rb_io_image_release(&img);
                return 1;
            }
        }
    }
    size_t n = (size_t)img.width_px * img.height_px, off = 0;
    double total[MAX_LAYERS] = {0}, worst = 0.0;
    size_t nonzero[MAX_LAYERS] = {0}, worst_at = 0;
    for (size_t i = 0; i < n; i++) {
        const float *p = img.pixels + i * img.channel_count;
        for (int c = 0; c < 3; c++) {
            double want = p[ch[0][c]], sum = 0.0;
            for (int l = 0; l < layer_count; l++) {
                double v = p[ch[l][c]];
                total[l] += v;
                nonzero[l] += v != 0.0;
                sum += l ? v : 0.0;
            }
            double e = fabs(sum - want), rel = e == 0.0 ? 0.0 : e / fabs(want);
            off += !(rel <= tol);
            if (!(rel <= worst)) {
                worst = rel;
                worst_at = i;
            }
        }
    }
    for (int l = 0; l < layer_count; l++)
        printf("%s total %.9g nonzero %zu\n", argv[3 + l], total[l], nonzero[l]);
    printf("max relative error %.3g\n", worst);
    if (off)
        fprintf(stderr,
                "layersum: %zu values of '%s' are not the sum of the parts (pixel %zu,%zu)\n", off,
                argv[3], worst_at % img.width_px, worst_at / img.width_px);
    rb_io_image_release(&img);
    return off ? 1 : 0;
}
