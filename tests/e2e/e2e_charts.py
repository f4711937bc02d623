"""Charts that cannot mislead, and shadebench sweep, end to end: a sweep over
two async distances and two workloads (2 and 40 lights), repeated twice,
run through the client, which downloads the table (JSON and CSV), charts
and report and turns the criteria into JUnit cases. The charts' SVG carries
its layout: no Pareto front joins points of two workloads, forward (the
reference) is timed and drawn beside OSL on each workload, no interval
goes below zero although the table's Student's t intervals over two runs
do, labels never overlap; the report writes the verdict; a job's report
shows its frame times over the run and its technique's figures."""

import csv
import json
import os
import xml.etree.ElementTree as ET

import testlib
from testlib import check
from clientlib import Client, junit_cases

testlib.skip_without_egl()
SWEEP = {"base": {"technique": "osl", "frames": 8, "warmup_frames": 2, "repeat": 2,
                  "osl": {"resolution": "auto"},
                  "scene": {"dynamic": True, "width": 160, "height": 120}},
         "vary": {"async_distance": [0, 5], "scene.lights": [2, 40]}}


def layout(path):
    root = ET.parse(path).getroot()
    meta = [e for e in root.iter() if e.tag.endswith("metadata") and e.get("id") == "shadebench-chart"]
    return json.loads(meta[0].text) if meta else None


def overlap(a, b):
    return a[0] < b[0] + b[2] and b[0] < a[0] + a[2] and a[1] < b[1] + b[3] and b[1] < a[1] + a[3]


d = testlib.Daemon()
cl = Client(d)
try:
    outdir, junit = cl.path("sweep"), cl.path("sweep.xml")
    out = cl.run("sweep", cl.write("sweep", SWEEP), "--wait", "--out", outdir, "--junit", junit,
                 "--label", "suite=charts")
    check(out.returncode in (0, 1), "sweep --wait ends with a verdict: %d %s" % (out.returncode, out.stderr[-400:]))
    with open(os.path.join(outdir, "sweep.json")) as f:
        sw = json.load(f)
    rows = sw["points"]
    check(sw["status"] == "done" and len(rows) == 6, "4 grid points and forward timed on each workload: %d" % len(rows))
    refs = [r for r in rows if r["technique"] == "forward"]
    check(sorted(r["values"]["scene.lights"] for r in refs) == [2, 40], "forward once per light count")
    with open(os.path.join(outdir, "table.csv")) as f:
        table = list(csv.DictReader(f))
    check(len(table) == 6 and all(float(r["frame_ms_median"]) > 0 for r in table), "table.csv: a row per point")
    for name in ("speed_accuracy", "speed_accuracy_flip", "time_vs_param", "distribution"):
        for ext in ("svg", "png"):
            check(os.path.getsize(os.path.join(outdir, "charts", name + "." + ext)) > 1000, "%s.%s" % (name, ext))
    with open(os.path.join(outdir, "report.html")) as f:
        html = f.read()
    check("<h2>Verdict</h2>" in html and "the reference) takes" in html, "the report writes the verdict")
    job = d.json("GET", "/v1/jobs/" + rows[0]["job"])[1]
    check(job["spec"]["labels"] == {"suite": "charts"}, "--label reached the point jobs through the base")

    # JUnit: each point's job and quality; PerceptualDiff failures are the
    # only failures, and the exit status says whether there were any.
    root, cases = junit_cases(junit)
    fails = [c[0] for c in cases.values() if c[0]]
    check(len([n for n in cases if n.endswith(": job")]) == 6 and
          len([n for n in cases if n.endswith(": quality")]) == 4, "a job case per point, quality per judged point")
    check(all("PerceptualDiff" in f for f in fails) and (out.returncode == 1) == bool(fails),
          "failures are PerceptualDiff's, exit 1 iff any: %s" % fails)
    check(all(not n.startswith("2026") for n in cases), "case names from content, not ids")

    sa = layout(os.path.join(outdir, "charts", "speed_accuracy.svg"))
    check(sa is not None and len(sa["points"]) == 6, "speed_accuracy.svg carries its layout")
    pts = sa["points"]
    # No front across workloads.
    check(len(sa["workloads"]) == 2, "two workloads: %s" % sa["workloads"])
    for w, front in enumerate(sa["fronts"]):
        check(front and all(pts[i]["workload"] == w for i in front),
              "the front of %s holds only its own points" % sa["workloads"][w])
    # The reference beside the others: a point per workload at SSIM 1.
    ref_pts = [p for p in pts if p["reference"]]
    check(len(ref_pts) == 2 and {p["workload"] for p in ref_pts} == {0, 1} and all(p["y"] == 1 for p in ref_pts),
          "forward drawn on each workload at SSIM 1")
    # No interval below zero, though two runs' t intervals can reach there.
    negative_rows = sum(1 for r in rows if r["frame_ms"]["ci95"][0] < 0)
    check(all(p["x_lo"] >= 0 for p in pts), "no interval crosses zero")
    check(sum(p["lo_clamped"] for p in pts) == negative_rows,
          "every interval the table has below zero is cut and marked (%d)" % negative_rows)
    boxes = [p["label_box"] for p in pts if p["label_box"]]
    check(all(not overlap(a, b) for i, a in enumerate(boxes) for b in boxes[i + 1:]), "no two labels overlap")
    check(len(boxes) + sa["labels_left_out"] == 6, "every label placed or counted as left out")
    check("llvmpipe" in sa["subtitle"] and "frame_ms" in sa["xlabel"], "frame_ms chosen on llvmpipe, and said so")
    tvp = layout(os.path.join(outdir, "charts", "time_vs_param.svg"))
    check(all(p["y_lo"] >= 0 for p in tvp["points"]) and all(l["lo"] >= 0 for l in tvp["levels"]),
          "time_vs_param: no interval below zero")
    series = {p["series"] for p in tvp["points"]}
    check(any("lights=2" in s for s in series) and any("lights=40" in s for s in series),
          "time_vs_param draws a line per workload: %s" % series)
    gpu = cl.path("gpu.svg")
    check(d.download("/v1/sweeps/%s/charts/speed_accuracy.svg?series=gpu_ms" % sw["id"], gpu) == 200 and
          "rasterization only" in layout(gpu)["subtitle"], "gpu_ms on llvmpipe is labelled for what it is")

    # A job's report: frame times over the run, the technique's figures.
    status, _, raw = d.request("GET", "/v1/jobs/%s/report.html" % rows[0]["job"])
    page = raw.decode()
    check(status == 200 and 'alt="frame times over the run"' in page and "Technique figures (osl)" in page and
          "<h2>Runs</h2>" in page, "the job report has the timeline, technique figures and runs")
    out = cl.run("sweep", cl.write("sweep2", SWEEP), "--wait", "--out", outdir)
    check(out.returncode == 2 and not out.stdout, "sweep --out refuses a folder holding another sweep")
    check(cl.run("sweep", cl.write("bad", {"base": {}, "vary": {"nope": [1]}})).returncode == 2,
          "a refused sweep exits 2")
finally:
    testlib.stop_and_check(d)
testlib.finish("e2e_charts")
