/* The job-file parser: YAML (libyaml's document API, for line/column marks) walked into a
 * struct rb_job through one table of keys. The table also drives the defaults, --set overrides,
 * `raybundle help job` and the man-page test. Rendering policy does not live here. */
#include "job/job.h"

#include <errno.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <yaml.h>

/* ---- the key table ----------------------------------------------------------------------- */

enum key_type {
    KT_BOOL = 1,
    KT_INT,     /* int */
    KT_UINT,    /* uint32_t */
    KT_FLOAT,   /* float */
    KT_DOUBLE,  /* double */
    KT_STRING,  /* char *, NULL: none */
    KT_PATH,    /* char *, resolved relative to the job file's directory */
    KT_ENUM,    /* an enum stored as int; names[value] spells it */
    KT_VEC3,    /* float[3] */
    KT_UINT2,   /* two consecutive uint32_t (resolution) */
    KT_STRLIST, /* char ** plus a size_t count at count_offset */
    KT_LIST,    /* an array of item_size structs plus a count; rows "path[].x" describe an item */
};

enum key_flags {
    KF_REQUIRED = 1 << 0,
    KF_MUST_EXIST = 1 << 1, /* a path that must name an existing file when given */
    KF_MIN_EXCL = 1 << 2,   /* value > min rather than >= min */
    KF_MAX_EXCL = 1 << 3,
    KF_NORMALIZE = 1 << 4, /* a direction: normalized on load, zero length is an error */
    KF_UNLIMITED = 1 << 5, /* KT_UINT: the word "unlimited" stores UINT32_MAX */
};

struct ctx;
struct mark;

/* Validates list item i after it was walked (marks: where its keys were set). */
typedef enum rb_status (*item_check_fn)(struct ctx *c, void *items, size_t i, const char *shown,
                                        const struct mark *marks, const struct mark *item_mark);

struct key {
    const char *path; /* dotted; "lights[].type" is a key of every item of "lights" */
    enum key_type type;
    size_t offset;   /* into struct rb_job, or into the item struct for "x[]." rows */
    double min, max; /* inclusive unless KF_*_EXCL; -INFINITY/INFINITY: unbounded */
    const char *def; /* the default as YAML flow text; NULL: none (or required) */
    unsigned flags;
    const char *help;
    const char *const *names; /* KT_ENUM: names[1..name_count-1]; names[0] is the 0 value */
    size_t name_count;
    size_t count_offset; /* KT_STRLIST, KT_LIST */
    size_t item_size;    /* KT_LIST */
    item_check_fn check; /* KT_LIST, may be NULL */
};

static const char *const integrator_names[] = {NULL, "direct", "bdpt", "hybrid", "reference"};
static const char *const interp_names[] = {NULL, "linear", "catmull-rom"};
static const char *const path_names[] = {NULL, "full", "direct", "bdpt"};
static const char *const pixel_filter_names[] = {NULL, "center", "box"};
static const char *const strategy_names[] = {NULL, "mis", "vpl", "bundle"};
static const char *const hit_test_names[] = {NULL, "gaussian", "binary"};
static const char *const samples_names[] = {NULL, "periodic", "fresh"};
static const char *const subpixel_names[] = {NULL, "center", "spread"};
static const char *const light_names[] = {NULL, "point", "spot", "directional"};
static const char *const default_light_names[] = {NULL, "auto", "on", "off"};
static const char *const bvh_select_names[] = {NULL, "relevance", "area"};

#define COUNT(a) (sizeof(a) / sizeof((a)[0]))
#define JOB(f) offsetof(struct rb_job, f)
#define KEYF(f) offsetof(struct rb_job_camera_key, f)
#define LIGHT(f) offsetof(struct rb_job_light, f)
/* One row: the last arguments are the help text, then designated initializers for the fields
 * only some types use. */
#define K(p, t, off, lo, hi, d, fl, ...)                                                           \
    {                                                                                              \
        .path = (p), .type = (t), .offset = (off), .min = (lo), .max = (hi), .def = (d),           \
        .flags = (fl), .help = __VA_ARGS__                                                         \
    }
#define NOLO (-INFINITY)
#define NOHI INFINITY
#define ENUM(n) .names = (n), .name_count = COUNT(n)

_Static_assert(offsetof(struct rb_job, height_px) ==
                   offsetof(struct rb_job, width_px) + sizeof(uint32_t),
               "resolution is stored as two consecutive uint32_t");
_Static_assert(sizeof(enum rb_integrator_kind) == sizeof(int) &&
                   sizeof(enum rb_interp) == sizeof(int) &&
                   sizeof(enum rb_light_type) == sizeof(int),
               "enums are stored as int");

static enum rb_status check_camera_key(struct ctx *c, void *items, size_t i, const char *shown,
                                       const struct mark *marks, const struct mark *item_mark);
static enum rb_status check_light(struct ctx *c, void *items, size_t i, const char *shown,
                                  const struct mark *marks, const struct mark *item_mark);

