/* pixels IMAGE X Y: prints the colour of pixel (X, Y) as rrggbb (8 bits a channel).
 * pixels IMAGE X Y W H RRGGBB: prints how many pixels of the W x H rectangle at (X, Y) have that
 * colour, each channel within 3/255. For tests that look at a screenshot. Exit 1 when the file
 * cannot be read or the rectangle leaves the image, 2 on bad usage. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "io/io.h"

/* Channel c of pixel (x, y) in 0..255 (an image with one channel is grey). */
static long byte_at(const struct rb_io_image *img, long x, long y, int c)
{
    uint32_t ch = img->channel_count < 3 ? 0 : (uint32_t)c;
    float v = img->pixels[((size_t)y * img->width_px + (size_t)x) * img->channel_count + ch];
    return lroundf(v * 255.0f);
}

int main(int argc, char **argv)
{
    if (argc != 4 && argc != 7) {
        fprintf(stderr, "usage: pixels IMAGE X Y [W H RRGGBB]\n");
        return 2;
    }
    long x = strtol(argv[2], NULL, 10), y = strtol(argv[3], NULL, 10), w = 1, h = 1;
    unsigned long want = 0;
    if (argc == 7) {
        char *end = NULL;
        w = strtol(argv[4], NULL, 10);
        h = strtol(argv[5], NULL, 10);
        want = strtoul(argv[6], &end, 16);
        if (*end || end - argv[6] != 6 || w < 1 || h < 1) {
            fprintf(stderr, "pixels: bad rectangle or colour\n");
            return 2;
        }
    }
    struct rb_io_image img = {0};
    struct rb_err err = RB_ERR_INIT;
    if (rb_io_image_read(argv[1], &img, &err)) {
        fprintf(stderr, "pixels: %s\n", err.msg);
        return 1;
    }
    int rc = 0;
    if (x < 0 || y < 0 || x + w > (long)img.width_px || y + h > (long)img.height_px) {
        fprintf(stderr, "pixels: %ldx%ld at (%ld, %ld) leaves the %ux%u image\n", w, h, x, y,
                img.width_px, img.height_px);
        rc = 1;
    } else if (argc == 4) {
        printf("%02lx%02lx%02lx\n", byte_at(&img, x, y, 0), byte_at(&img, x, y, 1),
               byte_at(&img, x, y, 2));
    } else {
        long count = 0;
        for (long j = y; j < y + h; j++)
            for (long i = x; i < x + w; i++) {
                bool is_same = true;
                for (int c = 0; c < 3; c++)
                    is_same = is_same && labs(byte_at(&img, i, j, c) -
                                              (long)((want >> (16 - 8 * c)) & 255)) <= 3;
                count += is_same;
            }
        printf("%ld\n", count);
    }
    rb_io_image_release(&img);
    return rc;
}
