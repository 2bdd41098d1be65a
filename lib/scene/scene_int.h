/* Private to lib/scene: helpers shared by scene.c, anim.c, camera.c and lights.c. */
#ifndef RB_SCENE_SCENE_INT_H
#define RB_SCENE_SCENE_INT_H

#include "scene/scene.h"

/* Writes the node indices with every parent before its children into order (node_count
 * entries). Fails with RB_E_INVALID when a parent index is out of range or the parents form a
 * cycle. */
enum rb_status rb_scene_node_order(const struct rb_scene *scene, uint32_t *order,
                                   struct rb_err *err);

/* The average linear RGB of texture tex (sRGB-encoded, as emissive textures are), in a fixed
 * order; white when tex is RB_SCENE_NONE or empty, so that a factor stands alone. */
void rb_scene_texture_average(const struct rb_scene *scene, uint32_t tex, double out[3]);

/* "kind 'name'", or "kind index" for an unnamed object, into buf (for messages). */
const char *rb_scene_label(char *buf, size_t size, const char *kind, const char *name,
                           size_t index);

#endif
