#!/usr/bin/env python3
"""A full disk (issue 34, items 2 and 9), on small tmpfs mounts (root, as
on CI; a test that cannot mount fails):

- a daemon started on a disk another user filled, with its store in place,
  starts (before: "cannot write store.db: disk I/O error" and exit 1),
  serves what it has (the jobs, their results, the assets) and /healthz
  saying the disk is full, refuses jobs, sweeps and uploads with 507, and
  recovers by itself once there is room again;
- an upload whose cache would not fit the room the disk has (its free
  space less the 64 MiB kept for jobs) is refused with 507 naming
  state_dir before the cache is written, and leaves nothing behind (before:
  the converter wrote until the disk filled, and the upload answered 422
  "the asset loader failed (exit 1)"), or, when it fits the disk but not
  the room, took the room jobs need."""

import os
import random
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gltf_gen  # noqa: E402
import testlib  # noqa: E402
from testlib import Daemon, check, stop_and_check  # noqa: E402
from e2e_assets import converter_path, glb, put  # noqa: E402

S = testlib.TIME_SCALE
TINY = {"technique": "unlit", "frames": 1, "warmup_frames": 0, "scene": {"width": 16, "height": 16}}


def mount_tmpfs(path, size):
    out = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=%s" % size, "tmpfs", path],
                         capture_output=True, text=True)
    return out.returncode == 0, out.stderr.strip()


def honest_png(edge, seed):
    """An RGBA PNG whose bytes honestly hold its edge x edge (about 50:1)."""
    rnd = random.Random(seed)
    tile = bytes(rnd.randrange(256) for _ in range(edge // 4))
    return gltf_gen.png_bytes(edge, edge, [(tile[y % 7:] + tile[:y % 7]) * 16
                                           for y in range(edge)])


def maps_asset(n):
    """A cube with n 2048x2048 maps: a cache of about n x 16 MiB."""
    g = gltf_gen.Gltf()
    mats = []
    for k in range(n):
        t = g.texture(g.image(honest_png(2048, k), mime="image/png"))
        mats.append(g.material(pbrMetallicRoughness={"baseColorTexture": {"index": t}}))
    for m in mats:
        g.node(mesh=g.mesh(gltf_gen.cube(), material=m, uv1=False))
    return g.glb()


def leftovers(state):
    folder = os.path.join(state, "assets")
    return [n for n in os.listdir(folder) if n.startswith(("upload-", "convert-")) or ".tmp" in n]


def start_on_full_disk(mnt):
    state = os.path.join(mnt, "state")
    filler = os.path.join(mnt, "filler")
    d = Daemon("--state-dir", state)
    try:
        job = d.run(TINY)
        check(job.get("status") == "done", "a job before the disk fills")
        check(put(d, "tri.glb", glb(1.0))[0] == 201, "an asset before the disk fills")
    finally:
        stop_and_check(d)
    testlib.fill_disk(filler)
    try:
        d = Daemon("--state-dir", state)
    except RuntimeError:
        check(False, "the daemon starts on a full disk with its store in place")
        return
    try:
        check(True, "the daemon starts on a full disk with its store in place")
        code, body = d.json("GET", "/v1/jobs/" + job["id"])
        check(code == 200 and body.get("status") == "done" and body.get("result"),
              "the earlier job and its result are served (%d %s)" % (code, body.get("status")))
        code, body = d.json("GET", "/v1/jobs")
        check(code == 200 and len(body.get("jobs", [])) == 1, "the job list is served (%d)" % code)
        code, body = d.json("GET", "/v1/assets/tri.glb")
        check(code == 200, "the asset is served (%d)" % code)
        code, body = d.json("GET", "/healthz")
        check(code == 200 and body.get("status") == "disk full",
              "/healthz says the disk is full (%d %s)" % (code, body))
        check("shadebench_state_disk_full 1" in d.request("GET", "/metrics")[2].decode(),
              "/metrics says the disk is full")
        code, body = d.json("POST", "/v1/jobs", TINY)
        check(code == 507 and body.get("error", {}).get("field") == "state_dir",
              "a job is refused with 507 (%d %s)" % (code, body))
        code, body = d.json("POST", "/v1/sweeps", {"base": TINY, "vary": {"frames": [1, 2]}})
        check(code == 507, "a sweep is refused with 507 (%d %s)" % (code, body))
        code, body = put(d, "new.glb", glb(2.0))
        check(code == 507 and body.get("error", {}).get("field") == "state_dir",
              "an upload is refused with 507 (%d %s)" % (code, body))

        # Room again: it recovers by itself, no restart.
        os.remove(filler)
        deadline = time.time() + 30 * S
        while True:
            code, body = d.json("POST", "/v1/jobs", TINY)
            if code != 507 or time.time() > deadline:
                break
            time.sleep(0.2)
        check(code == 202, "once there is room, jobs are accepted again (%d %s)" % (code, body))
        if code == 202:
            check(d.wait(body["id"]).get("status") == "done", "and run")
        code, body = d.json("GET", "/healthz")
        check(code == 200 and body.get("status") == "ok", "/healthz is ok again (%s)" % body)
        check(put(d, "new.glb", glb(2.0))[0] == 201, "uploads are accepted again")
    finally:
        stop_and_check(d)


def cache_over_room(mnt):
    if not os.access(converter_path(), os.X_OK):
        check(False, "the converter is there (%s)" % converter_path())
        return
    state = os.path.join(mnt, "state")
    d = Daemon("--state-dir", state)
    try:
        free = os.statvfs(mnt).f_bavail * os.statvfs(mnt).f_frsize
        # Seven maps (112 MiB): more than the whole disk.
        big = maps_asset(7)
        code, body = put(d, "huge.glb", big)
        check(code == 507 and body.get("error", {}).get("field") == "state_dir",
              "a %d-byte upload whose cache would not fit the disk (%d MiB free): 507 naming "
              "state_dir (%d %s)" % (len(big), free >> 20, code, body))
        # Three (48 MiB): fits the disk, not the room kept for jobs beside it.
        mid = maps_asset(3)
        code, body = put(d, "mid.glb", mid)
        check(code == 507, "one whose cache fits the disk but not its room for jobs: 507 (%d %s)"
              % (code, body))
        check(not leftovers(state), "nothing left behind (%s)" % leftovers(state))
        after = os.statvfs(mnt).f_bavail * os.statvfs(mnt).f_frsize
        check(after > free - (4 << 20), "the disk's room is still there (%d MiB free, %d before)"
              % (after >> 20, free >> 20))
        check(d.run(TINY).get("status") == "done", "and jobs run")
        code, body = put(d, "small.glb", glb(3.0))
        check(code == 201, "a small upload still fits (%d %s)" % (code, body))
    finally:
        stop_and_check(d)


def main():
    testlib.skip_without_egl()
    base = tempfile.mkdtemp(prefix="e2e_full_disk.")
    for name, size, part in (("full", "80m", start_on_full_disk),
                             ("room", "96m", cache_over_room)):
        mnt = os.path.join(base, name)
        os.mkdir(mnt)
        mounted, why = mount_tmpfs(mnt, size)
        check(mounted, "a %s tmpfs (needs root): %s" % (size, why))
        if not mounted:
            continue
        try:
            part(mnt)
        finally:
            subprocess.run(["umount", mnt], capture_output=True)
            os.rmdir(mnt)
    os.rmdir(base)
    testlib.finish("e2e_full_disk")


if __name__ == "__main__":
    main()
