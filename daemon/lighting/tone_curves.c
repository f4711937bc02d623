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

double srgb_encode(double c)
{
    c = c < 0 ? 0 : c > 1 ? 1 : c;
    return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}