static const struct key keys[] = {
    K("scene", KT_PATH, JOB(scene_path), NOLO, NOHI, NULL, KF_REQUIRED | KF_MUST_EXIST,
      "the glTF 2.0 scene (.gltf or .glb) to render"),
    K("output", KT_PATH, JOB(output), NOLO, NOHI, "out/frame.####.exr", 0,
      "output pattern for the EXR frames; a run of '#' is the zero-padded frame number"),
    K("resolution", KT_UINT2, JOB(width_px), 1, 16384, "[640, 360]", 0,
      "image width and height in pixels"),
    K("layers", KT_STRLIST, JOB(layers), NOLO, NOHI,
      "[direct, indirect, albedo, normal, depth, motion]", 0,
      "the EXR's layers beside the beauty (RGBA): direct, indirect, albedo, normal, depth, "
      "motion, indirect_diffuse, indirect_specular, samples, tiles (hybrid and reference), "
      "variance (reference); only these are read back from the device",
      .count_offset = JOB(layer_count)),
    K("frames.start", KT_INT, JOB(frame_start), 0, NOHI, "0", 0, "first frame to render"),
    K("frames.end", KT_INT, JOB(frame_end), -1, NOHI, "-1", 0,
      "last frame to render, inclusive; -1: to the end of the animation"),
    K("frames.rate", KT_DOUBLE, JOB(rate_fps), 0, NOHI, "24", KF_MIN_EXCL,
      "frames per second; frame f is rendered at time f / rate"),
    K("camera.node", KT_STRING, JOB(camera.node), NOLO, NOHI, NULL, 0,
      "name of a glTF node with a camera to look through; excludes camera.keys"),
    K("camera.fov_y_deg", KT_FLOAT, JOB(camera.fov_y_deg), 0, 180, "40", KF_MIN_EXCL | KF_MAX_EXCL,
      "vertical field of view of camera.keys in degrees"),
    K("camera.interpolation", KT_ENUM, JOB(camera.interpolation), NOLO, NOHI, "catmull-rom", 0,
      "how camera.keys are interpolated", ENUM(interp_names)),
    K("camera.near", KT_FLOAT, JOB(camera.near_m), 0, NOHI, "0", 0,
      "near clip plane in meters; 0: derived from the scene bounds"),
    K("camera.far", KT_FLOAT, JOB(camera.far_m), 0, NOHI, "0", 0,
      "far clip plane in meters; 0: derived from the scene bounds"),
    K("camera.keys", KT_LIST, JOB(camera.keys), NOLO, NOHI, "[]", 0,
      "camera path: keys with strictly increasing t; excludes camera.node",
      .count_offset = JOB(camera.key_count), .item_size = sizeof(struct rb_job_camera_key),
      .check = check_camera_key),
    K("camera.keys[].t", KT_DOUBLE, KEYF(t_s), NOLO, NOHI, NULL, KF_REQUIRED,
      "time of the key in seconds"),
    K("camera.keys[].position", KT_VEC3, KEYF(position), NOLO, NOHI, NULL, KF_REQUIRED,
      "camera position in world space"),
    K("camera.keys[].look_at", KT_VEC3, KEYF(look_at), NOLO, NOHI, NULL, KF_REQUIRED,
      "point the camera looks at, in world space"),
    K("camera.keys[].fov_y_deg", KT_FLOAT, KEYF(fov_y_deg), 0, 180, "0", KF_MAX_EXCL,
      "vertical field of view at this key in degrees; 0: camera.fov_y_deg"),
    K("animation.clips", KT_STRLIST, JOB(animation.clips), NOLO, NOHI, "[]", 0,
      "names of the glTF animations to play together; empty: the first animation",
      .count_offset = JOB(animation.clip_count)),
    K("animation.offset_s", KT_DOUBLE, JOB(animation.offset_s), NOLO, NOHI, "0", 0,
      "animation time at frame 0, in seconds"),
    K("animation.speed", KT_DOUBLE, JOB(animation.speed), NOLO, NOHI, "1", 0,
      "animation seconds per second of frame time"),
    K("animation.loop", KT_BOOL, JOB(animation.loop), NOLO, NOHI, "true", 0,
      "wrap the animation time around the clip length"),
    K("lights", KT_LIST, JOB(lights), NOLO, NOHI, "[]", 0, "lights added to the scene's own lights",
      .count_offset = JOB(light_count), .item_size = sizeof(struct rb_job_light),
      .check = check_light),
    K("lights[].type", KT_ENUM, LIGHT(type), NOLO, NOHI, NULL, KF_REQUIRED, "kind of light",
      ENUM(light_names)),
    K("lights[].position", KT_VEC3, LIGHT(position), NOLO, NOHI, "[0, 0, 0]", 0,
      "position of a point or spot light in world space"),
    K("lights[].direction", KT_VEC3, LIGHT(direction), NOLO, NOHI, "[0, -1, 0]", KF_NORMALIZE,
      "direction a spot or directional light travels; normalized"),
    K("lights[].color", KT_VEC3, LIGHT(color), 0, NOHI, "[1, 1, 1]", 0, "linear Rec.709 color"),
    K("lights[].intensity", KT_FLOAT, LIGHT(intensity), 0, NOHI, "1", 0,
      "candela for point and spot lights, lux for directional lights"),
    K("lights[].range", KT_FLOAT, LIGHT(range), 0, NOHI, "0", 0,
      "distance in meters where the light's influence ends; 0: infinite"),
    K("lights[].inner_cone_deg", KT_FLOAT, LIGHT(inner_cone_deg), 0, 90, "0", 0,
      "spot light: angle from the axis where the falloff starts; at most outer_cone_deg"),
    K("lights[].outer_cone_deg", KT_FLOAT, LIGHT(outer_cone_deg), 0, 90, "45", 0,
      "spot light: angle from the axis where the light ends"),
    K("scene_lights", KT_BOOL, JOB(use_scene_lights), NOLO, NOHI, "true", 0,
      "use the scene's KHR_lights_punctual lights"),
    K("default_light", KT_ENUM, JOB(default_light), NOLO, NOHI, "auto", 0,
      "add a point light: auto when the frame would be unlit (no punctual light, no emissive "
      "surface, a black environment), on always, off never",
      ENUM(default_light_names)),
    K("environment.map", KT_PATH, JOB(environment.map), NOLO, NOHI, NULL, KF_MUST_EXIST,
      "equirectangular EXR or HDR image of the distant environment"),
    K("environment.color", KT_VEC3, JOB(environment.color), 0, NOHI, "[0, 0, 0]", 0,
      "uniform linear Rec.709 radiance where there is no map"),
    K("environment.intensity", KT_FLOAT, JOB(environment.intensity), 0, NOHI, "1", 0,
      "multiplier for the map or color"),
    K("environment.rotation_deg", KT_FLOAT, JOB(environment.rotation_deg), NOLO, NOHI, "0", 0,
      "rotation of the map about +Y in degrees"),
    K("integrator.name", KT_ENUM, JOB(integrator.name), NOLO, NOHI, "bdpt", 0,
      "the light transport algorithm", ENUM(integrator_names)),
    K("integrator.direct.shadow_size", KT_UINT, JOB(integrator.direct.shadow_size_px), 16, 8192,
      "1024", 0, "shadow map size in pixels (per cube face for point lights)"),
    K("integrator.direct.shadow_bias", KT_FLOAT, JOB(integrator.direct.shadow_bias), 0, NOHI,
      "0.002", 0, "shadow depth bias as a fraction of the distance to the light"),
    K("integrator.direct.emitter_lights", KT_UINT, JOB(integrator.direct.emitter_lights), 0, 8, "8",
      0,
      "point samples standing for the emissive surfaces in direct (and the reference's direct "
      "path space), each with a cube of shadow maps; 0: emitters do not light"),
    K("integrator.direct.pcf_radius", KT_FLOAT, JOB(integrator.direct.pcf_radius_px), 0, NOHI,
      "1.5", 0, "radius of the 16-tap PCF shadow filter in shadow-map pixels"),
    K("integrator.bdpt.vpls", KT_UINT, JOB(integrator.bdpt.vpls), 1, 65536, "21", 0,
      "bdpt: virtual point lights per frame"),
    K("integrator.bdpt.bundles", KT_UINT, JOB(integrator.bdpt.bundles), 1, 65536, "21", 0,
      "bdpt: global ray-bundles per frame"),
    K("integrator.bdpt.rsm_size", KT_UINT, JOB(integrator.bdpt.rsm_size_px), 16, 4096, "256", 0,
      "bdpt: reflective shadow map size in pixels (per cube face for point lights)"),
    K("integrator.bdpt.vpl_size", KT_UINT, JOB(integrator.bdpt.vpl_size_px), 16, 4096, "256", 0,
      "bdpt: VPL paraboloid shadow map size in pixels"),
    K("integrator.bdpt.bounce_vpl_size", KT_UINT, JOB(integrator.bdpt.bounce_vpl_size_px), 0, 4096,
      "0", 0, "bdpt: bounce VPLs' paraboloid shadow map size in pixels; 0: vpl_size"),
    K("integrator.bdpt.bundle_size", KT_UINT, JOB(integrator.bdpt.bundle_size_px), 16, 4096, "256",
      0, "bdpt: ray-bundle head-pointer image size in pixels"),
    K("integrator.bdpt.node_buffer_kib", KT_UINT, JOB(integrator.bdpt.node_buffer_kib), 1, 131072,
      "20480", 0, "bdpt: ray-bundle node buffer in KiB (20-byte nodes)"),
    K("integrator.bdpt.interleave", KT_UINT, JOB(integrator.bdpt.interleave), 1, 8, "4", 0,
      "bdpt: spatial interleaving, n x n sub-images each with its own VPLs and bundles"),
    K("integrator.bdpt.filter_radius", KT_UINT, JOB(integrator.bdpt.filter_radius_px), 0, 16, "4",
      0, "bdpt: geometry-aware filter radius in pixels; 0: no filter"),
    K("integrator.bdpt.filter_depth", KT_FLOAT, JOB(integrator.bdpt.filter_depth), 0, NOHI, "0.05",
      0,
      "bdpt: distance from a pixel's tangent plane, relative to its depth, at which the filter "
      "stops"),
    K("integrator.bdpt.filter_normal", KT_FLOAT, JOB(integrator.bdpt.filter_normal), -1, 1, "0.9",
      0,
      "bdpt: cosine between normals below which the filter stops and a cache sample is not the "
      "pixel's surface"),
    K("integrator.bdpt.filter_light", KT_FLOAT, JOB(integrator.bdpt.filter_light), 0, 1, "0.5", 0,
      "bdpt: the least ratio of two pixels' direct light at which the filter still joins them (it "
      "stops at shadow edges); 0: it never stops for light"),
    K("integrator.bdpt.clamp", KT_FLOAT, JOB(integrator.bdpt.clamp), 0, NOHI, "100", 0,
      "bdpt: bound on the geometry term of the VPLs' connections (with mis, on it times the VPL's "
      "weight), in units of one over the scene diagonal squared; 0: no clamp"),
    K("integrator.bdpt.vpl_bias", KT_FLOAT, JOB(integrator.bdpt.vpl_bias), 0, NOHI, "0.01", 0,
      "bdpt: VPL shadow-map depth bias as a fraction of the distance to the VPL"),
    K("integrator.bdpt.vpl_spread", KT_FLOAT, JOB(integrator.bdpt.vpl_spread), 0, NOHI, "1", 0,
      "bdpt: a VPL lights as a disk of this many times the area it stands for among the frame's "
      "VPLs (it trades a spot beside a VPL for light lost there); 0: as a point"),
    K("integrator.bdpt.min_roughness", KT_FLOAT, JOB(integrator.bdpt.min_roughness), 0, 1, "0.5", 0,
      "bdpt: least roughness of the BRDF at a VPL and where a bundle lands (not at the camera's "
      "surface): a glossy VPL throws a bright spot; raising this trades the spot for a bias; 0: "
      "every material as it is"),
    K("integrator.bdpt.view_triangles", KT_UINT, JOB(integrator.bdpt.view_triangles), 0, UINT32_MAX,
      "50000", 0,
      "bdpt: triangle budget of the simplified mesh the small views draw; 0: the full mesh"),
    K("integrator.bdpt.strategies", KT_ENUM, JOB(integrator.bdpt.strategies), NOLO, NOHI, "mis", 0,
      "bdpt: mis weights VPL and bundle strategies; vpl or bundle use one alone",
      ENUM(strategy_names)),
    K("integrator.bdpt.caches", KT_UINT, JOB(integrator.bdpt.caches), 1, 8, "4", 0,
      "bdpt: temporal caches, one per subpixel offset, each rewritten every caches-th frame"),
    K("integrator.bdpt.hit_variance", KT_FLOAT, JOB(integrator.bdpt.hit_variance), 1e-12, NOHI,
      "0.00005", 0,
      "bdpt: sigma^2 of the cache hit weight exp(-log^2(z / z_cached) / (2 sigma^2))"),
    K("integrator.bdpt.hit_test", KT_ENUM, JOB(integrator.bdpt.hit_test), NOLO, NOHI, "gaussian", 0,
      "bdpt: cache hit weight: gaussian (log-space) or binary (|z - z_cached| < hit_epsilon)",
      ENUM(hit_test_names)),
    K("integrator.bdpt.hit_epsilon", KT_FLOAT, JOB(integrator.bdpt.hit_epsilon), 0, NOHI, "0.01", 0,
      "bdpt: the binary cache hit test's bound on the depth difference, in metres"),
    K("integrator.bdpt.samples", KT_ENUM, JOB(integrator.bdpt.samples), NOLO, NOHI, "periodic", 0,
      "bdpt: periodic (cache i always the same points) or fresh (new points every frame)",
      ENUM(samples_names)),
    K("integrator.bdpt.subpixel", KT_ENUM, JOB(integrator.bdpt.subpixel), NOLO, NOHI, "center", 0,
      "bdpt: where the caches sample a pixel: center (all at its centre) or spread (cache i at "
      "subpixel offset i)",
      ENUM(subpixel_names)),
    K("integrator.hybrid.rays", KT_UINT, JOB(integrator.hybrid.rays), 1, 16, "1", 0,
      "hybrid: rays each lobe (diffuse, specular) of a pixel may request a frame"),
    K("integrator.hybrid.spp", KT_UINT, JOB(integrator.hybrid.spp), 1, 65536, "64", 0,
      "hybrid: samples a lobe of a pixel aims for, scaled down by its material and direct light"),
    K("integrator.hybrid.history", KT_UINT, JOB(integrator.hybrid.history), 2, 1024, "128", 0,
      "hybrid: frames one accumulator spans before it starts again (two, staggered by half)"),
    K("integrator.hybrid.noise", KT_FLOAT, JOB(integrator.hybrid.noise), 0, NOHI, "0.02", 0,
      "hybrid: relative noise of a 16x16 tile below which it requests no more rays; 0: never"),
    K("integrator.hybrid.thickness", KT_FLOAT, JOB(integrator.hybrid.thickness), 0, NOHI, "0.03", 0,
      "hybrid: how far behind a depth sample a screen-space ray still hits it, relative"),
    K("integrator.hybrid.screen_steps", KT_UINT, JOB(integrator.hybrid.screen_steps), 0, 4096, "96",
      0, "hybrid: most hierarchical depth steps of a screen-space ray; 0: BVH only"),
    K("integrator.hybrid.bvh_triangles", KT_UINT, JOB(integrator.hybrid.bvh_triangles), 0,
      UINT32_MAX, "2000000", 0,
      "hybrid: triangle budget of the BVH, filled with the objects of best score; 0: all"),
    K("integrator.hybrid.bvh_select", KT_ENUM, JOB(integrator.hybrid.bvh_select), NOLO, NOHI,
      "relevance", 0, "hybrid: the BVH's object score (relevance from the camera, or area)",
      ENUM(bvh_select_names)),
    K("integrator.hybrid.bvh_lod", KT_BOOL, JOB(integrator.hybrid.bvh_lod), NOLO, NOHI, "true", 0,
      "hybrid: an object over the BVH's budget may enter by a quarter of its triangles"),
    K("integrator.hybrid.bvh_interval", KT_UINT, JOB(integrator.hybrid.bvh_interval), 1, 100000,
      "1", 0, "hybrid: frames between BVH builds (frames that are multiples of it build)"),
    K("integrator.hybrid.bake_texels", KT_UINT, JOB(integrator.hybrid.bake_texels), 0, 1u << 26,
      "65536", 0, "hybrid: baked light points beyond three a side of each of the BVH's triangles"),
    K("integrator.hybrid.bake_samples", KT_UINT, JOB(integrator.hybrid.bake_samples), 0, 65536,
      "32", 0, "hybrid: light samples per baked point; 0: no bake"),
    K("integrator.hybrid.max_bounces", KT_UINT, JOB(integrator.hybrid.max_bounces), 0, 8,
      "unlimited", KF_UNLIMITED,
      "hybrid: bounces after the first hit, as the reference counts them (0: direct light only); "
      "unlimited: hits reflect the light their pixels gathered"),
    K("integrator.hybrid.feedback", KT_BOOL, JOB(integrator.hybrid.feedback), NOLO, NOHI, "true", 0,
      "hybrid: the older spelling of max_bounces: true is unlimited, false is 1"),
    K("integrator.hybrid.check_screen", KT_BOOL, JOB(integrator.hybrid.check_screen), NOLO, NOHI,
      "false", 0, "hybrid: also trace screen-space hits through the BVH and count agreement"),
    K("integrator.hybrid.queue_rays", KT_UINT, JOB(integrator.hybrid.queue_rays), 0, UINT32_MAX,
      "0", 0, "hybrid: BVH ray queue capacity; 0: every ray a frame can request"),
    K("integrator.hybrid.filter_radius", KT_UINT, JOB(integrator.hybrid.filter_radius_px), 0, 16,
      "6", 0, "hybrid: the filter's radius in pixels at one sample; it shrinks as samples grow"),
    K("integrator.hybrid.filter_depth", KT_FLOAT, JOB(integrator.hybrid.filter_depth), 0, NOHI,
      "0.05", 0, "hybrid: relative depth difference at which the filter stops"),
    K("integrator.hybrid.filter_normal", KT_FLOAT, JOB(integrator.hybrid.filter_normal), -1, 1,
      "0.9", 0, "hybrid: cosine between normals below which the filter stops"),
    K("integrator.hybrid.screen_shadows", KT_BOOL, JOB(integrator.hybrid.screen_shadows), NOLO,
      NOHI, "true", 0,
      "hybrid: light samples' shadow rays also march the screen, for the surfaces the BVH's "
      "budget leaves out"),
    K("integrator.reference.spp", KT_UINT, JOB(integrator.reference.spp), 1, 1048576, "64", 0,
      "reference: samples per pixel"),
    K("integrator.reference.max_bounces", KT_UINT, JOB(integrator.reference.max_bounces), 0, 64,
      "8", 0, "reference: longest path in bounces after the first hit; 0: direct light only"),
    K("integrator.reference.rr_depth", KT_UINT, JOB(integrator.reference.rr_depth), 0, 64, "3", 0,
      "reference: bounces before Russian roulette may end a path"),
    K("integrator.reference.paths", KT_ENUM, JOB(integrator.reference.paths), NOLO, NOHI, "full", 0,
      "reference: which light paths count (full, direct, bdpt)", ENUM(path_names)),
    K("integrator.reference.pixel_filter", KT_ENUM, JOB(integrator.reference.pixel_filter), NOLO,
      NOHI, "center", 0, "reference: where samples pass through a pixel (center, box)",
      ENUM(pixel_filter_names)),
    K("integrator.reference.time_limit_s", KT_DOUBLE, JOB(integrator.reference.time_limit_s), 0,
      NOHI, "0", 0, "reference: stop after the pass of samples that crosses this time; 0: none"),
    K("color.config", KT_PATH, JOB(color.config), NOLO, NOHI, NULL, KF_MUST_EXIST,
      "OpenColorIO config for previews; none: $OCIO, then the bundled config"),
    K("color.display", KT_STRING, JOB(color.display), NOLO, NOHI, NULL, 0,
      "OpenColorIO display for previews; none: the config's default"),
    K("color.view", KT_STRING, JOB(color.view), NOLO, NOHI, NULL, 0,
      "OpenColorIO view for previews (--view overrides it); none: the display's default, in the "
      "bundled config 'ACES 1.0 - SDR Video', which tone-maps highlights instead of clipping"),
    K("color.preview", KT_BOOL, JOB(color.preview), NOLO, NOHI, "false", 0,
      "also write NAME.####.png through the display and view beside each EXR"),
};

