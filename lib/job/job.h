/* The job: a YAML job file (or a glTF for a quick look) turned into a validated struct.
 * Only lib/job knows YAML; everything else sees struct rb_job. Keys, types, ranges and defaults
 * live in one table (job.c), which also feeds `raybundle help job` and the man-page test. */
#ifndef RB_JOB_JOB_H
#define RB_JOB_JOB_H

#include "core/core.h"

#include <stdio.h>

enum rb_integrator_kind {
    RB_INTEGRATOR_DEFAULT = 0, /* resolves to BDPT */
    RB_INTEGRATOR_DIRECT,
    RB_INTEGRATOR_BDPT,
    RB_INTEGRATOR_HYBRID,
    RB_INTEGRATOR_REFERENCE,
};

enum rb_interp {
    RB_INTERP_DEFAULT = 0, /* resolves to CATMULL_ROM */
    RB_INTERP_LINEAR,
    RB_INTERP_CATMULL_ROM,
};

/* Which light paths the reference counts (DESIGN.md "reference"). */
enum rb_path_space {
    RB_PATHS_DEFAULT = 0, /* resolves to FULL */
    RB_PATHS_FULL,        /* every path up to max_bounces */
    RB_PATHS_DIRECT,      /* what the direct integrator computes: punctual lights and the
                           * emitters' point samples (shadowed), emission, and the environment
                           * seen directly */
    RB_PATHS_BDPT,        /* what bdpt computes: direct light and up to two indirect bounces
                           * from punctual lights and emissive triangles, the environment's
                           * direct light */
};

/* Which bdpt strategies count (BDPT.md): all of them weighted by MIS, or one side alone. */
enum rb_bdpt_strategies {
    RB_BDPT_STRATEGIES_DEFAULT = 0, /* resolves to MIS */
    RB_BDPT_STRATEGIES_MIS,         /* VPL and bundle strategies, balance heuristic */
    RB_BDPT_STRATEGIES_VPL,         /* one-bounce paths from VPLs alone, unweighted */
    RB_BDPT_STRATEGIES_BUNDLE,      /* one-bounce paths from bundles alone, unweighted */
};

/* How bdpt detects that a pixel's surface is in a temporal cache (seed 000, section A). */
enum rb_bdpt_hit_test {
    RB_BDPT_HIT_DEFAULT = 0, /* resolves to GAUSSIAN */
    RB_BDPT_HIT_GAUSSIAN,    /* equation (3): exp(-log^2(z / z_cached) / (2 hit_variance)) */
    RB_BDPT_HIT_BINARY,      /* equation (2): 1 when |z - z_cached| < hit_epsilon, else 0 */
};

/* Which quasi-random points bdpt's caches use, frame after frame. */
enum rb_bdpt_samples {
    RB_BDPT_SAMPLES_DEFAULT = 0, /* resolves to PERIODIC */
    RB_BDPT_SAMPLES_PERIODIC,    /* cache i always the i-th block: the seed's, flicker-free */
    RB_BDPT_SAMPLES_FRESH,       /* frame f the f-th block: new points every frame */
};

/* Where bdpt's temporal caches sample a pixel. */
enum rb_bdpt_subpixel {
    RB_BDPT_SUBPIXEL_DEFAULT = 0, /* resolves to CENTER */
    RB_BDPT_SUBPIXEL_CENTER,      /* every cache at the pixel's centre, as the direct light */
    RB_BDPT_SUBPIXEL_SPREAD,      /* cache i at subpixel offset i: the seed's supersampling */
};

/* How the hybrid's BVH scores objects for its triangle budget. */
enum rb_bvh_select {
    RB_BVH_SELECT_DEFAULT = 0, /* resolves to RELEVANCE */
    RB_BVH_SELECT_RELEVANCE,   /* projected size from the camera over triangles */
    RB_BVH_SELECT_AREA,        /* world area over triangles, camera-independent */
};

/* Where the reference's samples pass through a pixel. */
enum rb_pixel_filter {
    RB_PIXEL_FILTER_DEFAULT = 0, /* resolves to CENTER */
    RB_PIXEL_FILTER_CENTER,      /* all through the centre, as the rasterizer samples */
    RB_PIXEL_FILTER_BOX,         /* uniformly over the pixel: a 1-pixel box filter */
};

