/* Unit tests for lib/job: the job-file parser, its defaults, paths, error positions, --set
 * overrides, the glTF quick look, the hash and the key table against man/raybundle-job.5.
 * Runs from the repository root; fixtures are in tests/unit/jobs/. */
#include "job/job.h"

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>

#include "testutil.h"

#define JOBS "tests/unit/jobs"

/* Parses job text as if it were JOBS/job.yaml; the error text must be err->msg. */
static enum rb_status parse(const char *text, const struct rb_job_override *o, size_t n,
                            struct rb_job **job, struct rb_err *err)
{
    return rb_job_parse("job.yaml", text, strlen(text), JOBS, o, n, job, err);
}

static void expect_error(const char *text, const struct rb_job_override *o, size_t n,
                         enum rb_status want, const char *msg)
{
    struct rb_job *job = NULL;
    struct rb_err err = RB_ERR_INIT;
    enum rb_status st = parse(text, o, n, &job, &err);
    if (st != want || strcmp(err.msg, msg))
        print_error("got status %d '%s'\n", (int)st, err.msg);
    assert_int_equal(st, want);
    assert_string_equal(err.msg, msg);
    assert_null(job);
}

static struct rb_job *must_parse(const char *text, const struct rb_job_override *o, size_t n)
{
    struct rb_job *job = NULL;
    struct rb_err err = RB_ERR_INIT;
    enum rb_status st = parse(text, o, n, &job, &err);
    if (st)
        print_error("unexpected error: %s\n", err.msg);
    assert_int_equal(st, RB_OK);
    assert_non_null(job);
    return job;
}

static struct rb_job *must_load(const char *path, const struct rb_job_override *o, size_t n)
{
    struct rb_job *job = NULL;
    struct rb_err err = RB_ERR_INIT;
    enum rb_status st = rb_job_load(path, o, n, &job, &err);
    if (st)
        print_error("unexpected error: %s\n", err.msg);
    assert_int_equal(st, RB_OK);
    assert_non_null(job);
    return job;
}

static void assert_vec3(const float *v, float x, float y, float z)
{
    assert_float_equal(v[0], x, 1e-6);
    assert_float_equal(v[1], y, 1e-6);
    assert_float_equal(v[2], z, 1e-6);
}

/* ---- valid jobs ---------------------------------------------------------------------------- */

static void test_full_job(void **state)
{
    (void)state;
    struct rb_job *job = must_load(JOBS "/full.yaml", NULL, 0);

    assert_string_equal(job->path, JOBS "/full.yaml");
    assert_string_equal(job->scene_path, JOBS "/empty.gltf");
    assert_string_equal(job->output, JOBS "/renders/full.####.exr");
    assert_int_equal(job->width_px, 320);
    assert_int_equal(job->height_px, 240);
    assert_int_equal(job->frame_start, 2);
    assert_int_equal(job->frame_end, 10);
    assert_float_equal(job->rate_fps, 30.0, 0);

    assert_null(job->camera.node);
    assert_float_equal(job->camera.fov_y_deg, 55.5f, 0);
    assert_int_equal(job->camera.interpolation, RB_INTERP_LINEAR);
    assert_float_equal(job->camera.near_m, 0.05f, 0);
    assert_float_equal(job->camera.far_m, 200.0f, 0);
    assert_int_equal(job->camera.key_count, 2);
    assert_float_equal(job->camera.keys[0].t_s, 0.0, 0);
    assert_vec3(job->camera.keys[0].position, 0, 1.2f, 4.0f);
    assert_vec3(job->camera.keys[0].look_at, 0, 1, 0);
    assert_float_equal(job->camera.keys[0].fov_y_deg, 0, 0);
    assert_float_equal(job->camera.keys[1].t_s, 2.5, 0);
    assert_vec3(job->camera.keys[1].position, 1.5f, 1.4f, 3.2f);
    assert_float_equal(job->camera.keys[1].fov_y_deg, 30, 0);

    assert_int_equal(job->animation.clip_count, 2);
    assert_string_equal(job->animation.clips[0], "Walk");
    assert_string_equal(job->animation.clips[1], "Blink");
    assert_float_equal(job->animation.offset_s, 0.5, 0);
    assert_float_equal(job->animation.speed, 2.0, 0);
    assert_false(job->animation.loop);

    assert_int_equal(job->light_count, 3);
    const struct rb_job_light *l = job->lights;
    assert_int_equal(l[0].type, RB_LIGHT_POINT);
    assert_vec3(l[0].position, 0, 1.9f, 0);
    assert_vec3(l[0].color, 1, 0.5f, 0.25f);
    assert_float_equal(l[0].intensity, 8, 0);
    assert_float_equal(l[0].range, 10, 0);
    assert_vec3(l[0].direction, 0, -1, 0);
    assert_int_equal(l[1].type, RB_LIGHT_SPOT);
    assert_vec3(l[1].position, 1, 2, 3);
    assert_vec3(l[1].direction, 0, 0, -1); /* normalized from [0, 0, -2] */
    assert_float_equal(l[1].inner_cone_deg, 10, 0);
    assert_float_equal(l[1].outer_cone_deg, 30, 0);
    assert_vec3(l[1].color, 1, 1, 1);
    assert_int_equal(l[2].type, RB_LIGHT_DIRECTIONAL);
    assert_vec3(l[2].direction, 0.70710678f, -0.70710678f, 0);
    assert_false(job->use_scene_lights);

    assert_string_equal(job->environment.map, JOBS "/sky.hdr");
    assert_vec3(job->environment.color, 0.1f, 0.2f, 0.3f);
    assert_float_equal(job->environment.intensity, 0.5f, 0);
    assert_float_equal(job->environment.rotation_deg, 90, 0);

    assert_int_equal(job->integrator.name, RB_INTEGRATOR_BDPT);
    assert_int_equal(job->integrator.direct.shadow_size_px, 2048);
    assert_float_equal(job->integrator.direct.shadow_bias, 0.01f, 0);
    assert_float_equal(job->integrator.direct.pcf_radius_px, 2.5f, 0);

    assert_string_equal(job->color.config, JOBS "/test.ocio");
    assert_string_equal(job->color.display, "sRGB");
    assert_string_equal(job->color.view, "Raw");
    assert_true(job->color.preview);
    assert_true(job->hash != 0);
    rb_job_destroy(job);
}

