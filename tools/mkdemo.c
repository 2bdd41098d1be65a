/*
 * mkdemo: writes raybundle's own animated demo scene (jobs/demo/room.gltf + room.bin).
 * A Cornell-box room with a point light, an emissive ceiling panel, a TRS-animated box, a
 * skinned bending column and a camera, all in one 4 s looping animation called "Demo".
 * Plain C11 + libm; the output is byte-for-byte deterministic (little-endian buffer, "%.9g").
 * Usage: mkdemo OUTDIR
 */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846

/* glTF constants. */
#define GL_UNSIGNED_BYTE 5121
#define GL_UNSIGNED_SHORT 5123
#define GL_FLOAT 5126
#define GL_ARRAY_BUFFER 34962
#define GL_ELEMENT_ARRAY_BUFFER 34963

#define MAX_VIEWS 64
#define MAX_ACCESSORS 64
#define MAX_VERTS 512 /* per mesh; must stay <= 65536 for 16-bit indices */
#define MAX_INDICES 1024
#define BIN_CAP (256 * 1024)

/* One bufferView; each accessor gets its own, so no byteStride is ever needed. */
struct view {
    size_t offset, length;
    int target; /* 0: none (animation data, inverse bind matrices) */
};

struct accessor {
    int view;
    int component_type;
    size_t count;
    const char *type; /* "SCALAR", "VEC3", ... */
    int comps;        /* components per element */
    int has_minmax;
    double min[4], max[4]; /* float-exact values of the stored data */
};

/* The whole binary buffer and the glTF objects that index into it. */
struct demo {
    unsigned char bin[BIN_CAP];
    size_t bin_len;
    struct view views[MAX_VIEWS];
    int view_count;
    struct accessor accessors[MAX_ACCESSORS];
    int accessor_count;
};

/* Triangle soup under construction: positions, normals and 16-bit indices. */
struct geom {
    float pos[MAX_VERTS][3];
    float nrm[MAX_VERTS][3];
    size_t vert_count;
    uint16_t idx[MAX_INDICES];
    size_t index_count;
};

static void die(const char *fmt, ...)
{
    va_list ap;
    fputs("mkdemo: error: ", stderr);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    exit(1);
}

/* Reserves a 4-byte-aligned bufferView and returns its index. */
static int add_view(struct demo *d, size_t length, int target)
{
    if (d->view_count == MAX_VIEWS)
        die("too many bufferViews");
    size_t offset = (d->bin_len + 3) & ~(size_t)3;
    if (offset + length > BIN_CAP)
        die("buffer overflow (%zu bytes)", offset + length);
    memset(d->bin + d->bin_len, 0, offset - d->bin_len);
    d->bin_len = offset + length;
    d->views[d->view_count] = (struct view){.offset = offset, .length = length, .target = target};
    return d->view_count++;
}

static int add_accessor(struct demo *d, struct accessor a)
{
    if (d->accessor_count == MAX_ACCESSORS)
        die("too many accessors");
    d->accessors[d->accessor_count] = a;
    return d->accessor_count++;
}

static int comps_of(const char *type)
{
    if (!strcmp(type, "SCALAR"))
        return 1;
    if (!strcmp(type, "VEC3"))
        return 3;
    if (!strcmp(type, "VEC4"))
        return 4;
    if (!strcmp(type, "MAT4"))
        return 16;
    die("unknown accessor type '%s'", type);
    return 0;
}

/* Stores floats little-endian whatever the host, so the .bin is the same everywhere. */
static int add_floats(struct demo *d, const float *v, size_t count, const char *type, int target,
                      int with_minmax)
{
    int comps = comps_of(type);
    int vi = add_view(d, count * comps * 4, target);
    unsigned char *p = d->bin + d->views[vi].offset;
    struct accessor a = {.view = vi,
                         .component_type = GL_FLOAT,
                         .count = count,
                         .type = type,
                         .comps = comps,
                         .has_minmax = with_minmax};
    for (size_t i = 0; i < count * comps; i++) {
        uint32_t u;
        memcpy(&u, &v[i], 4);
        for (int b = 0; b < 4; b++)
            *p++ = (unsigned char)(u >> (8 * b));
    }
    if (with_minmax) {
        if (comps > 4)
            die("min/max for %s not supported", type);
        for (int c = 0; c < comps; c++) {
            a.min[c] = a.max[c] = v[c];
            for (size_t i = 1; i < count; i++) {
                double x = v[i * comps + c];
                a.min[c] = x < a.min[c] ? x : a.min[c];
                a.max[c] = x > a.max[c] ? x : a.max[c];
            }
        }
    }
    return add_accessor(d, a);
}

