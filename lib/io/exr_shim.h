/* The C face of OpenEXR (the format's reference library): write one scanline image with given
 * channels and header attributes, open one and read it as float. No policy lives here (channel
 * order, compression, metadata and temporary names are io.c's); only plain structs and sizes
 * cross. Private to lib/io. */
#ifndef RB_IO_EXR_SHIM_H
#define RB_IO_EXR_SHIM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#define RB_EXR_NOEXCEPT noexcept
#else
#define RB_EXR_NOEXCEPT
#endif

/* Shim results: 0 is success; a failure fills msg with OpenEXR's text (or the exception's). */
#define RB_EXR_OK 0
#define RB_EXR_FAIL 1
#define RB_EXR_NOSPACE 2 /* a write failed with ENOSPC (the disk is full) */
#define RB_EXR_NOQUOTA 3 /* a write failed with EDQUOT */

enum rb_exr_attr_type {
    RB_EXR_ATTR_STRING = 1,
    RB_EXR_ATTR_INT,
    RB_EXR_ATTR_FLOAT,
    RB_EXR_ATTR_M44,           /* 16 floats, row-major (Imath M44f) */
    RB_EXR_ATTR_CHROMATICITIES /* 8 floats: red, green, blue, white (x, y) */
};

struct rb_exr_attr {
    const char *name;
    enum rb_exr_attr_type type;
    const char *s;
    int i;
    float f;
    const float *fv; /* M44: 16 floats; CHROMATICITIES: 8 */
};

struct rb_exr_write_desc {
    const char *path; /* the file to create (io.c's temporary name) */
    uint32_t width_px, height_px, channel_count;
    const char *const *channel_names; /* channel_count names */
    const bool *channel_is_half;      /* per channel; NULL: all full float */
    const float *pixels;              /* channel_count floats per pixel, rows top to bottom */
    const struct rb_exr_attr *attrs;
    size_t attr_count;
};

/* OpenEXR's version, e.g. "3.1.5". */
const char *rb_exr_version(void) RB_EXR_NOEXCEPT;

/* True when the file starts with OpenEXR's magic number. */
bool rb_exr_is_exr(const char *path) RB_EXR_NOEXCEPT;

/* Writes one scanline image, ZIP-compressed, increasing y, exactly as described: no attribute
 * beyond OpenEXR's required ones and desc's (no date, no host), so equal pixels give equal
 * bytes. */
int rb_exr_write(const struct rb_exr_write_desc *desc, char *msg, size_t msg_size) RB_EXR_NOEXCEPT;

/* An open EXR file (its first part). */
struct rb_exr_input;

/* Opens path and reads its header; *out, *width_px, ... are written only on success. */
int rb_exr_open(const char *path, struct rb_exr_input **out, uint32_t *width_px,
                uint32_t *height_px, uint32_t *channel_count, char *msg,
                size_t msg_size) RB_EXR_NOEXCEPT;
/* The name of channel i in reading order: per layer (the beauty, then the layers by name),
 * R, G, B, A first, then the rest by name. Valid until rb_exr_close. */
const char *rb_exr_channel_name(const struct rb_exr_input *in, uint32_t i) RB_EXR_NOEXCEPT;
/* Reads every pixel of the data window, every channel as float, in reading order. */
int rb_exr_read(struct rb_exr_input *in, float *pixels, char *msg, size_t msg_size) RB_EXR_NOEXCEPT;
/* Formats the named header attribute as text into out: strings verbatim, ints in decimal,
 * floats with %g, vectors, boxes (min x, min y, max x, max y) and matrices as their numbers
 * separated by ", ", compression and line order by name ("zip", "increasing y"). False when
 * absent or of a type this does not format. */
bool rb_exr_attr_text(const struct rb_exr_input *in, const char *name, char *out,
                      size_t size) RB_EXR_NOEXCEPT;
/* The number of header attributes (OpenEXR's required ones included). */
size_t rb_exr_attr_count(const struct rb_exr_input *in) RB_EXR_NOEXCEPT;
/* The name of attribute i, in the header's order (by name), and OpenEXR's name for its type
 * ("string", "m44f", "box2i", ...); "" past the end. Valid until rb_exr_close. */
const char *rb_exr_attr_name(const struct rb_exr_input *in, size_t i) RB_EXR_NOEXCEPT;
const char *rb_exr_attr_type(const struct rb_exr_input *in, size_t i) RB_EXR_NOEXCEPT;
/* Closes and frees; NULL is fine. */
void rb_exr_close(struct rb_exr_input *in) RB_EXR_NOEXCEPT;

#ifdef __cplusplus
}
#endif

#endif
