/* The hybrid integrator: deferred path tracing, seed 003 (DESIGN.md "hybrid"). Its frame:
 *   animate -> gbuffer -> shadow -> direct -> hiz -> diffuse_rays -> specular_rays -> ray_queue
 *   -> bvh_rays -> light_rays -> accumulate -> tiles -> diffuse_filter -> specular_filter ->
 *   output
 * Rasterize what can be rasterized (the G-buffer, shadow maps), sample each lobe of the BRDF at
 * every pixel that still wants samples, trace in screen space first and through a BVH (built on
 * the CPU with Embree's builder, lib/bvh, on a thread of its own, from the objects of best score
 * under a triangle budget, an object that does not fit whole by a coarser version) what the
 * screen cannot answer, shade both kinds of hit alike, accumulate over time and filter with a
 * kernel that shrinks as samples grow.
 *
 * Next-event estimation at the camera vertex. Each ray a lobe traces also takes one light
 * sample (light_rays): an emissive triangle by emitted power (the emitter table, built on the
 * device each frame from the frame's vertices), a point uniformly on it, visibility by a shadow
 * ray through the BVH. A BRDF ray that finds an emitter, in screen space or in the BVH, and the
 * light sample are weighed by the power heuristic (beta 2, the reference's), per lobe: each lobe
 * is its own integral, sampled by its own rays (pdf rb_hybrid_pdf) and by the light samples.
 * The environment has its light sample too, by the importance table of its map (the
 * reference's, env_init) or cosine-weighted without one, weighed against the rays that miss.
 *
 * Bounces (integrator.hybrid.max_bounces). Unlimited, the default: a hit reflects what the
 * pixel that saw it in the previous frame gathered, diffuse and specular, direct and indirect
 * (rb_hybrid_feedback), read from this frame's younger accumulator and never on the frame that
 * starts it again; a hit the previous frame did not see takes its baked light and one secondary
 * diffuse ray through the BVH. So each frame adds a bounce, and what an accumulator holds still
 * depends only on the frames since its start: the feedback keeps the history contract below.
 * The feedback cannot stop at a count, so a count N, the reference's path space with its
 * max_bounces N, is traced instead: a hit reflects its direct light (punctual and baked) and
 * N - 1 further bounces, a chain of rays through the BVH weighed by the BRDFs, each hit lit the
 * same way (rb_hybrid_chain); 1 is direct light alone, 0 nothing. No frame reads another's light
 * then.
 *
 * History. Two accumulators take every sample; accumulator A starts again on the frames
 * sequence_start + kW, B on sequence_start + kW + W/2 (and both on sequence_start), W =
 * integrator.hybrid.history. The output reads the one that started longer ago; the rays'
 * requests follow the younger one, and a frame that starts one ignores the noise tiles, so no
 * request depends on anything before the older one's start. A frame's state therefore depends on
 * the W frames before it at most (history_frames = W): a chunk that renders them first as
 * warm-ups gets the bits of a whole run. Warm-ups before the job's first frame record nothing
 * but animate.
 *
 * The BVH's schedule (seed 003: "async BVH construction"). Frame f traces the BVH of the pose of
 * its epoch e(f), the last frame at or before f that is a multiple of bvh_interval after
 * sequence_start, whatever frame the run began at and however long anything took; its objects
 * are chosen as seen from e(f)'s camera (rb_bvh_select's relevance). The build
 * and the bake run on a worker thread, ahead of time: as soon as the prepare of e's first frame
 * has uploaded e's BVH, the thread starts on e + bvh_interval's (the animation is a function of
 * time, so a later pose is known now; none past the run's last frame) while the main thread
 * records and the device runs the frames up to it. The first frame of the next epoch waits for
 * that build if it is not done yet, and uploads it: the device's buffers are the main thread's
 * alone. A run's first frame builds its epoch's BVH and waits for it; one that needs another
 * epoch than the one built ahead (after a gap in a frame list) cancels that build and builds
 * the one it needs. So the thread changes when the work is done, never what is built: the bits
 * are those of a build on the main thread before each epoch's first frame, and chunks and
 * thread counts cannot change them.
 *
 * Baked light (seed 003: "bake direct artificial light"). When the BVH is built, the direct light
 * of the emissive triangles and the environment is baked at points of its triangles (a lattice
 * per triangle, finer for longer edges, within integrator.hybrid.bake_texels) by the CPU
 * reference's light sampling with exact visibility (rb_reference_bake), so a hit, screen or BVH,
 * reflects it as it reflects the punctual lights: an area-lit room gets its bounce. */
#include "integrators/integrators_int.h"

#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "bvh/bvh.h"
#include "reference/reference.h"

/* The BVH's thread (the schedule above). The main thread posts the epoch it wants built and
 * takes the result before it posts another. While a job is posted, what the build and the bake
 * use (positions, built, has_built, bvh_pose, the bake's buffers and world, the result) is the
 * worker's alone; while none is, the main thread's. The device's buffers are always the main
 * thread's. */
enum bvh_state { BVH_IDLE, BVH_POSTED, BVH_DONE };

struct bvh_worker {
    pthread_t thread;
    pthread_mutex_t lock;
    pthread_cond_t cond;
    bool has_sync, has_thread;
    enum bvh_state state; /* under lock */
    bool is_quitting;     /* under lock */
    atomic_bool cancel;   /* stop the posted build early: its result is dropped */
    int64_t epoch;        /* the frame whose pose the posted job builds (the main thread's) */
    float eye[3];         /* the camera's position at that frame (the BVH's relevance) */
    /* the result */
    enum rb_status st;
    struct rb_err err;
    bool is_same; /* the pose moved no vertex since the BVH the device holds: it stands */
    struct rb_bvh bvh;
    uint32_t bake_count; /* points baked (0: no bake) */
    uint64_t bake_rays;
    double build_ms, bake_ms;
};

struct hybrid {
    struct rb_integrator *it; /* the worker's way to the job, the scene and the frame's sizes */
    struct rb_base base;
    struct rb_pass_hybrid *passes;
    struct rb_hybrid_frame h;
    const struct rb_job_hybrid *settings;
    uint32_t queue_capacity;
    /* the BVH's inputs: the world vertices of a pose and the frame's triangle list; built: the
     * vertices of the BVH on the device */
    float *positions, *built;
    uint32_t *bake_words; /* the host's copy of each global triangle's bake word */
    uint32_t *indices;
    uint32_t triangle_count;     /* the frame's; the G-buffer's triangle indices */
    uint32_t lod_triangle_count; /* the coarser objects' after them in indices */
    struct rb_bvh_object *objects;
    uint32_t object_count;
    struct rb_scene_pose *bvh_pose;
    struct rb_scene_pose *eye_pose; /* the main thread's, for the camera of an epoch */
    uint8_t *choice, *built_choice; /* the worker's: rb_bvh_select's, and the device BVH's */
    uint8_t *logged_choice;         /* the main thread's: the last selection logged */
    bool has_logged_choice;
    uint32_t node_capacity, tri_capacity;
    bool has_bvh;      /* the device holds a BVH (the main thread's) */
    int64_t bvh_epoch; /* the frame whose pose it holds */
    bool has_built;    /* built holds the device BVH's vertices (the worker's) */
    struct bvh_worker worker;
    struct rb_ray_counts counts;
    bool has_counts;
    /* the bake: the reference's world of the scene, NULL when nothing emits; its points, their
     * light, and how many the device buffer holds */
    struct rb_reference *ref;
    struct rb_reference_bake_point *bake_points;
    float *bake_rgb;
    uint32_t bake_capacity;
    uint32_t word_vec4s; /* the bake words' room, in vec4s (0 without a bake) */
    bool has_bake;
    /* next-event estimation: the emissive triangles (global indices), after the triangles in
     * the device's index buffer */
    uint32_t *emitters;
    uint32_t emitter_count;
    /* the environment's importance table (hybrid.glsl), after the emitters; 0 floats without a
     * map */
    float *env_table;
    size_t env_floats;
};