static int add_indices(struct demo *d, const uint16_t *idx, size_t count)
{
    int vi = add_view(d, count * 2, GL_ELEMENT_ARRAY_BUFFER);
    unsigned char *p = d->bin + d->views[vi].offset;
    for (size_t i = 0; i < count; i++) {
        *p++ = (unsigned char)(idx[i] & 0xff);
        *p++ = (unsigned char)(idx[i] >> 8);
    }
    return add_accessor(d, (struct accessor){.view = vi,
                                             .component_type = GL_UNSIGNED_SHORT,
                                             .count = count,
                                             .type = "SCALAR",
                                             .comps = 1});
}

static int add_joints(struct demo *d, const uint8_t (*j)[4], size_t count)
{
    int vi = add_view(d, count * 4, GL_ARRAY_BUFFER);
    memcpy(d->bin + d->views[vi].offset, j, count * 4);
    return add_accessor(d, (struct accessor){.view = vi,
                                             .component_type = GL_UNSIGNED_BYTE,
                                             .count = count,
                                             .type = "VEC4",
                                             .comps = 4});
}

/*
 * Appends an nu x nv grid of quads spanning origin + [0,1]*u + [0,1]*v. The quads wind
 * counter-clockwise seen from u x v, which is also the normal (glTF front faces are CCW).
 */
static void geom_grid(struct geom *g, const double o[3], const double u[3], const double v[3],
                      int nu, int nv)
{
    double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    size_t base = g->vert_count, added = (size_t)(nu + 1) * (nv + 1);

    /* MAX_VERTS also keeps every index inside UNSIGNED_SHORT. */
    if (base + added > MAX_VERTS)
        die("too many vertices");
    if (g->index_count + (size_t)nu * nv * 6 > MAX_INDICES)
        die("too many indices");
    for (int j = 0; j <= nv; j++) {
        for (int i = 0; i <= nu; i++) {
            double s = (double)i / nu, t = (double)j / nv;
            for (int c = 0; c < 3; c++) {
                g->pos[g->vert_count][c] = (float)(o[c] + s * u[c] + t * v[c]);
                g->nrm[g->vert_count][c] = (float)(n[c] / len);
            }
            g->vert_count++;
        }
    }
    for (int j = 0; j < nv; j++) {
        for (int i = 0; i < nu; i++) {
            uint16_t a = (uint16_t)(base + j * (nu + 1) + i);
            uint16_t b = (uint16_t)(a + 1), c = (uint16_t)(a + nu + 2), e = (uint16_t)(a + nu + 1);
            uint16_t quad[6] = {a, b, c, a, c, e};
            memcpy(&g->idx[g->index_count], quad, sizeof(quad));
            g->index_count += 6;
        }
    }
}

/* Mesh and node bookkeeping for the JSON writer. */
struct prim {
    const char *name;
    int position, normal, indices, joints, weights; /* accessor indices; -1: absent */
    int material;
};

/* Stores a geometry's positions (with min/max), normals and indices as one primitive. */
static void add_prim(struct demo *d, struct prim *out, const char *name, const struct geom *g,
                     int material)
{
    *out = (struct prim){.name = name, .material = material, .joints = -1, .weights = -1};
    out->position = add_floats(d, &g->pos[0][0], g->vert_count, "VEC3", GL_ARRAY_BUFFER, 1);
    out->normal = add_floats(d, &g->nrm[0][0], g->vert_count, "VEC3", GL_ARRAY_BUFFER, 0);
    out->indices = add_indices(d, g->idx, g->index_count);
}

/* Materials, in the order they are written. */
enum { MAT_WHITE, MAT_RED, MAT_GREEN, MAT_PANEL, MAT_BOX, MAT_COLUMN, MAT_COUNT };

/* Meshes, in the order they are written. */
enum {
    MESH_FLOOR,
    MESH_CEILING,
    MESH_BACK,
    MESH_LEFT,
    MESH_RIGHT,
    MESH_PANEL,
    MESH_BOX,
    MESH_COLUMN,
    MESH_COUNT
};

