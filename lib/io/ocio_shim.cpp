// OpenColorIO behind a C interface (ocio_shim.h): load a config, resolve a display and view,
// apply the scene_linear -> display/view transform on the CPU. extern "C", noexcept; every
// exception becomes a message that names the config.
#include "io/ocio_shim.h"

#include <OpenColorIO/OpenColorIO.h>

#include <cstdio>
#include <cstring>
#include <exception>
#include <string>

namespace OCIO = OCIO_NAMESPACE;

namespace
{

int fail(char *msg, size_t msg_size, const std::string &text, int code = RB_OCIO_FAIL)
{
    std::string t = text;
    while (!t.empty() && (t.back() == '\n' || t.back() == ' '))
        t.pop_back();
    for (char &c : t) // OCIO's messages can span lines; ours are one line
        if (c == '\n')
            c = ' ';
    if (msg && msg_size)
        std::snprintf(msg, msg_size, "%s", t.c_str());
    return code;
}

bool is_set(const char *s)
{
    return s && *s;
}

std::string join_displays(const OCIO::ConstConfigRcPtr &config)
{
    std::string s;
    for (int i = 0; i < config->getNumDisplays(); i++)
        s += std::string(i ? ", " : "") + config->getDisplay(i);
    return s;
}

std::string join_views(const OCIO::ConstConfigRcPtr &config, const char *display)
{
    std::string s;
    for (int i = 0; i < config->getNumViews(display); i++)
        s += std::string(i ? ", " : "") + config->getView(display, i);
    return s;
}

void copy_name(char *dst, size_t size, const char *src)
{
    if (dst && size)
        std::snprintf(dst, size, "%s", src);
}

/* The config at config_path, validated, into config, and the display (the config's default
 * when none is set) into disp; RB_OCIO_OK, or a failure with the displays it has. Throws what
 * OpenColorIO throws, for the callers' catch. */
int open_display(const char *config_path, const char *display, const std::string &where,
                 OCIO::ConstConfigRcPtr &config, std::string &disp, char *msg, size_t msg_size)
{
    config = OCIO::Config::CreateFromFile(config_path);
    config->validate();
    disp = is_set(display) ? display : config->getDefaultDisplay();
    for (int i = 0; i < config->getNumDisplays(); i++)
        if (disp == config->getDisplay(i))
            return RB_OCIO_OK;
    return fail(msg, msg_size,
                "ocio: display '" + disp + "' not found in " + where +
                    " (has: " + join_displays(config) + ")",
                RB_OCIO_NO_NAME);
}

} // namespace

extern "C" const char *rb_ocio_version(void) noexcept
{
    return OCIO::GetVersion();
}

extern "C" int rb_ocio_display_view_apply(const char *config_path, const char *display,
                                          const char *view, float *rgba, uint32_t width_px,
                                          uint32_t height_px, char *display_out, char *view_out,
                                          size_t name_size, char *msg, size_t msg_size) noexcept
{
    const std::string where = std::string("config '") + config_path + "'";
    try {
        OCIO::ConstConfigRcPtr config;
        std::string disp;
        int rc = open_display(config_path, display, where, config, disp, msg, msg_size);
        if (rc != RB_OCIO_OK)
            return rc;

        std::string v = is_set(view) ? view : config->getDefaultView(disp.c_str());
        bool found = false;
        for (int i = 0; i < config->getNumViews(disp.c_str()) && !found; i++)
            found = v == config->getView(disp.c_str(), i);
        if (!found)
            return fail(msg, msg_size,
                        "ocio: view '" + v + "' not found for display '" + disp + "' in " + where +
                            " (has: " + join_views(config, disp.c_str()) + ")",
                        RB_OCIO_NO_NAME);

        OCIO::DisplayViewTransformRcPtr t = OCIO::DisplayViewTransform::Create();
        t->setSrc(OCIO::ROLE_SCENE_LINEAR);
        t->setDisplay(disp.c_str());
        t->setView(v.c_str());
        OCIO::ConstProcessorRcPtr proc = config->getProcessor(t);
        OCIO::ConstCPUProcessorRcPtr cpu = proc->getDefaultCPUProcessor();
        OCIO::PackedImageDesc img(rgba, long(width_px), long(height_px), 4);
        cpu->apply(img);

        copy_name(display_out, name_size, disp.c_str());
        copy_name(view_out, name_size, v.c_str());
        return RB_OCIO_OK;
    } catch (const std::exception &e) {
        return fail(msg, msg_size, "ocio: " + where + ": " + e.what());
    } catch (...) {
        return fail(msg, msg_size, "ocio: " + where + ": unknown exception");
    }
}

extern "C" int rb_ocio_view_names(const char *config_path, const char *display, char *display_out,
                                  char *names, size_t size, char *msg, size_t msg_size) noexcept
{
    const std::string where = std::string("config '") + config_path + "'";
    try {
        OCIO::ConstConfigRcPtr config;
        std::string disp;
        int rc = open_display(config_path, display, where, config, disp, msg, msg_size);
        if (rc != RB_OCIO_OK)
            return rc;
        std::string list;
        for (int i = 0; i < config->getNumViews(disp.c_str()); i++)
            list += std::string(config->getView(disp.c_str(), i)) + "\n";
        copy_name(names, size, list.c_str());
        copy_name(display_out, 256, disp.c_str());
        return RB_OCIO_OK;
    } catch (const std::exception &e) {
        return fail(msg, msg_size, "ocio: " + where + ": " + e.what());
    } catch (...) {
        return fail(msg, msg_size, "ocio: " + where + ": unknown exception");
    }
}
