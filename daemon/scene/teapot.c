/* The Utah teapot from its Bezier patches; see teapot.h. The control points
 * and patches are Newell's public-domain data set as it circulates (for
 * instance in Steve Baker's teaset), indices from zero. */
#include "daemon/scene/teapot.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The teapot's 306 control points (x, y, z with z up, as published). */
static const float TEAPOT_POINTS[TEAPOT_CONTROL_POINTS][3] = {
    {1.4, 0.0, 2.4},
    {1.4, -0.784, 2.4},
    {0.784, -1.4, 2.4},
    {0.0, -1.4, 2.4},
    {1.3375, 0.0, 2.53125},
    {1.3375, -0.749, 2.53125},
    {0.749, -1.3375, 2.53125},
    {0.0, -1.3375, 2.53125},
    {1.4375, 0.0, 2.53125},
    {1.4375, -0.805, 2.53125},
    {0.805, -1.4375, 2.53125},
    {0.0, -1.4375, 2.53125},
    {1.5, 0.0, 2.4},
    {1.5, -0.84, 2.4},
    {0.84, -1.5, 2.4},
    {0.0, -1.5, 2.4},
    {-0.784, -1.4, 2.4},
    {-1.4, -0.784, 2.4},
    {-1.4, 0.0, 2.4},
    {-0.749, -1.3375, 2.53125},
    {-1.3375, -0.749, 2.53125},
    {-1.3375, 0.0, 2.53125},
    {-0.805, -1.4375, 2.53125},
    {-1.4375, -0.805, 2.53125},
    {-1.4375, 0.0, 2.53125},
    {-0.84, -1.5, 2.4},
    {-1.5, -0.84, 2.4},
    {-1.5, 0.0, 2.4},
    {-1.4, 0.784, 2.4},
    {-0.784, 1.4, 2.4},
    {0.0, 1.4, 2.4},
    {-1.3375, 0.749, 2.53125},
    {-0.749, 1.3375, 2.53125},
    {0.0, 1.3375, 2.53125},
    {-1.4375, 0.805, 2.53125},
    {-0.805, 1.4375, 2.53125},
    {0.0, 1.4375, 2.53125},
    {-1.5, 0.84, 2.4},
    {-0.84, 1.5, 2.4},
    {0.0, 1.5, 2.4},
    {0.784, 1.4, 2.4},
    {1.4, 0.784, 2.4},
    {0.749, 1.3375, 2.53125},
    {1.3375, 0.749, 2.53125},
    {0.805, 1.4375, 2.53125},
    {1.4375, 0.805, 2.53125},
    {0.84, 1.5, 2.4},
    {1.5, 0.84, 2.4},
    {1.75, 0.0, 1.875},
    {1.75, -0.98, 1.875},
    {0.98, -1.75, 1.875},
    {0.0, -1.75, 1.875},
    {2.0, 0.0, 1.35},
    {2.0, -1.12, 1.35},
    {1.12, -2.0, 1.35},
    {0.0, -2.0, 1.35},
    {2.0, 0.0, 0.9},
    {2.0, -1.12, 0.9},
    {1.12, -2.0, 0.9},
    {0.0, -2.0, 0.9},
    {-0.98, -1.75, 1.875},
    {-1.75, -0.98, 1.875},
    {-1.75, 0.0, 1.875},
    {-1.12, -2.0, 1.35},
    {-2.0, -1.12, 1.35},
    {-2.0, 0.0, 1.35},
    {-1.12, -2.0, 0.9},
    {-2.0, -1.12, 0.9},
    {-2.0, 0.0, 0.9},
    {-1.75, 0.98, 1.875},
    {-0.98, 1.75, 1.875},
    {0.0, 1.75, 1.875},
    {-2.0, 1.12, 1.35},
    {-1.12, 2.0, 1.35},
    {0.0, 2.0, 1.35},
    {-2.0, 1.12, 0.9},
    {-1.12, 2.0, 0.9},
    {0.0, 2.0, 0.9},
    {0.98, 1.75, 1.875},
    {1.75, 0.98, 1.875},
    {1.12, 2.0, 1.35},
    {2.0, 1.12, 1.35},
    {1.12, 2.0, 0.9},
    {2.0, 1.12, 0.9},
    {2.0, 0.0, 0.45},
    {2.0, -1.12, 0.45},
    {1.12, -2.0, 0.45},
    {0.0, -2.0, 0.45},
    {1.5, 0.0, 0.225},
    {1.5, -0.84, 0.225},
    {0.84, -1.5, 0.225},
    {0.0, -1.5, 0.225},
    {1.5, 0.0, 0.15},
    {1.5, -0.84, 0.15},
    {0.84, -1.5, 0.15},
    {0.0, -1.5, 0.15},
    {-1.12, -2.0, 0.45},
    {-2.0, -1.12, 0.45},
    {-2.0, 0.0, 0.45},
    {-0.84, -1.5, 0.225},
    {-1.5, -0.84, 0.225},
    {-1.5, 0.0, 0.225},
    {-0.84, -1.5, 0.15},
    {-1.5, -0.84, 0.15},
    {-1.5, 0.0, 0.15},
    {-2.0, 1.12, 0.45},
    {-1.12, 2.0, 0.45},
    {0.0, 2.0, 0.45},
    {-1.5, 0.84, 0.225},
    {-0.84, 1.5, 0.225},
    {0.0, 1.5, 0.225},
    {-1.5, 0.84, 0.15},
    {-0.84, 1.5, 0.15},
    {0.0, 1.5, 0.15},
    {1.12, 2.0, 0.45},
    {2.0, 1.12, 0.45},
    {0.84, 1.5, 0.225},
    {1.5, 0.84, 0.225},
    {0.84, 1.5, 0.15},
    {1.5, 0.84, 0.15},
    {-1.6, 0.0, 2.025},
    {-1.6, -0.3, 2.025},
    {-1.5, -0.3, 2.25},
    {-1.5, 0.0, 2.25},
    {-2.3, 0.0, 2.025},
    {-2.3, -0.3, 2.025},
    {-2.5, -0.3, 2.25},
    {-2.5, 0.0, 2.25},
    {-2.7, 0.0, 2.025},
    {-2.7, -0.3, 2.025},
    {-3.0, -0.3, 2.25},
    {-3.0, 0.0, 2.25},
    {-2.7, 0.0, 1.8},
    {-2.7, -0.3, 1.8},
    {-3.0, -0.3, 1.8},
    {-3.0, 0.0, 1.8},
    {-1.5, 0.3, 2.25},
    {-1.6, 0.3, 2.025},
    {-2.5, 0.3, 2.25},
    {-2.3, 0.3, 2.025},
    {-3.0, 0.3, 2.25},
    {-2.7, 0.3, 2.025},
    {-3.0, 0.3, 1.8},
    {-2.7, 0.3, 1.8},
    {-2.7, 0.0, 1.575},
    {-2.7, -0.3, 1.575},
    {-3.0, -0.3, 1.35},
    {-3.0, 0.0, 1.35},
    {-2.5, 0.0, 1.125},
    {-2.5, -0.3, 1.125},
    {-2.65, -0.3, 0.9375},
    {-2.65, 0.0, 0.9375},
    {-2.0, -0.3, 0.9},
    {-1.9, -0.3, 0.6},
    {-1.9, 0.0, 0.6},
    {-3.0, 0.3, 1.35},
    {-2.7, 0.3, 1.575},
    {-2.65, 0.3, 0.9375},
    {-2.5, 0.3, 1.125},
    {-1.9, 0.3, 0.6},
    {-2.0, 0.3, 0.9},
    {1.7, 0.0, 1.425},
    {1.7, -0.66, 1.425},
    {1.7, -0.66, 0.6},
    {1.7, 0.0, 0.6},
    {2.6, 0.0, 1.425},
    {2.6, -0.66, 1.425},
    {3.1, -0.66, 0.825},
    {3.1, 0.0, 0.825},
    {2.3, 0.0, 2.1},
    {2.3, -0.25, 2.1},
    {2.4, -0.25, 2.025},
    {2.4, 0.0, 2.025},
    {2.7, 0.0, 2.4},
    {2.7, -0.25, 2.4},
    {3.3, -0.25, 2.4},
    {3.3, 0.0, 2.4},
    {1.7, 0.66, 0.6},
    {1.7, 0.66, 1.425},
    {3.1, 0.66, 0.825},
    {2.6, 0.66, 1.425},
    {2.4, 0.25, 2.025},
    {2.3, 0.25, 2.1},
    {3.3, 0.25, 2.4},
    {2.7, 0.25, 2.4},
    {2.8, 0.0, 2.475},
    {2.8, -0.25, 2.475},
    {3.525, -0.25, 2.49375},
    {3.525, 0.0, 2.49375},
    {2.9, 0.0, 2.475},
    {2.9, -0.15, 2.475},
    {3.45, -0.15, 2.5125},
    {3.45, 0.0, 2.5125},
    {2.8, 0.0, 2.4},
    {2.8, -0.15, 2.4},
    {3.2, -0.15, 2.4},
    {3.2, 0.0, 2.4},
    {3.525, 0.25, 2.49375},
    {2.8, 0.25, 2.475},
    {3.45, 0.15, 2.5125},
    {2.9, 0.15, 2.475},
    {3.2, 0.15, 2.4},
    {2.8, 0.15, 2.4},
    {0.0, 0.0, 3.15},
    {0.0, -0.002, 3.15},
    {0.002, 0.0, 3.15},
    {0.8, 0.0, 3.15},
    {0.8, -0.45, 3.15},
    {0.45, -0.8, 3.15},
    {0.0, -0.8, 3.15},
    {0.0, 0.0, 2.85},
    {0.2, 0.0, 2.7},
    {0.2, -0.112, 2.7},
    {0.112, -0.2, 2.7},
    {0.0, -0.2, 2.7},
    {-0.002, 0.0, 3.15},
    {-0.45, -0.8, 3.15},
    {-0.8, -0.45, 3.15},
    {-0.8, 0.0, 3.15},
    {-0.112, -0.2, 2.7},
    {-0.2, -0.112, 2.7},
    {-0.2, 0.0, 2.7},
    {0.0, 0.002, 3.15},
    {-0.8, 0.45, 3.15},
    {-0.45, 0.8, 3.15},
    {0.0, 0.8, 3.15},
    {-0.2, 0.112, 2.7},
    {-0.112, 0.2, 2.7},
    {0.0, 0.2, 2.7},
    {0.45, 0.8, 3.15},
    {0.8, 0.45, 3.15},
    {0.112, 0.2, 2.7},
    {0.2, 0.112, 2.7},
    {0.4, 0.0, 2.55},
    {0.4, -0.224, 2.55},
    {0.224, -0.4, 2.55},
    {0.0, -0.4, 2.55},
    {1.3, 0.0, 2.55},
    {1.3, -0.728, 2.55},
    {0.728, -1.3, 2.55},
    {0.0, -1.3, 2.55},
    {1.3, 0.0, 2.4},
    {1.3, -0.728, 2.4},
    {0.728, -1.3, 2.4},
    {0.0, -1.3, 2.4},
    {-0.224, -0.4, 2.55},
    {-0.4, -0.224, 2.55},
    {-0.4, 0.0, 2.55},
    {-0.728, -1.3, 2.55},
    {-1.3, -0.728, 2.55},
    {-1.3, 0.0, 2.55},
    {-0.728, -1.3, 2.4},
    {-1.3, -0.728, 2.4},
    {-1.3, 0.0, 2.4},
    {-0.4, 0.224, 2.55},
    {-0.224, 0.4, 2.55},
    {0.0, 0.4, 2.55},
    {-1.3, 0.728, 2.55},
    {-0.728, 1.3, 2.55},
    {0.0, 1.3, 2.55},
    {-1.3, 0.728, 2.4},
    {-0.728, 1.3, 2.4},
    {0.0, 1.3, 2.4},
    {0.224, 0.4, 2.55},
    {0.4, 0.224, 2.55},
    {0.728, 1.3, 2.55},
    {1.3, 0.728, 2.55},
    {0.728, 1.3, 2.4},
    {1.3, 0.728, 2.4},
    {0.0, 0.0, 0.0},
    {1.5, 0.0, 0.15},
    {1.5, 0.84, 0.15},
    {0.84, 1.5, 0.15},
    {0.0, 1.5, 0.15},
    {1.5, 0.0, 0.075},
    {1.5, 0.84, 0.075},
    {0.84, 1.5, 0.075},
    {0.0, 1.5, 0.075},
    {1.425, 0.0, 0.0},
    {1.425, 0.798, 0.0},
    {0.798, 1.425, 0.0},
    {0.0, 1.425, 0.0},
    {-0.84, 1.5, 0.15},
    {-1.5, 0.84, 0.15},
    {-1.5, 0.0, 0.15},
    {-0.84, 1.5, 0.075},
    {-1.5, 0.84, 0.075},
    {-1.5, 0.0, 0.075},
    {-0.798, 1.425, 0.0},
    {-1.425, 0.798, 0.0},
    {-1.425, 0.0, 0.0},
    {-1.5, -0.84, 0.15},
    {-0.84, -1.5, 0.15},
    {0.0, -1.5, 0.15},
    {-1.5, -0.84, 0.075},
    {-0.84, -1.5, 0.075},
    {0.0, -1.5, 0.075},
    {-1.425, -0.798, 0.0},
    {-0.798, -1.425, 0.0},
    {0.0, -1.425, 0.0},
    {0.84, -1.5, 0.15},
    {1.5, -0.84, 0.15},
    {0.84, -1.5, 0.075},
    {1.5, -0.84, 0.075},
    {0.798, -1.425, 0.0},
    {1.425, -0.798, 0.0},
};

