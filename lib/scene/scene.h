/* The scene: a glTF 2.0 file (.gltf or .glb, through tinygltf) as flat C arrays, and its
 * evaluation at a time: animated node transforms, skin joint matrices, morph weights, the camera
 * track and the lights in world space. Geometry is kept in the file's local spaces; the GPU
 * `animate` pass applies skins, morphs and node transforms. Objects refer to each other by index.
 */
#ifndef RB_SCENE_SCENE_H
#define RB_SCENE_SCENE_H

#include "core/core.h"
#include "job/job.h"

#define RB_SCENE_NONE UINT32_MAX /* "no such object" in an index field */

/* One vertex as the loader stores it and the animate pass reads it (std430-compatible). */
struct rb_scene_vertex {
    float position[3];
    float normal[3];  /* generated (flat, per face) when the file has none */
    float tangent[4]; /* xyz, w = handedness; generated when there is a normal map and none */
    float uv[2];      /* TEXCOORD_0, or 0 */
    uint32_t joints[4];
    float weights[4]; /* all 0 for an unskinned vertex */
};

/* Per morph target and vertex: deltas added with the target's weight. */
struct rb_scene_morph_delta {
    float position[3];
    float normal[3];
};

struct rb_scene_texture {
    char *name; /* for messages: the image's name or uri */
    uint32_t width_px, height_px;
    uint8_t *rgba8; /* width*height*4 bytes, rows top to bottom, as stored (sRGB or linear) */
};

enum rb_alpha_mode { RB_ALPHA_OPAQUE = 0, RB_ALPHA_MASK, RB_ALPHA_BLEND };

struct rb_scene_material {
    char *name;
    float base_color[4];             /* factor, linear */
    uint32_t base_color_tex;         /* texture index or RB_SCENE_NONE; sRGB-encoded */
    float metallic, roughness;       /* factors */
    uint32_t metallic_roughness_tex; /* G = roughness, B = metallic; linear */
    uint32_t normal_tex;
    float normal_scale;
    float emissive[3];     /* factor times KHR_materials_emissive_strength */
    uint32_t emissive_tex; /* sRGB-encoded */
    enum rb_alpha_mode alpha_mode;
    float alpha_cutoff;
    bool double_sided;
    float specular_factor;   /* KHR_materials_specular; 1 without the extension */
    float specular_color[3]; /* KHR_materials_specular; 1,1,1 without the extension */
};

struct rb_scene_primitive {
    uint32_t material;     /* index; the scene always has a default material at the end */
    uint32_t first_vertex; /* into scene->vertices */
    uint32_t vertex_count;
    uint32_t first_index; /* into scene->indices; values are relative to first_vertex */
    uint32_t index_count; /* triangles only; non-indexed primitives get 0..n-1 */
    uint32_t first_morph; /* into scene->morph_deltas: target t, vertex v at
                           * first_morph + t * vertex_count + v */
    uint32_t morph_target_count;
};

struct rb_scene_mesh {
    char *name;
    uint32_t first_primitive, primitive_count;
    float *default_weights; /* morph_target_count of them (mesh.weights or 0) */
    uint32_t weight_count;
};

struct rb_scene_node {
    char *name;
    uint32_t parent; /* RB_SCENE_NONE for a root */
    struct rb_vec3 translation;
    struct rb_quat rotation;
    struct rb_vec3 scale;
    uint32_t mesh, skin, camera, light; /* RB_SCENE_NONE when absent */
    float *weights;                     /* node.weights override, or NULL */
    bool in_scene;                      /* reachable from the default scene's roots */
};

struct rb_scene_skin {
    char *name;
    uint32_t *joints; /* node indices */
    struct rb_mat4 *inverse_bind;
    uint32_t joint_count;
};

struct rb_scene_camera {
    char *name;
    bool is_perspective;
    float yfov_rad, aspect; /* aspect 0: from the image */
    float znear, zfar;      /* zfar 0: infinite */
    float xmag, ymag;       /* orthographic */
};

