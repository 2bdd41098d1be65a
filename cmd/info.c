/* raybundle info: devices, drivers, and the features the renderer uses. */
#include "cmd.h"

#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>

#include "gpu/gpu.h"
#include "io/io.h"
#include "job/job.h"
#include "reference/reference.h"

static void usage(FILE *f)
{
    fprintf(f, "usage: raybundle info\n\n"
               "Lists every Vulkan device with its type, API and driver versions and whether it\n"
               "has what raybundle needs. The default device is lavapipe.\n");
}

int cmd_info(int argc, char **argv)
{
    static const struct option opts[] = {{"help", no_argument, NULL, 'h'}, {0}};
    int c;
    optind = 1;
    while ((c = getopt_long(argc, argv, "h", opts, NULL)) != -1) {
        if (c == 'h') {
            usage(stdout);
            return RB_EXIT_OK;
        }
        usage(stderr);
        return RB_EXIT_USAGE;
    }
    if (optind < argc) {
        cmd_error("info takes no arguments");
        usage(stderr);
        return RB_EXIT_USAGE;
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