#define KEY_COUNT COUNT(keys)

/* ---- parse state --------------------------------------------------------------------------- */

/* Where a value came from; seq == 0: never set. */
struct mark {
    const char *src;  /* the job file's name or "--set"; NULL: no position (a quick look) */
    size_t line, col; /* 1-based; for --set, line is the override's 1-based index */
    unsigned seq;     /* order of assignment, to tell which of two keys came last */
};

struct ctx {
    struct rb_job *job;
    const char *name;     /* the job as named in messages */
    const char *base_dir; /* resolves relative paths; "" for the current directory */
    const char *text;     /* the document's text, for reader errors that carry an offset */
    yaml_document_t *doc; /* the document being walked */
    size_t set_index;     /* 1-based override index; 0 while walking the file */
    const char *origin;   /* the override's origin (messages name it, not --set:N), or NULL */
    size_t col_offset;    /* columns before an override's value: strlen("key=") */
    unsigned seq;
    struct mark root;             /* the file's top-level mapping */
    struct mark marks[KEY_COUNT]; /* where each top-level key was last set */
    struct rb_err *err;
};

static struct mark mark_at(struct ctx *c, yaml_mark_t m)
{
    if (c->set_index && c->origin)
        return (struct mark){c->origin, 0, 0, ++c->seq};
    if (c->set_index)
        return (struct mark){"--set", c->set_index, c->col_offset + m.column + 1, ++c->seq};
    return (struct mark){c->name, m.line + 1, m.column + 1, ++c->seq};
}

static enum rb_status fail(struct ctx *c, const struct mark *m, enum rb_status code,
                           const char *fmt, ...) __attribute__((format(printf, 4, 5)));

static enum rb_status fail(struct ctx *c, const struct mark *m, enum rb_status code,
                           const char *fmt, ...)
{
    char msg[sizeof(c->err->msg)];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof(msg), fmt, ap);
    va_end(ap);
    if (m && m->src && m->line == 0) /* a command-line option, no position inside it */
        return rb_errf(c->err, code, "%s: %s", m->src, msg);
    if (m && m->src)
        return rb_errf(c->err, code, "%s:%zu:%zu: %s", m->src, m->line, m->col, msg);
    return rb_errf(c->err, code, "%s: %s", c->name, msg);
}

/* ---- key lookup and suggestions ------------------------------------------------------------ */

static const struct key *find_key(const char *path)
{
    for (size_t i = 0; i < KEY_COUNT; i++)
        if (!strcmp(keys[i].path, path))
            return &keys[i];
    return NULL;
}

/* True when path names a mapping of keys ("camera", "integrator.direct", "lights[]"). */
static bool is_mapping_path(const char *path)
{
    size_t n = strlen(path);
    for (size_t i = 0; i < KEY_COUNT; i++)
        if (!strncmp(keys[i].path, path, n) && keys[i].path[n] == '.')
            return true;
    return false;
}

/* The rest of key path after "prefix.", when the key belongs directly to the mapping prefix
 * ("" is the top level, "lights[]" an item of lights) and not to a list item below it. */
static const char *key_in_scope(const char *path, const char *prefix)
{
    size_t n = strlen(prefix);
    if (n) {
        if (strncmp(path, prefix, n) || path[n] != '.')
            return NULL;
        path += n + 1;
    }
    return strchr(path, '[') ? NULL : path;
}

/* Writes "; did you mean 'x'?" for the key of mapping prefix nearest to word, or "". */
static void suggest_key(const char *prefix, const char *word, char *buf, size_t size)
{
    size_t n = strlen(prefix);
    struct rb_suggest near;
    rb_suggest_init(&near, word);
    buf[0] = '\0';
    for (size_t i = 0; i < KEY_COUNT; i++) {
        const char *p = keys[i].path;
        if (n && (strncmp(p, prefix, n) || p[n] != '.'))
            continue;
        p += n ? n + 1 : 0;
        size_t len = strcspn(p, ".");
        if (!memchr(p, '[', len))
            rb_suggest_offer(&near, p, len);
    }
    if (near.best[0])
        snprintf(buf, size, "; did you mean '%s'?", near.best);
}

static void suggest_name(const struct key *k, const char *word, char *buf, size_t size)
{
    struct rb_suggest near;
    rb_suggest_init(&near, word);
    buf[0] = '\0';
    for (size_t i = 1; i < k->name_count; i++)
        rb_suggest_offer(&near, k->names[i], strlen(k->names[i]));
    if (near.best[0])
        snprintf(buf, size, "; did you mean '%s'?", near.best);
}

/* "between 16 and 8192", "> 0", "> 0 and < 180"; "" when unbounded. */
/* A bound as the key's type reads it: integers whole (4294967295, not 4.29497e+09). */
static void bound_text(const struct key *k, double v, char *buf, size_t size)
{
    bool is_int = k->type == KT_INT || k->type == KT_UINT || k->type == KT_UINT2;
    snprintf(buf, size, is_int ? "%.0f" : "%g", v);
}

static void range_text(const struct key *k, char *buf, size_t size)
{
    bool lo = isfinite(k->min), hi = isfinite(k->max);
    const char *ge = (k->flags & KF_MIN_EXCL) ? ">" : ">=";
    const char *le = (k->flags & KF_MAX_EXCL) ? "<" : "<=";
    char a[32], b[32];
    bound_text(k, k->min, a, sizeof(a));
    bound_text(k, k->max, b, sizeof(b));
    if (lo && hi && !(k->flags & (KF_MIN_EXCL | KF_MAX_EXCL)))
        snprintf(buf, size, "between %s and %s", a, b);
    else if (lo && hi)
        snprintf(buf, size, "%s %s and %s %s", ge, a, le, b);
    else if (lo)
        snprintf(buf, size, "%s %s", ge, a);
    else if (hi)
        snprintf(buf, size, "%s %s", le, b);
    else
        buf[0] = '\0';
    if (k->flags & KF_UNLIMITED)
        snprintf(buf + strlen(buf), size - strlen(buf), " or unlimited");
}

static bool in_range(const struct key *k, double v)
{
    if ((k->flags & KF_MIN_EXCL) ? !(v > k->min) : !(v >= k->min))
        return false;
    if ((k->flags & KF_MAX_EXCL) ? !(v < k->max) : !(v <= k->max))
        return false;
    return true;
}

static enum rb_status check_range(struct ctx *c, const struct key *k, const char *shown,
                                  const struct mark *m, double v)
{
    if (in_range(k, v))
        return RB_OK;
    char range[80];
    range_text(k, range, sizeof(range));
    return fail(c, m, RB_E_INVALID, "'%s' must be %s", shown, range);
}

/* ---- scalars ------------------------------------------------------------------------------- */

static const char *scalar(const yaml_node_t *node)
{
    return node && node->type == YAML_SCALAR_NODE ? (const char *)node->data.scalar.value : NULL;
}