static uint32_t history_frames(const struct rb_job *job)
{
    return job->integrator.hybrid.history;
}

/* The history spans W frames, but a frame reads the vertices of its own and the previous frame
 * only (motion vectors): two animation slots, whatever W. */
static uint32_t slot_frames(const struct rb_job *job)
{
    (void)job;
    return 1;
}

static void destroy(struct rb_integrator *it, void *state)
{
    struct hybrid *d = state;
    if (!d)
        return;
    struct bvh_worker *w = &d->worker;
    if (w->has_thread) {
        /* A build ahead stops at once; a bake runs to its end (at most one frame's). */
        pthread_mutex_lock(&w->lock);
        w->is_quitting = true;
        atomic_store(&w->cancel, true);
        pthread_cond_broadcast(&w->cond);
        pthread_mutex_unlock(&w->lock);
        pthread_join(w->thread, NULL);
    }
    if (w->has_sync) {
        pthread_cond_destroy(&w->cond);
        pthread_mutex_destroy(&w->lock);
    }
    rb_bvh_release(&w->bvh);
    struct rb_gpu *gpu = it->gpu;
    struct rb_hybrid_frame *h = &d->h;
    struct rb_gpu_buffer *bufs[] = {&h->hiz,     &h->slots,     &h->counters, &h->queue,
                                    &h->blocks,  &h->bvh_nodes, &h->bvh_tris, &h->tiles,
                                    &h->indices, &h->table};
    for (size_t i = 0; i < COUNT(bufs); i++)
        rb_gpu_buffer_release(gpu, bufs[i]);
    for (uint32_t i = 0; i < 2; i++)
        rb_gpu_image_release(gpu, &h->acc[i]);
    rb_gpu_image_release(gpu, &h->stats);
    for (uint32_t i = 0; i < RB_BDPT_LIGHT_COUNT; i++)
        rb_gpu_image_release(gpu, &h->light[i]);
    rb_pass_hybrid_destroy(d->passes);
    rb_base_destroy(&d->base);
    rb_scene_pose_destroy(d->bvh_pose);
    rb_scene_pose_destroy(d->eye_pose);
    free(d->choice);
    free(d->built_choice);
    free(d->logged_choice);
    rb_reference_destroy(d->ref);
    free(d->bake_points);
    free(d->bake_rgb);
    free(d->bake_words);
    free(d->positions);
    free(d->built);
    free(d->indices);
    free(d->objects);
    free(d->emitters);
    free(d->env_table);
    free(d);
}

/* Seed 003's LOD: each object of more than RB_SCENE_SIMPLIFY_MIN_TRIANGLES triangles gets a
 * coarser version, a quarter of its triangles over the same vertices (meshoptimizer, through
 * rb_scene_simplify, on the first frame's pose: only the topology is kept), appended to the
 * triangle list; the BVH takes it when the whole object does not fit the budget. */
static enum rb_status lod_init(struct rb_integrator *it, struct hybrid *d, struct rb_err *err)
{
    uint32_t t_count = d->triangle_count, added = 0;
    rb_scene_deform(it->scene, it->cur.pose, d->positions, 3, NULL, NULL, NULL);
    for (uint32_t i = 0; i < d->object_count; i++) {
        struct rb_bvh_object *o = &d->objects[i];
        if (o->triangle_count <= RB_SCENE_SIMPLIFY_MIN_TRIANGLES)
            continue;
        uint32_t target = o->triangle_count / 4;
        if (target < RB_SCENE_SIMPLIFY_MIN_TRIANGLES)
            target = RB_SCENE_SIMPLIFY_MIN_TRIANGLES;
        uint64_t have = (uint64_t)t_count + added;
        uint32_t *grown = realloc(d->indices, (have + o->triangle_count) * 3 * sizeof(uint32_t));
        if (!grown)
            return rb_errf(err, RB_E_NOMEM, "out of memory for the BVH's coarser objects");
        d->indices = grown;
        const struct rb_scene_simplify_mesh mesh = {
            .positions = d->positions,
            .stride_bytes = 3 * sizeof(float),
            .vertex_count = it->frame.vertex_count,
            .indices = d->indices + (size_t)o->first_triangle * 3,
            .index_count = o->triangle_count * 3,
        };
        struct rb_scene_simplified res;
        enum rb_status st = rb_scene_simplify(&mesh, target, d->indices + have * 3, &res, err);
        if (st) {
            rb_err_prefix(err, "hybrid: the coarser version of object %u", i);
            return st;
        }
        uint32_t n = res.index_count / 3;
        if (n == 0 || n >= o->triangle_count)
            continue;
        o->lod_first = (uint32_t)have;
        o->lod_count = n;
        added += n;
    }
    d->lod_triangle_count = added;
    return RB_OK;
}

/* The scene's triangles as the frame's index buffer lists them, and each instance's range. */
static enum rb_status geometry_init(struct rb_integrator *it, struct hybrid *d, struct rb_err *err)
{
    const struct rb_scene *scene = it->scene;
    const struct rb_scene_pose *pose = it->cur.pose;
    uint64_t icount = 0;
    d->indices = rb_frame_world_indices(scene, pose, &icount);
    /* positions, then normals (deformed only for the bake) */
    d->positions = malloc(((size_t)it->frame.vertex_count + 1) * 6 * sizeof(float));
    d->built = malloc(((size_t)it->frame.vertex_count + 1) * 6 * sizeof(float));
    d->objects = malloc(((size_t)pose->instance_count + 1) * sizeof(*d->objects));
    d->choice = calloc((size_t)pose->instance_count + 1, 1);
    d->built_choice = calloc((size_t)pose->instance_count + 1, 1);
    d->logged_choice = calloc((size_t)pose->instance_count + 1, 1);
    if (!d->indices || !d->positions || !d->built || !d->objects || !d->choice ||
        !d->built_choice || !d->logged_choice)
        return rb_errf(err, RB_E_NOMEM, "out of memory for the BVH's %llu triangles",
                       (unsigned long long)(icount / 3));
    d->triangle_count = (uint32_t)(icount / 3);
    uint32_t first = 0;
    for (uint32_t i = 0; i < pose->instance_count; i++) {
        uint32_t n = scene->primitives[pose->instances[i].primitive].index_count / 3;
        d->objects[i] = (struct rb_bvh_object){.first_triangle = first, .triangle_count = n};
        first += n;
    }
    d->object_count = pose->instance_count;
    enum rb_status st = rb_scene_pose_create(scene, &d->bvh_pose, err);
    if (st == RB_OK)
        st = rb_scene_pose_create(scene, &d->eye_pose, err);
    if (st || !d->settings->bvh_lod)
        return st;
    return lod_init(it, d, err);
}

