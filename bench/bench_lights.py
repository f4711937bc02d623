#!/usr/bin/env python3
"""The many-lights floor: the `lights` preset (objects on a ground plane,
lights through the volume above it) at several light counts, with `forward`
and `unlit`, in one run on one daemon, interleaved across repeats. Prints
the frame_ms medians, forward's ratio to unlit at each count, and how
forward's time grows with the count: the figures the light-culling
techniques (issue 10) are measured against.

  bench/bench_lights.py [--counts 16,256,4096] [--frames N] [--warmup N]
                        [--repeat R] [--width W --height H] [--json FILE]
                        [--from-json FILE]

On llvmpipe, forward at 4,096 lights and 1080x720 takes tens of seconds a
frame: keep --frames small there. frame_ms (present to present) is the
figure to read on llvmpipe (gpu_ms covers rasterization only); both are
printed, with cpu_work_ms: the CPU time all the daemon's threads took per
timed frame (result.interference), which on llvmpipe (all the work on the
CPU) other processes' load does not inflate. Interleaved: each repeat runs
every count and technique in turn (A, B, A, B over --repeat rounds). The
run's commit, command, date and load are printed."""

import json
import statistics
import sys
import time

import benchrun
from benchrun import testlib

ap = benchrun.parser()
ap.add_argument("--counts", default="16,256,4096", help="comma-separated light counts")
ap.add_argument("--techniques", default="forward,unlit")
ap.add_argument("--frames", type=int, default=3)
ap.add_argument("--warmup", type=int, default=1)
ap.add_argument("--repeat", type=int, default=2)
ap.add_argument("--width", type=int, default=1080)
ap.add_argument("--height", type=int, default=720)
ap.add_argument("--json", help="write every result here")
ap.add_argument("--from-json", help="report again on the results a --json run wrote, without running")
args = ap.parse_args()

counts = [int(c) for c in args.counts.split(",")]
techniques = args.techniques.split(",")
results = {(t, n): [] for t in techniques for n in counts}

if args.from_json:
    with open(args.from_json) as f:
        saved = json.load(f)
    info = saved["device"]
    for key, rs in saved["results"].items():
        t, n = key.rsplit("/", 1)
        if (t, int(n)) in results:
            results[(t, int(n))] = rs
    print("report on %s" % args.from_json)
else:
    bench = benchrun.Run()
    d = testlib.Daemon()
    try:
        info = d.json("GET", "/v1/info")[1]["device"]
        print("device: %s | %s | %s" % (info["gl_renderer"], info["gl_version"], info["egl_device"]))
        print("scene: lights preset %dx%d, %d timed frames after %d warm-up, %d repeat(s)"
              % (args.width, args.height, args.frames, args.warmup, args.repeat))
        bench.start()
        print()
        for rep in range(args.repeat):
            for n in counts:
                for t in techniques:
                    job = {"technique": t, "frames": args.frames, "warmup_frames": args.warmup,
                           "capture_interval": 0,
                           "scene": {"preset": "lights", "lights": n, "width": args.width,
                                     "height": args.height}}
                    t0 = time.time()
                    done = d.wait(d.submit(job), timeout=7200)
                    if done.get("status") != "done":
                        sys.exit("%s at %d lights failed: %s" % (t, n, done.get("error")))
                    r = done["result"]
                    results[(t, n)].append(r)
                    print("  [%d/%d] %-8s %6d lights  frame %10.2f ms  gpu %9.2f ms  (%.0f s)"
                          % (rep + 1, args.repeat, t, n, r["frame_ms"]["median"], r["gpu_ms"]["median"],
                             time.time() - t0), flush=True)
    finally:
        d.stop()
        d.cleanup()
    bench.end([r for rs in results.values() for r in rs])


work_ms = benchrun.cpu_work_ms


def med(t, n, series="frame_ms"):
    if series == "work":
        return statistics.median(work_ms(r) for r in results[(t, n)])
    return statistics.median(r[series]["median"] for r in results[(t, n)])


print("\n(medians over the repeats of each job's median; ratios of those medians)")
print("\n| lights | technique | frame_ms median | gpu_ms median | cpu_work_ms | frame / unlit "
      "| cpu_work / unlit | triangles/frame |")
print("|---|---|---|---|---|---|---|---|")
for n in counts:
    for t in techniques:
        ratio = "%.2f" % (med(t, n) / med("unlit", n)) if "unlit" in techniques else "-"
        wratio = "%.2f" % (med(t, n, "work") / med("unlit", n, "work")) if "unlit" in techniques else "-"
        print("| %d | %s | %.2f | %.2f | %.2f | %s | %s | %d |"
              % (n, t, med(t, n), med(t, n, "gpu_ms"), med(t, n, "work"), ratio, wratio,
                 results[(t, n)][0]["triangles_per_frame"]))
if "forward" in techniques and len(counts) > 1:
    first, last = counts[0], counts[-1]
    for series, label in (("frame_ms", "frame time"), ("work", "cpu_work_ms")):
        print("\nforward %s against %d lights: %s"
              % (label, first, ", ".join("%d lights x%.1f" % (n, med("forward", n, series) /
                                                             med("forward", first, series))
                                         for n in counts[1:])))
        # Cost per light: the slope between the smallest and largest counts.
        slope = (med("forward", last, series) - med("forward", first, series)) / (last - first)
        print("forward %s: %.3f ms per added light (%d to %d)" % (label, slope, first, last))
if args.json and not args.from_json:
    with open(args.json, "w") as f:
        json.dump({"device": info, "args": vars(args),
                   "results": {"%s/%d" % k: v for k, v in results.items()}}, f)
