/* raybundle info: devices, drivers, and the features the renderer uses; or, given image files,
 * what each holds: its size, layers and channels, and the metadata of its header. */
#include "cmd.h"

#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gpu/gpu.h"
#include "io/io.h"
#include "job/job.h"
#include "reference/reference.h"

static void usage(FILE *f)
{
    fprintf(f, "usage: raybundle info [FILE...]\n\n"
               "Without FILE, lists every Vulkan device with its type, API and driver versions\n"
               "and whether it has what raybundle needs. The default device is lavapipe.\n\n"
               "Given image files (EXR, PNG, or what OpenImageIO reads), prints for each its\n"
               "path, size, layers with their channels, and every attribute of its header:\n"
               "for a frame raybundle wrote, the integrator, job hash, frame, time, the camera\n"
               "matrices, ..., and the device and driver that rendered it, from the frame's\n"
               "timing sidecar (NAME.####.timing.json) when it is beside the file.\n"
               "Exit status 2 when a file is missing or does not read as an image.\n\n"
               "  -h, --help  show this help\n");
}

/* Header attributes that the size and layers lines already show. */
static bool is_shown(const char *name)
{
    static const char *const shown[] = {"channels", "dataWindow", "displayWindow"};
    for (size_t i = 0; i < sizeof(shown) / sizeof(shown[0]); i++)
        if (!strcmp(name, shown[i]))
            return true;
    return false;
}

/* Prints what the image at path holds, after a blank line when *has_printed (which it sets);
 * RB_EXIT_USAGE, after an error naming it, when it is missing or does not read. */
static int info_file(const char *path, bool *has_printed)
{
    struct rb_err err = RB_ERR_INIT;
    struct rb_io_image img = {0};
    struct rb_io_image_layers layers = {0};
    struct rb_io_image_attrs attrs = {0};
    int rc = RB_EXIT_OK;

    if (rb_io_image_read(path, &img, &err) || rb_io_image_layers_init(&layers, &img, &err) ||
        rb_io_image_attrs_read(path, &attrs, &err)) {
        cmd_error("%s", err.msg);
        rc = err.status == RB_E_NOMEM ? RB_EXIT_FAILED : RB_EXIT_USAGE;
        goto out;
    }
    printf("%spath: %s\nsize: %ux%u\nlayers: ", *has_printed ? "\n" : "", path, img.width_px,
           img.height_px);
    for (size_t i = 0; i < layers.count; i++) {
        const struct rb_io_image_layer *l = &layers.layers[i];
        printf("%s%s (", i ? ", " : "", l->name);
        for (uint32_t c = 0; c < l->channel_count; c++)
            printf("%s%s", c ? ", " : "", rb_io_channel_base(img.channel_names[l->channels[c]]));
        printf(")");
    }
    printf("\n");
    /* raybundle's own metadata first, then the rest of the header. */
    for (int pass = 0; pass < 2; pass++) {
        for (size_t i = 0; i < attrs.count; i++) {
            bool is_ours = !strncmp(attrs.names[i], "raybundle:", strlen("raybundle:"));
            if (!is_shown(attrs.names[i]) && is_ours == (pass == 0))
                printf("%s: %s\n", attrs.names[i], attrs.values[i]);
        }
    }
    /* The device is the sidecar's: the EXR's bytes do not depend on the driver. */
    char side[4096];
    struct rb_io_timing_file t = {0};
    if (rb_io_sidecar_path(path, ".timing.json", side, sizeof(side), NULL) == RB_OK &&
        rb_io_timing_read(side, &t, NULL) == RB_OK)
        printf("device: %s\ndriver: %s\n", t.device, t.driver);
    rb_io_timing_file_release(&t);
    *has_printed = true;
out:
    rb_io_image_attrs_release(&attrs);
    rb_io_image_layers_release(&layers);
    rb_io_image_release(&img);
    return rc;
}

int cmd_info(int argc, char **argv)
{
    static const struct option opts[] = {{"help", no_argument, NULL, 'h'}, {0}};
    int c;
    optind = 1;
    while ((c = cmd_getopt(argc, argv, "h", opts, "info")) != -1) {
        if (c == 'h') {
            usage(stdout);
            return RB_EXIT_OK;
        }
        return RB_EXIT_USAGE; /* reported */
    }
    if (optind < argc) {
        int rc = RB_EXIT_OK;
        bool has_printed = false;
        for (int i = optind; i < argc; i++) {
            int file_rc = info_file(argv[i], &has_printed);
            if (file_rc && !rc)
                rc = file_rc;
        }
        return rc;
    }
    printf("raybundle %s\n", RB_VERSION);
    printf("libraries: %s, Embree %s, libyaml %s\n", rb_io_library_versions(),
           rb_reference_embree_version(), rb_job_yaml_version());
    const char *ocio = getenv("OCIO");
    printf("OpenColorIO config: %s\n", ocio && *ocio ? ocio : rb_io_default_ocio_config());
    struct rb_err err = RB_ERR_INIT;
    if (rb_gpu_print_devices(stdout, &err)) {
        cmd_error("%s", err.msg);
        return RB_EXIT_NODEVICE;
    }
    return RB_EXIT_OK;
}
