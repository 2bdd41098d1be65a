/* triangles: how many triangles each glTF file's default scene draws, every mesh counted once
 * per node that instances it (the Khronos validator's totalTriangleCount), as the loader reads
 * the file; and a scene of as many triangles as asked, for the scale test and make bench. A
 * measurement and a scene writer, never a test by itself.
 *
 *   triangles SCENE...                 prints "TRIANGLES SCENE", a line a file
 *   triangles write DIR COUNT [flat]   writes DIR/terrain.gltf, DIR/terrain.bin and the job
 *                                      DIR/terrain.yaml: a rolling terrain of at least COUNT
 *                                      triangles (an N x N grid of quads, two triangles each,
 *                                      N = ceil(sqrt(COUNT / 2))) over [-1, 1] in x and z, one
 *                                      indexed primitive; with normals (smooth: the loader keeps
 *                                      (N + 1)^2 vertices), or with "flat" without them (the
 *                                      loader gives each triangle three vertices of its own,
 *                                      6 N^2). The job: 64x48, frame 0, a point light above, a
 *                                      black environment, the camera looking down across it.
 *                                      Prints "TRIANGLES VERTICES", the loader's vertices.
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

/* The terrain's height and its gradient at (x, z): a few gentle waves, low enough that the
 * light above leaves no shadow on it, so a renderer's image depends on its shading alone. */
static double height(double x, double z, double *dx, double *dz)
{
    const double a = 0.06, b = 0.03;
    *dx = a * 5.0 * cos(5.0 * x) * cos(4.0 * z) + b * 11.0 * cos(11.0 * x + 7.0 * z);
    *dz = -a * 4.0 * sin(5.0 * x) * sin(4.0 * z) + b * 7.0 * cos(11.0 * x + 7.0 * z);
    return a * sin(5.0 * x) * cos(4.0 * z) + b * sin(11.0 * x + 7.0 * z);
}

static int fail(const char *what, const char *path)
{
    fprintf(stderr, "triangles: %s '%s': %s\n", what, path, strerror(errno));
    return 1;
}