static void test_defaults(void **state)
{
    (void)state;
    struct rb_job *job = must_load(JOBS "/minimal.yaml", NULL, 0);

    assert_string_equal(job->scene_path, JOBS "/empty.gltf");
    assert_string_equal(job->output, JOBS "/out/frame.####.exr");
    assert_int_equal(job->width_px, 640);
    assert_int_equal(job->height_px, 360);
    assert_int_equal(job->frame_start, 0);
    assert_int_equal(job->frame_end, -1);
    assert_float_equal(job->rate_fps, 24.0, 0);
    assert_null(job->camera.node);
    assert_float_equal(job->camera.fov_y_deg, 40, 0);
    assert_int_equal(job->camera.interpolation, RB_INTERP_CATMULL_ROM);
    assert_float_equal(job->camera.near_m, 0, 0);
    assert_float_equal(job->camera.far_m, 0, 0);
    assert_int_equal(job->camera.key_count, 0);
    assert_null(job->camera.keys);
    assert_int_equal(job->animation.clip_count, 0);
    assert_float_equal(job->animation.offset_s, 0, 0);
    assert_float_equal(job->animation.speed, 1, 0);
    assert_true(job->animation.loop);
    assert_int_equal(job->light_count, 0);
    assert_true(job->use_scene_lights);
    assert_null(job->environment.map);
    assert_vec3(job->environment.color, 0, 0, 0);
    assert_float_equal(job->environment.intensity, 1, 0);
    assert_float_equal(job->environment.rotation_deg, 0, 0);
    assert_int_equal(job->integrator.name, RB_INTEGRATOR_BDPT); /* the seeds' system */
    assert_int_equal(job->integrator.direct.shadow_size_px, 1024);
    assert_float_equal(job->integrator.direct.shadow_bias, 0.002f, 0);
    assert_float_equal(job->integrator.direct.pcf_radius_px, 1.5f, 0);
    assert_null(job->color.config);
    assert_null(job->color.display);
    assert_null(job->color.view);
    assert_false(job->color.preview);
    rb_job_destroy(job);

    /* A light with only its type gets every per-light default. */
    job = must_parse("scene: empty.gltf\nlights: [{type: spot}]\ncamera: {node: Cam}\n", NULL, 0);
    assert_int_equal(job->light_count, 1);
    assert_vec3(job->lights[0].position, 0, 0, 0);
    assert_vec3(job->lights[0].direction, 0, -1, 0);
    assert_vec3(job->lights[0].color, 1, 1, 1);
    assert_float_equal(job->lights[0].intensity, 1, 0);
    assert_float_equal(job->lights[0].range, 0, 0);
    assert_float_equal(job->lights[0].inner_cone_deg, 0, 0);
    assert_float_equal(job->lights[0].outer_cone_deg, 45, 0);
    assert_string_equal(job->camera.node, "Cam");
    rb_job_destroy(job);
}

static void test_relative_paths(void **state)
{
    (void)state;
    char cwd[4096], abs_scene[4200];
    assert_non_null(getcwd(cwd, sizeof(cwd)));
    snprintf(abs_scene, sizeof(abs_scene), "%s/" JOBS "/empty.gltf", cwd);

    /* Relative to the job file's directory, whatever the current directory is. */
    struct rb_job *job = must_parse("scene: empty.gltf\noutput: a/b.####.exr\n"
                                    "environment: {map: sky.hdr}\n",
                                    NULL, 0);
    assert_string_equal(job->scene_path, JOBS "/empty.gltf");
    assert_string_equal(job->output, JOBS "/a/b.####.exr");
    assert_string_equal(job->environment.map, JOBS "/sky.hdr");
    rb_job_destroy(job);

    /* Absolute paths stay as they are. */
    char text[4400];
    snprintf(text, sizeof(text), "scene: %s\noutput: /tmp/x.####.exr\n", abs_scene);
    job = must_parse(text, NULL, 0);
    assert_string_equal(job->scene_path, abs_scene);
    assert_string_equal(job->output, "/tmp/x.####.exr");
    rb_job_destroy(job);

    /* An empty base directory means the current one: nothing is prepended. */
    struct rb_err err = RB_ERR_INIT;
    const char *t = "scene: " JOBS "/empty.gltf\n";
    assert_int_equal(rb_job_parse("j.yaml", t, strlen(t), "", NULL, 0, &job, &err), RB_OK);
    assert_string_equal(job->scene_path, JOBS "/empty.gltf");
    assert_string_equal(job->output, "out/frame.####.exr");
    rb_job_destroy(job);
}

/* ---- errors, each with its position -------------------------------------------------------- */

static void test_error_job_file_missing(void **state)
{
    (void)state;
    struct rb_job *job = NULL;
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(rb_job_load(JOBS "/nope.yaml", NULL, 0, &job, &err), RB_E_IO);
    assert_string_equal(err.msg, "cannot open '" JOBS "/nope.yaml': No such file or directory");
    assert_null(job);
}

