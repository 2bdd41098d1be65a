/* The tinygltf shim: checks the JSON types of a .gltf/.glb against a table, parses it (buffers
 * and images included) and exposes the document as plain C arrays that mirror the glTF JSON. No
 * defaults beyond tinygltf's and no validation of values: indices are passed through as read
 * (-1 == absent) and scene.c checks every one of them. */
#ifndef RB_SCENE_GLTF_SHIM_H
#define RB_SCENE_GLTF_SHIM_H

#ifndef __cplusplus
#include "scene/scene.h" /* gltf_shim.cpp includes it itself, inside extern "C" */
#endif

#ifdef __cplusplus
#define RB_GLTF_NOEXCEPT noexcept
extern "C" {
#else
#define RB_GLTF_NOEXCEPT
#endif

/* A name/accessor pair of a primitive's attributes or of a morph target. */
struct rb_gltf_attribute {
    const char *name;
    int32_t accessor;
};

struct rb_gltf_accessor {
    const char *name;
    int32_t buffer_view; /* -1: all zeros (possibly with sparse values on top) */
    size_t byte_offset;
    int32_t component_type; /* GL enum, 5120..5126 */
    bool normalized;
    size_t count;
    int32_t type; /* tinygltf's TINYGLTF_TYPE_* (SCALAR 65, VECn n, MATn 32 + n) */
    bool is_sparse;
    int32_t sparse_count;
    int32_t sparse_indices_view, sparse_indices_offset, sparse_indices_component_type;
    int32_t sparse_values_view, sparse_values_offset;
};

struct rb_gltf_buffer_view {
    int32_t buffer;
    size_t byte_offset, byte_length;
    size_t byte_stride; /* 0: tightly packed */
};

struct rb_gltf_buffer {
    const uint8_t *data;
    size_t size;
};

struct rb_gltf_image {
    const char *name, *uri; /* "" when absent; uri is "" for buffer-view and data: images */
    int32_t width, height, components, bits; /* as decoded; -1 when not decoded */
    const uint8_t *pixels;                   /* NULL when the image could not be loaded */
    size_t size;
};

struct rb_gltf_texture {
    const char *name;
    int32_t source; /* image index, -1 when absent (e.g. only an extension provides one) */
};

struct rb_gltf_texture_ref {
    int32_t index; /* texture, -1 when absent */
    int32_t tex_coord;
    bool has_transform; /* KHR_texture_transform present */
};

struct rb_gltf_material {
    const char *name;
    const double *base_color; /* base_color_count values */
    size_t base_color_count;
    struct rb_gltf_texture_ref base_color_tex;
    double metallic, roughness;
    struct rb_gltf_texture_ref metallic_roughness_tex;
    struct rb_gltf_texture_ref normal_tex;
    double normal_scale;
    const double *emissive; /* emissive_count values */
    size_t emissive_count;
    struct rb_gltf_texture_ref emissive_tex;
    bool has_emissive_strength; /* KHR_materials_emissive_strength */
    double emissive_strength;
    bool has_specular; /* KHR_materials_specular */
    double specular_factor;
    double specular_color[3];
    bool has_specular_textures; /* its textures, which are not supported */
    const char *alpha_mode;
    double alpha_cutoff;
    bool double_sided;
};

struct rb_gltf_target {
    const struct rb_gltf_attribute *attributes;
    size_t attribute_count;
};

struct rb_gltf_primitive {
    int32_t mode; /* TINYGLTF_MODE_*, -1 when absent */
    int32_t indices, material;
    const struct rb_gltf_attribute *attributes;
    size_t attribute_count;
    const struct rb_gltf_target *targets;
    size_t target_count;
};

struct rb_gltf_mesh {
    const char *name;
    const struct rb_gltf_primitive *primitives;
    size_t primitive_count;
    const double *weights;
    size_t weight_count;
};

struct rb_gltf_node {
    const char *name;
    const int32_t *children;
    size_t child_count;
    const double *translation, *rotation, *scale, *matrix;
    size_t translation_count, rotation_count, scale_count, matrix_count;
    const double *weights;
    size_t weight_count;
    int32_t mesh, skin, camera;
    int32_t light; /* KHR_lights_punctual, -1 when absent */
};

struct rb_gltf_skin {
    const char *name;
    int32_t inverse_bind_matrices; /* accessor, -1 when absent */
    const int32_t *joints;
    size_t joint_count;
};

struct rb_gltf_camera {
    const char *name, *type;          /* "perspective" or "orthographic" */
    double aspect, yfov, znear, zfar; /* perspective */
    double xmag, ymag, ortho_znear, ortho_zfar;
};

struct rb_gltf_light {
    const char *name, *type;
    const double *color;
    size_t color_count;
    double intensity, range, inner_cone, outer_cone;
    bool has_range; /* range present in the JSON (tinygltf reads an absent one as 0) */
};

struct rb_gltf_anim_sampler {
    int32_t input, output;
    const char *interpolation;
};

struct rb_gltf_anim_channel {
    int32_t sampler, node;
    const char *path;
};

struct rb_gltf_animation {
    const char *name;
    const struct rb_gltf_anim_sampler *samplers;
    size_t sampler_count;
    const struct rb_gltf_anim_channel *channels;
    size_t channel_count;
};

struct rb_gltf_scene {
    const char *name;
    const int32_t *nodes;
    size_t node_count;
};

/* The document. Every pointer stays valid until rb_gltf_shim_free. */
struct rb_gltf_doc {
    const char *errors;   /* what tinygltf found wrong in a file it still loaded (a primitive it
                           * dropped, a misaligned chunk), one per line; "" when none */
    const char *warnings; /* tinygltf's warnings (an image it could not load), one per line */
    const char *version, *min_version; /* asset.version and asset.minVersion; "" when absent */
    uint32_t glb_version;              /* a .glb's container version; 0 for a .gltf */
    const struct rb_gltf_accessor *accessors;
    size_t accessor_count;
    const struct rb_gltf_buffer_view *buffer_views;
    size_t buffer_view_count;
    const struct rb_gltf_buffer *buffers;
    size_t buffer_count;
    const struct rb_gltf_image *images;
    size_t image_count;
    const struct rb_gltf_texture *textures;
    size_t texture_count;
    const struct rb_gltf_material *materials;
    size_t material_count;
    const struct rb_gltf_mesh *meshes;
    size_t mesh_count;
    const struct rb_gltf_node *nodes;
    size_t node_count;
    const struct rb_gltf_skin *skins;
    size_t skin_count;
    const struct rb_gltf_camera *cameras;
    size_t camera_count;
    const struct rb_gltf_light *lights;
    size_t light_count;
    const struct rb_gltf_animation *animations;
    size_t animation_count;
    const struct rb_gltf_scene *scenes;
    size_t scene_count;
    int32_t default_scene; /* -1 when absent */
    const char *const *extensions_required;
    size_t extensions_required_count;
    const char *const *extensions_used;
    size_t extensions_used_count;
    void *impl; /* the shim's own object */
};

/* The deepest nesting of arrays and objects a glTF's JSON may have: glTF itself needs about 8,
 * and extras deep enough to matter only serve to overflow the JSON parsers' recursion. Checked
 * on the text before any parser sees it. */
#define RB_SCENE_JSON_MAX_DEPTH 512

/* The JSON type check rb_gltf_shim_load runs before tinygltf parses: see rb_scene_json_check. */
struct rb_gltf_check {
    const struct rb_scene_json_rule *rules;
    size_t rule_count;
    rb_scene_json_issue_fn on_issue; /* NULL: the first issue fails the load */
    void *user;
};

/* rb_scene_json_check: the JSON text checked against check's rules, on_issue called per issue. */
enum rb_status rb_gltf_shim_check(const char *text, size_t size, const struct rb_gltf_check *check,
                                  struct rb_err *err) RB_GLTF_NOEXCEPT;

/* Parses path: a binary glTF when the file starts with "glTF" (or is named *.glb), else JSON.
 * With check (may be NULL), the JSON (a .glb's JSON chunk) is checked first; when on_issue stops
 * the check, returns RB_E_PARSE with "<pointer>: <problem>" before tinygltf sees the file. JSON
 * that does not parse is left to tinygltf. Images are decoded to 8 or 16 bits per channel, RGBA
 * (tinygltf's default). On failure returns RB_E_IO with "cannot open 'path': ...", RB_E_PARSE
 * with "cannot load 'path': <tinygltf's error>" (RB_E_NOMEM, RB_E_EXTERNAL for exceptions);
 * *out only on success, freed with rb_gltf_shim_free. */
enum rb_status rb_gltf_shim_load(const char *path, const struct rb_gltf_check *check,
                                 struct rb_gltf_doc **out, struct rb_err *err) RB_GLTF_NOEXCEPT;
/* Frees everything rb_gltf_shim_load made; accepts NULL. */
void rb_gltf_shim_free(struct rb_gltf_doc *doc) RB_GLTF_NOEXCEPT;

#ifdef __cplusplus
}
#endif

#endif
