/* The bdpt integrator (seed 000; DESIGN.md "bdpt", BDPT.md): direct's frame, then
 *   rsm -> bounds -> [emitters] -> generate -> probe -> bounce -> [probe -> bounce] -> vpl ->
 *   split -> (bundle k -> connect k) for each k -> gather -> filter -> output.
 * Reflective shadow maps of the shadowed punctual lights give the VPLs' surfaces; the emissive
 * triangles give VPLs too, points on them picked by power, which light the camera's points
 * directly (weighed against the bundles that find the emitter) and, through a bundle, one bounce
 * further. Every VPL probes along a cosine-distributed direction (a 1x1 reflective shadow map)
 * for the surface its light meets first, VPL K_v + i, its bounce, which makes the VPL's bundle
 * connections again through its own connection to the camera's point, so that the balance
 * heuristic hands their short connections, where the VPL's 1/r^2 would spike, to the bounce; an
 * emitter's bounce has a bounce of its own, VPL 2 K_v + i, for the emitter's second bounce. Each
 * VPL gets a paraboloid shadow map; each global ray-bundle is an orthographic view into per-pixel
 * linked lists, kept only at the texels where the points of the sub-image of the interleaved
 * G-buffer it lights land, connected to that sub-image before the next one reuses the list.
 * Temporal interleaved sampling (seed 000, section A): l caches, each at the pixels' centre or
 * at a subpixel offset of its own (integrator.bdpt.subpixel); frame f computes cache f mod l
 * alone, with that slot's own block of the sampling table on a G-buffer at the slot's offset,
 * overwriting it whole (light and depth); the reproject pass finds
 * where each pixel's surface was in the frames of the other caches, and reconstruct takes the
 * hit-weighted mean of the caches (equations 1 to 3) for output, which adds the direct light of the
 * frame's own, centred G-buffer. Its history is the l - 1 frames before (at least one, for motion
 * vectors); frames before the sequence's start fill no cache. */
#include "integrators/integrators_int.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A frame's camera, as the caches' reprojection needs it. */
struct camera_then {
    struct rb_mat4 view_proj;
    float depth_row[4]; /* view depth = dot(depth_row, (x, 1)) */
};

struct bdpt {
    struct rb_base base;
    struct rb_pass_view *views;
    struct rb_pass_bdpt *passes;
    struct rb_pass_reproject *reproject;
    struct rb_bdpt_frame b;
    struct rb_gpu_buffer usage; /* struct rb_gpu_list_counter per bundle, host-visible */
    /* The caches' G-buffer, drawn at the slot's subpixel offset (l > 1; at the centre, in
     * warm-up frames alone) */
    struct rb_gpu_image jittered[RB_GBUFFER_COLOR_COUNT], jittered_depth;
    float offset_px[RB_BDPT_MAX_CACHES][2];      /* slot i's subpixel offset */
    int written[RB_BDPT_MAX_CACHES];             /* the frame each slot holds; INT_MIN: none */
    struct camera_then then[RB_BDPT_MAX_CACHES]; /* frame f's camera at f mod l */
};

/* The sampling table's streams (rb_qmc_point2): fixed, so every scene and frame draws the same
 * numbers. */
enum {
    STREAM_VPL_DIRECTION = 1,
    STREAM_VPL_LIGHT = 2,
    STREAM_BUNDLE = 3,
    STREAM_VPL_BOUNCE = 4,
    STREAM_VPL_BOUNCE2 = 5,
};

/* l, the temporal caches (the job's; 4 when unset). */
static uint32_t cache_count(const struct rb_job *job)
{
    uint32_t l = job->integrator.bdpt.caches ? job->integrator.bdpt.caches : 4;
    return l < RB_BDPT_MAX_CACHES ? l : RB_BDPT_MAX_CACHES;
}

/* A frame depends on the l - 1 before it (the caches they wrote), and on one at least (motion
 * vectors). */
static uint32_t history_frames(const struct rb_job *job)
{
    uint32_t l = cache_count(job);
    return l > 1 ? l - 1 : 1;
}

/* x mod n in 0..n-1, for negative x too (warm-ups before frame 0). */
static uint32_t wrap(int64_t x, uint32_t n)
{
    return (uint32_t)((x % n + n) % n);
}

/* Slot i's subpixel offset: the pixel's centre (integrator.bdpt.subpixel center, the default),
 * or the Hammersley points, centred, ((i + 1/2) / l, phi2(i) + 1/(2l)) - (1/2, 1/2), phi2 the
 * base-2 radical inverse (spread: seed 000's temporal supersampling); the centre when l is 1.
 * Spread makes a pixel's light the mean over four points of its area, while the direct light, the
 * G-buffer and the reference take its centre: where indirect light changes fast within a pixel
 * they differ. The Cornell box's ceiling, seen at a grazing angle, falls from 0.23 to 0.14 in its
 * last pixel before the back wall (128x128); spread read 0.25 there, the centre 0.19 (beauty
 * relMSE 0.0074 against 0.0068). */
static void cache_offset(uint32_t l, uint32_t i, bool spread, float out[2])
{
    if (!spread) {
        out[0] = out[1] = 0.0f;
        return;
    }
    double y = (double)rb_qmc_sobol(i, 0) / 4294967296.0 + 0.5 / l; /* phi2(i) + 1/(2l) */
    out[0] = (float)((i + 0.5) / l - 0.5);
    out[1] = (float)(y - floor(y) - 0.5);
}

static void release(struct rb_gpu *gpu, struct bdpt *d)
{
    struct rb_bdpt_frame *b = &d->b;
    struct rb_gpu_buffer *buffers[] = {
        &b->bounds,       &b->samples,     &b->lights,    &b->vpls,
        &b->vpl_views,    &b->probe_views, &b->vpl_draws, &b->probe_draws,
        &b->bundle_views, &b->emitters,    &b->emit_info, &b->emitter_cdf,
        &b->ltc,          &d->usage,       &b->history,   &b->hits};
    for (size_t i = 0; i < COUNT(buffers); i++)
        rb_gpu_buffer_release(gpu, buffers[i]);
    for (int i = 0; i < RB_VIEW_RSM_TARGETS; i++) {
        rb_gpu_image_release(gpu, &b->rsm[i]);
        rb_gpu_image_release(gpu, &b->probe[i]);
    }
    rb_gpu_image_release(gpu, &b->rsm_depth);
    rb_gpu_image_release(gpu, &b->probe_depth);
    rb_gpu_image_release(gpu, &b->vpl_maps);
    rb_gpu_image_release(gpu, &b->vpl_depth);
    rb_view_list_release(gpu, &b->bundle);
    for (int i = 0; i < RB_BDPT_LIGHT_COUNT; i++) {
        rb_gpu_image_release(gpu, &b->split[i]);
        rb_gpu_image_release(gpu, &b->accum[i]);
        rb_gpu_image_release(gpu, &b->gathered[i]);
        if (i < RB_BDPT_EMITTED_COUNT)
            rb_gpu_image_release(gpu, &b->emitted[i]);
        rb_gpu_image_release(gpu, &b->filtered[i]);
        rb_gpu_image_release(gpu, &b->light[i]);
    }
    rb_gpu_image_release(gpu, &b->reproject);
    for (int i = 0; i < RB_GBUFFER_COLOR_COUNT; i++)
        rb_gpu_image_release(gpu, &d->jittered[i]);
    rb_gpu_image_release(gpu, &d->jittered_depth);
}

static void destroy(struct rb_integrator *it, void *state)
{
    struct bdpt *d = state;
    if (!d)
        return;
    release(it->gpu, d);
    rb_pass_reproject_destroy(d->reproject);
    rb_pass_bdpt_destroy(d->passes);
    rb_pass_view_destroy(d->views);
    rb_base_destroy(&d->base);
    free(d);
}

/* The integrator's buffers are storage buffers, filled by the shaders or uploaded. */
#define STORAGE (VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT)
/* Draw commands the shaders edit. */
#define DRAWS (STORAGE | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT)

/* The VPLs' generations: each VPL (1), with its bounce (2), with an emitter's bounce's bounce
 * (3). The VPL buffers and maps hold that many times K_v. */
