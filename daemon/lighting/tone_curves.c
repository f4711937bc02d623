#include "daemon/lighting/tone_curves.h"

#include <math.h>

double tonemap_reinhard(double x) { return x > 0 ? x / (1.0 + x) : 0.0; }

double tonemap_aces(double x)
{
    if (x <= 0)
        return 0.0;
    x *= 0.6; /* Narkowicz's fit takes the exposure the RRT assumes */
    double y = (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14);
    return y < 0 ? 0 : y > 1 ? 1 : y;
}

void tonemap_pbr_neutral(double rgb[3])
{
    /* Highlights compress from start (0.8 less the F90 of 0.04 the curve
     * takes off the shadows) towards 1, desaturating at rate 0.15. */
    const double start = 0.8 - 0.04, desaturation = 0.15;
    for (int k = 0; k < 3; k++)
        rgb[k] = rgb[k] > 0 ? rgb[k] : 0.0;
    double x = fmin(rgb[0], fmin(rgb[1], rgb[2]));
    double offset = x < 0.08 ? x - 6.25 * x * x : 0.04;
    for (int k = 0; k < 3; k++)
        rgb[k] -= offset;
    double peak = fmax(rgb[0], fmax(rgb[1], rgb[2]));
    if (peak < start)
        return;
    double d = 1.0 - start;
    double new_peak = 1.0 - d * d / (peak + d - start);
    double g = 1.0 - 1.0 / (desaturation * (peak - new_peak) + 1.0);
    for (int k = 0; k < 3; k++) {
        double c = rgb[k] * new_peak / peak;
        rgb[k] = c + (new_peak - c) * g;
    }
}

double srgb_encode(double c)
{
    c = c < 0 ? 0 : c > 1 ? 1 : c;
    return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

double gamma22_encode(double c)
{
    c = c < 0 ? 0 : c > 1 ? 1 : c;
    return pow(c, 1.0 / 2.2);
}
