/* samebits A B: compares two images value by value, bit for bit (the metadata, which names the
 * frame, is not compared). Prints how many values differ; exit 0 when none does and the two have
 * the same size and channels, 1 otherwise, 2 on bad usage. */
#include <stdio.h>
#include <string.h>

#include "io/io.h"

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: samebits A B\n");
        return 2;
    }
    struct rb_io_image a = {0}, b = {0};
    struct rb_err err = RB_ERR_INIT;
    if (rb_io_image_read(argv[1], &a, &err) || rb_io_image_read(argv[2], &b, &err)) {
        printf("cannot read: %s\n", err.msg);
        rb_io_image_release(&a);
        return 1;
    }
    int st = 0;
    if (a.width_px != b.width_px || a.height_px != b.height_px ||
        a.channel_count != b.channel_count) {
        printf("%ux%u with %u channels against %ux%u with %u\n", a.width_px, a.height_px,
               a.channel_count, b.width_px, b.height_px, b.channel_count);
        st = 1;
    } else {
        size_t n = (size_t)a.width_px * a.height_px * a.channel_count, differ = 0;
        for (size_t i = 0; i < n; i++)
            differ += memcmp(&a.pixels[i], &b.pixels[i], sizeof(float)) != 0;
        printf("%zu of %zu values differ\n", differ, n);
        st = differ != 0;
    }
    rb_io_image_release(&a);
    rb_io_image_release(&b);
    return st;
}