/* Nodes, in the order they are written. */
enum {
    NODE_FLOOR,
    NODE_CEILING,
    NODE_BACK,
    NODE_LEFT,
    NODE_RIGHT,
    NODE_PANEL,
    NODE_LIGHT,
    NODE_BOX,
    NODE_COLUMN,
    NODE_COLUMN_ROOT,
    NODE_COLUMN_TIP,
    NODE_CAMERA,
    NODE_COUNT
};

/* The scene's fixed numbers, kept here so the JSON writer and the geometry agree. */
static const double box_pos[3] = {-0.45, 0.25, -0.3};
static const double box_bob_y = 0.55;
static const double column_pos[3] = {0.45, 0.0, 0.1};
static const double column_half = 0.15, column_height = 1.2, column_tip_y = 0.6;
enum { COLUMN_SEGMENTS = 12, WALL_CELLS = 8 };

/* Accessors of the animation and skin, filled by build_* and read by write_gltf. */
struct anim_ids {
    int box_rot_t, box_rot_q, box_bob_t, box_bob_p, tip_t, tip_q, ibm;
};

static void build_room(struct demo *d, struct prim *p)
{
    static const struct {
        const char *name;
        double o[3], u[3], v[3];
        int material;
    } walls[] = {
        /* u x v points into the room. */
        {"Floor", {-1, 0, -1}, {0, 0, 2}, {2, 0, 0}, MAT_WHITE},
        {"Ceiling", {-1, 2, -1}, {2, 0, 0}, {0, 0, 2}, MAT_WHITE},
        {"BackWall", {-1, 0, -1}, {2, 0, 0}, {0, 2, 0}, MAT_WHITE},
        {"LeftWall", {-1, 0, -1}, {0, 2, 0}, {0, 0, 2}, MAT_RED},
        {"RightWall", {1, 0, -1}, {0, 0, 2}, {0, 2, 0}, MAT_GREEN},
    };
    static struct geom g;

    for (int w = 0; w < 5; w++) {
        g.vert_count = g.index_count = 0;
        geom_grid(&g, walls[w].o, walls[w].u, walls[w].v, WALL_CELLS, WALL_CELLS);
        add_prim(d, &p[MESH_FLOOR + w], walls[w].name, &g, walls[w].material);
    }

    /* The light panel sits 1 mm under the ceiling and faces down (-Y). */
    g.vert_count = g.index_count = 0;
    geom_grid(&g, (double[3]){-0.2, 1.999, -0.2}, (double[3]){0.4, 0, 0}, (double[3]){0, 0, 0.4}, 1,
              1);
    add_prim(d, &p[MESH_PANEL], "LightPanel", &g, MAT_PANEL);
}

static void build_box(struct demo *d, struct prim *p, struct anim_ids *ids)
{
    const double h = 0.25, e = 0.5;
    static const struct {
        double o[3];
        int u, v; /* axes (0 x, 1 y, 2 z) with u x v = outward normal */
    } faces[] = {
        {{1, -1, -1}, 1, 2},  /* +X */
        {{-1, -1, -1}, 2, 1}, /* -X */
        {{-1, 1, -1}, 2, 0},  /* +Y */
        {{-1, -1, -1}, 0, 2}, /* -Y */
        {{-1, -1, 1}, 0, 1},  /* +Z */
        {{-1, -1, -1}, 1, 0}, /* -Z */
    };
    static struct geom g;

    g.vert_count = g.index_count = 0;
    for (int f = 0; f < 6; f++) {
        double o[3], u[3] = {0, 0, 0}, v[3] = {0, 0, 0};
        for (int c = 0; c < 3; c++)
            o[c] = faces[f].o[c] * h;
        u[faces[f].u] = e;
        v[faces[f].v] = e;
        geom_grid(&g, o, u, v, 1, 1);
    }
    add_prim(d, &p[MESH_BOX], "SpinningBox", &g, MAT_BOX);

    /* A full turn about +Y in 8 steps of 45 degrees; key 8 is -identity, the same rotation
     * as key 0, so the loop is seamless and every step slerps the short way. */
    float t9[9], q9[9][4];
    for (int k = 0; k <= 8; k++) {
        double half = PI * k / 8.0;
        double s = sin(half), c = cos(half);
        t9[k] = (float)(0.5 * k);
        q9[k][0] = 0.0f;
        q9[k][1] = (float)(fabs(s) < 1e-12 ? 0.0 : s);
        q9[k][2] = 0.0f;
        q9[k][3] = (float)(fabs(c) < 1e-12 ? 0.0 : c);
    }
    ids->box_rot_t = add_floats(d, t9, 9, "SCALAR", 0, 1);
    ids->box_rot_q = add_floats(d, &q9[0][0], 9, "VEC4", 0, 0);

    /* Bob up and back down: y 0.25 -> 0.55 -> 0.25. */
    float t3[3] = {0.0f, 2.0f, 4.0f}, p3[3][3];
    for (int k = 0; k < 3; k++) {
        p3[k][0] = (float)box_pos[0];
        p3[k][1] = (float)(k == 1 ? box_bob_y : box_pos[1]);
        p3[k][2] = (float)box_pos[2];
    }
    ids->box_bob_t = add_floats(d, t3, 3, "SCALAR", 0, 1);
    ids->box_bob_p = add_floats(d, &p3[0][0], 3, "VEC3", 0, 0);
}

