#ifndef SHADEBENCH_TIMING_SERIES_H
#define SHADEBENCH_TIMING_SERIES_H

/* Which timing series compares techniques on a device, written once for
 * everything that picks one by default (the client's gate, ab and history,
 * the daemon's charts): frame_ms on software renderers (llvmpipe, softpipe,
 * SwiftShader), whose GL_TIME_ELAPSED covers rasterization only, and
 * without a renderer string; gpu_ms on GPUs. Pure; any thread. */

#include <stdbool.h>

/* True for a software renderer's GL_RENDERER string. */
bool timing_renderer_is_software(const char *gl_renderer);

/* RK_FRAME_MS or RK_GPU_MS (common/result_keys.h) for a GL_RENDERER string
 * (NULL: unknown, frame_ms). */
const char *timing_series_for_renderer(const char *gl_renderer);

#endif
