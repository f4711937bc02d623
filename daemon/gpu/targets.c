#define _POSIX_C_SOURCE 200809L
#include "daemon/gpu/targets.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct target {
    char name[32];
    GLuint tex;
    GLenum format;
    int w, h;
    int samples; /* asked for; 1: GL_TEXTURE_2D; more: GL_TEXTURE_2D_MULTISAMPLE */
    int given;   /* what the driver allocated (at least samples) */
    unsigned epoch; /* the pool's epoch when it was last asked for */
};

struct framebuffer {
    char name[32];
    GLuint fbo;
    GLuint colors[8];
    int ncolors;
    GLuint depth;
};

struct gpu_targets {
    unsigned epoch;
    struct target targets[GPU_TARGETS_MAX];
    struct framebuffer fbos[GPU_TARGETS_MAX];
};

struct gpu_targets *gpu_targets_create(void) { return calloc(1, sizeof(struct gpu_targets)); }

void gpu_targets_destroy(struct gpu_targets *t)
{
    if (!t)
        return;
    for (int i = 0; i < GPU_TARGETS_MAX; i++) {
        if (t->targets[i].tex)
            glDeleteTextures(1, &t->targets[i].tex);
        if (t->fbos[i].fbo)
            glDeleteFramebuffers(1, &t->fbos[i].fbo);
    }
    free(t);
}

static double format_bytes(GLenum format)
{
    switch (format) {
    case GL_RGBA32F:
        return 16;
    case GL_RGBA16F:
    case GL_RG32F:
        return 8;
    case GL_DEPTH_COMPONENT32F:
    case GL_DEPTH_COMPONENT24:
    case GL_DEPTH24_STENCIL8:
    case GL_RGBA8:
    case GL_R32F:
    case GL_RG16F:
    case GL_R32UI:
    case GL_RGB10_A2:
        return 4;
    default:
        return 4;
    }
}

GLuint gpu_targets_texture(struct gpu_targets *t, const char *name, GLenum format, int w, int h,
                           char *err, size_t errlen)
{
    return gpu_targets_texture_ms(t, name, format, w, h, 1, err, errlen);
}

GLuint gpu_targets_texture_ms(struct gpu_targets *t, const char *name, GLenum format, int w,
                              int h, int samples, char *err, size_t errlen)
{
    struct target *slot = NULL;
    samples = samples > 1 ? samples : 1;
    for (int i = 0; i < GPU_TARGETS_MAX && !slot; i++)
        if (t->targets[i].tex && strcmp(t->targets[i].name, name) == 0)
            slot = &t->targets[i];
    if (slot && slot->format == format && slot->w == w && slot->h == h &&
        slot->samples == samples) {
        slot->epoch = t->epoch;
        return slot->tex;
    }
    for (int i = 0; i < GPU_TARGETS_MAX && !slot; i++)
        if (!t->targets[i].tex)
            slot = &t->targets[i];
    if (!slot) {
        snprintf(err, errlen, "render target %s: the pool's %d targets are in use", name,
                 GPU_TARGETS_MAX);
        return 0;
    }
    if (slot->tex)
        glDeleteTextures(1, &slot->tex);
    snprintf(slot->name, sizeof(slot->name), "%s", name);
    slot->format = format;
    slot->w = w;
    slot->h = h;
    slot->samples = slot->given = samples;
    slot->epoch = t->epoch;
    glGenTextures(1, &slot->tex);
    if (samples > 1) {
        /* Fixed sample locations: every plane of a framebuffer places its
         * samples alike, which a g-buffer read per sample relies on. A
         * multisampled texture has no sampler state to set. */
        glBindTexture(GL_TEXTURE_2D_MULTISAMPLE, slot->tex);
        glTexStorage2DMultisample(GL_TEXTURE_2D_MULTISAMPLE, samples, format, w, h, GL_TRUE);
        /* A driver may give more samples than asked (llvmpipe makes 2 into
         * 4): count, and let readers loop over, the ones it gave. */
        GLint given = 0;
        glGetTexLevelParameteriv(GL_TEXTURE_2D_MULTISAMPLE, 0, GL_TEXTURE_SAMPLES, &given);
        slot->given = given > samples ? given : samples;
        glBindTexture(GL_TEXTURE_2D_MULTISAMPLE, 0);
    } else {
        glBindTexture(GL_TEXTURE_2D, slot->tex);
        glTexStorage2D(GL_TEXTURE_2D, 1, format, w, h);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
        glBindTexture(GL_TEXTURE_2D, 0);
    }
    if (glGetError() != GL_NO_ERROR) {
        snprintf(err, errlen,
                 "render target %s (%dx%d, format 0x%04x, %d samples) could not be allocated",
                 name, w, h, format, samples);
        glDeleteTextures(1, &slot->tex);
        memset(slot, 0, sizeof(*slot));
        return 0;
    }
    /* Framebuffers over the old texture must re-attach. */
    for (int i = 0; i < GPU_TARGETS_MAX; i++)
        t->fbos[i].ncolors = -1;
    return slot->tex;
}