static uint32_t vpl_generations(const struct rb_bdpt_frame *b)
{
    return b->has_chain ? 3u : b->has_bounce ? 2u : 1u;
}

/* Where sample i of K goes among the sequence's K points of a block: connect hands sample i to
 * sub-image i mod m (m = n^2), so the sub-images' samples are made consecutive runs of the
 * sequence, sub-image 0's first. A run of a (0, 2)-sequence is spread over the whole domain; the
 * points i, i + m, i + 2m, ... that i mod m would give a sub-image share their m lowest strata
 * (the bundles of one sub-image all near one latitude, its VPLs all from one strip of an
 * emitter), and the sub-images' differences then stay in the image as a grid. */
static uint32_t sample_rank(uint32_t i, uint32_t count, uint32_t m)
{
    uint32_t s = i % m, before = 0;
    for (uint32_t t = 0; t < s; t++)
        before += rb_bdpt_share(count, t, m);
    return before + i / m;
}

/* The fixed quasi-random table (BDPT.md "Sampling"), a block of rows per cache slot, host-
 * visible: in slot c's block, VPL i draws its light and its direction from row i, bundle i its
 * direction from row K_v + i, and they are points k K + sample_rank(i) of their streams (K = K_v
 * or K_b), k = c when the samples are periodic. So the slots' subsets are disjoint, each one of
 * the sequence's runs, and together its first l K points, and each sub-image's subset of a slot
 * is a run too. With fresh samples, frame f rewrites its slot's block with k = f (new points
 * every frame, as amortized sampling has them). A block is padded to the device's storage offset
 * alignment, since generate binds one. */
static void fill_samples(struct rb_bdpt_frame *b, uint32_t slot, uint32_t block)
{
    uint32_t m = b->interleave * b->interleave;
    uint32_t rows = b->vpl_count + b->bundle_count;
    struct rb_gpu_bdpt_sample *s =
        (struct rb_gpu_bdpt_sample *)((char *)b->samples.mapped + slot * b->sample_block_bytes);
    for (uint32_t i = 0; i < rows; i++) {
        uint32_t u[2], l[2];
        bool is_vpl = i < b->vpl_count;
        uint32_t index =
            is_vpl ? block * b->vpl_count + sample_rank(i, b->vpl_count, m)
                   : block * b->bundle_count + sample_rank(i - b->vpl_count, b->bundle_count, m);
        if (is_vpl) {
            rb_qmc_point2(STREAM_VPL_LIGHT, index, l);
            rb_qmc_point2(STREAM_VPL_DIRECTION, index, u);
            s[i].u[0] = rb_qmc_float(l[0]);
            s[i].u[1] = rb_qmc_float(u[0]);
            s[i].u[2] = rb_qmc_float(u[1]);
            rb_qmc_point2(STREAM_VPL_BOUNCE, index, u);
            s[i].v[0] = rb_qmc_float(u[0]);
            s[i].v[1] = rb_qmc_float(u[1]);
            rb_qmc_point2(STREAM_VPL_BOUNCE2, index, u);
            s[i].v[2] = rb_qmc_float(u[0]);
            s[i].v[3] = rb_qmc_float(u[1]);
        } else {
            rb_qmc_point2(STREAM_BUNDLE, index, u);
            s[i].u[0] = rb_qmc_float(u[0]);
            s[i].u[1] = rb_qmc_float(u[1]);
        }
    }
}

/* The emissive triangles (a material whose emissive factor is above zero), as corners in the
 * frame's world vertex buffer, which holds each instance's vertices in instance order. Their
 * points are VPLs too: generate picks them by power each frame from where the animate pass put
 * them. */
static enum rb_status upload_emitters(struct rb_integrator *it, struct rb_bdpt_frame *b,
                                      struct rb_err *err)
{
    const struct rb_scene *scene = it->scene;
    const struct rb_scene_pose *pose = it->cur.pose;
    uint32_t count = 0, cap = 0, dst = 0;
    struct rb_gpu_bdpt_emitter *list = NULL;
    for (uint32_t i = 0; i < pose->instance_count; i++) {
        const struct rb_scene_primitive *p = &scene->primitives[pose->instances[i].primitive];
        const float *e = scene->materials[p->material].emissive;
        if (e[0] > 0.0f || e[1] > 0.0f || e[2] > 0.0f)
            for (uint32_t j = 0; j + 2 < p->index_count; j += 3) {
                if (count == cap) {
                    cap = cap ? 2 * cap : 64;
                    void *grown = realloc(list, cap * sizeof(*list));
                    if (!grown) {
                        free(list);
                        return rb_errf(err, RB_E_NOMEM, "out of memory for emissive triangles");
                    }
                    list = grown;
                }
                const uint32_t *t = &scene->indices[p->first_index + j];
                list[count++] = (struct rb_gpu_bdpt_emitter){
                    .tri = {dst + t[0], dst + t[1], dst + t[2], p->material}};
            }
        dst += p->vertex_count;
    }
    b->emitter_count = count;
    /* Each is one binding (unlike the vertices, not read by address): past the range (8.4 M
     * emissive triangles on lavapipe) the device cannot, said with the count. */
    enum rb_status st = rb_gpu_check_storage_range(it->gpu, "emitters", "bdpt.emitters",
                                                   (VkDeviceSize)count * sizeof(*list), err);
    if (st) {
        free(list);
        rb_err_prefix(err, "%u emissive triangles", count);
        return st;
    }
    st = rb_frame_buffer(it->gpu, (VkDeviceSize)(count ? count : 1) * sizeof(*list), STORAGE, false,
                         "bdpt.emitters", &b->emitters, err);
    if (st == RB_OK)
        st = rb_frame_buffer(it->gpu, (VkDeviceSize)(count ? count : 1) * sizeof(float), STORAGE,
                             false, "bdpt.emitter_cdf", &b->emitter_cdf, err);
    if (st == RB_OK && count)
        st = rb_gpu_buffer_upload(it->gpu, &b->emitters, list, count * sizeof(*list), err);
    free(list);
    return st;
}

static enum rb_status make_resources(struct rb_integrator *it, struct bdpt *d, struct rb_err *err)
{
    struct rb_gpu *gpu = it->gpu;
    struct rb_frame *frame = &it->frame;
    struct rb_bdpt_frame *b = &d->b;
    uint32_t kv = b->vpl_count ? b->vpl_count : 1, kb = b->bundle_count ? b->bundle_count : 1;
    enum rb_status st = upload_emitters(it, b, err);
    if (st)
        return st;
    VkDeviceSize align = gpu->props.limits.minStorageBufferOffsetAlignment;
    b->sample_block_bytes = (VkDeviceSize)(kv + kb) * sizeof(struct rb_gpu_bdpt_sample);
    if (align > 1)
        b->sample_block_bytes = (b->sample_block_bytes + align - 1) / align * align;
    VkDeviceSize sample_bytes = b->sample_block_bytes * b->cache_count;
    /* VPL i's bounce is VPL K_v + i (BDPT.md "Two bounces"). */
    b->has_bounce = b->vpl_count > 0;
    /* With emitters, the bounce of emitter VPL i's bounce is VPL 2 K_v + i. */
    b->has_chain = b->has_bounce && b->emitter_count > 0;
    uint32_t all = kv * vpl_generations(b);
    if ((st = rb_frame_buffer(gpu, 8 * sizeof(uint32_t), STORAGE, false, "bdpt.bounds", &b->bounds,
                              err)) ||
        (st =
             rb_frame_buffer(gpu, sample_bytes, STORAGE, true, "bdpt.samples", &b->samples, err)) ||
        (st = rb_frame_buffer(gpu,
                              (it->cur.light_capacity ? it->cur.light_capacity : 1) *
                                  sizeof(struct rb_gpu_bdpt_light),
                              STORAGE, true, "bdpt.lights", &b->lights, err)) ||
        (st = rb_frame_buffer(gpu, all * sizeof(struct rb_gpu_vpl), STORAGE, false, "bdpt.vpls",
                              &b->vpls, err)) ||
        (st = rb_frame_buffer(gpu, all * sizeof(struct rb_gpu_view), STORAGE, false,
                              "bdpt.vpl_views", &b->vpl_views, err)) ||
        (st = rb_frame_buffer(gpu, kv * sizeof(struct rb_gpu_view), STORAGE, false,
                              "bdpt.probe_views", &b->probe_views, err)) ||
        (st = rb_frame_buffer(gpu, all * sizeof(VkDrawIndexedIndirectCommand), DRAWS, false,
                              "bdpt.vpl_draws", &b->vpl_draws, err)) ||
        (st = rb_frame_buffer(gpu, kv * sizeof(VkDrawIndexedIndirectCommand), DRAWS, false,
                              "bdpt.probe_draws", &b->probe_draws, err)) ||
        (st = rb_view_draws_init(gpu, &it->frame, true, all, &b->vpl_draws, err)) ||
        (st = rb_view_draws_init(gpu, &it->frame, true, kv, &b->probe_draws, err)) ||
        (st = rb_frame_buffer(gpu, kb * sizeof(struct rb_gpu_view), STORAGE, false,
                              "bdpt.bundle_views", &b->bundle_views, err)) ||
        (st = rb_frame_buffer(gpu, kb * sizeof(struct rb_gpu_list_counter), STORAGE, true,
                              "bdpt.usage", &d->usage, err)) ||
        (st = rb_frame_buffer(gpu, sizeof(struct rb_gpu_bdpt_emit_info), STORAGE, false,
                              "bdpt.emit_info", &b->emit_info, err)) ||
        (st = rb_frame_buffer(gpu, sizeof(rb_pass_ltc_ggx), STORAGE, false, "bdpt.ltc", &b->ltc,
                              err)) ||
        (st = rb_gpu_buffer_upload(gpu, &b->ltc, rb_pass_ltc_ggx, sizeof(rb_pass_ltc_ggx), err)))
        return st;
    for (uint32_t c = 0; c < b->cache_count; c++)
        fill_samples(b, c, c);

