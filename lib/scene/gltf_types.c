/* The JSON type of every glTF property raybundle reads, one row each: the table the loader checks
 * a file against before tinygltf parses it (gltf_shim.cpp walks it), and the tests walk too.
 * tinygltf 2.7 skips an optional property of the wrong type without a word, which turns a typo
 * into a silently different picture. Not a schema validator: properties nobody reads are not
 * here, and values are checked by scene.c once they are converted. */
#include "scene/gltf_shim.h"

/* A property, a required one, an array of n numbers (0: any number of them). */
#define R(p, t)                                                                                    \
    {                                                                                              \
        .pointer = (p), .type = RB_SCENE_JSON_##t                                                  \
    }
#define REQ(p, t)                                                                                  \
    {                                                                                              \
        .pointer = (p), .type = RB_SCENE_JSON_##t, .is_required = true                             \
    }
#define NUMS(p, n)                                                                                 \
    {                                                                                              \
        .pointer = (p), .type = RB_SCENE_JSON_NUMBERS, .count = (n)                                \
    }
/* glTF's textureInfo (and normalTextureInfo without its scale). */
#define TEXTURE_INFO(p)                                                                            \
    R(p, OBJECT), REQ(p "/index", UINT), R(p "/texCoord", UINT), R(p "/extensions", OBJECT),       \
        R(p "/extensions/KHR_texture_transform", OBJECT)