static void test_error_malformed_yaml(void **state)
{
    (void)state;
    struct rb_job *job = NULL;
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(rb_job_load(JOBS "/bad_syntax.yaml", NULL, 0, &job, &err), RB_E_PARSE);
    assert_string_equal(err.msg, JOBS "/bad_syntax.yaml:3:7: did not find expected ',' or ']' "
                                      "while parsing a flow sequence");
    assert_null(job);

    expect_error("scene: empty.gltf\n  bad: indent\n", NULL, 0, RB_E_PARSE,
                 "job.yaml:2:6: mapping values are not allowed in this context");
    expect_error("scene: empty.gltf\nx: *nothing\n", NULL, 0, RB_E_PARSE,
                 "job.yaml:2:4: found undefined alias");
    expect_error("scene: empty.gltf\n---\nscene: empty.gltf\n", NULL, 0, RB_E_PARSE,
                 "job.yaml:3:1: a job holds one YAML document, found another");
    expect_error("- scene\n", NULL, 0, RB_E_PARSE, "job.yaml:1:1: a job file is a mapping of keys");
}

static void test_error_unknown_key(void **state)
{
    (void)state;
    expect_error("scene: empty.gltf\nintegrator:\n    nmae: bdpt\n", NULL, 0, RB_E_PARSE,
                 "job.yaml:3:5: unknown key 'nmae' in 'integrator'; did you mean 'name'?");
    expect_error("scene: empty.gltf\nscnee: x\n", NULL, 0, RB_E_PARSE,
                 "job.yaml:2:1: unknown key 'scnee'; did you mean 'scene'?");
    /* Too far from every key: no suggestion. */
    expect_error("scene: empty.gltf\nframes: {start: 0, samples: 4}\n", NULL, 0, RB_E_PARSE,
                 "job.yaml:2:20: unknown key 'samples' in 'frames'");
    /* Dotted names are not keys in the file; only --set uses them. */
    expect_error("scene: empty.gltf\nframes.rate: 30\n", NULL, 0, RB_E_PARSE,
                 "job.yaml:2:1: unknown key 'frames.rate'");
    expect_error("scene: empty.gltf\nlights: [{type: point, colour: [1, 1, 1]}]\n", NULL, 0,
                 RB_E_PARSE,
                 "job.yaml:2:24: unknown key 'colour' in 'lights[0]'; did you mean 'color'?");
}

static void test_error_wrong_type(void **state)
{
    (void)state;
    expect_error("scene: empty.gltf\nresolution: 640\n", NULL, 0, RB_E_PARSE,
                 "job.yaml:2:13: 'resolution' expects a list of 2 integers");
    expect_error("scene: empty.gltf\nresolution: [640, 360, 1]\n", NULL, 0, RB_E_PARSE,
                 "job.yaml:2:13: 'resolution' expects a list of 2 integers");
    expect_error("scene: empty.gltf\nresolution: [640.5, 360]\n", NULL, 0, RB_E_PARSE,
                 "job.yaml:2:14: 'resolution' expects a list of 2 integers");
    /* Quoted numbers are strings. */
    expect_error("scene: empty.gltf\nframes:\n  rate: \"24\"\n", NULL, 0, RB_E_PARSE,
                 "job.yaml:3:9: 'frames.rate' expects a number");
    expect_error("scene: empty.gltf\nscene_lights: yes\n", NULL, 0, RB_E_PARSE,
                 "job.yaml:2:15: 'scene_lights' expects true or false");
    expect_error("scene: empty.gltf\ncamera: 3\n", NULL, 0, RB_E_PARSE,
                 "job.yaml:2:9: 'camera' expects a mapping");
    expect_error("scene: empty.gltf\nanimation: {clips: [a, [b]]}\n", NULL, 0, RB_E_PARSE,
                 "job.yaml:2:24: 'animation.clips' expects a list of strings");
    expect_error("scene: empty.gltf\nlights: [{type: spot, color: [1, 1]}]\n", NULL, 0, RB_E_PARSE,
                 "job.yaml:2:30: 'lights[0].color' expects a list of 3 numbers");
    expect_error("scene: [a, b]\n", NULL, 0, RB_E_PARSE, "job.yaml:1:8: 'scene' expects a path");
}

static void test_error_out_of_range(void **state)
{
    (void)state;
    expect_error("scene: empty.gltf\nframes: {start: 0, rate: -1}\n", NULL, 0, RB_E_INVALID,
                 "job.yaml:2:26: 'frames.rate' must be > 0");
    expect_error("scene: empty.gltf\nresolution: [640, 0]\n", NULL, 0, RB_E_INVALID,
                 "job.yaml:2:19: 'resolution' must be between 1 and 16384");
    expect_error("scene: empty.gltf\ncamera: {fov_y_deg: 180}\n", NULL, 0, RB_E_INVALID,
                 "job.yaml:2:21: 'camera.fov_y_deg' must be > 0 and < 180");
    expect_error("scene: empty.gltf\nintegrator: {direct: {shadow_size: 8}}\n", NULL, 0,
                 RB_E_INVALID,
                 "job.yaml:2:36: 'integrator.direct.shadow_size' must be between 16 and 8192");
    expect_error("scene: empty.gltf\nlights: [{type: point, intensity: -1}]\n", NULL, 0,
                 RB_E_INVALID, "job.yaml:2:35: 'lights[0].intensity' must be >= 0");
    expect_error("scene: empty.gltf\nintegrator: {name: bpdt}\n", NULL, 0, RB_E_INVALID,
                 "job.yaml:2:20: 'integrator.name' must be one of direct, bdpt, hybrid, "
                 "reference, not 'bpdt'; did you mean 'bdpt'?");
    expect_error("scene: empty.gltf\nlights:\n  - {type: spot, direction: [0, 0, 0]}\n", NULL, 0,
                 RB_E_INVALID, "job.yaml:3:29: 'lights[0].direction' must not be zero");
    expect_error("scene: empty.gltf\nlights:\n  - {type: spot, outer_cone_deg: 91}\n", NULL, 0,
                 RB_E_INVALID,
                 "job.yaml:3:34: 'lights[0].outer_cone_deg' must be between 0 and 90");
    expect_error("scene: empty.gltf\nlights:\n  - {type: spot, inner_cone_deg: 50}\n", NULL, 0,
                 RB_E_INVALID,
                 "job.yaml:3:34: 'lights[0].inner_cone_deg' (50) must be <= its "
                 "outer_cone_deg (45)");
    expect_error("scene: empty.gltf\nframes: {start: 5, end: 3}\n", NULL, 0, RB_E_INVALID,
                 "job.yaml:2:25: 'frames.end' (3) must be -1 or >= 'frames.start' (5)");
    expect_error("scene: empty.gltf\ncamera: {near: 10, far: 1}\n", NULL, 0, RB_E_INVALID,
                 "job.yaml:2:25: 'camera.far' (1) must be greater than 'camera.near' (10)");
    expect_error("scene: empty.gltf\nframes: {start: 99999999999}\n", NULL, 0, RB_E_INVALID,
                 "job.yaml:2:17: 'frames.start' is out of range");
}