    const VkImageUsageFlags target =
        VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_STORAGE_BIT;
    const VkImageUsageFlags storage = VK_IMAGE_USAGE_STORAGE_BIT;
    uint32_t rsm = it->job->integrator.bdpt.rsm_size_px;
    uint32_t rsm_layers = frame->own_shadow_layer_count ? frame->own_shadow_layer_count : 1;
    static const char *const rsm_names[RB_VIEW_RSM_TARGETS] = {
        "bdpt.rsm.position", "bdpt.rsm.normal", "bdpt.rsm.flux", "bdpt.rsm.material"};
    static const char *const probe_names[RB_VIEW_RSM_TARGETS] = {
        "bdpt.probe.position", "bdpt.probe.normal", "bdpt.probe.flux", "bdpt.probe.material"};
    for (int i = 0; i < RB_VIEW_RSM_TARGETS && st == RB_OK; i++)
        if ((st = rb_frame_image(gpu, rsm, rsm, rsm_layers, rb_view_rsm_formats[i], target, true,
                                 rsm_names[i], &b->rsm[i], err)) == RB_OK)
            st = rb_frame_image(gpu, 1, 1, kv, rb_view_rsm_formats[i], target, true, probe_names[i],
                                &b->probe[i], err);
    if (st == RB_OK)
        st = rb_frame_image(gpu, 1, 1, 1, VK_FORMAT_D32_SFLOAT,
                            VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT, false, "bdpt.probe.depth",
                            &b->probe_depth, err);
    if (st == RB_OK)
        st = rb_frame_image(gpu, rsm, rsm, 1, VK_FORMAT_D32_SFLOAT,
                            VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT, false, "bdpt.rsm.depth",
                            &b->rsm_depth, err);
    if (st == RB_OK)
        st = rb_frame_image(gpu, b->vpl_size_px, b->vpl_size_px, all, VK_FORMAT_R32_SFLOAT,
                            VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT, true,
                            "bdpt.vpl_maps", &b->vpl_maps, err);
    if (st == RB_OK)
        st = rb_frame_image(gpu, b->vpl_size_px, b->vpl_size_px, 1, VK_FORMAT_D32_SFLOAT,
                            VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT, false, "bdpt.vpl_depth",
                            &b->vpl_depth, err);
    uint64_t nodes =
        (uint64_t)it->job->integrator.bdpt.node_buffer_kib * 1024 / sizeof(struct rb_gpu_list_node);
    if (st == RB_OK)
        st = rb_view_list_init(gpu,
                               &(struct rb_view_list_desc){.width_px = b->bundle_size_px,
                                                           .height_px = b->bundle_size_px,
                                                           .capacity_nodes = (uint32_t)nodes,
                                                           .debug_name = "bdpt.bundle"},
                               &b->bundle, err);
    uint32_t sw = b->sub_width_px * b->interleave, sh = b->sub_height_px * b->interleave;
    static const char *const split_names[RB_BDPT_SPLIT_COUNT] = {
        "bdpt.split.position", "bdpt.split.normal", "bdpt.split.fresnel", "bdpt.split.geometric"};
    static const char *const light_names[4][RB_BDPT_LIGHT_COUNT] = {
        {"bdpt.accum.direct_diffuse", "bdpt.accum.direct_specular", "bdpt.accum.indirect_diffuse",
         "bdpt.accum.indirect_specular"},
        {"bdpt.gathered.direct_diffuse", "bdpt.gathered.direct_specular",
         "bdpt.gathered.indirect_diffuse", "bdpt.gathered.indirect_specular"},
        {"bdpt.cache.direct_diffuse", "bdpt.cache.direct_specular", "bdpt.cache.indirect_diffuse",
         "bdpt.cache.indirect_specular"},
        {"bdpt.light.direct_diffuse", "bdpt.light.direct_specular", "bdpt.light.indirect_diffuse",
         "bdpt.light.indirect_specular"}};
    const VkFormat f = VK_FORMAT_R32G32B32A32_SFLOAT;
    for (int i = 0; i < RB_BDPT_SPLIT_COUNT && st == RB_OK; i++)
        st = rb_frame_image(gpu, sw, sh, 1, f, storage, false, split_names[i], &b->split[i], err);
    uint32_t w = frame->width_px, h = frame->height_px, l = b->cache_count;
    for (int i = 0; i < RB_BDPT_LIGHT_COUNT && st == RB_OK; i++)
        if ((st = rb_frame_image(gpu, sw, sh, 1, f, storage | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                                 false, light_names[0][i], &b->accum[i], err)) == RB_OK &&
            (st = rb_frame_image(gpu, w, h, 1, f, storage, false, light_names[1][i],
                                 &b->gathered[i], err)) == RB_OK &&
            (st = rb_frame_image(gpu, w, h, l, f, storage, true, light_names[2][i], &b->filtered[i],
                                 err)) == RB_OK)
            st = rb_frame_image(gpu, w, h, 1, f, storage, false, light_names[3][i], &b->light[i],
                                err);
    static const char *const emitted_names[RB_BDPT_EMITTED_COUNT] = {"bdpt.emitted.diffuse",
                                                                     "bdpt.emitted.specular"};
    for (int i = 0; i < RB_BDPT_EMITTED_COUNT && st == RB_OK; i++)
        st = rb_frame_image(gpu, w, h, 1, f, storage, false, emitted_names[i], &b->emitted[i], err);
    if (st == RB_OK)
        st = rb_frame_image(gpu, w, h, l, f, storage | VK_IMAGE_USAGE_TRANSFER_DST_BIT, true,
                            "bdpt.reproject", &b->reproject, err);
    if (st == RB_OK)
        st = rb_frame_buffer(gpu, sizeof(struct rb_gpu_bdpt_history),
                             VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, true, "bdpt.history", &b->history,
                             err);
    if (st == RB_OK)
        st = rb_frame_buffer(gpu, (VkDeviceSize)w * h * sizeof(float), STORAGE, true, "bdpt.hits",
                             &b->hits, err);
    static const char *const jittered_names[RB_GBUFFER_COLOR_COUNT] = {
        "bdpt.gbuffer.position", "bdpt.gbuffer.normal",   "bdpt.gbuffer.albedo",
        "bdpt.gbuffer.specular", "bdpt.gbuffer.emission", "bdpt.gbuffer.motion"};
    for (int i = 0; i < RB_GBUFFER_COLOR_COUNT && st == RB_OK && l > 1; i++)
        st = rb_frame_image(gpu, w, h, 1, rb_gbuffer_formats[i],
                            VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_STORAGE_BIT, false,
                            jittered_names[i], &d->jittered[i], err);
    if (st == RB_OK && l > 1)
        st = rb_frame_image(gpu, w, h, 1, VK_FORMAT_D32_SFLOAT,
                            VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT, false,
                            "bdpt.gbuffer.depth", &d->jittered_depth, err);
    if (st)
        return st;

