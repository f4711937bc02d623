"""End to end over HTTP: a small forward job submitted with curl, its
statistics, captures, timings, determinism, listing, cancelling, waiting
clients, --once, and a shader the driver rejects failing only its job."""

import json
import os
import subprocess
import threading
import time

import testlib
from testlib import check

testlib.skip_without_egl()

STATS = ("n", "mean", "median", "stddev", "min", "max", "p95", "p99", "cv")
JOB = {"technique": "forward", "frames": 12, "warmup_frames": 2, "capture_interval": 6,
       "scene": {"preset": "grid", "dynamic": True, "width": 256, "height": 160}}

d = testlib.Daemon()
tmp = d.tmp
try:
    status, health = d.json("GET", "/healthz")
    check(status == 200 and health.get("status") == "ok", "healthz answers 200")

    status, info = d.json("GET", "/v1/info")
    check(status == 200, "info answers 200")
    check(info.get("version") and info.get("device", {}).get("gl_renderer"),
          "info names the version and GL renderer")
    names = [t["name"] for t in info.get("techniques", [])]
    check({"forward", "unlit", "osl"} <= set(names), "info lists the techniques: %s" % names)

    # Submit exactly as a user would: curl -d @job.json
    job_path = os.path.join(tmp, "job.json")
    with open(job_path, "w") as f:
        json.dump(JOB, f)
    out = subprocess.run(["curl", "-sS", "-d", "@" + job_path, d.base + "/v1/jobs",
                          "-w", "\n%{http_code}"], capture_output=True, text=True)
    body, code = out.stdout.rsplit("\n", 1)
    check(code == "202", "POST /v1/jobs with curl -d answers 202 (got %s)" % code)
    sub = json.loads(body)
    check(sub.get("status") == "queued" and sub.get("url") == "/v1/jobs/" + sub.get("id", ""),
          "submission answer has id, status and url")

    out = subprocess.run(["curl", "-sS", d.base + sub["url"] + "?wait=120"],
                         capture_output=True, text=True)
    job = json.loads(out.stdout)
    check(job.get("status") == "done", "job done: %s" % job.get("error"))
    check(job.get("spec", {}).get("scene", {}).get("lights") == 10, "spec has defaults filled in")
    check(job.get("progress") == {"frames_done": 12, "frames_total": 12}, "progress complete")
    res = job.get("result", {})
    check(res.get("frames") == 12 and res.get("warmup_frames") == 2, "frame counts")
    for series in ("gpu_ms", "cpu_ms", "frame_ms"):
        s = res.get(series, {})
        check(all(k in s for k in STATS) and s["n"] == 12, "%s has every statistic" % series)
        check(s.get("min", -1) >= 0 and s["min"] <= s["median"] <= s["max"], "%s ordered" % series)
    check(res["cpu_ms"]["median"] > 0 and res["frame_ms"]["median"] > 0, "CPU and frame time measured")
    check(res.get("wall_s", 0) > 0 and res.get("fps", 0) > 0, "wall time and fps")
    check(res.get("triangles_per_frame") == 256 * 32 * 16 * 2 + 256 * 12, "triangle count")
    check(res.get("device", {}).get("gl_version"), "result names the GL version")
    check("capture" in res.get("capture_policy", ""), "result says how captures were kept out")
    caps = res.get("captures", [])
    check([c["frame"] for c in caps] == [6, 12], "captures at frames 6 and 12")

    png = os.path.join(tmp, "a.png")
    check(d.download(caps[1]["url"], png) == 200, "capture downloads")
    pi = testlib.png_info(png)
    check(pi and pi["width"] == 256 and pi["height"] == 160, "capture is a 256x160 PNG: %s" % pi)
    check(pi and pi["lit_pixels"] > 256 * 160 // 10 and pi["colours"] > 50,
          "capture shows the scene, not a blank frame: %s" % pi)

    status, _, csv = d.request("GET", sub["url"] + "/timings.csv")
    rows = csv.decode().strip().split("\n")
    check(status == 200 and rows[0].startswith("frame,gpu_ms,cpu_ms"), "timings.csv header")
    check([int(r.split(",")[0]) for r in rows[1:]] == list(range(1, 13)), "one row per timed frame")

    # Determinism: the same job again gives identical pixels; another technique does not.
    again = d.run(JOB)
    png2 = os.path.join(tmp, "b.png")
    d.download(again["result"]["captures"][1]["url"], png2)
    diff = testlib.png_diff(png, png2)
    check(diff and diff["max_abs"] == 0, "same job, same pixels: %s" % diff)
    unlit = d.run(dict(JOB, technique="unlit"))
    png3 = os.path.join(tmp, "c.png")
    d.download(unlit["result"]["captures"][1]["url"], png3)
    diff = testlib.png_diff(png, png3)
    check(diff and diff["differing_pixels"] > 1000, "unlit differs from forward: %s" % diff)

    # A missing capture frame and unfinished job files answer clearly.
    status, body = d.json("GET", sub["url"] + "/frames/7.png")
    check(status == 404 and body["error"]["field"] == "frame", "uncaptured frame is 404")

    status, listing = d.json("GET", "/v1/jobs")
    ids = [j["id"] for j in listing.get("jobs", [])]
    check(status == 200 and sub["id"] in ids and again["id"] in ids, "list has the jobs")

    # Cancel a running job and a queued one; many waiting clients never block others.
    long_job = dict(JOB, frames=100000, timeout_s=0, capture_interval=0, scene={"width": 64, "height": 64})
    running = d.submit(long_job)
    queued = d.submit(long_job)
    deadline = time.time() + 30
    while d.json("GET", "/v1/jobs/" + running)[1]["status"] != "running" and time.time() < deadline:
        time.sleep(0.05)
    waiters = [threading.Thread(target=d.json, args=("GET", "/v1/jobs/%s?wait=30" % running))
               for _ in range(24)]
    for w in waiters:
        w.start()
    t0 = time.time()
    status, _ = d.json("GET", "/healthz")
    check(status == 200 and time.time() - t0 < 5, "healthz answers while 24 clients wait")
    status, body = d.json("DELETE", "/v1/jobs/" + queued)
    check(status == 200 and body["status"] == "cancelled", "queued job cancelled at once")
    status, body = d.json("DELETE", "/v1/jobs/" + running)
    check(status in (200, 202), "running job cancel accepted")
    final = d.wait(running)
    check(final["status"] == "cancelled" and "cancelled" in final.get("error", ""),
          "running job ends cancelled")
    for w in waiters:
        w.join(60)
    check(not any(w.is_alive() for w in waiters), "waiting clients were answered")
    status, body = d.json("DELETE", "/v1/jobs/" + sub["id"])
    check(status == 409, "cancelling a finished job is 409")

    # --once writes the same result files without HTTP, with the same pixels.
    once_dir = os.path.join(tmp, "once")
    out = subprocess.run([testlib.SHADEBENCHD, "--once", job_path, "--out", once_dir],
                         capture_output=True, text=True)
    check(out.returncode == 0, "--once exits 0")
    with open(os.path.join(once_dir, "result.json")) as f:
        once = json.load(f)
    check(once["gpu_ms"]["n"] == 12 and len(once["captures"]) == 2, "--once result")
    diff = testlib.png_diff(png, os.path.join(once_dir, "frame-000012.png"))
    check(diff and diff["max_abs"] == 0, "--once gives the daemon's pixels: %s" % diff)
    check(os.path.exists(os.path.join(once_dir, "job.json")) and
          os.path.exists(os.path.join(once_dir, "task.json")) and
          not [n for n in os.listdir(tmp) if ".partial-" in n],
          "--once adds job.json and task.json, and leaves no partial folder")
    # It replaces its folder whole, so a folder of other files is refused, untouched.
    foreign = os.path.join(tmp, "foreign")
    os.makedirs(foreign)
    open(os.path.join(foreign, "notes.txt"), "w").close()
    out = subprocess.run([testlib.SHADEBENCHD, "--once", job_path, "--out", foreign],
                         capture_output=True, text=True)
    check(out.returncode == 2 and "other files" in out.stderr and
          os.listdir(foreign) == ["notes.txt"], "--once refuses a folder of other files: %s"
          % out.stderr[-300:])
    check(d.alive(), "daemon still running")
