#ifndef SHADEBENCH_TONE_CURVES_H
#define SHADEBENCH_TONE_CURVES_H

/* The look's tone curves (look.tonemap) and the sRGB encoding, in C: the
 * resolve applies them in GLSL (shaders/harness/resolve.frag follows these
 * formulas), and they are unit-tested here. Pure; any thread.
 *
 * How they relate to the Khronos glTF Sample Viewer's (its
 * tonemapping.glsl), for a reference render driven with the same look:
 *  - "aces" is Narkowicz's fit after a 0.6 scale (his own exposure
 *    correction): the viewer's "ACES Narkowicz" at exposure 0.6 times ours;
 *  - "pbr_neutral" is the Khronos PBR Neutral curve, the same formula;
 *  - "srgb" is no curve, a clamp: the viewer's "None" (linear);
 *  - every curve then encodes with the exact sRGB transfer function
 *    (IEC 61966-2-1) unless look.transfer is "gamma_2.2", the viewer's
 *    x^(1/2.2): the two agree at 0 and 1 and differ most in the shadows
 *    (linear 0.01: sRGB 25.5 of 255, gamma 2.2 31.4). */

/* Tone curves on a linear value (after exposure), to [0, 1]. */
double tonemap_reinhard(double x);
double tonemap_aces(double x); /* Narkowicz's 2015 fit of the ACES RRT+ODT */
/* Khronos PBR Neutral (github.com/KhronosGroup/ToneMapping, PBR_Neutral):
 * on a colour, since it desaturates towards white; rgb in place, linear
 * Rec. 709 in (negative components read as 0), linear [0, 1] out. */
void tonemap_pbr_neutral(double rgb[3]);
/* The sRGB transfer function (IEC 61966-2-1) on [0, 1]. */
double srgb_encode(double linear);
/* look.transfer "gamma_2.2": x^(1/2.2) on [0, 1], the glTF Sample Viewer's. */
double gamma22_encode(double linear);

#endif
