#!/usr/bin/env python3
"""Issue 34's attacks, repeated against a daemon (all but item 5, the
render thread's, which bench_runaway-style tests own): each prints what the
red team measured before and what this daemon does now.

  bench/bench_attacks.py [--rounds N] [--only NAME,...] [--json FILE]

  races      a DELETE and a replacing PUT racing a job's POST, --rounds
             each: how many accepted jobs failed
  decode     a 2,172-byte GLB whose 16x16 JPEG declares 8192x8192, four of
             them, and an honest asset with four 2048x2048 maps: the
             answers, the cache written, a 64x48 job's charge and the
             daemon's resident set before, during and after it
  nodes      a million root nodes (10 MB) and 60,000 mesh nodes: the
             upload's answer and time, and a small upload's wait behind it
  slow       four uploads sending a byte every 2 s: how long until a fifth
             gets in, from another address and from the same one
  orphans    kill -9 during a conversion: converters left, temporaries left
             after the restart
  replaced   a replaced hash's files: when they go after its last job
  disk       a start on a full disk (a 80 MiB tmpfs, root): does it start,
             what /healthz says, how long until it accepts jobs again once
             the disk has room; an upload whose cache would not fit (96 MiB)
  small      an unused mesh, 257 levels, bad base64, data longer than
             byteLength, two Host headers, a lowercase bearer, 1e-400, %zz

Needs the daemon and the converter beside it (SHADEBENCHD=build/shadebenchd)."""

import hashlib
import os
import random
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time

import benchrun
from benchrun import testlib

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "e2e"))
import gltf_gen  # noqa: E402
from e2e_assets import glb, put  # noqa: E402
from e2e_full_disk import maps_asset, mount_tmpfs  # noqa: E402
from e2e_upload_slots import SlowUpload, put_from  # noqa: E402

ap = benchrun.parser()
ap.add_argument("--rounds", type=int, default=100, help="rounds of each race")
ap.add_argument("--only", help="comma-separated attacks (default: all)")
ap.add_argument("--json", help="write every figure here")
args = ap.parse_args()
ONLY = set(args.only.split(",")) if args.only else None
FIGURES = {}
TINY = {"technique": "forward", "frames": 1, "warmup_frames": 0,
        "scene": {"width": 16, "height": 16, "lights": 1}}


def wanted(name):
    return ONLY is None or name in ONLY


def report(name, **figures):
    FIGURES[name] = figures
    print("%-9s %s" % (name, ", ".join("%s %s" % (k, v) for k, v in figures.items())),
          flush=True)


def rss_mb(pid):
    with open("/proc/%d/status" % pid) as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) // 1024
    return 0


def on(asset):
    job = dict(TINY)
    job["scene"] = dict(TINY["scene"], asset=asset)
    return job


def races(d):
    for kind in ("DELETE", "PUT"):
        accepted, refused = [], 0
        t0 = time.time()
        put(d, "race.glb", glb(2.0))
        put(d, "race.glb", glb(3.0))
        put_s = (time.time() - t0) / 2
        for r in range(args.rounds):
            put(d, "race.glb", glb(1.0))
            out = {}
            if kind == "DELETE":
                offset = random.uniform(-0.003, 0.008)
                other = lambda: d.json("DELETE", "/v1/assets/race.glb")  # noqa: E731
            else:
                offset = random.uniform(-1.1 * put_s, -0.8 * put_s)
                other = lambda r=r: put(d, "race.glb", glb(2.0 + r % 2))  # noqa: E731

            def job():
                time.sleep(max(0.0, -offset))
                out["job"] = d.json("POST", "/v1/jobs", on("race.glb"))

            def interfere():
                time.sleep(max(0.0, offset))
                other()
            ts = [threading.Thread(target=job), threading.Thread(target=interfere)]
            for t in ts:
                t.start()
            for t in ts:
                t.join()
            code, body = out["job"]
            if code == 202:
                accepted.append(body["id"])
            else:
                refused += 1
        failed = [j for j in accepted if d.wait(j).get("status") != "done"]
        report("race_" + kind.lower(), rounds=args.rounds, accepted=len(accepted),
               refused=refused, accepted_failed=len(failed))