static void test_error_missing_required(void **state)
{
    (void)state;
    expect_error("output: x.exr\n", NULL, 0, RB_E_PARSE,
                 "job.yaml:1:1: missing required key 'scene'");
    expect_error("\n\n# only a comment\n", NULL, 0, RB_E_PARSE,
                 "job.yaml:1:1: missing required key 'scene'");
    /* In a list item: the position of the item's mapping. */
    expect_error("scene: empty.gltf\nlights:\n  - {position: [1, 2, 3]}\n", NULL, 0, RB_E_PARSE,
                 "job.yaml:3:5: 'lights[0]' is missing required key 'type'");
    expect_error("scene: empty.gltf\ncamera:\n  keys:\n    - t: 0\n      position: [0, 0, 1]\n",
                 NULL, 0, RB_E_PARSE,
                 "job.yaml:4:7: 'camera.keys[0]' is missing required key 'look_at'");
}

static void test_error_missing_files(void **state)
{
    (void)state;
    struct rb_job *job = NULL;
    struct rb_err err = RB_ERR_INIT;
    assert_int_equal(rb_job_load(JOBS "/missing_scene.yaml", NULL, 0, &job, &err), RB_E_IO);
    assert_string_equal(err.msg,
                        JOBS "/missing_scene.yaml:2:8: scene file '" JOBS "/nope.glb' not found");
    assert_null(job);

    expect_error("scene: empty.gltf\nenvironment: {map: nope.exr}\n", NULL, 0, RB_E_IO,
                 "job.yaml:2:20: environment map file '" JOBS "/nope.exr' not found");
    expect_error("scene: empty.gltf\ncolor:\n  config: nope.ocio\n", NULL, 0, RB_E_IO,
                 "job.yaml:3:11: color config file '" JOBS "/nope.ocio' not found");
}

static void test_error_duplicate_key(void **state)
{
    (void)state;
    expect_error("scene: empty.gltf\nresolution: [1, 1]\nscene: empty.gltf\n", NULL, 0, RB_E_PARSE,
                 "job.yaml:3:1: duplicate key 'scene'");
    expect_error("scene: empty.gltf\nframes: {start: 1, end: 4, start: 2}\n", NULL, 0, RB_E_PARSE,
                 "job.yaml:2:28: duplicate key 'start' in 'frames'");
}

static void test_error_camera(void **state)
{
    (void)state;
    /* node and keys conflict: reported where the later of the two was set. */
    expect_error("scene: empty.gltf\ncamera:\n  node: Cam\n  keys:\n"
                 "    - {t: 0, position: [0, 0, 1], look_at: [0, 0, 0]}\n",
                 NULL, 0, RB_E_INVALID,
                 "job.yaml:5:5: 'camera.node' and 'camera.keys' are mutually exclusive");
    expect_error("scene: empty.gltf\ncamera:\n  keys:\n"
                 "    - {t: 0, position: [0, 0, 1], look_at: [0, 0, 0]}\n"
                 "    - {t: 1, position: [0, 0, 2], look_at: [0, 0, 0]}\n"
                 "    - {t: 1, position: [0, 0, 3], look_at: [0, 0, 0]}\n",
                 NULL, 0, RB_E_INVALID,
                 "job.yaml:6:11: 'camera.keys[2].t' (1) must be greater than the previous "
                 "key's t (1)");
    expect_error("scene: empty.gltf\ncamera:\n  keys:\n"
                 "    - {t: 2, position: [0, 0, 1], look_at: [0, 0, 0]}\n"
                 "    - {t: 1, position: [0, 0, 2], look_at: [0, 0, 0]}\n",
                 NULL, 0, RB_E_INVALID,
                 "job.yaml:5:11: 'camera.keys[1].t' (1) must be greater than the previous "
                 "key's t (2)");
    expect_error("scene: empty.gltf\ncamera:\n  keys:\n"
                 "    - {t: 0, position: [1, 2, 3], look_at: [1, 2, 3]}\n",
                 NULL, 0, RB_E_INVALID,
                 "job.yaml:4:44: 'camera.keys[0].look_at' must differ from its position");
}

/* ---- --set overrides ----------------------------------------------------------------------- */