finally:
    code = d.stop()
check(code == 0, "SIGTERM stops the daemon with exit code 0 (got %s)" % code)
if testlib.failures:
    d.dump_log()
d.cleanup(keep=testlib.failures > 0)

# A shader the driver rejects fails that job, with the driver's message, and
# the daemon keeps serving the next one.
d = testlib.Daemon(env={"SHADEBENCH_FAULT_SHADER": "forward.frag"})
try:
    bad = d.run(JOB)
    check(bad["status"] == "failed" and "compile" in bad.get("error", ""),
          "broken shader fails the job: %s" % bad.get("error"))
    check(len(bad.get("error", "")) > 40, "the error carries the driver's message")
    good = d.run(dict(JOB, technique="unlit"))
    check(good["status"] == "done", "the next job still runs")
    check(d.json("GET", "/healthz")[0] == 200, "daemon healthy after a GL failure")
finally:
    testlib.stop_and_check(d)
# The first timed frame of a fresh daemon, with no warm-up before it: its
# GPU time is a real one (llvmpipe answered a context's first timer query
# with the time since boot, 86 minutes into a frame of 30 ms).
d = testlib.Daemon()
try:
    first = d.run({"technique": "forward", "frames": 3, "warmup_frames": 0,
                   "scene": {"width": 32, "height": 32}})
    r = first.get("result", {})
    check(first["status"] == "done" and r.get("timer_query_implausible") == 0 and
          r["gpu_ms"]["max"] <= r["wall_s_including_captures"] * 1e3,
          "a fresh daemon's first frame has a plausible GPU time: %s ms in %s s, %s implausible"
          % (r.get("gpu_ms", {}).get("max"), r.get("wall_s_including_captures"),
             r.get("timer_query_implausible")))
finally:
    testlib.stop_and_check(d)
testlib.finish("e2e_http")