def decode(d):
    for name, images in (("one", [gltf_gen.lying_jpeg()]), ("four", [gltf_gen.lying_jpeg()] * 4)):
        data = gltf_gen.image_asset(images, "image/jpeg").glb()
        t0 = time.time()
        code, body = put(d, "lying_%s.glb" % name, data)
        cache = os.path.join(d.state, "assets", hashlib.sha256(data).hexdigest() + ".sbasset")
        report("lying_jpeg_" + name, upload_bytes=len(data), status=code,
               field=body.get("error", {}).get("field"), seconds=round(time.time() - t0, 2),
               cache_bytes=os.path.getsize(cache) if os.path.exists(cache) else 0)
    pid = d.proc.pid
    d.run(on("race.glb"))
    idle = rss_mb(pid)
    data = maps_asset(4)
    code, _ = put(d, "maps.glb", data)
    code, body = d.json("POST", "/v1/jobs", {"frames": 2, "warmup_frames": 0, "scene": {
        "asset": "maps.glb", "width": 64, "height": 48}})
    peak = idle
    while d.json("GET", "/v1/jobs/" + body["id"])[1].get("status") in ("queued", "running"):
        peak = max(peak, rss_mb(pid))
        time.sleep(0.05)
    time.sleep(1.0)
    report("honest_maps", upload_bytes=len(data), charged_mib=round(
        body.get("cost", {}).get("asset_bytes", 0) / 1048576), rss_idle_mb=idle,
        rss_peak_mb=peak, rss_after_mb=rss_mb(pid))


def nodes(d):
    for name, data in (("roots_1m", gltf_gen.many_nodes_asset(1000000)),
                       ("mesh_nodes_60k", gltf_gen.many_nodes_asset(60000, 60000))):
        out = {}

        def big():
            t0 = time.time()
            out["code"], body = put(d, name + ".glb", data)
            out["field"] = body.get("error", {}).get("field")
            out["s"] = time.time() - t0
        t = threading.Thread(target=big)
        t.start()
        time.sleep(0.5)
        t0 = time.time()
        small, _ = put(d, "behind.glb", glb(4.0 + len(name)))
        behind = time.time() - t0
        t.join()
        report(name, upload_bytes=len(data), status=out["code"], field=out["field"],
               seconds=round(out["s"], 2), small_upload_behind_it_s=round(behind, 2),
               small_status=small)


def slow(d):
    uploads = [SlowUpload(d.port, "slow%d.glb" % i) for i in range(4)]
    time.sleep(1.0)
    refused = sum(1 for u in uploads if u.status() == 429)
    t0 = time.time()
    other = put_from(d.port, "127.0.0.2", "fifth.glb", glb(5.0))[0]
    other_s = time.time() - t0
    t0 = time.time()
    while True:
        code, headers, _ = put_from(d.port, "127.0.0.1", "sixth.glb", glb(6.0))
        if code != 429 or time.time() - t0 > 600:
            break
        time.sleep(float(headers.get("Retry-After", "1")))
    same_s = time.time() - t0
    for u in uploads:
        u.close()
    report("slow_uploads", refused_429=refused, other_address_status=other,
           other_address_s=round(other_s, 2), same_address_status=code,
           same_address_s=round(same_s, 1))


def orphans():
    mark = tempfile.mkdtemp(prefix="bench_attacks.")
    stand_in = os.path.join(mark, "converter")
    from e2e_orphans import STAND_IN, running
    with open(stand_in, "w") as f:
        f.write(STAND_IN)
    os.chmod(stand_in, 0o755)
    state = os.path.join(mark, "state")
    d = testlib.Daemon("--state-dir", state, "--asset-converter", stand_in,
                       env={"ORPHAN_MARK": mark})
    def upload():
        try:
            put(d, "x.glb", glb(7.0), timeout=10)
        except OSError:
            pass  # the daemon is killed under it
    threading.Thread(target=upload, daemon=True).start()
    while not os.path.exists(os.path.join(mark, "pid")):
        time.sleep(0.05)
    pid = int(open(os.path.join(mark, "pid")).read().split()[0])
    d.proc.send_signal(signal.SIGKILL)
    d.proc.wait()
    d.log.close()
    time.sleep(1.0)
    left = running(pid)
    if left:
        os.kill(pid, signal.SIGKILL)
    d = testlib.Daemon("--state-dir", state, "--asset-converter", stand_in)
    temps = [n for n in os.listdir(os.path.join(state, "assets"))
             if n.startswith(("upload-", "convert-"))]
    d.stop()
    report("orphans", converters_left_1s_after=int(left), temporaries_after_restart=len(temps))