static bool is_plain(const yaml_node_t *node)
{
    return scalar(node) && node->data.scalar.style == YAML_PLAIN_SCALAR_STYLE;
}

static bool is_null(const yaml_node_t *node)
{
    if (!node)
        return true;
    if (!is_plain(node))
        return false;
    const char *s = scalar(node);
    return !strcmp(s, "") || !strcmp(s, "~") || !strcmp(s, "null") || !strcmp(s, "Null") ||
           !strcmp(s, "NULL");
}

static bool parse_long(const yaml_node_t *node, long *out)
{
    if (!is_plain(node) || is_null(node))
        return false;
    const char *s = scalar(node);
    char *end = NULL;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (end == s || *end || errno == ERANGE)
        return false;
    *out = v;
    return true;
}

static bool parse_number(const yaml_node_t *node, double *out)
{
    if (!is_plain(node) || is_null(node))
        return false;
    const char *s = scalar(node);
    char *end = NULL;
    double v = strtod(s, &end);
    if (end == s || *end || !isfinite(v))
        return false;
    *out = v;
    return true;
}

static bool parse_bool(const yaml_node_t *node, bool *out)
{
    static const char *const yes[] = {"true", "True", "TRUE"};
    static const char *const no[] = {"false", "False", "FALSE"};
    if (!is_plain(node))
        return false;
    for (size_t i = 0; i < COUNT(yes); i++) {
        if (!strcmp(scalar(node), yes[i]) || !strcmp(scalar(node), no[i])) {
            *out = !strcmp(scalar(node), yes[i]);
            return true;
        }
    }
    return false;
}

static size_t seq_len(const yaml_node_t *node)
{
    return (size_t)(node->data.sequence.items.top - node->data.sequence.items.start);
}

static yaml_node_t *seq_item(struct ctx *c, const yaml_node_t *node, size_t i)
{
    return yaml_document_get_node(c->doc, node->data.sequence.items.start[i]);
}

/* ---- paths --------------------------------------------------------------------------------- */

/* base_dir/p, or p itself when it is absolute or base_dir is the current directory. */
static char *resolve_path(const char *base_dir, const char *p)
{
    if (p[0] == '/' || !base_dir || !base_dir[0] || !strcmp(base_dir, "."))
        return rb_strdup(p);
    size_t nb = strlen(base_dir), np = strlen(p);
    bool slash = base_dir[nb - 1] != '/';
    char *r = malloc(nb + slash + np + 1);
    if (!r)
        return NULL;
    memcpy(r, base_dir, nb);
    if (slash)
        r[nb] = '/';
    memcpy(r + nb + slash, p, np + 1);
    return r;
}

static bool has_suffix_ci(const char *s, const char *suffix)
{
    size_t n = strlen(s), m = strlen(suffix);
    return n >= m && !strcasecmp(s + n - m, suffix);
}

/* ---- setting values ------------------------------------------------------------------------ */

static void *field(void *base, const struct key *k)
{
    return (char *)base + k->offset;
}

static void *get_ptr(void *base, const struct key *k)
{
    void *p;
    memcpy(&p, field(base, k), sizeof(p));
    return p;
}

static void set_ptr(void *base, const struct key *k, void *p)
{
    memcpy(field(base, k), &p, sizeof(p));
}

static size_t *count_field(void *base, const struct key *k)
{
    return (size_t *)((char *)base + k->count_offset);
}

static void free_strlist(char **list, size_t count)
{
    for (size_t i = 0; i < count; i++)
        free(list[i]);
    free(list);
}

static enum rb_status walk_mapping(struct ctx *c, yaml_node_t *map, const char *prefix,
                                   const char *shown, void *base, struct mark *marks);
static enum rb_status apply_defaults(struct ctx *c, const char *prefix, void *base);

static enum rb_status set_list(struct ctx *c, const struct key *k, yaml_node_t *node,
                               const char *shown, void *base)
{
    struct mark at = mark_at(c, node->start_mark);
    size_t n = is_null(node) ? 0 : seq_len(node);
    if (!is_null(node) && node->type != YAML_SEQUENCE_NODE)
        return fail(c, &at, RB_E_PARSE, "'%s' expects a list of mappings", shown);

    free(get_ptr(base, k));
    set_ptr(base, k, NULL);
    *count_field(base, k) = 0;
    if (!n)
        return RB_OK;
    char *items = calloc(n, k->item_size);
    if (!items)
        return fail(c, &at, RB_E_NOMEM, "out of memory for '%s'", shown);
    set_ptr(base, k, items);
    *count_field(base, k) = n;

    char prefix[64], item_shown[96];
    snprintf(prefix, sizeof(prefix), "%s[]", k->path);
    for (size_t i = 0; i < n; i++) {
        yaml_node_t *item = seq_item(c, node, i);
        void *ib = items + i * k->item_size;
        struct mark item_mark = mark_at(c, item->start_mark);
        struct mark marks[KEY_COUNT] = {{0}};
        snprintf(item_shown, sizeof(item_shown), "%s[%zu]", shown, i);
        if (item->type != YAML_MAPPING_NODE)
            return fail(c, &item_mark, RB_E_PARSE, "'%s' expects a mapping", item_shown);
        enum rb_status st = apply_defaults(c, prefix, ib);
        if (!st)
            st = walk_mapping(c, item, prefix, item_shown, ib, marks);
        if (st)
            return st;
        for (size_t j = 0; j < KEY_COUNT; j++) {
            const char *name = key_in_scope(keys[j].path, prefix);
            if (name && (keys[j].flags & KF_REQUIRED) && !marks[j].seq)
                return fail(c, &item_mark, RB_E_PARSE, "'%s' is missing required key '%s'",
                            item_shown, name);
        }
        if (k->check && (st = k->check(c, items, i, item_shown, marks, &item_mark)))
            return st;
    }
    return RB_OK;
}

static enum rb_status set_strlist(struct ctx *c, const struct key *k, yaml_node_t *node,
                                  const char *shown, void *base)
{
    struct mark at = mark_at(c, node->start_mark);
    if (!is_null(node) && node->type != YAML_SEQUENCE_NODE)
        return fail(c, &at, RB_E_PARSE, "'%s' expects a list of strings", shown);
    size_t n = is_null(node) ? 0 : seq_len(node);

    free_strlist(get_ptr(base, k), *count_field(base, k));
    set_ptr(base, k, NULL);
    *count_field(base, k) = 0;
    if (!n)
        return RB_OK;
    char **list = calloc(n, sizeof(*list));
    if (!list)
        return fail(c, &at, RB_E_NOMEM, "out of memory for '%s'", shown);
    set_ptr(base, k, list);
    *count_field(base, k) = n;
    for (size_t i = 0; i < n; i++) {
        yaml_node_t *item = seq_item(c, node, i);
        struct mark im = mark_at(c, item->start_mark);
        if (!scalar(item) || is_null(item))
            return fail(c, &im, RB_E_PARSE, "'%s' expects a list of strings", shown);
        if (!scalar(item)[0])
            return fail(c, &im, RB_E_INVALID, "'%s' names must not be empty", shown);
        if (!(list[i] = rb_strdup(scalar(item))))
            return fail(c, &im, RB_E_NOMEM, "out of memory for '%s'", shown);
    }
    return RB_OK;
}

static enum rb_status set_vec3(struct ctx *c, const struct key *k, yaml_node_t *node,
                               const char *shown, const struct mark *at, void *base)
{
    float v[3];
    if (node->type != YAML_SEQUENCE_NODE || seq_len(node) != 3)
        return fail(c, at, RB_E_PARSE, "'%s' expects a list of 3 numbers", shown);
    for (size_t i = 0; i < 3; i++) {
        yaml_node_t *item = seq_item(c, node, i);
        struct mark im = mark_at(c, item->start_mark);
        double d;
        if (!parse_number(item, &d))
            return fail(c, &im, RB_E_PARSE, "'%s' expects a list of 3 numbers", shown);
        if (fabs(d) > FLT_MAX)
            return fail(c, &im, RB_E_INVALID, "'%s' is out of range", shown);
        enum rb_status st = check_range(c, k, shown, &im, d);
        if (st)
            return st;
        v[i] = (float)d;
    }
    if (k->flags & KF_NORMALIZE) {
        double len = sqrt((double)v[0] * v[0] + (double)v[1] * v[1] + (double)v[2] * v[2]);
        if (!(len > 0) || !isfinite(len))
            return fail(c, at, RB_E_INVALID, "'%s' must not be zero", shown);
        for (size_t i = 0; i < 3; i++)
            v[i] = (float)(v[i] / len);
    }
    memcpy(field(base, k), v, sizeof(v));
    return RB_OK;
}

static enum rb_status set_uint2(struct ctx *c, const struct key *k, yaml_node_t *node,
                                const char *shown, const struct mark *at, void *base)
{
    uint32_t v[2];
    if (node->type != YAML_SEQUENCE_NODE || seq_len(node) != 2)
        return fail(c, at, RB_E_PARSE, "'%s' expects a list of 2 integers", shown);
    for (size_t i = 0; i < 2; i++) {
        yaml_node_t *item = seq_item(c, node, i);
        struct mark im = mark_at(c, item->start_mark);
        long l;
        if (!parse_long(item, &l))
            return fail(c, &im, RB_E_PARSE, "'%s' expects a list of 2 integers", shown);
        enum rb_status st = check_range(c, k, shown, &im, (double)l);
        if (st)
            return st;
        v[i] = (uint32_t)l;
    }
    memcpy(field(base, k), v, sizeof(v));
    return RB_OK;
}

static enum rb_status set_string(struct ctx *c, const struct key *k, yaml_node_t *node,
                                 const char *shown, const struct mark *at, void *base)
{
    char **dst = (char **)field(base, k);
    if (is_null(node) && !k->def && !(k->flags & KF_REQUIRED)) {
        free(*dst);
        *dst = NULL;
        return RB_OK;
    }
    if (!scalar(node) || is_null(node))
        return fail(c, at, RB_E_PARSE, "'%s' expects a %s", shown,
                    k->type == KT_PATH ? "path" : "string");
    if (!scalar(node)[0])
        return fail(c, at, RB_E_INVALID, "'%s' must not be empty", shown);
    char *s =
        k->type == KT_PATH ? resolve_path(c->base_dir, scalar(node)) : rb_strdup(scalar(node));
    if (!s)
        return fail(c, at, RB_E_NOMEM, "out of memory for '%s'", shown);
    free(*dst);
    *dst = s;
    return RB_OK;
}

