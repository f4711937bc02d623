#ifndef SHADEBENCH_TONE_CURVES_H
#define SHADEBENCH_TONE_CURVES_H

/* The look's tone curves (look.tonemap) and the sRGB encoding, in C: the
 * resolve applies them in GLSL (shaders/harness/resolve.frag follows these
 * formulas), and they are unit-tested here. Pure; any thread. */

/* Tone curves on a linear value (after exposure), to [0, 1]. */
double tonemap_reinhard(double x);
double tonemap_aces(double x); /* Narkowicz's 2015 fit of the ACES RRT+ODT */
/* The sRGB transfer function (IEC 61966-2-1) on [0, 1]. */
double srgb_encode(double linear);

#endif