    VkCommandBuffer cmd;
    if ((st = rb_gpu_oneshot_begin(gpu, &cmd, err)))
        return st;
    struct rb_gpu_image *general[] = {&b->rsm[0],    &b->rsm[1],      &b->rsm[2],   &b->rsm[3],
                                      &b->rsm_depth, &b->probe[0],    &b->probe[1], &b->probe[2],
                                      &b->probe[3],  &b->probe_depth, &b->vpl_maps, &b->vpl_depth};
    for (size_t i = 0; i < COUNT(general); i++)
        rb_gpu_image_barrier(gpu, cmd, general[i], VK_IMAGE_LAYOUT_UNDEFINED,
                             VK_IMAGE_LAYOUT_GENERAL);
    for (int i = 0; i < RB_BDPT_LIGHT_COUNT; i++) {
        rb_gpu_image_barrier(gpu, cmd, &b->split[i], VK_IMAGE_LAYOUT_UNDEFINED,
                             VK_IMAGE_LAYOUT_GENERAL);
        rb_gpu_image_barrier(gpu, cmd, &b->accum[i], VK_IMAGE_LAYOUT_UNDEFINED,
                             VK_IMAGE_LAYOUT_GENERAL);
        rb_gpu_image_barrier(gpu, cmd, &b->gathered[i], VK_IMAGE_LAYOUT_UNDEFINED,
                             VK_IMAGE_LAYOUT_GENERAL);
        rb_gpu_image_barrier(gpu, cmd, &b->filtered[i], VK_IMAGE_LAYOUT_UNDEFINED,
                             VK_IMAGE_LAYOUT_GENERAL);
        rb_gpu_image_barrier(gpu, cmd, &b->light[i], VK_IMAGE_LAYOUT_UNDEFINED,
                             VK_IMAGE_LAYOUT_GENERAL);
    }
    for (int i = 0; i < RB_BDPT_EMITTED_COUNT; i++)
        rb_gpu_image_barrier(gpu, cmd, &b->emitted[i], VK_IMAGE_LAYOUT_UNDEFINED,
                             VK_IMAGE_LAYOUT_GENERAL);
    rb_gpu_image_barrier(gpu, cmd, &b->reproject, VK_IMAGE_LAYOUT_UNDEFINED,
                         VK_IMAGE_LAYOUT_GENERAL);
    for (int i = 0; i < RB_GBUFFER_COLOR_COUNT && l > 1; i++)
        rb_gpu_image_barrier(gpu, cmd, &d->jittered[i], VK_IMAGE_LAYOUT_UNDEFINED,
                             VK_IMAGE_LAYOUT_GENERAL);
    if (l > 1)
        rb_gpu_image_barrier(gpu, cmd, &d->jittered_depth, VK_IMAGE_LAYOUT_UNDEFINED,
                             VK_IMAGE_LAYOUT_GENERAL);
    return rb_gpu_oneshot_end(gpu, cmd, err);
}

static enum rb_status create(struct rb_integrator *it, void **state, struct rb_err *err)
{
    const struct rb_job_bdpt *job = &it->job->integrator.bdpt;
    const struct rb_frame *frame = &it->frame;
    struct bdpt *d = calloc(1, sizeof(*d));
    if (!d)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    struct rb_bdpt_frame *b = &d->b;
    uint32_t n = job->interleave ? job->interleave : 1;
    struct rb_vec3 lo = it->setup.bounds_min, hi = it->setup.bounds_max;
    float diag = rb_v3_length(rb_v3_sub(hi, lo));
    if (!(diag > 0.0f))
        diag = 2.0f;
    *b = (struct rb_bdpt_frame){
        .vpl_count = job->vpls,
        .bundle_count = job->bundles,
        .interleave = n,
        .sub_width_px = (frame->width_px + n - 1) / n,
        .sub_height_px = (frame->height_px + n - 1) / n,
        .vpl_size_px = job->vpl_size_px,
        .bounce_vpl_size_px = job->bounce_vpl_size_px && job->bounce_vpl_size_px < job->vpl_size_px
                                  ? job->bounce_vpl_size_px
                                  : job->vpl_size_px,
        .bundle_size_px = job->bundle_size_px,
        .filter_radius_px = job->filter_radius_px,
        .filter_depth = job->filter_depth,
        .filter_normal = job->filter_normal,
        .filter_light = job->filter_light,
        .clamp_g = job->clamp / (diag * diag),
        .vpl_bias = job->vpl_bias,
        .min_roughness = job->min_roughness,
        .vpl_spread = job->vpl_spread,
        .strategies = job->strategies ? job->strategies : RB_BDPT_STRATEGIES_MIS,
        .scene_centre = {0.5f * (lo.x + hi.x), 0.5f * (lo.y + hi.y), 0.5f * (lo.z + hi.z)},
        .scene_radius = 0.5f * diag,
        .cache_count = cache_count(it->job),
    };
    for (uint32_t i = 0; i < RB_BDPT_MAX_CACHES; i++) {
        d->written[i] = INT_MIN;
        cache_offset(b->cache_count, i, job->subpixel == RB_BDPT_SUBPIXEL_SPREAD, d->offset_px[i]);
    }
    static const struct rb_view_variant variants[] = {
        {RB_VIEW_KIND_PERSPECTIVE, RB_VIEW_OUTPUT_RSM},
        {RB_VIEW_KIND_ORTHOGRAPHIC, RB_VIEW_OUTPUT_RSM},
        {RB_VIEW_KIND_PARABOLOID, RB_VIEW_OUTPUT_DEPTH},
        {RB_VIEW_KIND_ORTHOGRAPHIC, RB_VIEW_OUTPUT_LIST},
    };
    enum rb_status st;
    if ((st = rb_base_create(it, &d->base, err)) ||
        (st = rb_pass_view_create(it->gpu,
                                  &(struct rb_pass_view_desc){.variants = variants,
                                                              .variant_count = COUNT(variants),
                                                              .debug_name = "bdpt.view"},
                                  &d->views, err)) ||
        (st = rb_pass_bdpt_create(it->gpu, &d->passes, err)) ||
        (st = rb_pass_reproject_create(it->gpu, &d->reproject, err)) ||
        (st = make_resources(it, d, err))) {
        destroy(it, d);
        return st;
    }
    *state = d;
    return RB_OK;
}

static float luminance(const float c[3])
{
    return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2];
}

/* Each light's chance of a VPL among the punctual lights, by emitted power (BDPT.md "VPL"),
 * and its sampling densities: a point light's sphere, a spot light's cone, a directional
 * light's beam across its shadow map's square. Lights without a shadow map get no VPLs (the
 * bundles' side lights them). Generate weighs the sum, set in b, against the emitters'. */
/* Light l's emitted power as VPLs see it (0 without a shadow map: gl, its GPU record), and
 * its sampling density and spot cosine. */
static double light_power(const struct rb_world_light *l, const struct rb_gpu_light *gl, float beam,
                          float *density, float *cos_outer)
{
    float lum = luminance(l->color);
    *cos_outer = 0.0f;
    if (l->type == RB_LIGHT_DIRECTIONAL) {
        *density = 1.0f / (beam * beam);
    } else if (l->type == RB_LIGHT_SPOT) {
        *cos_outer = cosf(l->outer_cone_rad);
        *density = 1.0f / (2.0f * (float)RB_PI * (1.0f - *cos_outer));
    } else {
        *density = 1.0f / (4.0f * (float)RB_PI);
    }
    return gl->color[3] >= 0.0f && lum > 0.0f ? lum / *density : 0.0;
}