/* The triangles of the list the BVH chooses from: the frame's, then the coarser objects'. */
static uint64_t all_triangles(const struct hybrid *d)
{
    return (uint64_t)d->triangle_count + d->lod_triangle_count;
}

/* The most triangles the BVH may hold: the budget, or every triangle when it is 0 or larger. */
static uint64_t bvh_budget(const struct hybrid *d)
{
    uint32_t b = d->settings->bvh_triangles;
    return b && b < d->triangle_count ? b : d->triangle_count;
}

static enum rb_status create_resources(struct rb_integrator *it, struct hybrid *d,
                                       struct rb_err *err)
{
    struct rb_gpu *gpu = it->gpu;
    const struct rb_job_hybrid *s = d->settings;
    struct rb_hybrid_frame *h = &d->h;
    uint32_t w = it->frame.width_px, ht = it->frame.height_px;
    const VkBufferUsageFlags storage =
        VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    uint64_t cells = 0;
    h->hiz_levels = 0;
    for (uint32_t lw = w, lh = ht;; lw = (lw + 1) / 2, lh = (lh + 1) / 2) {
        cells += (uint64_t)lw * lh;
        h->hiz_levels++;
        if (lw == 1 && lh == 1)
            break;
    }
    h->slot_count = 2ull * s->rays * w * ht;
    uint64_t capacity = s->queue_rays ? s->queue_rays : h->slot_count;
    d->queue_capacity = (uint32_t)(capacity < h->slot_count ? capacity : h->slot_count);
    uint64_t blocks = (h->slot_count + RB_HYBRID_QUEUE_GROUP - 1) / RB_HYBRID_QUEUE_GROUP;
    uint64_t tiles = (uint64_t)((w + RB_HYBRID_TILE - 1) / RB_HYBRID_TILE) *
                     ((ht + RB_HYBRID_TILE - 1) / RB_HYBRID_TILE);
    uint64_t budget = bvh_budget(d);
    d->tri_capacity = (uint32_t)(budget ? budget : 1);
    /* a node holds both children: no more nodes than leaves, so than triangles (a root at
     * least) */
    d->node_capacity = d->tri_capacity;
    /* Every buffer is bound whole, each within maxStorageBufferRange, or a clear error; but what
     * grows with the scene's triangles is read by address (geometry_shared.h) and needs only to
     * be one buffer: the triangles' indices with the tables after them, and the bake after the
     * BVH's triangles (bound as far as those, budget-bound). */
    uint64_t tri_bytes = (uint64_t)d->tri_capacity * sizeof(struct rb_gpu_bvh_triangle);
    uint64_t bake_bytes = ((uint64_t)d->word_vec4s + d->bake_capacity) * 16;
    uint64_t table_bytes =
        (all_triangles(d) * 3 + d->emitter_count + d->env_floats) * sizeof(uint32_t);
    const struct {
        const char *name;
        uint64_t bytes;
        uint64_t unbound_bytes; /* read by address alone, past the binding's range */
    } bound[] = {
        {"hierarchical depth", cells * 2 * sizeof(float), 0},
        {"ray slots", h->slot_count * sizeof(struct rb_gpu_hybrid_slot), 0},
        {"ray queue", (uint64_t)d->queue_capacity * sizeof(uint32_t), 0},
        {"queue blocks and emitter table", (blocks + d->emitter_count) * sizeof(uint32_t), 0},
        {"BVH nodes", (uint64_t)d->node_capacity * sizeof(struct rb_gpu_bvh_node), 0},
        {"BVH triangles and baked light", tri_bytes + bake_bytes, bake_bytes},
        {"noise tiles", 2 * tiles * sizeof(float), 0},
        {"triangles, emitters and the environment's table", table_bytes, table_bytes},
    };
    enum rb_status st;
    for (size_t i = 0; i < COUNT(bound); i++) {
        uint64_t range = bound[i].bytes - bound[i].unbound_bytes;
        if ((st = rb_gpu_check_buffer_size(gpu, "hybrid", bound[i].name, bound[i].bytes, err)) ||
            (range && (st = rb_gpu_check_storage_range(gpu, "hybrid", bound[i].name, range, err))))
            return st;
    }
    h->bvh_tri_bytes = tri_bytes;
    if ((st = rb_frame_buffer(gpu, bound[0].bytes, storage, false, "hybrid.hiz", &h->hiz, err)) ||
        (st = rb_frame_buffer(gpu, bound[1].bytes, storage, false, "hybrid.slots", &h->slots,
                              err)) ||
        (st = rb_frame_buffer(gpu, sizeof(struct rb_gpu_hybrid_counters),
                              storage | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT, true,
                              "hybrid.counters", &h->counters, err)) ||
        (st = rb_frame_buffer(gpu, bound[2].bytes, storage, false, "hybrid.queue", &h->queue,
                              err)) ||
        (st = rb_frame_buffer(gpu, bound[3].bytes, storage, false, "hybrid.blocks", &h->blocks,
                              err)) ||
        (st = rb_frame_buffer(gpu, bound[4].bytes, storage, true, "hybrid.bvh_nodes", &h->bvh_nodes,
                              err)) ||
        (st = rb_gpu_buffer_init(gpu,
                                 &(struct rb_gpu_buffer_desc){.size_bytes = bound[5].bytes,
                                                              .usage = storage,
                                                              .is_host_visible = true,
                                                              .is_addressed = true,
                                                              .debug_name = "hybrid.bvh_tris"},
                                 &h->bvh_tris, err)) ||
        (st = rb_frame_buffer(gpu, bound[6].bytes, storage, false, "hybrid.tiles", &h->tiles,
                              err)) ||
        (st = rb_gpu_buffer_init(
             gpu,
             &(struct rb_gpu_buffer_desc){.size_bytes = bound[7].bytes ? bound[7].bytes : 4,
                                          .usage = storage,
                                          .is_host_visible = true,
                                          .is_addressed = true,
                                          .debug_name = "hybrid.indices"},
             &h->indices, err)) ||
        (st = rb_frame_buffer(gpu, sizeof(struct rb_gpu_hybrid_table),
                              VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, true, "hybrid.table", &h->table,
                              err)))
        return st;
    memcpy(h->table.mapped,
           &(struct rb_gpu_hybrid_table){.indices = h->indices.address,
                                         .bake = h->bvh_tris.address,
                                         .bake_words = h->bvh_tris.address},
           sizeof(struct rb_gpu_hybrid_table));
    memcpy(h->indices.mapped, d->indices, all_triangles(d) * 3 * sizeof(uint32_t));
    memcpy((uint32_t *)h->indices.mapped + all_triangles(d) * 3, d->emitters,
           (size_t)d->emitter_count * sizeof(uint32_t));
    memcpy((uint32_t *)h->indices.mapped + all_triangles(d) * 3 + d->emitter_count, d->env_table,
           d->env_floats * sizeof(float));
    const VkImageUsageFlags image_use = VK_IMAGE_USAGE_STORAGE_BIT;
    static const char *const acc_names[2] = {"hybrid.acc0", "hybrid.acc1"};
    static const char *const light_names[RB_BDPT_LIGHT_COUNT] = {
        "hybrid.direct_diffuse", "hybrid.direct_specular", "hybrid.indirect_diffuse",
        "hybrid.indirect_specular"};
    for (uint32_t i = 0; i < 2; i++)
        if ((st = rb_frame_image(gpu, w, ht, RB_HYBRID_ACC_LAYERS, VK_FORMAT_R32G32B32A32_SFLOAT,
                                 image_use, false, acc_names[i], &h->acc[i], err)))
            return st;
    for (uint32_t i = 0; i < RB_BDPT_LIGHT_COUNT; i++)
        if ((st = rb_frame_image(gpu, w, ht, 1, VK_FORMAT_R32G32B32A32_SFLOAT, image_use, false,
                                 light_names[i], &h->light[i], err)))
            return st;
    if ((st = rb_frame_image(gpu, w, ht, 1, VK_FORMAT_R32G32B32A32_SFLOAT, image_use, false,
                             "hybrid.stats", &h->stats, err)))
        return st;
    /* Images to GENERAL, where they stay; the tile mask starts empty (a frame that starts an
     * accumulator does not read it, but no bit is left to chance). */
    VkCommandBuffer cmd;
    if ((st = rb_gpu_oneshot_begin(gpu, &cmd, err)))
        return st;
    struct rb_gpu_image *images[] = {&h->acc[0],   &h->acc[1],   &h->stats,   &h->light[0],
                                     &h->light[1], &h->light[2], &h->light[3]};
    _Static_assert(RB_BDPT_LIGHT_COUNT == 4, "every light image listed");
    for (size_t i = 0; i < COUNT(images); i++)
        rb_gpu_image_barrier(gpu, cmd, images[i], VK_IMAGE_LAYOUT_UNDEFINED,
                             VK_IMAGE_LAYOUT_GENERAL);
    vkCmdFillBuffer(cmd, h->tiles.buffer, 0, VK_WHOLE_SIZE, 0);
    return rb_gpu_oneshot_end(gpu, cmd, err);
}