static void test_overrides(void **state)
{
    (void)state;
    const char *text = "scene: empty.gltf\nframes: {start: 0, end: 9, rate: 25}\n"
                       "lights: [{type: point}, {type: spot}]\n";
    struct rb_job_override set[] = {
        {"integrator.direct.shadow_size", "512", NULL}, /* nested scalar */
        {"resolution", "[320, 200]", NULL},             /* list */
        {"frames", "{start: 1, end: 4}", NULL},         /* mapping: merges, rate stays */
        {"integrator.name", "reference", NULL},         /* enum */
        {"scene_lights", "false", NULL},                /* bool */
        {"lights", "[{type: directional, direction: [0, 0, -3]}]", NULL}, /* replaces the list */
        {"animation.clips", "[Run]", NULL},
        {"camera.node", "Cam", NULL},
        {"camera.node", "", NULL},            /* an empty value unsets an optional string */
        {"environment.map", "sky.hdr", NULL}, /* relative to the job's directory */
    };
    struct rb_job *job = must_parse(text, set, sizeof(set) / sizeof(set[0]));
    assert_int_equal(job->integrator.direct.shadow_size_px, 512);
    assert_int_equal(job->width_px, 320);
    assert_int_equal(job->height_px, 200);
    assert_int_equal(job->frame_start, 1);
    assert_int_equal(job->frame_end, 4);
    assert_float_equal(job->rate_fps, 25, 0);
    assert_int_equal(job->integrator.name, RB_INTEGRATOR_REFERENCE);
    assert_false(job->use_scene_lights);
    assert_int_equal(job->light_count, 1);
    assert_int_equal(job->lights[0].type, RB_LIGHT_DIRECTIONAL);
    assert_vec3(job->lights[0].direction, 0, 0, -1);
    assert_int_equal(job->animation.clip_count, 1);
    assert_string_equal(job->animation.clips[0], "Run");
    assert_null(job->camera.node);
    assert_string_equal(job->environment.map, JOBS "/sky.hdr");
    rb_job_destroy(job);

    /* Overrides apply in order: the last one wins; an empty list clears. */
    struct rb_job_override order[] = {
        {"frames.rate", "30", NULL}, {"frames.rate", "48", NULL}, {"lights", "[]", NULL}};
    job = must_parse(text, order, 3);
    assert_float_equal(job->rate_fps, 48, 0);
    assert_int_equal(job->light_count, 0);
    assert_null(job->lights);
    rb_job_destroy(job);

    /* On the command line a name's case does not matter; in a job file it does. */
    struct rb_job_override upper[] = {{"integrator.name", "BDPT", NULL},
                                      {"lights", "[{type: Spot}]", NULL}};
    job = must_parse(text, upper, 2);
    assert_int_equal(job->integrator.name, RB_INTEGRATOR_BDPT);
    assert_int_equal(job->lights[0].type, RB_LIGHT_SPOT);
    rb_job_destroy(job);
    expect_error("scene: empty.gltf\nintegrator: {name: BDPT}\n", NULL, 0, RB_E_INVALID,
                 "job.yaml:2:20: 'integrator.name' must be one of direct, bdpt, hybrid, "
                 "reference, not 'BDPT'; did you mean 'bdpt'?");

    /* A --set can supply a key the file lacks. */
    struct rb_job_override scene[] = {{"scene", "empty.gltf", NULL}};
    job = must_parse("resolution: [8, 8]\n", scene, 1);
    assert_string_equal(job->scene_path, JOBS "/empty.gltf");
    rb_job_destroy(job);
}

static void test_override_errors(void **state)
{
    (void)state;
    const char *text = "scene: empty.gltf\n";
    struct rb_job_override unknown[] = {{"integrator.direct.shadow_sise", "512", NULL}};
    expect_error(text, unknown, 1, RB_E_PARSE,
                 "--set:1:19: unknown key 'shadow_sise' in 'integrator.direct'; "
                 "did you mean 'shadow_size'?");
    struct rb_job_override top[] = {{"samples", "4", NULL}};
    expect_error(text, top, 1, RB_E_PARSE, "--set:1:1: unknown key 'samples'");
    struct rb_job_override leaf[] = {{"resolution.x", "3", NULL}};
    expect_error(text, leaf, 1, RB_E_PARSE, "--set:1:12: unknown key 'x' in 'resolution'");
    struct rb_job_override item[] = {{"lights[].type", "point", NULL}};
    expect_error(text, item, 1, RB_E_PARSE,
                 "--set:1:1: unknown key 'lights[]'; did you mean 'lights'?");

    /* The column counts from the start of "key=value". */
    struct rb_job_override bad[] = {{"resolution", "[1, 2]", NULL}, {"frames.rate", "abc", NULL}};
    expect_error(text, bad, 2, RB_E_PARSE, "--set:2:13: 'frames.rate' expects a number");
    struct rb_job_override range[] = {{"resolution", "[64, 99999]", NULL}};
    expect_error(text, range, 1, RB_E_INVALID,
                 "--set:1:17: 'resolution' must be between 1 and 16384");
    struct rb_job_override nested[] = {{"frames", "{strat: 1}", NULL}};
    expect_error(text, nested, 1, RB_E_PARSE,
                 "--set:1:9: unknown key 'strat' in 'frames'; did you mean 'start'?");
    struct rb_job_override conflict[] = {{"camera.node", "Cam", NULL}};
    expect_error("scene: empty.gltf\ncamera:\n  keys:\n"
                 "    - {t: 0, position: [0, 0, 1], look_at: [0, 0, 0]}\n",
                 conflict, 1, RB_E_INVALID,
                 "--set:1:13: 'camera.node' and 'camera.keys' are mutually exclusive");
    struct rb_job_override missing[] = {{"scene", "nope.glb", NULL}};
    expect_error(text, missing, 1, RB_E_IO, "--set:1:7: scene file '" JOBS "/nope.glb' not found");
}

