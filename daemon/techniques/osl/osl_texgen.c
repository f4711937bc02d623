/* OSL texture generation: the geometry atlas (osl_gl.h). */
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/gpu/glutil.h"
#include "common/log.h"
#include "daemon/gpu/bindings.h"
#include "daemon/techniques/osl/osl_gl.h"

/* The geometry entries: one per (mesh, tile size) in use, in mesh order
 * then size order, so the same scene always packs the same way. */
static bool plan_geometry(struct osl *o, const struct scene *s, int **sizes_out, int **mesh_out)
{
    int n = s->instance_count;
    int *sizes = malloc((size_t)(n ? n : 1) * sizeof(int));
    int *mesh = malloc((size_t)(n ? n : 1) * sizeof(int));
    o->geo_entry = malloc((size_t)(n ? n : 1) * sizeof(int));
    if (!sizes || !mesh || !o->geo_entry) {
        free(sizes);
        free(mesh);
        return false;
    }
    int count = 0;
    for (int m = 0; m < s->mesh_count; m++)
        for (int size = OSL_TILE_MAX; size >= 1; size >>= 1) {
            int entry = -1;
            for (int i = 0; i < n; i++) {
                if (s->instances[i].mesh != m || o->tiles[i].size != size)
                    continue;
                if (entry < 0) {
                    entry = count++;
                    sizes[entry] = size;
                    mesh[entry] = m;
                }
                o->geo_entry[i] = entry;
            }
        }
    o->geo_count = count;
    *sizes_out = sizes;
    *mesh_out = mesh;
    return true;
}

static int rect_cmp(const void *a, const void *b)
{
    return memcmp(a, b, 4 * sizeof(float));
}

/* The distinct chart rectangles of a mesh (mesh_chart_rects), less the
 * whole square (no clamp, no owner). Returns how many; *out malloc'd. */
static int mesh_rects(const struct mesh *m, float (**out)[4])
{
    float(*r)[4] = malloc((size_t)(m->vertex_count ? m->vertex_count : 1) * sizeof(*r));
    int n = 0;
    *out = r;
    if (!r)
        return -1;
    for (uint32_t v = 0; v < m->vertex_count; v++) {
        const float *c = m->vertices[v].chart;
        if (!(c[0] == 0.0f && c[1] == 0.0f && c[2] == 1.0f && c[3] == 1.0f))
            memcpy(r[n++], c, sizeof(*r));
    }
    qsort(r, (size_t)n, sizeof(*r), rect_cmp);
    int k = 0;
    for (int i = 0; i < n; i++)
        if (!k || memcmp(r[k - 1], r[i], sizeof(*r)))
            memcpy(r[k++], r[i], sizeof(*r));
    return k;
}

/* An asset's uv1 charts are not whole rectangles (the procedural meshes'
 * are): the texels of each chart's rectangle that no triangle covered are
 * filled from the chart's own edge, out to the raster pass's filter reach,
 * so that filtering clamped to the rectangle (osl_draw.frag) reads the
 * chart's surface and never its neighbour's, at every level. Counts what no
 * triangle covered. */
static bool dilate_entry(struct osl *o, const struct mesh *mesh, const GLuint *scratch,
                         int channels, int size)
{
    size_t texels = (size_t)size * size;
    float *img[OSL_GEO_CHANNELS] = {NULL};
    float(*rects)[4] = NULL;
    int *owner = malloc(texels * sizeof(int));
    int nrects = mesh_rects(mesh, &rects);
    bool ok = owner && nrects >= 0;
    for (int c = 0; c < channels; c++)
        ok = ok && (img[c] = malloc(texels * 4 * sizeof(float)));
    if (ok) {
        osl_chart_owners((const float(*)[4])rects, nrects, size, owner);
        glPixelStorei(GL_PACK_ALIGNMENT, 4);
        glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
        for (int c = 0; c < channels; c++) {
            glBindTexture(GL_TEXTURE_2D, scratch[c]);
            glGetTexImage(GL_TEXTURE_2D, 0, GL_RGBA, GL_FLOAT, img[c]);
        }
        size_t covered = 0;
        for (size_t t = 0; t < texels; t++)
            covered += img[0][t * 4 + 3] > 0.0f;
        o->asset_texels += (double)texels;
        o->asset_uncovered += (double)(texels - covered);
        o->asset_filled += (double)osl_dilate_geometry(img[0], img[1], img + 2, channels - 2, size,
                                                       OSL_GUTTER_TEXELS(o), owner);
        for (int c = 0; c < channels; c++) {
            glBindTexture(GL_TEXTURE_2D, scratch[c]);
            glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, size, size, GL_RGBA, GL_FLOAT, img[c]);
        }
    }
    for (int c = 0; c < channels; c++)
        free(img[c]);
    free(owner);
    free(rects);
    return ok;
}

/* Texture generation: each entry rasterized alone into a scratch target of
 * its size at the origin, then copied into its place in the geometry
 * atlas. Rendering at the origin keeps every texel the exact sample it was
 * when each mesh had textures of its own (a viewport offset into a larger
 * target would round window coordinates differently). Asset scenes bake
 * their materials into two more channels, each entry with its mesh's
 * material bound. */
