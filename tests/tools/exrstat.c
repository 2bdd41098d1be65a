/* exrstat EXR CHANNEL MIN_MEAN: checks that every value of every channel is finite and that the
 * mean of CHANNEL exceeds MIN_MEAN (the picture is not black). Prints TAP. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "io/io.h"

int main(int argc, char **argv)
{
    if (argc != 4) {
        fprintf(stderr, "usage: exrstat EXR CHANNEL MIN_MEAN\n");
        return 2;
    }
    struct rb_io_image img = {0};
    struct rb_err err = RB_ERR_INIT;
    if (rb_io_image_read(argv[1], &img, &err)) {
        printf("not ok 1 - read %s: %s\n1..1\n", argv[1], err.msg);
        return 1;
    }
    int ch = rb_io_image_channel(&img, argv[2]);
    size_t n = (size_t)img.width_px * img.height_px, bad = 0;
    double sum = 0.0;
    for (size_t i = 0; i < n * img.channel_count; i++)
        if (!isfinite(img.pixels[i]))
            bad++;
    for (size_t i = 0; ch >= 0 && i < n; i++)
        sum += img.pixels[i * img.channel_count + (size_t)ch];
    double mean = n ? sum / (double)n : 0.0, min = atof(argv[3]);
    printf("%s 1 - every value in %s is finite (%zu are not)\n", bad ? "not ok" : "ok", argv[1],
           bad);
    printf("%s 2 - mean of %s is %g, above %g\n", ch >= 0 && mean > min ? "ok" : "not ok", argv[2],
           mean, min);
    printf("1..2\n");
    rb_io_image_release(&img);
    return bad || ch < 0 || mean <= min;
}
