/* An uploaded OpenEXR image into an environment image: see env_exr.h.
 * OpenEXRCore reads through the two callbacks below from the bytes in
 * memory; its error handler keeps the last message, which a refusal
 * quotes. The image is the data window of the first part; its rows are
 * stored top first, as the environment wants (OpenEXR's y grows down). */
#define _POSIX_C_SOURCE 200809L
#include "daemon/assets/env_exr.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <openexr.h>

struct source {
    const uint8_t *data;
    size_t len;
    char last_error[256]; /* OpenEXRCore's last message */
};


bool env_exr_is(const uint8_t *data, size_t len)
{
    return len >= 4 && data[0] == 0x76 && data[1] == 0x2f && data[2] == 0x31 && data[3] == 0x01;
}

static int64_t read_memory(exr_const_context_t ctxt, void *user, void *buffer, uint64_t size,
                           uint64_t offset, exr_stream_error_func_ptr_t error_cb)
{
    (void)ctxt;
    (void)error_cb;
    const struct source *s = user;
    if (offset >= s->len)
        return 0;
    uint64_t n = s->len - offset < size ? s->len - offset : size;
    memcpy(buffer, s->data + offset, n);
    return (int64_t)n;
}

static int64_t size_of_memory(exr_const_context_t ctxt, void *user)
{
    (void)ctxt;
    return (int64_t)((const struct source *)user)->len;
}

static void keep_error(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    void *user = NULL;
    if (exr_get_user_data(ctxt, &user) != EXR_ERR_SUCCESS || !user)
        return;
    struct source *s = user;
    snprintf(s->last_error, sizeof(s->last_error), "%s",
             msg ? msg : exr_get_default_error_message(code));
}

/* OpenEXR's message for rc, the handler's when it gave one. */
static const char *why(const struct source *s, exr_result_t rc)
{
    return s->last_error[0] ? s->last_error : exr_get_default_error_message(rc);
}

/* The channels read: R, G, B into 0, 1, 2, or Y into all three. Fills
 * index[3] with each output's channel in the list; false with e. */
static bool pick_channels(const exr_attr_chlist_t *ch, int index[3], bool *grey,
                          struct asset_convert_error *e)
{
    static const char *const rgb[3] = {"R", "G", "B"};
    int y = -1;
    index[0] = index[1] = index[2] = -1;
    for (int i = 0; i < ch->num_channels; i++) {
        const char *name = ch->entries[i].name.str;
        for (int c = 0; c < 3; c++)
            if (name && strcmp(name, rgb[c]) == 0)
                index[c] = i;
        if (name && strcmp(name, "Y") == 0)
            y = i;
    }
    *grey = false;
    if (index[0] < 0 || index[1] < 0 || index[2] < 0) {
        if (y < 0) {
            char names[200] = "";
            size_t used = 0;
            for (int i = 0; i < ch->num_channels && used + 1 < sizeof(names); i++)
                used += (size_t)snprintf(names + used, sizeof(names) - used, "%s%s",
                                         i ? ", " : "",
                                         ch->entries[i].name.str ? ch->entries[i].name.str : "?");
            return env_fail(e, 422, "body", "the OpenEXR image has no R, G and B channels (nor Y): "
                        "its channels are %s", ch->num_channels ? names : "none");
        }
        index[0] = index[1] = index[2] = y;
        *grey = true;
    }
    for (int c = 0; c < 3; c++) {
        const exr_attr_chlist_entry_t *en = &ch->entries[index[c]];
        if (en->x_sampling != 1 || en->y_sampling != 1)
            return env_fail(e, 422, "body", "the OpenEXR channel %s is subsampled (%d x %d): only "
                        "full-resolution channels are read", en->name.str, en->x_sampling,
                        en->y_sampling);
    }
    return true;
}

/* Decodes one chunk into the image: the chunk's pixels at (col, row) of
 * the data window (a scanline chunk's start_y is a coordinate, a tile's
 * start_x and start_y are its indices: the caller says where it goes). */