enum rb_light_type {
    RB_LIGHT_INVALID = 0,
    RB_LIGHT_POINT,
    RB_LIGHT_SPOT,
    RB_LIGHT_DIRECTIONAL,
    RB_LIGHT_EMITTER, /* a point sample of the emissive surfaces (rb_scene_emitter_lights); never
                       * named in a job: light_names in job.c stops before it */
};

/* When a default point light is added (lib/scene/setup.c). */
enum rb_default_light {
    RB_DEFAULT_LIGHT_DEFAULT = 0, /* resolves to AUTO */
    RB_DEFAULT_LIGHT_AUTO,        /* only when the frame would otherwise be unlit */
    RB_DEFAULT_LIGHT_ON,          /* always, beside the other lights */
    RB_DEFAULT_LIGHT_OFF,         /* never */
};

struct rb_job_camera_key {
    double t_s;
    float position[3];
    float look_at[3];
    float fov_y_deg; /* 0 == the track's fov_y_deg */
};

struct rb_job_light {
    enum rb_light_type type;
    float position[3];  /* point, spot */
    float direction[3]; /* spot, directional: the direction the light travels */
    float color[3];     /* linear Rec.709, default 1,1,1 */
    float intensity;    /* candela (point, spot) or lux (directional), as KHR_lights_punctual */
    float range;        /* 0 == infinite */
    float inner_cone_deg, outer_cone_deg; /* spot; defaults 0 and 45 */
};

struct rb_job {
    char *path;       /* the job file as given */
    char *scene_path; /* resolved relative to the job file's directory */
    char *output;     /* output pattern, resolved relative to the job file; '#' run = frame */
    char **layers;    /* names of the EXR's layers beside the beauty (rb_layer_name) */
    size_t layer_count;
    uint32_t layer_mask; /* the same as bits of enum rb_layer; resolved by the parser */
    uint32_t width_px, height_px;
    int frame_start, frame_end; /* inclusive; frame_end == -1: to the end of the animation */
    int sequence_start;         /* frames.start as the job file has it, before the command line's
                                 * overrides (--frames, --set): where the sequence begins, which a
                                 * chunk or a frame list does not move */
    bool fill_before_start;     /* a quick look: the frames bdpt warms up on before the sequence's
                                 * start fill its caches too, so its first frame is its steady
                                 * state (a job file's first frame has only its own cache, as a
                                 * sequence's first frame has) */
    double rate_fps;

    struct {
        char *node; /* a glTF camera node by name; NULL: use keys, or fit to the scene */
        float fov_y_deg;
        enum rb_interp interpolation;
        struct rb_job_camera_key *keys;
        size_t key_count;
        float near_m, far_m; /* clip planes; 0 == derived from the scene bounds */
    } camera;

    struct {
        char **clips; /* names; none: the scene's first animation, if any */
        size_t clip_count;
        double offset_s, speed;
        bool loop;
    } animation;

    struct rb_job_light *lights; /* added to the scene's own lights */
    size_t light_count;
    bool use_scene_lights; /* default true */
    enum rb_default_light default_light;

    struct {
        char *map;          /* equirectangular EXR/HDR, resolved; NULL: uniform color */
        float color[3];     /* radiance where there is no map, default 0 */
        float intensity;    /* default 1 */
        float rotation_deg; /* about +Y */
    } environment;