static void write_lights(const struct rb_integrator *it, struct rb_bdpt_frame *b,
                         const struct rb_moment *m)
{
    struct rb_gpu_bdpt_light *out = b->lights.mapped;
    const struct rb_gpu_light *gl = it->frame.lights.mapped;
    double total = 0.0;
    float beam = 2.0f * b->scene_radius; /* write_shadow_views' box: 2 radius across */
    uint32_t count = m->light_count - m->layer_light_count; /* the layers' are not bdpt's */
    for (uint32_t i = 0; i < count; i++) {
        float density, cos_outer;
        total += light_power(&m->lights[i], &gl[i], beam, &density, &cos_outer);
        out[i] = (struct rb_gpu_bdpt_light){.choice = {0.0f, 0.0f, density, cos_outer}};
    }
    b->punctual_power = (float)total;
    double cdf = 0.0;
    for (uint32_t i = 0; i < count && total > 0.0; i++) {
        float density, cos_outer;
        double power = light_power(&m->lights[i], &gl[i], beam, &density, &cos_outer);
        cdf += power;
        out[i].choice[0] = (float)(power / total);
        out[i].choice[1] = cdf >= total ? 1.0f : (float)(cdf / total);
    }
}

static void record_rsm(struct rb_integrator *it, struct bdpt *d, VkCommandBuffer cmd,
                       const struct rb_frame_ctx *ctx)
{
    struct rb_frame *frame = &it->frame;
    struct rb_bdpt_frame *b = &d->b;
    const struct rb_gpu_access uses[] = {
        {.buffer = &ctx->cur->vertices, .use = RB_GPU_VERTEX_READ},
        {.buffer = &frame->shadow_views, .use = RB_GPU_GRAPHICS_READ},
        {.buffer = rb_view_index_buffer(frame, true), .use = RB_GPU_INDEX_READ},
        {.buffer = &frame->materials, .use = RB_GPU_FRAGMENT_READ},
        {.image = &frame->srgb_textures, .use = RB_GPU_FRAGMENT_SAMPLED},
        {.image = &frame->linear_textures, .use = RB_GPU_FRAGMENT_SAMPLED},
        {.image = &b->rsm[0], .use = RB_GPU_COLOR_ATTACHMENT},
        {.image = &b->rsm[1], .use = RB_GPU_COLOR_ATTACHMENT},
        {.image = &b->rsm[3], .use = RB_GPU_COLOR_ATTACHMENT},
        {.image = &b->rsm_depth, .use = RB_GPU_DEPTH_ATTACHMENT},
    };
    rb_integrator_pass_begin(it, cmd, "rsm", uses, COUNT(uses));
    const struct rb_gpu_light *lights = frame->lights.mapped;
    for (uint32_t i = 0; i < frame->light_count - frame->layer_light_count; i++) {
        int first = (int)lights[i].color[3];
        if (first < 0)
            continue;
        uint32_t kind = (uint32_t)lights[i].position[3];
        struct rb_view_batch batch = {
            .kind =
                kind == RB_KIND_DIRECTIONAL ? RB_VIEW_KIND_ORTHOGRAPHIC : RB_VIEW_KIND_PERSPECTIVE,
            .output = RB_VIEW_OUTPUT_RSM,
            .views = &frame->shadow_views,
            .first_view = (uint32_t)first,
            .first_layer = (uint32_t)first,
            .view_count = kind == RB_KIND_POINT ? 6 : 1,
            /* generate reads where the light lands, not its flux: no flux target */
            .targets = {&b->rsm[0], &b->rsm[1], NULL, &b->rsm[3]},
            .depth = &b->rsm_depth,
            .intensity = {lights[i].color[0], lights[i].color[1], lights[i].color[2]},
            .use_simplified = true,
        };
        rb_pass_view_record(d->views, cmd, frame, ctx->cur, &batch);
    }
    rb_integrator_pass_end(it, cmd);
}

/* The VPLs' bounces (BDPT.md "Two bounces"), one round: each probe (a 1x1 reflective shadow
 * map along its direction: the first surface its VPL's light meets), then the bounces from them:
 * round 0 makes VPLs K_v + i from VPLs i, round 1 VPLs 2 K_v + i from the emitters' bounces. */
static void record_bounce(struct rb_integrator *it, struct bdpt *d, VkCommandBuffer cmd,
                          const struct rb_frame_ctx *ctx, uint32_t round)
{
    struct rb_frame *frame = &it->frame;
    struct rb_bdpt_frame *b = &d->b;
    const struct rb_gpu_access probe[] = {
        {.buffer = &ctx->cur->vertices, .use = RB_GPU_VERTEX_READ},
        {.buffer = &b->probe_views, .use = RB_GPU_GRAPHICS_READ},
        {.buffer = &b->probe_draws, .use = RB_GPU_INDIRECT_READ},
        {.buffer = rb_view_index_buffer(frame, true), .use = RB_GPU_INDEX_READ},
        {.buffer = &frame->materials, .use = RB_GPU_FRAGMENT_READ},
        {.image = &frame->srgb_textures, .use = RB_GPU_FRAGMENT_SAMPLED},
        {.image = &frame->linear_textures, .use = RB_GPU_FRAGMENT_SAMPLED},
        {.image = &b->probe[0], .use = RB_GPU_COLOR_ATTACHMENT},
        {.image = &b->probe[1], .use = RB_GPU_COLOR_ATTACHMENT},
        {.image = &b->probe[2], .use = RB_GPU_COLOR_ATTACHMENT},
        {.image = &b->probe[3], .use = RB_GPU_COLOR_ATTACHMENT},
        {.image = &b->probe_depth, .use = RB_GPU_DEPTH_ATTACHMENT},
    };
    rb_integrator_pass_begin(it, cmd, "probe", probe, COUNT(probe));
    rb_pass_view_record(d->views, cmd, frame, ctx->cur,
                        &(struct rb_view_batch){
                            .kind = RB_VIEW_KIND_PERSPECTIVE,
                            .output = RB_VIEW_OUTPUT_RSM,
                            .views = &b->probe_views,
                            .view_count = b->vpl_count,
                            .targets = {&b->probe[0], &b->probe[1], &b->probe[2], &b->probe[3]},
                            .depth = &b->probe_depth,
                            .use_simplified = true,
                            .draws = &b->probe_draws,
                        });
    rb_integrator_pass_end(it, cmd);

    const struct rb_gpu_access bounce[] = {
        {.buffer = &b->vpls, .use = RB_GPU_COMPUTE_READ_WRITE},
        {.buffer = &b->vpl_views, .use = RB_GPU_COMPUTE_WRITE},
        {.buffer = &b->probe_views, .use = RB_GPU_COMPUTE_READ_WRITE},
        {.image = &b->probe[0], .use = RB_GPU_COMPUTE_READ},
        {.image = &b->probe[1], .use = RB_GPU_COMPUTE_READ},
        {.image = &b->probe[3], .use = RB_GPU_COMPUTE_READ},
        {.buffer = &b->vpl_draws, .use = RB_GPU_COMPUTE_WRITE},
        {.buffer = &b->samples, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &b->probe_draws, .use = RB_GPU_COMPUTE_WRITE},
    };
    rb_integrator_pass_begin(it, cmd, "bounce", bounce, COUNT(bounce));
    rb_pass_bdpt_bounce_record(d->passes, cmd, b, round);
    rb_integrator_pass_end(it, cmd);
}

