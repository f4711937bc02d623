#include "daemon/gpu/caps.h"

#include <epoxy/gl.h>
#include <string.h>

static int geti(GLenum name)
{
    GLint v = 0;
    glGetIntegerv(name, &v);
    return v;
}

void gpu_caps_query(struct gpu_caps *c)
{
    memset(c, 0, sizeof(*c));
    c->max_texture_size = geti(GL_MAX_TEXTURE_SIZE);
    c->max_renderbuffer_size = geti(GL_MAX_RENDERBUFFER_SIZE);
    glGetIntegerv(GL_MAX_VIEWPORT_DIMS, c->max_viewport);
    c->max_color_attachments = geti(GL_MAX_COLOR_ATTACHMENTS);
    c->max_draw_buffers = geti(GL_MAX_DRAW_BUFFERS);
    c->max_texture_units = geti(GL_MAX_COMBINED_TEXTURE_IMAGE_UNITS);
    for (GLuint i = 0; i < 3; i++) {
        glGetIntegeri_v(GL_MAX_COMPUTE_WORK_GROUP_COUNT, i, &c->max_compute_work_group_count[i]);
        glGetIntegeri_v(GL_MAX_COMPUTE_WORK_GROUP_SIZE, i, &c->max_compute_work_group_size[i]);
    }
    c->max_compute_invocations = geti(GL_MAX_COMPUTE_WORK_GROUP_INVOCATIONS);
    c->max_compute_shared_bytes = geti(GL_MAX_COMPUTE_SHARED_MEMORY_SIZE);
    c->max_compute_image_uniforms = geti(GL_MAX_COMPUTE_IMAGE_UNIFORMS);
    c->max_ssbo_bindings = geti(GL_MAX_SHADER_STORAGE_BUFFER_BINDINGS);
    c->max_uniform_block_bytes = geti(GL_MAX_UNIFORM_BLOCK_SIZE);
    GLint64 ssbo = 0;
    glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &ssbo);
    c->max_ssbo_bytes = ssbo;
    glGetQueryiv(GL_TIME_ELAPSED, GL_QUERY_COUNTER_BITS, &c->timer_query_bits);
    c->max_samples = geti(GL_MAX_SAMPLES);
    c->max_color_texture_samples = geti(GL_MAX_COLOR_TEXTURE_SAMPLES);
    c->max_depth_texture_samples = geti(GL_MAX_DEPTH_TEXTURE_SAMPLES);
    c->max_integer_samples = geti(GL_MAX_INTEGER_SAMPLES);
    int m = c->max_samples;
    m = c->max_color_texture_samples < m ? c->max_color_texture_samples : m;
    m = c->max_depth_texture_samples < m ? c->max_depth_texture_samples : m;
    /* A job asks for a power of two: the largest one within the limits. */
    c->max_msaa = 1;
    while (c->max_msaa * 2 <= m && c->max_msaa < 8)
        c->max_msaa *= 2;
    c->debug_groups = epoxy_gl_version() >= 43 || epoxy_has_gl_extension("GL_KHR_debug");
}

json_t *gpu_caps_json(const struct gpu_caps *c)
{
    json_t *j = json_pack(
        "{s:i, s:i, s:[i, i], s:i, s:i, s:i, s:[i, i, i], s:[i, i, i], s:i, s:i, s:i, s:i, s:i, "
        "s:I, s:i, s:b}",
        "max_texture_size", c->max_texture_size, "max_renderbuffer_size",
        c->max_renderbuffer_size, "max_viewport_dims", c->max_viewport[0], c->max_viewport[1],
        "max_color_attachments", c->max_color_attachments, "max_draw_buffers",
        c->max_draw_buffers, "max_texture_units", c->max_texture_units,
        "max_compute_work_group_count", c->max_compute_work_group_count[0],
        c->max_compute_work_group_count[1], c->max_compute_work_group_count[2],
        "max_compute_work_group_size", c->max_compute_work_group_size[0],
        c->max_compute_work_group_size[1], c->max_compute_work_group_size[2],
        "max_compute_invocations", c->max_compute_invocations, "max_compute_shared_bytes",
        c->max_compute_shared_bytes, "max_compute_image_uniforms", c->max_compute_image_uniforms,
        "max_ssbo_bindings", c->max_ssbo_bindings, "max_uniform_block_bytes",
        c->max_uniform_block_bytes, "max_ssbo_bytes", (json_int_t)c->max_ssbo_bytes,
        "timer_query_bits", c->timer_query_bits, "debug_groups", c->debug_groups);
    json_object_set_new(j, "max_samples", json_integer(c->max_samples));
    json_object_set_new(j, "max_color_texture_samples",
                        json_integer(c->max_color_texture_samples));
    json_object_set_new(j, "max_depth_texture_samples",
                        json_integer(c->max_depth_texture_samples));
    json_object_set_new(j, "max_integer_samples", json_integer(c->max_integer_samples));
    json_object_set_new(j, "max_msaa", json_integer(c->max_msaa));
    return j;
}

static bool gl_has_extension(const char *name, void *ctx)
{
    (void)ctx;
    return epoxy_has_gl_extension(name);
}

static void gl_get_integers(unsigned pname, int *values, void *ctx)
{
    (void)ctx;
    glGetIntegerv((GLenum)pname, values);
}

void gpu_memory_sample_gl(struct gpu_memory_sample *out)
{
    const struct gpu_memory_reader reader = {gl_has_extension, gl_get_integers, NULL};
    gpu_memory_read(&reader, out);
}
