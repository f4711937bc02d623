#include "common/job_files.h"

#include <stdio.h>

static const struct job_image_kind KINDS[JOB_IMAGE_COUNT] = {
    [JOB_IMAGE_FRAME] = {"frame", "frames", "file", "url"},
    [JOB_IMAGE_REFERENCE] = {"reference", "reference", "reference_file", "reference_url"},
    [JOB_IMAGE_SSIM] = {"ssim", "ssim", "ssim_map_file", "ssim_map_url"},
    [JOB_IMAGE_FLIP] = {"flip", "flip", "flip_map_file", "flip_map_url"},
    [JOB_IMAGE_HEATMAP] = {"heatmap", "heatmap", "file", "url"},
};

const struct job_image_kind *job_image_kind(enum job_image image)
{
    return &KINDS[image];
}

void job_image_name(enum job_image image, int frame, char out[JOB_IMAGE_NAME_MAX])
{
    snprintf(out, JOB_IMAGE_NAME_MAX, "%s-%06d.png", KINDS[image].prefix, frame);
}

bool job_image_path(const char *dir, enum job_image image, int frame, char *out, size_t cap)
{
    char name[JOB_IMAGE_NAME_MAX];
    job_image_name(image, frame, name);
    return job_file_path(dir, name, out, cap);
}

bool job_file_path(const char *dir, const char *file, char *out, size_t cap)
{
    int n = snprintf(out, cap, "%s/%s", dir, file);
    return n >= 0 && (size_t)n < cap;
}
