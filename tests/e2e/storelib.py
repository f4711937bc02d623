"""The record store as the end-to-end tests read it: STATE_DIR/store.db, an
SQLite database (daemon/store/store.h), opened with Python's own sqlite3
module, read-only. Rows are read while the daemon runs (its write-ahead log
lets readers in) or after it stopped."""

import json
import os
import sqlite3

JOBS, SWEEPS = 0, 1


def db_path(state):
    return os.path.join(state, "store.db")


def connect(state, write=False):
    if write:
        return sqlite3.connect(db_path(state), timeout=30)
    return sqlite3.connect("file:%s?mode=ro" % db_path(state), uri=True, timeout=30)


def row(state, kind, record_id):
    """The record's row as a dict (labels, figures, spec and extra decoded),
    or None."""
    db = connect(state)
    try:
        db.row_factory = sqlite3.Row
        r = db.execute("SELECT * FROM records WHERE kind = ? AND id = ?", (kind, record_id)).fetchone()
    finally:
        db.close()
    if r is None:
        return None
    out = dict(r)
    for key in ("labels", "figures", "spec", "extra"):
        if out.get(key) is not None:
            out[key] = json.loads(out[key])
    return out


def ids(state, kind=JOBS):
    db = connect(state)
    try:
        return [r[0] for r in db.execute("SELECT id FROM records WHERE kind = ? ORDER BY id", (kind,))]
    finally:
        db.close()


def set_status(state, kind, record_id, status, **columns):
    """Changes a stopped daemon's row, as a crash at a given moment would
    have left it."""
    db = connect(state, write=True)
    try:
        sets = ["status = ?"] + ["%s = ?" % k for k in columns]
        with db:
            db.execute("UPDATE records SET %s WHERE kind = ? AND id = ?" % ", ".join(sets),
                       [status] + list(columns.values()) + [kind, record_id])
    finally:
        db.close()
