/* analytic: the analytic-light test's scene writer and checker.
 *   analytic scene DIR         writes DIR/plane.gltf: a 20 m Lambertian floor (albedo 0.5,
 *                              KHR_materials_specular factor 0) and a 0.5 m occluder quad at
 *                              height 1 centred on (1.5, 1, 0); glossy.gltf and metal.gltf;
 *                              and the jobs point.yaml, spot.yaml, sun.yaml, glossy.yaml,
 *                              metal.yaml and lights.yaml (point and spot together), written
 *                              from the same constants the checks below use
 *   analytic point EXR         checks the point-light render: radiance I cos(theta)/r^2 albedo/pi
 *                              within 1% on lit floor pixels, 0 inside the occluder's shadow
 *   analytic spot EXR          checks the spot-light render: lit inside the inner cone, dark
 *                              outside the outer cone
 *   analytic sun EXR           checks a directional light straight down (3 lux): E albedo/pi,
 *                              and the occluder's shadow right under it
 *   analytic sky EXR           checks a view of a constant environment (0.2 0.4 0.8, intensity
 *                              2): every pixel 0.4 0.8 1.6 with alpha 0
 *   analytic glossy|metal EXR  checks glossy.gltf (dielectric, roughness 0.4) and metal.gltf
 *                              (metallic, roughness 0.5) under the point light against the glTF
 *                              BRDF evaluated here in double precision
 * The camera and lights are those of tests/integration/t0040-analytic.sh; the ray for a pixel
 * is computed here independently of the renderer (double precision, own look-at). Prints TAP. */
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/io.h"

#define PI 3.14159265358979323846

/* Camera and lights, mirrored in the test's job files. */
static const double cam_pos[3] = {0.0, 6.0, 4.0};
static const double cam_target[3] = {0.0, 0.0, 0.0};
static const double fov_y_deg = 60.0;
static const double albedo = 0.5;
static const double point_pos[3] = {0.0, 2.0, 0.0};
static const double point_intensity = 10.0;
static const double spot_pos[3] = {-2.0, 2.0, 0.0};
static const double spot_intensity = 20.0;
static const double spot_inner_deg = 20.0, spot_outer_deg = 30.0;
static const double sun_lux = 3.0; /* a directional light straight down */

static int test_no;
static int failures;

static void check(int ok, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void check(int ok, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    printf("%s %d - ", ok ? "ok" : "not ok", ++test_no);
    vprintf(fmt, ap);
    printf("\n");
    va_end(ap);
    if (!ok)
        failures++;
}

static void sub(const double a[3], const double b[3], double o[3])
{
    for (int i = 0; i < 3; i++)
        o[i] = a[i] - b[i];
}

static void cross(const double a[3], const double b[3], double o[3])
{
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}

static void normalize(double v[3])
{
    double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int i = 0; i < 3; i++)
        v[i] /= l;
}

/* The floor point (y = 0) seen through pixel (x, y); returns 0 when the ray misses it. */
static int floor_point(int px, int py, int w, int h, double out[3])
{
    double f[3], r[3], u[3], up[3] = {0, 1, 0};
    sub(cam_target, cam_pos, f);
    normalize(f);
    cross(f, up, r);
    normalize(r);
    cross(r, f, u);
    double t = tan(fov_y_deg * PI / 360.0), aspect = (double)w / h;
    double nx = ((px + 0.5) / w * 2.0 - 1.0) * t * aspect;
    double ny = (1.0 - (py + 0.5) / h * 2.0) * t;
    double d[3];
    for (int i = 0; i < 3; i++)
        d[i] = f[i] + r[i] * nx + u[i] * ny;
    if (d[1] >= 0.0)
        return 0;
    double s = -cam_pos[1] / d[1];
    for (int i = 0; i < 3; i++)
        out[i] = cam_pos[i] + s * d[i];
    return fabs(out[0]) < 9.5 && fabs(out[2]) < 9.5;
}

/* Radiance from a point light of intensity I on the Lambertian floor. */
static double lambert(const double light[3], double intensity, const double p[3])
{
    double d[3];
    sub(light, p, d);
    double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    double cos_t = d[1] / sqrt(r2);
    return intensity * cos_t / r2 * albedo / PI;
}

/* The glTF 2.0 metallic-roughness BRDF (spec appendix B) times cos, written here in double
 * independently of the shaders: Lambert + GGX, Smith height-correlated, Schlick. */