/*
 * The column is modelled in world space (its bind pose), standing on the floor. Its skinned
 * mesh node stays at the identity, so the inverse bind matrices are the inverse world
 * transforms of ColumnRoot (base) and ColumnTip (0.6 m up). Weights move from the root to
 * the tip with a smoothstep between rings 3 and 9 (y 0.3 .. 0.9 m), centred on the tip joint.
 */
static void build_column(struct demo *d, struct prim *p, struct anim_ids *ids)
{
    const double x0 = column_pos[0] - column_half, z0 = column_pos[2] - column_half;
    const double w = 2 * column_half, hgt = column_height;
    static struct geom g;
    static uint8_t joints[MAX_VERTS][4];
    static float weights[MAX_VERTS][4];

    g.vert_count = g.index_count = 0;
    /* Sides: grids of 1 x 12 (or 12 x 1) quads, outward normals. */
    geom_grid(&g, (double[3]){x0 + w, 0, z0}, (double[3]){0, hgt, 0}, (double[3]){0, 0, w},
              COLUMN_SEGMENTS, 1); /* +X */
    geom_grid(&g, (double[3]){x0, 0, z0}, (double[3]){0, 0, w}, (double[3]){0, hgt, 0}, 1,
              COLUMN_SEGMENTS); /* -X */
    geom_grid(&g, (double[3]){x0, 0, z0 + w}, (double[3]){w, 0, 0}, (double[3]){0, hgt, 0}, 1,
              COLUMN_SEGMENTS); /* +Z */
    geom_grid(&g, (double[3]){x0, 0, z0}, (double[3]){0, hgt, 0}, (double[3]){w, 0, 0},
              COLUMN_SEGMENTS, 1); /* -Z */
    geom_grid(&g, (double[3]){x0, hgt, z0}, (double[3]){0, 0, w}, (double[3]){w, 0, 0}, 1,
              1); /* top */
    geom_grid(&g, (double[3]){x0, 0, z0}, (double[3]){w, 0, 0}, (double[3]){0, 0, w}, 1,
              1); /* bottom */

    for (size_t i = 0; i < g.vert_count; i++) {
        /* Ring index from the height; weights are exact functions of it. */
        long ring = lround(g.pos[i][1] / (hgt / COLUMN_SEGMENTS));
        double t = (ring - 3) / 6.0;
        t = t < 0 ? 0 : t > 1 ? 1 : t;
        float tip = (float)(t * t * (3 - 2 * t));
        memset(joints[i], 0, 4);
        memset(weights[i], 0, sizeof(weights[i]));
        /* Zero-weight slots keep joint 0, as the validator expects. */
        if (tip == 0.0f) {
            weights[i][0] = 1.0f;
        } else if (tip == 1.0f) {
            joints[i][0] = 1;
            weights[i][0] = 1.0f;
        } else {
            joints[i][1] = 1;
            weights[i][0] = 1.0f - tip;
            weights[i][1] = tip;
        }
    }
    add_prim(d, &p[MESH_COLUMN], "BendingColumn", &g, MAT_COLUMN);
    p[MESH_COLUMN].joints = add_joints(d, (const uint8_t(*)[4])joints, g.vert_count);
    p[MESH_COLUMN].weights =
        add_floats(d, &weights[0][0], g.vert_count, "VEC4", GL_ARRAY_BUFFER, 0);

    /* Column-major inverse bind matrices: pure translations by minus the joint positions. */
    float ibm[2][16];
    for (int j = 0; j < 2; j++) {
        memset(ibm[j], 0, sizeof(ibm[j]));
        ibm[j][0] = ibm[j][5] = ibm[j][10] = ibm[j][15] = 1.0f;
        /* 0.0 - x rather than -x: no negative zero in the buffer. */
        ibm[j][12] = (float)(0.0 - column_pos[0]);
        ibm[j][13] = (float)(0.0 - (column_pos[1] + (j ? column_tip_y : 0.0)));
        ibm[j][14] = (float)(0.0 - column_pos[2]);
    }
    ids->ibm = add_floats(d, &ibm[0][0], 2, "MAT4", 0, 0);

    /* ColumnTip about +Z: 0, +30, 0, -30, 0 degrees at 0..4 s. */
    static const double deg[5] = {0, 30, 0, -30, 0};
    float t5[5], q5[5][4];
    for (int k = 0; k < 5; k++) {
        double half = deg[k] * PI / 360.0;
        t5[k] = (float)k;
        q5[k][0] = q5[k][1] = 0.0f;
        q5[k][2] = (float)sin(half);
        q5[k][3] = (float)cos(half);
    }
    ids->tip_t = add_floats(d, t5, 5, "SCALAR", 0, 1);
    ids->tip_q = add_floats(d, &q5[0][0], 5, "VEC4", 0, 0);
}

