/* hitband HITS FRAME RADIUS: the hit ratio around what moves and away from it. FRAME's motion
 * layer marks the pixels that move (|motion| above a hundredth of a pixel, with a static camera
 * the pixels of moving objects, which reprojection follows); the band is every pixel that does
 * not move within RADIUS pixels of one (the ring around a moving object, which it uncovers and
 * covers), "away" every pixel farther than 2 RADIUS. Prints "band MEAN N away MEAN N" (the mean of
 * the HITS image's first channel and the pixel count); exit 1 when a file cannot be read, the sizes
 * differ, FRAME has no motion layer or either set is empty, 2 on bad usage. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "io/io.h"

int main(int argc, char **argv)
{
    if (argc != 4) {
        fprintf(stderr, "usage: hitband HITS FRAME RADIUS\n");
        return 2;
    }
    struct rb_io_image hits = {0}, frame = {0};
    struct rb_err err = RB_ERR_INIT;
    if (rb_io_image_read(argv[1], &hits, &err) || rb_io_image_read(argv[2], &frame, &err)) {
        printf("cannot read: %s\n", err.msg);
        rb_io_image_release(&hits);
        return 1;
    }
    long r = atol(argv[3]), w = (long)frame.width_px, h = (long)frame.height_px;
    int mx = rb_io_image_channel(&frame, "motion.X"), my = rb_io_image_channel(&frame, "motion.Y");
    int st = 1;
    unsigned char *moving = calloc((size_t)(w * h) + 1, 1);
    if (mx < 0 || my < 0 || !moving || hits.width_px != frame.width_px ||
        hits.height_px != frame.height_px) {
        printf("no motion layer, or the sizes differ\n");
        goto out;
    }
    for (long i = 0; i < w * h; i++) {
        const float *p = &frame.pixels[i * frame.channel_count];
        moving[i] = hypotf(p[mx], p[my]) > 0.01f;
    }
    double sum[2] = {0, 0};
    long count[2] = {0, 0};
    for (long y = 0; y < h; y++)
        for (long x = 0; x < w; x++) {
            long nearest = 1L << 30; /* the distance to the nearest moving pixel, in pixels */
            for (long dy = -2 * r; dy <= 2 * r; dy++)
                for (long dx = -2 * r; dx <= 2 * r; dx++) {
                    long qx = x + dx, qy = y + dy;
                    if (qx >= 0 && qy >= 0 && qx < w && qy < h && moving[qy * w + qx]) {
                        long d = (long)ceil(sqrt((double)(dx * dx + dy * dy)));
                        nearest = d < nearest ? d : nearest;
                    }
                }
            int set = nearest > 2 * r ? 1 : nearest <= r && !moving[y * w + x] ? 0 : -1;
            if (set >= 0) {
                sum[set] += hits.pixels[(y * w + x) * hits.channel_count];
                count[set]++;
            }
        }
    printf("band %.4f %ld away %.4f %ld\n", count[0] ? sum[0] / count[0] : 0.0, count[0],
           count[1] ? sum[1] / count[1] : 0.0, count[1]);
    st = !count[0] || !count[1];
out:
    free(moving);
    rb_io_image_release(&hits);
    rb_io_image_release(&frame);
    return st;
}
