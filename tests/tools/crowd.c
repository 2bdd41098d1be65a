/* crowd: writes a scene with more triangles than a small BVH budget, for the hybrid integrator's
 * object selection (seed 003: occlusion relevance against traversal cost). A floor lit by a white
 * sky; eight finely tessellated spheres (960 triangles each) standing on it around the camera's
 * view, half of them inside it and half just outside, beside and behind the camera, where only
 * the BVH can find them; and 64 coarse boxes (12 triangles each, 4 m a side) on a ring 35 m away,
 * large for their triangles but small as seen from the camera.
 *
 *   crowd DIR    writes DIR/crowd.gltf, DIR/crowd.bin, DIR/crowd.yaml (a still hybrid shot of
 *                16 frames) and DIR/crowd-moving.yaml (12 frames, the camera moving left and
 *                closer to the spheres there)
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#define SLICES 32
#define STACKS 16
#define SPHERE_VERTS ((SLICES + 1) * (STACKS + 1))
#define SPHERE_TRIS (SLICES * (2 * STACKS - 2))
#define BOX_VERTS 24
#define BOX_TRIS 12
#define FLOOR_VERTS 4
#define FLOOR_TRIS 2
#define NEAR_COUNT 8
#define FAR_COUNT 64

static const double pi = 3.14159265358979323846;

/* Each mesh: positions and normals (3 floats a vertex), then 32-bit indices. */
struct mesh {
    float pos[SPHERE_VERTS * 3], nrm[SPHERE_VERTS * 3];
    uint32_t idx[SPHERE_TRIS * 3];
    uint32_t verts, tris;
};

static void vert(struct mesh *m, float x, float y, float z, float nx, float ny, float nz)
{
    float *p = &m->pos[m->verts * 3], *n = &m->nrm[m->verts * 3];
    p[0] = x, p[1] = y, p[2] = z;
    n[0] = nx, n[1] = ny, n[2] = nz;
    m->verts++;
}

static void tri(struct mesh *m, uint32_t a, uint32_t b, uint32_t c)
{
    uint32_t *t = &m->idx[m->tris * 3];
    t[0] = a, t[1] = b, t[2] = c;
    m->tris++;
}

static void sphere(struct mesh *m, float r)
{
    for (int j = 0; j <= STACKS; j++)
        for (int i = 0; i <= SLICES; i++) {
            double th = pi * j / STACKS, ph = 2.0 * pi * i / SLICES;
            float nx = (float)(sin(th) * cos(ph)), ny = (float)cos(th),
                  nz = (float)(-sin(th) * sin(ph));
            vert(m, r * nx, r * ny, r * nz, nx, ny, nz);
        }
    for (uint32_t j = 0; j < STACKS; j++)
        for (uint32_t i = 0; i < SLICES; i++) {
            uint32_t a = j * (SLICES + 1) + i, b = a + 1, c = a + SLICES + 1, d = c + 1;
            if (j != 0)
                tri(m, a, c, b);
            if (j != STACKS - 1)
                tri(m, b, c, d);
        }
}

/* A box of side s standing on y = 0, flat normals. */
static void box(struct mesh *m, float s)
{
    static const int axes[6][3] = {{0, 1, 2}, {0, 1, 2}, {1, 2, 0},
                                   {1, 2, 0}, {2, 0, 1}, {2, 0, 1}};
    for (int f = 0; f < 6; f++) {
        int n = axes[f][0], u = axes[f][1], v = axes[f][2];
        float sign = f % 2 ? -1.0f : 1.0f;
        uint32_t base = m->verts;
        for (int k = 0; k < 4; k++) {
            float p[3], nn[3] = {0, 0, 0};
            p[n] = sign * s / 2;
            p[u] = (k == 1 || k == 2 ? 1 : -1) * s / 2;
            p[v] = (k >= 2 ? 1 : -1) * s / 2 * sign;
            nn[n] = sign;
            vert(m, p[0], p[1] + s / 2, p[2], nn[0], nn[1], nn[2]);
        }
        tri(m, base, base + 1, base + 2);
        tri(m, base, base + 2, base + 3);
    }
}

static void floor_quad(struct mesh *m, float half)
{
    vert(m, -half, 0, -half, 0, 1, 0);
    vert(m, -half, 0, half, 0, 1, 0);
    vert(m, half, 0, half, 0, 1, 0);
    vert(m, half, 0, -half, 0, 1, 0);
    tri(m, 0, 1, 2);
    tri(m, 0, 2, 3);
}

/* Writes m into bin at offset at and its three buffer views' JSON at views + *len; returns the
 * bytes written. */
static size_t put(FILE *bin, char *views, size_t cap, size_t *len, const struct mesh *m, size_t at)
{
    fwrite(m->pos, sizeof(float), (size_t)m->verts * 3, bin);
    fwrite(m->nrm, sizeof(float), (size_t)m->verts * 3, bin);
    fwrite(m->idx, sizeof(uint32_t), (size_t)m->tris * 3, bin);
    size_t vb = (size_t)m->verts * 12, ib = (size_t)m->tris * 12;
    *len += (size_t)snprintf(views + *len, cap - *len,
                             "%s{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu},"
                             "{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu},"
                             "{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu}",
                             *len ? "," : "", at, vb, at + vb, vb, at + 2 * vb, ib);
    return 2 * vb + ib;
}

/* A hybrid job over crowd.gltf: frames 0 to last, the camera still at its first key unless
 * more_keys adds some. */
