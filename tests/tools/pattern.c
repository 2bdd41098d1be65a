/* pattern EXR LAYER N: how strongly an image shows the N x N grid of interleaved sampling (seed
 * 000, A.1), where each class of pixels (x mod N, y mod N) has its own samples. For every pixel
 * inside a surface (every pixel within R = N of it has a normal within acos 0.95 of its own and
 * a depth within 5% of its own, from the file's normal and depth layers) and not in the dark
 * (its local mean above a tenth of the median), its relative departure from the local mean of
 * LAYER's luminance, (L - m) / m, m the mean over the (2R + 1)^2 pixels around it weighted so
 * that every class counts the same (so m does not contain the grid it measures); then the
 * median departure of each class. A grid moves every pixel of a class, and so its median; a
 * shadow's edge moves the few pixels beside it a long way, which would swing a mean by where
 * the edge falls among the classes, but not the median. A smooth image has every class median
 * near 0 (a linear gradient cancels). Prints the spread (largest class median minus smallest)
 * as "pattern SPREAD", then the N x N class medians in percent, and the fraction of the pixels
 * measured. LAYER "" is the beauty (R, G, B). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/io.h"

/* The channel LAYER.NAME, or NAME for the beauty. */
static int channel(const struct rb_io_image *img, const char *layer, const char *name)
{
    char full[64];
    snprintf(full, sizeof(full), "%s%s%s", layer, *layer ? "." : "", name);
    return rb_io_image_channel(img, full);
}

/* The weight of offset d along one axis of a window of radius r over n classes: one over how
 * many of the window's offsets share d's class. */
static double axis_weight(int d, int r, int n)
{
    int rho = ((d % n) + n) % n, count = 0;
    for (int e = -r; e <= r; e++)
        count += ((e % n) + n) % n == rho;
    return 1.0 / count;
}

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(int argc, char **argv)
{
    if (argc != 4) {
        fprintf(stderr, "usage: pattern EXR LAYER N\n");
        return 2;
    }
    const char *layer = argv[2];
    int n = atoi(argv[3]);
    if (n < 1 || n > 8) {
        fprintf(stderr, "pattern: N must be 1 to 8\n");
        return 2;
    }
    struct rb_io_image img = {0};
    struct rb_err err = RB_ERR_INIT;
    if (rb_io_image_read(argv[1], &img, &err)) {
        fprintf(stderr, "pattern: %s\n", err.msg);
        return 1;
    }
    int c[3] = {channel(&img, layer, "R"), channel(&img, layer, "G"), channel(&img, layer, "B")};
    int nx = rb_io_image_channel(&img, "normal.X"), ny = rb_io_image_channel(&img, "normal.Y");
    int nz = rb_io_image_channel(&img, "normal.Z"), z = rb_io_image_channel(&img, "depth.Z");
    if (c[0] < 0 || c[1] < 0 || c[2] < 0 || nx < 0 || ny < 0 || nz < 0 || z < 0) {
        fprintf(stderr, "pattern: '%s' lacks layer '%s' (R, G, B), normal or depth\n", argv[1],
                layer);
        return 1;
    }
    int w = (int)img.width_px, h = (int)img.height_px, r = n;
    size_t count = (size_t)w * h;
    double *lum = malloc(sizeof(double) * count), *mean = calloc(count, sizeof(double));
    unsigned char *inside = calloc(count, 1);
    double *means = malloc(sizeof(double) * count);
    if (!lum || !mean || !inside || !means)
        return 1;
#define AT(x, y, ch) img.pixels[((size_t)(y)*w + (x)) * img.channel_count + (size_t)(ch)]
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            lum[(size_t)y * w + x] = (AT(x, y, c[0]) + AT(x, y, c[1]) + AT(x, y, c[2])) / 3.0;
    size_t measured = 0;
    for (int y = r; y < h - r; y++)
        for (int x = r; x < w - r; x++) {
            double zp = AT(x, y, z), sum = 0.0, weight = 0.0;
            bool ok = zp > 0.0;
            for (int dy = -r; dy <= r && ok; dy++)
                for (int dx = -r; dx <= r && ok; dx++) {
                    int qx = x + dx, qy = y + dy;
                    double dot = AT(x, y, nx) * AT(qx, qy, nx) + AT(x, y, ny) * AT(qx, qy, ny) +
                                 AT(x, y, nz) * AT(qx, qy, nz);
                    ok = dot > 0.95 && fabs(AT(qx, qy, z) - zp) <= 0.05 * zp;
                    double wq = axis_weight(dx, r, n) * axis_weight(dy, r, n);
                    sum += wq * lum[(size_t)qy * w + qx];
                    weight += wq;
                }
            if (ok) {
                inside[(size_t)y * w + x] = 1;
                mean[(size_t)y * w + x] = sum / weight;
                means[measured++] = sum / weight;
            }
        }
    double median = 0.0;
    if (measured) {
        qsort(means, measured, sizeof(double), compare_doubles);
        median = means[measured / 2];
    }
    /* each class's departures, then their medians */
    double *dep[64];
    size_t dep_count[64] = {0}, used = 0;
    for (int k = 0; k < n * n; k++)
        if (!(dep[k] = malloc(sizeof(double) * (count / (size_t)(n * n) + (size_t)w + 1))))
            return 1;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            size_t i = (size_t)y * w + x;
            if (!inside[i] || !(mean[i] > 0.1 * median))
                continue;
            int k = (y % n) * n + x % n;
            dep[k][dep_count[k]++] = (lum[i] - mean[i]) / mean[i];
            used++;
        }
    double class_median[64] = {0}, lo = INFINITY, hi = -INFINITY;
    for (int k = 0; k < n * n; k++) {
        if (dep_count[k]) {
            qsort(dep[k], dep_count[k], sizeof(double), compare_doubles);
            class_median[k] = dep[k][dep_count[k] / 2];
        }
        lo = fmin(lo, class_median[k]);
        hi = fmax(hi, class_median[k]);
        free(dep[k]);
    }
    if (!used) {
        fprintf(stderr, "pattern: no pixel of '%s' lies inside a lit surface\n", argv[1]);
        return 1;
    }
    printf("pattern %.6f\n", hi - lo);
    for (int y = 0; y < n; y++) {
        for (int x = 0; x < n; x++)
            printf("%s%+.3f", x ? " " : "# ", 100.0 * class_median[y * n + x]);
        printf("\n");
    }
    printf("# measured %.3f of the pixels\n", (double)used / (double)count);
    free(lum);
    free(mean);
    free(inside);
    free(means);
    rb_io_image_release(&img);
    return 0;
}