/* ---- quick look at a glTF ------------------------------------------------------------------ */

/* Where the keys that the scene or the disk check later were set, kept for their messages. */
static void test_key_positions(void **state)
{
    (void)state;
    const char *text = "scene: empty.gltf\n"
                       "camera: {node: Cam}\n"
                       "animation:\n"
                       "  clips: [Run, Walk]\n"
                       "lights: [{type: point}]\n";
    struct rb_job_override set[] = {{"environment.map", "sky.hdr", NULL},
                                    {"color.config", "test.ocio", "--ocio 'test.ocio'"}};
    struct rb_job *job = must_parse(text, set, 2);
    assert_string_equal(job->at.camera_node, "job.yaml:2:16");
    assert_string_equal(job->at.animation_clips, "job.yaml:4:10");
    assert_string_equal(job->at.lights, "job.yaml:5:9");
    assert_string_equal(job->at.environment_map, "--set:1:17");
    assert_string_equal(job->at.color_config, "--ocio 'test.ocio'");
    rb_job_destroy(job);
    job = must_parse("scene: empty.gltf\n", NULL, 0); /* keys left at their defaults */
    assert_null(job->at.camera_node);
    assert_null(job->at.animation_clips);
    assert_null(job->at.lights);
    assert_null(job->at.environment_map);
    assert_null(job->at.color_config);
    rb_job_destroy(job);
}

static void test_quick_look(void **state)
{
    (void)state;
    char fox[4096];
    if (rb_test_scene(fox, sizeof(fox), "Fox/Fox.glb"))
        skip(); /* a checkout without the external sample scenes */

    struct rb_job *job = must_load(fox, NULL, 0);
    assert_string_equal(job->path, fox);
    assert_string_equal(job->scene_path, fox);
    assert_string_equal(job->output, "out/Fox/frame.####.exr");
    assert_int_equal(job->frame_start, 0);
    assert_int_equal(job->frame_end, -1);
    assert_float_equal(job->rate_fps, 24, 0);
    assert_null(job->camera.node);
    assert_int_equal(job->camera.key_count, 0);
    assert_int_equal(job->animation.clip_count, 0);
    assert_true(job->use_scene_lights);
    assert_int_equal(job->width_px, 640);
    assert_int_equal(job->integrator.name, RB_INTEGRATOR_BDPT); /* shows every kind of light */
    rb_job_destroy(job);

    /* Overrides still apply; paths in them are relative to the current directory. */
    struct rb_job_override set[] = {{"resolution", "[64, 32]", NULL},
                                    {"environment.map", JOBS "/sky.hdr", NULL},
                                    {"integrator.name", "direct", NULL}};
    job = must_load(fox, set, 3);
    assert_int_equal(job->integrator.name, RB_INTEGRATOR_DIRECT);
    assert_int_equal(job->width_px, 64);
    assert_int_equal(job->height_px, 32);
    assert_string_equal(job->environment.map, JOBS "/sky.hdr");
    rb_job_destroy(job);

    /* The extension is matched without regard to case. */
    const char *tmp = getenv("TMPDIR");
    char dir[4096], path[4200];
    snprintf(dir, sizeof(dir), "%s/rb_test_job_XXXXXX", tmp && tmp[0] ? tmp : "/tmp");
    assert_non_null(mkdtemp(dir));
    snprintf(path, sizeof(path), "%s/Room.GLTF", dir);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs("{\"asset\":{\"version\":\"2.0\"}}\n", f);
    fclose(f);
    job = must_load(path, NULL, 0);
    assert_string_equal(job->scene_path, path);
    assert_string_equal(job->output, "out/Room/frame.####.exr");
    rb_job_destroy(job);
    remove(path);
    rmdir(dir);

    struct rb_err err = RB_ERR_INIT;
    job = NULL;
    assert_int_equal(rb_job_load(JOBS "/nope.glb", NULL, 0, &job, &err), RB_E_IO);
    assert_string_equal(err.msg, "cannot open '" JOBS "/nope.glb': No such file or directory");
    assert_null(job);
}

/* ---- hash ---------------------------------------------------------------------------------- */

static uint64_t hash_of(const char *text, const struct rb_job_override *o, size_t n)
{
    struct rb_job *job = must_parse(text, o, n);
    uint64_t h = job->hash;
    rb_job_destroy(job);
    return h;
}

static void test_hash(void **state)
{
    (void)state;
    const char *text = "scene: empty.gltf\nframes: {start: 0, end: 99}\n";
    uint64_t base = hash_of(text, NULL, 0);

    /* Chunks of one sequence, written anywhere, share the hash. */
    struct rb_job_override chunk[] = {{"frames", "{start: 50, end: 74}", NULL},
                                      {"output", "elsewhere/f.####.exr", NULL}};
    assert_true(hash_of(text, chunk, 2) == base);
    /* Previews and color management do not change the EXR. */
    struct rb_job_override preview[] = {{"color.preview", "true", NULL}};
    assert_true(hash_of(text, preview, 1) == base);

    const struct rb_job_override changes[][1] = {
        {{"resolution", "[641, 360]", NULL}},
        {{"frames.rate", "25", NULL}},
        {{"camera.fov_y_deg", "41", NULL}},
        {{"camera.node", "Cam", NULL}},
        {{"animation.clips", "[Walk]", NULL}},
        {{"animation.loop", "false", NULL}},
        {{"lights", "[{type: point}]", NULL}},
        {{"scene_lights", "false", NULL}},
        {{"environment.intensity", "2", NULL}},
        {{"integrator.name", "direct", NULL}},
        {{"integrator.bdpt.vpl_bias", "0.02", NULL}},
        {{"integrator.bdpt.min_roughness", "0.6", NULL}},
        {{"integrator.bdpt.vpl_spread", "2", NULL}},
    };
    for (size_t i = 0; i < sizeof(changes) / sizeof(changes[0]); i++) {
        if (hash_of(text, changes[i], 1) == base)
            fail_msg("--set %s=%s did not change the hash", changes[i][0].key, changes[i][0].value);
    }

    /* rb_job_rehash follows a caller's change, and is what the parser computed. */
    struct rb_job *job = must_parse(text, NULL, 0);
    rb_job_rehash(job);
    assert_true(job->hash == base);
    job->width_px = 641;
    rb_job_rehash(job);
    assert_true(job->hash == hash_of(text, changes[0], 1));
    rb_job_destroy(job);
}