    struct {
        enum rb_integrator_kind name;
        struct {
            uint32_t shadow_size_px; /* per cube face / shadow map, default 1024 */
            float shadow_bias;       /* fraction of the distance to the light; default 0.002 */
            float pcf_radius_px;     /* radius of the 16-tap PCF kernel, default 1.5 */
            uint32_t emitter_lights; /* point samples standing for the emissive surfaces, each
                                      * a cube of shadow maps; default 8, 0: none */
        } direct;
        struct rb_job_bdpt {
            uint32_t vpls;             /* VPLs per frame, default 21 */
            uint32_t bundles;          /* global ray-bundles per frame, default 21 */
            uint32_t rsm_size_px;      /* reflective shadow map, per cube face, default 256 */
            uint32_t vpl_size_px;      /* VPL paraboloid shadow map, default 256 */
            uint32_t bundle_size_px;   /* ray-bundle head image, default 256 */
            uint32_t node_buffer_kib;  /* ray-bundle node buffer, default 20480 (20 MiB) */
            uint32_t interleave;       /* n: n x n sub-images, default 4 */
            uint32_t filter_radius_px; /* geometry-aware filter, default 4 */
            float filter_depth;        /* relative depth difference that stops it, default 0.05 */
            float filter_normal;       /* cosine between normals below which it stops, 0.9 */
            float filter_light;        /* least ratio of two pixels' direct light it joins, 0.5 */
            float clamp;               /* bound on G(z1, z2) of two-bounce paths, times the
                                        * scene's diagonal squared; 0: none; default 100 */
            float vpl_bias;            /* VPL shadow-map depth bias, fraction of distance */
            float min_roughness;       /* the least roughness of the BRDF at a VPL or a bundle's
                                        * hit (path regularization); 0: as the material has it */
            float vpl_spread;          /* a VPL's disk, in the areas it stands for among the
                                        * frame's VPLs; 0: a point; default 1 */
            uint32_t view_triangles;   /* triangle budget of the small views' simplified mesh;
                                        * 0: the full mesh; default 50000 */
            enum rb_bdpt_strategies strategies;
            uint32_t caches;    /* l: temporal caches, one per subpixel offset, default 4 */
            float hit_variance; /* sigma^2 of equation (3), default 0.00005 */
            enum rb_bdpt_hit_test hit_test;
            float hit_epsilon; /* equation (2)'s bound on the depth difference, in metres */
            enum rb_bdpt_samples samples;
            enum rb_bdpt_subpixel subpixel;
            uint32_t bounce_vpl_size_px; /* the bounce VPLs' maps, at most vpl_size_px; 0 (the
                                          * default): vpl_size_px */
        } bdpt;
        struct rb_job_hybrid {
            uint32_t rays;             /* rays a lobe per pixel and frame, default 1 */
            uint32_t spp;              /* samples a lobe a pixel aims for, default 64 */
            uint32_t history;          /* W: frames an accumulator spans, default 128 */
            float noise;               /* tile noise target (relative error), default 0.02 */
            float thickness;           /* screen hit depth tolerance, relative, default 0.03 */
            uint32_t screen_steps;     /* most hierarchical depth steps a ray, default 96 */
            uint32_t bvh_triangles;    /* BVH triangle budget, default 2000000 */
            uint32_t bvh_interval;     /* frames between BVH builds, default 1 */
            bool bvh_lod;              /* coarser objects under the budget, default true */
            uint32_t bake_texels;      /* baked light points past the vertices, 65536 */
            uint32_t bake_samples;     /* light samples a baked point, default 32; 0: none */
            bool check_screen;         /* screen hits traced again through the BVH */
            uint32_t max_bounces;      /* past the first hit; UINT32_MAX (default): unlimited */
            bool feedback;             /* max_bounces is UINT32_MAX (the older key's spelling) */
            uint32_t queue_rays;       /* BVH queue capacity; 0: every ray of a frame */
            uint32_t filter_radius_px; /* the filter's radius at one sample, default 6 */
            float filter_depth;        /* relative depth difference that stops it, 0.05 */
            float filter_normal;       /* cosine between normals below which it stops, 0.9 */
            /* the score the BVH's budget chooses objects by, default relevance */
            enum rb_bvh_select bvh_select;
            /* light samples also find occluders the BVH leaves out by a screen march */
            bool screen_shadows;
        } hybrid;
        struct {
            uint32_t spp;         /* samples per pixel, default 64 */
            uint32_t max_bounces; /* default 8; 0: direct light only */
            uint32_t rr_depth;    /* Russian roulette after this many bounces, default 3 */
            enum rb_path_space paths;
            enum rb_pixel_filter pixel_filter;
            double time_limit_s; /* 0: none; else stop at a whole pass when it runs out */
        } reference;
    } integrator;