static int write_terrain(const char *dir, uint64_t count, int flat)
{
    uint64_t n = (uint64_t)ceil(sqrt((double)(count ? count : 2) / 2.0));
    uint64_t v = n + 1, verts = v * v, tris = 2 * n * n;
    if (tris * 3 > UINT32_MAX / 4 || verts > UINT32_MAX) {
        fprintf(stderr, "triangles: %llu triangles are more than one glTF buffer holds\n",
                (unsigned long long)tris);
        return 2;
    }
    char path[4096];
    snprintf(path, sizeof(path), "%s/terrain.bin", dir);
    FILE *f = fopen(path, "wb");
    if (!f)
        return fail("cannot write", path);
    /* positions, normals (smooth only), then indices; a row at a time */
    float *row = malloc(v * 3 * sizeof(float));
    uint32_t *quads = malloc(n * 6 * sizeof(uint32_t));
    if (!row || !quads) {
        fprintf(stderr, "triangles: out of memory\n");
        fclose(f);
        free(row);
        free(quads);
        return 1;
    }
    float lo = 0, hi = 0;
    for (int attr = 0; attr < (flat ? 1 : 2); attr++)
        for (uint64_t j = 0; j < v; j++) {
            for (uint64_t i = 0; i < v; i++) {
                double x = -1.0 + 2.0 * (double)i / (double)n, z = -1.0 + 2.0 * (double)j / n;
                double dx, dz, y = height(x, z, &dx, &dz);
                float *o = &row[i * 3];
                if (attr == 0) {
                    o[0] = (float)x, o[1] = (float)y, o[2] = (float)z;
                    lo = o[1] < lo ? o[1] : lo;
                    hi = o[1] > hi ? o[1] : hi;
                } else {
                    double l = sqrt(dx * dx + 1.0 + dz * dz);
                    o[0] = (float)(-dx / l), o[1] = (float)(1.0 / l), o[2] = (float)(-dz / l);
                }
            }
            fwrite(row, sizeof(float), v * 3, f);
        }
    for (uint64_t j = 0; j < n; j++) {
        for (uint64_t i = 0; i < n; i++) {
            uint32_t a = (uint32_t)(j * v + i), *q = &quads[i * 6];
            q[0] = a, q[1] = a + (uint32_t)v, q[2] = a + 1;
            q[3] = a + 1, q[4] = a + (uint32_t)v, q[5] = a + (uint32_t)v + 1;
        }
        fwrite(quads, sizeof(uint32_t), n * 6, f);
    }
    free(row);
    free(quads);
    if (fclose(f) != 0)
        return fail("cannot write", path);

    uint64_t attr_bytes = verts * 12, index_bytes = tris * 3 * 4;
    uint64_t total = attr_bytes * (flat ? 1 : 2) + index_bytes;
    snprintf(path, sizeof(path), "%s/terrain.gltf", dir);
    if (!(f = fopen(path, "w")))
        return fail("cannot write", path);
    fprintf(f,
            "{\"asset\": {\"version\": \"2.0\"}, \"scene\": 0, \"scenes\": [{\"nodes\": [0]}],\n"
            " \"nodes\": [{\"mesh\": 0, \"name\": \"terrain\"}],\n"
            " \"materials\": [{\"name\": \"ground\", \"pbrMetallicRoughness\": "
            "{\"baseColorFactor\": [0.7, 0.6, 0.5, 1], \"metallicFactor\": 0, "
            "\"roughnessFactor\": 1}}],\n"
            " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0%s}, "
            "\"indices\": %d, \"material\": 0}]}],\n"
            " \"buffers\": [{\"byteLength\": %llu, \"uri\": \"terrain.bin\"}],\n"
            " \"bufferViews\": [{\"buffer\": 0, \"byteLength\": %llu}",
            flat ? "" : ", \"NORMAL\": 1", flat ? 1 : 2, (unsigned long long)total,
            (unsigned long long)attr_bytes);
    if (!flat)
        fprintf(f, ", {\"buffer\": 0, \"byteOffset\": %llu, \"byteLength\": %llu}",
                (unsigned long long)attr_bytes, (unsigned long long)attr_bytes);
    fprintf(f,
            ", {\"buffer\": 0, \"byteOffset\": %llu, \"byteLength\": %llu}],\n"
            " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": %llu, "
            "\"type\": \"VEC3\", \"min\": [-1, %.9g, -1], \"max\": [1, %.9g, 1]}",
            (unsigned long long)(attr_bytes * (flat ? 1 : 2)), (unsigned long long)index_bytes,
            (unsigned long long)verts, lo, hi);
    if (!flat)
        fprintf(f,
                ", {\"bufferView\": 1, \"componentType\": 5126, \"count\": %llu, "
                "\"type\": \"VEC3\"}",
                (unsigned long long)verts);
    fprintf(f,
            ", {\"bufferView\": %d, \"componentType\": 5125, \"count\": %llu, "
            "\"type\": \"SCALAR\"}]}\n",
            flat ? 1 : 2, (unsigned long long)(tris * 3));
    if (fclose(f) != 0)
        return fail("cannot write", path);

    snprintf(path, sizeof(path), "%s/terrain.yaml", dir);
    if (!(f = fopen(path, "w")))
        return fail("cannot write", path);
    fprintf(f, "scene: terrain.gltf\n"
               "output: out/frame.####.exr\n"
               "resolution: [64, 48]\n"
               "frames: {start: 0, end: 0, rate: 24}\n"
               "camera: {fov_y_deg: 50, keys: [{t: 0, position: [0, 1.3, 1.9], "
               "look_at: [0, 0, 0]}]}\n"
               "environment: {color: [0, 0, 0]}\n"
               "lights:\n"
               "  - {type: point, position: [0.3, 2.0, 0.4], intensity: 12}\n");
    if (fclose(f) != 0)
        return fail("cannot write", path);
    printf("%llu %llu\n", (unsigned long long)tris, (unsigned long long)(flat ? tris * 3 : verts));
    return 0;
}

int main(int argc, char **argv)
{
    if (argc >= 2 && strcmp(argv[1], "write") == 0) {
        char *end = NULL;
        unsigned long long count = argc >= 4 ? strtoull(argv[3], &end, 10) : 0;
        if ((argc != 4 && argc != 5) || !end || *end || count == 0 ||
            (argc == 5 && strcmp(argv[4], "flat") != 0)) {
            fprintf(stderr, "usage: triangles write DIR COUNT [flat]\n");
            return 2;
        }
        return write_terrain(argv[2], count, argc == 5);
    }
    if (argc < 2) {
        fprintf(stderr, "usage: triangles SCENE...\n       triangles write DIR COUNT [flat]\n");
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