struct rb_scene_light {
    char *name;
    enum rb_light_type type;
    float color[3];
    float intensity;
    float range; /* 0: infinite */
    float inner_cone_rad, outer_cone_rad;
};

enum rb_anim_path { RB_ANIM_TRANSLATION = 1, RB_ANIM_ROTATION, RB_ANIM_SCALE, RB_ANIM_WEIGHTS };
enum rb_anim_interp { RB_ANIM_LINEAR = 0, RB_ANIM_STEP, RB_ANIM_CUBICSPLINE };

struct rb_scene_anim_sampler {
    enum rb_anim_interp interpolation;
    float *times;  /* key_count, increasing */
    float *values; /* key_count * components (x3 for CUBICSPLINE: in-tangent, value,
                    * out-tangent per key, as glTF stores them) */
    uint32_t key_count;
    uint32_t components; /* 3, 4, or the morph target count */
};

struct rb_scene_anim_channel {
    uint32_t sampler; /* within the animation */
    uint32_t node;
    enum rb_anim_path path;
};

struct rb_scene_animation {
    char *name;
    struct rb_scene_anim_sampler *samplers;
    uint32_t sampler_count;
    struct rb_scene_anim_channel *channels;
    uint32_t channel_count;
    float duration_s; /* the largest key time */
};

struct rb_scene {
    char *path;
    uint64_t content_hash; /* of the file's bytes, every buffer and every decoded image: changes
                            * whenever anything the file refers to does (rb_hash_bulk) */
    struct rb_scene_vertex *vertices;
    uint32_t vertex_count;
    uint32_t *indices;
    uint32_t index_count;
    struct rb_scene_morph_delta *morph_deltas;
    uint32_t morph_delta_count;
    struct rb_scene_primitive *primitives;
    uint32_t primitive_count;
    struct rb_scene_mesh *meshes;
    uint32_t mesh_count;
    struct rb_scene_material *materials; /* the last one is the default material */
    uint32_t material_count;
    struct rb_scene_texture *textures;
    uint32_t texture_count;
    struct rb_scene_node *nodes;
    uint32_t node_count;
    struct rb_scene_skin *skins;
    uint32_t skin_count;
    struct rb_scene_camera *cameras;
    uint32_t camera_count;
    struct rb_scene_light *lights;
    uint32_t light_count;
    struct rb_scene_animation *animations;
    uint32_t animation_count;
};

/* Flags for rb_scene_load; 0 is the strict default. */
enum rb_scene_load_flags {
    RB_SCENE_LOAD_LENIENT = 1 << 0, /* JSON type errors, tinygltf's complaints and values glTF
                                     * forbids are warnings */
};

/* Loads a .gltf or .glb. Before tinygltf parses, the JSON (a .glb's JSON chunk) is checked
 * against rb_scene_json_rules: a property of the wrong type, or a required one that is missing,
 * is an error naming its JSON pointer ("scene 'x.gltf': /meshes/0/primitives: expected array,
 * found object"), as is anything tinygltf complains about while loading. flags holds
 * RB_SCENE_LOAD_* bits; with RB_SCENE_LOAD_LENIENT those become warnings through rb_log and the
 * file loads as tinygltf reads it (a property of the wrong type is skipped). Values glTF 2.0
 * forbids or float arithmetic cannot carry (a version other than 2.x, an accessor of 0 elements,
 * a NaN or Inf, a rotation of length 0, negative key times or light intensity, a light range
 * <= 0, an emission or light above RB_MAX_RADIANCE) are errors naming their JSON pointer, and
 * warnings with RB_SCENE_LOAD_LENIENT; normals of length 0 are replaced with a warning.
 * Unsupported features that change the picture (a non-triangle primitive, a required extension
 * we lack) are errors naming the element ("mesh 'Body' primitive 2: ..."); ones that do not are
 * warnings through rb_log. Missing or corrupt files and images are errors. Returns RB_E_IO,
 * RB_E_PARSE or RB_E_UNSUPPORTED on failure; *out only on success. */
