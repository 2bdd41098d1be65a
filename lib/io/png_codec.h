/* PNG through libpng: encode 8-bit RGBA in memory, decode a file to float. No policy lives here
 * (what the bytes are, where they go: io.c's). Private to lib/io. */
#ifndef RB_IO_PNG_CODEC_H
#define RB_IO_PNG_CODEC_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* True when the file starts with PNG's signature. */
bool rb_png_is_png(const char *path);

/* Encodes width*height unassociated 8-bit RGBA pixels (rows top to bottom) as a PNG with a
 * "Software" text chunk and nothing that depends on the time. *out (freed with free()) and *size
 * only on success; false fills msg. */
bool rb_png_encode(const uint8_t *rgba, uint32_t width_px, uint32_t height_px, const char *software,
                   void **out, size_t *size, char *msg, size_t msg_size);

/* The most samples (width x height x channels, after expansion) rb_png_decode takes: 2^30, the
 * glTF loader's decoder's limit. */
#define RB_PNG_MAX_SAMPLES (1ull << 30)

/* Decodes a PNG file: gray, gray+alpha, RGB or RGBA, 8 or 16 bits (palettes and lower depths
 * expanded), each value as stored divided by 255 or 65535 (no gamma, no premultiplication).
 * *pixels (width*height*channels floats, freed with free()) only on success. A PNG whose header
 * declares more than RB_PNG_MAX_SAMPLES is refused before anything is allocated or inflated,
 * msg naming its size and the limit. */
bool rb_png_decode(const char *path, uint32_t *width_px, uint32_t *height_px,
                   uint32_t *channel_count, float **pixels, char *msg, size_t msg_size);

/* The channel names OpenImageIO gives a PNG of count channels: Y; Y, A; R, G, B; R, G, B, A. */
const char *rb_png_channel_name(uint32_t channel_count, uint32_t i);

/* libpng's version, e.g. "1.6.39". */
const char *rb_png_version(void);

#endif
