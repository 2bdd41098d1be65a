/* triangles: how many triangles each glTF file's default scene draws, every mesh counted once
 * per node that instances it (the Khronos validator's totalTriangleCount), as the loader reads
 * the file. make bench names its largest scene with it; a measurement, never a test.
 *
 *   triangles SCENE...    prints "TRIANGLES SCENE", a line a file
 */
#include <stdio.h>

#include "scene/scene.h"

static uint64_t count_triangles(const struct rb_scene *scene)
{
    uint64_t count = 0;
    for (uint32_t n = 0; n < scene->node_count; n++) {
        const struct rb_scene_node *node = &scene->nodes[n];
        if (!node->in_scene || node->mesh == RB_SCENE_NONE)
            continue;
        const struct rb_scene_mesh *mesh = &scene->meshes[node->mesh];
        for (uint32_t p = 0; p < mesh->primitive_count; p++)
            count += scene->primitives[mesh->first_primitive + p].index_count / 3;
    }
    return count;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: triangles SCENE...\n");
        return 2;
    }
    int status = 0;
    for (int i = 1; i < argc; i++) {
        struct rb_err err = RB_ERR_INIT;
        struct rb_scene *scene = NULL;
        if (rb_scene_load(argv[i], 0, &scene, &err)) {
            fprintf(stderr, "triangles: %s\n", err.msg);
            status = 1;
            continue;
        }
        printf("%llu %s\n", (unsigned long long)count_triangles(scene), argv[i]);
        rb_scene_destroy(scene);
    }
    return status;
}