enum rb_status rb_scene_load(const char *path, unsigned flags, struct rb_scene **out,
                             struct rb_err *err);
void rb_scene_destroy(struct rb_scene *scene);

/* ---- glTF JSON types ------------------------------------------------------------------------ */

/* What a property must be. tinygltf 2.7 silently skips an optional property of the wrong type,
 * so the loader checks these first. */
enum rb_scene_json_type {
    RB_SCENE_JSON_INVALID = 0,
    RB_SCENE_JSON_OBJECT,
    RB_SCENE_JSON_ARRAY,
    RB_SCENE_JSON_STRING,
    RB_SCENE_JSON_BOOLEAN,
    RB_SCENE_JSON_NUMBER,
    RB_SCENE_JSON_UINT,    /* integer 0 to 2^31 - 1: an index or enum (tinygltf keeps an int) */
    RB_SCENE_JSON_SIZE,    /* integer >= 0: a byte offset, length or element count */
    RB_SCENE_JSON_NUMBERS, /* array of numbers, exactly count of them unless count is 0 */
    RB_SCENE_JSON_UINTS,   /* array of RB_SCENE_JSON_UINT */
    RB_SCENE_JSON_STRINGS, /* array of strings */
};

/* One property: a JSON pointer (RFC 6901) where "*" stands for every element of an array or
 * every member of an object (whichever the rule for the pointer before it says). A rule applies
 * when its parent is there: "/a/b" is checked only where "/a" is an object. */
struct rb_scene_json_rule {
    const char *pointer; /* e.g. "/nodes/N/scale" with a "*" token for N */
    enum rb_scene_json_type type;
    uint32_t count;   /* RB_SCENE_JSON_NUMBERS: the exact length; 0 == any */
    bool is_required; /* missing from a parent that is there: an issue too */
};

/* The properties raybundle reads (everything gltf_shim.cpp takes from tinygltf), parents before
 * their children: the one table the loader checks and the tests walk. */
extern const struct rb_scene_json_rule rb_scene_json_rules[];
extern const size_t rb_scene_json_rule_count;

/* Called for each property that breaks a rule: pointer is concrete ("/nodes/3/scale"), problem
 * reads "expected array of 3 numbers, found string". Return true to go on, false to stop. */
typedef bool (*rb_scene_json_issue_fn)(void *user, const char *pointer, const char *problem);

/* Checks the glTF JSON text (size bytes, no terminator needed) against rules, in table order and
 * then document order, calling on_issue for each issue (NULL: stop at the first). Returns RB_OK
 * when the walk finished, RB_E_PARSE with "<pointer>: <problem>" when on_issue stopped it and
 * with "invalid JSON: <cause>" when the text does not parse. Thread-safe. */
enum rb_status rb_scene_json_check(const char *text, size_t size,
                                   const struct rb_scene_json_rule *rules, size_t rule_count,
                                   rb_scene_json_issue_fn on_issue, void *user, struct rb_err *err);

/* Index of the node, camera node, or animation with that name, or RB_SCENE_NONE. */
uint32_t rb_scene_find_node(const struct rb_scene *scene, const char *name);
uint32_t rb_scene_find_animation(const struct rb_scene *scene, const char *name);

/* ---- evaluation ----------------------------------------------------------------------------- */

/* One drawable: a primitive of a mesh instanced by a node of the default scene. */
struct rb_scene_instance {
    uint32_t node, primitive;
    uint32_t first_joint;  /* into pose->joint_matrices, or RB_SCENE_NONE when not skinned */
    uint32_t first_weight; /* into pose->morph_weights, or RB_SCENE_NONE without morphs */
};