/* Whether anything would be baked: an emissive material on some instance, or a lit
 * environment. */
static bool has_light_to_bake(const struct rb_integrator *it)
{
    const struct rb_job *job = it->job;
    const float *c = job->environment.color;
    if (job->environment.intensity > 0.0f &&
        (it->env_rgba || c[0] > 0.0f || c[1] > 0.0f || c[2] > 0.0f))
        return true;
    const struct rb_scene_pose *pose = it->cur.pose;
    for (uint32_t i = 0; i < pose->instance_count; i++) {
        uint32_t m = it->scene->primitives[pose->instances[i].primitive].material;
        const float *e = m < it->scene->material_count ? it->scene->materials[m].emissive : NULL;
        if (e && (e[0] > 0.0f || e[1] > 0.0f || e[2] > 0.0f))
            return true;
    }
    return false;
}

/* The bake's world and buffers: room for bake_texels points beyond the three of each side of
 * every triangle the BVH may hold. */
static enum rb_status bake_init(struct rb_integrator *it, struct hybrid *d, struct rb_err *err)
{
    const struct rb_job_hybrid *s = d->settings;
    if (s->bake_samples == 0 || !has_light_to_bake(it))
        return RB_OK;
    uint64_t budget = bvh_budget(d);
    uint64_t cap = (uint64_t)s->bake_texels + 6 * budget;
    uint64_t words = (all_triangles(d) + 3) / 4;
    /* the points follow the triangles' room (3 vec4s a triangle) and the words in their buffer */
    if (3 * budget + words + cap >= (1ull << (32 - RB_HYBRID_BAKE_SHIFT)))
        return rb_errf(err, RB_E_INVALID,
                       "hybrid: %llu baked points (integrator.hybrid.bake_texels %u and the "
                       "vertices of %llu triangles) are more than the %llu the bake can index",
                       (unsigned long long)cap, s->bake_texels, (unsigned long long)budget,
                       (unsigned long long)(1ull << (32 - RB_HYBRID_BAKE_SHIFT)) - 1);
    d->bake_capacity = (uint32_t)cap;
    d->word_vec4s = (uint32_t)words;
    d->bake_points = malloc((size_t)cap * sizeof(*d->bake_points));
    d->bake_rgb = malloc((size_t)cap * 3 * sizeof(float));
    d->bake_words = malloc(((size_t)all_triangles(d) + 1) * sizeof(*d->bake_words));
    if (!d->bake_points || !d->bake_rgb || !d->bake_words)
        return rb_errf(err, RB_E_NOMEM, "out of memory for %llu baked points",
                       (unsigned long long)cap);
    const struct rb_reference_desc desc = {.job = it->job,
                                           .scene = it->scene,
                                           .env_rgba = it->env_rgba,
                                           .env_width_px = it->env_width_px,
                                           .env_height_px = it->env_height_px,
                                           .setup = &it->setup,
                                           .is_bake_only = true};
    enum rb_status st = rb_reference_create(&desc, &d->ref, err);
    if (st)
        rb_err_prefix(err, "hybrid: the baked light's world");
    return st;
}

static void *bvh_main(void *arg);

/* Starts the BVH's thread, with every signal blocked in it: SIGINT and SIGTERM stay the main
 * thread's, as the frame driver's callers expect. */
static enum rb_status worker_start(struct hybrid *d, struct rb_err *err)
{
    struct bvh_worker *w = &d->worker;
    atomic_init(&w->cancel, false);
    if (pthread_mutex_init(&w->lock, NULL) != 0)
        return rb_errf(err, RB_E_NOMEM, "hybrid: cannot create the BVH thread's lock");
    if (pthread_cond_init(&w->cond, NULL) != 0) {
        pthread_mutex_destroy(&w->lock);
        return rb_errf(err, RB_E_NOMEM, "hybrid: cannot create the BVH thread's condition");
    }
    w->has_sync = true;
    sigset_t all, old;
    sigfillset(&all);
    pthread_sigmask(SIG_SETMASK, &all, &old);
    int e = pthread_create(&w->thread, NULL, bvh_main, d);
    pthread_sigmask(SIG_SETMASK, &old, NULL);
    if (e != 0)
        return rb_errf(err, RB_E_NOMEM, "hybrid: cannot start the BVH's thread: %s", strerror(e));
    w->has_thread = true;
    return RB_OK;
}

/* The emitter table's triangles (hybrid_shared.h): those of every instance whose material's
 * emissive factor is not black, as the reference and bdpt list them. */