/* ---- JSON ---------------------------------------------------------------------------- */

/* Writes a list of doubles as "[a, b, c]" with the fixed "%.9g" format. */
static void json_vec(FILE *f, const double *v, int n)
{
    fputc('[', f);
    for (int i = 0; i < n; i++)
        fprintf(f, "%s%.9g", i ? ", " : "", v[i]);
    fputc(']', f);
}

static void write_accessors(FILE *f, const struct demo *d)
{
    fputs("  \"accessors\": [\n", f);
    for (int i = 0; i < d->accessor_count; i++) {
        const struct accessor *a = &d->accessors[i];
        fprintf(f,
                "    {\"bufferView\": %d, \"componentType\": %d, \"count\": %zu, "
                "\"type\": \"%s\"",
                a->view, a->component_type, a->count, a->type);
        if (a->has_minmax) {
            fputs(", \"min\": ", f);
            json_vec(f, a->min, a->comps);
            fputs(", \"max\": ", f);
            json_vec(f, a->max, a->comps);
        }
        fprintf(f, "}%s\n", i + 1 < d->accessor_count ? "," : "");
    }
    fputs("  ],\n", f);
}

static void write_views(FILE *f, const struct demo *d)
{
    fputs("  \"bufferViews\": [\n", f);
    for (int i = 0; i < d->view_count; i++) {
        const struct view *v = &d->views[i];
        fprintf(f, "    {\"buffer\": 0, \"byteOffset\": %zu, \"byteLength\": %zu", v->offset,
                v->length);
        if (v->target)
            fprintf(f, ", \"target\": %d", v->target);
        fprintf(f, "}%s\n", i + 1 < d->view_count ? "," : "");
    }
    fputs("  ],\n", f);
}

static void write_materials(FILE *f)
{
    static const struct {
        const char *name;
        double base[3], roughness;
        int is_emissive;
    } m[MAT_COUNT] = {
        [MAT_WHITE] = {"White", {0.73, 0.73, 0.73}, 0.9, 0},
        [MAT_RED] = {"Red", {0.65, 0.05, 0.05}, 0.9, 0},
        [MAT_GREEN] = {"Green", {0.12, 0.45, 0.15}, 0.9, 0},
        [MAT_PANEL] = {"LightPanel", {0.73, 0.73, 0.73}, 0.9, 1},
        [MAT_BOX] = {"SpinningBox", {0.8, 0.6, 0.2}, 0.5, 0},
        [MAT_COLUMN] = {"BendingColumn", {0.2, 0.35, 0.8}, 0.35, 0},
    };
    fputs("  \"materials\": [\n", f);
    for (int i = 0; i < MAT_COUNT; i++) {
        double base[4] = {m[i].base[0], m[i].base[1], m[i].base[2], 1.0};
        fprintf(f, "    {\"name\": \"%s\", \"pbrMetallicRoughness\": {\"baseColorFactor\": ",
                m[i].name);
        json_vec(f, base, 4);
        fprintf(f, ", \"metallicFactor\": %.9g, \"roughnessFactor\": %.9g}", 0.0, m[i].roughness);
        if (m[i].is_emissive)
            fputs(", \"emissiveFactor\": [1, 1, 1], \"extensions\": "
                  "{\"KHR_materials_emissive_strength\": {\"emissiveStrength\": 3}}",
                  f);
        fprintf(f, ", \"doubleSided\": false}%s\n", i + 1 < MAT_COUNT ? "," : "");
    }
    fputs("  ],\n", f);
}

