/* output: packs beauty and the named layers into one host-visible buffer, so a frame is read
 * back with a single copy (the order is RB_OUT_* in shaders/common/shared.h), and counts the
 * NaN and infinite values it writes, so none reaches a file unnoticed. With bdpt's gathered
 * light, it textures that light with the diffuse and gray specular maps and adds it (seed 000,
 * B.1 "Output"); with the hybrid's sample counts and tile masks, it copies them into the samples
 * and tiles layers; after the transparency pass, it composites the frame under the blended
 * layers' light (premultiplied: rgb + a x what lies behind). */
#include "passes/passes_int.h"

#include <stdlib.h>

#include "output.comp.h"

struct rb_pass_output {
    struct rb_gpu *gpu;
    struct rb_pass pass;
    struct rb_gpu_buffer nonfinite; /* one uint32, host-visible: zeroed, then added to */
};

/* The push constants of shaders/output.comp: the band of rows one dispatch writes, and what a
 * pixel holds (the job's layers, packed: rb_layer_offset). */
struct band {
    uint32_t first_row, row_count;
    uint32_t layer_mask, floats_per_pixel;
    uint32_t has_light, has_stats, has_transparency, pad;
};

static const struct rb_pass_binding bindings[] = {
    RB_PASS_BIND(RB_BIND_OUTPUT_GLOBALS, UNIFORM_BUFFER),
    RB_PASS_BIND(RB_BIND_OUTPUT_BEAUTY, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_OUTPUT_DIRECT, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_OUTPUT_ALBEDO, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_OUTPUT_NORMAL, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_OUTPUT_POSITION, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_OUTPUT_MOTION, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_OUTPUT_READBACK, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_OUTPUT_NONFINITE, STORAGE_BUFFER),
    RB_PASS_BIND(RB_BIND_OUTPUT_SPECULAR, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_OUTPUT_LIGHT + 0, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_OUTPUT_LIGHT + 1, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_OUTPUT_LIGHT + 2, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_OUTPUT_LIGHT + 3, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_OUTPUT_STATS, STORAGE_IMAGE),
    RB_PASS_BIND(RB_BIND_OUTPUT_TRANSPARENCY, STORAGE_IMAGE),
};
_Static_assert(COUNT(bindings) == RB_BIND_OUTPUT_COUNT, "output bindings");

enum rb_status rb_pass_output_create(struct rb_gpu *gpu, struct rb_pass_output **out,
                                     struct rb_err *err)
{
    struct rb_pass_output *p = calloc(1, sizeof(*p));
    if (!p)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    p->gpu = gpu;
    enum rb_status st = rb_gpu_buffer_init(
        gpu,
        &(struct rb_gpu_buffer_desc){.size_bytes = sizeof(uint32_t),
                                     .usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT |
                                              VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                     .is_host_visible = true,
                                     .debug_name = "output.nonfinite"},
        &p->nonfinite, err);
    if (st == RB_OK)
        st = rb_pass_compute_init(
            gpu,
            &(struct rb_pass_compute_desc){.name = "output",
                                           RB_PASS_BINDINGS(bindings),
                                           .push_bytes = sizeof(struct band),
                                           .spv = rb_spv_output_comp,
                                           .spv_bytes = sizeof(rb_spv_output_comp)},
            &p->pass, err);
    if (st) {
        rb_pass_output_destroy(p);
        return st;
    }
    *out = p;
    return RB_OK;
}

