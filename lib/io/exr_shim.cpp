// OpenEXR behind a C interface (exr_shim.h). Thin: every function is extern "C" and noexcept,
// turns OpenEXR's exceptions into a message, and decides nothing that io.c could decide instead.
#include "io/exr_shim.h"

#include <ImfBoxAttribute.h>
#include <ImfChannelList.h>
#include <ImfChromaticitiesAttribute.h>
#include <ImfCompressionAttribute.h>
#include <ImfDoubleAttribute.h>
#include <ImfFloatAttribute.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfIntAttribute.h>
#include <ImfLineOrderAttribute.h>
#include <ImfMatrixAttribute.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>
#include <ImfTestFile.h>
#include <IexErrnoExc.h>
#include <ImfVecAttribute.h>
#include <OpenEXRConfig.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <exception>
#include <memory>
#include <string>
#include <vector>

namespace
{

int fail(char *msg, size_t msg_size, const char *text)
{
    if (msg && msg_size) {
        std::string t = text && *text ? text : "unknown OpenEXR error";
        for (char &c : t)
            if (c == '\n')
                c = ' ';
        std::snprintf(msg, msg_size, "%s", t.c_str());
    }
    return RB_EXR_FAIL;
}

// Reading order within a layer: R, G, B, A, then the other channels by name.
int rank(const std::string &base)
{
    static const char *const first[] = {"R", "G", "B", "A"};
    for (int i = 0; i < 4; i++)
        if (base == first[i])
            return i;
    return 4;
}

struct channel_key {
    std::string name, layer, base;
};

channel_key split(const std::string &name)
{
    size_t dot = name.rfind('.');
    if (dot == std::string::npos)
        return {name, "", name};
    return {name, name.substr(0, dot), name.substr(dot + 1)};
}

bool before(const channel_key &a, const channel_key &b)
{
    if (a.layer != b.layer)
        return a.layer < b.layer; // "" (the beauty) sorts first
    int ra = rank(a.base), rb = rank(b.base);
    if (ra != rb)
        return ra < rb;
    return a.base < b.base;
}

} // namespace

struct rb_exr_input {
    std::unique_ptr<Imf::InputFile> file;
    std::vector<std::string> names;      // reading order
    std::vector<std::string> attr_names; // the header's order (by name)
    std::vector<std::string> attr_types; // OpenEXR's type names, e.g. "string", "box2i"
    int min_x = 0, min_y = 0, width = 0, height = 0;
};

extern "C" const char *rb_exr_version(void) noexcept
{
    return OPENEXR_VERSION_STRING;
}

extern "C" bool rb_exr_is_exr(const char *path) noexcept
{
    try {
        return path && Imf::isOpenExrFile(path);
    } catch (...) {
        return false;
    }
}

