"""The shadebench client against a daemon with a bearer token: submit
--wait --out --junit, quality verdicts, a baseline comparison that passes on
the same job and fails on a slower one, status/list/cancel/fetch/info, exit
codes, and the token itself (401 without it, /healthz open)."""

import json
import os
import subprocess
import time
import xml.etree.ElementTree as ET

import testlib
from testlib import check

testlib.skip_without_egl()
CLIENT = os.environ.get("SHADEBENCH_CLIENT", "./shadebench")
SCENE = {"width": 160, "height": 120, "dynamic": True}
TOKEN = "s3cret-token-for-tests"


def client(*args, env_token=True, timeout=600):
    env = dict(os.environ, SHADEBENCH_SERVER=d.base)
    env.pop("SHADEBENCH_TOKEN", None)
    if env_token:
        env["SHADEBENCH_TOKEN"] = TOKEN
    return subprocess.run([CLIENT] + list(args), capture_output=True, text=True, env=env,
                          timeout=timeout)


def write_job(name, job):
    path = os.path.join(d.tmp, name + ".json")
    with open(path, "w") as f:
        json.dump(job, f)
    return path


tmp_token = os.path.join(os.environ.get("TMPDIR", "/tmp"), "shadebench-token-%d" % os.getpid())
with open(tmp_token, "w") as f:
    f.write(TOKEN + "\n")
