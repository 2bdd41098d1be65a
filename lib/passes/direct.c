/* direct: direct light from punctual lights (shadow-mapped) and emission at each G-buffer pixel,
 * the environment where there is no geometry (DESIGN.md "direct"). */
#include "passes/passes_int.h"

#include <stdlib.h>

#include "direct.comp.h"

struct rb_pass_direct {
    struct rb_pass pass;
};

static const struct rb_pass_binding bindings[] = {
    RB_PASS_BIND(RB_BIND_DIRECT_GLOBALS, UNIFORM_BUFFER),
    RB_PASS_BIND(RB_BIND_DIRECT_GB_POSITION, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_DIRECT_GB_NORMAL, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_DIRECT_GB_ALBEDO, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_DIRECT_GB_SPECULAR, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_DIRECT_GB_EMISSION, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_DIRECT_GB_MOTION, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_DIRECT_LIGHTS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_DIRECT_SHADOW_VIEWS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_DIRECT_SHADOW_MAPS, COMBINED_IMAGE_SAMPLER),
    RB_PASS_BIND(RB_BIND_DIRECT_ENV_MAP, COMBINED_IMAGE_SAMPLER),
    RB_PASS_BIND(RB_BIND_DIRECT_OUT, STORAGE_IMAGE),
};
_Static_assert(COUNT(bindings) == RB_BIND_DIRECT_COUNT, "direct bindings");

enum rb_status rb_pass_direct_create(struct rb_gpu *gpu, struct rb_pass_direct **out,
                                     struct rb_err *err)
{
    struct rb_pass_direct *p = calloc(1, sizeof(*p));
    if (!p)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    enum rb_status st = rb_pass_compute_init(
        gpu,
        &(struct rb_pass_compute_desc){.name = "direct",
                                       RB_PASS_BINDINGS(bindings),
                                       .spv = rb_spv_direct_comp,
                                       .spv_bytes = sizeof(rb_spv_direct_comp)},
        &p->pass, err);
    if (st) {
        rb_pass_direct_destroy(p);
        return st;
    }
    *out = p;
    return RB_OK;
}

void rb_pass_direct_record(struct rb_pass_direct *p, VkCommandBuffer cmd,
                           const struct rb_frame *frame)
{
    const struct rb_gpu_image *gb = frame->gbuffer;
    struct rb_pass_bindings b = {.pass = &p->pass};
    rb_pass_bind_buffer(&b, RB_BIND_DIRECT_GLOBALS, &frame->globals);
    rb_pass_bind_image(&b, RB_BIND_DIRECT_GB_POSITION, gb[RB_GB_POSITION].view, VK_NULL_HANDLE);
    rb_pass_bind_image(&b, RB_BIND_DIRECT_GB_NORMAL, gb[RB_GB_NORMAL].view, VK_NULL_HANDLE);
    rb_pass_bind_image(&b, RB_BIND_DIRECT_GB_ALBEDO, gb[RB_GB_ALBEDO].view, VK_NULL_HANDLE);
    rb_pass_bind_image(&b, RB_BIND_DIRECT_GB_SPECULAR, gb[RB_GB_SPECULAR].view, VK_NULL_HANDLE);
    rb_pass_bind_image(&b, RB_BIND_DIRECT_GB_EMISSION, gb[RB_GB_EMISSION].view, VK_NULL_HANDLE);
    rb_pass_bind_image(&b, RB_BIND_DIRECT_GB_MOTION, gb[RB_GB_MOTION].view, VK_NULL_HANDLE);
    rb_pass_bind_buffer(&b, RB_BIND_DIRECT_LIGHTS, &frame->lights);
    rb_pass_bind_buffer(&b, RB_BIND_DIRECT_SHADOW_VIEWS, &frame->shadow_views);
    rb_pass_bind_image(&b, RB_BIND_DIRECT_SHADOW_MAPS, frame->shadow_maps.view,
                       p->pass.gpu->nearest_sampler);
    rb_pass_bind_image(&b, RB_BIND_DIRECT_ENV_MAP, frame->env_map.view, p->pass.gpu->env_sampler);
    rb_pass_bind_image(&b, RB_BIND_DIRECT_OUT, frame->direct.view, VK_NULL_HANDLE);
    rb_pass_record_bindings(cmd, &b);
    vkCmdDispatch(cmd, (frame->width_px + 7) / 8, (frame->height_px + 7) / 8, 1);
}

void rb_pass_direct_destroy(struct rb_pass_direct *p)
{
    if (!p)
        return;
    rb_pass_release(&p->pass);
    free(p);
}
