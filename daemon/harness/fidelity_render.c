#define _GNU_SOURCE /* M_PI */
#include "daemon/harness/fidelity_render.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <epoxy/gl.h>

#include "common/job_files.h"
#include "common/png_io.h"
#include "daemon/harness/reference.h"
#include "daemon/harness/transparent.h"
#include "daemon/look/look.h"
#include "daemon/jobs/fidelity.h"

static json_t *floats(const float *v, int n)
{
    json_t *a = json_array();
    for (int i = 0; a && i < n; i++)
        json_array_append_new(a, json_real(v[i]));
    return a;
}

/* Every light at frame k in glTF's terms; NULL with err when one has none
 * (the presets' window falloff, which glTF cannot state). */
static json_t *gltf_lights(const struct scene *s, int64_t k, char *err, size_t errlen)
{
    json_t *list = json_array();
    for (int i = 0; list && i < s->light_count; i++) {
        const struct scene_light *l = &s->lights[i];
        if (l->falloff != SCENE_FALLOFF_GLTF) {
            snprintf(err, errlen, "light %d falls off as the presets' lights do, which "
                     "KHR_lights_punctual cannot state", i);
            json_decref(list);
            return NULL;
        }
        json_t *o = json_pack("{s:s, s:o, s:f}", "type", scene_light_type_names[l->type],
                              "color", floats(l->gltf_color, 3), "intensity",
                              (double)l->gltf_intensity);
        if (l->type != SCENE_LIGHT_DIRECTIONAL) {
            float p[3];
            scene_light_position(s, i, k, p);
            json_object_set_new(o, "position", floats(p, 3));
            if (l->range > 0)
                json_object_set_new(o, "range", json_real(l->range));
        }
        if (l->type != SCENE_LIGHT_POINT)
            json_object_set_new(o, "direction", floats(l->direction, 3));
        if (l->type == SCENE_LIGHT_SPOT) {
            json_object_set_new(o, "inner_cone_deg", json_real(acos(l->cos_inner) * 180.0 / M_PI));
            json_object_set_new(o, "outer_cone_deg", json_real(acos(l->cos_outer) * 180.0 / M_PI));
        }
        json_array_append_new(list, o);
    }
    return list;
}

/* The job's look with look.debug set to name: NULL with why when this build
 * or the name is refused (look_spec_parse's own rule). */
static bool debug_look(const struct look_spec *base, const char *name, struct look_spec *out,
                       char *why, size_t whylen)
{
    json_t *j = look_spec_to_json(base);
    json_object_set_new(j, "debug", json_string(name));
    *out = *base;
    struct job_error e = {0};
    bool ok = look_spec_parse(j, "look", out, &e);
    json_decref(j);
    if (!ok)
        snprintf(why, whylen, "%s: %s", e.field, e.message);
    /* A channel needs no lighting: no environment to filter again. */
    out->ibl.enabled = false;
    out->shadows.enabled = false;
    return ok;
}

/* One channel: the job's technique over the measured run's scene, with the
 * debug look's own stages (its debug pass) and transparent pass (the
 * blended meshes' channel), both built with the debug look's defines. */
static bool draw_channel(struct harness_run *run, const struct look_spec *look, int k,
                         uint8_t *pixels, enum job_status *status)
{
    struct harness_run dbg = *run;
    dbg.look = look;
    char defines[sizeof(run->defines)];
    look_defines(look, defines, sizeof(defines));
    size_t used = strlen(defines);
    snprintf(defines + used, sizeof(defines) - used, "#define SCENE_TEXTURED 1\n");
    memset(&dbg.stages, 0, sizeof(dbg.stages));
    memset(&dbg.transparent, 0, sizeof(dbg.transparent));
    struct frame_source src = {0};
    bool ok = look_stages_init(&dbg.stages, look, &run->scene, &run->gpu, &run->gl->frame_block,
                               &run->gl->caps, &run->budget, defines, NULL, run->err,
                               sizeof(run->err)) &&
              transparent_init(&dbg.transparent, &run->gpu, defines, run->err,
                               sizeof(run->err)) &&
              frame_source_open(&dbg, &src, "fidelity channel", run->tech,
                                job_spec_technique_options(run->spec), look, 1) &&
              frame_source_frame(&dbg, &src, k, true, pixels, status);
    frame_source_close(&src);
    if (!ok && dbg.err[0] && dbg.err != run->err)
        snprintf(run->err, sizeof(run->err), "%s", dbg.err);
    transparent_finish(&dbg.transparent);
    look_stages_finish(&dbg.stages);
    return ok;
}

json_t *fidelity_render(struct harness_run *run, enum job_status *status)
{
    const struct job_spec *spec = run->spec;
    int w = spec->scene.width, h = spec->scene.height;
    int k = spec->frames - spec->frames % spec->capture_interval;
    char dir[PATH_MAX + 16], path[PATH_MAX + 64];
    snprintf(dir, sizeof(dir), "%s/" FIDELITY_DIR, run->job->dir);
    if (mkdir(dir, 0755) != 0 && errno != EEXIST) {
        snprintf(run->err, sizeof(run->err), "fidelity: %.900s: %s", dir, strerror(errno));
        return NULL;
    }
    struct scene_camera cam;
    scene_camera_at(&run->scene, k, &cam);
    char why[512];
    json_t *lights = gltf_lights(&run->scene, k, why, sizeof(why));
    if (!lights) {
        snprintf(run->err, sizeof(run->err), "fidelity: %s", why);
        return NULL;
    }
    json_t *channels = json_object();
    json_t *view = json_pack("{s:i, s:o, s:o, s:o, s:o, s:o}", "frame", k, "view",
                             floats(cam.view, 16), "projection", floats(cam.proj, 16), "eye",
                             floats(cam.eye, 3), "lights", lights, "channels", channels);
    /* The rasteriser's sub-pixel precision: where an edge passes within a
     * fraction of a pixel of pixel centres, the two renderers' coverage
     * differs by it (docs/assets.md, "What still differs"). */
    GLint subpixel_bits = 0;
    glGetIntegerv(GL_SUBPIXEL_BITS, &subpixel_bits);
    json_object_set_new(view, "subpixel_bits", json_integer(subpixel_bits));
    /* The lit image: the captured frame. */
    job_image_path(run->job->dir, JOB_IMAGE_FRAME, k, path, sizeof(path));
    json_object_set_new(channels, "lit", json_pack("{s:s}", "source", path));
    uint8_t *pixels = malloc((size_t)w * (size_t)h * 4);
    if (!pixels) {
        snprintf(run->err, sizeof(run->err), "fidelity: out of memory");
        json_decref(view);
        return NULL;
    }
    bool ok = true;
    for (int c = 1; ok && c < FIDELITY_CHANNELS; c++) {
        if (!(spec->fidelity.channels & (1u << c)))
            continue;
        const char *name = fidelity_channel_names[c];
        struct look_spec look;
        if (!debug_look(&spec->look, name, &look, why, sizeof(why))) {
            json_object_set_new(channels, name, json_pack("{s:s}", "error", why));
            continue;
        }
        ok = draw_channel(run, &look, k, pixels, status);
        if (!ok)
            break;
        snprintf(path, sizeof(path), "%s/shadebench-%s.png", dir, name);
        if (!(ok = png_write_gl_rgba(path, pixels, w, h, run->err, sizeof(run->err))))
            break;
        json_object_set_new(channels, name, json_pack("{s:s}", "source", path));
    }
    free(pixels);
    if (!ok) {
        json_decref(view);
        return NULL;
    }
    return view;
}