static int write_job(const char *dir, const char *name, int last, const char *more_keys)
{
    char path[4096];
    snprintf(path, sizeof(path), "%s/%s.yaml", dir, name);
    FILE *f = fopen(path, "w");
    if (!f) {
        perror(path);
        return 1;
    }
    fprintf(f,
            "scene: crowd.gltf\n"
            "output: %s/frame.####.exr\n"
            "resolution: [96, 54]\n"
            "frames: {start: 0, end: %d, rate: 24}\n"
            "camera:\n"
            "  fov_y_deg: 40\n"
            "  keys: [{t: 0, position: [0, 1.6, 4], look_at: [0, 0.3, 0]}%s]\n"
            "environment: {color: [1, 1, 1], intensity: 1}\n"
            "default_light: off\n"
            "integrator: {name: hybrid}\n",
            name, last, more_keys);
    if (fclose(f) != 0) {
        perror(path);
        return 1;
    }
    return 0;
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: crowd DIR\n");
        return 2;
    }
    static struct mesh meshes[3];
    floor_quad(&meshes[0], 20.0f);
    sphere(&meshes[1], 0.4f);
    box(&meshes[2], 4.0f);
    char path[4096];
    snprintf(path, sizeof(path), "%s/crowd.bin", argv[1]);
    FILE *bin = fopen(path, "wb");
    if (!bin) {
        perror(path);
        return 1;
    }
    char view_text[1024];
    size_t at = 0, len = 0;
    for (int i = 0; i < 3; i++)
        at += put(bin, view_text, sizeof(view_text), &len, &meshes[i], at);
    if (fclose(bin) != 0) {
        perror(path);
        return 1;
    }

    snprintf(path, sizeof(path), "%s/crowd.gltf", argv[1]);
    FILE *f = fopen(path, "w");
    if (!f) {
        perror(path);
        return 1;
    }
    /* The camera at (0, 1.6, 4) looks at (0, 0.3, 0); the spheres stand on the floor. */
    static const float near[NEAR_COUNT][2] = {{-1.0f, 0.0f}, {1.0f, 0.3f},  {0.0f, -1.0f},
                                              {0.3f, 1.2f},  {-2.8f, 1.5f}, {2.8f, 1.5f},
                                              {-1.5f, 3.5f}, {1.5f, 3.5f}};
    fprintf(f, "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[");
    for (int i = 0; i < 1 + NEAR_COUNT + FAR_COUNT; i++)
        fprintf(f, "%s%d", i ? "," : "", i);
    fprintf(f, "]}],\"nodes\":[{\"name\":\"floor\",\"mesh\":0}");
    for (int i = 0; i < NEAR_COUNT; i++)
        fprintf(f, ",{\"name\":\"near%d\",\"mesh\":1,\"translation\":[%g,0.4,%g]}", i, near[i][0],
                near[i][1]);
    for (int i = 0; i < FAR_COUNT; i++) {
        double a = 2.0 * pi * (i + 0.5) / FAR_COUNT;
        fprintf(f, ",{\"name\":\"far%d\",\"mesh\":2,\"translation\":[%.4f,0,%.4f]}", i,
                35.0 * cos(a), 4.0 + 35.0 * sin(a));
    }
    fprintf(f, "],\"meshes\":[");
    for (int i = 0; i < 3; i++)
        fprintf(f,
                "%s{\"primitives\":[{\"attributes\":{\"POSITION\":%d,\"NORMAL\":%d},"
                "\"indices\":%d,\"material\":%d}]}",
                i ? "," : "", 3 * i, 3 * i + 1, 3 * i + 2, i);
    fprintf(f, "],\"materials\":["
               "{\"name\":\"floor\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.6,0.6,0.6,1],"
               "\"metallicFactor\":0,\"roughnessFactor\":1}},"
               "{\"name\":\"sphere\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.8,0.2,0.1,1],"
               "\"metallicFactor\":0,\"roughnessFactor\":1}},"
               "{\"name\":\"box\",\"pbrMetallicRoughness\":{\"baseColorFactor\":[0.5,0.5,0.5,1],"
               "\"metallicFactor\":0,\"roughnessFactor\":1}}],");
    fprintf(f, "\"buffers\":[{\"byteLength\":%zu,\"uri\":\"crowd.bin\"}],\"bufferViews\":[%s],", at,
            view_text);
    fprintf(f, "\"accessors\":[");
    for (int i = 0; i < 3; i++) {
        const struct mesh *m = &meshes[i];
        float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
        for (uint32_t v = 0; v < m->verts; v++)
            for (int c = 0; c < 3; c++) {
                lo[c] = fminf(lo[c], m->pos[v * 3 + c]);
                hi[c] = fmaxf(hi[c], m->pos[v * 3 + c]);
            }
        fprintf(f,
                "%s{\"bufferView\":%d,\"componentType\":5126,\"count\":%u,\"type\":\"VEC3\","
                "\"min\":[%.9g,%.9g,%.9g],\"max\":[%.9g,%.9g,%.9g]},"
                "{\"bufferView\":%d,\"componentType\":5126,\"count\":%u,\"type\":\"VEC3\"},"
                "{\"bufferView\":%d,\"componentType\":5125,\"count\":%u,\"type\":\"SCALAR\"}",
                i ? "," : "", 3 * i, m->verts, lo[0], lo[1], lo[2], hi[0], hi[1], hi[2], 3 * i + 1,
                m->verts, 3 * i + 2, m->tris * 3);
    }
    fprintf(f, "]}\n");
    if (fclose(f) != 0) {
        perror(path);
        return 1;
    }

    return write_job(argv[1], "crowd", 15, "") ||
           write_job(argv[1], "crowd-moving", 11,
                     ", {t: 0.5, position: [-3, 1.6, 0.5], look_at: [0, 0.3, 0]}");
}
