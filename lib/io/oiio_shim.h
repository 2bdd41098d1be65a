/* The C face of OpenImageIO, for what only it does here: open an image of any format it reads
 * and read it as float, resize, base64 (EXR and PNG go through exr_shim.h and png_codec.h). No
 * policy lives here; only plain structs and sizes cross. Private to lib/io. */
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

/* OpenImageIO's version, e.g. "2.4.7". */
const char *rb_oiio_version(void) RB_SHIM_NOEXCEPT;

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