static bool decode_chunk(exr_context_t ctx, exr_decode_pipeline_t *dec, bool *started,
                         const exr_chunk_info_t *ci, int64_t col, int64_t row,
                         const int index[3], bool grey, struct environment_image *out,
                         struct source *s, int chunk, int chunks, struct asset_convert_error *e)
{
    if (ci->data_offset > s->len || ci->packed_size > s->len - ci->data_offset)
        return env_fail(e, 422, "body", "truncated: chunk %d of %d (rows %lld to %lld) ends %llu "
                    "bytes past the file's end", chunk + 1, chunks, (long long)row,
                    (long long)row + ci->height - 1,
                    (unsigned long long)(ci->data_offset + ci->packed_size - s->len));
    if (row < 0 || col < 0 || ci->height <= 0 || ci->width <= 0 ||
        row + ci->height > (int64_t)out->height || col + ci->width > (int64_t)out->width)
        return env_fail(e, 422, "body", "corrupt: chunk %d of %d lies outside the data window",
                    chunk + 1, chunks);
    exr_result_t rc = *started ? exr_decoding_update(ctx, 0, ci, dec)
                               : exr_decoding_initialize(ctx, 0, ci, dec);
    if (rc != EXR_ERR_SUCCESS)
        return env_fail(e, 422, "body", "corrupt: chunk %d of %d: %s", chunk + 1, chunks, why(s, rc));
    *started = true;
    /* Every channel decodes somewhere: the ones not read into a scratch
     * plane. OpenEXRCore 3.1's unpackers write through a channel whose
     * decode_to_ptr is NULL in some layouts (fuzz_env_convert: channels B,
     * Y and R under ZIPS wrote to address 0). */
    float *scratch = calloc((size_t)ci->width * (size_t)ci->height, sizeof(float));
    if (!scratch)
        return env_fail(e, 422, "body", "out of memory decoding chunk %d of %d", chunk + 1, chunks);
    for (int i = 0; i < dec->channel_count; i++) {
        exr_coding_channel_info_t *cc = &dec->channels[i];
        cc->decode_to_ptr = (uint8_t *)scratch;
        cc->user_pixel_stride = (int32_t)sizeof(float);
        cc->user_line_stride = (int32_t)(ci->width * sizeof(float));
        cc->user_bytes_per_element = sizeof(float);
        cc->user_data_type = EXR_PIXEL_FLOAT;
    }
    /* Y alone goes to red; green and blue are copied after. */
    for (int c = 0; c < (grey ? 1 : 3); c++) {
        exr_coding_channel_info_t *cc = &dec->channels[index[c]];
        cc->decode_to_ptr = (uint8_t *)(out->rgb + ((size_t)row * out->width + (size_t)col) * 3 + c);
        cc->user_pixel_stride = 3 * (int32_t)sizeof(float);
        cc->user_line_stride = (int32_t)(out->width * 3 * sizeof(float));
        cc->user_bytes_per_element = sizeof(float);
        cc->user_data_type = EXR_PIXEL_FLOAT;
    }
    rc = exr_decoding_choose_default_routines(ctx, 0, dec);
    if (rc == EXR_ERR_SUCCESS)
        rc = exr_decoding_run(ctx, 0, dec);
    free(scratch);
    if (rc != EXR_ERR_SUCCESS)
        return env_fail(e, 422, "body", "corrupt: chunk %d of %d does not decode: %s", chunk + 1,
                    chunks, why(s, rc));
    if (grey)
        for (int y = 0; y < ci->height; y++)
            for (int x = 0; x < ci->width; x++) {
                float *p = out->rgb + ((size_t)(row + y) * out->width + (size_t)(col + x)) * 3;
                p[1] = p[2] = p[0];
            }
    return true;
}