static double gltf_brdf_cos(double metallic, double roughness, const double n[3], const double v[3],
                            const double l[3])
{
    double h[3] = {v[0] + l[0], v[1] + l[1], v[2] + l[2]};
    normalize(h);
    double ndl = n[0] * l[0] + n[1] * l[1] + n[2] * l[2];
    double ndv = n[0] * v[0] + n[1] * v[1] + n[2] * v[2];
    double ndh = n[0] * h[0] + n[1] * h[1] + n[2] * h[2];
    double vdh = v[0] * h[0] + v[1] * h[1] + v[2] * h[2];
    if (ndl <= 0.0)
        return 0.0;
    double a = roughness * roughness, a2 = a * a;
    double f0 = 0.04 * (1.0 - metallic) + albedo * metallic;
    double F = f0 + (1.0 - f0) * pow(1.0 - vdh, 5.0);
    double dd = ndh * ndh * (a2 - 1.0) + 1.0;
    double D = a2 / (PI * dd * dd);
    double V =
        0.5 / (ndl * sqrt(ndv * ndv * (1.0 - a2) + a2) + ndv * sqrt(ndl * ndl * (1.0 - a2) + a2));
    double c_diff = albedo * (1.0 - metallic);
    return ((1.0 - F) * c_diff / PI + F * D * V) * ndl;
}

