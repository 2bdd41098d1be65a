/* animate: morph targets, skins and node transforms on the GPU (DESIGN.md "animate"). The CPU
 * evaluates the animation curves into per-instance matrices and weights; this pass deforms the
 * vertices, one dispatch per instance (or per run of its vertices, past the workgroup count),
 * into the slot's world-space vertex buffer, read and written by address (geometry_shared.h). */
#include "passes/passes_int.h"

#include <stdint.h>
#include <stdlib.h>

#include "animate.comp.h"

struct rb_pass_animate {
    struct rb_pass pass;
};

static const struct rb_pass_binding bindings[] = {
    RB_PASS_BIND(RB_BIND_ANIMATE_GEOMETRY, UNIFORM_BUFFER),
    RB_PASS_BIND(RB_BIND_ANIMATE_INSTANCES, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_ANIMATE_JOINTS, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_ANIMATE_WEIGHTS, STORAGE_BUFFER),
};
_Static_assert(COUNT(bindings) == RB_BIND_ANIMATE_COUNT, "animate bindings");

enum rb_status rb_pass_animate_create(struct rb_gpu *gpu, struct rb_pass_animate **out,
                                      struct rb_err *err)
{
    struct rb_pass_animate *p = calloc(1, sizeof(*p));
    if (!p)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    enum rb_status st = rb_pass_compute_init(
        gpu,
        &(struct rb_pass_compute_desc){.name = "animate",
                                       RB_PASS_BINDINGS(bindings),
                                       .push_bytes = 2 * sizeof(uint32_t),
                                       .spv = rb_spv_animate_comp,
                                       .spv_bytes = sizeof(rb_spv_animate_comp)},
        &p->pass, err);
    if (st) {
        rb_pass_animate_destroy(p);
        return st;
    }
    *out = p;
    return RB_OK;
}

void rb_pass_animate_record(struct rb_pass_animate *p, VkCommandBuffer cmd,
                            const struct rb_frame *frame, const struct rb_frame_slot *slot)
{
    struct rb_pass_bindings b = {.pass = &p->pass};
    rb_pass_bind_buffer(&b, RB_BIND_ANIMATE_GEOMETRY, &slot->geometry);
    rb_pass_bind_buffer(&b, RB_BIND_ANIMATE_INSTANCES, &slot->instances);
    rb_pass_bind_buffer(&b, RB_BIND_ANIMATE_JOINTS, &slot->joints);
    rb_pass_bind_buffer(&b, RB_BIND_ANIMATE_WEIGHTS, &slot->weights);
    rb_pass_record_bindings(cmd, &b);
    /* An instance of more than maxComputeWorkGroupCount[0] groups of 64 vertices (4.2 M on
     * lavapipe) takes several dispatches, each from its first vertex. */
    uint32_t most_groups = p->pass.gpu->props.limits.maxComputeWorkGroupCount[0];
    for (uint32_t i = 0; i < frame->instance_count; i++) {
        uint32_t count = frame->instances[i].range[1];
        for (uint32_t first = 0; first < count;) {
            uint32_t groups = (count - first + 63) / 64;
            groups = groups < most_groups ? groups : most_groups;
            uint32_t push[2] = {i, first};
            vkCmdPushConstants(cmd, p->pass.layout.pipeline_layout, VK_SHADER_STAGE_ALL, 0,
                               sizeof(push), push);
            vkCmdDispatch(cmd, groups, 1, 1);
            first += groups * 64; /* counts stay below 2^31 (upload_geometry) */
        }
    }
}

void rb_pass_animate_destroy(struct rb_pass_animate *p)
{
    if (!p)
        return;
    rb_pass_release(&p->pass);
    free(p);
}