/* ---- names, the key table and the man page ------------------------------------------------- */

static void test_integrator_names(void **state)
{
    (void)state;
    const char *names[] = {"direct", "bdpt", "hybrid", "reference"};
    for (size_t i = 0; i < 4; i++) {
        enum rb_integrator_kind k = rb_integrator_from_name(names[i]);
        assert_int_equal(k, (int)(RB_INTEGRATOR_DIRECT + i));
        assert_string_equal(rb_integrator_name(k), names[i]);
    }
    assert_int_equal(rb_integrator_from_name("pathtracer"), RB_INTEGRATOR_DEFAULT);
    assert_int_equal(rb_integrator_from_name(NULL), RB_INTEGRATOR_DEFAULT);
    assert_string_equal(rb_integrator_name(RB_INTEGRATOR_DEFAULT), "bdpt");
    rb_job_destroy(NULL);
}

static void test_key_table(void **state)
{
    (void)state;
    size_t n = rb_job_key_count();
    assert_true(n >= 40);
    assert_null(rb_job_key_path(n));
    for (size_t i = 0; i < n; i++) {
        assert_non_null(rb_job_key_path(i));
        for (size_t j = 0; j < i; j++)
            assert_string_not_equal(rb_job_key_path(i), rb_job_key_path(j));
    }
    assert_string_equal(rb_job_key_path(0), "scene");

    /* A block per key: its path at the margin, its help indented; no line past the width. */
    char *buf = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&buf, &size);
    assert_non_null(f);
    assert_int_equal(rb_job_print_keys(f, NULL, 80), n);
    fclose(f);
    size_t keys = 0;
    for (char *line = buf; line && *line;) {
        char *nl = strchr(line, '\n');
        assert_non_null(nl);
        assert_true(nl - line <= 80);
        if (line[0] != ' ') {
            assert_true(keys < n);
            const char *path = rb_job_key_path(keys++);
            assert_memory_equal(line, path, strlen(path));
            assert_int_equal(line[strlen(path)], ' ');
        }
        line = nl + 1;
    }
    assert_int_equal(keys, n);
    /* Integer bounds print whole. */
    assert_non_null(strstr(buf, "between 0 and 4294967295"));
    assert_null(strstr(buf, "e+0"));
    assert_non_null(strstr(buf, "integrator.direct.shadow_size"));
    assert_non_null(strstr(buf, "out/frame.####.exr"));
    free(buf);

    /* A prefix picks the keys whose path starts with it. */
    buf = NULL;
    f = open_memstream(&buf, &size);
    assert_non_null(f);
    size_t camera = rb_job_print_keys(f, "camera.", 60);
    fclose(f);
    assert_true(camera >= 5 && camera < n);
    assert_null(strstr(buf, "\nscene"));
    assert_non_null(strstr(buf, "camera.fov_y_deg"));
    free(buf);
    f = open_memstream(&buf, &size);
    assert_int_equal(rb_job_print_keys(f, "camra", 80), 0);
    fclose(f);
    free(buf);
}

/* samples and tiles: written by the hybrid integrator and the reference; asked of direct or bdpt,
 * refused at the later of the two keys. */
static void test_adaptive_layers(void **state)
{
    (void)state;
    const uint32_t both = 1u << RB_LAYER_SAMPLES | 1u << RB_LAYER_TILES;
    static const char *const ok[] = {"hybrid", "reference"};
    for (size_t i = 0; i < 2; i++) {
        char text[128];
        snprintf(text, sizeof(text),
                 "scene: empty.gltf\nlayers: [tiles, samples]\n"
                 "integrator: {name: %s}\n",
                 ok[i]);
        struct rb_job *job = must_parse(text, NULL, 0);
        assert_int_equal(job->layer_mask, both);
        rb_job_destroy(job);
    }
    expect_error("scene: empty.gltf\nintegrator: {name: bdpt}\nlayers: [direct, samples]\n", NULL,
                 0, RB_E_INVALID,
                 "job.yaml:3:9: layer 'samples' is written by the hybrid and reference "
                 "integrators only, and this job renders with 'bdpt'");
    expect_error("scene: empty.gltf\nlayers: [tiles]\n", NULL, 0, RB_E_INVALID,
                 "job.yaml:2:9: layer 'tiles' is written by the hybrid and reference integrators "
                 "only, and this job renders with 'bdpt'");
    /* variance: the reference's alone, and it needs two samples a pixel */
    struct rb_job *vj = must_parse("scene: empty.gltf\nlayers: [variance]\n"
                                   "integrator: {name: reference}\n",
                                   NULL, 0);
    assert_int_equal(vj->layer_mask, 1u << RB_LAYER_VARIANCE);
    rb_job_destroy(vj);
    expect_error("scene: empty.gltf\nintegrator: {name: hybrid}\nlayers: [variance]\n", NULL, 0,
                 RB_E_INVALID,
                 "job.yaml:3:9: layer 'variance' is written by the reference integrator only, and "
                 "this job renders with 'hybrid'");
    expect_error("scene: empty.gltf\nlayers: [variance]\n"
                 "integrator: {name: reference, reference: {spp: 1}}\n",
                 NULL, 0, RB_E_INVALID,
                 "job.yaml:3:48: layer 'variance' needs at least 2 samples a pixel, and "
                 "'integrator.reference.spp' is 1");
    struct rb_job_override o[] = {{"integrator.name", "bdpt", "--integrator 'bdpt'"}};
    expect_error("scene: empty.gltf\nlayers: [samples]\nintegrator: {name: hybrid}\n", o, 1,
                 RB_E_INVALID,
                 "--integrator 'bdpt': layer 'samples' is written by the hybrid and reference "
                 "integrators only, and this job renders with 'bdpt'");
    expect_error(
        "scene: empty.gltf\nlayers: [indirect_difuse]\n", NULL, 0, RB_E_INVALID,
        "job.yaml:2:9: unknown layer 'indirect_difuse' (direct, indirect, albedo, normal, "
        "depth, motion, indirect_diffuse, indirect_specular, samples, tiles, variance); did "
        "you mean 'indirect_diffuse'?");
}