static void record_bundle(struct rb_integrator *it, struct bdpt *d, VkCommandBuffer cmd,
                          const struct rb_frame_ctx *ctx, uint32_t k)
{
    struct rb_frame *frame = &it->frame;
    struct rb_bdpt_frame *b = &d->b;
    const struct rb_gpu_access uses[] = {
        {.buffer = &ctx->cur->vertices, .use = RB_GPU_VERTEX_READ},
        {.buffer = &b->bundle_views, .use = RB_GPU_GRAPHICS_READ},
        {.buffer = rb_view_index_buffer(frame, true), .use = RB_GPU_INDEX_READ},
        {.buffer = &frame->materials, .use = RB_GPU_FRAGMENT_READ},
        {.image = &frame->srgb_textures, .use = RB_GPU_FRAGMENT_SAMPLED},
        {.image = &frame->linear_textures, .use = RB_GPU_FRAGMENT_SAMPLED},
        {.image = &b->bundle.heads, .use = RB_GPU_FRAGMENT_READ_WRITE},
        {.buffer = &b->bundle.nodes, .use = RB_GPU_FRAGMENT_READ_WRITE},
        {.buffer = &d->usage, .use = RB_GPU_TRANSFER_WRITE},
        {.image = &b->split[0], .use = RB_GPU_COMPUTE_READ},
    };
    rb_integrator_pass_begin(it, cmd, "bundle", uses, COUNT(uses));
    /* Lists only where sub-image k mod n^2's points search the bundle: the rest of the grid
     * skips the fragment shader's work. */
    rb_view_list_clear(cmd, &b->bundle, 0, 1, RB_VIEW_LIST_SKIP,
                       VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT |
                           VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT);
    rb_pass_bdpt_mark_record(d->passes, cmd, b, k);
    rb_gpu_memory_barrier(
        cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
        VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
        VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
    struct rb_view_batch batch = {
        .kind = RB_VIEW_KIND_ORTHOGRAPHIC,
        .output = RB_VIEW_OUTPUT_LIST,
        .views = &b->bundle_views,
        .first_view = k,
        .first_layer = 0,
        .view_count = 1,
        .list = &b->bundle,
        .has_marked_heads = true,
        .use_simplified = true,
    };
    rb_pass_view_record(d->views, cmd, frame, ctx->cur, &batch);
    /* The pool's counters, kept per bundle for collect (the next batch resets them). */
    rb_gpu_memory_barrier(cmd, VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
                          VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                          VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_READ_BIT);
    VkBufferCopy region = {.srcOffset = 0,
                           .dstOffset = (VkDeviceSize)k * sizeof(struct rb_gpu_list_counter),
                           .size = sizeof(struct rb_gpu_list_counter)};
    vkCmdCopyBuffer(cmd, b->bundle.counter.buffer, d->usage.buffer, 1, &region);
    rb_integrator_pass_end(it, cmd);
}

/* Iteration k of connect; with k = RB_NONE its emitters' dispatch, which writes b->emitted and
 * reads what an iteration reads. */
static void record_connect(struct rb_integrator *it, struct bdpt *d, VkCommandBuffer cmd,
                           uint32_t k)
{
    struct rb_frame *frame = &it->frame;
    struct rb_bdpt_frame *b = &d->b;
    struct rb_gpu_access uses[14 + RB_BDPT_SPLIT_COUNT + RB_BDPT_LIGHT_COUNT] = {
        {.buffer = &frame->globals, .use = RB_GPU_COMPUTE_UNIFORM},
        {.buffer = &b->vpls, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &b->vpl_views, .use = RB_GPU_COMPUTE_READ},
        {.image = &b->vpl_maps, .use = RB_GPU_COMPUTE_SAMPLED},
        {.buffer = &b->bundle_views, .use = RB_GPU_COMPUTE_READ},
        {.image = &b->bundle.heads, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &b->bundle.nodes, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &frame->lights, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &b->lights, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &frame->shadow_views, .use = RB_GPU_COMPUTE_READ},
        {.image = &frame->shadow_maps, .use = RB_GPU_COMPUTE_SAMPLED},
        {.image = &frame->env_map, .use = RB_GPU_COMPUTE_SAMPLED},
        {.buffer = &b->emit_info, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &b->ltc, .use = RB_GPU_COMPUTE_READ},
    };
    uint32_t count = 14;
    for (int i = 0; i < RB_BDPT_SPLIT_COUNT; i++)
        uses[count++] = (struct rb_gpu_access){.image = &b->split[i], .use = RB_GPU_COMPUTE_READ};
    if (k == RB_NONE) {
        for (int i = 0; i < RB_BDPT_EMITTED_COUNT; i++)
            uses[count++] =
                (struct rb_gpu_access){.image = &b->emitted[i], .use = RB_GPU_COMPUTE_WRITE};
        rb_integrator_pass_begin(it, cmd, "emitter_direct", uses, count);
        rb_pass_bdpt_emitters_direct_record(d->passes, cmd, frame, b);
        rb_integrator_pass_end(it, cmd);
        return;
    }
    for (int i = 0; i < RB_BDPT_LIGHT_COUNT; i++)
        uses[count++] =
            (struct rb_gpu_access){.image = &b->accum[i], .use = RB_GPU_COMPUTE_READ_WRITE};
    rb_integrator_pass_begin(it, cmd, "connect", uses, count);
    rb_pass_bdpt_connect_record(d->passes, cmd, frame, b, k);
    rb_integrator_pass_end(it, cmd);
}

/* Cache b->slot: everything from the RSMs to the filter, on the cache's G-buffer (b->gbuffer),
 * with the slot's block of the sampling table. */
static void record_cache(struct rb_integrator *it, struct bdpt *d, VkCommandBuffer cmd,
                         const struct rb_frame_ctx *ctx)
{
    struct rb_bdpt_frame *b = &d->b;
    struct rb_frame *frame = &it->frame;
    const struct rb_gpu_image *gb = b->gbuffer;
    write_lights(it, b, ctx->moment);
    record_rsm(it, d, cmd, ctx);

    const struct rb_gpu_access bounds[] = {
        {.image = &gb[RB_GB_POSITION], .use = RB_GPU_COMPUTE_READ},
        {.buffer = &b->bounds, .use = RB_GPU_COMPUTE_READ_WRITE},
    };
    rb_integrator_pass_begin(it, cmd, "bounds", bounds, COUNT(bounds));
    rb_pass_bdpt_bounds_record(d->passes, cmd, frame, b);
    rb_integrator_pass_end(it, cmd);

    const struct rb_gpu_access generate[] = {
        {.buffer = &b->bounds, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &b->samples, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &frame->lights, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &b->lights, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &frame->shadow_views, .use = RB_GPU_COMPUTE_READ},
        {.image = &b->rsm[0], .use = RB_GPU_COMPUTE_READ},
        {.image = &b->rsm[1], .use = RB_GPU_COMPUTE_READ},
        {.image = &b->rsm[3], .use = RB_GPU_COMPUTE_READ},
        {.buffer = &b->vpls, .use = RB_GPU_COMPUTE_WRITE},
        {.buffer = &b->vpl_views, .use = RB_GPU_COMPUTE_WRITE},
        {.buffer = &b->bundle_views, .use = RB_GPU_COMPUTE_WRITE},
        {.buffer = &ctx->cur->vertices, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &b->emitters, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &frame->materials, .use = RB_GPU_COMPUTE_READ},
        {.image = &frame->srgb_textures, .use = RB_GPU_COMPUTE_SAMPLED},
        {.image = &frame->linear_textures, .use = RB_GPU_COMPUTE_SAMPLED},
        {.buffer = &b->emit_info, .use = RB_GPU_COMPUTE_WRITE},
        {.buffer = &b->probe_views, .use = RB_GPU_COMPUTE_WRITE},
        {.buffer = &b->vpl_draws, .use = RB_GPU_COMPUTE_WRITE},
        {.buffer = &b->probe_draws, .use = RB_GPU_COMPUTE_WRITE},
        {.buffer = &b->emitter_cdf, .use = RB_GPU_COMPUTE_READ},
    };
    if (b->emitter_count) {
        const struct rb_gpu_access emitters[] = {
            {.buffer = &ctx->cur->vertices, .use = RB_GPU_COMPUTE_READ},
            {.buffer = &b->emitters, .use = RB_GPU_COMPUTE_READ},
            {.buffer = &frame->materials, .use = RB_GPU_COMPUTE_READ},
            {.buffer = &b->emitter_cdf, .use = RB_GPU_COMPUTE_WRITE},
        };
        rb_integrator_pass_begin(it, cmd, "emitters", emitters, COUNT(emitters));
        rb_pass_bdpt_emitters_record(d->passes, cmd, frame, ctx->cur, b);
        rb_integrator_pass_end(it, cmd);
    }
    rb_integrator_pass_begin(it, cmd, "generate", generate, COUNT(generate));
    rb_pass_bdpt_generate_record(d->passes, cmd, frame, ctx->cur, b);
    rb_integrator_pass_end(it, cmd);
    if (b->has_bounce)
        record_bounce(it, d, cmd, ctx, 0);
    if (b->has_chain)
        record_bounce(it, d, cmd, ctx, 1);

    if (b->vpl_count) {
        const struct rb_gpu_access vpl[] = {
            {.buffer = &ctx->cur->vertices, .use = RB_GPU_VERTEX_READ},
            {.buffer = &b->vpl_views, .use = RB_GPU_GRAPHICS_READ},
            {.buffer = &b->vpl_draws, .use = RB_GPU_INDIRECT_READ},
            {.buffer = rb_view_index_buffer(frame, true), .use = RB_GPU_INDEX_READ},
            {.image = &b->vpl_maps, .use = RB_GPU_COLOR_ATTACHMENT},
            {.image = &b->vpl_depth, .use = RB_GPU_DEPTH_ATTACHMENT},
        };
        /* The VPLs' maps at vpl_size; their bounces' (layers K_v on) in a corner of theirs at
         * bounce_vpl_size, when the job makes it smaller: their light has scattered once more,
         * and the pass's time is mostly the maps' fragments. */
        struct rb_view_batch batch = {
            .kind = RB_VIEW_KIND_PARABOLOID,
            .output = RB_VIEW_OUTPUT_DEPTH,
            .views = &b->vpl_views,
            .view_count = b->vpl_count,
            .targets = {&b->vpl_maps},
            .depth = &b->vpl_depth,
            .use_simplified = true,
            .draws = &b->vpl_draws,
        };
        rb_integrator_pass_begin(it, cmd, "vpl", vpl, COUNT(vpl));
        rb_pass_view_record(d->views, cmd, frame, ctx->cur, &batch);
        batch.first_view = batch.first_layer = b->vpl_count;
        batch.view_count = b->vpl_count * (vpl_generations(b) - 1);
        batch.size_px = b->bounce_vpl_size_px;
        rb_pass_view_record(d->views, cmd, frame, ctx->cur, &batch);
        rb_integrator_pass_end(it, cmd);
    }

    struct rb_gpu_access split[5 + RB_BDPT_SPLIT_COUNT + RB_BDPT_LIGHT_COUNT] = {
        {.image = &gb[RB_GB_POSITION], .use = RB_GPU_COMPUTE_READ},
        {.image = &gb[RB_GB_NORMAL], .use = RB_GPU_COMPUTE_READ},
        {.image = &gb[RB_GB_SPECULAR], .use = RB_GPU_COMPUTE_READ},
        {.image = &gb[RB_GB_EMISSION], .use = RB_GPU_COMPUTE_READ},
        {.image = &gb[RB_GB_MOTION], .use = RB_GPU_COMPUTE_READ},
    };
    uint32_t count = 5;
    for (int i = 0; i < RB_BDPT_SPLIT_COUNT; i++)
        split[count++] = (struct rb_gpu_access){.image = &b->split[i], .use = RB_GPU_COMPUTE_WRITE};
    for (int i = 0; i < RB_BDPT_LIGHT_COUNT; i++)
        split[count++] = (struct rb_gpu_access){.image = &b->accum[i], .use = RB_GPU_COMPUTE_WRITE};
    rb_integrator_pass_begin(it, cmd, "split", split, count);
    rb_pass_bdpt_split_record(d->passes, cmd, b);
    rb_integrator_pass_end(it, cmd);

    uint32_t loops = b->vpl_count > b->bundle_count ? b->vpl_count : b->bundle_count;
    for (uint32_t k = 0; k < loops; k++) {
        if (k < b->bundle_count)
            record_bundle(it, d, cmd, ctx, k);
        record_connect(it, d, cmd, k);
    }
    record_connect(it, d, cmd, RB_NONE); /* the emitters' points at every pixel */
    if (b->bundle_count)                 /* the counters' copies, for collect */
        rb_gpu_memory_barrier(cmd, VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT,
                              VK_ACCESS_2_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_2_HOST_BIT,
                              VK_ACCESS_2_HOST_READ_BIT);

    struct rb_gpu_access gather[2 * RB_BDPT_LIGHT_COUNT];
    for (int i = 0; i < RB_BDPT_LIGHT_COUNT; i++) {
        gather[2 * i] = (struct rb_gpu_access){.image = &b->accum[i], .use = RB_GPU_COMPUTE_READ};
        gather[2 * i + 1] =
            (struct rb_gpu_access){.image = &b->gathered[i], .use = RB_GPU_COMPUTE_WRITE};
    }
    rb_integrator_pass_begin(it, cmd, "gather", gather, COUNT(gather));
    rb_pass_bdpt_gather_record(d->passes, cmd, frame, b);
    rb_integrator_pass_end(it, cmd);

    struct rb_gpu_access filter[2 + 2 * RB_BDPT_LIGHT_COUNT + RB_BDPT_EMITTED_COUNT] = {
        {.image = &gb[RB_GB_POSITION], .use = RB_GPU_COMPUTE_READ},
        {.image = &gb[RB_GB_NORMAL], .use = RB_GPU_COMPUTE_READ},
    };
    for (int i = 0; i < RB_BDPT_EMITTED_COUNT; i++)
        filter[2 + 2 * RB_BDPT_LIGHT_COUNT + i] =
            (struct rb_gpu_access){.image = &b->emitted[i], .use = RB_GPU_COMPUTE_READ};
    for (int i = 0; i < RB_BDPT_LIGHT_COUNT; i++) {
        filter[2 + 2 * i] =
            (struct rb_gpu_access){.image = &b->gathered[i], .use = RB_GPU_COMPUTE_READ};
        filter[3 + 2 * i] =
            (struct rb_gpu_access){.image = &b->filtered[i], .use = RB_GPU_COMPUTE_WRITE};
    }
    rb_integrator_pass_begin(it, cmd, "filter", filter, COUNT(filter));
    rb_pass_bdpt_filter_record(d->passes, cmd, frame, b);
    rb_integrator_pass_end(it, cmd);
}

/* What reproject and reconstruct read of the caches this frame, by age (the cache written a
 * frames ago) and by slot. A cache counts when its slot holds frame f - a, written in this
 * run (a warm-up included) and not before the sequence's start, unless the job fills before it. */
static void write_history(const struct rb_integrator *it, struct bdpt *d, int f)
{
    const struct rb_bdpt_frame *b = &d->b;
    const struct rb_job_bdpt *job = &it->job->integrator.bdpt;
    struct rb_gpu_bdpt_history *h = b->history.mapped;
    uint32_t l = b->cache_count, mask = 1u; /* age 0: this frame's, written now */
    memset(h, 0, sizeof(*h));
    for (uint32_t a = 0; a < l; a++) {
        uint32_t slot = wrap((int64_t)f - a, l);
        memcpy(h->view_proj[a], d->then[slot].view_proj.m, sizeof(h->view_proj[a]));
        memcpy(h->depth_row[a], d->then[slot].depth_row, sizeof(h->depth_row[a]));
        if (a > 0 && d->written[slot] == f - (int)a)
            mask |= 1u << a;
        h->offset[a][0] = d->offset_px[a][0];
        h->offset[a][1] = d->offset_px[a][1];
    }
    h->info[0] = l;
    h->info[1] = mask;
    h->info[2] =
        job->hit_test == RB_BDPT_HIT_BINARY ? RB_BDPT_HIT_TEST_BINARY : RB_BDPT_HIT_TEST_GAUSSIAN;
    h->info[3] = wrap(f, l);
    h->params[0] = 2.0f * job->hit_variance;
    h->params[1] = job->hit_epsilon;
    h->params[2] = job->filter_normal;
}

/* Frame f's camera, for the frames that reproject into it while its cache lives. */
static void remember_camera(struct rb_integrator *it, struct bdpt *d,
                            const struct rb_frame_ctx *ctx)
{
    const struct rb_camera *cam = &ctx->moment->camera;
    struct camera_then *t = &d->then[wrap(ctx->frame, d->b.cache_count)];
    struct rb_mat4 proj = rb_frame_projection(&it->frame, cam);
    t->view_proj = rb_mat4_mul(&proj, &cam->world_to_camera);
    for (int c = 0; c < 4; c++)
        t->depth_row[c] = -cam->world_to_camera.m[c][2];
}

static void record_reproject(struct rb_integrator *it, struct bdpt *d, VkCommandBuffer cmd,
                             const struct rb_frame_ctx *ctx)
{
    struct rb_frame *frame = &it->frame;
    struct rb_bdpt_frame *b = &d->b;
    const struct rb_frame_slot *slots[RB_BDPT_MAX_CACHES];
    struct rb_gpu_access uses[5 + RB_BDPT_MAX_CACHES] = {
        {.buffer = &frame->globals, .use = RB_GPU_GRAPHICS_UNIFORM},
        {.buffer = &b->history, .use = RB_GPU_GRAPHICS_UNIFORM},
        {.buffer = &frame->indices, .use = RB_GPU_INDEX_READ},
        {.image = &frame->depth, .use = RB_GPU_DEPTH_ATTACHMENT},
        {.image = &b->reproject, .use = RB_GPU_FRAGMENT_READ_WRITE},
    };
    uint32_t count = 5;
    for (uint32_t a = 0; a < b->cache_count; a++) {
        slots[a] = &frame->slots[wrap((int64_t)ctx->frame - a, frame->slot_count)];
        uses[count++] =
            (struct rb_gpu_access){.buffer = &slots[a]->vertices, .use = RB_GPU_VERTEX_READ};
    }
    rb_integrator_pass_begin(it, cmd, "reproject", uses, count);
    rb_pass_reproject_record(d->reproject, cmd, frame,
                             &(struct rb_pass_reproject_in){.history = &b->history,
                                                            .slots = slots,
                                                            .age_count = b->cache_count,
                                                            .target = &b->reproject});
    rb_integrator_pass_end(it, cmd);
}

static void record_reconstruct(struct rb_integrator *it, struct bdpt *d, VkCommandBuffer cmd)
{
    struct rb_frame *frame = &it->frame;
    struct rb_bdpt_frame *b = &d->b;
    struct rb_gpu_access uses[5 + 2 * RB_BDPT_LIGHT_COUNT] = {
        {.buffer = &b->history, .use = RB_GPU_COMPUTE_UNIFORM},
        {.image = &frame->gbuffer[RB_GB_POSITION], .use = RB_GPU_COMPUTE_READ},
        {.image = &frame->gbuffer[RB_GB_NORMAL], .use = RB_GPU_COMPUTE_READ},
        {.image = &b->reproject, .use = RB_GPU_COMPUTE_READ},
        {.buffer = &b->hits, .use = RB_GPU_COMPUTE_WRITE},
    };
    uint32_t count = 5;
    for (int i = 0; i < RB_BDPT_LIGHT_COUNT; i++) {
        uses[count++] =
            (struct rb_gpu_access){.image = &b->filtered[i], .use = RB_GPU_COMPUTE_READ};
        uses[count++] = (struct rb_gpu_access){.image = &b->light[i], .use = RB_GPU_COMPUTE_WRITE};
    }
    rb_integrator_pass_begin(it, cmd, "reconstruct", uses, count);
    rb_pass_bdpt_reconstruct_record(d->passes, cmd, frame, b);
    rb_integrator_pass_end(it, cmd);
    /* the hit ratios, for collect */
    rb_gpu_memory_barrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                          VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, VK_PIPELINE_STAGE_2_HOST_BIT,
                          VK_ACCESS_2_HOST_READ_BIT);
}

