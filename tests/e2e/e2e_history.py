"""History end to end: labels on jobs (and on sweeps, through the base job),
GET /v1/jobs filtered by technique, status, label and since with each job's
headline figures, rejections naming the filter, and shadebench history
with its table, CSV and trend chart."""

import csv
import os
import time
import urllib.parse
import xml.etree.ElementTree as ET

import testlib
from testlib import check
from clientlib import Client

testlib.skip_without_egl()
SCENE = {"width": 128, "height": 96}
JOB = {"technique": "forward", "frames": 6, "warmup_frames": 1, "scene": SCENE}


def listed(d, **query):
    status, body = d.json("GET", "/v1/jobs?" + urllib.parse.urlencode(query))
    return status, body


d = testlib.Daemon()
cl = Client(d)
try:
    t0 = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(time.time() - 1))
    a = d.run(dict(JOB, labels={"branch": "main", "commit": "aaa"}))
    b = d.run(dict(JOB, labels={"branch": "main", "commit": "bbb"}))
    o = d.run(dict(JOB, technique="osl", capture_interval=6, reference="forward",
                   osl={"resolution": "auto"}, labels={"branch": "topic", "commit": "ccc"}))
    check(a["spec"]["labels"] == {"branch": "main", "commit": "aaa"}, "the spec keeps the labels")
    long_id = d.submit({"frames": 1000000, "warmup_frames": 0, "timeout_s": 0, "scene": {"width": 32, "height": 32}})
    d.json("DELETE", "/v1/jobs/" + long_id)
    d.wait(long_id)

    status, body = listed(d)
    jobs = {j["id"]: j for j in body["jobs"]}
    check(status == 200 and len(jobs) == 4, "no filter lists every job")
    fig = jobs[a["id"]].get("figures", {})
    check(fig.get("frame_ms", {}).get("median") == a["result"]["frame_ms"]["median"] and
          len(fig["frame_ms"]["ci95"]) == 2 and fig.get("gl_renderer") and fig.get("runs") == 1,
          "each job has its headline figures: %s" % fig)
    check(jobs[o["id"]]["figures"].get("worst_ssim") == o["result"]["quality"]["worst_ssim"]["value"],
          "worst SSIM among the figures")
    check("figures" not in jobs[long_id] and jobs[long_id]["labels"] == {}, "a cancelled job has no figures")
    check("result" not in jobs[a["id"]], "the list stays small: no results")

    ids = lambda body: sorted(j["id"] for j in body["jobs"])
    check(ids(listed(d, technique="forward")[1]) == sorted([a["id"], b["id"], long_id]), "technique=forward")
    check(ids(listed(d, technique="osl")[1]) == [o["id"]], "technique=osl")
    check(ids(listed(d, **{"label.branch": "main"})[1]) == sorted([a["id"], b["id"]]), "label.branch=main")
    check(ids(listed(d, **{"label.commit": "bbb", "technique": "forward"})[1]) == [b["id"]],
          "filters combine")
    status, body = d.json("GET", "/v1/jobs?label.commit=aaa&label.commit=ccc")
    check(ids(body) == sorted([a["id"], o["id"]]), "a repeated filter accepts any of its values")
    check(ids(listed(d, status="cancelled")[1]) == [long_id], "status=cancelled")
    check(len(listed(d, since=t0)[1]["jobs"]) == 4, "since before the first job: all")
    check(listed(d, since="2999-01-01")[1]["jobs"] == [], "since in the future: none")
    check(ids(listed(d, since=o["created"])[1]) == sorted([o["id"], long_id]), "since a job's creation time")
    for query, field in (("techniqe=forward", "techniqe"), ("status=finished", "status"),
                         ("since=yesterday", "since"), ("label.bad%20key=x", "label.bad key")):
        status, body = d.json("GET", "/v1/jobs?" + query)
        check(status == 400 and body.get("error", {}).get("field") == field,
              "?%s -> 400 naming %s: %s" % (query, field, body))

    # Labels are validated like every field.
    for labels, field in (({"commit": 5}, "labels.commit"), ({"a b": "x"}, "labels.a b"),
                          ({"k": "x" * 200}, "labels.k"), (["main"], "labels")):
        testlib.rejects(d, dict(JOB, labels=labels), field)

    # A sweep passes its base job's labels to every point.
    status, reply = d.json("POST", "/v1/sweeps", {"base": dict(JOB, labels={"sweep": "s1"}),
                                                 "vary": {"scene.lights": [1, 2]}})
    sw = d.wait_sweep(reply["id"])
    points = {p["job"] for p in sw["points"]}
    check(sw["status"] == "done" and points <= set(ids(listed(d, **{"label.sweep": "s1"})[1])) and points,
          "the sweep's point jobs carry its labels")

    # shadebench history: table, CSV, trend chart.
    outdir = cl.path("hist")
    out = cl.run("history", "--filter", "label.branch=main", "--filter", "technique=forward", "--out", outdir)
    check(out.returncode == 0, "history exits 0: %s" % out.stderr[-300:])
    rows = [l for l in out.stdout.splitlines()[1:] if l.strip()]
    check(len(rows) == 2 and a["id"] in out.stdout and "commit=aaa" in out.stdout and "frame_ms" in out.stdout,
          "the table has the two jobs, their figure and labels: %s" % out.stdout)
    with open(os.path.join(outdir, "history.csv")) as f:
        table = list(csv.DictReader(f))
    check(len(table) == 2 and float(table[0]["frame_ms"]) > 0, "history.csv has the rows")
    root = ET.parse(os.path.join(outdir, "trend.svg")).getroot()
    points = [e for e in root.iter() if e.get("class") == "point"]
    values = sorted(float(p.get("data-value")) for p in points)
    expected = sorted(j["result"]["frame_ms"]["median"] for j in (a, b))
    check(len(points) == 2 and all(abs(v - e) < 1e-3 * e for v, e in zip(values, expected)),
          "the trend chart has a point per job at its figure: %s vs %s" % (values, expected))
    check(all(float(e.get("data-low")) >= 0 for e in root.iter() if e.get("class") == "interval"),
          "no interval below zero")
    out = cl.run("history", "--filter", "technique=osl", "--figure", "worst_ssim")
    check(out.returncode == 0 and "%.6f" % o["result"]["quality"]["worst_ssim"]["value"] in out.stdout,
          "--figure worst_ssim: %s" % out.stdout)
    out = cl.run("history", "--filter", "status=cancelled")
    check(out.returncode == 0 and long_id in out.stdout, "a status filter replaces the done default")
    out = cl.run("history", "--filter", "colour=red")
    check(out.returncode == 2 and "colour" in out.stderr, "a bad filter exits 2 naming it")
    out = cl.run("history", "--out", outdir)
    check(out.returncode == 2, "--out of an earlier history is refused")
finally:
    testlib.stop_and_check(d)
testlib.finish("e2e_history")