static int write_scene(const char *dir, const char *name, double metallic, double roughness,
                       int lambert)
{
    /* Two quads: floor (4 verts) and occluder (4 verts), normals +Y, indices 6 each. */
    float pos[8][3] = {{-10, 0, -10},     {10, 0, -10},       {10, 0, 10},
                       {-10, 0, 10},      {1.25f, 1, -0.25f}, {1.75f, 1, -0.25f},
                       {1.75f, 1, 0.25f}, {1.25f, 1, 0.25f}};
    float nrm[8][3];
    uint16_t idx[12] = {0, 2, 1, 0, 3, 2, 0, 2, 1, 0, 3, 2};
    for (int i = 0; i < 8; i++)
        nrm[i][0] = 0, nrm[i][1] = 1, nrm[i][2] = 0;
    unsigned char buf[sizeof(pos) + sizeof(nrm) + sizeof(idx)];
    memcpy(buf, pos, sizeof(pos));
    memcpy(buf + sizeof(pos), nrm, sizeof(nrm));
    memcpy(buf + sizeof(pos) + sizeof(nrm), idx, sizeof(idx));
    static const char b64[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    char enc[4 * ((sizeof(buf) + 2) / 3) + 1];
    size_t e = 0;
    for (size_t i = 0; i < sizeof(buf); i += 3) {
        unsigned v = buf[i] << 16;
        if (i + 1 < sizeof(buf))
            v |= buf[i + 1] << 8;
        if (i + 2 < sizeof(buf))
            v |= buf[i + 2];
        enc[e++] = b64[(v >> 18) & 63];
        enc[e++] = b64[(v >> 12) & 63];
        enc[e++] = i + 1 < sizeof(buf) ? b64[(v >> 6) & 63] : '=';
        enc[e++] = i + 2 < sizeof(buf) ? b64[v & 63] : '=';
    }
    enc[e] = '\0';
    char path[4096];
    snprintf(path, sizeof(path), "%s/%s", dir, name);
    FILE *f = fopen(path, "w");
    if (!f) {
        perror(path);
        return 1;
    }
    fprintf(
        f,
        "{\"asset\":{\"version\":\"2.0\"},\"extensionsUsed\":[\"KHR_materials_specular\"],"
        "\"scene\":0,\"scenes\":[{\"nodes\":[0,1]}],"
        "\"nodes\":[{\"mesh\":0,\"name\":\"Floor\"},{\"mesh\":1,\"name\":\"Occluder\"}],"
        "\"meshes\":[{\"primitives\":[{\"attributes\":{\"POSITION\":0,\"NORMAL\":2},"
        "\"indices\":4,\"material\":0}]},"
        "{\"primitives\":[{\"attributes\":{\"POSITION\":1,\"NORMAL\":3},\"indices\":5,"
        "\"material\":0}]}],"
        "\"materials\":[{\"name\":\"Floor\",\"doubleSided\":true,"
        "\"pbrMetallicRoughness\":{\"baseColorFactor\":[%g,%g,%g,1],\"metallicFactor\":%g,"
        "\"roughnessFactor\":%g}%s}],"
        "\"buffers\":[{\"byteLength\":%zu,\"uri\":\"data:application/octet-stream;base64,%s\"}],"
        "\"bufferViews\":[{\"buffer\":0,\"byteOffset\":0,\"byteLength\":96},"
        "{\"buffer\":0,\"byteOffset\":96,\"byteLength\":96},"
        "{\"buffer\":0,\"byteOffset\":192,\"byteLength\":24}],"
        "\"accessors\":["
        "{\"bufferView\":0,\"byteOffset\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\","
        "\"min\":[-10,0,-10],\"max\":[10,0,10]},"
        "{\"bufferView\":0,\"byteOffset\":48,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\","
        "\"min\":[1.25,1,-0.25],\"max\":[1.75,1,0.25]},"
        "{\"bufferView\":1,\"byteOffset\":0,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
        "{\"bufferView\":1,\"byteOffset\":48,\"componentType\":5126,\"count\":4,\"type\":\"VEC3\"},"
        "{\"bufferView\":2,\"byteOffset\":0,\"componentType\":5123,\"count\":6,\"type\":\"SCALAR\"}"
        ","
        "{\"bufferView\":2,\"byteOffset\":12,\"componentType\":5123,\"count\":6,\"type\":"
        "\"SCALAR\"}"
        "]}\n",
        albedo, albedo, albedo, metallic, roughness,
        lambert ? ",\"extensions\":{\"KHR_materials_specular\":{\"specularFactor\":0}}" : "",
        sizeof(buf), enc);
    return fclose(f) != 0;
}

/* One job over scene with this tool's camera, lit by the given `lights:` items: direct light,
 * which the closed forms give. */
static int write_job(const char *dir, const char *name, const char *scene, const char *lights)
{
    char path[4096];
    snprintf(path, sizeof(path), "%s/%s.yaml", dir, name);
    FILE *f = fopen(path, "w");
    if (!f) {
        perror(path);
        return 1;
    }
    fprintf(f,
            "scene: %s\n"
            "output: %s/frame.####.exr\n"
            "resolution: [320, 200]\n"
            "frames: {start: 0, end: 0}\n"
            "integrator: {name: direct}\n"
            "camera:\n"
            "  fov_y_deg: %g\n"
            "  keys: [{t: 0, position: [%g, %g, %g], look_at: [%g, %g, %g]}]\n"
            "lights:\n%s",
            scene, name, fov_y_deg, cam_pos[0], cam_pos[1], cam_pos[2], cam_target[0],
            cam_target[1], cam_target[2], lights);
    return fclose(f) != 0;
}

static int write_jobs(const char *dir)
{
    char point[256], spot[256], sun[128], both[512];
    snprintf(point, sizeof(point),
             "  - {type: point, position: [%g, %g, %g], color: [1, 1, 1], intensity: %g}\n",
             point_pos[0], point_pos[1], point_pos[2], point_intensity);
    snprintf(spot, sizeof(spot),
             "  - {type: spot, position: [%g, %g, %g], direction: [0, -1, 0], intensity: %g, "
             "inner_cone_deg: %g, outer_cone_deg: %g}\n",
             spot_pos[0], spot_pos[1], spot_pos[2], spot_intensity, spot_inner_deg, spot_outer_deg);
    snprintf(sun, sizeof(sun), "  - {type: directional, direction: [0, -1, 0], intensity: %g}\n",
             sun_lux);
    snprintf(both, sizeof(both), "%s%s", point, spot);
    return write_job(dir, "point", "plane.gltf", point) ||
           write_job(dir, "spot", "plane.gltf", spot) || write_job(dir, "sun", "plane.gltf", sun) ||
           write_job(dir, "glossy", "glossy.gltf", point) ||
           write_job(dir, "metal", "metal.gltf", point) ||
           write_job(dir, "lights", "plane.gltf", both);
}

struct image {
    struct rb_io_image img;
    int r, g, b;
};

static int load(const char *path, struct image *im)
{
    struct rb_err err = RB_ERR_INIT;
    if (rb_io_image_read(path, &im->img, &err)) {
        fprintf(stderr, "analytic: %s\n", err.msg);
        return 1;
    }
    im->r = rb_io_image_channel(&im->img, "R");
    im->g = rb_io_image_channel(&im->img, "G");
    im->b = rb_io_image_channel(&im->img, "B");
    return im->r < 0 || im->g < 0 || im->b < 0;
}

static double lum(const struct image *im, int x, int y)
{
    const float *p = &im->img.pixels[((size_t)y * im->img.width_px + x) * im->img.channel_count];
    return (p[im->r] + p[im->g] + p[im->b]) / 3.0;
}

/* Whether the camera sees the occluder quad (y = 1, x 1.25..1.75, z -0.25..0.25, grown by a
 * margin) in front of floor point p. */
static int behind_occluder(const double p[3])
{
    double s = (cam_pos[1] - 1.0) / (cam_pos[1] - p[1]);
    double qx = cam_pos[0] + s * (p[0] - cam_pos[0]), qz = cam_pos[2] + s * (p[2] - cam_pos[2]);
    return qx > 1.15 && qx < 1.85 && qz > -0.35 && qz < 0.35;
}

static int in_shadow(const double p[3], double margin)
{
    /* The occluder's shadow from point_pos on the floor: the square scaled by 2 about the light's
     * foot, i.e. x in [2.5, 3.5], z in [-0.5, 0.5]. */
    return p[0] > 2.5 + margin && p[0] < 3.5 - margin && fabs(p[2]) < 0.5 - margin;
}

static int near_shadow(const double p[3], double margin)
{
    return p[0] > 2.5 - margin && p[0] < 3.5 + margin && fabs(p[2]) < 0.5 + margin;
}

static int check_point(const char *path)
{
    struct image im;
    if (load(path, &im))
        return 1;
    int w = (int)im.img.width_px, h = (int)im.img.height_px;
    int lit = 0, dark = 0;
    double worst = 0.0;
    for (int y = 2; y < h; y += 7)
        for (int x = 2; x < w; x += 7) {
            double p[3];
            if (!floor_point(x, y, w, h, p))
                continue;
            /* Skip the occluder's own pixels (seen from the camera) and the penumbra. */
            if (behind_occluder(p))
                continue;
            double got = lum(&im, x, y);
            if (in_shadow(p, 0.1)) {
                dark++;
                if (got > 1e-6)
                    check(0, "pixel %d,%d (floor %.2f,%.2f) should be in shadow, got %g", x, y,
                          p[0], p[2], got);
                continue;
            }
            if (near_shadow(p, 0.15))
                continue;
            double want = lambert(point_pos, point_intensity, p);
            double rel = fabs(got - want) / want;
            if (rel > worst)
                worst = rel;
            lit++;
            if (rel > 0.01)
                check(0, "pixel %d,%d (floor %.3f,%.3f): radiance %.6g, closed form %.6g (%.2f%%)",
                      x, y, p[0], p[2], got, want, rel * 100.0);
        }
    check(lit > 50, "%d lit floor pixels checked against I cos/r^2 albedo/pi, worst %.3f%%", lit,
          worst * 100.0);
    check(dark > 3, "%d pixels inside the occluder's shadow are black", dark);
    rb_io_image_release(&im.img);
    return 0;
}

/* A glossy floor (metallic, roughness) under the point light: every checked pixel within 1% of
 * the BRDF above. */
static int check_brdf(const char *path, double metallic, double roughness)
{
    struct image im;
    if (load(path, &im))
        return 1;
    int w = (int)im.img.width_px, h = (int)im.img.height_px;
    int checked = 0, bad = 0;
    double worst = 0.0;
    for (int y = 2; y < h; y += 5)
        for (int x = 2; x < w; x += 5) {
            double p[3];
            if (!floor_point(x, y, w, h, p) || near_shadow(p, 0.15) || behind_occluder(p))
                continue;
            double n[3] = {0, 1, 0}, v[3], l[3];
            sub(cam_pos, p, v);
            normalize(v);
            sub(point_pos, p, l);
            double r2 = l[0] * l[0] + l[1] * l[1] + l[2] * l[2];
            normalize(l);
            double want = gltf_brdf_cos(metallic, roughness, n, v, l) * point_intensity / r2;
            double got = lum(&im, x, y);
            double rel = fabs(got - want) / want;
            if (rel > worst)
                worst = rel;
            checked++;
            if (rel > 0.01 && bad++ < 5)
                check(0, "pixel %d,%d (floor %.3f,%.3f): %.6g, glTF BRDF %.6g (%.2f%%)", x, y, p[0],
                      p[2], got, want, rel * 100.0);
        }
    check(checked > 100 && bad == 0,
          "metallic %g roughness %g: %d pixels match the glTF BRDF, worst %.3f%%", metallic,
          roughness, checked, worst * 100.0);
    rb_io_image_release(&im.img);
    return 0;
}

/* The directional light straight down: E albedo / pi on the floor, black directly under the
 * occluder. */
static int check_sun(const char *path)
{
    struct image im;
    if (load(path, &im))
        return 1;
    int w = (int)im.img.width_px, h = (int)im.img.height_px;
    int lit = 0, dark = 0, bad = 0;
    double want = sun_lux * albedo / PI;
    for (int y = 1; y < h; y += 3)
        for (int x = 1; x < w; x += 3) {
            double p[3];
            if (!floor_point(x, y, w, h, p) || behind_occluder(p))
                continue;
            double got = lum(&im, x, y);
            if (p[0] > 1.3 && p[0] < 1.7 && fabs(p[2]) < 0.2) {
                dark++;
                if (got > 1e-6 && bad++ < 5)
                    check(0, "pixel %d,%d (floor %.2f,%.2f) under the occluder: %g, want 0", x, y,
                          p[0], p[2], got);
            } else if (!(p[0] > 1.1 && p[0] < 1.9 && fabs(p[2]) < 0.4)) {
                lit++;
                if (fabs(got - want) > 0.01 * want && bad++ < 5)
                    check(0, "pixel %d,%d (floor %.2f,%.2f): %g, want E albedo/pi = %g", x, y, p[0],
                          p[2], got, want);
            }
        }
    check(lit > 100 && bad == 0, "%d floor pixels lit by the directional light match E albedo/pi",
          lit);
    check(dark > 3 && bad == 0, "%d pixels under the occluder are in its directional shadow", dark);
    rb_io_image_release(&im.img);
    return 0;
}

/* Every pixel sees the environment (the camera looks at the sky): color times intensity. */
static int check_sky(const char *path, double r, double g, double b)
{
    struct image im;
    if (load(path, &im))
        return 1;
    size_t n = (size_t)im.img.width_px * im.img.height_px, bad = 0;
    int a = rb_io_image_channel(&im.img, "A");
    for (size_t i = 0; i < n; i++) {
        const float *p = &im.img.pixels[i * im.img.channel_count];
        if (fabs(p[im.r] - r) > 1e-5 || fabs(p[im.g] - g) > 1e-5 || fabs(p[im.b] - b) > 1e-5 ||
            (a >= 0 && p[a] != 0.0f))
            bad++;
    }
    check(bad == 0,
          "all %zu background pixels are the environment times its intensity "
          "(%g %g %g), alpha 0; %zu are not",
          n, r, g, b, bad);
    rb_io_image_release(&im.img);
    return 0;
}

static int check_spot(const char *path)
{
    struct image im;
    if (load(path, &im))
        return 1;
    int w = (int)im.img.width_px, h = (int)im.img.height_px;
    int inner = 0, outer = 0, bad = 0;
    for (int y = 1; y < h; y += 3)
        for (int x = 1; x < w; x += 3) {
            double p[3];
            if (!floor_point(x, y, w, h, p))
                continue;
            double d[3];
            sub(p, spot_pos, d);
            normalize(d);
            double angle = acos(-d[1]) * 180.0 / PI; /* from the spot's axis, straight down */
            double got = lum(&im, x, y);
            if (angle < spot_inner_deg - 1.0) {
                double want = lambert(spot_pos, spot_intensity, p);
                inner++;
                if (fabs(got - want) > 0.01 * want && bad++ < 5)
                    check(0, "pixel %d,%d inside the inner cone (%.1f deg): %g, want %g", x, y,
                          angle, got, want);
            } else if (angle > spot_outer_deg + 1.0) {
                outer++;
                if (got > 1e-6 && bad++ < 5)
                    check(0, "pixel %d,%d outside the outer cone (%.1f deg): %g, want 0", x, y,
                          angle, got);
            }
        }
    check(inner > 20, "%d pixels inside the inner cone match the closed form", inner);
    check(outer > 20, "%d pixels outside the outer cone are black", outer);
    check(bad == 0, "spot cone edges land where the cone angles say");
    rb_io_image_release(&im.img);
    return 0;
}

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: analytic scene DIR | point|spot|sun|sky|glossy|metal EXR\n");
        return 2;
    }
    if (strcmp(argv[1], "scene") == 0)
        return write_scene(argv[2], "plane.gltf", 0.0, 1.0, 1) ||
               write_scene(argv[2], "glossy.gltf", 0.0, 0.4, 0) ||
               write_scene(argv[2], "metal.gltf", 1.0, 0.5, 0) || write_jobs(argv[2]);
    int rc;
    if (strcmp(argv[1], "point") == 0)
        rc = check_point(argv[2]);
    else if (strcmp(argv[1], "spot") == 0)
        rc = check_spot(argv[2]);
    else if (strcmp(argv[1], "sun") == 0)
        rc = check_sun(argv[2]);
    else if (strcmp(argv[1], "sky") == 0)
        rc = check_sky(argv[2], 0.4, 0.8, 1.6);
    else if (strcmp(argv[1], "glossy") == 0)
        rc = check_brdf(argv[2], 0.0, 0.4);
    else if (strcmp(argv[1], "metal") == 0)
        rc = check_brdf(argv[2], 1.0, 0.5);
    else
        return 2;
    printf("1..%d\n", test_no);
    return rc || failures ? 1 : 0;
}