const struct rb_scene_json_rule rb_scene_json_rules[] = {
    REQ("/asset", OBJECT),
    REQ("/asset/version", STRING),
    R("/extensionsUsed", STRINGS),
    R("/extensionsRequired", STRINGS),
    R("/scene", UINT),
    R("/scenes", ARRAY),
    R("/scenes/*", OBJECT),
    R("/scenes/*/name", STRING),
    R("/scenes/*/nodes", UINTS),

    R("/nodes", ARRAY),
    R("/nodes/*", OBJECT),
    R("/nodes/*/name", STRING),
    R("/nodes/*/children", UINTS),
    R("/nodes/*/mesh", UINT),
    R("/nodes/*/skin", UINT),
    R("/nodes/*/camera", UINT),
    NUMS("/nodes/*/matrix", 16),
    NUMS("/nodes/*/translation", 3),
    NUMS("/nodes/*/rotation", 4),
    NUMS("/nodes/*/scale", 3),
    NUMS("/nodes/*/weights", 0),
    R("/nodes/*/extensions", OBJECT),
    R("/nodes/*/extensions/KHR_lights_punctual", OBJECT),
    REQ("/nodes/*/extensions/KHR_lights_punctual/light", UINT),

    R("/meshes", ARRAY),
    R("/meshes/*", OBJECT),
    R("/meshes/*/name", STRING),
    REQ("/meshes/*/primitives", ARRAY),
    R("/meshes/*/primitives/*", OBJECT),
    REQ("/meshes/*/primitives/*/attributes", OBJECT),
    R("/meshes/*/primitives/*/attributes/*", UINT),
    R("/meshes/*/primitives/*/indices", UINT),
    R("/meshes/*/primitives/*/material", UINT),
    R("/meshes/*/primitives/*/mode", UINT),
    R("/meshes/*/primitives/*/targets", ARRAY),
    R("/meshes/*/primitives/*/targets/*", OBJECT),
    R("/meshes/*/primitives/*/targets/*/*", UINT),
    NUMS("/meshes/*/weights", 0),

    R("/accessors", ARRAY),
    R("/accessors/*", OBJECT),
    R("/accessors/*/name", STRING),
    R("/accessors/*/bufferView", UINT),
    R("/accessors/*/byteOffset", SIZE),
    REQ("/accessors/*/componentType", UINT),
    R("/accessors/*/normalized", BOOLEAN),
    REQ("/accessors/*/count", SIZE),
    REQ("/accessors/*/type", STRING),
    R("/accessors/*/sparse", OBJECT),
    REQ("/accessors/*/sparse/count", UINT),
    REQ("/accessors/*/sparse/indices", OBJECT),
    REQ("/accessors/*/sparse/indices/bufferView", UINT),
    R("/accessors/*/sparse/indices/byteOffset", UINT),
    REQ("/accessors/*/sparse/indices/componentType", UINT),
    REQ("/accessors/*/sparse/values", OBJECT),
    REQ("/accessors/*/sparse/values/bufferView", UINT),
    R("/accessors/*/sparse/values/byteOffset", UINT),

    R("/bufferViews", ARRAY),
    R("/bufferViews/*", OBJECT),
    REQ("/bufferViews/*/buffer", UINT),
    R("/bufferViews/*/byteOffset", SIZE),
    REQ("/bufferViews/*/byteLength", SIZE),
    R("/bufferViews/*/byteStride", SIZE),
    R("/buffers", ARRAY),
    R("/buffers/*", OBJECT),
    R("/buffers/*/uri", STRING),
    REQ("/buffers/*/byteLength", SIZE),

    R("/materials", ARRAY),
    R("/materials/*", OBJECT),
    R("/materials/*/name", STRING),
    R("/materials/*/pbrMetallicRoughness", OBJECT),
    NUMS("/materials/*/pbrMetallicRoughness/baseColorFactor", 4),
    TEXTURE_INFO("/materials/*/pbrMetallicRoughness/baseColorTexture"),
    R("/materials/*/pbrMetallicRoughness/metallicFactor", NUMBER),
    R("/materials/*/pbrMetallicRoughness/roughnessFactor", NUMBER),
    TEXTURE_INFO("/materials/*/pbrMetallicRoughness/metallicRoughnessTexture"),
    TEXTURE_INFO("/materials/*/normalTexture"),
    R("/materials/*/normalTexture/scale", NUMBER),
    TEXTURE_INFO("/materials/*/emissiveTexture"),
    NUMS("/materials/*/emissiveFactor", 3),
    R("/materials/*/alphaMode", STRING),
    R("/materials/*/alphaCutoff", NUMBER),
    R("/materials/*/doubleSided", BOOLEAN),
    R("/materials/*/extensions", OBJECT),
    R("/materials/*/extensions/KHR_materials_emissive_strength", OBJECT),
    R("/materials/*/extensions/KHR_materials_emissive_strength/emissiveStrength", NUMBER),
    R("/materials/*/extensions/KHR_materials_specular", OBJECT),
    R("/materials/*/extensions/KHR_materials_specular/specularFactor", NUMBER),
    NUMS("/materials/*/extensions/KHR_materials_specular/specularColorFactor", 3),
    R("/materials/*/extensions/KHR_materials_specular/specularTexture", OBJECT),
    R("/materials/*/extensions/KHR_materials_specular/specularColorTexture", OBJECT),

    R("/textures", ARRAY),
    R("/textures/*", OBJECT),
    R("/textures/*/name", STRING),
    R("/textures/*/source", UINT),
    R("/textures/*/sampler", UINT),
    R("/images", ARRAY),
    R("/images/*", OBJECT),
    R("/images/*/name", STRING),
    R("/images/*/uri", STRING),
    R("/images/*/mimeType", STRING),
    R("/images/*/bufferView", UINT),
    R("/samplers", ARRAY),
    R("/samplers/*", OBJECT),
    R("/samplers/*/magFilter", UINT),
    R("/samplers/*/minFilter", UINT),
    R("/samplers/*/wrapS", UINT),
    R("/samplers/*/wrapT", UINT),

    R("/skins", ARRAY),
    R("/skins/*", OBJECT),
    R("/skins/*/name", STRING),
    R("/skins/*/inverseBindMatrices", UINT),
    R("/skins/*/skeleton", UINT),
    REQ("/skins/*/joints", UINTS),

    R("/cameras", ARRAY),
    R("/cameras/*", OBJECT),
    R("/cameras/*/name", STRING),
    REQ("/cameras/*/type", STRING),
    R("/cameras/*/perspective", OBJECT),
    R("/cameras/*/perspective/aspectRatio", NUMBER),
    REQ("/cameras/*/perspective/yfov", NUMBER),
    R("/cameras/*/perspective/zfar", NUMBER),
    REQ("/cameras/*/perspective/znear", NUMBER),
    R("/cameras/*/orthographic", OBJECT),
    REQ("/cameras/*/orthographic/xmag", NUMBER),
    REQ("/cameras/*/orthographic/ymag", NUMBER),
    REQ("/cameras/*/orthographic/zfar", NUMBER),
    REQ("/cameras/*/orthographic/znear", NUMBER),

    R("/animations", ARRAY),
    R("/animations/*", OBJECT),
    R("/animations/*/name", STRING),
    REQ("/animations/*/channels", ARRAY),
    R("/animations/*/channels/*", OBJECT),
    REQ("/animations/*/channels/*/sampler", UINT),
    REQ("/animations/*/channels/*/target", OBJECT),
    R("/animations/*/channels/*/target/node", UINT),
    REQ("/animations/*/channels/*/target/path", STRING),
    REQ("/animations/*/samplers", ARRAY),
    R("/animations/*/samplers/*", OBJECT),
    REQ("/animations/*/samplers/*/input", UINT),
    R("/animations/*/samplers/*/interpolation", STRING),
    REQ("/animations/*/samplers/*/output", UINT),

    R("/extensions", OBJECT),
    R("/extensions/KHR_lights_punctual", OBJECT),
    R("/extensions/KHR_lights_punctual/lights", ARRAY),
    R("/extensions/KHR_lights_punctual/lights/*", OBJECT),
    R("/extensions/KHR_lights_punctual/lights/*/name", STRING),
    REQ("/extensions/KHR_lights_punctual/lights/*/type", STRING),
    NUMS("/extensions/KHR_lights_punctual/lights/*/color", 3),
    R("/extensions/KHR_lights_punctual/lights/*/intensity", NUMBER),
    R("/extensions/KHR_lights_punctual/lights/*/range", NUMBER),
    R("/extensions/KHR_lights_punctual/lights/*/spot", OBJECT),
    R("/extensions/KHR_lights_punctual/lights/*/spot/innerConeAngle", NUMBER),
    R("/extensions/KHR_lights_punctual/lights/*/spot/outerConeAngle", NUMBER),
};

const size_t rb_scene_json_rule_count =
    sizeof(rb_scene_json_rules) / sizeof(rb_scene_json_rules[0]);

enum rb_status rb_scene_json_check(const char *text, size_t size,
                                   const struct rb_scene_json_rule *rules, size_t rule_count,
                                   rb_scene_json_issue_fn on_issue, void *user, struct rb_err *err)
{
    return rb_gltf_shim_check(text, size,
                              &(struct rb_gltf_check){rules, rule_count, on_issue, user}, err);
}