/* integrator.hybrid.max_bounces: a count from 0 to 8 or the word unlimited (the default, the
 * hits' feedback); feedback is its older spelling, and whichever of the two was set last counts. */
static void test_hybrid_max_bounces(void **state)
{
    (void)state;
    struct rb_job *job = must_parse("scene: empty.gltf\nintegrator: {name: hybrid}\n", NULL, 0);
    assert_int_equal(job->integrator.hybrid.max_bounces, UINT32_MAX);
    assert_true(job->integrator.hybrid.feedback);
    uint64_t unlimited_hash = job->hash;
    rb_job_destroy(job);
    job = must_parse("scene: empty.gltf\nintegrator: {name: hybrid, hybrid: {max_bounces: 2}}\n",
                     NULL, 0);
    assert_int_equal(job->integrator.hybrid.max_bounces, 2);
    assert_false(job->integrator.hybrid.feedback);
    uint64_t two_hash = job->hash;
    rb_job_destroy(job);
    assert_true(two_hash != unlimited_hash);
    job = must_parse("scene: empty.gltf\nintegrator: {name: hybrid, hybrid: {feedback: false}}\n",
                     NULL, 0);
    assert_int_equal(job->integrator.hybrid.max_bounces, 1);
    uint64_t off_hash = job->hash;
    rb_job_destroy(job);
    job = must_parse("scene: empty.gltf\nintegrator: {name: hybrid, hybrid: {max_bounces: 1}}\n",
                     NULL, 0);
    assert_int_equal(job->hash, off_hash);
    rb_job_destroy(job);
    struct rb_job_override later[] = {{"integrator.hybrid.max_bounces", "unlimited", NULL}};
    job = must_parse("scene: empty.gltf\nintegrator: {name: hybrid, hybrid: {feedback: false}}\n",
                     later, 1);
    assert_int_equal(job->integrator.hybrid.max_bounces, UINT32_MAX);
    assert_true(job->integrator.hybrid.feedback);
    rb_job_destroy(job);
    struct rb_job_override off[] = {{"integrator.hybrid.feedback", "false", NULL}};
    job = must_parse("scene: empty.gltf\nintegrator: {name: hybrid, hybrid: {max_bounces: 3}}\n",
                     off, 1);
    assert_int_equal(job->integrator.hybrid.max_bounces, 1);
    rb_job_destroy(job);
    expect_error("scene: empty.gltf\nintegrator:\n  hybrid: {max_bounces: 9}\n", NULL, 0,
                 RB_E_INVALID,
                 "job.yaml:3:25: 'integrator.hybrid.max_bounces' must be between 0 and 8 or "
                 "unlimited");
    expect_error("scene: empty.gltf\nintegrator:\n  hybrid: {max_bounces: all}\n", NULL, 0,
                 RB_E_PARSE,
                 "job.yaml:3:25: 'integrator.hybrid.max_bounces' expects an integer or unlimited");
}

static void test_man_page_covers_keys(void **state)
{
    (void)state;
    char *man = NULL;
    struct rb_err err = RB_ERR_INIT;
    if (rb_read_file("man/raybundle-job.5", &man, NULL, &err))
        fail_msg("%s", err.msg);
    for (size_t i = 0; i < rb_job_key_count(); i++) {
        if (!strstr(man, rb_job_key_path(i)))
            fail_msg("job key '%s' is missing from man/raybundle-job.5", rb_job_key_path(i));
    }
    free(man);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_full_job),
        cmocka_unit_test(test_defaults),
        cmocka_unit_test(test_relative_paths),
        cmocka_unit_test(test_error_job_file_missing),
        cmocka_unit_test(test_error_malformed_yaml),
        cmocka_unit_test(test_error_unknown_key),
        cmocka_unit_test(test_error_wrong_type),
        cmocka_unit_test(test_error_out_of_range),
        cmocka_unit_test(test_error_missing_required),
        cmocka_unit_test(test_error_missing_files),
        cmocka_unit_test(test_error_duplicate_key),
        cmocka_unit_test(test_error_camera),
        cmocka_unit_test(test_overrides),
        cmocka_unit_test(test_override_errors),
        cmocka_unit_test(test_key_positions),
        cmocka_unit_test(test_quick_look),
        cmocka_unit_test(test_hash),
        cmocka_unit_test(test_integrator_names),
        cmocka_unit_test(test_key_table),
        cmocka_unit_test(test_adaptive_layers),
        cmocka_unit_test(test_hybrid_max_bounces),
        cmocka_unit_test(test_man_page_covers_keys),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
