/*
 * ltcfit: fits linearly transformed cosines (Heitz, Dupuy, Hill and Neubelt, "Real-Time
 * Polygonal-Light Shading with Linearly Transformed Cosines", 2016) to raybundle's specular lobe,
 * the GGX distribution with the height-correlated Smith term of shaders/common/brdf.glsl (rb_ggx,
 * alpha = max(roughness^2, 1e-4)), Fresnel left out, times the cosine, and writes the table that
 * lib/passes/ltc.c compiles in (lib/passes/ltc_ggx.inc; make ltc-table).
 *
 * The table has SIZE^2 entries, row t (sqrt(1 - cos theta_v) * (SIZE - 1)) by column r
 * (perceptual roughness * (SIZE - 1)), each of four numbers: the inverse transform's m00 m02 m20
 * m22, of the matrix that takes a direction in the frame (T1, T2, n), the view in the x-z plane
 * (x >= 0), to the cosine's frame, scaled so that m11 = 1 (a polygon's integral does not see the
 * scale). The integral of the fitted density over a polygon is the cosine's over the polygon so
 * transformed: Lambert's sum over its edges.
 *
 * The transform keeps the surface's plane: M = [[m11, 0, m13], [0, m22, 0], [0, 0, 1]] (a scale
 * and a shear toward the lobe), so the density vanishes at the horizon as the lobe does, linearly.
 * The paper's fit turns the cosine to the lobe's mean direction first, and a light just above the
 * horizon, seen at a grazing angle, then took 3 to 10 times the lobe's integral (the Cornell box's
 * light quad, 0.9 units below the ceiling, lighting the ceiling beside it); this one keeps such a
 * light within a factor of 2 and most lights within 15% (tests/unit/test_ltc.c).
 *
 * Nelder-Mead minimises the cubed difference of the two normalised distributions, sampled by
 * both (balance heuristic), as the paper's fit does. Each roughness starts at normal incidence
 * from the next rougher one's fit, then each row from the last; the normal-incidence column is
 * fitted first, in order, and then the roughnesses are independent and run on threads, so the
 * output does not depend on their count. The nearly mirror-like roughnesses below MIRROR start
 * each row from MIRROR's fit instead, scaled to their width (fit_mirror_column). Every loop runs
 * in a fixed order: the same libm, the same bits.
 *
 * Usage: ltcfit OUT                  writes the whole table
 *        ltcfit --check FILE R...    refits the roughness columns R (0 to SIZE - 1) and compares
 *                                    them with FILE's numbers, which must match as printed
 */
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846
#define SIZE 64
#define FIT_SAMPLES 32  /* per axis, each way, in the error */
#define AVG_SAMPLES 128 /* per axis, for the lobe's integrals */
#define MAX_ITERATIONS 100
#define THREADS 8
#define STEP 0.05 /* the simplex's side */

struct vec3 {
    double x, y, z;
};

static struct vec3 v3(double x, double y, double z)
{
    return (struct vec3){x, y, z};
}