static enum rb_status emitters_init(struct rb_integrator *it, struct hybrid *d, struct rb_err *err)
{
    const struct rb_scene *scene = it->scene;
    const struct rb_scene_pose *pose = it->cur.pose;
    uint64_t count = 0;
    for (int pass = 0; pass < 2; pass++) {
        count = 0;
        for (uint32_t i = 0; i < d->object_count; i++) {
            uint32_t m = scene->primitives[pose->instances[i].primitive].material;
            const float *e = m < scene->material_count ? scene->materials[m].emissive : NULL;
            if (!e || !(e[0] > 0.0f || e[1] > 0.0f || e[2] > 0.0f))
                continue;
            for (uint32_t k = 0; k < d->objects[i].triangle_count; k++, count++)
                if (pass)
                    d->emitters[count] = d->objects[i].first_triangle + k;
        }
        if (pass || !count)
            break;
        if (count > UINT32_MAX / 8 || !(d->emitters = malloc((size_t)count * sizeof(*d->emitters))))
            return rb_errf(err, RB_E_NOMEM, "out of memory for %llu emissive triangles",
                           (unsigned long long)count);
    }
    d->emitter_count = (uint32_t)count;
    return RB_OK;
}

/* The environment's light samples: whether it is lit, and with a map the importance table of
 * its texels, the reference's own (rb_reference_env_table), so that both sample the same
 * directions with the same pdf. */
static enum rb_status env_init(struct rb_integrator *it, struct hybrid *d, struct rb_err *err)
{
    const struct rb_job *job = it->job;
    const float *c = job->environment.color;
    bool lit = job->environment.intensity > 0.0f &&
               (it->env_rgba || c[0] > 0.0f || c[1] > 0.0f || c[2] > 0.0f);
    d->h.has_env_light = lit;
    if (!lit || !it->env_rgba)
        return RB_OK;
    d->env_floats = rb_reference_env_table_floats(it->env_width_px, it->env_height_px);
    if (!(d->env_table = malloc(d->env_floats * sizeof(float))))
        return rb_errf(err, RB_E_NOMEM, "out of memory for the environment's importance table");
    return rb_reference_env_table(it->env_rgba, it->env_width_px, it->env_height_px, d->env_table,
                                  err);
}

static enum rb_status create(struct rb_integrator *it, void **state, struct rb_err *err)
{
    struct hybrid *d = calloc(1, sizeof(*d));
    if (!d)
        return rb_errf(err, RB_E_NOMEM, "out of memory");
    d->it = it;
    d->settings = &it->job->integrator.hybrid;
    d->bvh_epoch = INT64_MIN;
    enum rb_status st;
    if ((st = rb_base_create(it, &d->base, err)) ||
        (st = rb_pass_hybrid_create(
             it->gpu, !d->settings->feedback && d->settings->max_bounces >= 2, &d->passes, err)) ||
        (st = geometry_init(it, d, err)) || (st = emitters_init(it, d, err)) ||
        (st = env_init(it, d, err)) || (st = bake_init(it, d, err)) ||
        (st = create_resources(it, d, err)) || (st = worker_start(d, err))) {
        destroy(it, d);
        return st;
    }
    *state = d;
    return RB_OK;
}

/* The frame whose pose the BVH of frame f holds: the last multiple of bvh_interval from the
 * sequence's start. */
static int64_t bvh_epoch(const struct rb_integrator *it, const struct hybrid *d, int frame)
{
    int64_t rel = (int64_t)frame - it->job->sequence_start;
    int64_t k = d->settings->bvh_interval;
    int64_t m = ((rel % k) + k) % k;
    return (int64_t)frame - m;
}

static uint32_t lattice_points(uint32_t r)
{
    return (r + 1) * (r + 2) / 2;
}

/* A triangle's lattice resolution for point spacing h: its longest edge over h, 1 to the most. */
static uint32_t lattice_res(double edge, double h)
{
    if (!(h > 0.0))
        return RB_HYBRID_BAKE_MAX_RES;
    double r = ceil(edge / h);
    return r < 1.0 ? 1 : r > RB_HYBRID_BAKE_MAX_RES ? RB_HYBRID_BAKE_MAX_RES : (uint32_t)r;
}

static uint64_t lattice_total(uint32_t n, const double *edge, const uint8_t *sides, double h)
{
    uint64_t total = 0;
    for (uint32_t k = 0; k < n; k++)
        total += (uint64_t)sides[k] * lattice_points(lattice_res(edge[k], h));
    return total;
}

static double edge_len(const float a[4], const float b[4])
{
    double x = (double)a[0] - b[0], y = (double)a[1] - b[1], z = (double)a[2] - b[2];
    return sqrt(x * x + y * y + z * z);
}

/* Bakes the emitters' and the environment's light at the lattices of the BVH's triangles (pose
 * of frame epoch) into bake_rgb, the words into bake_words and each triangle's v2.w (the
 * worker's; upload copies them to the device). The spacing is the finest whose points fit in
 * three a side of every triangle plus bake_texels. */
static enum rb_status bake(struct rb_integrator *it, struct hybrid *d, struct rb_bvh *bvh,
                           int64_t epoch, struct rb_err *err)
{
    uint32_t n = bvh->triangle_count;
    double *edge = calloc((size_t)n + 1, sizeof(double));
    uint8_t *sides = calloc((size_t)n + 1, 1);
    if (!edge || !sides) {
        free(edge);
        free(sides);
        return rb_errf(err, RB_E_NOMEM, "out of memory for the bake of %u triangles", n);
    }
    const struct rb_scene *scene = it->scene;
    const struct rb_scene_pose *pose = d->bvh_pose;
    double longest = 0.0;
    for (uint32_t k = 0; k < n; k++) {
        const struct rb_gpu_bvh_triangle *t = &bvh->triangles[k];
        double e =
            fmax(edge_len(t->v0, t->v1), fmax(edge_len(t->v1, t->v2), edge_len(t->v2, t->v0)));
        edge[k] = e;
        longest = fmax(longest, e);
        uint32_t object;
        memcpy(&object, &t->v1[3], sizeof(object));
        uint32_t m = scene->primitives[pose->instances[object].primitive].material;
        sides[k] = m < scene->material_count && scene->materials[m].double_sided ? 2 : 1;
    }
    /* The finest spacing that fits: bisection between 0 (the finest lattices) and the longest
     * edge (three points a side); the budget never falls below what the coarsest needs. */
    uint64_t coarsest = lattice_total(n, edge, sides, longest);
    uint64_t cap = coarsest + d->settings->bake_texels;
    double h = 0.0;
    if (lattice_total(n, edge, sides, 0.0) > cap) {
        double lo = 0.0, hi = longest;
        for (int i = 0; i < 60; i++) {
            double mid = 0.5 * (lo + hi);
            if (lattice_total(n, edge, sides, mid) > cap)
                lo = mid;
            else
                hi = mid;
        }
        h = hi;
    }
    uint64_t total = lattice_total(n, edge, sides, h);
    if (total > d->bake_capacity) {
        free(edge);
        free(sides);
        return rb_errf(err, RB_E_INVALID,
                       "hybrid: the bake of frame %lld needs %llu points, more than the %u it was "
                       "given room for",
                       (long long)epoch, (unsigned long long)total, d->bake_capacity);
    }
    uint32_t *words = d->bake_words;
    memset(words, 0, (size_t)all_triangles(d) * sizeof(*words));
    uint32_t count = 0;
    for (uint32_t k = 0; k < n; k++) {
        struct rb_gpu_bvh_triangle *t = &bvh->triangles[k];
        uint32_t r = lattice_res(edge[k], h), id;
        memcpy(&id, &t->v0[3], sizeof(id));
        uint32_t first = 3 * d->tri_capacity + d->word_vec4s + count;
        uint32_t word =
            (first << RB_HYBRID_BAKE_SHIFT) | r | (sides[k] == 2 ? RB_HYBRID_BAKE_BACK : 0);
        memcpy(&t->v2[3], &word, sizeof(word));
        words[id] = word;
        const float c = 1.0f / 3.0f, shrink = 1.0f - (float)RB_HYBRID_BAKE_SHRINK;
        for (uint32_t s = 0; s < sides[k]; s++)
            for (uint32_t j = 0; j <= r; j++)
                for (uint32_t i = 0; i + j <= r; i++)
                    d->bake_points[count++] = (struct rb_reference_bake_point){
                        .vertex = {d->indices[(size_t)id * 3], d->indices[(size_t)id * 3 + 1],
                                   d->indices[(size_t)id * 3 + 2]},
                        .u = c + ((float)i / (float)r - c) * shrink,
                        .v = c + ((float)j / (float)r - c) * shrink,
                        .is_back = s == 1,
                    };
    }
    free(edge);
    free(sides);
    double start = rb_monotonic_s();
    struct bvh_worker *w = &d->worker;
    enum rb_status st =
        rb_reference_bake(d->ref, (int)epoch, d->bake_points, count, d->settings->bake_samples,
                          d->bake_rgb, &w->bake_rays, err);
    w->bake_count = count;
    w->bake_ms = (rb_monotonic_s() - start) * 1e3;
    return st;
}