/* A frame: animate; then, for a frame whose output is wanted, the centred G-buffer and where its
 * surfaces were in the caches' frames; shadow maps; direct light; the cache this frame writes
 * (at its subpixel offset); the caches' reconstruction and output. A warm-up frame stops after
 * its cache, and fills one only when later frames read it (l > 1) and it is not before the
 * sequence's start (the job file's first frame): a chunk's first frame then has the caches the
 * same frame of a whole run has. A quick look fills them before its start too
 * (fill_before_start), so that a still scene's one frame is the steady state. */
static void record(struct rb_integrator *it, void *state, VkCommandBuffer cmd,
                   const struct rb_frame_ctx *ctx)
{
    struct bdpt *d = state;
    struct rb_bdpt_frame *b = &d->b;
    uint32_t l = b->cache_count, slot = wrap(ctx->frame, l);
    remember_camera(it, d, ctx);
    rb_base_record_animate(it, d->base.animate, cmd, ctx->cur);
    if (ctx->is_warmup &&
        (l == 1 || (ctx->frame < it->job->sequence_start && !it->job->fill_before_start))) {
        d->written[slot] = INT_MIN;
        return;
    }
    if (!ctx->is_warmup) {
        write_history(it, d, ctx->frame);
        rb_base_record_gbuffer(it, &d->base, cmd, ctx, NULL);
        record_reproject(it, d, cmd, ctx);
    }
    rb_base_record_shadow(it, &d->base, cmd, ctx);
    if (!ctx->is_warmup)
        rb_base_record_direct_light(it, &d->base, cmd);
    /* A cache at the pixels' centres reads the frame's own G-buffer when there is one: the same
     * bits as drawing it again at offset 0 (chunks equal whole runs); a warm-up frame draws no
     * frame G-buffer, and draws the cache's. */
    bool centred = d->offset_px[slot][0] == 0.0f && d->offset_px[slot][1] == 0.0f;
    b->gbuffer = l > 1 && (ctx->is_warmup || !centred) ? d->jittered : it->frame.gbuffer;
    if (b->gbuffer == d->jittered)
        rb_base_record_gbuffer(it, &d->base, cmd, ctx,
                               &(struct rb_gbuffer_target){
                                   .colors = d->jittered,
                                   .depth = &d->jittered_depth,
                                   .offset_px = {d->offset_px[slot][0], d->offset_px[slot][1]}});
    b->slot = slot;
    b->offset_px[0] = d->offset_px[slot][0];
    b->offset_px[1] = d->offset_px[slot][1];
    if (it->job->integrator.bdpt.samples == RB_BDPT_SAMPLES_FRESH)
        fill_samples(b, slot, (uint32_t)ctx->frame);
    record_cache(it, d, cmd, ctx);
    d->written[slot] = ctx->frame;
    if (ctx->is_warmup)
        return;
    record_reconstruct(it, d, cmd);
    rb_base_record_output(it, &d->base, cmd, b->light, NULL);
}

