#ifndef SHADEBENCH_CDP_H
#define SHADEBENCH_CDP_H

/* The Chrome DevTools Protocol over Chromium's --remote-debugging-pipe: JSON
 * messages, each ended by a NUL byte, written to the browser's fd 3 and read
 * from its fd 4. Commands carry an id and are answered by a message with the
 * same id; everything else is an event, handed to the event function while
 * a command waits (the Fetch domain's requestPaused is how the page's files
 * are served). No WebSocket, no port, nothing on the network. GL-free;
 * one thread (shadebench-reference's). */

#include <jansson.h>
#include <stdbool.h>
#include <stddef.h>

/* A message larger than this (an image answered as base64 is about 5.4
 * bytes a pixel) ends the session. */
#define CDP_MAX_MESSAGE (512u << 20)

struct cdp;
typedef void (*cdp_event_fn)(void *ctx, struct cdp *c, const char *method, json_t *params,
                             const char *session);

/* wfd: the browser's fd 3 (we write), rfd: its fd 4 (we read); both are
 * owned from here on (cdp_destroy closes them). */
struct cdp *cdp_create(int wfd, int rfd, cdp_event_fn on_event, void *ctx);
void cdp_destroy(struct cdp *c);

/* Sends method(params) to session (NULL: the browser), params stolen (NULL:
 * {}); returns the message's id, or -1 with err (the pipe is closed). */
long cdp_send(struct cdp *c, const char *session, const char *method, json_t *params, char *err,
              size_t errlen);
/* Sends and waits until the answer comes or deadline (clock_mono_s()) passes,
 * handing events to the event function meanwhile. The answer's "result"
 * (a new reference), or NULL with err: the protocol's error message, the
 * time-out, or the browser gone. */
json_t *cdp_call(struct cdp *c, const char *session, const char *method, json_t *params,
                 double deadline, char *err, size_t errlen);

#endif