/* 32 bicubic patches, 16 control point indices each, row by row. */
static const short TEAPOT_PATCHES[TEAPOT_PATCH_COUNT][16] = {
    {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15},
    {3, 16, 17, 18, 7, 19, 20, 21, 11, 22, 23, 24, 15, 25, 26, 27},
    {18, 28, 29, 30, 21, 31, 32, 33, 24, 34, 35, 36, 27, 37, 38, 39},
    {30, 40, 41, 0, 33, 42, 43, 4, 36, 44, 45, 8, 39, 46, 47, 12},
    {12, 13, 14, 15, 48, 49, 50, 51, 52, 53, 54, 55, 56, 57, 58, 59},
    {15, 25, 26, 27, 51, 60, 61, 62, 55, 63, 64, 65, 59, 66, 67, 68},
    {27, 37, 38, 39, 62, 69, 70, 71, 65, 72, 73, 74, 68, 75, 76, 77},
    {39, 46, 47, 12, 71, 78, 79, 48, 74, 80, 81, 52, 77, 82, 83, 56},
    {56, 57, 58, 59, 84, 85, 86, 87, 88, 89, 90, 91, 92, 93, 94, 95},
    {59, 66, 67, 68, 87, 96, 97, 98, 91, 99, 100, 101, 95, 102, 103, 104},
    {68, 75, 76, 77, 98, 105, 106, 107, 101, 108, 109, 110, 104, 111, 112, 113},
    {77, 82, 83, 56, 107, 114, 115, 84, 110, 116, 117, 88, 113, 118, 119, 92},
    {120, 121, 122, 123, 124, 125, 126, 127, 128, 129, 130, 131, 132, 133, 134, 135},
    {123, 136, 137, 120, 127, 138, 139, 124, 131, 140, 141, 128, 135, 142, 143, 132},
    {132, 133, 134, 135, 144, 145, 146, 147, 148, 149, 150, 151, 68, 152, 153, 154},
    {135, 142, 143, 132, 147, 155, 156, 144, 151, 157, 158, 148, 154, 159, 160, 68},
    {161, 162, 163, 164, 165, 166, 167, 168, 169, 170, 171, 172, 173, 174, 175, 176},
    {164, 177, 178, 161, 168, 179, 180, 165, 172, 181, 182, 169, 176, 183, 184, 173},
    {173, 174, 175, 176, 185, 186, 187, 188, 189, 190, 191, 192, 193, 194, 195, 196},
    {176, 183, 184, 173, 188, 197, 198, 185, 192, 199, 200, 189, 196, 201, 202, 193},
    {203, 203, 203, 203, 206, 207, 208, 209, 210, 210, 210, 210, 211, 212, 213, 214},
    {203, 203, 203, 203, 209, 216, 217, 218, 210, 210, 210, 210, 214, 219, 220, 221},
    {203, 203, 203, 203, 218, 223, 224, 225, 210, 210, 210, 210, 221, 226, 227, 228},
    {203, 203, 203, 203, 225, 229, 230, 206, 210, 210, 210, 210, 228, 231, 232, 211},
    {211, 212, 213, 214, 233, 234, 235, 236, 237, 238, 239, 240, 241, 242, 243, 244},
    {214, 219, 220, 221, 236, 245, 246, 247, 240, 248, 249, 250, 244, 251, 252, 253},
    {221, 226, 227, 228, 247, 254, 255, 256, 250, 257, 258, 259, 253, 260, 261, 262},
    {228, 231, 232, 211, 256, 263, 264, 233, 259, 265, 266, 237, 262, 267, 268, 241},
    {269, 269, 269, 269, 278, 279, 280, 281, 274, 275, 276, 277, 270, 271, 272, 273},
    {269, 269, 269, 269, 281, 288, 289, 290, 277, 285, 286, 287, 273, 282, 283, 284},
    {269, 269, 269, 269, 290, 297, 298, 299, 287, 294, 295, 296, 284, 291, 292, 293},
    {269, 269, 269, 269, 299, 304, 305, 278, 296, 302, 303, 274, 293, 300, 301, 270},
};