static bool decode_part(exr_context_t ctx, struct source *s, const struct environment_limits *lim,
                        struct environment_image *out, struct asset_convert_error *e)
{
    exr_storage_t storage;
    exr_attr_box2i_t dw;
    const exr_attr_chlist_t *ch = NULL;
    exr_result_t rc;
    if ((rc = exr_get_storage(ctx, 0, &storage)) != EXR_ERR_SUCCESS ||
        (rc = exr_get_data_window(ctx, 0, &dw)) != EXR_ERR_SUCCESS ||
        (rc = exr_get_channels(ctx, 0, &ch)) != EXR_ERR_SUCCESS || !ch)
        return env_fail(e, 422, "body", "the OpenEXR header is incomplete: %s", why(s, rc));
    if (storage != EXR_STORAGE_SCANLINE && storage != EXR_STORAGE_TILED)
        return env_fail(e, 422, "body", "a deep OpenEXR image is not an environment map: only "
                    "scanline and tiled images are read");
    int64_t w = (int64_t)dw.max.x - dw.min.x + 1, h = (int64_t)dw.max.y - dw.min.y + 1;
    if (w <= 0 || h <= 0)
        return env_fail(e, 422, "body", "the OpenEXR data window is empty (%lld x %lld)",
                    (long long)w, (long long)h);
    /* The limits from the header, before a byte is decoded. */
    if (w > lim->max_edge || h > lim->max_edge)
        return env_fail(e, 422, "limits.max_environment_edge", "%lld x %lld pixels: an "
                    "environment's width and height must be at most %u", (long long)w,
                    (long long)h, lim->max_edge);
    if ((uint64_t)w * (uint64_t)h > lim->max_pixels)
        return env_fail(e, 422, "limits.max_environment_pixels", "%lld x %lld is %llu pixels "
                    "(%llu bytes decoded): the limit is %llu pixels", (long long)w, (long long)h,
                    (unsigned long long)(w * h), (unsigned long long)(w * h * 12),
                    (unsigned long long)lim->max_pixels);
    int index[3];
    bool grey;
    if (!pick_channels(ch, index, &grey, e))
        return false;
    uint32_t tw = 0, th = 0;
    int32_t lines = 0;
    if (storage == EXR_STORAGE_TILED) {
        exr_tile_level_mode_t level;
        exr_tile_round_mode_t round;
        if ((rc = exr_get_tile_descriptor(ctx, 0, &tw, &th, &level, &round)) != EXR_ERR_SUCCESS)
            return env_fail(e, 422, "body", "the OpenEXR tile description: %s", why(s, rc));
        /* A tile is decoded whole: its size is bounded as the image is. */
        if (tw == 0 || th == 0 || tw > lim->max_edge || th > lim->max_edge ||
            (uint64_t)tw * th > lim->max_pixels)
            return env_fail(e, 422, "limits.max_environment_pixels", "OpenEXR tiles of %u x %u "
                        "pixels: a tile is bounded as the image is (edges at most %u, %llu "
                        "pixels)", tw, th, lim->max_edge, (unsigned long long)lim->max_pixels);
    } else if ((rc = exr_get_scanlines_per_chunk(ctx, 0, &lines)) != EXR_ERR_SUCCESS ||
               lines <= 0) {
        return env_fail(e, 422, "body", "the OpenEXR compression's lines per chunk: %s",
                    why(s, rc));
    }
    out->width = (uint32_t)w;
    out->height = (uint32_t)h;
    if (!(out->rgb = calloc((size_t)w * (size_t)h * 3, sizeof(float))))
        return env_fail(e, 500, "body", "out of memory for %lld x %lld pixels", (long long)w,
                    (long long)h);
    exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
    bool started = false, ok = true;
    if (storage == EXR_STORAGE_SCANLINE) {
        int chunks = (int)((h + lines - 1) / lines);
        for (int k = 0; ok && k < chunks; k++) {
            exr_chunk_info_t ci;
            int y = dw.min.y + k * lines;
            if ((rc = exr_read_scanline_chunk_info(ctx, 0, y, &ci)) != EXR_ERR_SUCCESS)
                ok = env_fail(e, 422, "body", "truncated or corrupt: chunk %d of %d (from row %d): "
                          "%s", k + 1, chunks, k * lines, why(s, rc));
            else
                ok = decode_chunk(ctx, &dec, &started, &ci, 0, (int64_t)k * lines, index, grey,
                                  out, s, k, chunks, e);
        }
    } else {
        int across = (int)((w + tw - 1) / tw), down = (int)((h + th - 1) / th);
        int chunks = across * down;
        for (int k = 0; ok && k < chunks; k++) {
            exr_chunk_info_t ci;
            if ((rc = exr_read_tile_chunk_info(ctx, 0, k % across, k / across, 0, 0, &ci)) !=
                EXR_ERR_SUCCESS)
                ok = env_fail(e, 422, "body", "truncated or corrupt: tile %d of %d: %s", k + 1,
                          chunks, why(s, rc));
            else
                ok = decode_chunk(ctx, &dec, &started, &ci, (int64_t)(k % across) * tw,
                                  (int64_t)(k / across) * th, index, grey, out, s, k, chunks, e);
        }
    }
    if (started)
        exr_decoding_destroy(ctx, &dec);
    if (!ok)
        return false;
    size_t n = (size_t)w * (size_t)h * 3;
    for (size_t i = 0; i < n; i++)
        if (!(isfinite(out->rgb[i]) && out->rgb[i] > 0))
            out->rgb[i] = 0.0f;
    return true;
}

bool env_exr_decode(const uint8_t *data, size_t len, const struct environment_limits *lim,
                    struct environment_image *out, struct asset_convert_error *e)
{
    memset(out, 0, sizeof(*out));
    memset(e, 0, sizeof(*e));
    if (!env_exr_is(data, len))
        return env_fail(e, 422, "body", "not an OpenEXR image: it must start with 76 2f 31 01");
    struct source s = {.data = data, .len = len};
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.user_data = &s;
    init.read_fn = read_memory;
    init.size_fn = size_of_memory;
    init.error_handler_fn = keep_error;
    exr_context_t ctx = NULL;
    exr_result_t rc = exr_start_read(&ctx, "upload.exr", &init);
    if (rc != EXR_ERR_SUCCESS) {
        exr_finish(&ctx);
        return env_fail(e, 422, "body", "the OpenEXR header does not read (a truncated or corrupt "
                    "file): %s", why(&s, rc));
    }
    int parts = 0;
    bool ok = exr_get_count(ctx, &parts) == EXR_ERR_SUCCESS && parts >= 1
                  ? decode_part(ctx, &s, lim, out, e)
                  : env_fail(e, 422, "body", "the OpenEXR file has no image part");
    exr_finish(&ctx);
    if (!ok) {
        environment_image_finish(out);
        out->width = out->height = 0;
    }
    return ok;
}