/* The scene at one time. Sized once per scene (rb_scene_pose_create) and refilled per frame. */
struct rb_scene_pose {
    struct rb_mat4 *node_world; /* node_count */
    struct rb_scene_instance *instances;
    uint32_t instance_count;
    struct rb_mat4 *joint_matrices; /* joint world * inverse bind, per skinned instance */
    uint32_t joint_matrix_count;
    float *morph_weights; /* per morphed instance, its primitive's target count */
    uint32_t morph_weight_count;
    struct rb_vec3 bounds_min, bounds_max; /* world bounds of the posed geometry (approximate
                                            * for skinned meshes: joint-transformed boxes) */
};

/* Which clips play and how their time maps from the frame time. */
struct rb_anim_selection {
    const uint32_t *clips; /* animation indices; all play at once */
    uint32_t clip_count;
    double offset_s, speed;
    bool loop;
};

enum rb_status rb_scene_pose_create(const struct rb_scene *scene, struct rb_scene_pose **out,
                                    struct rb_err *err);
void rb_scene_pose_destroy(struct rb_scene_pose *pose);

/* The world-space vertices of every instance of pose, in instance order (as the frame's world
 * vertex buffer lays them out, lib/integrators/frame.c), with the math of shaders/animate.comp:
 * morph deltas, then the skin or the node matrix (deform.c). pos gets pos_stride floats per
 * vertex; nrm (3), tan (4) and uv (2) may be NULL. */
void rb_scene_deform(const struct rb_scene *scene, const struct rb_scene_pose *pose, float *pos,
                     size_t pos_stride, float *nrm, float *tan, float *uv);

/* Evaluates the selected clips at time_s (seconds of the sequence; the selection maps it to clip
 * time) into pose. Deterministic and allocation-free. */
void rb_scene_evaluate(const struct rb_scene *scene, const struct rb_anim_selection *sel,
                       double time_s, struct rb_scene_pose *pose);

/* Samples one sampler at clip time t into out (components floats), for tests. */
void rb_scene_sample(const struct rb_scene_anim_sampler *s, float t, float *out);

/* rb_scene_sample clamps before the first and after the last key, interpolates LINEAR
 * component-wise (no slerp) and CUBICSPLINE as glTF's Hermite spline with tangents scaled by
 * the key interval. This variant is for a channel of the given path: a 4-component
 * RB_ANIM_ROTATION sampler slerps (LINEAR) or is normalized after interpolation (STEP,
 * CUBICSPLINE), as rb_scene_evaluate does. Other paths are plain rb_scene_sample. */
void rb_scene_sample_path(const struct rb_scene_anim_sampler *s, enum rb_anim_path path, float t,
                          float *out);

/* The camera at a time, in world space. */
struct rb_camera {
    struct rb_mat4 world_to_camera;
    struct rb_vec3 position;
    float fov_y_rad;
    float z_near, z_far;
};

/* A light in world space, from the scene (with its node's transform) or from the job. */
struct rb_world_light {
    enum rb_light_type type;
    struct rb_vec3 position;
    struct rb_vec3 direction; /* unit, the direction light travels */
    float color[3];           /* color * intensity */
    float range;
    float inner_cone_rad, outer_cone_rad;
};

/* A side of an axis-aligned box; NONE (0) for none. */
enum rb_scene_side {
    RB_SIDE_NONE = 0,
    RB_SIDE_NEG_X,
    RB_SIDE_POS_X,
    RB_SIDE_NEG_Y,
    RB_SIDE_POS_Y,
    RB_SIDE_NEG_Z,
    RB_SIDE_POS_Z,
};

/* What a job decides once for all its frames (lib/scene/setup.c), so that nothing placed from
 * the scene's extent follows the animated bounds from frame to frame, and a chunk of frames
 * decides exactly as the whole sequence does. */