void rb_pass_output_record(struct rb_pass_output *p, VkCommandBuffer cmd,
                           const struct rb_frame *frame, const struct rb_gpu_buffer *target,
                           const struct rb_gpu_image *light, const struct rb_gpu_image *stats,
                           bool has_transparency)
{
    /* The count starts from zero on the device, ordered before the shader's atomic adds. */
    vkCmdFillBuffer(cmd, p->nonfinite.buffer, 0, VK_WHOLE_SIZE, 0);
    rb_gpu_memory_barrier(cmd, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                          VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                          VK_ACCESS_2_SHADER_STORAGE_READ_BIT |
                              VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
    /* The readback outgrows maxStorageBufferRange (1920x1080 is 166 MB, lavapipe binds 128 MiB):
     * it is written one band of rows at a time, each bound as its own aligned range, so the host
     * still reads one buffer, rows top to bottom. rb_frame_init checked that a band fits. */
    VkDeviceSize row_bytes = (VkDeviceSize)frame->width_px * frame->readback_floats * sizeof(float);
    uint32_t band_rows = rb_gpu_storage_band_rows(p->gpu, row_bytes, frame->height_px);
    if (band_rows == 0)
        RB_BUG("readback rows of %llu bytes fit no storage binding", (unsigned long long)row_bytes);
    for (uint32_t first = 0; first < frame->height_px; first += band_rows) {
        uint32_t rows = frame->height_px - first;
        struct band band = {first,
                            rows < band_rows ? rows : band_rows,
                            frame->layer_mask,
                            frame->readback_floats,
                            light != NULL,
                            stats != NULL,
                            has_transparency,
                            0};
        struct rb_pass_bindings b = {.pass = &p->pass};
        rb_pass_bind_buffer(&b, RB_BIND_OUTPUT_GLOBALS, &frame->globals);
        rb_pass_bind_image(&b, RB_BIND_OUTPUT_BEAUTY, frame->beauty->view, VK_NULL_HANDLE);
        rb_pass_bind_image(&b, RB_BIND_OUTPUT_DIRECT, frame->direct.view, VK_NULL_HANDLE);
        rb_pass_bind_image(&b, RB_BIND_OUTPUT_ALBEDO, frame->gbuffer[RB_GB_ALBEDO].view,
                           VK_NULL_HANDLE);
        rb_pass_bind_image(&b, RB_BIND_OUTPUT_NORMAL, frame->gbuffer[RB_GB_NORMAL].view,
                           VK_NULL_HANDLE);
        rb_pass_bind_image(&b, RB_BIND_OUTPUT_POSITION, frame->gbuffer[RB_GB_POSITION].view,
                           VK_NULL_HANDLE);
        rb_pass_bind_image(&b, RB_BIND_OUTPUT_MOTION, frame->gbuffer[RB_GB_MOTION].view,
                           VK_NULL_HANDLE);
        rb_pass_bind_buffer_range(&b, RB_BIND_OUTPUT_READBACK, target, first * row_bytes,
                                  band.row_count * row_bytes);
        rb_pass_bind_buffer(&b, RB_BIND_OUTPUT_NONFINITE, &p->nonfinite);
        rb_pass_bind_image(&b, RB_BIND_OUTPUT_SPECULAR, frame->gbuffer[RB_GB_SPECULAR].view,
                           VK_NULL_HANDLE);
        for (uint32_t i = 0; i < RB_BDPT_LIGHT_COUNT; i++) /* unread without light */
            rb_pass_bind_image(&b, RB_BIND_OUTPUT_LIGHT + i,
                               light ? light[i].view : frame->direct.view, VK_NULL_HANDLE);
        rb_pass_bind_image(&b, RB_BIND_OUTPUT_STATS, stats ? stats->view : frame->direct.view,
                           VK_NULL_HANDLE); /* unread without stats */
        rb_pass_bind_image(&b, RB_BIND_OUTPUT_TRANSPARENCY,
                           has_transparency ? frame->transparency.view : frame->direct.view,
                           VK_NULL_HANDLE); /* unread without the pass */
        rb_pass_record_bindings(cmd, &b);
        vkCmdPushConstants(cmd, p->pass.layout.pipeline_layout, VK_SHADER_STAGE_ALL, 0,
                           sizeof(band), &band);
        vkCmdDispatch(cmd, (frame->width_px + 7) / 8, (band.row_count + 7) / 8, 1);
    }
    /* Make the shader writes visible to the host's read after the fence. */
    rb_gpu_memory_barrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                          VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, VK_PIPELINE_STAGE_2_HOST_BIT,
                          VK_ACCESS_2_HOST_READ_BIT);
}

uint32_t rb_pass_output_nonfinite_count(const struct rb_pass_output *p)
{
    return *(const uint32_t *)p->nonfinite.mapped;
}

void rb_pass_output_destroy(struct rb_pass_output *p)
{
    if (!p)
        return;
    rb_pass_release(&p->pass);
    rb_gpu_buffer_release(p->gpu, &p->nonfinite);
    free(p);
}