    struct {
        char *config;  /* OCIO config, resolved; NULL: $OCIO, then the bundled config */
        char *display; /* NULL: the config's default */
        char *view;    /* NULL: the config's default */
        bool preview;  /* write NAME.####.png beside each EXR */
    } color;

    /* Where the keys that later stages check against the scene or the disk were set, for
     * their messages: "job.yaml:12:5", "--set:2:8" or the option ("--integrator 'x'"); NULL
     * where the job does not set the key (its default, or a quick look). RB_JOB_AT prints one. */
    struct {
        char *camera_node, *animation_clips, *lights, *environment_map, *color_config;
    } at;

    uint64_t hash; /* of every setting that changes pixels: the scene's path, not its contents
                    * (struct rb_scene_setup's job_hash adds those); the named integrator's
                    * settings only; not the frame range or output */
};

/* A message's prefix for a key's position (struct rb_job's at): printf arguments for "%s%s",
 * "job.yaml:12:5: " or "" where there is none. */
#define RB_JOB_AT(where) (where) ? (where) : "", (where) ? ": " : ""

/* One `--set key.path=value` override, applied after the file is parsed. */
struct rb_job_override {
    const char *key;    /* dotted path, e.g. "integrator.direct.shadow_size" */
    const char *value;  /* YAML flow text, e.g. "512" or "[640, 360]" */
    const char *origin; /* what the user wrote, for messages ("--frames '2-1'"); NULL: --set,
                         * and messages name "--set:N:col" */
};

/* Parses a job file, applies overrides in order, validates, resolves defaults and relative paths
 * and computes the hash. A path ending in .gltf or .glb builds the default job for that scene.
 * Errors name file:line:column ("--set:N:col" for overrides) and return RB_E_PARSE or
 * RB_E_INVALID; a missing file returns RB_E_IO. *out is written only on success and is freed
 * with rb_job_destroy. */
enum rb_status rb_job_load(const char *path, const struct rb_job_override *overrides,
                           size_t override_count, struct rb_job **out, struct rb_err *err);

/* Parses job text held in memory; name is used in messages and base_dir resolves paths. */
enum rb_status rb_job_parse(const char *name, const char *text, size_t size, const char *base_dir,
                            const struct rb_job_override *overrides, size_t override_count,
                            struct rb_job **out, struct rb_err *err);

/* Checks an output pattern for frames frame_start..frame_end (-1: to the end of the animation):
 * its file name ends in .exr, and has a run of '#' unless the range is one frame. Returns
 * RB_E_INVALID with a message naming the pattern. The job parser applies it to the output key;
 * callers that change job->output afterwards call it again. */
enum rb_status rb_job_check_output(const char *pattern, int frame_start, int frame_end,
                                   struct rb_err *err);

/* Recomputes job->hash after a caller changed fields (the CLI's --size and such). */
void rb_job_rehash(struct rb_job *job);

void rb_job_destroy(struct rb_job *job);

/* libyaml's version, e.g. "0.2.5". */
const char *rb_job_yaml_version(void);

const char *rb_integrator_name(enum rb_integrator_kind kind);

/* The integrator a job with integrator.name `kind` renders with: that one, or for
 * RB_INTEGRATOR_DEFAULT (a job built without the key table's default) bdpt, the key's default. */
static inline enum rb_integrator_kind rb_integrator_resolve(enum rb_integrator_kind kind)
{
    return kind == RB_INTEGRATOR_DEFAULT ? RB_INTEGRATOR_BDPT : kind;
}
/* Returns RB_INTEGRATOR_DEFAULT when name is unknown. */
enum rb_integrator_kind rb_integrator_from_name(const char *name);

/* Writes the keys whose dotted path starts with prefix (NULL or "": every key) to f, for
 * `raybundle help job`: each as its path, type and default on a line at the margin, then its help
 * (with the values it takes) indented by four, every line wrapped to width columns (at least 40;
 * a word longer than a line stands alone). Returns how many keys it wrote. */
size_t rb_job_print_keys(FILE *f, const char *prefix, int width);
/* The number of keys in the table and the dotted path of key i (for the man-page test). */
size_t rb_job_key_count(void);
const char *rb_job_key_path(size_t i);

#endif