/* The device's copy of the bake the worker made (the main thread, the worker idle). */
static void upload_bake(struct hybrid *d, const struct rb_bvh *bvh, int64_t epoch)
{
    const struct bvh_worker *w = &d->worker;
    char *room = (char *)d->h.bvh_tris.mapped + (size_t)d->tri_capacity * sizeof(*bvh->triangles);
    memset(room, 0, (size_t)d->word_vec4s * 16);
    memcpy(room, d->bake_words, (size_t)all_triangles(d) * sizeof(*d->bake_words));
    float *dst = (float *)(room + (size_t)d->word_vec4s * 16);
    for (uint32_t i = 0; i < w->bake_count; i++) {
        memcpy(dst + (size_t)i * 4, d->bake_rgb + (size_t)i * 3, 3 * sizeof(float));
        dst[(size_t)i * 4 + 3] = 0.0f;
    }
    rb_log(RB_LOG_DEBUG,
           "hybrid: baked %u points of %u triangles for frame %lld, %llu rays, %.1f ms",
           w->bake_count, bvh->triangle_count, (long long)epoch, (unsigned long long)w->bake_rays,
           w->bake_ms);
    d->has_bake = true;
}

/* The worker's job: builds (and bakes) the BVH of the pose at frame epoch into the worker's
 * result, or finds that the pose moved no vertex since the BVH the device holds. */
static enum rb_status build_bvh(struct rb_integrator *it, struct hybrid *d, int64_t epoch,
                                struct rb_err *err)
{
    struct bvh_worker *w = &d->worker;
    rb_scene_evaluate(it->scene, &it->sel, (double)epoch / it->job->rate_fps, d->bvh_pose);
    size_t v = it->frame.vertex_count;
    rb_scene_deform(it->scene, d->bvh_pose, d->positions, 3, d->ref ? d->positions + v * 3 : NULL,
                    NULL, NULL);
    const struct rb_bvh_mesh mesh = {.positions = d->positions,
                                     .stride_floats = 3,
                                     .vertex_count = it->frame.vertex_count,
                                     .indices = d->indices,
                                     .triangle_count = (uint32_t)all_triangles(d)};
    const struct rb_bvh_desc desc = {
        .mesh = &mesh,
        .objects = d->objects,
        .object_count = d->object_count,
        .triangle_budget = d->settings->bvh_triangles,
        .score = d->settings->bvh_select == RB_BVH_SELECT_AREA ? RB_BVH_SCORE_AREA
                                                               : RB_BVH_SCORE_RELEVANCE,
        .eye = {w->eye[0], w->eye[1], w->eye[2]},
        .thread_count = 0,
        .cancel = &w->cancel,
    };
    /* The build is a function of the vertices and of the objects chosen (the triangles, objects
     * and budget do not change), the bake of their positions and normals: a pose that did not
     * move them, seen from where the same objects are chosen, keeps the BVH the device has. */
    enum rb_status st = rb_bvh_select(&desc, d->choice, err);
    if (st) {
        rb_err_prefix(err, "hybrid: the BVH of frame %lld", (long long)epoch);
        return st;
    }
    size_t bytes = v * (d->ref ? 6 : 3) * sizeof(float);
    if (d->has_built && memcmp(d->positions, d->built, bytes) == 0 &&
        memcmp(d->choice, d->built_choice, d->object_count) == 0) {
        w->is_same = true;
        return RB_OK;
    }
    double start = rb_monotonic_s();
    struct rb_bvh *bvh = &w->bvh;
    st = rb_bvh_build(&desc, bvh, err);
    if (st) {
        rb_err_prefix(err, "hybrid: the BVH of frame %lld", (long long)epoch);
        return st;
    }
    w->build_ms = (rb_monotonic_s() - start) * 1e3;
    if (bvh->node_count > d->node_capacity || bvh->triangle_count > d->tri_capacity)
        st = rb_errf(err, RB_E_INVALID,
                     "hybrid: the BVH of frame %lld has %u nodes and %u triangles, more than "
                     "the %u and %u it was given room for",
                     (long long)epoch, bvh->node_count, bvh->triangle_count, d->node_capacity,
                     d->tri_capacity);
    else if (d->ref)
        st = bake(it, d, bvh, epoch, err);
    if (st) {
        rb_bvh_release(bvh);
        return st;
    }
    d->has_built = true;
    memcpy(d->built_choice, bvh->choice, d->object_count);
    float *t = d->built;
    d->built = d->positions;
    d->positions = t;
    return RB_OK;
}

static void *bvh_main(void *arg)
{
    struct hybrid *d = arg;
    struct bvh_worker *w = &d->worker;
    pthread_mutex_lock(&w->lock);
    for (;;) {
        while (w->state != BVH_POSTED && !w->is_quitting)
            pthread_cond_wait(&w->cond, &w->lock);
        if (w->is_quitting)
            break;
        int64_t epoch = w->epoch;
        pthread_mutex_unlock(&w->lock);
        struct rb_err err = RB_ERR_INIT;
        enum rb_status st = build_bvh(d->it, d, epoch, &err);
        pthread_mutex_lock(&w->lock);
        w->st = st;
        w->err = err;
        w->state = BVH_DONE;
        pthread_cond_broadcast(&w->cond);
    }
    pthread_mutex_unlock(&w->lock);
    return NULL;
}