static enum rb_status set_enum(struct ctx *c, const struct key *k, yaml_node_t *node,
                               const char *shown, const struct mark *at, void *base)
{
    const char *s = scalar(node);
    if (!s || is_null(node))
        return fail(c, at, RB_E_PARSE, "'%s' expects a name", shown);
    /* On the command line (--set, --integrator) a name's case does not matter; a job file
     * spells it as documented. */
    for (int i = 1; i < (int)k->name_count; i++) {
        if (c->set_index ? !strcasecmp(s, k->names[i]) : !strcmp(s, k->names[i])) {
            memcpy(field(base, k), &i, sizeof(i));
            return RB_OK;
        }
    }
    char choices[128] = "", hint[80];
    for (size_t i = 1; i < k->name_count; i++) {
        size_t len = strlen(choices);
        snprintf(choices + len, sizeof(choices) - len, "%s%s", i > 1 ? ", " : "", k->names[i]);
    }
    suggest_name(k, s, hint, sizeof(hint));
    return fail(c, at, RB_E_INVALID, "'%s' must be one of %s, not '%s'%s", shown, choices, s, hint);
}

/* Sets key k of the struct at base from node; marks (may be NULL) records where. */
static enum rb_status set_key(struct ctx *c, const struct key *k, yaml_node_t *node,
                              const char *shown, void *base, struct mark *marks)
{
    struct mark at = mark_at(c, node->start_mark);
    enum rb_status st = RB_OK;
    if (marks)
        marks[k - keys] = at;

    switch (k->type) {
    case KT_BOOL: {
        bool b;
        if (!parse_bool(node, &b))
            return fail(c, &at, RB_E_PARSE, "'%s' expects true or false", shown);
        *(bool *)field(base, k) = b;
        break;
    }
    case KT_INT:
    case KT_UINT: {
        long l;
        const char *word = scalar(node);
        if ((k->flags & KF_UNLIMITED) && word && !strcmp(word, "unlimited")) {
            *(uint32_t *)field(base, k) = UINT32_MAX;
            break;
        }
        if (!parse_long(node, &l))
            return fail(c, &at, RB_E_PARSE, "'%s' expects an integer%s", shown,
                        (k->flags & KF_UNLIMITED) ? " or unlimited" : "");
        if (l < INT_MIN || l > (k->type == KT_INT ? (long)INT_MAX : (long)UINT32_MAX))
            return fail(c, &at, RB_E_INVALID, "'%s' is out of range", shown);
        if ((st = check_range(c, k, shown, &at, (double)l)))
            return st;
        if (k->type == KT_INT)
            *(int *)field(base, k) = (int)l;
        else
            *(uint32_t *)field(base, k) = (uint32_t)l;
        break;
    }
    case KT_FLOAT:
    case KT_DOUBLE: {
        double d;
        if (!parse_number(node, &d))
            return fail(c, &at, RB_E_PARSE, "'%s' expects a number", shown);
        if (k->type == KT_FLOAT && fabs(d) > FLT_MAX)
            return fail(c, &at, RB_E_INVALID, "'%s' is out of range", shown);
        if ((st = check_range(c, k, shown, &at, d)))
            return st;
        if (k->type == KT_FLOAT)
            *(float *)field(base, k) = (float)d;
        else
            *(double *)field(base, k) = d;
        break;
    }
    case KT_STRING:
    case KT_PATH: st = set_string(c, k, node, shown, &at, base); break;
    case KT_ENUM: st = set_enum(c, k, node, shown, &at, base); break;
    case KT_VEC3: st = set_vec3(c, k, node, shown, &at, base); break;
    case KT_UINT2: st = set_uint2(c, k, node, shown, &at, base); break;
    case KT_STRLIST: st = set_strlist(c, k, node, shown, base); break;
    case KT_LIST: st = set_list(c, k, node, shown, base); break;
    }
    return st;
}

/* Walks node into the key or mapping at path (which must exist in the table). */
static enum rb_status walk_at(struct ctx *c, const char *path, const char *shown, yaml_node_t *node,
                              void *base, struct mark *marks)
{
    const struct key *k = find_key(path);
    if (k)
        return set_key(c, k, node, shown, base, marks);
    if (is_null(node))
        return RB_OK; /* "camera:" with nothing below it */
    if (node->type != YAML_MAPPING_NODE) {
        struct mark at = mark_at(c, node->start_mark);
        return fail(c, &at, RB_E_PARSE, "'%s' expects a mapping", shown);
    }
    return walk_mapping(c, node, path, shown, base, marks);
}

/* Walks the keys of map, which sits at table path prefix ("" for the top level). */
static enum rb_status walk_mapping(struct ctx *c, yaml_node_t *map, const char *prefix,
                                   const char *shown, void *base, struct mark *marks)
{
    yaml_node_pair_t *pairs = map->data.mapping.pairs.start;
    size_t n = (size_t)(map->data.mapping.pairs.top - pairs);
    for (size_t i = 0; i < n; i++) {
        yaml_node_t *kn = yaml_document_get_node(c->doc, pairs[i].key);
        yaml_node_t *vn = yaml_document_get_node(c->doc, pairs[i].value);
        struct mark at = mark_at(c, kn->start_mark);
        const char *name = scalar(kn);
        if (!name)
            return fail(c, &at, RB_E_PARSE, "keys must be plain names");
        for (size_t j = 0; j < i; j++) {
            const char *prev = scalar(yaml_document_get_node(c->doc, pairs[j].key));
            if (prev && !strcmp(prev, name))
                return fail(c, &at, RB_E_PARSE, "duplicate key '%s'%s%s%s", name,
                            shown[0] ? " in '" : "", shown, shown[0] ? "'" : "");
        }
        char path[128], full_shown[160];
        int len = snprintf(path, sizeof(path), "%s%s%s", prefix, prefix[0] ? "." : "", name);
        bool known = name[0] && !strpbrk(name, ".[]") && len > 0 && (size_t)len < sizeof(path) &&
                     (find_key(path) || is_mapping_path(path));
        if (!known) {
            char hint[80];
            suggest_key(prefix, name, hint, sizeof(hint));
            if (!shown[0])
                return fail(c, &at, RB_E_PARSE, "unknown key '%s'%s", name, hint);
            return fail(c, &at, RB_E_PARSE, "unknown key '%s' in '%s'%s", name, shown, hint);
        }
        snprintf(full_shown, sizeof(full_shown), "%s%s%s", shown, shown[0] ? "." : "", name);
        enum rb_status st = walk_at(c, path, full_shown, vn, base, marks);
        if (st)
            return st;
    }
    return RB_OK;
}

/* The deepest nesting of sequences and mappings a job may have. No key is deeper than 4, and
 * the cap keeps parsing linear: libyaml's scanner walks its stack of possible simple keys, one
 * per open flow collection, at every token, so a document nested n deep costs n^2. */
#define JOB_MAX_DEPTH 64

/* Checks the nesting with libyaml's events before anything builds a document, stopping at the
 * first collection past JOB_MAX_DEPTH: the scanner then has seen little beyond that point. A
 * YAML error is left to load_yaml, which reports it at the same mark. */
static enum rb_status check_depth(struct ctx *c, const char *text, size_t size)
{
    yaml_parser_t parser;
    yaml_event_t ev;
    enum rb_status st = RB_OK;
    size_t depth = 0;
    if (!yaml_parser_initialize(&parser))
        return rb_errf(c->err, RB_E_NOMEM, "%s: cannot initialize the YAML parser", c->name);
    yaml_parser_set_input_string(&parser, (const unsigned char *)text, size);
    for (;;) {
        if (!yaml_parser_parse(&parser, &ev))
            break;
        yaml_event_type_t type = ev.type;
        if (type == YAML_SEQUENCE_START_EVENT || type == YAML_MAPPING_START_EVENT) {
            if (++depth > JOB_MAX_DEPTH) {
                struct mark at = mark_at(c, ev.start_mark);
                st = fail(c, &at, RB_E_PARSE, "nested deeper than %d levels", JOB_MAX_DEPTH);
            }
        } else if (type == YAML_SEQUENCE_END_EVENT || type == YAML_MAPPING_END_EVENT) {
            depth--;
        }
        yaml_event_delete(&ev);
        if (st || type == YAML_STREAM_END_EVENT)
            break;
    }
    yaml_parser_delete(&parser);
    return st;
}

/* Parses text into doc; on failure, a message at libyaml's mark. */
static enum rb_status load_yaml(struct ctx *c, const char *text, size_t size, yaml_document_t *doc,
                                bool *has_doc)
{
    yaml_parser_t parser;
    enum rb_status st = RB_OK;
    *has_doc = false;
    if ((st = check_depth(c, text, size)))
        return st;
    if (!yaml_parser_initialize(&parser))
        return rb_errf(c->err, RB_E_NOMEM, "%s: cannot initialize the YAML parser", c->name);
    yaml_parser_set_input_string(&parser, (const unsigned char *)text, size);
    if (!yaml_parser_load(&parser, doc))
        goto parse_error;
    *has_doc = true;

    /* One document per job: a second one is a mistake worth naming. */
    yaml_document_t extra;
    if (!yaml_parser_load(&parser, &extra))
        goto parse_error;
    yaml_node_t *root = yaml_document_get_root_node(&extra);
    if (root) {
        struct mark at = mark_at(c, root->start_mark);
        st = fail(c, &at, RB_E_PARSE, "a job holds one YAML document, found another");
    }
    yaml_document_delete(&extra);
    goto out;

parse_error:
    if (parser.error == YAML_MEMORY_ERROR) {
        st = rb_errf(c->err, RB_E_NOMEM, "%s: out of memory parsing YAML", c->name);
    } else {
        yaml_mark_t m = parser.problem_mark;
        if (parser.error == YAML_READER_ERROR) {
            /* The reader reports a byte offset, not a mark. */
            memset(&m, 0, sizeof(m));
            for (size_t i = 0; i < parser.problem_offset && i < size; i++) {
                if (text[i] == '\n') {
                    m.line++;
                    m.column = 0;
                } else {
                    m.column++;
                }
            }
        }
        struct mark at = mark_at(c, m);
        st = fail(c, &at, RB_E_PARSE, "%s%s%s", parser.problem ? parser.problem : "bad YAML",
                  parser.context ? " " : "", parser.context ? parser.context : "");
    }
out:
    yaml_parser_delete(&parser);
    return st;
}

/* Sets every key of mapping prefix that has a default, from the table's default text. */
static enum rb_status apply_defaults(struct ctx *c, const char *prefix, void *base)
{
    enum rb_status st = RB_OK;
    yaml_document_t *saved = c->doc;
    size_t saved_index = c->set_index;
    c->set_index = 0;
    for (size_t i = 0; i < KEY_COUNT && !st; i++) {
        if (!keys[i].def || !key_in_scope(keys[i].path, prefix))
            continue;
        yaml_document_t doc;
        bool has_doc = false;
        st = load_yaml(c, keys[i].def, strlen(keys[i].def), &doc, &has_doc);
        if (!st) {
            c->doc = &doc;
            st = set_key(c, &keys[i], yaml_document_get_root_node(&doc), keys[i].path, base, NULL);
        }
        if (has_doc)
            yaml_document_delete(&doc);
        if (st && st != RB_E_NOMEM)
            RB_BUG("default of job key '%s' does not parse: %s", keys[i].path, c->err->msg);
    }
    c->doc = saved;
    c->set_index = saved_index;
    return st;
}

