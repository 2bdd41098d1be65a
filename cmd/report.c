/* raybundle report: reads a rendered sequence (and a reference sequence) through lib/analysis,
 * writes one self-contained HTML page of plots and thumbnails, and says where it went. The page
 * and its numbers are lib/analysis/report.c's. */
#include "cmd.h"

#include <errno.h>
#include <getopt.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "analysis/analysis.h"

static void usage(FILE *f)
{
    fprintf(f, "usage: raybundle report SEQ [--reference REFSEQ] -o REPORT.html\n"
               "\n"
               "Writes one self-contained HTML page about the sequence rendered into the\n"
               "directory SEQ: time per pass and frame time over the frames, the frame-to-frame\n"
               "difference, the error against the reference sequence REFSEQ, hit ratios where\n"
               "the sequence has them, and thumbnails through the OpenColorIO view.\n"
               "\n"
               "  --reference DIR   the reference sequence (raybundle reference), frame by frame\n"
               "  -o, --output PATH the page to write\n"
               "  --thumb-width N   thumbnails N pixels wide at most (240)\n"
               "  --filmstrip N     show at most N frames' thumbnails, evenly spaced, the first\n"
               "                    and the last among them (24; 0: every frame)\n"
               "  -h, --help        show this help\n"
               "\n"
               "Exit status: 0 written, 1 the page could not be written, 2 bad usage or a\n"
               "sequence that cannot be read or does not match.\n");
}

/* Parses s as a whole decimal number in min..max into *out. */
static bool parse_count(const char *s, long min, long max, long *out)
{
    char *end = NULL;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (end == s || *end || errno || v < min || v > max)
        return false;
    *out = v;
    return true;
}

int cmd_report(int argc, char **argv)
{
    enum { O_REFERENCE = 256, O_THUMB_WIDTH, O_FILMSTRIP };
    static const struct option opts[] = {
        {"reference", required_argument, NULL, O_REFERENCE},
        {"output", required_argument, NULL, 'o'},
        {"thumb-width", required_argument, NULL, O_THUMB_WIDTH},
        {"filmstrip", required_argument, NULL, O_FILMSTRIP},
        {"help", no_argument, NULL, 'h'},
        {0},
    };
    struct rb_analysis_report_desc desc = {0};
    const char *output = NULL;
    long v;
    int c;
    optind = 1;
    while ((c = cmd_getopt(argc, argv, "ho:", opts, "report")) != -1) {
        switch (c) {
        case O_REFERENCE: desc.reference_dir = optarg; break;
        case 'o': output = optarg; break;
        case O_THUMB_WIDTH:
            if (!parse_count(optarg, 1, 4096, &v)) {
                cmd_error("--thumb-width expects 1..4096 pixels, got '%s'", optarg);
                return RB_EXIT_USAGE;
            }
            desc.thumb_width_px = (uint32_t)v;
            break;
        case O_FILMSTRIP: /* 1 cannot hold both the first and the last frame */
            if (!parse_count(optarg, 0, 100000, &v) || v == 1) {
                cmd_error("--filmstrip expects 0 (every frame) or 2..100000 frames, got '%s'",
                          optarg);
                return RB_EXIT_USAGE;
            }
            desc.filmstrip_max = v ? (size_t)v : SIZE_MAX;
            break;
        case 'h': usage(stdout); return RB_EXIT_OK;
        default: return RB_EXIT_USAGE; /* reported */
        }
    }
    if (argc - optind != 1) {
        cmd_usage_error("report", argc - optind ? "report takes one sequence directory, SEQ"
                                                : "report needs a sequence directory, SEQ");
        return RB_EXIT_USAGE;
    }
    if (!output) {
        cmd_usage_error("report", "report needs -o REPORT.html");
        return RB_EXIT_USAGE;
    }
    desc.dir = argv[optind];

    struct rb_err err = RB_ERR_INIT;
    struct rb_analysis_report *r = NULL;
    int rc = RB_EXIT_OK;
    enum rb_status st;
    if ((st = rb_analysis_report_create(&desc, &r, &err))) {
        cmd_error("%s", err.msg);
        rc = st == RB_E_NOMEM ? RB_EXIT_FAILED : RB_EXIT_USAGE;
        goto out;
    }
    if ((st = rb_io_make_parent_dirs(output, &err)) ||
        (st = rb_analysis_report_write(r, output, &err))) {
        cmd_error("%s", err.msg);
        rc = RB_EXIT_FAILED;
        goto out;
    }
    printf("%zu frame%s of %s/%s.####.exr%s%s in %s\n", r->seq.frame_count,
           r->seq.frame_count == 1 ? "" : "s", r->seq.dir, r->seq.stem,
           r->has_reference ? " against " : "", r->has_reference ? r->ref.dir : "", output);
out:
    rb_analysis_report_destroy(r);
    return rc;
}
