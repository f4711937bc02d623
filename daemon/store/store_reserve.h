#ifndef SHADEBENCH_STORE_RESERVE_H
#define SHADEBENCH_STORE_RESERVE_H

/* Room kept on the state directory's disk so that a full disk cannot make
 * the store lie about how a job ended. A full disk fails a job (its
 * result.json cannot be written), and then the write of "failed" into
 * store.db fails too: the row kept saying running or queued, and after a
 * restart the job ran again as if it had never failed.
 *
 * STATE_DIR/store.reserve is a file of STORE_RESERVE_BYTES taken (with
 * posix_fallocate) when the store opens. When a write of the store fails
 * for want of space, the store releases the room (all but the file's first
 * block) and writes again; from then on no job starts and none is accepted
 * until the room can be taken back, so that the room goes to recording the
 * ends of jobs already running. The first block holds notes: before a
 * failed write is retried, the state it could not write is noted there, in
 * place (the block is the file's own: writing it needs no new space), and
 * the note is removed once the state is stored. A note left behind (the
 * retry failed too: the disk was full and stayed full) is read by the next
 * start, which records the state it says (queue.c), with the reason.
 *
 * The store's (store.c); its calls are made under the store's write lock
 * except store_reserve_ready and store_reserve_released, which any thread
 * may call. GL-free. Unit-tested in tests/unit/test_store.c. */

#include <stdbool.h>
#include <stddef.h>

#define STORE_RESERVE_FILE "store.reserve"
#define STORE_RESERVE_BYTES (1024 * 1024)
#define STORE_RESERVE_NOTES_BYTES 4096
/* Free space, beside the reserve, below which the disk counts as full. */
#define STORE_RESERVE_HEADROOM (64 * 1024)

struct store_reserve;

/* Opens (creating it) STATE_DIR/store.reserve, reads the notes an earlier
 * run left, and takes its room (logged when the disk has none: the store
 * then works without a reserve until it can take one). NULL when the file
 * cannot be opened at all (logged). */
struct store_reserve *store_reserve_open(const char *state_dir);
/* Accepts NULL. */
void store_reserve_close(struct store_reserve *r);

/* The state a write could not store: kind and id name the record, status
 * and error what it was to become. Written in place and synced; false when
 * the notes are full. */
bool store_reserve_note(struct store_reserve *r, int kind, const char *id, const char *status,
                        const char *error);
/* The state got stored after all: its note goes. */
void store_reserve_unnote(struct store_reserve *r, int kind, const char *id);
/* Gives the room back to the disk; false when it was already given. */
bool store_reserve_release(struct store_reserve *r);

/* Is there room: the reserve taken (when released, it tries to take it
 * again, at most once a second) and STORE_RESERVE_HEADROOM free beside it?
 * The change either way is logged. Any thread. */
bool store_reserve_ready(struct store_reserve *r);
/* The reserve is released, or the last store_reserve_ready found no room
 * (no attempt made here). Any thread. */
bool store_reserve_released(struct store_reserve *r);

/* What an earlier run noted for kind/id (the newest note): status and
 * error; false when nothing. */
bool store_reserve_found(const struct store_reserve *r, int kind, const char *id, char *status,
                         size_t status_cap, char *error, size_t error_cap);
/* The earlier run's notes are applied: they go from the file. */
void store_reserve_found_done(struct store_reserve *r);

#endif