static const struct target *find_target(const struct gpu_targets *t, GLuint tex)
{
    for (int i = 0; tex && i < GPU_TARGETS_MAX; i++)
        if (t->targets[i].tex == tex)
            return &t->targets[i];
    return NULL;
}

static bool has_stencil(const struct gpu_targets *t, GLuint tex)
{
    const struct target *x = find_target(t, tex);
    return x && (x->format == GL_DEPTH24_STENCIL8 || x->format == GL_DEPTH32F_STENCIL8);
}

int gpu_targets_samples(const struct gpu_targets *t, GLuint tex)
{
    const struct target *x = find_target(t, tex);
    return x ? x->given : 1;
}

/* The texture target a pool texture attaches and binds as. */
GLenum gpu_targets_kind(const struct gpu_targets *t, GLuint tex)
{
    return gpu_targets_samples(t, tex) > 1 ? GL_TEXTURE_2D_MULTISAMPLE : GL_TEXTURE_2D;
}

GLuint gpu_targets_fbo(struct gpu_targets *t, const char *name, const GLuint *colors, int ncolors,
                       GLuint depth, char *err, size_t errlen)
{
    struct framebuffer *slot = NULL;
    for (int i = 0; i < GPU_TARGETS_MAX && !slot; i++)
        if (t->fbos[i].fbo && strcmp(t->fbos[i].name, name) == 0)
            slot = &t->fbos[i];
    if (slot && slot->ncolors == ncolors && slot->depth == depth &&
        memcmp(slot->colors, colors, (size_t)ncolors * sizeof(GLuint)) == 0)
        return slot->fbo;
    for (int i = 0; i < GPU_TARGETS_MAX && !slot; i++)
        if (!t->fbos[i].fbo)
            slot = &t->fbos[i];
    if (!slot || ncolors > 8) {
        snprintf(err, errlen, "framebuffer %s: no room in the pool", name);
        return 0;
    }
    if (!slot->fbo)
        glGenFramebuffers(1, &slot->fbo);
    snprintf(slot->name, sizeof(slot->name), "%s", name);
    glBindFramebuffer(GL_FRAMEBUFFER, slot->fbo);
    GLenum bufs[8];
    for (int i = 0; i < 8; i++) {
        GLuint tex = i < ncolors ? colors[i] : 0;
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + (GLenum)i,
                               gpu_targets_kind(t, tex), tex, 0);
        bufs[i] = GL_COLOR_ATTACHMENT0 + (GLenum)i;
    }
    /* Detach both first: the attachment point follows the format, and a
     * slot may have held the other kind. */
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_TEXTURE_2D, 0, 0);
    glFramebufferTexture2D(GL_FRAMEBUFFER,
                           has_stencil(t, depth) ? GL_DEPTH_STENCIL_ATTACHMENT : GL_DEPTH_ATTACHMENT,
                           gpu_targets_kind(t, depth), depth, 0);
    if (ncolors)
        glDrawBuffers(ncolors, bufs);
    else
        glDrawBuffer(GL_NONE);
    GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    if (status != GL_FRAMEBUFFER_COMPLETE) {
        snprintf(err, errlen, "framebuffer %s incomplete (0x%04x)", name, status);
        slot->ncolors = -1;
        return 0;
    }
    memcpy(slot->colors, colors, (size_t)ncolors * sizeof(GLuint));
    slot->ncolors = ncolors;
    slot->depth = depth;
    return slot->fbo;
}

double gpu_targets_bytes(const struct gpu_targets *t)
{
    double b = 0;
    for (int i = 0; i < GPU_TARGETS_MAX; i++)
        if (t->targets[i].tex)
            b += format_bytes(t->targets[i].format) * t->targets[i].w * t->targets[i].h *
                 t->targets[i].given;
    return b;
}

void gpu_targets_new_epoch(struct gpu_targets *t) { t->epoch++; }

double gpu_targets_bytes_in_use(const struct gpu_targets *t)
{
    double b = 0;
    for (int i = 0; i < GPU_TARGETS_MAX; i++)
        if (t->targets[i].tex && t->targets[i].epoch == t->epoch)
            b += format_bytes(t->targets[i].format) * t->targets[i].w * t->targets[i].h *
                 t->targets[i].given;
    return b;
}
