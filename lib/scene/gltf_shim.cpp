// The only file that includes tiny_gltf.h (Debian's libtinygltf holds the implementation, so
// TINYGLTF_IMPLEMENTATION is not defined here) and nlohmann/json.hpp, its JSON parser. It checks
// the JSON against a table of property types (gltf_types.c's, or any), parses the file, and
// mirrors the tinygltf::Model into the plain structs of gltf_shim.h; scene.c validates and
// converts them. No policy here: the caller's callback decides what a type issue means.

#include "core/core.h"

extern "C" {
#include "scene/scene.h"
}

#include "scene/gltf_shim.h"

#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include <cctype>
#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstring>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include <sys/stat.h>
#include <unistd.h>

namespace
{

using nlohmann::json;

// ---- the JSON type check ----------------------------------------------------------------------

// tinygltf stores indices and enums in an int.
constexpr uint64_t UINT_LIMIT = INT32_MAX;

std::string expected(const rb_scene_json_rule &r)
{
    switch (r.type) {
    case RB_SCENE_JSON_OBJECT: return "object";
    case RB_SCENE_JSON_ARRAY: return "array";
    case RB_SCENE_JSON_STRING: return "string";
    case RB_SCENE_JSON_BOOLEAN: return "boolean";
    case RB_SCENE_JSON_NUMBER: return "number";
    case RB_SCENE_JSON_UINT:
    case RB_SCENE_JSON_SIZE: return "non-negative integer";
    case RB_SCENE_JSON_NUMBERS:
        return r.count ? "array of " + std::to_string(r.count) + " numbers" : "array of numbers";
    case RB_SCENE_JSON_UINTS: return "array of non-negative integers";
    case RB_SCENE_JSON_STRINGS: return "array of strings";
    case RB_SCENE_JSON_INVALID: break;
    }
    return "a valid rule type";
}

// What a value is, for "found ...": its type, or for a number its value.
std::string describe(const json &v)
{
    switch (v.type()) {
    case json::value_t::null: return "null";
    case json::value_t::object: return "object";
    case json::value_t::array: return "array";
    case json::value_t::string: return "string";
    case json::value_t::boolean: return "boolean";
    case json::value_t::number_integer: return std::to_string(v.get<int64_t>());
    case json::value_t::number_unsigned: return std::to_string(v.get<uint64_t>());
    case json::value_t::number_float: {
        char buf[40];
        std::snprintf(buf, sizeof(buf), "%g", v.get<double>());
        std::string s = buf;
        if (s.find_first_of(".eEin") == std::string::npos)
            s += ".0"; // 1.0 is not the integer 1
        return s;
    }
    case json::value_t::binary:
    case json::value_t::discarded: break;
    }
    return "no JSON value";
}

bool is_uint(const json &v, uint64_t limit)
{
    if (v.is_number_unsigned())
        return v.get<uint64_t>() <= limit;
    return v.is_number_integer() && v.get<int64_t>() >= 0 &&
           static_cast<uint64_t>(v.get<int64_t>()) <= limit;
}

// A pointer token as RFC 6901 writes it; control characters become '?' so a message stays one
// printable line.
std::string escape(const std::string &token)
{
    std::string out;
    for (char ch : token) {
        if (ch == '~')
            out += "~0";
        else if (ch == '/')
            out += "~1";
        else if (static_cast<unsigned char>(ch) < 0x20 || ch == 0x7f)
            out += '?';
        else
            out += ch;
    }
    return out;
}

struct Walk {
    const rb_scene_json_rule *rules;
    size_t rule_count;
    rb_scene_json_issue_fn on_issue;
    void *user;
    std::string stop; // "<pointer>: <problem>" of the issue that stopped the walk
};

// One issue; false when the walk stops there.
bool issue(Walk &w, const std::string &pointer, const std::string &problem)
{
    if (w.on_issue && w.on_issue(w.user, pointer.c_str(), problem.c_str()))
        return true;
    w.stop = pointer + ": " + problem;
    return false;
}

bool check_scalar(Walk &w, const std::string &pointer, const json &v, rb_scene_json_type type,
                  const std::string &want)
{
    bool ok = false;
    switch (type) {
    case RB_SCENE_JSON_OBJECT: ok = v.is_object(); break;
    case RB_SCENE_JSON_ARRAY: ok = v.is_array(); break;
    case RB_SCENE_JSON_STRING: ok = v.is_string(); break;
    case RB_SCENE_JSON_BOOLEAN: ok = v.is_boolean(); break;
    case RB_SCENE_JSON_NUMBER: ok = v.is_number(); break;
    case RB_SCENE_JSON_UINT:
    case RB_SCENE_JSON_SIZE: {
        uint64_t limit = type == RB_SCENE_JSON_UINT ? UINT_LIMIT : UINT64_MAX;
        if (is_uint(v, UINT64_MAX) && !is_uint(v, limit))
            return issue(w, pointer,
                         "expected " + want + ", found " + describe(v) + " (more than " +
                             std::to_string(limit) + ")");
        ok = is_uint(v, limit);
        break;
    }
    default: break;
    }
    return ok || issue(w, pointer, "expected " + want + ", found " + describe(v));
}

bool check_value(Walk &w, const rb_scene_json_rule &r, const std::string &pointer, const json &v)
{
    rb_scene_json_type elem = RB_SCENE_JSON_INVALID;
    switch (r.type) {
    case RB_SCENE_JSON_NUMBERS: elem = RB_SCENE_JSON_NUMBER; break;
    case RB_SCENE_JSON_UINTS: elem = RB_SCENE_JSON_UINT; break;
    case RB_SCENE_JSON_STRINGS: elem = RB_SCENE_JSON_STRING; break;
    case RB_SCENE_JSON_INVALID: return issue(w, pointer, "the rule has no type");
    default: return check_scalar(w, pointer, v, r.type, expected(r));
    }
    if (!v.is_array())
        return issue(w, pointer, "expected " + expected(r) + ", found " + describe(v));
    if (r.type == RB_SCENE_JSON_NUMBERS && r.count && v.size() != r.count)
        return issue(w, pointer,
                     "expected " + expected(r) + ", found array of " + std::to_string(v.size()));
    rb_scene_json_rule er{};
    er.type = elem;
    for (size_t i = 0; i < v.size(); i++)
        if (!check_scalar(w, pointer + "/" + std::to_string(i), v[i], elem, expected(er)))
            return false;
    return true;
}

// One rule, split into tokens; wild[k] says what a "*" token walks: 'a' the elements of an
// array, 'o' the members of an object (from the rule for the pointer before it), 0 a name.
struct Path {
    const rb_scene_json_rule *rule;
    std::vector<std::string> tokens;
    std::vector<char> wild;
};

Path split(const Walk &w, const rb_scene_json_rule &r)
{
    Path p{&r, {}, {}};
    std::string ptr = r.pointer ? r.pointer : "";
    size_t pos = 0;
    while (pos < ptr.size() && ptr[pos] == '/') {
        size_t end = ptr.find('/', pos + 1);
        if (end == std::string::npos)
            end = ptr.size();
        std::string raw = ptr.substr(pos + 1, end - pos - 1), tok;
        for (size_t i = 0; i < raw.size(); i++) {
            if (raw[i] == '~' && i + 1 < raw.size() && (raw[i + 1] == '0' || raw[i + 1] == '1'))
                tok += raw[++i] == '0' ? '~' : '/';
            else
                tok += raw[i];
        }
        char kind = 0;
        if (raw == "*") {
            kind = 'a';
            std::string prefix = ptr.substr(0, pos);
            for (size_t i = 0; i < w.rule_count; i++)
                if (w.rules[i].pointer && prefix == w.rules[i].pointer &&
                    w.rules[i].type == RB_SCENE_JSON_OBJECT)
                    kind = 'o';
        }
        p.tokens.push_back(tok);
        p.wild.push_back(kind);
        pos = end;
    }
    return p;
}

bool walk(Walk &w, const Path &p, size_t k, const json &v, std::string &pointer)
{
    if (k == p.tokens.size())
        return check_value(w, *p.rule, pointer, v);
    size_t len = pointer.size();
    bool go = true;
    if (p.wild[k] == 'a' && v.is_array()) {
        for (size_t i = 0; go && i < v.size(); i++) {
            pointer += "/" + std::to_string(i);
            go = walk(w, p, k + 1, v[i], pointer);
            pointer.resize(len);
        }
    } else if (p.wild[k] == 'o' && v.is_object()) {
        for (auto it = v.begin(); go && it != v.end(); ++it) {
            pointer += "/" + escape(it.key());
            go = walk(w, p, k + 1, it.value(), pointer);
            pointer.resize(len);
        }
    } else if (!p.wild[k] && v.is_object()) {
        // A parent of another type is its own rule's issue: nothing to look into here.
        auto it = v.find(p.tokens[k]);
        pointer += "/" + escape(p.tokens[k]);
        if (it != v.end())
            go = walk(w, p, k + 1, *it, pointer);
        else if (k + 1 == p.tokens.size() && p.rule->is_required)
            go = issue(w, pointer, "expected " + expected(*p.rule) + ", found nothing");
        pointer.resize(len);
    }
    return go;
}

// Walks every rule over doc, an object; false when on_issue stopped it (w.stop says where).
bool check_doc(Walk &w, const json &doc)
{
    for (size_t i = 0; i < w.rule_count; i++) {
        Path p = split(w, w.rules[i]);
        std::string pointer;
        if (!walk(w, p, 0, doc, pointer))
            return false;
    }
    return true;
}

uint32_t le32(const unsigned char *p)
{
    return static_cast<uint32_t>(p[0]) | static_cast<uint32_t>(p[1]) << 8 |
           static_cast<uint32_t>(p[2]) << 16 | static_cast<uint32_t>(p[3]) << 24;
}

// The JSON text of a file: all of a .gltf, the first chunk of a .glb (glTF 4.4). False when a
// .glb's header is too broken to find it; tinygltf then says why.
bool json_span(const std::vector<unsigned char> &data, bool binary, const char **text, size_t *size)
{
    if (!binary) {
        *text = reinterpret_cast<const char *>(data.data());
        *size = data.size();
        return true;
    }
    if (data.size() < 20 || std::memcmp(data.data(), "glTF", 4) != 0 ||
        le32(&data[16]) != 0x4E4F534Au /* "JSON" */ || le32(&data[12]) > data.size() - 20)
        return false;
    *text = reinterpret_cast<const char *>(&data[20]);
    *size = le32(&data[12]);
    return true;
}

// What is wrong with a GLB's header, said of its field, where tinygltf would say only "Invalid
// glTF binary." (or "Invalid magic."): the 12-byte header (magic, version, length) and the JSON
// chunk's 8-byte header (length, type). "" when tinygltf accepts them; the version is scene.c's.
std::string glb_header_problem(const std::vector<unsigned char> &d)
{
    uint64_t size = d.size();
    if (size < 20)
        return "a GLB starts with a 12-byte header and the JSON chunk's 8-byte header, and the "
               "file has " +
               std::to_string(size) + " bytes";
    if (std::memcmp(d.data(), "glTF", 4) != 0)
        return "the file does not start with the GLB magic 'glTF'";
    uint64_t length = le32(&d[8]), json_length = le32(&d[12]), type = le32(&d[16]);
    if (length > size)
        return "the header's length (bytes 8 to 11) is " + std::to_string(length) +
               " bytes, and the file has " + std::to_string(size);
    if (json_length < 1)
        return "the JSON chunk's length (bytes 12 to 15) is 0";
    if (20 + json_length > length)
        return "the JSON chunk's length (bytes 12 to 15) is " + std::to_string(json_length) +
               " bytes, past the end of the GLB (" + std::to_string(length) +
               " bytes, the header's length)";
    if (type != 0x4E4F534Au) {
        char hex[16];
        std::snprintf(hex, sizeof(hex), "0x%08X", static_cast<unsigned>(type));
        return std::string("the first chunk's type (bytes 16 to 19) is ") + hex +
               ", not JSON (0x4E4F534A)";
    }
    return std::string();
}

// ---- tinygltf's complaints ----------------------------------------------------------------

// Lines of tinygltf 2.7's error text about files that glTF 2.0 allows: a skin without
// inverseBindMatrices (5.28.1: identity matrices) is not worth a word, and a channel whose target
// node is left to an extension (5.7.1) is dropped, which we would do anyway: a warning.
const char *const quiet_errors[] = {"'inverseBindMatrices' property is missing in Skin."};
const char *const warning_errors[] = {"'node' property is missing.",
                                      "`node` field is missing in animation.channels.target"};

struct Doc {
    rb_gltf_doc pub{}; // pub.impl points back here
    tinygltf::Model model;
    std::string errors, warnings;
    std::vector<rb_gltf_accessor> accessors;
    std::vector<rb_gltf_buffer_view> views;
    std::vector<rb_gltf_buffer> buffers;
    std::vector<rb_gltf_image> images;
    std::vector<rb_gltf_texture> textures;
    std::vector<rb_gltf_material> materials;
    std::vector<std::vector<rb_gltf_attribute>> attributes; // primitive and target attributes
    std::vector<std::vector<rb_gltf_target>> targets;       // per primitive
    std::vector<std::vector<rb_gltf_primitive>> primitives; // per mesh
    std::vector<rb_gltf_mesh> meshes;
    std::vector<rb_gltf_node> nodes;
    std::vector<rb_gltf_skin> skins;
    std::vector<rb_gltf_camera> cameras;
    std::vector<rb_gltf_light> lights;
    std::vector<std::vector<rb_gltf_anim_sampler>> anim_samplers;
    std::vector<std::vector<rb_gltf_anim_channel>> anim_channels;
    std::vector<rb_gltf_animation> animations;
    std::vector<rb_gltf_scene> scenes;
    std::vector<const char *> ext_required, ext_used;
};

// tinygltf's messages are newline-separated and end with a newline: trim each line and join
// them with sep.
std::string join_lines(const std::string &s, const char *sep)
{
    std::string out;
    size_t start = 0;
    while (start < s.size()) {
        size_t end = s.find('\n', start);
        if (end == std::string::npos)
            end = s.size();
        std::string line = s.substr(start, end - start);
        while (!line.empty() && (line.back() == '\r' || line.back() == ' '))
            line.pop_back();
        if (!line.empty()) {
            if (!out.empty())
                out += sep;
            out += line;
        }
        start = end + 1;
    }
    return out;
}

// Sorts tinygltf's error text from a load that succeeded into errors and warnings (each joined
// with newlines), leaving out the lines quiet_errors names.
void sort_errors(const std::string &text, std::string *errors, std::string *warnings)
{
    std::string lines = join_lines(text, "\n");
    size_t start = 0;
    while (start < lines.size()) {
        size_t end = lines.find('\n', start);
        if (end == std::string::npos)
            end = lines.size();
        std::string line = lines.substr(start, end - start);
        start = end + 1;
        bool quiet = false, warn = false;
        for (const char *q : quiet_errors)
            quiet = quiet || line == q;
        for (const char *q : warning_errors)
            warn = warn || line == q;
        std::string *to = warn ? warnings : errors;
        if (quiet)
            continue;
        if (!to->empty())
            *to += '\n';
        *to += line;
    }
}

const tinygltf::Value *find_ext(const tinygltf::ExtensionMap &ext, const char *name)
{
    auto it = ext.find(name);
    return it == ext.end() ? nullptr : &it->second;
}

rb_gltf_texture_ref texture_ref(int index, int tex_coord, const tinygltf::ExtensionMap &ext)
{
    rb_gltf_texture_ref r{};
    r.index = index;
    r.tex_coord = tex_coord;
    r.has_transform = find_ext(ext, "KHR_texture_transform") != nullptr;
    return r;
}

const rb_gltf_attribute *attribute_list(Doc &d, const std::map<std::string, int> &attrs,
                                        size_t *count)
{
    d.attributes.emplace_back();
    std::vector<rb_gltf_attribute> &v = d.attributes.back();
    for (const auto &kv : attrs)
        v.push_back(rb_gltf_attribute{kv.first.c_str(), kv.second});
    *count = v.size();
    return v.data();
}

void mirror(Doc &d)
{
    tinygltf::Model &m = d.model;

    for (const auto &a : m.accessors) {
        rb_gltf_accessor o{};
        o.name = a.name.c_str();
        o.buffer_view = a.bufferView;
        o.byte_offset = a.byteOffset;
        o.component_type = a.componentType;
        o.normalized = a.normalized;
        o.count = a.count;
        o.type = a.type;
        o.is_sparse = a.sparse.isSparse;
        if (a.sparse.isSparse) {
            o.sparse_count = a.sparse.count;
            o.sparse_indices_view = a.sparse.indices.bufferView;
            o.sparse_indices_offset = a.sparse.indices.byteOffset;
            o.sparse_indices_component_type = a.sparse.indices.componentType;
            o.sparse_values_view = a.sparse.values.bufferView;
            o.sparse_values_offset = a.sparse.values.byteOffset;
        }
        d.accessors.push_back(o);
    }
    for (const auto &v : m.bufferViews)
        d.views.push_back(rb_gltf_buffer_view{v.buffer, v.byteOffset, v.byteLength, v.byteStride});
    for (const auto &b : m.buffers)
        d.buffers.push_back(rb_gltf_buffer{b.data.data(), b.data.size()});
    for (const auto &im : m.images) {
        rb_gltf_image o{};
        o.name = im.name.c_str();
        o.uri = im.uri.c_str();
        o.width = im.width;
        o.height = im.height;
        o.components = im.component;
        o.bits = im.bits;
        o.pixels = im.image.empty() ? nullptr : im.image.data();
        o.size = im.image.size();
        d.images.push_back(o);
    }
    for (const auto &t : m.textures)
        d.textures.push_back(rb_gltf_texture{t.name.c_str(), t.source});

    for (const auto &mat : m.materials) {
        const auto &pbr = mat.pbrMetallicRoughness;
        rb_gltf_material o{};
        o.name = mat.name.c_str();
        o.base_color = pbr.baseColorFactor.data();
        o.base_color_count = pbr.baseColorFactor.size();
        o.base_color_tex = texture_ref(pbr.baseColorTexture.index, pbr.baseColorTexture.texCoord,
                                       pbr.baseColorTexture.extensions);
        o.metallic = pbr.metallicFactor;
        o.roughness = pbr.roughnessFactor;
        o.metallic_roughness_tex =
            texture_ref(pbr.metallicRoughnessTexture.index, pbr.metallicRoughnessTexture.texCoord,
                        pbr.metallicRoughnessTexture.extensions);
        o.normal_tex = texture_ref(mat.normalTexture.index, mat.normalTexture.texCoord,
                                   mat.normalTexture.extensions);
        o.normal_scale = mat.normalTexture.scale;
        o.emissive = mat.emissiveFactor.data();
        o.emissive_count = mat.emissiveFactor.size();
        o.emissive_tex = texture_ref(mat.emissiveTexture.index, mat.emissiveTexture.texCoord,
                                     mat.emissiveTexture.extensions);
        const tinygltf::Value *es = find_ext(mat.extensions, "KHR_materials_emissive_strength");
        if (es && es->IsObject() && es->Has("emissiveStrength") &&
            es->Get("emissiveStrength").IsNumber()) {
            o.has_emissive_strength = true;
            o.emissive_strength = es->Get("emissiveStrength").GetNumberAsDouble();
        }
        const tinygltf::Value *sp = find_ext(mat.extensions, "KHR_materials_specular");
        if (sp && sp->IsObject()) {
            o.has_specular = true;
            o.specular_factor = 1.0;
            o.specular_color[0] = o.specular_color[1] = o.specular_color[2] = 1.0;
            if (sp->Has("specularFactor") && sp->Get("specularFactor").IsNumber())
                o.specular_factor = sp->Get("specularFactor").GetNumberAsDouble();
            const tinygltf::Value &sc = sp->Get("specularColorFactor");
            if (sc.IsArray() && sc.ArrayLen() == 3)
                for (int k = 0; k < 3; k++)
                    if (sc.Get(k).IsNumber())
                        o.specular_color[k] = sc.Get(k).GetNumberAsDouble();
            o.has_specular_textures = sp->Has("specularTexture") || sp->Has("specularColorTexture");
        }
        o.alpha_mode = mat.alphaMode.c_str();
        o.alpha_cutoff = mat.alphaCutoff;
        o.double_sided = mat.doubleSided;
        d.materials.push_back(o);
    }

    // Nested arrays: size the outer vectors first so inner data pointers never move.
    size_t prim_total = 0, list_total = 0;
    for (const auto &mesh : m.meshes)
        for (const auto &p : mesh.primitives) {
            prim_total++;
            list_total += 1 + p.targets.size();
        }
    d.attributes.reserve(list_total);
    d.targets.reserve(prim_total);
    d.primitives.reserve(m.meshes.size());
    for (const auto &mesh : m.meshes) {
        d.primitives.emplace_back();
        std::vector<rb_gltf_primitive> &prims = d.primitives.back();
        for (const auto &p : mesh.primitives) {
            rb_gltf_primitive o{};
            o.mode = p.mode;
            o.indices = p.indices;
            o.material = p.material;
            o.attributes = attribute_list(d, p.attributes, &o.attribute_count);
            d.targets.emplace_back();
            std::vector<rb_gltf_target> &tv = d.targets.back();
            for (const auto &t : p.targets) {
                rb_gltf_target ot{};
                ot.attributes = attribute_list(d, t, &ot.attribute_count);
                tv.push_back(ot);
            }
            o.targets = tv.data();
            o.target_count = tv.size();
            prims.push_back(o);
        }
        rb_gltf_mesh o{};
        o.name = mesh.name.c_str();
        o.primitives = prims.data();
        o.primitive_count = prims.size();
        o.weights = mesh.weights.data();
        o.weight_count = mesh.weights.size();
        d.meshes.push_back(o);
    }

    for (const auto &n : m.nodes) {
        rb_gltf_node o{};
        o.name = n.name.c_str();
        o.children = reinterpret_cast<const int32_t *>(n.children.data());
        o.child_count = n.children.size();
        o.translation = n.translation.data();
        o.translation_count = n.translation.size();
        o.rotation = n.rotation.data();
        o.rotation_count = n.rotation.size();
        o.scale = n.scale.data();
        o.scale_count = n.scale.size();
        o.matrix = n.matrix.data();
        o.matrix_count = n.matrix.size();
        o.weights = n.weights.data();
        o.weight_count = n.weights.size();
        o.mesh = n.mesh;
        o.skin = n.skin;
        o.camera = n.camera;
        o.light = -1;
        const tinygltf::Value *lp = find_ext(n.extensions, "KHR_lights_punctual");
        if (lp)
            o.light = lp->IsObject() && lp->Has("light") && lp->Get("light").IsInt()
                          ? lp->Get("light").GetNumberAsInt()
                          : -2;
        d.nodes.push_back(o);
    }
    for (const auto &s : m.skins) {
        rb_gltf_skin o{};
        o.name = s.name.c_str();
        o.inverse_bind_matrices = s.inverseBindMatrices;
        o.joints = reinterpret_cast<const int32_t *>(s.joints.data());
        o.joint_count = s.joints.size();
        d.skins.push_back(o);
    }
    for (const auto &c : m.cameras) {
        rb_gltf_camera o{};
        o.name = c.name.c_str();
        o.type = c.type.c_str();
        o.aspect = c.perspective.aspectRatio;
        o.yfov = c.perspective.yfov;
        o.znear = c.perspective.znear;
        o.zfar = c.perspective.zfar;
        o.xmag = c.orthographic.xmag;
        o.ymag = c.orthographic.ymag;
        o.ortho_znear = c.orthographic.znear;
        o.ortho_zfar = c.orthographic.zfar;
        d.cameras.push_back(o);
    }
    for (const auto &l : m.lights) {
        rb_gltf_light o{};
        o.name = l.name.c_str();
        o.type = l.type.c_str();
        o.color = l.color.data();
        o.color_count = l.color.size();
        o.intensity = l.intensity;
        o.range = l.range;
        o.inner_cone = l.spot.innerConeAngle;
        o.outer_cone = l.spot.outerConeAngle;
        d.lights.push_back(o);
    }
    // tinygltf keeps the extension's JSON beside the lights it read from it: whether a range
    // was given at all is only there.
    const tinygltf::Value *lp = find_ext(m.extensions, "KHR_lights_punctual");
    if (lp && lp->IsObject() && lp->Has("lights") && lp->Get("lights").IsArray()) {
        const tinygltf::Value &ls = lp->Get("lights");
        for (size_t i = 0; i < d.lights.size() && i < ls.ArrayLen(); i++)
            d.lights[i].has_range =
                ls.Get(static_cast<int>(i)).IsObject() && ls.Get(static_cast<int>(i)).Has("range");
    }
    d.anim_samplers.reserve(m.animations.size());
    d.anim_channels.reserve(m.animations.size());
    for (const auto &a : m.animations) {
        d.anim_samplers.emplace_back();
        for (const auto &s : a.samplers)
            d.anim_samplers.back().push_back(
                rb_gltf_anim_sampler{s.input, s.output, s.interpolation.c_str()});
        d.anim_channels.emplace_back();
        for (const auto &c : a.channels)
            d.anim_channels.back().push_back(
                rb_gltf_anim_channel{c.sampler, c.target_node, c.target_path.c_str()});
        rb_gltf_animation o{};
        o.name = a.name.c_str();
        o.samplers = d.anim_samplers.back().data();
        o.sampler_count = d.anim_samplers.back().size();
        o.channels = d.anim_channels.back().data();
        o.channel_count = d.anim_channels.back().size();
        d.animations.push_back(o);
    }
    for (const auto &s : m.scenes)
        d.scenes.push_back(rb_gltf_scene{
            s.name.c_str(), reinterpret_cast<const int32_t *>(s.nodes.data()), s.nodes.size()});
    for (const auto &e : m.extensionsRequired)
        d.ext_required.push_back(e.c_str());
    for (const auto &e : m.extensionsUsed)
        d.ext_used.push_back(e.c_str());

    rb_gltf_doc &p = d.pub;
    p.errors = d.errors.c_str();
    p.warnings = d.warnings.c_str();
    p.version = m.asset.version.c_str();
    p.min_version = m.asset.minVersion.c_str();
    p.accessors = d.accessors.data();
    p.accessor_count = d.accessors.size();
    p.buffer_views = d.views.data();
    p.buffer_view_count = d.views.size();
    p.buffers = d.buffers.data();
    p.buffer_count = d.buffers.size();
    p.images = d.images.data();
    p.image_count = d.images.size();
    p.textures = d.textures.data();
    p.texture_count = d.textures.size();
    p.materials = d.materials.data();
    p.material_count = d.materials.size();
    p.meshes = d.meshes.data();
    p.mesh_count = d.meshes.size();
    p.nodes = d.nodes.data();
    p.node_count = d.nodes.size();
    p.skins = d.skins.data();
    p.skin_count = d.skins.size();
    p.cameras = d.cameras.data();
    p.camera_count = d.cameras.size();
    p.lights = d.lights.data();
    p.light_count = d.lights.size();
    p.animations = d.animations.data();
    p.animation_count = d.animations.size();
    p.scenes = d.scenes.data();
    p.scene_count = d.scenes.size();
    p.default_scene = m.defaultScene;
    p.extensions_required = d.ext_required.data();
    p.extensions_required_count = d.ext_required.size();
    p.extensions_used = d.ext_used.data();
    p.extensions_used_count = d.ext_used.size();
}

bool ends_with(const std::string &s, const char *suffix)
{
    size_t n = std::strlen(suffix);
    if (s.size() < n)
        return false;
    for (size_t i = 0; i < n; i++)
        if (std::tolower(static_cast<unsigned char>(s[s.size() - n + i])) != suffix[i])
            return false;
    return true;
}

// Reads all of path into data: a regular file only, bounded by its size when opened.
enum rb_status read_file(const char *path, uint64_t max_bytes, std::vector<unsigned char> &data,
                         struct rb_err *err)
{
    int fd = -1;
    uint64_t size = 0;
    enum rb_status st = rb_file_open_regular(path, max_bytes, &fd, &size, err);
    if (st)
        return st;
    data.resize(static_cast<size_t>(size)); // bad_alloc is the caller's "out of memory"
    size_t got = 0;
    while (got < data.size()) {
        ssize_t n = ::read(fd, data.data() + got, data.size() - got);
        if (n < 0 && errno == EINTR)
            continue;
        if (n <= 0) {
            if (n == 0)
                break; // shrank meanwhile: tinygltf then finds the size wrong
            int saved = errno;
            ::close(fd);
            return rb_errf(err, RB_E_IO, "cannot read '%s': %s", path, std::strerror(saved));
        }
        got += static_cast<size_t>(n);
    }
    ::close(fd);
    data.resize(got);
    return RB_OK;
}

// Where JSON text nests deeper than RB_SCENE_JSON_MAX_DEPTH, found without recursion: both JSON
// parsers recurse per level, and a few tens of thousands of '[' overflow the stack. Returns the
// byte offset of the bracket that passes the cap, or SIZE_MAX when none does. Strings are
// skipped; text that does not parse is left to the parser.
size_t json_too_deep(const char *text, size_t size)
{
    size_t depth = 0;
    bool in_string = false;
    for (size_t i = 0; i < size; i++) {
        char ch = text[i];
        if (in_string) {
            if (ch == '\\')
                i++;
            else if (ch == '"')
                in_string = false;
        } else if (ch == '"') {
            in_string = true;
        } else if (ch == '[' || ch == '{') {
            if (++depth > RB_SCENE_JSON_MAX_DEPTH)
                return i;
        } else if ((ch == ']' || ch == '}') && depth > 0) {
            depth--;
        }
    }
    return SIZE_MAX;
}

// The message for json_too_deep's offset at, as "line L, column C" of the JSON text; path is
// NULL for text that came from no file.
enum rb_status too_deep(const char *path, const char *text, size_t at, bool binary,
                        struct rb_err *err)
{
    size_t line = 1, col = 1;
    for (size_t i = 0; i < at; i++) {
        if (text[i] == '\n') {
            line++;
            col = 1;
        } else {
            col++;
        }
    }
    if (!path)
        return rb_errf(err, RB_E_PARSE, "JSON nests deeper than %d levels at line %zu, column %zu",
                       RB_SCENE_JSON_MAX_DEPTH, line, col);
    return rb_errf(err, RB_E_PARSE,
                   "cannot load '%s': JSON%s nests deeper than %d levels at line %zu, column %zu",
                   path, binary ? " chunk" : "", RB_SCENE_JSON_MAX_DEPTH, line, col);
}

// What tinygltf's file callbacks know: the byteLength each external buffer file declares, by
// the path tinygltf will ask for (the uri decoded and joined to the base directory, or to ".",
// as its FindFile does).
struct Files {
    std::vector<std::pair<std::string, uint64_t>> buffers;
};

std::string join_path(const std::string &a, const std::string &b)
{
    if (a.empty())
        return b;
    return a.back() == '/' || a.back() == '\\' ? a + b : a + "/" + b;
}

// dlib::urldecode, which tinygltf applies to buffer uris: "%XX" is a byte, '+' a space.
std::string url_decode(const std::string &s)
{
    std::string out;
    for (size_t i = 0; i < s.size(); i++) {
        if (s[i] == '+') {
            out += ' ';
        } else if (s[i] == '%' && i + 2 < s.size() && std::isxdigit((unsigned char)s[i + 1]) &&
                   std::isxdigit((unsigned char)s[i + 2])) {
            out += static_cast<char>(std::stoi(s.substr(i + 1, 2), nullptr, 16));
            i += 2;
        } else {
            out += s[i];
        }
    }
    return out;
}

void collect_buffers(const json &doc, const std::string &base, Files &files)
{
    auto it = doc.find("buffers");
    if (it == doc.end() || !it->is_array())
        return;
    for (const json &b : *it) {
        if (!b.is_object())
            continue;
        auto uri = b.find("uri");
        auto len = b.find("byteLength");
        if (uri == b.end() || !uri->is_string() || len == b.end() || !len->is_number_unsigned())
            continue;
        std::string u = uri->get<std::string>();
        if (u.compare(0, 5, "data:") == 0)
            continue;
        std::string d = url_decode(u);
        files.buffers.emplace_back(join_path(base, d), len->get<uint64_t>());
        files.buffers.emplace_back(join_path(".", d), len->get<uint64_t>());
    }
}

bool fs_exists(const std::string &path, void *)
{
    struct stat sb;
    return ::stat(path.c_str(), &sb) == 0;
}

std::string fs_expand(const std::string &path, void *)
{
    return path;
}

// tinygltf's reader for external buffers and images: regular files only, and a buffer file
// no longer than the byteLength a buffer declares for it (a longer one is refused unread;
// tinygltf wants the size exact and names a shorter one itself).
bool fs_read(std::vector<unsigned char> *out, std::string *why, const std::string &path, void *user)
{
    const Files *files = static_cast<const Files *>(user);
    uint64_t limit = RB_FILE_MAX_BYTES;
    bool is_buffer = false;
    for (const auto &b : files->buffers)
        if (b.first == path && (!is_buffer || b.second > limit)) {
            limit = b.second;
            is_buffer = true;
        }
    struct rb_err err = RB_ERR_INIT;
    struct stat sb;
    if (is_buffer && rb_file_check_regular(path.c_str(), &err) == RB_OK &&
        ::stat(path.c_str(), &sb) == 0 && static_cast<uint64_t>(sb.st_size) > limit) {
        *why = std::to_string(sb.st_size) + " bytes, more than the byteLength " +
               std::to_string(limit) + " its buffer declares";
        return false;
    }
    if (read_file(path.c_str(), limit, *out, &err) != RB_OK) {
        *why = err.msg;
        return false;
    }
    return true;
}

bool fs_write(std::string *, const std::string &, const std::vector<unsigned char> &, void *)
{
    return false; // raybundle never writes glTF
}

// stb_image's limits, which tinygltf's decoder (built into Debian's libtinygltf) applies: at
// most 2^24 pixels a side, 2^30 bytes of pixels as the file stores them (width x height x
// channels), and 2^31 bytes once expanded to RGBA (twice as many for 16 bits a channel).
constexpr uint64_t STB_MAX_SIDE = 1u << 24;
constexpr uint64_t STB_MAX_STORED = 1u << 30;
constexpr uint64_t STB_MAX_RGBA = INT_MAX;

uint32_t be32(const unsigned char *p)
{
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

// A byte count in powers of 1000 to three figures: "6.4 GB", "1.07 GB", "512 kB".
std::string bytes_text(uint64_t n)
{
    static const char *const units[] = {"bytes", "kB", "MB", "GB", "TB"};
    double v = static_cast<double>(n);
    int u = 0;
    while (v >= 1000.0 && u < 4) {
        v /= 1000.0;
        u++;
    }
    char buf[32];
    std::snprintf(buf, sizeof(buf), u ? "%.3g %s" : "%.0f %s", v, units[u]);
    return buf;
}

// Why a PNG that failed to decode is too large for stb_image ("" when its header is within the
// limits, or it is no PNG): its size from the IHDR chunk, and the limit it passes.
std::string png_too_large(const unsigned char *bytes, int size)
{
    static const unsigned char magic[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    if (size < 33 || std::memcmp(bytes, magic, 8) != 0 || std::memcmp(bytes + 12, "IHDR", 4) != 0)
        return std::string();
    uint64_t w = be32(bytes + 16), h = be32(bytes + 20);
    unsigned depth = bytes[24], type = bytes[25];
    uint64_t channels = type == 2 ? 3 : type == 4 ? 2 : type == 6 ? 4 : 1;
    uint64_t rgba = w * h * 4 * (depth == 16 ? 2 : 1);
    std::string size_text = std::to_string(w) + " x " + std::to_string(h) + " pixels";
    if (w > STB_MAX_SIDE || h > STB_MAX_SIDE)
        return "the PNG is " + size_text + ", too large: the decoder takes at most " +
               std::to_string(STB_MAX_SIDE) + " pixels a side";
    if (w * h * channels > STB_MAX_STORED)
        return "the PNG is " + size_text + " of " + std::to_string(channels) + " channel" +
               (channels == 1 ? "" : "s") + " (" + bytes_text(w * h * channels) +
               "), too large: the decoder takes at most " + bytes_text(STB_MAX_STORED) +
               " (width x height x channels)";
    if (rgba > STB_MAX_RGBA)
        return "the PNG is " + size_text + " (" + bytes_text(rgba) +
               " as RGBA), too large: the decoder takes at most " + bytes_text(STB_MAX_RGBA);
    return std::string();
}

// tinygltf's own image decoder, with a PNG that is only too large said so (stb_image calls that
// "Unknown image format"). user is passed on: nullptr, tinygltf's default options.
bool load_image(tinygltf::Image *image, const int index, std::string *err, std::string *warn,
                int req_width, int req_height, const unsigned char *bytes, int size, void *user)
{
    std::string before = err ? *err : std::string();
    if (tinygltf::LoadImageData(image, index, err, warn, req_width, req_height, bytes, size, user))
        return true;
    std::string why = png_too_large(bytes, size);
    if (err && !why.empty())
        *err = before + "image " + std::to_string(index) +
               (image->name.empty() ? std::string() : " '" + image->name + "'") + ": " + why + "\n";
    return false;
}

// The directory tinygltf resolves external buffers and images against, as its *FromFile do.
std::string base_dir(const std::string &path)
{
    size_t slash = path.find_last_of("/\\");
    return slash == std::string::npos ? std::string() : path.substr(0, slash);
}

} // namespace

// int32_t and int must agree for the reinterpret_casts of tinygltf's index vectors above.
static_assert(sizeof(int) == sizeof(int32_t), "int is not 32 bits");

extern "C" enum rb_status rb_gltf_shim_check(const char *text, size_t size,
                                             const struct rb_gltf_check *check,
                                             struct rb_err *err) noexcept
{
    try {
        size_t deep = json_too_deep(text, size);
        if (deep != SIZE_MAX)
            return too_deep(nullptr, text, deep, false, err);
        json doc;
        try {
            doc = json::parse(text, text + size);
        } catch (const json::parse_error &e) {
            std::string why = e.what();
            size_t cut = why.find("] "); // drop "[json.exception.parse_error.101] "
            return rb_errf(err, RB_E_PARSE, "invalid JSON: %s",
                           cut == std::string::npos ? why.c_str() : why.c_str() + cut + 2);
        }
        if (!doc.is_object())
            return rb_errf(err, RB_E_PARSE,
                           "not a glTF document: the top level is %s, not an object",
                           describe(doc).c_str());
        Walk w{check->rules, check->rule_count, check->on_issue, check->user, {}};
        if (!check_doc(w, doc))
            return rb_errf(err, RB_E_PARSE, "%s", w.stop.c_str());
        return RB_OK;
    } catch (const std::bad_alloc &) {
        return rb_errf(err, RB_E_NOMEM, "out of memory checking glTF JSON");
    } catch (const std::exception &e) {
        return rb_errf(err, RB_E_EXTERNAL, "checking glTF JSON: %s", e.what());
    } catch (...) {
        return rb_errf(err, RB_E_EXTERNAL, "checking glTF JSON: unknown exception");
    }
}

extern "C" enum rb_status rb_gltf_shim_load(const char *path, const struct rb_gltf_check *check,
                                            struct rb_gltf_doc **out, struct rb_err *err) noexcept
{
    // What the load was doing, for a failed allocation's message.
    const char *stage = "reading the file";
    uint64_t file_bytes = 0;
    try {
        std::vector<unsigned char> data;
        // tinygltf takes an unsigned int size: larger files are refused unread.
        enum rb_status st = read_file(path, UINT_MAX, data, err);
        if (st)
            return st;
        file_bytes = data.size();
        stage = "checking its JSON";
        // Sniff the magic: a .gltf may hold binary glTF and vice versa.
        bool binary = (data.size() >= 4 && std::memcmp(data.data(), "glTF", 4) == 0) ||
                      ends_with(path, ".glb");

        // The nesting first, then the types: tinygltf would skip what does not match. JSON
        // that does not parse, or is no object, is left to tinygltf's own message.
        if (binary) {
            std::string why = glb_header_problem(data);
            if (!why.empty())
                return rb_errf(err, RB_E_PARSE, "cannot load '%s': invalid GLB: %s", path,
                               why.c_str());
        }
        const char *text = nullptr;
        size_t text_size = 0;
        std::string base = base_dir(path);
        Files files;
        if (json_span(data, binary, &text, &text_size)) {
            size_t deep = json_too_deep(text, text_size);
            if (deep != SIZE_MAX)
                return too_deep(path, text, deep, binary, err);
            json doc = json::parse(text, text + text_size, nullptr, false);
            if (!doc.is_discarded() && doc.is_object()) {
                if (check) {
                    Walk w{check->rules, check->rule_count, check->on_issue, check->user, {}};
                    if (!check_doc(w, doc))
                        return rb_errf(err, RB_E_PARSE, "%s", w.stop.c_str());
                }
                collect_buffers(doc, base, files);
            }
        }

        stage = "parsing it and decoding its buffers and images";
        std::unique_ptr<Doc> d(new Doc());
        tinygltf::TinyGLTF loader;
        tinygltf::FsCallbacks fs = {fs_exists, fs_expand, fs_read, fs_write, &files};
        loader.SetFsCallbacks(fs);
        loader.SetImageLoader(load_image, nullptr); // no option: tinygltf's default, RGBA
        std::string terr, twarn;
        static const unsigned char empty[1] = {0};
        const unsigned char *bytes = data.empty() ? empty : data.data();
        unsigned size = static_cast<unsigned>(data.size());
        bool ok =
            binary ? loader.LoadBinaryFromMemory(&d->model, &terr, &twarn, bytes, size, base)
                   : loader.LoadASCIIFromString(&d->model, &terr, &twarn,
                                                reinterpret_cast<const char *>(bytes), size, base);
        if (!ok) {
            std::string msg = join_lines(terr, "; ");
            return rb_errf(err, RB_E_PARSE, "cannot load '%s': %s", path,
                           msg.empty() ? "unknown tinygltf error" : msg.c_str());
        }
        // tinygltf also reports errors on success (a dropped primitive, a misaligned GLB
        // chunk): they go to the caller as errors, apart from the few about valid files.
        d->warnings = join_lines(twarn, "\n");
        sort_errors(terr, &d->errors, &d->warnings);
        stage = "copying its arrays";
        mirror(*d);
        if (binary && data.size() >= 12)
            d->pub.glb_version = le32(&data[4]);
        d->pub.impl = d.get();
        *out = &d.release()->pub;
        return RB_OK;
    } catch (const std::bad_alloc &) {
        struct stat sb;
        if (!file_bytes && ::stat(path, &sb) == 0)
            file_bytes = static_cast<uint64_t>(sb.st_size);
        try {
            return rb_errf(err, RB_E_NOMEM, "cannot load '%s' (%s): out of memory %s", path,
                           bytes_text(file_bytes).c_str(), stage);
        } catch (...) {
            return rb_errf(err, RB_E_NOMEM, "cannot load '%s': out of memory %s", path, stage);
        }
    } catch (const std::exception &e) {
        return rb_errf(err, RB_E_EXTERNAL, "cannot load '%s': %s", path, e.what());
    } catch (...) {
        return rb_errf(err, RB_E_EXTERNAL, "cannot load '%s': unknown exception", path);
    }
}

extern "C" void rb_gltf_shim_free(struct rb_gltf_doc *doc) noexcept
{
    if (doc)
        delete static_cast<Doc *>(doc->impl); // Doc's destructor cannot throw
}