/* ---- overrides ----------------------------------------------------------------------------- */

static enum rb_status apply_override(struct ctx *c, size_t index, const struct rb_job_override *o)
{
    const char *key = o->key ? o->key : "";
    const char *value = o->value && o->value[0] ? o->value : "~";
    char path[128] = "";
    enum rb_status st = RB_OK;

    c->set_index = index;
    c->origin = o->origin;
    c->col_offset = 0;
    /* Walk the dotted key one component at a time, so an error points at the bad one. */
    for (size_t pos = 0;;) {
        size_t len = strcspn(key + pos, ".");
        char name[64];
        struct mark at = o->origin ? (struct mark){o->origin, 0, 0, ++c->seq}
                                   : (struct mark){"--set", index, pos + 1, ++c->seq};
        if (!len || len >= sizeof(name))
            return fail(c, &at, RB_E_PARSE, "bad key '%s'", key);
        memcpy(name, key + pos, len);
        name[len] = '\0';
        char prefix[128];
        memcpy(prefix, path, sizeof(prefix));
        size_t plen = strlen(path);
        if (plen + 1 + len >= sizeof(path))
            return fail(c, &at, RB_E_PARSE, "bad key '%s'", key);
        snprintf(path + plen, sizeof(path) - plen, "%s%s", plen ? "." : "", name);
        bool last = key[pos + len] == '\0';
        bool ok = !strpbrk(name, "[]") && (find_key(path) || is_mapping_path(path));
        if (ok && !last && find_key(path)) {
            /* A leaf with more after it: "resolution.x" names nothing below resolution. */
            size_t next = pos + len + 1;
            at.col = next + 1;
            return fail(c, &at, RB_E_PARSE, "unknown key '%.*s' in '%s'",
                        (int)strcspn(key + next, "."), key + next, path);
        }
        if (!ok) {
            char hint[80];
            suggest_key(prefix, name, hint, sizeof(hint));
            if (!prefix[0])
                return fail(c, &at, RB_E_PARSE, "unknown key '%s'%s", name, hint);
            return fail(c, &at, RB_E_PARSE, "unknown key '%s' in '%s'%s", name, prefix, hint);
        }
        if (last)
            break;
        pos += len + 1;
    }

    yaml_document_t doc;
    bool has_doc = false;
    c->col_offset = strlen(key) + 1;
    st = load_yaml(c, value, strlen(value), &doc, &has_doc);
    if (!st) {
        yaml_document_t *saved = c->doc;
        c->doc = &doc;
        yaml_node_t *root = yaml_document_get_root_node(&doc);
        if (!root) {
            struct mark at = mark_at(c, (yaml_mark_t){0});
            st = fail(c, &at, RB_E_PARSE, "'%s' has no value", path);
        } else {
            st = walk_at(c, path, path, root, c->job, c->marks);
        }
        c->doc = saved;
    }
    if (has_doc)
        yaml_document_delete(&doc);
    c->set_index = 0;
    c->origin = NULL;
    c->col_offset = 0;
    return st;
}

/* ---- validation ---------------------------------------------------------------------------- */

enum rb_status rb_job_check_output(const char *pattern, int frame_start, int frame_end,
                                   struct rb_err *err)
{
    const char *slash = strrchr(pattern, '/');
    const char *base = slash ? slash + 1 : pattern;
    size_t n = strlen(base);
    if (n < 5 || strcasecmp(base + n - 4, ".exr") != 0)
        return rb_errf(err, RB_E_INVALID,
                       "output '%s' must name an .exr file (sidecars and previews go beside it)",
                       pattern);
    if (!strchr(base, '#') && frame_end != frame_start) {
        char end[32] = "the end of the animation";
        if (frame_end >= 0)
            snprintf(end, sizeof(end), "%d", frame_end);
        return rb_errf(err, RB_E_INVALID,
                       "output '%s' has no '#' for the frame number, and frames %d to %s are "
                       "more than one",
                       pattern, frame_start, end);
    }
    return RB_OK;
}

static size_t key_index(const char *path)
{
    const struct key *k = find_key(path);
    if (!k)
        RB_BUG("no job key '%s'", path);
    return (size_t)(k - keys);
}

/* The mark of whichever key was set explicitly, preferring a; the fallback otherwise. */
static const struct mark *mark_of(const struct mark *marks, const char *a, const char *b,
                                  const struct mark *fallback)
{
    const struct mark *ma = &marks[key_index(a)];
    const struct mark *mb = b ? &marks[key_index(b)] : NULL;
    if (ma->seq)
        return ma;
    if (mb && mb->seq)
        return mb;
    return fallback;
}

/* The later of two set keys' marks. */
static const struct mark *later_mark(const struct mark *marks, const char *a, const char *b)
{
    const struct mark *ma = &marks[key_index(a)], *mb = &marks[key_index(b)];
    return ma->seq > mb->seq ? ma : mb;
}

static enum rb_status check_camera_key(struct ctx *c, void *items, size_t i, const char *shown,
                                       const struct mark *marks, const struct mark *item_mark)
{
    const struct rb_job_camera_key *k = items;
    if (i > 0 && !(k[i].t_s > k[i - 1].t_s))
        return fail(c, mark_of(marks, "camera.keys[].t", NULL, item_mark), RB_E_INVALID,
                    "'%s.t' (%g) must be greater than the previous key's t (%g)", shown, k[i].t_s,
                    k[i - 1].t_s);
    if (!memcmp(k[i].position, k[i].look_at, sizeof(k[i].position)))
        return fail(c, mark_of(marks, "camera.keys[].look_at", NULL, item_mark), RB_E_INVALID,
                    "'%s.look_at' must differ from its position", shown);
    return RB_OK;
}

static enum rb_status check_light(struct ctx *c, void *items, size_t i, const char *shown,
                                  const struct mark *marks, const struct mark *item_mark)
{
    const struct rb_job_light *l = (const struct rb_job_light *)items + i;
    if (l->inner_cone_deg > l->outer_cone_deg)
        return fail(c,
                    mark_of(marks, "lights[].inner_cone_deg", "lights[].outer_cone_deg", item_mark),
                    RB_E_INVALID, "'%s.inner_cone_deg' (%g) must be <= its outer_cone_deg (%g)",
                    shown, l->inner_cone_deg, l->outer_cone_deg);
    double peak = fmax(fmax(l->color[0], l->color[1]), l->color[2]);
    if (!(peak * l->intensity <= RB_MAX_RADIANCE))
        return fail(c, mark_of(marks, "lights[].intensity", "lights[].color", item_mark),
                    RB_E_INVALID, "'%s.color' x '%s.intensity' is %g, more than %g", shown, shown,
                    peak * l->intensity, RB_MAX_RADIANCE);
    return RB_OK;
}

/* A mark as messages print it ("job.yaml:12:5", "--set:2:8", the option), allocated; NULL for
 * a key that was not set or has no position, and when out of memory (the message loses its
 * position, nothing else). */
static char *mark_text(const struct mark *m)
{
    if (!m->seq || !m->src)
        return NULL;
    size_t n = strlen(m->src) + 48;
    char *s = malloc(n);
    if (s && m->line == 0)
        snprintf(s, n, "%s", m->src);
    else if (s)
        snprintf(s, n, "%s:%zu:%zu", m->src, m->line, m->col);
    return s;
}

/* Keeps where the keys that the scene or the disk check later were set (struct rb_job's at). */
static void keep_marks(struct ctx *c)
{
    const struct mark *m = c->marks;
    struct rb_job *job = c->job;
    job->at.camera_node = mark_text(&m[key_index("camera.node")]);
    job->at.animation_clips = mark_text(&m[key_index("animation.clips")]);
    job->at.lights = mark_text(&m[key_index("lights")]);
    job->at.environment_map = mark_text(&m[key_index("environment.map")]);
    job->at.color_config = mark_text(&m[key_index("color.config")]);
}

/* The checks that span keys, and files that must exist; run after the overrides. */
static enum rb_status validate(struct ctx *c)
{
    struct rb_job *job = c->job;
    const struct mark *m = c->marks;

    for (size_t i = 0; i < KEY_COUNT; i++) {
        const char *name = key_in_scope(keys[i].path, "");
        if (name && (keys[i].flags & KF_REQUIRED) && !m[i].seq)
            return fail(c, &c->root, RB_E_PARSE, "missing required key '%s'", name);
    }
    if (job->frame_end != -1 && job->frame_end < job->frame_start)
        return fail(c, mark_of(m, "frames.end", "frames.start", &c->root), RB_E_INVALID,
                    "'frames.end' (%d) must be -1 or >= 'frames.start' (%d)", job->frame_end,
                    job->frame_start);
    job->layer_mask = 0;
    for (size_t i = 0; i < job->layer_count; i++) {
        uint32_t l = 0;
        while (l < RB_LAYER_COUNT && strcmp(job->layers[i], rb_layer_name((enum rb_layer)l)))
            l++;
        if (l == RB_LAYER_COUNT) {
            char known[256] = "";
            struct rb_suggest near;
            rb_suggest_init(&near, job->layers[i]);
            for (l = 0; l < RB_LAYER_COUNT; l++) {
                const char *name = rb_layer_name((enum rb_layer)l);
                snprintf(known + strlen(known), sizeof(known) - strlen(known), "%s%s",
                         l ? ", " : "", name);
                rb_suggest_offer(&near, name, strlen(name));
            }
            return fail(c, mark_of(m, "layers", NULL, &c->root), RB_E_INVALID,
                        "unknown layer '%s' (%s)%s%s%s", job->layers[i], known,
                        near.best[0] ? "; did you mean '" : "", near.best,
                        near.best[0] ? "'?" : "");
        }
        job->layer_mask |= 1u << l;
    }
    /* samples and tiles say how the hybrid integrator sampled each pixel (and the reference
     * its fixed count); direct and bdpt keep no such counts, and a layer of zeros would claim
     * that they took no samples. */
    enum rb_integrator_kind kind = rb_integrator_resolve(job->integrator.name);
    for (uint32_t l = RB_LAYER_SAMPLES; l <= RB_LAYER_TILES; l++)
        if ((job->layer_mask & (1u << l)) && kind != RB_INTEGRATOR_HYBRID &&
            kind != RB_INTEGRATOR_REFERENCE)
            return fail(c, later_mark(m, "layers", "integrator.name"), RB_E_INVALID,
                        "layer '%s' is written by the hybrid and reference integrators only, "
                        "and this job renders with '%s'",
                        rb_layer_name((enum rb_layer)l), rb_integrator_name(kind));
    /* variance is the spread of the reference's samples of a pixel; the GPU integrators keep
     * no samples apart, and one sample has no spread. */
    if (job->layer_mask & (1u << RB_LAYER_VARIANCE)) {
        if (kind != RB_INTEGRATOR_REFERENCE)
            return fail(c, later_mark(m, "layers", "integrator.name"), RB_E_INVALID,
                        "layer 'variance' is written by the reference integrator only, and this "
                        "job renders with '%s'",
                        rb_integrator_name(kind));
        if (job->integrator.reference.spp == 1)
            return fail(c, later_mark(m, "layers", "integrator.reference.spp"), RB_E_INVALID,
                        "layer 'variance' needs at least 2 samples a pixel, and "
                        "'integrator.reference.spp' is 1");
    }
    /* feedback is max_bounces's older spelling: whichever of the two was set last counts. */
    struct rb_job_hybrid *hy = &job->integrator.hybrid;
    if (m[key_index("integrator.hybrid.feedback")].seq >
        m[key_index("integrator.hybrid.max_bounces")].seq)
        hy->max_bounces = hy->feedback ? UINT32_MAX : 1;
    hy->feedback = hy->max_bounces == UINT32_MAX;
    struct rb_err why = RB_ERR_INIT;
    if (rb_job_check_output(job->output, job->frame_start, job->frame_end, &why))
        return fail(c, mark_of(m, "output", NULL, &c->root), RB_E_INVALID, "%s", why.msg);
    if (job->camera.node && job->camera.key_count)
        return fail(c, later_mark(m, "camera.node", "camera.keys"), RB_E_INVALID,
                    "'camera.node' and 'camera.keys' are mutually exclusive");
    if (job->camera.near_m > 0 && job->camera.far_m > 0 &&
        !(job->camera.far_m > job->camera.near_m))
        return fail(c, mark_of(m, "camera.far", "camera.near", &c->root), RB_E_INVALID,
                    "'camera.far' (%g) must be greater than 'camera.near' (%g)", job->camera.far_m,
                    job->camera.near_m);

