#include "daemon/gpu/pass.h"

#include <math.h>
#include <string.h>

#include "daemon/gpu/bindings.h"

bool gpu_passes_init(struct gpu_passes *p, struct gpu_timer *timer, const char *const *names,
                     bool debug_groups)
{
    memset(p, 0, sizeof(*p));
    p->timer = timer;
    p->debug_groups = debug_groups;
    for (int i = 0; names && names[i]; i++)
        if (gpu_passes_add(p, names[i]) < 0)
            return false;
    return true;
}

int gpu_passes_add(struct gpu_passes *p, const char *name)
{
    if (p->count >= GPU_MAX_PASSES)
        return -1;
    p->names[p->count] = name;
    return p->count++;
}

void gpu_pass_begin(const struct gpu_passes *p, int pass, GLuint fbo, int w, int h)
{
    gpu_timer_section(p->timer, pass);
    if (p->debug_groups)
        glPushDebugGroup(GL_DEBUG_SOURCE_APPLICATION, (GLuint)pass, -1, p->names[pass]);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glViewport(0, 0, w, h);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glEnable(GL_CULL_FACE);
    glCullFace(GL_BACK);
    glFrontFace(GL_CCW);
    glDisable(GL_BLEND);
    glDisable(GL_SCISSOR_TEST);
    glDisable(GL_STENCIL_TEST);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
}

void gpu_pass_end(const struct gpu_passes *p)
{
    if (p->debug_groups)
        glPopDebugGroup();
}

bool gpu_frame_block_init(struct gpu_frame_block *b)
{
    glGenBuffers(1, &b->ubo);
    glBindBuffer(GL_UNIFORM_BUFFER, b->ubo);
    glBufferData(GL_UNIFORM_BUFFER, sizeof(struct gpu_frame_data), NULL, GL_DYNAMIC_DRAW);
    glBindBuffer(GL_UNIFORM_BUFFER, 0);
    return b->ubo != 0;
}

void gpu_frame_block_finish(struct gpu_frame_block *b)
{
    if (b->ubo)
        glDeleteBuffers(1, &b->ubo);
    b->ubo = 0;
}

void gpu_frame_block_update(struct gpu_frame_block *b, const struct gpu_frame_data *d)
{
    glBindBuffer(GL_UNIFORM_BUFFER, b->ubo);
    glBufferSubData(GL_UNIFORM_BUFFER, 0, sizeof(*d), d);
    glBindBuffer(GL_UNIFORM_BUFFER, 0);
    glBindBufferBase(GL_UNIFORM_BUFFER, SB_UBO_FRAME, b->ubo);
}

bool mat4_invert(const float m[16], float out[16])
{
    /* Cofactor expansion in double, for matrices near the far plane's scale. */
    double inv[16], a[16];
    for (int i = 0; i < 16; i++)
        a[i] = m[i];
    inv[0] = a[5] * a[10] * a[15] - a[5] * a[11] * a[14] - a[9] * a[6] * a[15] +
             a[9] * a[7] * a[14] + a[13] * a[6] * a[11] - a[13] * a[7] * a[10];
    inv[4] = -a[4] * a[10] * a[15] + a[4] * a[11] * a[14] + a[8] * a[6] * a[15] -
             a[8] * a[7] * a[14] - a[12] * a[6] * a[11] + a[12] * a[7] * a[10];
    inv[8] = a[4] * a[9] * a[15] - a[4] * a[11] * a[13] - a[8] * a[5] * a[15] +
             a[8] * a[7] * a[13] + a[12] * a[5] * a[11] - a[12] * a[7] * a[9];
    inv[12] = -a[4] * a[9] * a[14] + a[4] * a[10] * a[13] + a[8] * a[5] * a[14] -
              a[8] * a[6] * a[13] - a[12] * a[5] * a[10] + a[12] * a[6] * a[9];
    inv[1] = -a[1] * a[10] * a[15] + a[1] * a[11] * a[14] + a[9] * a[2] * a[15] -
             a[9] * a[3] * a[14] - a[13] * a[2] * a[11] + a[13] * a[3] * a[10];
    inv[5] = a[0] * a[10] * a[15] - a[0] * a[11] * a[14] - a[8] * a[2] * a[15] +
             a[8] * a[3] * a[14] + a[12] * a[2] * a[11] - a[12] * a[3] * a[10];
    inv[9] = -a[0] * a[9] * a[15] + a[0] * a[11] * a[13] + a[8] * a[1] * a[15] -
             a[8] * a[3] * a[13] - a[12] * a[1] * a[11] + a[12] * a[3] * a[9];
    inv[13] = a[0] * a[9] * a[14] - a[0] * a[10] * a[13] - a[8] * a[1] * a[14] +
              a[8] * a[2] * a[13] + a[12] * a[1] * a[10] - a[12] * a[2] * a[9];
    inv[2] = a[1] * a[6] * a[15] - a[1] * a[7] * a[14] - a[5] * a[2] * a[15] +
             a[5] * a[3] * a[14] + a[13] * a[2] * a[7] - a[13] * a[3] * a[6];
    inv[6] = -a[0] * a[6] * a[15] + a[0] * a[7] * a[14] + a[4] * a[2] * a[15] -
             a[4] * a[3] * a[14] - a[12] * a[2] * a[7] + a[12] * a[3] * a[6];
    inv[10] = a[0] * a[5] * a[15] - a[0] * a[7] * a[13] - a[4] * a[1] * a[15] +
              a[4] * a[3] * a[13] + a[12] * a[1] * a[7] - a[12] * a[3] * a[5];
    inv[14] = -a[0] * a[5] * a[14] + a[0] * a[6] * a[13] + a[4] * a[1] * a[14] -
              a[4] * a[2] * a[13] - a[12] * a[1] * a[6] + a[12] * a[2] * a[5];
    inv[3] = -a[1] * a[6] * a[11] + a[1] * a[7] * a[10] + a[5] * a[2] * a[11] -
             a[5] * a[3] * a[10] - a[9] * a[2] * a[7] + a[9] * a[3] * a[6];
    inv[7] = a[0] * a[6] * a[11] - a[0] * a[7] * a[10] - a[4] * a[2] * a[11] +
             a[4] * a[3] * a[10] + a[8] * a[2] * a[7] - a[8] * a[3] * a[6];
    inv[11] = -a[0] * a[5] * a[11] + a[0] * a[7] * a[9] + a[4] * a[1] * a[11] -
              a[4] * a[3] * a[9] - a[8] * a[1] * a[7] + a[8] * a[3] * a[5];
    inv[15] = a[0] * a[5] * a[10] - a[0] * a[6] * a[9] - a[4] * a[1] * a[10] +
              a[4] * a[2] * a[9] + a[8] * a[1] * a[6] - a[8] * a[2] * a[5];
    double det = a[0] * inv[0] + a[1] * inv[4] + a[2] * inv[8] + a[3] * inv[12];
    if (det == 0 || !isfinite(det))
        return false;
    for (int i = 0; i < 16; i++)
        out[i] = (float)(inv[i] / det);
    return true;
}