static double dot3(struct vec3 a, struct vec3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

static struct vec3 scale3(struct vec3 a, double s)
{
    return v3(a.x * s, a.y * s, a.z * s);
}

static struct vec3 add3(struct vec3 a, struct vec3 b)
{
    return v3(a.x + b.x, a.y + b.y, a.z + b.z);
}

static struct vec3 normalize3(struct vec3 a)
{
    return scale3(a, 1.0 / sqrt(dot3(a, a)));
}

/* Row-major 3x3. */
struct mat3 {
    double m[3][3];
};

static struct vec3 mul3(const struct mat3 *a, struct vec3 v)
{
    return v3(a->m[0][0] * v.x + a->m[0][1] * v.y + a->m[0][2] * v.z,
              a->m[1][0] * v.x + a->m[1][1] * v.y + a->m[1][2] * v.z,
              a->m[2][0] * v.x + a->m[2][1] * v.y + a->m[2][2] * v.z);
}

static double det3(const struct mat3 *a)
{
    const double(*m)[3] = a->m;
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
           m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

static struct mat3 inverse3(const struct mat3 *a)
{
    const double(*m)[3] = a->m;
    double d = det3(a);
    struct mat3 r;
    r.m[0][0] = (m[1][1] * m[2][2] - m[1][2] * m[2][1]) / d;
    r.m[0][1] = (m[0][2] * m[2][1] - m[0][1] * m[2][2]) / d;
    r.m[0][2] = (m[0][1] * m[1][2] - m[0][2] * m[1][1]) / d;
    r.m[1][0] = (m[1][2] * m[2][0] - m[1][0] * m[2][2]) / d;
    r.m[1][1] = (m[0][0] * m[2][2] - m[0][2] * m[2][0]) / d;
    r.m[1][2] = (m[0][2] * m[1][0] - m[0][0] * m[1][2]) / d;
    r.m[2][0] = (m[1][0] * m[2][1] - m[1][1] * m[2][0]) / d;
    r.m[2][1] = (m[0][1] * m[2][0] - m[0][0] * m[2][1]) / d;
    r.m[2][2] = (m[0][0] * m[1][1] - m[0][1] * m[1][0]) / d;
    return r;
}

/* The lobe at l for the view v (normal z): D Vis cos, as rb_ggx with F = 1, and the density
 * of sample_lobe's directions there. */
static double lobe(struct vec3 v, struct vec3 l, double alpha, double *pdf)
{
    *pdf = 0.0;
    double ndl = l.z, ndv = fmax(v.z, 1e-4);
    struct vec3 lv = add3(l, v);
    if (ndl <= 0.0 || !(dot3(lv, lv) > 0.0))
        return 0.0;
    struct vec3 h = normalize3(lv);
    double ndh = fmax(h.z, 0.0), vdh = fmin(fmax(dot3(v, h), 0.0), 1.0);
    double a2 = alpha * alpha, d = ndh * ndh * (a2 - 1.0) + 1.0;
    double D = a2 / (PI * d * d);
    double den = ndl * sqrt(ndv * ndv * (1.0 - a2) + a2) + ndv * sqrt(ndl * ndl * (1.0 - a2) + a2);
    double vis = den > 0.0 ? 0.5 / den : 0.0;
    *pdf = vdh > 0.0 ? D * ndh / (4.0 * vdh) : 0.0;
    return D * vis * ndl;
}

/* A direction drawn by the distribution of normals (D cos_h) and reflected about it. */
static struct vec3 sample_lobe(struct vec3 v, double alpha, double u1, double u2)
{
    double phi = 2.0 * PI * u1, a2 = alpha * alpha;
    double c2 = (1.0 - u2) / (1.0 + (a2 - 1.0) * u2), c = sqrt(c2), s = sqrt(fmax(1.0 - c2, 0.0));
    struct vec3 h = v3(s * cos(phi), s * sin(phi), c);
    return add3(scale3(h, 2.0 * dot3(v, h)), scale3(v, -1.0));
}

struct ltc {
    double m11, m22, m13;
    double norm; /* the lobe's integral over the hemisphere */
    struct mat3 m, inv;
    double inv_det;
};

static void ltc_update(struct ltc *t)
{
    t->m = (struct mat3){{{t->m11, 0.0, t->m13}, {0.0, t->m22, 0.0}, {0.0, 0.0, 1.0}}};
    t->inv = inverse3(&t->m);
    t->inv_det = fabs(det3(&t->inv));
}

/* The fitted distribution at l, times the lobe's integral. */
static double ltc_eval(const struct ltc *t, struct vec3 l)
{
    struct vec3 o = mul3(&t->inv, l);
    double len = sqrt(dot3(o, o));
    double cosine = fmax(o.z / len, 0.0) / PI;
    return t->norm * cosine * t->inv_det / (len * len * len);
}

static struct vec3 ltc_sample(const struct ltc *t, double u1, double u2)
{
    double r = sqrt(u1), phi = 2.0 * PI * u2;
    struct vec3 o = v3(r * cos(phi), r * sin(phi), sqrt(fmax(1.0 - u1, 0.0)));
    return normalize3(mul3(&t->m, o));
}

/* One direction's share of the error: both densities at l, the lobe's and the fit's. */
static double error_at(const struct ltc *t, struct vec3 v, double alpha, struct vec3 l)
{
    double pdf_lobe, f = lobe(v, l, alpha, &pdf_lobe);
    double g = ltc_eval(t, l), pdf_ltc = g / t->norm;
    double e = fabs(f - g);
    double den = pdf_ltc + pdf_lobe;
    return den > 0.0 ? e * e * e / den : 0.0;
}

static double fit_error(const struct ltc *t, struct vec3 v, double alpha)
{
    double sum = 0.0;
    for (int j = 0; j < FIT_SAMPLES; j++)
        for (int i = 0; i < FIT_SAMPLES; i++) {
            double u1 = (i + 0.5) / FIT_SAMPLES, u2 = (j + 0.5) / FIT_SAMPLES;
            sum += error_at(t, v, alpha, ltc_sample(t, u1, u2));
            sum += error_at(t, v, alpha, sample_lobe(v, alpha, u1, u2));
        }
    return sum / (FIT_SAMPLES * FIT_SAMPLES);
}

/* The lobe's integral and its mean direction (in the x-z plane). */
static void lobe_moments(struct vec3 v, double alpha, double *norm, struct vec3 *mean)
{
    double n = 0.0;
    struct vec3 d = v3(0, 0, 0);
    for (int j = 0; j < AVG_SAMPLES; j++)
        for (int i = 0; i < AVG_SAMPLES; i++) {
            struct vec3 l = sample_lobe(v, alpha, (i + 0.5) / AVG_SAMPLES, (j + 0.5) / AVG_SAMPLES);
            double pdf, value = lobe(v, l, alpha, &pdf);
            if (!(pdf > 0.0) || !(value > 0.0))
                continue;
            double w = value / pdf;
            n += w;
            d = add3(d, scale3(l, w));
        }
    *norm = n / (AVG_SAMPLES * AVG_SAMPLES);
    d.y = 0.0;
    *mean = normalize3(d);
}

/* The parameters x into t: isotropic, x[0] alone. */
static void set_params(struct ltc *t, const double x[3], int isotropic)
{
    t->m11 = fmax(x[0], 1e-7);
    t->m22 = isotropic ? t->m11 : fmax(x[1], 1e-7);
    t->m13 = isotropic ? 0.0 : x[2];
    ltc_update(t);
}

static double objective(struct ltc *t, const double x[3], int isotropic, struct vec3 v,
                        double alpha)
{
    set_params(t, x, isotropic);
    return fit_error(t, v, alpha);
}

/* Nelder-Mead from start, with a simplex of side delta, until the values' spread is under
 * tolerance or MAX_ITERATIONS; leaves the best point in t. */
static void fit(struct ltc *t, struct vec3 v, double alpha, int isotropic, double delta)
{
    enum { DIM = 3 };
    const double tolerance = 1e-5;
    double p[DIM + 1][DIM], f[DIM + 1];
    double start[DIM] = {t->m11, t->m22, t->m13};
    for (int i = 0; i <= DIM; i++) {
        memcpy(p[i], start, sizeof(start));
        if (i > 0)
            p[i][i - 1] += delta;
        f[i] = objective(t, p[i], isotropic, v, alpha);
    }
    for (int iteration = 0; iteration < MAX_ITERATIONS; iteration++) {
        /* Order: best first (a stable insertion sort, so ties keep their order). */
        for (int i = 1; i <= DIM; i++)
            for (int j = i; j > 0 && f[j] < f[j - 1]; j--) {
                double tf = f[j], tp[DIM];
                memcpy(tp, p[j], sizeof(tp));
                f[j] = f[j - 1];
                memcpy(p[j], p[j - 1], sizeof(tp));
                f[j - 1] = tf;
                memcpy(p[j - 1], tp, sizeof(tp));
            }
        if (fabs(f[DIM] - f[0]) <= tolerance * (fabs(f[0]) + fabs(f[DIM])) + 1e-30)
            break;
        double c[DIM] = {0}, r[DIM], e[DIM], k[DIM];
        for (int i = 0; i < DIM; i++) {
            for (int j = 0; j < DIM; j++)
                c[j] += p[i][j] / DIM;
        }
        for (int j = 0; j < DIM; j++)
            r[j] = c[j] + (c[j] - p[DIM][j]);
        double fr = objective(t, r, isotropic, v, alpha);
        if (fr < f[0]) {
            for (int j = 0; j < DIM; j++)
                e[j] = c[j] + 2.0 * (c[j] - p[DIM][j]);
            double fe = objective(t, e, isotropic, v, alpha);
            memcpy(p[DIM], fe < fr ? e : r, sizeof(e));
            f[DIM] = fe < fr ? fe : fr;
        } else if (fr < f[DIM - 1]) {
            memcpy(p[DIM], r, sizeof(r));
            f[DIM] = fr;
        } else {
            int outside = fr < f[DIM];
            for (int j = 0; j < DIM; j++)
                k[j] = outside ? c[j] + 0.5 * (r[j] - c[j]) : c[j] + 0.5 * (p[DIM][j] - c[j]);
            double fk = objective(t, k, isotropic, v, alpha);
            if (fk < (outside ? fr : f[DIM])) {
                memcpy(p[DIM], k, sizeof(k));
                f[DIM] = fk;
            } else {
                for (int i = 1; i <= DIM; i++) {
                    for (int j = 0; j < DIM; j++)
                        p[i][j] = p[0][j] + 0.5 * (p[i][j] - p[0][j]);
                    f[i] = objective(t, p[i], isotropic, v, alpha);
                }
            }
        }
    }
    int best = 0;
    for (int i = 1; i <= DIM; i++)
        if (f[i] < f[best])
            best = i;
    set_params(t, p[best], isotropic);
}

static float table[SIZE * SIZE][4];
static struct ltc normal_fits[SIZE]; /* each roughness's fit at normal incidence */

static double roughness_alpha(int r)
{
    double roughness = (double)r / (SIZE - 1);
    return fmax(roughness * roughness, 1e-4);
}

static struct vec3 view_at(int t)
{
    double x = (double)t / (SIZE - 1), c = 1.0 - x * x;
    double theta = fmin(acos(c), 1.57);
    return v3(sin(theta), 0.0, cos(theta));
}

static void store(int t, int r, const struct ltc *fit_)
{
    float *e = table[t * SIZE + r];
    const struct mat3 *inv = &fit_->inv;
    double s = inv->m[1][1];
    e[0] = (float)(inv->m[0][0] / s);
    e[1] = (float)(inv->m[0][2] / s);
    e[2] = (float)(inv->m[2][0] / s);
    e[3] = (float)(inv->m[2][2] / s);
}

/* The normal-incidence fits, from the roughest down, each starting from the last. */
static void fit_normal_column(void)
{
    struct ltc t = {.m11 = 1.0, .m22 = 1.0, .m13 = 0.0};
    for (int r = SIZE - 1; r >= 0; r--) {
        struct vec3 v = view_at(0), mean;
        double alpha = roughness_alpha(r);
        lobe_moments(v, alpha, &t.norm, &mean);
        t.m22 = t.m11;
        t.m13 = 0.0;
        ltc_update(&t);
        fit(&t, v, alpha, 1, STEP);
        normal_fits[r] = t;
        store(0, r, &t);
    }
}

/* Roughness r's rows 1 to SIZE - 1, each starting from the last; the first's shear from the
 * lobe's mean direction. */
static void fit_column(int r)
{
    struct ltc t = normal_fits[r];
    double alpha = roughness_alpha(r);
    for (int row = 1; row < SIZE; row++) {
        struct vec3 v = view_at(row), mean;
        lobe_moments(v, alpha, &t.norm, &mean);
        if (row == 1)
            t.m13 = mean.x / fmax(mean.z, 1e-3) * t.m11;
        ltc_update(&t);
        fit(&t, v, alpha, 0, STEP);
        store(row, r, &t);
    }
}

/* Below MIRROR's roughness (alpha 1e-4 to 0.006) the search from the next rougher fit did not
 * find the lobe: the simplex's first step of 0.05 lands far out in the cosine's tail, and those
 * fits came out tens to thousands of times too wide at some view angles and not at the next (a
 * mirror's fireflies, where the emitters' ratio divided by a density that missed the lobe's
 * peak). There the lobe is near its mirror limit, as the fits from MIRROR up show: its shape at
 * a view angle (m00 and m02 over m11) hardly changes with alpha, and its width (m22) is
 * proportional to alpha. So each row starts from MIRROR's fit, its width scaled down, and the
 * search steps in the lobe's own scale, a twentieth of m11. */
#define MIRROR 6

static void fit_mirror_column(int r)
{
    double alpha = roughness_alpha(r), ratio = alpha / roughness_alpha(MIRROR);
    for (int row = 0; row < SIZE; row++) {
        const float *from = table[row * SIZE + MIRROR];
        double m22 = from[3] * ratio, m11 = m22 / from[0];
        struct ltc t = {.m11 = m11, .m22 = m22, .m13 = -from[1] / from[0]};
        ltc_update(&t);
        if (row > 0) {
            struct vec3 v = view_at(row), mean;
            lobe_moments(v, alpha, &t.norm, &mean);
            fit(&t, v, alpha, 0, STEP * m11);
        }
        store(row, r, &t);
    }
}

struct job {
    const int *columns;
    int count, first, stride;
};

static void *worker(void *arg)
{
    const struct job *j = arg;
    for (int i = j->first; i < j->count; i += j->stride) {
        int r = j->columns[i];
        if (r < MIRROR)
            fit_mirror_column(r);
        else
            fit_column(r);
    }
    return NULL;
}

/* The columns on up to THREADS threads; 1 when a thread could not start. */
static int run_columns(const int *columns, int count)
{
    pthread_t threads[THREADS];
    struct job jobs[THREADS];
    int started = 0;
    for (int i = 0; i < THREADS && i < count; i++) {
        jobs[i] = (struct job){columns, count, i, THREADS};
        if (pthread_create(&threads[i], NULL, worker, &jobs[i]) != 0) {
            fprintf(stderr, "ltcfit: cannot start a thread\n");
            break;
        }
        started++;
    }
    for (int i = 0; i < started; i++)
        pthread_join(threads[i], NULL);
    return started == (count < THREADS ? count : THREADS) ? 0 : 1;
}

/* The columns asked for: those from MIRROR up first (and MIRROR itself when one below it is
 * asked for), then those below, which start from MIRROR's. */
static int fit_columns(const int *columns, int count)
{
    fit_normal_column();
    int rough[SIZE], smooth[SIZE], n_rough = 0, n_smooth = 0, has_mirror = 0;
    for (int i = 0; i < count; i++) {
        if (columns[i] >= MIRROR)
            rough[n_rough++] = columns[i];
        else
            smooth[n_smooth++] = columns[i];
        has_mirror |= columns[i] == MIRROR;
    }
    if (n_smooth > 0 && !has_mirror)
        rough[n_rough++] = MIRROR;
    return run_columns(rough, n_rough) || run_columns(smooth, n_smooth) ? 1 : 0;
}

static int write_table(const char *path)
{
    char tmp[4096];
    if (snprintf(tmp, sizeof(tmp), "%s.tmp", path) >= (int)sizeof(tmp)) {
        fprintf(stderr, "ltcfit: path too long: '%s'\n", path);
        return 1;
    }
    FILE *out = fopen(tmp, "w");
    if (!out) {
        fprintf(stderr, "ltcfit: cannot write '%s': %s\n", tmp, strerror(errno));
        return 1;
    }
    fprintf(out,
            "/* Written by tools/ltcfit.c (make ltc-table): %d x %d entries, rows by\n"
            " * sqrt(1 - cos theta_v), columns by roughness; see there for the layout. */\n",
            SIZE, SIZE);
    for (int i = 0; i < SIZE * SIZE; i++) {
        for (int k = 0; k < 4; k++)
            fprintf(out, "%.9g,%s", (double)table[i][k], k == 3 ? "\n" : " ");
    }
    if (fclose(out) != 0 || rename(tmp, path) != 0) {
        fprintf(stderr, "ltcfit: cannot write '%s': %s\n", path, strerror(errno));
        remove(tmp);
        return 1;
    }
    return 0;
}

/* FILE's numbers for columns r against a refit of them, printed as write_table prints them. */
static int check_table(const char *path, const int *columns, int count)
{
    FILE *in = fopen(path, "r");
    if (!in) {
        fprintf(stderr, "ltcfit: cannot read '%s': %s\n", path, strerror(errno));
        return 1;
    }
    static char text[SIZE * SIZE][4][32];
    int c, prev = 0, n = 0, in_comment = 0;
    char word[32];
    size_t len = 0;
    /* The numbers, each followed by a comma, after the opening comment. */
    while ((c = fgetc(in)) != EOF && n < SIZE * SIZE * 4) {
        if (in_comment) {
            if (prev == '*' && c == '/')
                in_comment = 0;
            prev = c;
            continue;
        }
        if (c == '/') {
            in_comment = 1;
            prev = 0;
            continue;
        }
        if (c == ',') {
            word[len] = '\0';
            memcpy(text[n / 4][n % 4], word, len + 1);
            n++;
            len = 0;
        } else if (c != ' ' && c != '\n' && len + 1 < sizeof(word)) {
            word[len++] = (char)c;
        }
    }
    fclose(in);
    if (n != SIZE * SIZE * 4) {
        fprintf(stderr, "ltcfit: '%s' has %d numbers, not %d\n", path, n, SIZE * SIZE * 4);
        return 1;
    }
    if (fit_columns(columns, count))
        return 1;
    int bad = 0;
    for (int i = 0; i < count; i++)
        for (int t = 0; t < SIZE; t++)
            for (int k = 0; k < 4; k++) {
                char mine[32];
                snprintf(mine, sizeof(mine), "%.9g", (double)table[t * SIZE + columns[i]][k]);
                if (strcmp(mine, text[t * SIZE + columns[i]][k]) != 0) {
                    if (bad++ < 10)
                        fprintf(stderr, "ltcfit: row %d column %d number %d: %s, refit %s\n", t,
                                columns[i], k, text[t * SIZE + columns[i]][k], mine);
                }
            }
    if (bad) {
        fprintf(stderr, "ltcfit: %d numbers differ\n", bad);
        return 1;
    }
    printf("ltcfit: columns match (%d)\n", count);
    return 0;
}

int main(int argc, char **argv)
{
    if (argc >= 4 && strcmp(argv[1], "--check") == 0) {
        int columns[SIZE], count = 0;
        for (int i = 3; i < argc && count < SIZE; i++) {
            char *end;
            long r = strtol(argv[i], &end, 10);
            if (*end || r < 0 || r >= SIZE) {
                fprintf(stderr, "ltcfit: not a column: '%s'\n", argv[i]);
                return 2;
            }
            columns[count++] = (int)r;
        }
        return check_table(argv[2], columns, count);
    }
    if (argc != 2) {
        fprintf(stderr, "usage: ltcfit OUT | ltcfit --check FILE COLUMN...\n");
        return 2;
    }
    int columns[SIZE];
    for (int r = 0; r < SIZE; r++)
        columns[r] = r;
    if (fit_columns(columns, SIZE))
        return 1;
    return write_table(argv[1]);
}