struct rb_scene_setup {
    struct rb_vec3 bounds_min, bounds_max; /* every pose the selected clips take, over their
                                            * whole clip time: clip planes, shadow boxes, the
                                            * fitted camera and the default light use these */
    uint32_t punctual_count;               /* the scene's (when used) and the job's lights */
    bool has_emitters;                     /* a drawn primitive's emission is > 0 */
    double emitter_irradiance;             /* how strongly they light the scene: an irradiance
                                            * at the bounds' centre (setup.c) */
    bool has_environment;                  /* the environment is not black */
    enum rb_scene_side room_open_side;     /* the bounds enclose a room open on this side */
    struct rb_vec3 fit_direction; /* unit, from the bounds' centre towards a fitted camera */
    bool has_default_light;       /* default_light on, or auto and the frame would be unlit:
                                   * no punctual light, no emitter strong enough to light
                                   * the view, a black environment */
    struct rb_world_light default_light;
    char default_light_note[128]; /* "none", or where the default light is (EXR metadata) */
    uint64_t job_hash; /* job->hash (the settings) with the scene's contents and the environment
                        * map's pixels: equal hashes, equal frames (what --resume checks) */
};

/* Decides the setup of a job: the bounds over the selected clips' whole clip time (sampled at
 * the frame rate, independent of the frame range), the light sources, the default light (logged
 * once when added: at info level, or as a warning when it is added beside emitters too weak
 * to light the view) and the fitted camera's side (through the open side of a
 * room). env_rgba (env_width_px x env_height_px RGBA floats, or NULL) is the loaded
 * environment map, checked for all-black. Fails only on a bad clip name or out of memory. */
enum rb_status rb_scene_setup_init(const struct rb_job *job, const struct rb_scene *scene,
                                   const float *env_rgba, uint32_t env_width_px,
                                   uint32_t env_height_px, struct rb_scene_setup *out,
                                   struct rb_err *err);

/* Evaluates the job's camera: a glTF camera node (from pose), keyframes (linear or Catmull-Rom,
 * clamped at the ends), the scene's first camera, or, with none of these, a view fitted to the
 * setup's bounds from its fit_direction. Clip planes not given by the job or the file come from
 * the setup's bounds. Fails only for a camera node name that does not exist or has no camera
 * (RB_E_INVALID). */
enum rb_status rb_camera_evaluate(const struct rb_job *job, const struct rb_scene *scene,
                                  const struct rb_scene_setup *setup,
                                  const struct rb_scene_pose *pose, double time_s,
                                  struct rb_camera *out, struct rb_err *err);

/* Writes up to cap lights (scene lights when job->use_scene_lights, then job lights, then the
 * setup's default light when it has one) and returns how many there are in all, so a caller
 * can detect and report a list that did not fit. */
uint32_t rb_scene_world_lights(const struct rb_job *job, const struct rb_scene *scene,
                               const struct rb_scene_setup *setup, const struct rb_scene_pose *pose,
                               struct rb_world_light *out, uint32_t cap);

/* The most point samples that may stand for the emissive surfaces where they light as lights do
 * (the direct integrator, and the reference's direct path space; the job's
 * integrator.direct.emitter_lights, 8 by default): each a cube of shadow maps, which the shadow
 * layers' budget (RB_MAX_SHADOW_LAYERS) bounds. */
#define RB_SCENE_EMITTER_LIGHTS_MAX 8

/* The emissive surfaces as count (at most RB_SCENE_EMITTER_LIGHTS_MAX) lights of type
 * RB_LIGHT_EMITTER, or none when
 * no drawn primitive has an emissive material: fixed, stratified points picked by power (each
 * triangle's area times the luminance of its emission, factor x strength x the average of its
 * emissive texture), from the pose's node transforms (skinned and morphed emitters at their bind
 * shape). Each sends color x |cos| (its own area's share of the emitted power, both sides, cos
 * against direction, the triangle's normal) with the inverse-square falloff. Writes up to cap;
 * returns the count, the same for every pose of a scene. */