extern "C" int rb_exr_write(const struct rb_exr_write_desc *d, char *msg, size_t msg_size) noexcept
{
    try {
        Imf::Header header(int(d->width_px), int(d->height_px));
        header.compression() = Imf::ZIP_COMPRESSION;
        header.lineOrder() = Imf::INCREASING_Y;
        for (uint32_t c = 0; c < d->channel_count; c++) {
            bool half = d->channel_is_half && d->channel_is_half[c];
            header.channels().insert(d->channel_names[c],
                                     Imf::Channel(half ? Imf::HALF : Imf::FLOAT));
        }
        for (size_t k = 0; k < d->attr_count; k++) {
            const struct rb_exr_attr *a = &d->attrs[k];
            switch (a->type) {
            case RB_EXR_ATTR_STRING:
                header.insert(a->name, Imf::StringAttribute(a->s ? a->s : ""));
                break;
            case RB_EXR_ATTR_INT: header.insert(a->name, Imf::IntAttribute(a->i)); break;
            case RB_EXR_ATTR_FLOAT: header.insert(a->name, Imf::FloatAttribute(a->f)); break;
            case RB_EXR_ATTR_M44: {
                const float *m = a->fv;
                Imath::M44f v(m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8], m[9], m[10],
                              m[11], m[12], m[13], m[14], m[15]);
                header.insert(a->name, Imf::M44fAttribute(v));
                break;
            }
            case RB_EXR_ATTR_CHROMATICITIES: {
                const float *v = a->fv;
                Imf::Chromaticities c(Imath::V2f(v[0], v[1]), Imath::V2f(v[2], v[3]),
                                      Imath::V2f(v[4], v[5]), Imath::V2f(v[6], v[7]));
                header.insert(a->name, Imf::ChromaticitiesAttribute(c));
                break;
            }
            default: return fail(msg, msg_size, "unknown attribute type");
            }
        }

        // A float slice over the interleaved pixels for each float channel; a half channel
        // needs a half slice (OpenEXR converts on reading, not on writing): its own plane,
        // rounded to nearest even by Imath's half.
        const size_t xs = size_t(d->channel_count) * sizeof(float);
        const size_t ys = xs * d->width_px;
        const size_t count = size_t(d->width_px) * d->height_px;
        std::vector<std::vector<Imath::half>> planes;
        Imf::FrameBuffer fb;
        for (uint32_t c = 0; c < d->channel_count; c++) {
            if (d->channel_is_half && d->channel_is_half[c]) {
                planes.emplace_back(count);
                std::vector<Imath::half> &p = planes.back();
                for (size_t i = 0; i < count; i++)
                    p[i] = Imath::half(d->pixels[i * d->channel_count + c]);
                fb.insert(d->channel_names[c],
                          Imf::Slice(Imf::HALF, (char *)p.data(), sizeof(Imath::half),
                                     sizeof(Imath::half) * d->width_px));
            } else {
                fb.insert(d->channel_names[c],
                          Imf::Slice(Imf::FLOAT, (char *)(d->pixels + c), xs, ys));
            }
        }
        Imf::OutputFile out(d->path, header, 1);
        out.setFrameBuffer(fb);
        out.writePixels(int(d->height_px));
        return RB_EXR_OK;
    } catch (const IEX_NAMESPACE::EnospcExc &e) {
        fail(msg, msg_size, e.what());
        return RB_EXR_NOSPACE;
    } catch (const IEX_NAMESPACE::EdquotExc &e) {
        fail(msg, msg_size, e.what());
        return RB_EXR_NOQUOTA;
    } catch (const std::exception &e) {
        return fail(msg, msg_size, e.what());
    } catch (...) {
        return fail(msg, msg_size, nullptr);
    }
}

extern "C" int rb_exr_open(const char *path, struct rb_exr_input **out, uint32_t *width_px,
                           uint32_t *height_px, uint32_t *channel_count, char *msg,
                           size_t msg_size) noexcept
{
    try {
        auto in = std::make_unique<rb_exr_input>();
        in->file = std::make_unique<Imf::InputFile>(path, 1);
        const Imf::Header &h = in->file->header();
        const Imath::Box2i &dw = h.dataWindow();
        if (dw.isEmpty())
            return fail(msg, msg_size, "image has no pixels");
        std::vector<channel_key> keys;
        for (auto it = h.channels().begin(); it != h.channels().end(); ++it) {
            if (it.channel().xSampling != 1 || it.channel().ySampling != 1)
                return fail(msg, msg_size,
                            (std::string("subsampled channel '") + it.name() + "' is not supported")
                                .c_str());
            keys.push_back(split(it.name()));
        }
        if (keys.empty())
            return fail(msg, msg_size, "image has no channels");
        std::stable_sort(keys.begin(), keys.end(), before);
        for (const auto &k : keys)
            in->names.push_back(k.name);
        for (auto it = h.begin(); it != h.end(); ++it) {
            in->attr_names.push_back(it.name());
            in->attr_types.push_back(it.attribute().typeName());
        }
        in->min_x = dw.min.x;
        in->min_y = dw.min.y;
        in->width = dw.max.x - dw.min.x + 1;
        in->height = dw.max.y - dw.min.y + 1;
        *width_px = uint32_t(in->width);
        *height_px = uint32_t(in->height);
        *channel_count = uint32_t(in->names.size());
        *out = in.release();
        return RB_EXR_OK;
    } catch (const std::exception &e) {
        return fail(msg, msg_size, e.what());
    } catch (...) {
        return fail(msg, msg_size, nullptr);
    }
}

extern "C" const char *rb_exr_channel_name(const struct rb_exr_input *in, uint32_t i) noexcept
{
    if (!in || i >= in->names.size())
        return "";
    return in->names[i].c_str();
}

extern "C" int rb_exr_read(struct rb_exr_input *in, float *pixels, char *msg,
                           size_t msg_size) noexcept
{
    try {
        const size_t n = in->names.size();
        const ptrdiff_t xs = ptrdiff_t(n * sizeof(float));
        const ptrdiff_t ys = xs * in->width;
        // OpenEXR addresses a pixel as base + x * xs + y * ys with the data window's own x, y.
        char *origin = (char *)pixels - in->min_x * xs - in->min_y * ys;
        Imf::FrameBuffer fb;
        for (size_t c = 0; c < n; c++)
            fb.insert(in->names[c],
                      Imf::Slice(Imf::FLOAT, origin + c * sizeof(float), size_t(xs), size_t(ys)));
        in->file->setFrameBuffer(fb);
        in->file->readPixels(in->min_y, in->min_y + in->height - 1);
        return RB_EXR_OK;
    } catch (const std::exception &e) {
        return fail(msg, msg_size, e.what());
    } catch (...) {
        return fail(msg, msg_size, nullptr);
    }
}