static void write_meshes(FILE *f, const struct prim *p)
{
    fputs("  \"meshes\": [\n", f);
    for (int i = 0; i < MESH_COUNT; i++) {
        fprintf(f,
                "    {\"name\": \"%s\", \"primitives\": [{\"attributes\": {\"POSITION\": %d, "
                "\"NORMAL\": %d",
                p[i].name, p[i].position, p[i].normal);
        if (p[i].joints >= 0)
            fprintf(f, ", \"JOINTS_0\": %d, \"WEIGHTS_0\": %d", p[i].joints, p[i].weights);
        fprintf(f, "}, \"indices\": %d, \"material\": %d, \"mode\": 4}]}%s\n", p[i].indices,
                p[i].material, i + 1 < MESH_COUNT ? "," : "");
    }
    fputs("  ],\n", f);
}

static void write_nodes(FILE *f)
{
    const double light_pos[3] = {0, 1.8, 0}, tip_pos[3] = {0, column_tip_y, 0};
    const double camera_pos[3] = {0, 1, 3.6};

    fputs("  \"nodes\": [\n", f);
    /* Static meshes: walls and the light panel, mesh i on node i. */
    static const char *const names[] = {"Floor",    "Ceiling",   "BackWall",
                                        "LeftWall", "RightWall", "LightPanel"};
    for (int i = NODE_FLOOR; i <= NODE_PANEL; i++)
        fprintf(f, "    {\"name\": \"%s\", \"mesh\": %d},\n", names[i], i);

    fputs("    {\"name\": \"Light\", \"translation\": ", f);
    json_vec(f, light_pos, 3);
    fputs(", \"extensions\": {\"KHR_lights_punctual\": {\"light\": 0}}},\n", f);

    fprintf(f, "    {\"name\": \"SpinningBox\", \"mesh\": %d, \"translation\": ", MESH_BOX);
    json_vec(f, box_pos, 3);
    fputs("},\n", f);

    /* Skinned mesh: root-level, identity transform (glTF ignores it anyway). */
    fprintf(f, "    {\"name\": \"BendingColumn\", \"mesh\": %d, \"skin\": 0},\n", MESH_COLUMN);

    fprintf(
        f, "    {\"name\": \"ColumnRoot\", \"children\": [%d], \"translation\": ", NODE_COLUMN_TIP);
    json_vec(f, column_pos, 3);
    fputs("},\n", f);
    fputs("    {\"name\": \"ColumnTip\", \"translation\": ", f);
    json_vec(f, tip_pos, 3);
    fputs("},\n", f);

    fputs("    {\"name\": \"Camera\", \"camera\": 0, \"translation\": ", f);
    json_vec(f, camera_pos, 3);
    fputs("}\n", f);
    fputs("  ],\n", f);
}

static void write_animation(FILE *f, const struct anim_ids *a)
{
    const struct {
        int input, output, node;
        const char *path;
    } ch[] = {
        {a->box_rot_t, a->box_rot_q, NODE_BOX, "rotation"},
        {a->box_bob_t, a->box_bob_p, NODE_BOX, "translation"},
        {a->tip_t, a->tip_q, NODE_COLUMN_TIP, "rotation"},
    };
    const int n = (int)(sizeof(ch) / sizeof(ch[0]));

    fputs("  \"animations\": [\n    {\n      \"name\": \"Demo\",\n      \"channels\": [\n", f);
    for (int i = 0; i < n; i++)
        fprintf(f, "        {\"sampler\": %d, \"target\": {\"node\": %d, \"path\": \"%s\"}}%s\n", i,
                ch[i].node, ch[i].path, i + 1 < n ? "," : "");
    fputs("      ],\n      \"samplers\": [\n", f);
    for (int i = 0; i < n; i++)
        fprintf(f, "        {\"input\": %d, \"output\": %d, \"interpolation\": \"LINEAR\"}%s\n",
                ch[i].input, ch[i].output, i + 1 < n ? "," : "");
    fputs("      ]\n    }\n  ],\n", f);
}

