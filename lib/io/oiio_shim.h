/* The C face of OpenImageIO: write one image part with given channels and attributes, open an
 * image and read it as float. No policy lives here (channel order, compression, metadata and
 * temporary names are io.c's); only plain structs and sizes cross. Private to lib/io. */
#ifndef RB_IO_OIIO_SHIM_H
#define RB_IO_OIIO_SHIM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The shims' functions never throw; C++ sees that in their type. */
#ifndef RB_SHIM_NOEXCEPT
#ifdef __cplusplus
#define RB_SHIM_NOEXCEPT noexcept
#else
#define RB_SHIM_NOEXCEPT
#endif
#endif

/* Shim results: 0 is success; a failure fills msg with OIIO's text (or the exception's). */
#define RB_OIIO_OK 0
#define RB_OIIO_FAIL 1

enum rb_oiio_attr_type {
    RB_OIIO_ATTR_STRING = 1,
    RB_OIIO_ATTR_INT,
    RB_OIIO_ATTR_FLOAT,
    RB_OIIO_ATTR_M44,   /* 16 floats, row-major (Imath M44f) */
    RB_OIIO_ATTR_FLOATS /* fv_count floats, e.g. the 8 of EXR "chromaticities" */
};

struct rb_oiio_attr {
    const char *name;
    enum rb_oiio_attr_type type;
    const char *s;
    int i;
    float f;
    const float *fv; /* M44: 16 floats; FLOATS: fv_count floats */
    uint32_t fv_count;
};

/* Receives an image encoded in memory (rb_oiio_write with a sink): size bytes, valid during the
 * call. Returns false when it cannot keep them (out of memory). */
typedef bool (*rb_oiio_sink_fn)(const void *bytes, size_t size, void *user);

struct rb_oiio_write_desc {
    const char *path;        /* file to create (a temporary name; io.c renames it); with a sink,
                              * only the name the format and messages see */
    const char *format_name; /* OIIO plugin: "openexr", "png" */
    uint32_t width_px, height_px, channel_count;
    const char *const *channel_names; /* channel_count names, in file order */
    const bool *channel_is_half;      /* per channel, EXR only; NULL: all full float */
    bool is_uint8;                    /* pixels are uint8_t (PNG); else float */
    const void *pixels;               /* interleaved, rows top to bottom */
    const struct rb_oiio_attr *attrs;
    size_t attr_count;
    rb_oiio_sink_fn sink; /* NULL: write the file; else encode in memory and hand it to sink */
    void *sink_user;
};

/* Writes one image (one part, scanlines) exactly as described. */
/* OpenImageIO's version, e.g. "2.4.7". */
const char *rb_oiio_version(void) RB_SHIM_NOEXCEPT;

int rb_oiio_write(const struct rb_oiio_write_desc *desc, char *msg,
                  size_t msg_size) RB_SHIM_NOEXCEPT;

/* Resizes src (width*height*channel_count floats, interleaved) into dst, which the caller
 * allocates (dst_width*dst_height*channel_count floats), with ImageBufAlgo::resize's default
 * filter for the change of size. */
int rb_oiio_resize(const float *src, uint32_t width_px, uint32_t height_px, uint32_t channel_count,
                   float *dst, uint32_t dst_width_px, uint32_t dst_height_px, char *msg,
                   size_t msg_size) RB_SHIM_NOEXCEPT;

/* Encodes size bytes in base64 (RFC 4648, padded) into out, NUL-terminated; out_size must be at
 * least 4 * ((size + 2) / 3) + 1. */
int rb_oiio_base64_encode(const void *data, size_t size, char *out, size_t out_size, char *msg,
                          size_t msg_size) RB_SHIM_NOEXCEPT;

/* An open image file (subimage 0, miplevel 0). */
struct rb_oiio_input;

struct rb_oiio_info {
    uint32_t width_px, height_px, channel_count;
};

/* Opens path and reads its header; *out is written only on success. */
int rb_oiio_input_open(const char *path, struct rb_oiio_input **out, struct rb_oiio_info *info,
                       char *msg, size_t msg_size) RB_SHIM_NOEXCEPT;
/* The name of channel i as stored in the file; valid until rb_oiio_input_close. */
const char *rb_oiio_input_channel_name(const struct rb_oiio_input *in, uint32_t i) RB_SHIM_NOEXCEPT;
/* Reads every pixel of every channel as float into pixels (width*height*channels floats). */
int rb_oiio_input_read(struct rb_oiio_input *in, float *pixels, char *msg,
                       size_t msg_size) RB_SHIM_NOEXCEPT;
/* Formats the named header attribute as text into out (strings verbatim; numbers, matrices and
 * arrays as OIIO prints them). False when absent. */
bool rb_oiio_input_attr(const struct rb_oiio_input *in, const char *name, char *out,
                        size_t size) RB_SHIM_NOEXCEPT;
/* Closes and frees; NULL is fine. */
void rb_oiio_input_close(struct rb_oiio_input *in) RB_SHIM_NOEXCEPT;

#ifdef __cplusplus
}
#endif

#endif
