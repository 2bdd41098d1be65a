/* Fuzz target for the glTF loader: any bytes, as a .glb and as a .gltf, strict and lenient, must
 * load or fail with a message, never crash. The loader reads files (external buffers and images
 * are resolved beside them), so each input goes through a temporary file. Built like
 * fuzz_job.c. */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

#include "scene/scene.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const char *const ext[] = {"glb", "gltf"};
    rb_log_set_level(RB_LOG_ERROR);
    for (int i = 0; i < 2; i++) {
        char path[256];
        snprintf(path, sizeof(path), "%s/rb-fuzz-scene.%ld.%s",
                 getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp", (long)getpid(), ext[i]);
        FILE *f = fopen(path, "wb");
        if (!f)
            return 0;
        fwrite(data, 1, size, f);
        fclose(f);
        for (unsigned flags = 0; flags <= RB_SCENE_LOAD_LENIENT; flags += RB_SCENE_LOAD_LENIENT) {
            struct rb_scene *scene = NULL;
            struct rb_err err = RB_ERR_INIT;
            if (rb_scene_load(path, flags, &scene, &err) != RB_OK)
                continue;
            struct rb_scene_pose *pose = NULL;
            if (rb_scene_pose_create(scene, &pose, &err) == RB_OK) {
                uint32_t clips[4], n = 0;
                struct rb_job job = {0};
                if (rb_scene_select_clips(scene, &job, clips, 4, &n, &err) == RB_OK) {
                    struct rb_anim_selection sel = {clips, n, 0.0, 1.0, true};
                    rb_scene_evaluate(scene, &sel, 0.37, pose);
                }
                rb_scene_pose_destroy(pose);
            }
            rb_scene_destroy(scene);
        }
        unlink(path);
    }
    return 0;
}