    /* Each may be in range while their product, the radiance, overflows the renderer's floats. */
    const float *env = job->environment.color;
    double env_peak = fmax(fmax(env[0], env[1]), env[2]) * job->environment.intensity;
    if (!(env_peak <= RB_MAX_RADIANCE))
        return fail(c, later_mark(m, "environment.color", "environment.intensity"), RB_E_INVALID,
                    "'environment.color' x 'environment.intensity' is %g, more than %g", env_peak,
                    RB_MAX_RADIANCE);

    for (size_t i = 0; i < KEY_COUNT; i++) {
        if (!(keys[i].flags & KF_MUST_EXIST) || keys[i].type != KT_PATH)
            continue;
        const char *p = get_ptr(job, &keys[i]);
        struct stat sb;
        char what[64];
        rb_strlcpy(what, keys[i].path, sizeof(what));
        for (char *d = what; *d; d++)
            if (*d == '.')
                *d = ' ';
        if (!p)
            continue;
        if (stat(p, &sb) != 0) {
            if (errno == ENOENT || errno == ENOTDIR)
                return fail(c, &m[i], RB_E_IO, "%s file '%s' not found", what, p);
            return fail(c, &m[i], RB_E_IO, "cannot access %s file '%s': %s", what, p,
                        strerror(errno));
        }
        if (S_ISDIR(sb.st_mode))
            return fail(c, &m[i], RB_E_IO, "%s file '%s' is a directory", what, p);
    }
    return RB_OK;
}

/* ---- hashing ------------------------------------------------------------------------------- */

static uint64_t h_u32(uint64_t h, uint32_t v)
{
    return rb_hash64(&v, sizeof(v), h);
}

static uint64_t h_f32(uint64_t h, float v)
{
    uint32_t bits;
    if (v == 0.0f)
        v = 0.0f; /* -0 and +0 render alike */
    memcpy(&bits, &v, sizeof(bits));
    return h_u32(h, bits);
}

static uint64_t h_f64(uint64_t h, double v)
{
    uint64_t bits;
    if (v == 0.0)
        v = 0.0;
    memcpy(&bits, &v, sizeof(bits));
    return rb_hash64(&bits, sizeof(bits), h);
}

static uint64_t h_vec3(uint64_t h, const float v[3])
{
    for (int i = 0; i < 3; i++)
        h = h_f32(h, v[i]);
    return h;
}

/* Length-prefixed, so adjacent strings cannot run together; NULL differs from "". */
static uint64_t h_str(uint64_t h, const char *s)
{
    if (!s)
        return h_u32(h, UINT32_MAX);
    size_t n = strlen(s);
    h = h_u32(h, (uint32_t)n);
    return rb_hash64(s, n, h);
}

void rb_job_rehash(struct rb_job *job)
{
    uint64_t h = h_str(RB_HASH_SEED, "raybundle job 1");
    h = h_str(h, job->scene_path);
    h = h_u32(h, job->width_px);
    h = h_u32(h, job->height_px);
    h = h_u32(h, job->layer_mask);
    h = h_f64(h, job->rate_fps);
    h = h_u32(h, job->fill_before_start);

    enum rb_interp interp =
        job->camera.interpolation ? job->camera.interpolation : RB_INTERP_CATMULL_ROM;
    h = h_str(h, job->camera.node);
    h = h_f32(h, job->camera.fov_y_deg);
    h = h_u32(h, (uint32_t)interp);
    h = h_f32(h, job->camera.near_m);
    h = h_f32(h, job->camera.far_m);
    h = h_u32(h, (uint32_t)job->camera.key_count);
    for (size_t i = 0; i < job->camera.key_count; i++) {
        const struct rb_job_camera_key *k = &job->camera.keys[i];
        h = h_f64(h, k->t_s);
        h = h_vec3(h, k->position);
        h = h_vec3(h, k->look_at);
        h = h_f32(h, k->fov_y_deg);
    }

    h = h_u32(h, (uint32_t)job->animation.clip_count);
    for (size_t i = 0; i < job->animation.clip_count; i++)
        h = h_str(h, job->animation.clips[i]);
    h = h_f64(h, job->animation.offset_s);
    h = h_f64(h, job->animation.speed);
    h = h_u32(h, job->animation.loop);

    h = h_u32(h, (uint32_t)job->light_count);
    for (size_t i = 0; i < job->light_count; i++) {
        const struct rb_job_light *l = &job->lights[i];
        h = h_u32(h, (uint32_t)l->type);
        h = h_vec3(h, l->position);
        h = h_vec3(h, l->direction);
        h = h_vec3(h, l->color);
        h = h_f32(h, l->intensity);
        h = h_f32(h, l->range);
        h = h_f32(h, l->inner_cone_deg);
        h = h_f32(h, l->outer_cone_deg);
    }
    h = h_u32(h, job->use_scene_lights);
    h = h_u32(h, job->default_light == RB_DEFAULT_LIGHT_DEFAULT ? RB_DEFAULT_LIGHT_AUTO
                                                                : job->default_light);

    h = h_str(h, job->environment.map);
    h = h_vec3(h, job->environment.color);
    h = h_f32(h, job->environment.intensity);
    h = h_f32(h, job->environment.rotation_deg);

    enum rb_integrator_kind kind = rb_integrator_resolve(job->integrator.name);
    h = h_u32(h, (uint32_t)kind);
    /* Only the named integrator's settings: a frame does not depend on another's. */
    if (kind == RB_INTEGRATOR_REFERENCE) {
        h = h_u32(h, job->integrator.reference.spp);
        h = h_u32(h, job->integrator.reference.max_bounces);
        h = h_u32(h, job->integrator.reference.rr_depth);
        h = h_u32(h, (uint32_t)job->integrator.reference.paths);
        h = h_f64(h, job->integrator.reference.time_limit_s);
        h = h_u32(h, (uint32_t)job->integrator.reference.pixel_filter);
        if (job->integrator.reference.paths == RB_PATHS_DIRECT)
            h = h_u32(h, job->integrator.direct.emitter_lights);
    } else {
        h = h_u32(h, job->integrator.direct.shadow_size_px);
        h = h_f32(h, job->integrator.direct.shadow_bias);
        h = h_f32(h, job->integrator.direct.pcf_radius_px);
        /* direct's emitter lights; bdpt's and hybrid's blended layers' */
        h = h_u32(h, job->integrator.direct.emitter_lights);
    }
    if (kind == RB_INTEGRATOR_BDPT) {
        const struct rb_job_bdpt *b = &job->integrator.bdpt;
        h = h_u32(h, b->vpls);
        h = h_u32(h, b->bundles);
        h = h_u32(h, b->rsm_size_px);
        h = h_u32(h, b->vpl_size_px);
        /* only where it changes the maps: 0 and vpl_size and above draw them whole, and the
         * jobs from before the key keep their hash */
        if (b->bounce_vpl_size_px && b->bounce_vpl_size_px < b->vpl_size_px)
            h = h_u32(h, b->bounce_vpl_size_px);
        h = h_u32(h, b->bundle_size_px);
        h = h_u32(h, b->node_buffer_kib); /* an overflowing buffer drops fragments */
        h = h_u32(h, b->interleave);
        h = h_u32(h, b->filter_radius_px);
        h = h_f32(h, b->filter_depth);
        h = h_f32(h, b->filter_normal);
        h = h_f32(h, b->filter_light);
        h = h_f32(h, b->clamp);
        h = h_f32(h, b->vpl_bias);
        h = h_f32(h, b->min_roughness);
        h = h_f32(h, b->vpl_spread);
        h = h_u32(h, b->view_triangles);
        h = h_u32(h, (uint32_t)b->strategies);
        h = h_u32(h, b->caches);
        h = h_f32(h, b->hit_variance);
        h = h_u32(h, (uint32_t)b->hit_test);
        h = h_f32(h, b->hit_epsilon);
        h = h_u32(h, (uint32_t)b->samples);
    }
    if (kind == RB_INTEGRATOR_HYBRID) {
        const struct rb_job_hybrid *y = &job->integrator.hybrid;
        h = h_u32(h, y->rays);
        h = h_u32(h, y->spp);
        h = h_u32(h, y->history);
        h = h_f32(h, y->noise);
        h = h_f32(h, y->thickness);
        h = h_u32(h, y->screen_steps);
        h = h_u32(h, y->bvh_triangles);
        h = h_u32(h, y->bvh_interval);
        h = h_u32(h, (uint32_t)y->bvh_select);
        h = h_u32(h, y->screen_shadows);
        h = h_u32(h, y->bvh_lod);
        h = h_u32(h, y->bake_texels);
        h = h_u32(h, y->bake_samples);
        h = h_u32(h, y->check_screen); /* the sidecar's screen_check */
        h = h_u32(h, y->queue_rays);   /* an overflowing queue drops rays */
        h = h_u32(h, y->filter_radius_px);
        h = h_f32(h, y->filter_depth);
        h = h_f32(h, y->filter_normal);
        h = h_u32(h, y->feedback);
        /* a count feedback does not already say (it says unlimited and 1) */
        if (y->max_bounces != UINT32_MAX && y->max_bounces != 1)
            h = h_u32(h, y->max_bounces);
    }
    job->hash = h;
}