/* The main thread's side of the worker: post a job (none posted), wait for its result. */
static void worker_post(struct bvh_worker *w, int64_t epoch, const struct rb_camera *cam)
{
    pthread_mutex_lock(&w->lock);
    if (w->state != BVH_IDLE)
        RB_BUG("a second BVH job posted before the first was taken");
    w->epoch = epoch;
    w->eye[0] = cam->position.x;
    w->eye[1] = cam->position.y;
    w->eye[2] = cam->position.z;
    w->st = RB_OK;
    w->is_same = false;
    w->bake_count = 0;
    w->state = BVH_POSTED;
    pthread_cond_broadcast(&w->cond);
    pthread_mutex_unlock(&w->lock);
}

/* Waits for the posted job, if any, and takes it: the worker is idle afterwards. Returns
 * whether a job was posted. */
static bool worker_take(struct bvh_worker *w)
{
    pthread_mutex_lock(&w->lock);
    bool was_posted = w->state != BVH_IDLE;
    while (w->state == BVH_POSTED)
        pthread_cond_wait(&w->cond, &w->lock);
    w->state = BVH_IDLE;
    pthread_mutex_unlock(&w->lock);
    return was_posted;
}

/* Logs (debug) what the BVH of frame epoch holds of each object, when that changed. */
static void log_choice(struct hybrid *d, const struct rb_bvh *bvh, int64_t epoch)
{
    if (d->has_logged_choice && memcmp(d->logged_choice, bvh->choice, d->object_count) == 0)
        return;
    static const char *const what[] = {"left out", "whole", "coarser"};
    const struct rb_scene *scene = d->it->scene;
    const struct rb_scene_pose *pose = d->it->cur.pose;
    for (uint32_t i = 0; i < d->object_count; i++) {
        const struct rb_bvh_object *o = &d->objects[i];
        uint8_t c = bvh->choice[i];
        const char *name = scene->nodes[pose->instances[i].node].name;
        rb_log(RB_LOG_DEBUG,
               "hybrid: the BVH of frame %lld: object %u (node '%s'): %s, %u triangles",
               (long long)epoch, i, name ? name : "", what[c < 3 ? c : 0],
               c == RB_BVH_COARSER ? o->lod_count : o->triangle_count);
    }
    memcpy(d->logged_choice, bvh->choice, d->object_count);
    d->has_logged_choice = true;
}

/* Uploads the worker's result as the BVH of frame epoch (the main thread, the worker idle). */
static void upload(struct hybrid *d, int64_t epoch, double wait_ms)
{
    struct bvh_worker *w = &d->worker;
    d->bvh_epoch = epoch;
    if (w->is_same) {
        rb_log(RB_LOG_DEBUG, "hybrid: the pose of frame %lld keeps the BVH (waited %.1f ms)",
               (long long)epoch, wait_ms);
        return;
    }
    struct rb_bvh *bvh = &w->bvh;
    if (d->ref)
        upload_bake(d, bvh, epoch);
    /* Occluders the budget left out of the BVH are found on the screen (hybrid_light.comp); an
     * object held by its coarser version shadows by that. */
    d->h.screen_shadows = d->settings->screen_shadows && bvh->triangles_left_out > 0;
    memcpy(d->h.bvh_nodes.mapped, bvh->nodes, bvh->node_count * sizeof(*bvh->nodes));
    memcpy(d->h.bvh_tris.mapped, bvh->triangles, bvh->triangle_count * sizeof(*bvh->triangles));
    if (bvh->triangles_left_out || bvh->objects_simplified)
        rb_log(RB_LOG_INFO,
               "hybrid: the BVH holds %u of %u objects (%u triangles), %u of them by their "
               "coarser version; %llu triangles left out by the budget of %u",
               bvh->objects_included, bvh->object_count, bvh->triangle_count,
               bvh->objects_simplified, (unsigned long long)bvh->triangles_left_out,
               d->settings->bvh_triangles);
    log_choice(d, bvh, epoch);
    rb_log(RB_LOG_DEBUG,
           "hybrid: the BVH of frame %lld: built in %.1f ms and baked in %.1f ms on its thread, "
           "%.1f ms of it waited for",
           (long long)epoch, w->build_ms, w->bake_ms, wait_ms);
    d->has_bvh = true;
    rb_bvh_release(bvh);
}

/* The camera at frame epoch, whose position the BVH's relevance is seen from (the main thread:
 * the camera's evaluation may log). */
static enum rb_status epoch_camera(struct rb_integrator *it, struct hybrid *d, int64_t epoch,
                                   struct rb_camera *cam, struct rb_err *err)
{
    double t = (double)epoch / it->job->rate_fps;
    rb_scene_evaluate(it->scene, &it->sel, t, d->eye_pose);
    return rb_camera_evaluate(it->job, it->scene, &it->setup, d->eye_pose, t, cam, err);
}

/* The schedule of the file comment: the BVH of frame f's epoch, from the worker, and the next
 * epoch's build started at once. */
static enum rb_status prepare(struct rb_integrator *it, void *state, const struct rb_frame_ctx *ctx,
                              struct rb_err *err)
{
    struct hybrid *d = state;
    struct bvh_worker *w = &d->worker;
    if (ctx->frame < it->job->sequence_start)
        return RB_OK;
    int64_t epoch = bvh_epoch(it, d, ctx->frame);
    if (d->has_bvh && d->bvh_epoch == epoch)
        return RB_OK;
    double start = rb_monotonic_s();
    pthread_mutex_lock(&w->lock);
    bool is_posted = w->state != BVH_IDLE;
    pthread_mutex_unlock(&w->lock);
    if (is_posted && w->epoch != epoch) {
        /* Built ahead for an epoch this run skips (a gap in a frame list): dropped, and its
         * vertices are not the device's. */
        atomic_store(&w->cancel, true);
        worker_take(w);
        atomic_store(&w->cancel, false);
        rb_bvh_release(&w->bvh);
        d->has_built = false;
        is_posted = false;
        rb_log(RB_LOG_DEBUG,
               "hybrid: dropped the BVH built ahead for frame %lld: frame %d needs "
               "frame %lld's",
               (long long)w->epoch, ctx->frame, (long long)epoch);
    }
    struct rb_camera cam;
    enum rb_status st;
    if (!is_posted) {
        if ((st = epoch_camera(it, d, epoch, &cam, err)))
            return st;
        worker_post(w, epoch, &cam);
    }
    worker_take(w);
    if (w->st) {
        rb_bvh_release(&w->bvh);
        *err = w->err;
        return w->st;
    }
    upload(d, epoch, (rb_monotonic_s() - start) * 1e3);
    /* The next epoch's, while this frame and the ones before it run; none past the run's last
     * frame. */
    int64_t next = epoch + d->settings->bvh_interval;
    if (it->job->frame_end < 0 || next <= it->job->frame_end) {
        if ((st = epoch_camera(it, d, next, &cam, err)))
            return st;
        worker_post(w, next, &cam);
    }
    return RB_OK;
}

/* The frame's settings in the push constants: which accumulator starts again, which one the
 * output reads and which the requests follow (the history contract above). */