d = testlib.Daemon("--token", tmp_token)
try:
    # The token: every endpoint but /healthz needs it.
    check(d.json("GET", "/healthz")[0] == 200, "/healthz is open")
    status, body = d.json("GET", "/v1/jobs")
    check(status == 401 and body["error"]["field"] == "Authorization", "no token: 401 naming Authorization")
    check(d.json("GET", "/v1/jobs", headers={"Authorization": "Bearer wrong"})[0] == 401, "wrong token: 401")
    check(d.json("POST", "/v1/jobs", {"frames": 1})[0] == 401, "no token: POST refused")
    auth = {"Authorization": "Bearer " + TOKEN}
    check(d.json("GET", "/v1/jobs", headers=auth)[0] == 200, "right token: 200")
    out = client("list", env_token=False)
    check(out.returncode == 2 and "401" in out.stderr, "client without token exits 2: %s" % out.stderr)
    out = client("--token", TOKEN, "info", env_token=False)
    check(out.returncode == 0 and json.loads(out.stdout)["version"], "--token works")

    # submit --wait --out --junit, with quality judged against a reference.
    good = write_job("good", {"technique": "osl", "frames": 12, "warmup_frames": 2,
                              "capture_interval": 6, "reference": "forward",
                              "scene": dict(SCENE, dynamic=False)})
    outdir, junit = os.path.join(d.tmp, "good"), os.path.join(d.tmp, "good.xml")
    out = client("submit", good, "--wait", "--out", outdir, "--junit", junit)
    check(out.returncode == 0, "good job passes: rc %d %s" % (out.returncode, out.stderr[-500:]))
    job_id = out.stdout.strip()
    check(len(job_id) > 10, "submit prints the job id")
    check("frames" in out.stderr, "progress is shown (plain lines when not a terminal)")
    for name in ("job.json", "result.json", "timings.csv", "frame-000006.png", "frame-000012.png",
                 "reference-000012.png", "ssim-000012.png", "flip-000012.png"):
        check(os.path.exists(os.path.join(outdir, name)), "--out has %s" % name)
    with open(os.path.join(outdir, "result.json")) as f:
        result = json.load(f)
    check(len(result.get("samples", {}).get("frame_ms", [])) == 12, "result.json carries per-frame samples")
    tree = ET.parse(junit)
    cases = tree.getroot().findall(".//testcase")
    check(len(cases) == 3 and tree.getroot().get("failures") == "0",
          "JUnit: job + 2 captures, no failures (%d cases)" % len(cases))

    # A quality failure: unlit against forward fails PerceptualDiff, exit 1.
    bad = write_job("bad", {"technique": "unlit", "frames": 6, "warmup_frames": 0,
                            "capture_interval": 3, "reference": "forward", "scene": SCENE})
    bad_junit = os.path.join(d.tmp, "bad.xml")
    out = client("submit", bad, "--wait", "--junit", bad_junit, "--min-ssim", "0.99")
    check(out.returncode == 1, "quality failure exits 1 (rc %d)" % out.returncode)
    root = ET.parse(bad_junit).getroot()
    failures = root.findall(".//failure")
    check(len(failures) == 2 and "PerceptualDiff" in failures[0].get("message") and "SSIM" in failures[0].get("message"),
          "JUnit failures name PerceptualDiff and SSIM: %s" % [f.get("message") for f in failures])

    # Baselines: the same job passes; one with 20x the lights (3.5 times
    # slower on llvmpipe) is a regression. The 60% allowance keeps the first
    # check clear of noise from tests running in parallel.
    base_job = {"technique": "forward", "frames": 40, "warmup_frames": 5, "scene": SCENE}
    base_dir = os.path.join(d.tmp, "base")
    out = client("submit", write_job("base", base_job), "--wait", "--out", base_dir)
    check(out.returncode == 0, "baseline run")
    baseline = os.path.join(base_dir, "result.json")
    gate_junit = os.path.join(d.tmp, "gate.xml")
    out = client("submit", write_job("same", base_job), "--wait", "--baseline", baseline,
                 "--max-slowdown", "60%", "--junit", gate_junit)
    check(out.returncode == 0, "same job against its baseline passes: %s" % out.stderr[-400:])
    names = [c.get("name") for c in ET.parse(gate_junit).getroot().findall(".//testcase")]
    check("median frame_ms vs baseline" in names, "JUnit has the timing gate: %s" % names)
    slow_job = dict(base_job, scene=dict(SCENE, lights=200))
    out = client("submit", write_job("slow", slow_job), "--wait", "--baseline", baseline,
                 "--max-slowdown", "60%", "--junit", gate_junit)
    check(out.returncode == 1 and "REGRESSION" in out.stderr, "200 lights is a regression: %s" % out.stderr[-400:])
    fail = ET.parse(gate_junit).getroot().find(".//failure")
    check(fail is not None and "slower by" in fail.get("message", ""), "JUnit explains the regression")

    # status, list, fetch, cancel, info.
    out = client("status", job_id)
    check(out.returncode == 0 and " done " in out.stdout, "status: %s" % out.stdout)
    out = client("list")
    check(out.returncode == 0 and job_id in out.stdout, "list has the job")
    fetched = os.path.join(d.tmp, "fetched")
    out = client("fetch", job_id, "--out", fetched)
    check(out.returncode == 0 and os.path.exists(os.path.join(fetched, "flip-000006.png")), "fetch downloads")
    long_id = client("submit", write_job("long", {"frames": 1000000, "warmup_frames": 0,
                                                  "scene": {"width": 32, "height": 32}})).stdout.strip()
    time.sleep(0.5)
    out = client("cancel", long_id)
    check(out.returncode == 0, "cancel exits 0")
    out = client("status", long_id)
    check("cancelled" in out.stdout, "the job is cancelled: %s" % out.stdout)

    # Usage and server errors exit 2.
    check(client("frobnicate").returncode == 2, "unknown command exits 2")
    check(client("submit").returncode == 2, "missing argument exits 2")
    check(client("status", "nope-nope").returncode == 2, "unknown job exits 2")
    check(client("submit", write_job("invalid", {"frames": -1})).returncode == 2, "invalid job exits 2")
    down = subprocess.run([CLIENT, "--server", "http://127.0.0.1:9", "list"], capture_output=True, text=True)
    check(down.returncode == 2, "unreachable server exits 2")
finally:
    os.unlink(tmp_token)
    testlib.stop_and_check(d)
testlib.finish("e2e_client")