def replaced(d):
    first = glb(8.0)
    sha = hashlib.sha256(first).hexdigest()
    put(d, "r.glb", first)
    blocker = d.submit({"frames": 1000000, "warmup_frames": 0, "timeout_s": 0,
                        "scene": {"width": 16, "height": 16}})
    job = d.submit(on("r.glb"))
    put(d, "r.glb", glb(9.0))
    d.json("DELETE", "/v1/jobs/" + blocker)
    d.wait(job)
    t0 = time.time()
    folder = os.path.join(d.state, "assets")
    while any(n.startswith(sha) for n in os.listdir(folder)) and time.time() - t0 < 30:
        time.sleep(0.02)
    gone = not any(n.startswith(sha) for n in os.listdir(folder))
    report("replaced_hash", gone=gone, seconds_after_last_job=round(time.time() - t0, 2))


def disk():
    base = tempfile.mkdtemp(prefix="bench_attacks_disk.")
    mnt = os.path.join(base, "full")
    os.mkdir(mnt)
    ok, why = mount_tmpfs(mnt, "80m")
    if not ok:
        report("full_disk", skipped=why)
        return
    try:
        state = os.path.join(mnt, "state")
        d = testlib.Daemon("--state-dir", state)
        d.run(TINY)
        d.stop()
        testlib.fill_disk(os.path.join(mnt, "filler"))
        try:
            d = testlib.Daemon("--state-dir", state)
        except RuntimeError:
            report("full_disk", started=False)
            return
        health = d.json("GET", "/healthz")[1].get("status")
        refused = d.json("POST", "/v1/jobs", TINY)[0]
        os.remove(os.path.join(mnt, "filler"))
        t0 = time.time()
        while d.json("POST", "/v1/jobs", TINY)[0] == 507 and time.time() - t0 < 60:
            time.sleep(0.05)
        report("full_disk", started=True, healthz=health, job_status_while_full=refused,
               accepting_again_after_s=round(time.time() - t0, 2))
        d.stop()
    finally:
        subprocess.run(["umount", mnt], capture_output=True)
    room = os.path.join(base, "room")
    os.mkdir(room)
    ok, why = mount_tmpfs(room, "96m")
    try:
        d = testlib.Daemon("--state-dir", os.path.join(room, "state"))
        data = maps_asset(7)
        code, body = put(d, "huge.glb", data)
        free = os.statvfs(room).f_bavail * os.statvfs(room).f_frsize
        report("cache_over_room", upload_bytes=len(data), status=code,
               field=body.get("error", {}).get("field"), free_mib_after=free >> 20)
        d.stop()
    finally:
        subprocess.run(["umount", room], capture_output=True)


def small(d):
    figures = {}
    for name, data in (("unused_mesh", gltf_gen.unused_mesh_asset().glb()),
                       ("chain_257", gltf_gen.node_chain_asset(257).glb()),
                       ("base64", gltf_gen.data_uri_asset(gltf_gen.bad_base64_unpadded)),
                       ("data_longer", gltf_gen.data_uri_asset(gltf_gen.data_longer_than_bytelength))):
        code, body = put(d, name + ".glb", data)
        figures[name] = "%d %s" % (code, body.get("error", {}).get("field", ""))

    def raw(request):
        s = socket.create_connection(("127.0.0.1", d.port))
        s.sendall(request)
        answer = s.recv(65536).split(b" ", 2)[1].decode()
        s.close()
        return answer
    figures["two_hosts"] = raw(b"GET /v1/jobs HTTP/1.1\r\nHost: a\r\nHost: b\r\n\r\n")
    figures["percent_zz"] = raw(b"GET /v1/jobs?status=%zz HTTP/1.1\r\nHost: a\r\n\r\n")
    code, body = d.json("POST", "/v1/jobs", b'{"warmup_frames": 1e-400}')
    figures["1e-400"] = "%d %s" % (code, body.get("error", {}).get("field", ""))
    report("small", **figures)
    tmp = tempfile.mkdtemp(prefix="bench_attacks_token.")
    with open(os.path.join(tmp, "token"), "w") as f:
        f.write("sesame\n")
    t = testlib.Daemon("--token", os.path.join(tmp, "token"))
    code, _ = t.json("GET", "/v1/info", headers={"Authorization": "bearer sesame"})
    t.stop()
    report("bearer", lowercase_scheme_status=code)


run = benchrun.Run()
run.start()
d = testlib.Daemon("--queue-size", "1024")
try:
    if wanted("races"):
        races(d)
    if wanted("decode"):
        decode(d)
    if wanted("nodes"):
        nodes(d)
    if wanted("slow"):
        slow(d)
    if wanted("replaced"):
        replaced(d)
    if wanted("small"):
        small(d)
finally:
    d.stop()
if wanted("orphans"):
    orphans()
if wanted("disk"):
    disk()
run.end([])
benchrun.write_json(args.json, FIGURES, indent=1)