const char *const teapot_part_names[] = {"rim", "body", "handle", "spout", "lid", "bottom", NULL};

/* Patch p belongs to this part: the data's order. */
enum teapot_part teapot_patch_part(int p)
{
    return p < 4 ? TEAPOT_RIM : p < 12 ? TEAPOT_BODY : p < 16 ? TEAPOT_HANDLE
         : p < 20 ? TEAPOT_SPOUT : p < 28 ? TEAPOT_LID : TEAPOT_BOTTOM;
}

/* The data's bounding box centre (x, y, z up), which the mesh is centred on. */
static const double CENTRE[3] = {(-3.0 + 3.525) / 2.0, 0.0, TEAPOT_HEIGHT / 2.0};

static void bernstein(double t, double b[4], double d[4])
{
    double s = 1.0 - t;
    b[0] = s * s * s, b[1] = 3.0 * t * s * s, b[2] = 3.0 * t * t * s, b[3] = t * t * t;
    d[0] = -3.0 * s * s, d[1] = 3.0 * s * s - 6.0 * t * s, d[2] = 6.0 * t * s - 3.0 * t * t;
    d[3] = 3.0 * t * t;
}

/* Position and the two tangents in the data's frame. */
static void eval_raw(int patch, double u, double v, double p[3], double pu[3], double pv[3])
{
    double bu[4], du[4], bv[4], dv[4];
    bernstein(u, bu, du);
    bernstein(v, bv, dv);
    memset(p, 0, 3 * sizeof(double));
    memset(pu, 0, 3 * sizeof(double));
    memset(pv, 0, 3 * sizeof(double));
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            const float *c = TEAPOT_POINTS[TEAPOT_PATCHES[patch][i * 4 + j]];
            for (int k = 0; k < 3; k++) {
                p[k] += bu[i] * bv[j] * c[k];
                pu[k] += du[i] * bv[j] * c[k];
                pv[k] += bu[i] * dv[j] * c[k];
            }
        }
}