uint32_t rb_scene_emitter_lights(const struct rb_scene *scene, const struct rb_scene_pose *pose,
                                 uint32_t count, struct rb_world_light *out, uint32_t cap);

/* Resolves the job's clip names to indices (all names must exist; none given: the first
 * animation, if any). Writes at most cap indices. */
enum rb_status rb_scene_select_clips(const struct rb_scene *scene, const struct rb_job *job,
                                     uint32_t *out, uint32_t cap, uint32_t *count,
                                     struct rb_err *err);

/* ---- simplify.c: a coarser mesh for views that can do with less ---------------------------- */

/* The fewest triangles a mesh keeps under any budget (all of them when it has fewer): a closed
 * box's worth, so that a small object stays a solid in the views that draw the simplified mesh
 * rather than vanishing from them. */
#define RB_SCENE_SIMPLIFY_MIN_TRIANGLES 12

/* Splits budget_triangles over count meshes of triangles[i] triangles in proportion to their
 * size: targets[i] = floor(budget * triangles[i] / total), in 64-bit integers (total is the sum
 * of triangles), raised to min(triangles[i], RB_SCENE_SIMPLIFY_MIN_TRIANGLES). A budget of 0 or
 * of at least the total keeps every mesh whole (targets[i] = triangles[i]). Equal meshes get
 * equal targets. Returns the sum of the targets: at most the budget plus what the minimum added. */
uint64_t rb_scene_simplify_targets(const uint32_t *triangles, uint32_t count,
                                   uint64_t budget_triangles, uint32_t *targets);

/* A triangle mesh to simplify: only positions count, so vertices that share a position are one
 * (UV and normal seams do not hold the simplifier back). */
struct rb_scene_simplify_mesh {
    const float *positions; /* x, y, z of vertex 0; vertex i's stride_bytes * i further on */
    const float *normals;   /* NULL, or x, y, z at the same stride: each corner of a simplified
                             * triangle then takes, of the vertices at its position, the one whose
                             * normal is closest to the triangle's (hard edges keep their normals) */
    size_t stride_bytes;    /* at least 12 and a multiple of 4 */
    uint32_t vertex_count;
    const uint32_t *indices; /* a triangle list into the vertices */
    uint32_t index_count;
};

/* What rb_scene_simplify made. */
struct rb_scene_simplified {
    uint32_t index_count; /* written to out; a multiple of 3 */
    float error;          /* meshoptimizer's error: the geometric deviation relative to the
                           * mesh's extent (0: the shape is kept exactly) */
    bool is_sloppy;       /* meshopt_simplifySloppy's result (see rb_scene_simplify) */
};

/* Simplifies mesh to at most target_triangles triangles into out (the caller's, room for
 * mesh->index_count indices), indexing the same vertices, deterministically (the same input
 * gives the same indices). A target of at least the mesh's triangle count copies the indices.
 * Otherwise meshopt_simplify collapses edges of the mesh welded by position (one vertex per
 * distinct position) with no bound on the error; when topology stops it above the target
 * (non-manifold edges), the grid-based meshopt_simplifySloppy runs on the same welded mesh,
 * and its result is taken when it is not empty and smaller; otherwise the edge collapses'
 * result stands, over the target. A mesh that both would leave empty is kept whole. Edge
 * collapses may still remove a small closed part of a mesh (a tetrahedron collapses to
 * nothing); the error then says how far. Fails with RB_E_INVALID for an index out of range or
 * a count not a multiple of 3 and RB_E_NOMEM; meshoptimizer itself aborts the process if it
 * runs out of memory. Thread-safe. */
enum rb_status rb_scene_simplify(const struct rb_scene_simplify_mesh *mesh,
                                 uint32_t target_triangles, uint32_t *out,
                                 struct rb_scene_simplified *result, struct rb_err *err);

#endif
