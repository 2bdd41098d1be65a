/* The packed layout of a frame's layers: what the GPU output pass writes for a job's layer mask,
 * what the reference fills (every layer) and what lib/render reads to write the EXR. */
#include "core/core.h"

uint32_t rb_layer_width(enum rb_layer layer)
{
    static const uint32_t width[RB_LAYER_COUNT] = {3, 3, 3, 3, 1, 2, 3, 3, 2, 2, 1};
    return (uint32_t)layer < RB_LAYER_COUNT ? width[layer] : 0;
}

uint32_t rb_layer_offset(uint32_t mask, enum rb_layer layer)
{
    uint32_t off = 4; /* the beauty, RGBA */
    for (uint32_t l = 0; l < (uint32_t)layer && l < RB_LAYER_COUNT; l++)
        if (mask & (1u << l))
            off += rb_layer_width((enum rb_layer)l);
    return off;
}

uint32_t rb_layer_stride(uint32_t mask)
{
    return (rb_layer_offset(mask, RB_LAYER_COUNT) + 3u) & ~3u;
}

const char *rb_layer_name(enum rb_layer layer)
{
    static const char *const names[RB_LAYER_COUNT] = {
        "direct",           "indirect",          "albedo",  "normal", "depth",   "motion",
        "indirect_diffuse", "indirect_specular", "samples", "tiles",  "variance"};
    return (uint32_t)layer < RB_LAYER_COUNT ? names[layer] : NULL;
}

const char *rb_layer_channel(enum rb_layer layer, uint32_t c)
{
    static const char *const rgb[] = {"R", "G", "B"}, *const xyz[] = {"X", "Y", "Z"},
                             *const z[] = {"Z"}, *const lobes[] = {"diffuse", "specular"},
                             *const y[] = {"Y"};
    static const char *const *const channels[RB_LAYER_COUNT] = {rgb, rgb, rgb,   xyz,   z, xyz,
                                                                rgb, rgb, lobes, lobes, y};
    return c < rb_layer_width(layer) ? channels[layer][c] : NULL;
}
