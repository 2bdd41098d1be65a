/* shadow: the direct light's shadow maps (DESIGN.md "shadow"; seed 000, B.3: cube maps for
 * point lights), six perspective layers per point light, one per spot light and an orthographic
 * one per directional light, each the distance to the light (or along it) in an R32F array
 * layer, drawn by the raster-view pass. The direct pass filters them by hand with 16-tap PCF.
 * Which views there are, and their matrices, the frame decides (lib/integrators/frame.c). */
#include "passes/passes.h"

#include <stddef.h>
#include <stdlib.h>

/* A shadow view is a raster view as it is: the light's position is the view's origin. */
_Static_assert(offsetof(struct rb_gpu_shadow_view, view_proj) ==
                   offsetof(struct rb_gpu_view, transform),
               "shadow view transform");
_Static_assert(offsetof(struct rb_gpu_shadow_view, light) == offsetof(struct rb_gpu_view, origin),
               "shadow view origin");
_Static_assert(offsetof(struct rb_gpu_shadow_view, axis) == offsetof(struct rb_gpu_view, axis),
               "shadow view axis");
_Static_assert(sizeof(struct rb_gpu_shadow_view) == sizeof(struct rb_gpu_view), "shadow view");

struct rb_pass_shadow {
    struct rb_pass_view *view;
};

enum rb_status rb_pass_shadow_create(struct rb_gpu *gpu, struct rb_pass_shadow **out,
                                     struct rb_err *err)
{
    static const struct rb_view_variant variants[] = {
        {RB_VIEW_KIND_PERSPECTIVE, RB_VIEW_OUTPUT_DEPTH},
        {RB_VIEW_KIND_ORTHOGRAPHIC, RB_VIEW_OUTPUT_DEPTH},
    };
    struct rb_pass_shadow *p = calloc(1, sizeof(*p));
    if (!p)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    enum rb_status st = rb_pass_view_create(gpu,
                                            &(struct rb_pass_view_desc){
                                                .variants = variants,
                                                .variant_count = 2,
                                                .debug_name = "shadow",
                                            },
                                            &p->view, err);
    if (st) {
        rb_pass_shadow_destroy(p);
        return st;
    }
    *out = p;
    return RB_OK;
}

static enum rb_view_kind kind_of(const struct rb_gpu_shadow_view *v)
{
    return (uint32_t)v->light[3] == RB_KIND_DIRECTIONAL ? RB_VIEW_KIND_ORTHOGRAPHIC
                                                        : RB_VIEW_KIND_PERSPECTIVE;
}

void rb_pass_shadow_record(struct rb_pass_shadow *p, VkCommandBuffer cmd,
                           const struct rb_frame *frame, const struct rb_frame_slot *cur)
{
    /* Consecutive layers of one kind (a point light's six faces, lights of one type) go as one
     * batch. */
    const struct rb_gpu_shadow_view *views = frame->shadow_views.mapped;
    uint32_t count = frame->shadow_layer_count;
    for (uint32_t first = 0, end; first < count; first = end) {
        enum rb_view_kind kind = kind_of(&views[first]);
        for (end = first + 1; end < count && kind_of(&views[end]) == kind; end++)
            ;
        rb_pass_view_record(p->view, cmd, frame, cur,
                            &(struct rb_view_batch){
                                .kind = kind,
                                .output = RB_VIEW_OUTPUT_DEPTH,
                                .views = &frame->shadow_views,
                                .first_view = first,
                                .first_layer = first,
                                .view_count = end - first,
                                .targets = {&frame->shadow_maps},
                                .depth = &frame->shadow_depth,
                            });
    }
}

void rb_pass_shadow_destroy(struct rb_pass_shadow *p)
{
    if (!p)
        return;
    rb_pass_view_destroy(p->view);
    free(p);
}
