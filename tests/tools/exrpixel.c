/* exrpixel EXR X Y CHANNEL...: prints the value of each named channel at pixel (X, Y), one per
 * line, for shell tests that check a particular pixel. Exit 1 when the file or a channel is
 * missing, 2 on bad usage. */
#include <stdio.h>
#include <stdlib.h>

#include "io/io.h"

int main(int argc, char **argv)
{
    if (argc < 5) {
        fprintf(stderr, "usage: exrpixel EXR X Y CHANNEL...\n");
        return 2;
    }
    struct rb_io_image img = {0};
    struct rb_err err = RB_ERR_INIT;
    if (rb_io_image_read(argv[1], &img, &err)) {
        fprintf(stderr, "exrpixel: %s\n", err.msg);
        return 1;
    }
    long x = strtol(argv[2], NULL, 10), y = strtol(argv[3], NULL, 10);
    int rc = 0;
    if (x < 0 || y < 0 || x >= (long)img.width_px || y >= (long)img.height_px) {
        fprintf(stderr, "exrpixel: (%ld, %ld) is outside %ux%u\n", x, y, img.width_px,
                img.height_px);
        rc = 1;
    }
    for (int i = 4; i < argc && rc == 0; i++) {
        int ch = rb_io_image_channel(&img, argv[i]);
        if (ch < 0) {
            fprintf(stderr, "exrpixel: no channel '%s' in %s\n", argv[i], argv[1]);
            rc = 1;
            break;
        }
        printf("%.9g\n",
               img.pixels[((size_t)y * img.width_px + (size_t)x) * img.channel_count + (size_t)ch]);
    }
    rb_io_image_release(&img);
    return rc;
}
