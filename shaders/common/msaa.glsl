// The output's depth (and a g-buffer's planes) as a program that reads them
// sees them: sampler2D at msaa 1, sampler2DMS with SB_MSAA_SAMPLES samples
// a pixel otherwise (the harness #defines it, daemon/harness/run.c).
#ifndef MSAA_GLSL
#define MSAA_GLSL 1
#ifdef SB_MSAA_SAMPLES
#define MSAA_SAMPLES SB_MSAA_SAMPLES
#define msaa_sampler2D sampler2DMS
#define msaa_fetch(tex, pixel, sample) texelFetch(tex, pixel, sample)
#else
#define MSAA_SAMPLES 1
#define msaa_sampler2D sampler2D
#define msaa_fetch(tex, pixel, sample) texelFetch(tex, pixel, 0)
#endif
#endif
