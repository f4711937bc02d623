/* shadebench-compare: the daemon's image-quality metrics on any two PNGs.
 * Prints JSON; exits 0 when PerceptualDiff passes, 1 when it fails, 2 on bad
 * input (unreadable file, size mismatch, not 8-bit RGB/RGBA), like
 * perceptualdiff, so CI scripts can use it directly. Translucent PNGs are
 * judged premultiplied by their alpha, as perceptualdiff judges them. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <stdint.h>
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "daemon/quality/metrics.h"
#include "common/png_io.h"

static void usage(FILE *f)
{
    fprintf(f,
            "Usage: shadebench-compare REFERENCE.png TEST.png [OPTION]...\n"
            "Compares TEST with REFERENCE: SSIM, PerceptualDiff, PSNR and FLIP as JSON.\n"
            "Exit status: 0 PerceptualDiff passes (or was not asked for), 1 it fails,\n"
            "2 bad input (including images over 8192x8192 pixels, refused before they\n"
            "are decoded).\n\n"
            "  --metrics LIST          comma-separated: ssim,pdiff,psnr,flip (default all)\n"
            "  --fov DEG               PerceptualDiff field of view (default 22.6)\n"
            "  --threshold-pixels N    PerceptualDiff fails from N failing pixels (default 100)\n"
            "  --gamma G               PerceptualDiff gamma (default 2.2)\n"
            "  --luminance L           PerceptualDiff white luminance, cd/m^2 (default 100)\n"
            "  --color-factor F        PerceptualDiff colour test weight (default 1)\n"
            "  --luminance-only        PerceptualDiff without the colour test\n"
            "  --ppd P                 FLIP pixels per degree (default 67.02)\n"
            "  --diff-out DIR          write DIR/ssim.png and DIR/flip.png\n"
            "  --swap-red-blue         read red as blue and blue as red, as perceptualdiff 2.x\n"
            "                          does on little-endian machines (FreeImage's byte order),\n"
            "                          to reproduce its figures\n\n"
            "An RGBA image is judged premultiplied by its alpha, as perceptualdiff judges\n"
            "it: PerceptualDiff multiplies each channel by alpha before its gamma; SSIM,\n"
            "PSNR and FLIP compare the colours times alpha, rounded to 8 bits (the image\n"
            "over black). A difference of alpha alone does not show where the colour is\n"
            "black.\n");
}

static bool number(const char *s, double min, double max, double *out)
{
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (errno || end == s || *end || !(v >= min && v <= max))
        return false;
    *out = v;
    return true;
}

int main(int argc, char **argv)
{
    struct metrics_options o;
    metrics_options_defaults(&o);
    const char *diff_out = NULL;
    bool swap_red_blue = false;
    enum { O_METRICS = 256, O_FOV, O_THRESHOLD, O_GAMMA, O_LUM, O_COLOR, O_LUMONLY, O_PPD,
           O_DIFF, O_SWAP, O_HELP };
    static const struct option longopts[] = {
        {"metrics", required_argument, NULL, O_METRICS},
        {"fov", required_argument, NULL, O_FOV},
        {"threshold-pixels", required_argument, NULL, O_THRESHOLD},
        {"gamma", required_argument, NULL, O_GAMMA},
        {"luminance", required_argument, NULL, O_LUM},
        {"color-factor", required_argument, NULL, O_COLOR},
        {"luminance-only", no_argument, NULL, O_LUMONLY},
        {"ppd", required_argument, NULL, O_PPD},
        {"diff-out", required_argument, NULL, O_DIFF},
        {"swap-red-blue", no_argument, NULL, O_SWAP},
        {"help", no_argument, NULL, O_HELP},
        {NULL, 0, NULL, 0},
    };
    int c;
    double v;
    while ((c = getopt_long(argc, argv, "", longopts, NULL)) != -1) {
        const char *bad = NULL;
        switch (c) {
        case O_METRICS: {
            o.which = 0;
            char *list = strdup(optarg), *save = NULL;
            for (char *t = strtok_r(list, ",", &save); t; t = strtok_r(NULL, ",", &save)) {
                if (strcmp(t, "ssim") == 0) o.which |= METRIC_SSIM;
                else if (strcmp(t, "pdiff") == 0) o.which |= METRIC_PDIFF;
                else if (strcmp(t, "psnr") == 0) o.which |= METRIC_PSNR;
                else if (strcmp(t, "flip") == 0) o.which |= METRIC_FLIP;
                else bad = "--metrics takes ssim, pdiff, psnr and flip";
            }
            free(list);
            if (!o.which)
                bad = "--metrics names no metric";
            break;
        }
        case O_FOV: if (!number(optarg, 0.1, 179, &o.pdiff.fov)) bad = "--fov must be 0.1 to 179"; break;
        case O_THRESHOLD:
            if (!number(optarg, 0, 1e9, &v)) bad = "--threshold-pixels must be 0 to 1e9";
            o.pdiff.threshold_pixels = (long)v;
            break;
        case O_GAMMA: if (!number(optarg, 0.1, 10, &o.pdiff.gamma)) bad = "--gamma must be 0.1 to 10"; break;
        case O_LUM: if (!number(optarg, 0.01, 1e5, &o.pdiff.luminance)) bad = "--luminance must be 0.01 to 100000"; break;
        case O_COLOR: if (!number(optarg, 0, 100, &o.pdiff.color_factor)) bad = "--color-factor must be 0 to 100"; break;
        case O_LUMONLY: o.pdiff.luminance_only = true; break;
        case O_PPD: if (!number(optarg, 1, 1000, &o.flip_ppd)) bad = "--ppd must be 1 to 1000"; break;
        case O_DIFF: diff_out = optarg; break;
        case O_SWAP: swap_red_blue = true; break;
        case O_HELP: usage(stdout); return 0;
        default: usage(stderr); return 2;
        }
        if (bad) {
            fprintf(stderr, "shadebench-compare: %s\n", bad);
            return 2;
        }
    }
    if (argc - optind != 2) {
        usage(stderr);
        return 2;
    }
    const char *ref_path = argv[optind], *test_path = argv[optind + 1];
    struct image ref, test;
    char err[512];
    if (!png_read_rgba(ref_path, &ref, err, sizeof(err))) {
        fprintf(stderr, "shadebench-compare: %s\n", err);
        return 2;
    }
    if (!png_read_rgba(test_path, &test, err, sizeof(err))) {
        fprintf(stderr, "shadebench-compare: %s\n", err);
        image_finish(&ref);
        return 2;
    }
    if (swap_red_blue)
        for (int k = 0; k < 2; k++) {
            struct image *img = k ? &test : &ref;
            for (size_t i = 0; i < (size_t)img->width * (size_t)img->height; i++) {
                uint8_t r = img->rgb[3 * i];
                img->rgb[3 * i] = img->rgb[3 * i + 2];
                img->rgb[3 * i + 2] = r;
            }
        }
    char ssim_path[4096], flip_path[4096];
    if (diff_out) {
        if (mkdir(diff_out, 0755) != 0 && errno != EEXIST) {
            fprintf(stderr, "shadebench-compare: cannot create %s\n", diff_out);
            return 2;
        }
        snprintf(ssim_path, sizeof(ssim_path), "%s/ssim.png", diff_out);
        snprintf(flip_path, sizeof(flip_path), "%s/flip.png", diff_out);
    }
    json_t *result = metrics_compare(&ref, &test, &o, diff_out ? ssim_path : NULL,
                                     diff_out ? flip_path : NULL, NULL, err, sizeof(err));
    int rc = 2;
    if (!result) {
        fprintf(stderr, "shadebench-compare: %s\n", err);
    } else {
        json_object_set_new(result, "reference", json_string(ref_path));
        json_object_set_new(result, "test", json_string(test_path));
        json_object_set_new(result, "width", json_integer(ref.width));
        json_object_set_new(result, "height", json_integer(ref.height));
        bool translucent = ref.alpha || test.alpha;
        json_object_set_new(result, "alpha", json_string(translucent ? "premultiplied" : "opaque"));
        json_object_set_new(result, "memory_budget_bytes",
                            json_real(metrics_memory_bytes(ref.width, ref.height, o.flip_ppd) +
                                      (translucent ? metrics_alpha_memory_bytes(ref.width, ref.height)
                                                   : 0.0)));
        json_dumpf(result, stdout, JSON_INDENT(2) | JSON_REAL_PRECISION(10));
        putchar('\n');
        json_t *pdiff = json_object_get(result, "pdiff");
        rc = pdiff && !json_is_true(json_object_get(pdiff, "pass")) ? 1 : 0;
        json_decref(result);
    }
    image_finish(&ref);
    image_finish(&test);
    return rc;
}