static void cross(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

/* The data's (u, v) runs so that cross(Pu, Pv) points into the teapot on
 * every patch (rows run from the top down, columns around it clockwise
 * seen from above), so every patch is flipped; kept as a function so that a
 * data set with mixed orientations needs one change. test_teapot.c checks
 * the result independently (winding numbers). */
static bool patch_flipped(int patch)
{
    (void)patch;
    return true;
}

void teapot_eval(int patch, double u, double v, double pos[3], double normal[3])
{
    double p[3], pu[3], pv[3], n[3];
    eval_raw(patch, u, v, p, pu, pv);
    cross(pu, pv, n);
    double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (len < 1e-9) {
        /* A collapsed edge (the lid's knob and the bottom's centre are
         * patches with a whole row of control points at one point): the
         * normal is the limit from just inside the patch. */
        double u2 = u < 0.5 ? 1e-4 : 1.0 - 1e-4, v2 = v < 0.5 ? 1e-4 : 1.0 - 1e-4, q[3];
        eval_raw(patch, fabs(pu[0]) + fabs(pu[1]) + fabs(pu[2]) < 1e-9 ? u2 : u,
                 fabs(pv[0]) + fabs(pv[1]) + fabs(pv[2]) < 1e-9 ? v2 : v, q, pu, pv);
        cross(pu, pv, n);
        len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (len < 1e-12) {
            n[0] = n[1] = 0.0, n[2] = p[2] > CENTRE[2] ? 1.0 : -1.0;
            len = 1.0;
        }
    }
    double sign = patch_flipped(patch) ? -1.0 : 1.0;
    /* Data (x, y, z up) to y-up (x, z, -y): a rotation, so orientation holds. */
    pos[0] = p[0] - CENTRE[0];
    pos[1] = p[2] - CENTRE[2];
    pos[2] = -(p[1] - CENTRE[1]);
    normal[0] = sign * n[0] / len;
    normal[1] = sign * n[2] / len;
    normal[2] = -sign * n[1] / len;
}

enum { CHART_COLS = 8, CHART_ROWS = 4 };

bool mesh_create_teapot(struct mesh *out, int segments, float scale)
{
    memset(out, 0, sizeof(*out));
    if (segments < TEAPOT_MIN_SEGMENTS || segments > TEAPOT_MAX_SEGMENTS)
        return false;
    uint32_t side = (uint32_t)segments + 1;
    uint32_t verts = TEAPOT_PATCH_COUNT * side * side;
    uint32_t indices = TEAPOT_PATCH_COUNT * (uint32_t)segments * (uint32_t)segments * 6;
    out->vertices = calloc(verts, sizeof(*out->vertices));
    out->indices = calloc(indices, sizeof(*out->indices));
    if (!out->vertices || !out->indices) {
        mesh_finish(out);
        return false;
    }
    out->vertex_count = verts;
    out->index_count = indices;
    double bound = 0, uv_per_unit = INFINITY;
    uint32_t *idx = out->indices;
    for (int p = 0; p < TEAPOT_PATCH_COUNT; p++) {
        float c0 = (float)(p % CHART_COLS) / CHART_COLS, r0 = (float)(p / CHART_COLS) / CHART_ROWS;
        float chart[4] = {c0, r0, c0 + 1.0f / CHART_COLS, r0 + 1.0f / CHART_ROWS};
        uint32_t base = (uint32_t)p * side * side;
        double len_u = 0, len_v = 0, prev_u[3] = {0}, prev_v[3] = {0};
        for (uint32_t i = 0; i < side; i++)
            for (uint32_t j = 0; j < side; j++) {
                double u = (double)i / segments, v = (double)j / segments, pos[3], n[3];
                teapot_eval(p, u, v, pos, n);
                struct mesh_vertex *vx = &out->vertices[base + i * side + j];
                for (int k = 0; k < 3; k++) {
                    vx->pos[k] = (float)(pos[k] * scale);
                    vx->normal[k] = (float)n[k];
                }
                /* u runs along the chart's height, v along its width. */
                vx->uv[0] = chart[0] + (float)v / CHART_COLS;
                vx->uv[1] = chart[1] + (float)u / CHART_ROWS;
                memcpy(vx->chart, chart, sizeof(chart));
                double r = sqrt(pos[0] * pos[0] + pos[1] * pos[1] + pos[2] * pos[2]);
                bound = fmax(bound, r);
                /* Arc lengths along the patch's middle lines, for its UV density. */
                if (j == side / 2) {
                    if (i)
                        len_u += sqrt(pow(pos[0] - prev_u[0], 2) + pow(pos[1] - prev_u[1], 2) +
                                      pow(pos[2] - prev_u[2], 2));
                    memcpy(prev_u, pos, sizeof(pos));
                }
                if (i == side / 2) {
                    if (j)
                        len_v += sqrt(pow(pos[0] - prev_v[0], 2) + pow(pos[1] - prev_v[1], 2) +
                                      pow(pos[2] - prev_v[2], 2));
                    memcpy(prev_v, pos, sizeof(pos));
                }
            }
        /* The sparsest direction of the sparsest chart (the body's), as the
         * sphere does, so that "auto" object-space tiles give the body a
         * texel per pixel; the small knob and spout charts get more. */
        if (len_u > 0)
            uv_per_unit = fmin(uv_per_unit, (1.0 / CHART_ROWS) / len_u);
        if (len_v > 0)
            uv_per_unit = fmin(uv_per_unit, (1.0 / CHART_COLS) / len_v);
        bool flip = patch_flipped(p);
        for (uint32_t i = 0; i < (uint32_t)segments; i++)
            for (uint32_t j = 0; j < (uint32_t)segments; j++) {
                uint32_t a = base + i * side + j, b = a + 1, c = a + side, d = c + 1;
                /* (u, v) -> (x, z, -y) keeps the data's orientation, in which
                 * cross(Pu, Pv) is the (unflipped) normal: a, c, d runs
                 * counter-clockwise around it. */
                if (!flip) {
                    *idx++ = a, *idx++ = c, *idx++ = d;
                    *idx++ = a, *idx++ = d, *idx++ = b;
                } else {
                    *idx++ = a, *idx++ = d, *idx++ = c;
                    *idx++ = a, *idx++ = b, *idx++ = d;
                }
            }
    }
    out->bound_radius = (float)(bound * scale);
    out->uv_per_unit = (float)(uv_per_unit / scale);
    return true;
}

static double dist3(const double a[3], const double b[3])
{
    double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

double teapot_tessellation_error(int segments)
{
    /* Each quad (u0..u1, v0..v1) is split along its diagonal; the flat
     * triangle's point at a given (u, v) is the bilinear blend of its
     * corners on the half that holds it. */
    double worst = 0;
    double h = 1.0 / segments;
    static const double samples[][2] = {{0.5, 0.0}, {0.0, 0.5}, {0.5, 0.5}, {1.0 / 3, 2.0 / 3},
                                        {2.0 / 3, 1.0 / 3}, {0.5, 1.0}, {1.0, 0.5}};
    int step = segments > 8 ? segments / 8 : 1; /* at most 8 x 8 quads a patch */
    for (int p = 0; p < TEAPOT_PATCH_COUNT; p++)
        for (int i = 0; i < segments; i += step)
            for (int j = 0; j < segments; j += step) {
                double c[4][3], n[3];
                teapot_eval(p, i * h, j * h, c[0], n);
                teapot_eval(p, (i + 1) * h, j * h, c[1], n);
                teapot_eval(p, i * h, (j + 1) * h, c[2], n);
                teapot_eval(p, (i + 1) * h, (j + 1) * h, c[3], n);
                for (size_t s = 0; s < sizeof(samples) / sizeof(samples[0]); s++) {
                    double a = samples[s][0], b = samples[s][1], flat[3], surf[3];
                    /* Triangles (c0, c1, c3) below the diagonal a = b, (c0, c3, c2) above. */
                    for (int k = 0; k < 3; k++)
                        flat[k] = a >= b ? c[0][k] + a * (c[1][k] - c[0][k]) + b * (c[3][k] - c[1][k])
                                         : c[0][k] + b * (c[2][k] - c[0][k]) + a * (c[3][k] - c[2][k]);
                    teapot_eval(p, (i + a) * h, (j + b) * h, surf, n);
                    worst = fmax(worst, dist3(flat, surf));
                }
            }
    return worst;
}

int teapot_auto_segments(double pixels_per_unit, double bound_px)
{
    for (int s = TEAPOT_MIN_SEGMENTS; s < TEAPOT_MAX_SEGMENTS; s++)
        if (teapot_tessellation_error(s) * pixels_per_unit <= bound_px)
            return s;
    return TEAPOT_MAX_SEGMENTS;
}