bool osl_generate_textures(struct osl *o, const struct technique_env *env, char *err,
                              size_t errlen)
{
    const struct scene *s = env->scene;
    int *sizes = NULL, *mesh = NULL;
    if (!plan_geometry(o, s, &sizes, &mesh)) {
        snprintf(err, errlen, "osl: out of memory");
        return false;
    }
    int channels = o->textured ? 4 : 2;
    o->geo = calloc((size_t)(o->geo_count ? o->geo_count : 1), sizeof(*o->geo));
    GLint max_tex = 0;
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_tex);
    /* 16 bytes a channel's texel (RGBA32F), against the packer's 4; the
     * levels stacked below level 0 take half as much again. */
    double stack = o->levels > 1 ? 1.5 : 1.0;
    bool ok = o->geo && osl_atlas_pack(sizes, o->geo_count, max_tex,
                                       1024.0 * 1024.0 * 1024.0 / (4.0 * channels) / stack,
                                       o->geo, &o->geo_w, &o->geo_h0, err, errlen);
    o->geo_h = o->levels > 1 ? o->geo_h0 + o->geo_h0 / 2 : o->geo_h0;
    if (ok && o->geo_h > max_tex) {
        snprintf(err, errlen, "osl: the geometry atlas and its levels need %dx%d texels; this "
                 "device allows at most %dx%d", o->geo_w, o->geo_h, max_tex, max_tex);
        ok = false;
    }
    if (!ok) {
        if (!o->geo)
            snprintf(err, errlen, "osl: out of memory");
        free(sizes);
        free(mesh);
        return false;
    }
    GLuint texs[OSL_GEO_CHANNELS] = {0}, scratch[OSL_GEO_CHANNELS] = {0}, fbo;
    glGenTextures(channels, texs);
    o->geo_position = texs[0];
    o->geo_normal = texs[1];
    o->geo_albedo = texs[2];
    o->geo_surface = texs[3];
    for (int t = 0; t < channels; t++) {
        glBindTexture(GL_TEXTURE_2D, texs[t]);
        glTexStorage2D(GL_TEXTURE_2D, 1, GL_RGBA32F, o->geo_w, o->geo_h);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    }
    glGenFramebuffers(1, &fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    struct scene_program texgen = gpu_scene_program(env->gpu, o->texgen_prog);
    gpu_scene_bind(env->gpu, &texgen);
    static const GLenum bufs[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1,
                                  GL_COLOR_ATTACHMENT2, GL_COLOR_ATTACHMENT3};
    glDrawBuffers(channels, bufs);
    int scratch_size = 0;
    for (int k = 0; k < o->geo_count * 16 && ok; k++) {
        /* Entry e at level l (each level rasterized at its own size). */
        int e = k / 16, l = k % 16, m = mesh[e];
        if (l >= osl_tile_levels(sizes[e], o->levels))
            continue;
        int size = sizes[e] >> l, gx, gy;
        osl_level_origin(l, o->geo_w, o->geo_h0, &gx, &gy);
        gx += o->geo[e].x >> l;
        gy += o->geo[e].y >> l;
        if (size != scratch_size) {
            glDeleteTextures(channels, scratch);
            glGenTextures(channels, scratch);
            for (int t = 0; t < channels; t++) {
                glBindTexture(GL_TEXTURE_2D, scratch[t]);
                glTexStorage2D(GL_TEXTURE_2D, 1, GL_RGBA32F, size, size);
            }
            scratch_size = size;
        }
        for (int t = 0; t < channels; t++)
            glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + (GLenum)t, GL_TEXTURE_2D,
                                   scratch[t], 0);
        ok = glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
        if (!ok) {
            snprintf(err, errlen, "osl: texture generation framebuffer incomplete");
            break;
        }
        glViewport(0, 0, size, size);
        glClearColor(0, 0, 0, 0);
        glClear(GL_COLOR_BUFFER_BIT);
        if (o->textured)
            gpu_scene_bind_material(env->gpu, m, SB_LOC_MATERIAL);
        glBindVertexArray(env->gpu->vao[m]);
        glDrawElements(GL_TRIANGLES, (GLsizei)s->meshes[m].index_count, GL_UNSIGNED_INT, NULL);
        if (m >= SCENE_MESH_PROCEDURAL && !dilate_entry(o, &s->meshes[m], scratch, channels, size)) {
            snprintf(err, errlen, "osl: out of memory filling gutters");
            ok = false;
            break;
        }
        for (int t = 0; t < channels; t++)
            glCopyImageSubData(scratch[t], GL_TEXTURE_2D, 0, 0, 0, 0, texs[t], GL_TEXTURE_2D, 0,
                               gx, gy, 0, size, size, 1);
    }
    glDeleteTextures(channels, scratch);
    glBindVertexArray(0);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDeleteFramebuffers(1, &fbo);
    free(sizes);
    free(mesh);
    return ok;
}