extern "C" bool rb_exr_attr_text(const struct rb_exr_input *in, const char *name, char *out,
                                 size_t size) noexcept
{
    try {
        const Imf::Header &h = in->file->header();
        Imf::Header::ConstIterator it = h.find(name);
        if (it == h.end())
            return false;
        const Imf::Attribute *a = &it.attribute();
        std::string v;
        char num[64];
        auto add = [&](double x) {
            std::snprintf(num, sizeof(num), "%g", x);
            if (!v.empty())
                v += ", ";
            v += num;
        };
        auto addi = [&](int x) {
            if (!v.empty())
                v += ", ";
            v += std::to_string(x);
        };
        if (auto s = dynamic_cast<const Imf::StringAttribute *>(a)) {
            v = s->value();
        } else if (auto i = dynamic_cast<const Imf::IntAttribute *>(a)) {
            std::snprintf(num, sizeof(num), "%d", i->value());
            v = num;
        } else if (auto f = dynamic_cast<const Imf::FloatAttribute *>(a)) {
            add(f->value());
        } else if (auto dbl = dynamic_cast<const Imf::DoubleAttribute *>(a)) {
            add(dbl->value());
        } else if (auto m = dynamic_cast<const Imf::M44fAttribute *>(a)) {
            for (int r = 0; r < 4; r++)
                for (int c = 0; c < 4; c++)
                    add(m->value()[r][c]);
        } else if (auto ch = dynamic_cast<const Imf::ChromaticitiesAttribute *>(a)) {
            const Imf::Chromaticities &c = ch->value();
            for (const Imath::V2f &p : {c.red, c.green, c.blue, c.white}) {
                add(p.x);
                add(p.y);
            }
        } else if (auto v2 = dynamic_cast<const Imf::V2fAttribute *>(a)) {
            add(v2->value().x);
            add(v2->value().y);
        } else if (auto v2i = dynamic_cast<const Imf::V2iAttribute *>(a)) {
            addi(v2i->value().x);
            addi(v2i->value().y);
        } else if (auto v3 = dynamic_cast<const Imf::V3fAttribute *>(a)) {
            add(v3->value().x);
            add(v3->value().y);
            add(v3->value().z);
        } else if (auto box = dynamic_cast<const Imf::Box2iAttribute *>(a)) {
            addi(box->value().min.x);
            addi(box->value().min.y);
            addi(box->value().max.x);
            addi(box->value().max.y);
        } else if (auto co = dynamic_cast<const Imf::CompressionAttribute *>(a)) {
            static const char *const names[] = {"none",  "rle", "zips", "zip",  "piz",
                                                "pxr24", "b44", "b44a", "dwaa", "dwab"};
            int id = int(co->value());
            if (id >= 0 && id < int(sizeof(names) / sizeof(names[0])))
                v = names[id];
            else
                v = std::to_string(id);
        } else if (auto lo = dynamic_cast<const Imf::LineOrderAttribute *>(a)) {
            static const char *const names[] = {"increasing y", "decreasing y", "random y"};
            int id = int(lo->value());
            if (id >= 0 && id < 3)
                v = names[id];
            else
                v = std::to_string(id);
        } else {
            return false;
        }
        if (size)
            std::snprintf(out, size, "%s", v.c_str());
        return true;
    } catch (...) {
        return false;
    }
}

extern "C" size_t rb_exr_attr_count(const struct rb_exr_input *in) noexcept
{
    return in ? in->attr_names.size() : 0;
}

extern "C" const char *rb_exr_attr_name(const struct rb_exr_input *in, size_t i) noexcept
{
    if (!in || i >= in->attr_names.size())
        return "";
    return in->attr_names[i].c_str();
}

extern "C" const char *rb_exr_attr_type(const struct rb_exr_input *in, size_t i) noexcept
{
    if (!in || i >= in->attr_types.size())
        return "";
    return in->attr_types[i].c_str();
}

extern "C" void rb_exr_close(struct rb_exr_input *in) noexcept
{
    delete in;
}