static void write_gltf(FILE *f, const struct demo *d, const struct prim *p,
                       const struct anim_ids *a)
{
    fputs("{\n", f);
    fputs("  \"asset\": {\"version\": \"2.0\", \"generator\": \"raybundle mkdemo\"},\n", f);
    fputs("  \"extensionsUsed\": [\"KHR_lights_punctual\", \"KHR_materials_emissive_strength\"],\n",
          f);
    fputs("  \"extensions\": {\"KHR_lights_punctual\": {\"lights\": [{\"name\": \"Light\", "
          "\"type\": \"point\", \"color\": [1, 1, 1], \"intensity\": 6}]}},\n",
          f);
    fputs("  \"scene\": 0,\n", f);
    fprintf(f, "  \"scenes\": [{\"name\": \"Room\", \"nodes\": [");
    for (int i = 0, first = 1; i < NODE_COUNT; i++) {
        if (i == NODE_COLUMN_TIP)
            continue; /* a child of ColumnRoot */
        fprintf(f, "%s%d", first ? "" : ", ", i);
        first = 0;
    }
    fputs("]}],\n", f);
    write_nodes(f);
    fputs("  \"cameras\": [{\"name\": \"Camera\", \"type\": \"perspective\", \"perspective\": "
          "{\"yfov\": 0.7, \"znear\": 0.05, \"zfar\": 20}}],\n",
          f);
    fprintf(f,
            "  \"skins\": [{\"name\": \"ColumnSkin\", \"inverseBindMatrices\": %d, "
            "\"skeleton\": %d, \"joints\": [%d, %d]}],\n",
            a->ibm, NODE_COLUMN_ROOT, NODE_COLUMN_ROOT, NODE_COLUMN_TIP);
    write_animation(f, a);
    write_materials(f);
    write_meshes(f, p);
    write_accessors(f, d);
    write_views(f, d);
    fprintf(f, "  \"buffers\": [{\"uri\": \"room.bin\", \"byteLength\": %zu}]\n", d->bin_len);
    fputs("}\n", f);
}

static FILE *open_out(const char *dir, const char *name, char *path, size_t path_size)
{
    int n = snprintf(path, path_size, "%s/%s", dir, name);
    if (n < 0 || (size_t)n >= path_size)
        die("output path too long: '%s/%s'", dir, name);
    FILE *f = fopen(path, "wb");
    if (!f)
        die("cannot open '%s': %s", path, strerror(errno));
    return f;
}

static void close_out(FILE *f, const char *path)
{
    int bad = ferror(f);
    if (fclose(f) != 0 || bad)
        die("cannot write '%s': %s", path, strerror(errno));
}

int main(int argc, char **argv)
{
    static struct demo d;
    struct prim prims[MESH_COUNT];
    struct anim_ids ids;
    char path[4096];

    if (argc != 2 || argv[1][0] == '-') {
        fputs("usage: mkdemo OUTDIR\n"
              "Writes OUTDIR/room.gltf and OUTDIR/room.bin, raybundle's animated demo scene.\n",
              argc == 2 && (!strcmp(argv[1], "-h") || !strcmp(argv[1], "--help")) ? stdout
                                                                                  : stderr);
        return argc == 2 && (!strcmp(argv[1], "-h") || !strcmp(argv[1], "--help")) ? 0 : 2;
    }

    build_room(&d, prims);
    build_box(&d, prims, &ids);
    build_column(&d, prims, &ids);
    /* The buffer ends on a 4-byte boundary so byteLength equals the file size. */
    while (d.bin_len % 4)
        d.bin[d.bin_len++] = 0;

    FILE *f = open_out(argv[1], "room.bin", path, sizeof(path));
    if (fwrite(d.bin, 1, d.bin_len, f) != d.bin_len)
        die("cannot write '%s': %s", path, strerror(errno));
    close_out(f, path);

    f = open_out(argv[1], "room.gltf", path, sizeof(path));
    write_gltf(f, &d, prims, &ids);
    close_out(f, path);
    return 0;
}
