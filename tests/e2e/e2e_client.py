"""The shadebench client against a daemon with a bearer token: the token from
a file or the environment (argv works, with a warning), submit --wait --out
--junit with quality verdicts, JUnit names from the job's content with real
times and figures, status/list/cancel/fetch/info, exit codes, and the
hygiene rules: --baseline needs --wait, a missing baseline or an --out
folder of another job is refused before anything runs."""

import json
import os
import subprocess
import time

import testlib
from testlib import check
from clientlib import Client, junit_cases, CLIENT

testlib.skip_without_egl()
SCENE = {"width": 160, "height": 120, "dynamic": True}
TOKEN = "s3cret-token-for-tests"

tmp_token = os.path.join(os.environ.get("TMPDIR", "/tmp"), "shadebench-token-%d" % os.getpid())
with open(tmp_token, "w") as f:
    f.write(TOKEN + "\n")
d = testlib.Daemon("--token", tmp_token)
cl = Client(d, TOKEN)
try:
    # The token: every endpoint but /healthz needs it.
    check(d.json("GET", "/healthz")[0] == 200, "/healthz is open")
    status, body = d.json("GET", "/v1/jobs")
    check(status == 401 and body["error"]["field"] == "Authorization", "no token: 401 naming Authorization")
    check(d.json("GET", "/v1/jobs", headers={"Authorization": "Bearer wrong"})[0] == 401, "wrong token: 401")
    check(d.json("POST", "/v1/jobs", {"frames": 1})[0] == 401, "no token: POST refused")
    auth = {"Authorization": "Bearer " + TOKEN}
    check(d.json("GET", "/v1/jobs", headers=auth)[0] == 200, "right token: 200")
    out = cl.run("list", env_token=False)
    check(out.returncode == 2 and "401" in out.stderr, "client without token exits 2: %s" % out.stderr)
    out = cl.run("--token-file", tmp_token, "info", "--json", env_token=False)
    check(out.returncode == 0 and json.loads(out.stdout)["version"], "--token-file works")
    out = cl.run("info", env_token=False, extra_env={"SHADEBENCH_TOKEN_FILE": tmp_token})
    check(out.returncode == 0, "$SHADEBENCH_TOKEN_FILE works")
    out = cl.run("info")
    check(out.returncode == 0 and "warning" not in out.stderr, "$SHADEBENCH_TOKEN works, silently")
    out = cl.run("--token", TOKEN, "info", env_token=False)
    check(out.returncode == 0 and "--token-file" in out.stderr,
          "--token on the command line works but warns: %s" % out.stderr)
    out = cl.run("--token-file", cl.path("no-such-token"), "info", env_token=False)
    check(out.returncode == 2 and "token file" in out.stderr, "a missing token file exits 2")

    # submit --wait --out --junit, with quality judged against a reference
    # (OSL at 64 texels an object: as close to forward as the default 256
    # here, in a seventh of the time).
    good_job = {"technique": "osl", "frames": 12, "warmup_frames": 2, "capture_interval": 6,
                "reference": "forward", "osl": {"resolution": 64}, "scene": dict(SCENE, dynamic=False)}
    good = cl.write("good", good_job)
    outdir, junit = cl.path("good"), cl.path("good.xml")
    out = cl.run("submit", good, "--wait", "--out", outdir, "--junit", junit, "--label", "commit=abc")
    check(out.returncode == 0, "good job passes: rc %d %s" % (out.returncode, out.stderr[-500:]))
    job_id = out.stdout.strip()
    check(len(job_id) > 10 and "\n" not in job_id, "submit prints the job id")
    check("frames" in out.stderr, "progress is shown (plain lines when not a terminal)")
    for name in ("job.json", "result.json", "timings.csv", "frame-000006.png", "frame-000012.png",
                 "reference-000012.png", "ssim-000012.png", "flip-000012.png"):
        check(os.path.exists(os.path.join(outdir, name)), "--out has %s" % name)
    with open(os.path.join(outdir, "result.json")) as f:
        result = json.load(f)
    check(len(result.get("samples", {}).get("frame_ms", [])) == 12, "result.json carries per-frame samples")
    check(result.get("spec", {}).get("labels") == {"commit": "abc"} and result.get("job_id") == job_id,
          "result.json carries the spec with --label's label, and the job id")
    root, cases = junit_cases(junit)
    check(len(cases) == 3 and root.get("failures") == "0", "JUnit: job + 2 captures, no failures (%d cases)" % len(cases))
    names = sorted(cases)
    check(all(job_id not in n for n in names), "JUnit names do not carry the job id: %s" % names)
    check(any(n.startswith("osl ") and "160x120" in n and n.endswith(": job") for n in names),
          "JUnit names say technique and scene: %s" % names)
    jobcase = [c for n, c in cases.items() if n.endswith(": job")][0]
    check(jobcase[1] > 0 and float(jobcase[2].get("frame_ms_median", 0)) > 0 and jobcase[2].get("job") == job_id,
          "the job case has its real time and the figures as properties: %s" % (jobcase,))
    check("frame_ms median" in out.stderr and "PASS" in out.stderr, "the figures are in the CI log")
    # The same job again gets the same names: CI systems track them.
    junit2 = cl.path("good2.xml")
    out = cl.run("submit", good, "--wait", "--junit", junit2)
    check(out.returncode == 0 and sorted(junit_cases(junit2)[1]) == names, "names are stable from run to run")

    # A quality failure: unlit against forward fails PerceptualDiff, exit 1.
    bad = cl.write("bad", {"technique": "unlit", "frames": 6, "warmup_frames": 0,
                           "capture_interval": 3, "reference": "forward", "scene": SCENE})
    bad_junit = cl.path("bad.xml")
    out = cl.run("submit", bad, "--wait", "--junit", bad_junit, "--min-ssim", "0.99")
    check(out.returncode == 1, "quality failure exits 1 (rc %d)" % out.returncode)
    fails = [c[0] for c in junit_cases(bad_junit)[1].values() if c[0]]
    check(len(fails) == 2 and "PerceptualDiff" in fails[0] and "SSIM" in fails[0],
          "JUnit failures name PerceptualDiff and SSIM: %s" % fails)

    # Hygiene: refused before any job is submitted (nothing on stdout).
    small = cl.write("small", {"frames": 4, "warmup_frames": 0, "scene": SCENE})
    before = len(d.json("GET", "/v1/jobs", headers=auth)[1]["jobs"])
    out = cl.run("submit", small, "--baseline", os.path.join(outdir, "result.json"))
    check(out.returncode == 2 and "--wait" in out.stderr and not out.stdout, "--baseline without --wait is refused")
    out = cl.run("submit", small, "--wait", "--baseline", cl.path("missing", "result.json"))
    check(out.returncode == 2 and "missing" in out.stderr and not out.stdout,
          "a missing baseline is noticed before the job runs: %s" % out.stderr)
    out = cl.run("submit", small, "--wait", "--out", outdir)
    check(out.returncode == 2 and job_id in out.stderr and not out.stdout,
          "--out holding another job's files is refused: %s" % out.stderr)
    check(len(d.json("GET", "/v1/jobs", headers=auth)[1]["jobs"]) == before, "and no job was submitted")

    # status, list, fetch (again into its own folder), cancel, info.
    out = cl.run("status", job_id)
    check(out.returncode == 0 and " done " in out.stdout, "status: %s" % out.stdout)
    out = cl.run("list")
    check(out.returncode == 0 and job_id in out.stdout, "list has the job")
    out = cl.run("fetch", job_id, "--out", outdir)
    check(out.returncode == 0, "fetch into the job's own folder: %s" % out.stderr[-300:])
    fetched = cl.path("fetched")
    out = cl.run("fetch", job_id, "--out", fetched)
    check(out.returncode == 0 and os.path.exists(os.path.join(fetched, "flip-000006.png")), "fetch downloads")
    long_id = cl.run("submit", cl.write("long", {"frames": 1000000, "warmup_frames": 0, "timeout_s": 0,
                                                 "scene": {"width": 32, "height": 32}})).stdout.strip()
    out = cl.run("fetch", long_id, "--out", fetched)
    check(out.returncode == 2 and "already holds" in out.stderr, "fetch refuses another job's folder")
    time.sleep(0.5)
    out = cl.run("cancel", long_id)
    check(out.returncode == 0, "cancel exits 0")
    out = cl.run("status", long_id)
    check("cancelled" in out.stdout, "the job is cancelled: %s" % out.stdout)

    # Usage and server errors exit 2.
    check(cl.run("frobnicate").returncode == 2, "unknown command exits 2")
    check(cl.run("submit").returncode == 2, "missing argument exits 2")
    check(cl.run("status", "nope-nope").returncode == 2, "unknown job exits 2")
    check(cl.run("submit", cl.write("invalid", {"frames": -1})).returncode == 2, "invalid job exits 2")
    check(cl.run("submit", small, "--wait", "--runs", "0").returncode == 2, "--runs 0 exits 2")
    check(cl.run("submit", small, "--label", "novalue").returncode == 2, "--label without = exits 2")
    check(cl.run("list", "--filter", "technique=forward").returncode == 2, "--filter outside history exits 2")
    down = subprocess.run([CLIENT, "--server", "http://127.0.0.1:9", "list"], capture_output=True, text=True)
    check(down.returncode == 2, "unreachable server exits 2")
finally:
    os.unlink(tmp_token)
    testlib.stop_and_check(d)
testlib.finish("e2e_client")