/* ---- public entry points ------------------------------------------------------------------- */

static enum rb_status apply_overrides(struct ctx *c, const struct rb_job_override *overrides,
                                      size_t override_count)
{
    /* "--set:N" counts the --set options alone; options that are sugar for one name themselves. */
    size_t sets = 0;
    for (size_t i = 0; i < override_count; i++) {
        size_t index = overrides[i].origin ? i + 1 : ++sets;
        enum rb_status st = apply_override(c, index, &overrides[i]);
        if (st)
            return st;
    }
    return RB_OK;
}

enum rb_status rb_job_parse(const char *name, const char *text, size_t size, const char *base_dir,
                            const struct rb_job_override *overrides, size_t override_count,
                            struct rb_job **out, struct rb_err *err)
{
    struct rb_err scratch = RB_ERR_INIT;
    struct ctx c = {.name = name ? name : "job",
                    .base_dir = base_dir ? base_dir : "",
                    .text = text,
                    .err = err ? err : &scratch};
    yaml_document_t doc;
    bool has_doc = false;
    enum rb_status st = RB_OK;

    c.root = (struct mark){c.name, 1, 1, 0};
    if (!(c.job = calloc(1, sizeof(*c.job))) || !(c.job->path = rb_strdup(c.name))) {
        st = rb_errf(c.err, RB_E_NOMEM, "%s: out of memory", c.name);
        goto out;
    }
    if ((st = apply_defaults(&c, "", c.job)))
        goto out;
    if ((st = load_yaml(&c, text ? text : "", text ? size : 0, &doc, &has_doc)))
        goto out;
    c.doc = &doc;
    yaml_node_t *root = yaml_document_get_root_node(&doc);
    if (root && !is_null(root)) {
        c.root = mark_at(&c, root->start_mark);
        if (root->type != YAML_MAPPING_NODE) {
            st = fail(&c, &c.root, RB_E_PARSE, "a job file is a mapping of keys");
            goto out;
        }
        if ((st = walk_mapping(&c, root, "", "", c.job, c.marks)))
            goto out;
    }
    c.doc = NULL;
    c.job->sequence_start = c.job->frame_start;
    if ((st = apply_overrides(&c, overrides, override_count)))
        goto out;
    if ((st = validate(&c)))
        goto out;
    keep_marks(&c);
    rb_job_rehash(c.job);
    *out = c.job;
    c.job = NULL;
out:
    if (has_doc)
        yaml_document_delete(&doc);
    rb_job_destroy(c.job);
    return st;
}

/* The default job for a quick look at a glTF: its first camera (or one fitted to the bounds),
 * its first animation, its own lights, rendered with bdpt, written to out/<name>/ under the
 * current directory. */
static enum rb_status quick_look(const char *path, const struct rb_job_override *overrides,
                                 size_t override_count, struct rb_job **out, struct rb_err *err)
{
    struct rb_err scratch = RB_ERR_INIT;
    struct ctx c = {.name = path, .base_dir = "", .err = err ? err : &scratch};
    enum rb_status st = RB_OK;
    struct stat sb;

    if (stat(path, &sb) != 0)
        return rb_errf(err, RB_E_IO, "cannot open '%s': %s", path, strerror(errno));
    if (S_ISDIR(sb.st_mode))
        return rb_errf(err, RB_E_IO, "cannot open '%s': %s", path, strerror(EISDIR));

    const char *base = strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
    size_t stem = strrchr(base, '.') ? (size_t)(strrchr(base, '.') - base) : strlen(base);
    size_t olen = strlen("out//frame.####.exr") + stem + 1;
    c.root = (struct mark){NULL, 0, 0, 0};
    if (!(c.job = calloc(1, sizeof(*c.job)))) {
        st = rb_errf(c.err, RB_E_NOMEM, "%s: out of memory", path);
        goto out;
    }
    if ((st = apply_defaults(&c, "", c.job)))
        goto out;
    /* A quick look shows the scene's light, whatever lights it: bdpt, not direct. */
    c.job->integrator.name = RB_INTEGRATOR_BDPT;
    free(c.job->output);
    c.job->output = malloc(olen);
    c.job->path = rb_strdup(path);
    c.job->scene_path = rb_strdup(path);
    if (!c.job->output || !c.job->path || !c.job->scene_path) {
        st = rb_errf(c.err, RB_E_NOMEM, "%s: out of memory", path);
        goto out;
    }
    snprintf(c.job->output, olen, "out/%.*s/frame.####.exr", (int)stem, base);
    c.marks[key_index("scene")] = (struct mark){NULL, 0, 0, ++c.seq};
    c.marks[key_index("output")] = (struct mark){NULL, 0, 0, ++c.seq};
    c.job->sequence_start = c.job->frame_start;
    c.job->fill_before_start = true;
    if ((st = apply_overrides(&c, overrides, override_count)))
        goto out;
    if ((st = validate(&c)))
        goto out;
    keep_marks(&c);
    rb_job_rehash(c.job);
    *out = c.job;
    c.job = NULL;
out:
    rb_job_destroy(c.job);
    return st;
}

enum rb_status rb_job_load(const char *path, const struct rb_job_override *overrides,
                           size_t override_count, struct rb_job **out, struct rb_err *err)
{
    if (has_suffix_ci(path, ".gltf") || has_suffix_ci(path, ".glb"))
        return quick_look(path, overrides, override_count, out, err);

    char *text = NULL, *dir = NULL;
    size_t size = 0;
    enum rb_status st = rb_read_file(path, &text, &size, err);
    if (st)
        return st;
    const char *slash = strrchr(path, '/');
    if (slash) {
        size_t n = slash == path ? 1 : (size_t)(slash - path);
        if ((dir = malloc(n + 1))) {
            memcpy(dir, path, n);
            dir[n] = '\0';
        }
    }
    if (slash && !dir)
        st = rb_errf(err, RB_E_NOMEM, "%s: out of memory", path);
    else
        st = rb_job_parse(path, text, size, dir ? dir : "", overrides, override_count, out, err);
    free(dir);
    free(text);
    return st;
}

void rb_job_destroy(struct rb_job *job)
{
    if (!job)
        return;
    free(job->path);
    free(job->scene_path);
    free(job->output);
    free(job->camera.node);
    free(job->camera.keys);
    free_strlist(job->animation.clips, job->animation.clip_count);
    free_strlist(job->layers, job->layer_count);
    free(job->lights);
    free(job->environment.map);
    free(job->color.config);
    free(job->color.display);
    free(job->color.view);
    free(job->at.camera_node);
    free(job->at.animation_clips);
    free(job->at.lights);
    free(job->at.environment_map);
    free(job->at.color_config);
    free(job);
}

const char *rb_job_yaml_version(void)
{
    return yaml_get_version_string();
}

const char *rb_integrator_name(enum rb_integrator_kind kind)
{
    kind = rb_integrator_resolve(kind);
    if ((size_t)kind < COUNT(integrator_names))
        return integrator_names[kind];
    return "unknown";
}

enum rb_integrator_kind rb_integrator_from_name(const char *name)
{
    for (size_t i = 1; name && i < COUNT(integrator_names); i++)
        if (!strcmp(name, integrator_names[i]))
            return (enum rb_integrator_kind)i;
    return RB_INTEGRATOR_DEFAULT;
}

/* ---- the table, for help and the man-page test ----------------------------------------- */

static void type_text(const struct key *k, char *buf, size_t size)
{
    switch (k->type) {
    case KT_BOOL: snprintf(buf, size, "bool"); break;
    case KT_INT:
    case KT_UINT: snprintf(buf, size, "int"); break;
    case KT_FLOAT:
    case KT_DOUBLE: snprintf(buf, size, "float"); break;
    case KT_STRING: snprintf(buf, size, "string"); break;
    case KT_PATH: snprintf(buf, size, "path"); break;
    case KT_VEC3: snprintf(buf, size, "[x, y, z]"); break;
    case KT_UINT2: snprintf(buf, size, "[w, h]"); break;
    case KT_STRLIST: snprintf(buf, size, "[string]"); break;
    case KT_LIST: snprintf(buf, size, "[mapping]"); break;
    case KT_ENUM:
        buf[0] = '\0';
        for (size_t i = 1; i < k->name_count; i++) {
            size_t len = strlen(buf);
            snprintf(buf + len, size - len, "%s%s", i > 1 ? "|" : "", k->names[i]);
        }
        break;
    }
}

static const char *default_text(const struct key *k)
{
    return k->def ? k->def : (k->flags & KF_REQUIRED) ? "required" : "none";
}

/* Writes text's words to f from column col, breaking before a word that would pass width and
 * going on at column indent; a word longer than a line gets a line of its own. Ends the line. */
static void print_wrapped(FILE *f, const char *text, int col, int indent, int width)
{
    bool is_first = true;
    for (const char *p = text; *p;) {
        while (*p == ' ')
            p++;
        int len = (int)strcspn(p, " ");
        if (!len)
            break;
        if (!is_first && col + 1 + len > width) {
            fprintf(f, "\n%*s", indent, "");
            col = indent;
        } else if (!is_first) {
            fputc(' ', f);
            col++;
        }
        fprintf(f, "%.*s", len, p);
        col += len;
        p += len;
        is_first = false;
    }
    fputc('\n', f);
}

size_t rb_job_print_keys(FILE *f, const char *prefix, int width)
{
    char type[128], range[80], head[512], text[1024];
    size_t printed = 0, len = prefix ? strlen(prefix) : 0;
    if (width < 40) /* narrower than this, the indented help would be a word a line */
        width = 40;
    for (size_t i = 0; i < KEY_COUNT; i++) {
        if (len && strncmp(keys[i].path, prefix, len) != 0)
            continue;
        type_text(&keys[i], type, sizeof(type));
        range_text(&keys[i], range, sizeof(range));
        /* A block a key: the path at the margin (so a reader, or grep '^frames', finds it),
         * then its type and default, then its help indented, each wrapped to the width. */
        const char *def = default_text(&keys[i]);
        snprintf(head, sizeof(head), "%s (%s, %s%s)", keys[i].path, type,
                 strcmp(def, "required") ? "default " : "", def);
        print_wrapped(f, head, 0, 4, width);
        snprintf(text, sizeof(text), "%s%s%s%s", keys[i].help, range[0] ? " (" : "", range,
                 range[0] ? ")" : "");
        fputs("    ", f);
        print_wrapped(f, text, 4, 4, width);
        printed++;
    }
    return printed;
}

size_t rb_job_key_count(void)
{
    return KEY_COUNT;
}

const char *rb_job_key_path(size_t i)
{
    return i < KEY_COUNT ? keys[i].path : NULL;
}
