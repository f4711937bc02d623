#include "common/timing_series.h"

#include <string.h>

#include "common/result_keys.h"

bool timing_renderer_is_software(const char *gl_renderer)
{
    static const char *const software[] = {"llvmpipe", "softpipe", "SwiftShader", NULL};
    for (const char *const *s = software; gl_renderer && *s; s++)
        if (strstr(gl_renderer, *s))
            return true;
    return false;
}

const char *timing_series_for_renderer(const char *gl_renderer)
{
    return !gl_renderer || timing_renderer_is_software(gl_renderer) ? RK_FRAME_MS : RK_GPU_MS;
}