static void set_push(const struct rb_integrator *it, struct hybrid *d, int frame)
{
    const struct rb_job_hybrid *s = d->settings;
    struct rb_gpu_hybrid_push *p = &d->h.push;
    uint32_t w = s->history, half = s->history / 2;
    uint64_t rel = (uint64_t)((int64_t)frame - it->job->sequence_start);
    uint64_t last_a = rel - rel % w;
    uint64_t last_b = rel < half ? 0 : rel - (rel - half) % w;
    bool b_older = last_b < last_a;
    struct rb_vec3 lo = it->setup.bounds_min, hi = it->setup.bounds_max;
    float dx = hi.x - lo.x, dy = hi.y - lo.y, dz = hi.z - lo.z;
    *p = (struct rb_gpu_hybrid_push){
        .frame = {(uint32_t)frame, s->rays, 0, (uint32_t)(d->h.slot_count / 2)},
        .history = {rel % w == 0, rel == 0 || (rel >= half && (rel - half) % w == 0),
                    b_older | (s->feedback ? 2u : s->max_bounces << 2), !b_older},
        .sizes = {s->spp, s->screen_steps, d->queue_capacity, d->h.hiz_levels},
        .more = {0, 0, 0, s->filter_radius_px},
        .params = {s->noise, s->thickness, s->filter_depth, s->filter_normal},
        .scene = {sqrtf(dx * dx + dy * dy + dz * dz), 1e-4f, 0.0f, s->check_screen ? 1.0f : 0.0f},
        /* the G-buffer's float holds a triangle's index exactly below 2^24 */
        .bake = {d->has_bake, d->triangle_count <= (1u << 24), 12 * d->tri_capacity,
                 d->emitter_count},
    };
    uint32_t emitters_at = (uint32_t)(all_triangles(d) * 3);
    memcpy(&p->scene[2], &emitters_at, sizeof(emitters_at));
    d->h.cur = (uint32_t)frame & 1u;
}

/* Every resource of the integrator's own and the frame's a hybrid pass may touch, with how:
 * the passes share one binding table, so each declares the whole of it. */
static void begin(struct rb_integrator *it, struct hybrid *d, VkCommandBuffer cmd,
                  const struct rb_frame_ctx *ctx, const char *name)
{
    struct rb_frame *frame = &it->frame;
    struct rb_hybrid_frame *h = &d->h;
    const struct rb_gpu_image *gb = frame->gbuffer;
    const enum rb_gpu_use rw = RB_GPU_COMPUTE_READ_WRITE, rd = RB_GPU_COMPUTE_READ;
    const struct rb_gpu_access uses[] = {
        {.buffer = &frame->globals, .use = RB_GPU_COMPUTE_UNIFORM},
        {.image = &gb[RB_GB_POSITION], .use = rd},
        {.image = &gb[RB_GB_NORMAL], .use = rd},
        {.image = &gb[RB_GB_ALBEDO], .use = rd},
        {.image = &gb[RB_GB_SPECULAR], .use = rd},
        {.image = &gb[RB_GB_EMISSION], .use = rd},
        {.image = &gb[RB_GB_MOTION], .use = rd},
        {.buffer = &frame->lights, .use = rd},
        {.buffer = &frame->shadow_views, .use = rd},
        {.image = &frame->shadow_maps, .use = RB_GPU_COMPUTE_SAMPLED},
        {.image = &frame->env_map, .use = RB_GPU_COMPUTE_SAMPLED},
        {.image = &frame->direct, .use = rd},
        {.buffer = &h->hiz, .use = rw},
        {.buffer = &h->slots, .use = rw},
        {.buffer = &h->counters, .use = rw},
        {.buffer = &h->queue, .use = rw},
        {.buffer = &h->blocks, .use = rw},
        {.buffer = &h->bvh_nodes, .use = rd},
        {.buffer = &h->bvh_tris, .use = rd},
        {.buffer = &ctx->cur->vertices, .use = rd},
        {.buffer = &h->indices, .use = rd},
        {.buffer = &frame->materials, .use = rd},
        {.image = &frame->srgb_textures, .use = RB_GPU_COMPUTE_SAMPLED},
        {.image = &frame->linear_textures, .use = RB_GPU_COMPUTE_SAMPLED},
        {.image = &h->acc[h->cur ^ 1u], .use = rd},
        {.image = &h->acc[h->cur], .use = rw},
        {.buffer = &h->tiles, .use = rw},
        {.image = &h->stats, .use = rw},
        {.image = &h->light[0], .use = rw},
        {.image = &h->light[1], .use = rw},
        {.image = &h->light[2], .use = rw},
        {.image = &h->light[3], .use = rw},
    };
    _Static_assert(RB_BDPT_LIGHT_COUNT == 4, "every light image declared");
    rb_integrator_pass_begin(it, cmd, name, uses, COUNT(uses));
}

static void record(struct rb_integrator *it, void *state, VkCommandBuffer cmd,
                   const struct rb_frame_ctx *ctx)
{
    struct hybrid *d = state;
    struct rb_base *b = &d->base;
    struct rb_hybrid_frame *h = &d->h;
    d->has_counts = false;
    rb_base_record_animate(it, b->animate, cmd, ctx->cur);
    if (ctx->frame < it->job->sequence_start)
        return; /* before the sequence: nothing a frame of it reads */
    rb_base_record_gbuffer(it, b, cmd, ctx, NULL);
    rb_base_record_shadow(it, b, cmd, ctx);
    rb_base_record_direct_light(it, b, cmd);
    set_push(it, d, ctx->frame);
    /* A warm-up records what later frames read: up to the tiles, not the filters. */
    uint32_t end = ctx->is_warmup ? RB_HYBRID_PASS_TILES + 1 : RB_HYBRID_PASS_COUNT;
    for (uint32_t which = 0; which < end; which++) {
        begin(it, d, cmd, ctx, rb_pass_hybrid_names[which]);
        rb_pass_hybrid_record(d->passes, cmd, &it->frame, ctx->cur, h, which);
        rb_integrator_pass_end(it, cmd);
    }
    if (ctx->is_warmup)
        return;
    rb_gpu_memory_barrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                          VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT, VK_PIPELINE_STAGE_2_HOST_BIT,
                          VK_ACCESS_2_HOST_READ_BIT);
    rb_base_record_output(it, b, cmd, h->light, &h->stats);
    d->has_counts = true;
}

static void collect(struct rb_integrator *it, void *state, struct rb_frame_result *out)
{
    (void)it;
    struct hybrid *d = state;
    out->nonfinite_count = rb_pass_output_nonfinite_count(d->base.output);
    if (!d->has_counts)
        return;
    const struct rb_gpu_hybrid_counters *c = d->h.counters.mapped;
    d->counts = (struct rb_ray_counts){
        .requested = c->rays[0],
        .screen_hits = c->rays[1],
        .queued = c->rays[2],
        .bvh_hits = c->rays[3],
        .misses = c->more[0],
        .dropped = c->more[1],
        .has_check = d->settings->check_screen,
        .screen_checked = c->check[0],
        .screen_agreed = c->check[1],
    };
    out->ray_counts = &d->counts;
}

const struct rb_integrator_ops rb_integrator_hybrid = {
    .name = "hybrid",
    .history_frames = history_frames,
    .slot_frames = slot_frames,
    .create = create,
    .prepare = prepare,
    .record = record,
    .collect = collect,
    .destroy = destroy,
};
