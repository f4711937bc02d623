#!/usr/bin/env python3
"""shadebench benchmark: every configuration side by side in one run, on one
daemon, interleaved across repeats so that machine noise spreads evenly.
Reports medians of per-job medians and ratios to forward and to unlit, plus
the daemon's own overhead (HTTP job against --once).

  bench/bench.py [--frames N] [--repeat R] [--width W --height H] [--json FILE] [--from-json FILE]

Figures are measured on whatever GL device the daemon picks (shown first).
On llvmpipe, GL_TIME_ELAPSED covers rasterization only (vertex work and
compute shaders run outside the query on the CPU), so frame_ms (the
present-to-present interval) is the figure to compare there; on a GPU both
are meaningful. cpu_work_ms is the CPU time all the daemon's threads took
per timed frame (result.interference): on llvmpipe, where all the work is on
the CPU, the figure other processes' load does not inflate. The run's commit, command, date and load (/proc/loadavg at
the start and the end, and the jobs' result.interference) are printed."""

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

import benchrun
from benchrun import testlib

ap = benchrun.parser()
ap.add_argument("--frames", type=int, default=60)
ap.add_argument("--warmup", type=int, default=10)
ap.add_argument("--repeat", type=int, default=3)
ap.add_argument("--width", type=int, default=1080)
ap.add_argument("--height", type=int, default=720)
ap.add_argument("--only", default="", help="comma-separated config names to run")
ap.add_argument("--json", help="write every measurement here")
ap.add_argument("--from-json", help="report again on the results a --json run wrote, without running "
                "(give the same --only)")
args = ap.parse_args()

CONFIGS = []
for dyn in (False, True):
    tag = "dynamic" if dyn else "static"
    CONFIGS.append(("unlit/" + tag, {"technique": "unlit"}, dyn))
    CONFIGS.append(("forward/" + tag, {"technique": "forward"}, dyn))
    for res in (256, "auto"):
        for d in (0, 20):
            CONFIGS.append(("osl-%s/%s/d%d" % (res, tag, d),
                            {"technique": "osl", "async_distance": d, "osl": {"resolution": res}}, dyn))
if args.only:
    wanted = set(args.only.split(","))
    CONFIGS = [c for c in CONFIGS if c[0] in wanted or c[0].split("/")[0] in wanted]


def job_for(extra, dyn):
    job = {"frames": args.frames, "warmup_frames": args.warmup, "capture_interval": 0,
           "scene": {"preset": "grid", "dynamic": dyn, "width": args.width, "height": args.height}}
    job.update(extra)
    return job


results = {name: [] for name, _, _ in CONFIGS}
overhead = {"http": [], "once": []}
if args.from_json:
    with open(args.from_json) as f:
        saved = json.load(f)
    info = saved["device"]
    results = {name: saved["results"][name] for name, _, _ in CONFIGS}
    overhead = saved["overhead"]
    print("report on %s" % args.from_json)
else:
    bench = benchrun.Run()
    d = testlib.Daemon()
    try:
        info = d.json("GET", "/v1/info")[1]["device"]
        print("device: %s | %s | %s" % (info["gl_renderer"], info["gl_version"], info["egl_device"]))
        print("scene: grid %dx%d, %d timed frames after %d warm-up, %d repeats\n"
              % (args.width, args.height, args.frames, args.warmup, args.repeat))
        bench.start()
        print()
        for rep in range(args.repeat):
            for name, extra, dyn in CONFIGS:
                t0 = time.time()
                job = d.run(job_for(extra, dyn))
                if job["status"] != "done":
                    sys.exit("%s failed: %s" % (name, job.get("error")))
                r = job["result"]
                results[name].append(r)
                print("  [%d/%d] %-24s frame %8.2f ms  gpu %8.2f ms  (%.0f s)"
                      % (rep + 1, args.repeat, name, r["frame_ms"]["median"], r["gpu_ms"]["median"],
                         time.time() - t0), flush=True)
            # Daemon overhead: the same forward job over HTTP and in-process.
            job = job_for({"technique": "forward"}, True)
            overhead["http"].append(d.run(job)["result"])
            with tempfile.TemporaryDirectory() as tmp:
                path = os.path.join(tmp, "job.json")
                with open(path, "w") as f:
                    json.dump(job, f)
                # The daemon holds the GL device meanwhile but is idle.
                subprocess.run([testlib.SHADEBENCHD, "--once", path, "--out", tmp],
                               check=True, capture_output=True)
                with open(os.path.join(tmp, "result.json")) as f:
                    overhead["once"].append(json.load(f))
    finally:
        d.stop()
        d.cleanup()
    bench.end([r for rs in results.values() for r in rs] + overhead["http"])


work_ms = benchrun.cpu_work_ms


def med(runs, series):
    if series == "work":
        return statistics.median(work_ms(r) for r in runs)
    return statistics.median(r[series]["median"] for r in runs)


def cell(name, series, base):
    if base not in results or not results[base]:
        return "-"
    return "%.2f" % (med(results[name], series) / med(results[base], series))


print("\n(medians over the repeats of each job's median; ratios of those medians)")
print("\n| configuration | frame_ms median | gpu_ms median | cpu_work_ms | frame / forward | frame / unlit "
      "| cpu_work / forward | cpu_work / unlit | gpu / forward | gpu / unlit | objects reshaded/frame "
      "| texels shaded/frame |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|")
for name, _, dyn in CONFIGS:
    tag = "dynamic" if dyn else "static"
    fwd, unl = "forward/" + tag, "unlit/" + tag
    o = results[name][0].get("osl")
    objs = "%.1f" % statistics.median(r["osl"]["objects_reshaded_per_frame"]["mean"] for r in results[name]) if o else "-"
    tex = "%.0f" % statistics.median(r["osl"]["texels_shaded_per_frame"]["mean"] for r in results[name]) if o else "-"
    print("| %s | %.2f | %.3f | %.2f | %s | %s | %s | %s | %s | %s | %s | %s |"
          % (name, med(results[name], "frame_ms"), med(results[name], "gpu_ms"), med(results[name], "work"),
             cell(name, "frame_ms", fwd), cell(name, "frame_ms", unl),
             cell(name, "work", fwd), cell(name, "work", unl),
             cell(name, "gpu_ms", fwd), cell(name, "gpu_ms", unl), objs, tex))

# Each HTTP job ran right before its --once twin: the median of the paired
# ratios is robust to the machine drifting over a long run.
pairs = list(zip(overhead["http"], overhead["once"]))
wall_ratio = statistics.median(h["wall_s"] / o["wall_s"] for h, o in pairs)
frame_ratio = statistics.median(h["frame_ms"]["median"] / o["frame_ms"]["median"] for h, o in pairs)
print("\ndaemon overhead, forward/dynamic, %d pairs: HTTP job / --once = %.3f (wall_s), %.3f "
      "(frame_ms median); walls %s s against %s s"
      % (len(pairs), wall_ratio, frame_ratio,
         "/".join("%.2f" % h["wall_s"] for h, _ in pairs), "/".join("%.2f" % o["wall_s"] for _, o in pairs)))
if args.json and not args.from_json:
    with open(args.json, "w") as f:
        json.dump({"device": info, "args": vars(args), "results": results, "overhead": overhead}, f)
