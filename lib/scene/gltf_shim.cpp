// The only file that includes tiny_gltf.h (Debian's libtinygltf holds the implementation, so
// TINYGLTF_IMPLEMENTATION is not defined here). It parses a file and mirrors the tinygltf::Model
// into the plain structs of gltf_shim.h; scene.c validates and converts them. No policy here.

#include "core/core.h"

#include "scene/gltf_shim.h"

#include <tiny_gltf.h>

#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <new>
#include <string>
#include <vector>

namespace
{

struct Doc {
    rb_gltf_doc pub{}; // pub.impl points back here
    tinygltf::Model model;
    std::string warnings;
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
    p.warnings = d.warnings.c_str();
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

} // namespace

// int32_t and int must agree for the reinterpret_casts of tinygltf's index vectors above.
static_assert(sizeof(int) == sizeof(int32_t), "int is not 32 bits");

extern "C" enum rb_status rb_gltf_shim_load(const char *path, struct rb_gltf_doc **out,
                                            struct rb_err *err) noexcept
{
    try {
        // Sniff the magic: a .gltf may hold binary glTF and vice versa.
        char magic[4] = {0};
        std::FILE *f = std::fopen(path, "rb");
        if (!f)
            return rb_errf(err, RB_E_IO, "cannot open '%s': %s", path, std::strerror(errno));
        size_t got = std::fread(magic, 1, sizeof(magic), f);
        std::fclose(f);
        bool binary = (got == 4 && std::memcmp(magic, "glTF", 4) == 0) || ends_with(path, ".glb");

        std::unique_ptr<Doc> d(new Doc());
        tinygltf::TinyGLTF loader;
        std::string terr, twarn;
        bool ok = binary ? loader.LoadBinaryFromFile(&d->model, &terr, &twarn, path)
                         : loader.LoadASCIIFromFile(&d->model, &terr, &twarn, path);
        if (!ok) {
            std::string msg = join_lines(terr, "; ");
            return rb_errf(err, RB_E_PARSE, "cannot load '%s': %s", path,
                           msg.empty() ? "unknown tinygltf error" : msg.c_str());
        }
        // tinygltf may also report errors on success (e.g. a misaligned GLB chunk): pass them
        // on as warnings; scene.c decides what matters.
        d->warnings = join_lines(twarn + "\n" + terr, "\n");
        mirror(*d);
        d->pub.impl = d.get();
        *out = &d.release()->pub;
        return RB_OK;
    } catch (const std::bad_alloc &) {
        return rb_errf(err, RB_E_NOMEM, "cannot load '%s': out of memory", path);
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