/* The ray-bundle pool's use, bundle by bundle: the most nodes a bundle asked for, and the
 * fragments dropped because the pool was full (a warning here; the timing sidecar carries
 * the numbers, and --strict makes them fatal). */
static void collect(struct rb_integrator *it, void *state, struct rb_frame_result *out)
{
    const struct bdpt *d = state;
    const struct rb_gpu_list_counter *usage = d->usage.mapped;
    uint32_t most = 0, dropped = 0, overflowed = 0;
    for (uint32_t k = 0; k < d->b.bundle_count; k++) {
        if (usage[k].requested > most)
            most = usage[k].requested;
        dropped += usage[k].dropped;
        overflowed += usage[k].dropped > 0;
    }
    out->nonfinite_count = rb_pass_output_nonfinite_count(d->base.output);
    out->hits = d->b.hits.mapped;
    out->bundle_nodes_max = most;
    out->bundle_nodes_capacity = d->b.bundle.capacity_nodes;
    out->bundle_nodes_dropped = dropped;
    if (dropped)
        rb_log(RB_LOG_WARN,
               "frame %d: the ray-bundle node buffer overflowed: %u of %u bundles dropped %u "
               "fragments; a bundle needed up to %u nodes and the buffer holds %u (%u KiB); "
               "raise integrator.bdpt.node_buffer_kib",
               out->frame, overflowed, d->b.bundle_count, dropped, most, d->b.bundle.capacity_nodes,
               it->job->integrator.bdpt.node_buffer_kib);
}

const struct rb_integrator_ops rb_integrator_bdpt = {
    .name = "bdpt",
    .history_frames = history_frames,
    .create = create,
    .record = record,
    .collect = collect,
    .destroy = destroy,
};

const struct rb_bdpt_frame *rb_integrator_bdpt_frame(const struct rb_integrator *it)
{
    const struct bdpt *d = it->ops == &rb_integrator_bdpt ? it->state : NULL;
    return d ? &d->b : NULL;
}
