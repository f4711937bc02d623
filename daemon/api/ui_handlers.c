/* / and /ui/...: the dashboard's files (docs/dashboard.md), embedded at
 * build time (ui_files.h). They are served without the token: they hold no
 * data, only the page that asks for the token and then calls the API with
 * it, as any other client does. Runs on libmicrohttpd's polling threads. */
#define _POSIX_C_SOURCE 200809L
#include <string.h>

#include "daemon/api/server.h"
#include "daemon/api/ui_files.h"

const struct ui_file *ui_file_find(const char *url)
{
    if (strcmp(url, "/") == 0)
        url = "/ui/index.html";
    for (const struct ui_file *f = ui_files; f->url; f++)
        if (strcmp(f->url, url) == 0)
            return f;
    return NULL;
}

/* The pages load scripts and styles from the daemon alone, and images from
 * the API (fetched with the token, shown as blob: URLs). */
static const char CSP[] =
    "default-src 'self'; img-src 'self' blob: data:; style-src 'self' 'unsafe-inline'; "
    "script-src 'self'; connect-src 'self'; object-src 'none'; base-uri 'none'; "
    "frame-ancestors 'none'";

enum MHD_Result respond_ui(struct MHD_Connection *c, const struct route *r)
{
    const struct ui_file *f = ui_file_find(r->ui);
    if (!f)
        return respond_error(c, MHD_HTTP_NOT_FOUND, "url", "no such file of the dashboard");
    const char *inm = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "If-None-Match");
    bool fresh = inm && strcmp(inm, ui_etag) == 0;
    struct MHD_Response *resp = MHD_create_response_from_buffer(
        fresh ? 0 : f->len, fresh ? NULL : (void *)f->data, MHD_RESPMEM_PERSISTENT);
    if (!resp)
        return MHD_NO;
    MHD_add_response_header(resp, "Content-Type", f->type);
    /* Revalidated on every load (a cheap 304): a new build's files are
     * never mixed with an old one's. */
    MHD_add_response_header(resp, "Cache-Control", "no-cache");
    MHD_add_response_header(resp, "ETag", ui_etag);
    MHD_add_response_header(resp, "X-Content-Type-Options", "nosniff");
    MHD_add_response_header(resp, "Content-Security-Policy", CSP);
    if (connections_is_reserve(connections_of(c)))
        MHD_add_response_header(resp, "Connection", "close");
    unsigned status = fresh ? MHD_HTTP_NOT_MODIFIED : MHD_HTTP_OK;
    connections_set_status(connections_of(c), status);
    enum MHD_Result ret = MHD_queue_response(c, status, resp);
    MHD_destroy_response(resp);
    return ret;
}
