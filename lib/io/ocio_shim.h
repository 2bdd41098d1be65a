/* The C face of OpenColorIO: apply a config's display/view transform to float RGBA pixels.
 * Which config, display and view to use is io.c's decision. Private to lib/io. */
#ifndef RB_IO_OCIO_SHIM_H
#define RB_IO_OCIO_SHIM_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The shims' functions never throw; C++ sees that in their type. */
#ifndef RB_SHIM_NOEXCEPT
#ifdef __cplusplus
#define RB_SHIM_NOEXCEPT noexcept
#else
#define RB_SHIM_NOEXCEPT
#endif
#endif

/* Shim results: 0 is success; a failure fills msg (naming the config, display or view). */
#define RB_OCIO_OK 0
#define RB_OCIO_FAIL 1    /* the config does not load, or OCIO failed */
#define RB_OCIO_NO_NAME 2 /* the display or view is not in the config */

/* Transforms width*height RGBA float pixels in place from the config's scene_linear role to
 * display/view. display NULL or "": the config's default display; view NULL or "": that
 * display's default view. The resolved names are copied to display_out/view_out when given. */
/* OpenColorIO's version, e.g. "2.1.2". */
const char *rb_ocio_version(void) RB_SHIM_NOEXCEPT;

int rb_ocio_display_view_apply(const char *config_path, const char *display, const char *view,
                               float *rgba, uint32_t width_px, uint32_t height_px,
                               char *display_out, char *view_out, size_t name_size, char *msg,
                               size_t msg_size) RB_SHIM_NOEXCEPT;

/* The views of display (NULL or "": the config's default display) in the config, in its order,
 * each followed by '\n', into names (cut at size); the display's name to display_out. Fails as
 * rb_ocio_display_view_apply does for a config or display it cannot find. */
int rb_ocio_view_names(const char *config_path, const char *display, char *display_out, char *names,
                       size_t size, char *msg, size_t msg_size) RB_SHIM_NOEXCEPT;

#ifdef __cplusplus
}
#endif

#endif
