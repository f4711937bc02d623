#ifndef SHADEBENCH_PBR_MATH_H
#define SHADEBENCH_PBR_MATH_H

/* The physically based lighting model in C (GL-free): the same GGX, Smith
 * height-correlated and Schlick terms as shaders/common/pbr.glsl, so that
 * the unit tests can check the model itself (normalisation, energy against
 * roughness, the white furnace of the split sum), and the split-sum
 * environment BRDF table (Karis 2013) the image-based lighting samples.
 * Pure functions; any thread. */

#include <stdbool.h>

/* Perceptual roughness is clamped to this before alpha = roughness^2: GGX's
 * peak 1 / (pi alpha^2) then stays within a half float under the scene's
 * lights, and roughness 0 (D = 0/0 at N = H) never reaches a shader's
 * division. Filament's bound for half-float targets. Passed to the shaders
 * as a #define so that C and GLSL cannot disagree. */
#define PBR_MIN_ROUGHNESS 0.089

double pbr_alpha(double roughness);
/* GGX normal distribution, alpha = roughness^2. */
double pbr_d_ggx(double NoH, double alpha);
/* G2 / (4 NoL NoV), height-correlated Smith for GGX. */
double pbr_v_smith(double NoV, double NoL, double alpha);
double pbr_f_schlick(double f0, double VoH);

/* Point i of n of the Hammersley set in [0, 1)^2. */
void pbr_hammersley(unsigned i, unsigned n, double *u, double *v);
/* A half vector drawn from GGX's D(h) (n.h) around +z for the point (u, v). */
void pbr_sample_ggx(double u, double v, double alpha, double h[3]);

/* The split sum's environment BRDF at (roughness, NoV): the scale A and bias
 * B of F0 in the specular albedo F0 A + B, by importance sampling GGX with
 * `samples` Hammersley points. */
void pbr_env_brdf(double roughness, double NoV, int samples, double *a, double *b);

/* The table the shaders sample: size x size texels of (A, B), NoV along x and
 * roughness along y at the texel centres, row-major from y = 0. */
bool pbr_env_brdf_table(int size, int samples, float *out);

/* The specular lobe's directional albedo (fraction of the energy arriving
 * from V that it reflects) for a material of reflectance f0 at NoV, by
 * uniform hemisphere sampling of the full BRDF (not the split sum): the
 * reference the energy tests hold the model to. */
double pbr_specular_albedo(double roughness, double NoV, double f0, int samples);

#endif
