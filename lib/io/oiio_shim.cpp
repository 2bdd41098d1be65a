// OpenImageIO behind a C interface (oiio_shim.h): what only it does here (reading formats other
// than EXR and PNG, resizing thumbnails). Compiled only where RB_WITH_OIIO is 1. Thin: every
// function is extern "C" and noexcept, turns exceptions and OIIO's geterror() into a message, and
// decides nothing that io.c could decide instead.
#include "io/oiio_shim.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>
#include <OpenImageIO/strutil.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace
{

int fail(char *msg, size_t msg_size, const std::string &text)
{
    if (msg && msg_size) {
        std::string t = text;
        // OIIO messages sometimes end in a newline; our messages are one line.
        while (!t.empty() && (t.back() == '\n' || t.back() == ' '))
            t.pop_back();
        for (char &c : t)
            if (c == '\n')
                c = ' ';
        std::snprintf(msg, msg_size, "%s", t.empty() ? "unknown OpenImageIO error" : t.c_str());
    }
    return RB_OIIO_FAIL;
}

int fail_unknown(char *msg, size_t msg_size)
{
    return fail(msg, msg_size, "unknown exception in OpenImageIO");
}

// Debian builds OIIO with debug messages on, which print to stderr on ordinary writes; the
// library must stay quiet. OPENIMAGEIO_DEBUG, when set, still wins.
void quiet_debug()
{
    static std::once_flag once;
    std::call_once(once, [] {
        if (!std::getenv("OPENIMAGEIO_DEBUG"))
            OIIO::attribute("debug", 0);
    });
}

} // namespace

struct rb_oiio_input {
    std::unique_ptr<OIIO::ImageInput> in;
    OIIO::ImageSpec spec;
};

extern "C" const char *rb_oiio_version(void) noexcept
{
    return OIIO_VERSION_STRING;
}

extern "C" int rb_oiio_resize(const float *src, uint32_t width_px, uint32_t height_px,
                              uint32_t channel_count, float *dst, uint32_t dst_width_px,
                              uint32_t dst_height_px, char *msg, size_t msg_size) noexcept
{
    try {
        quiet_debug();
        const OIIO::ImageBuf in(OIIO::ImageSpec(int(width_px), int(height_px), int(channel_count),
                                                OIIO::TypeDesc::FLOAT),
                                const_cast<float *>(src));
        OIIO::ImageBuf out(OIIO::ImageSpec(int(dst_width_px), int(dst_height_px),
                                           int(channel_count), OIIO::TypeDesc::FLOAT),
                           dst);
        if (!OIIO::ImageBufAlgo::resize(out, in))
            return fail(msg, msg_size, out.geterror());
        return RB_OIIO_OK;
    } catch (const std::exception &e) {
        return fail(msg, msg_size, e.what());
    } catch (...) {
        return fail_unknown(msg, msg_size);
    }
}

extern "C" int rb_oiio_base64_encode(const void *data, size_t size, char *out, size_t out_size,
                                     char *msg, size_t msg_size) noexcept
{
    try {
        std::string s =
            OIIO::Strutil::base64_encode(OIIO::string_view(static_cast<const char *>(data), size));
        if (s.size() + 1 > out_size)
            return fail(msg, msg_size, "base64: the output buffer is too small");
        std::memcpy(out, s.c_str(), s.size() + 1);
        return RB_OIIO_OK;
    } catch (const std::exception &e) {
        return fail(msg, msg_size, e.what());
    } catch (...) {
        return fail_unknown(msg, msg_size);
    }
}

extern "C" int rb_oiio_input_open(const char *path, struct rb_oiio_input **out,
                                  struct rb_oiio_info *info, char *msg, size_t msg_size) noexcept
{
    try {
        quiet_debug();
        // Values as stored: no premultiplication of unassociated alpha (PNG) on read.
        OIIO::ImageSpec config;
        config.attribute("oiio:UnassociatedAlpha", 1);
        auto in = OIIO::ImageInput::open(path, &config);
        if (!in)
            return fail(msg, msg_size, OIIO::geterror());
        const OIIO::ImageSpec &spec = in->spec();
        if (spec.deep)
            return fail(msg, msg_size, "deep images are not supported");
        if (spec.depth > 1)
            return fail(msg, msg_size, "volume images are not supported");
        if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0)
            return fail(msg, msg_size, "image has no pixels");
        auto *h = new rb_oiio_input;
        h->spec = spec;
        h->in = std::move(in);
        info->width_px = uint32_t(spec.width);
        info->height_px = uint32_t(spec.height);
        info->channel_count = uint32_t(spec.nchannels);
        *out = h;
        return RB_OIIO_OK;
    } catch (const std::exception &e) {
        return fail(msg, msg_size, e.what());
    } catch (...) {
        return fail_unknown(msg, msg_size);
    }
}

extern "C" const char *rb_oiio_input_channel_name(const struct rb_oiio_input *in,
                                                  uint32_t i) noexcept
{
    if (!in || i >= in->spec.channelnames.size())
        return "";
    return in->spec.channelnames[i].c_str();
}

extern "C" int rb_oiio_input_read(struct rb_oiio_input *in, float *pixels, char *msg,
                                  size_t msg_size) noexcept
{
    try {
        if (!in->in->read_image(0, 0, 0, in->spec.nchannels, OIIO::TypeDesc::FLOAT, pixels))
            return fail(msg, msg_size, in->in->geterror());
        // A reader may log a problem and still return true; treat that as a failure too.
        if (in->in->has_error())
            return fail(msg, msg_size, in->in->geterror());
        return RB_OIIO_OK;
    } catch (const std::exception &e) {
        return fail(msg, msg_size, e.what());
    } catch (...) {
        return fail_unknown(msg, msg_size);
    }
}

extern "C" bool rb_oiio_input_attr(const struct rb_oiio_input *in, const char *name, char *out,
                                   size_t size) noexcept
{
    try {
        const OIIO::ParamValue *p = in->spec.find_attribute(name);
        if (!p)
            return false;
        std::string v = p->type() == OIIO::TypeString ? std::string(p->get_ustring().string())
                                                      : p->get_string(1024);
        if (size)
            std::snprintf(out, size, "%s", v.c_str());
        return true;
    } catch (...) {
        return false;
    }
}

extern "C" void rb_oiio_input_close(struct rb_oiio_input *in) noexcept
{
    if (!in)
        return;
    try {
        in->in->close();
        (void)in->in->geterror(); // clear, so OIIO does not report it at exit
    } catch (...) {
    }
    delete in;
}
