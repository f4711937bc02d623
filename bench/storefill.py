"""A state directory holding many finished jobs, filled in the store's own
format without the daemon's help (bench_store.py, bench_dashboard.py): one
real job's row (spec, figures, labels) is copied `jobs` times into store.db
with Python's sqlite3 module, under time-ordered ids and finish times, with
labels commit=cNNNNN (10 jobs each) and branch=main or topic, and
techniques in turn; each job gets its directory (the start-up scan reads
them), and `with_results` of them the real job's files (its result.json,
and with whole_dirs its timings, captures and maps too)."""

import json
import os
import random
import shutil
import sqlite3
import time

TECHNIQUES = ["forward", "unlit", "osl", "deferred"]


def stamp_id(t, serial):
    return time.strftime("%Y%m%d-%H%M%S", time.gmtime(t)) + "-%04d" % (serial % 10000)


def fill(state, template_id, jobs, with_results, whole_dirs=False, seed=20):
    """Fills state (a stopped daemon's, holding the finished job template_id).
    Returns {"ids", "start", "spec", "result_text", "with_result", "db_mb"}."""
    db = sqlite3.connect(os.path.join(state, "store.db"))
    db.row_factory = sqlite3.Row
    template = dict(db.execute("SELECT * FROM records WHERE id = ?", (template_id,)).fetchone())
    template_dir = os.path.join(state, "jobs", template_id)
    with open(os.path.join(template_dir, "result.json")) as f:
        result_text = f.read()
    with open(os.path.join(template_dir, "spec.json")) as f:
        spec_template = json.load(f)["spec"]  # a finished job's row has none: its spec.json has it
    rng = random.Random(seed)
    start = time.time() - jobs * 5.0  # one job every 5 s, up to now
    columns = list(template.keys())
    rows, labels, ids = [], [], []
    for i in range(jobs):
        created = start + i * 5.0
        job_id = stamp_id(created, i)
        ids.append(job_id)
        lab = {"commit": "c%05d" % (i // 10), "branch": "main" if i % 3 else "topic"}
        row = dict(template, id=job_id, technique=TECHNIQUES[i % len(TECHNIQUES)], created=created,
                   started=created + 1, finished=created + 2 + rng.random(),
                   labels=json.dumps(lab, separators=(",", ":")))
        rows.append(tuple(row[c] for c in columns))
        labels += [(0, job_id, k, v) for k, v in lab.items()]
    with db:
        db.execute("DELETE FROM records")
        db.execute("DELETE FROM labels")
        db.executemany("INSERT INTO records (%s) VALUES (%s)" % (", ".join(columns), ", ".join("?" * len(columns))),
                       rows)
        db.executemany("INSERT INTO labels (kind, id, key, value) VALUES (?, ?, ?, ?)", labels)
    db.close()
    jobs_root = os.path.join(state, "jobs")
    kept = os.path.join(state, "template-job")
    if whole_dirs:
        shutil.move(template_dir, kept)
    shutil.rmtree(jobs_root)
    os.mkdir(jobs_root)
    with_result = set(rng.sample(range(jobs), min(with_results, jobs)))
    for i, job_id in enumerate(ids):
        path = os.path.join(jobs_root, job_id)
        if i in with_result and whole_dirs:
            shutil.copytree(kept, path)
        else:
            os.mkdir(path)
        if i in with_result:
            with open(os.path.join(path, "result.json"), "w") as f:
                f.write(result_text)
            with open(os.path.join(path, "spec.json"), "w") as f:
                json.dump({"id": job_id, "created_unix": start + i * 5.0,
                           "spec": dict(spec_template, technique=TECHNIQUES[i % len(TECHNIQUES)])}, f)
    if whole_dirs:
        shutil.rmtree(kept)
    db_mb = sum(os.path.getsize(os.path.join(state, f)) for f in os.listdir(state) if f.startswith("store.db")) / 1e6
    return {"ids": ids, "start": start, "spec": spec_template, "result_text": result_text,
            "with_result": with_result, "db_mb": db_mb}
