#!/usr/bin/env python3
"""OSL's options against forward on the thesis grid (issue 25): forward,
OSL as the thesis had it (whole tiles) and OSL with visibility "seen", at
async distance 1, 5, 20 and 60, with moving and with still lights, auto
tiles, in one run on one daemon, interleaved (each round runs every
configuration, so that load spreads evenly over them). Prints per
configuration: the median frame_ms and its ratio to forward's in the same
round (the median of the per-round ratios), cpu_work_ms (the CPU time all
the daemon's threads took per timed frame: what load moves least on
llvmpipe), the lighting and raster passes' medians (which pass is the
cost), texels shaded per frame and per pixel on screen, the frame times'
spread (p99 / median), and stale blocks (blocks read with other shading
than scheduled, visibility "seen" only).

  bench/bench_osl.py [--distances 1,5,20,60] [--frames N] [--warmup N] [--repeat R]
      [--width W --height H] [--json FILE]

On llvmpipe GL_TIME_ELAPSED covers rasterisation only, so frame_ms (and
cpu_work_ms) compare techniques there; on a GPU gpu_ms does."""

import argparse
import json
import os
import statistics
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "e2e"))
import testlib  # noqa: E402
import benchrun  # noqa: E402

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("--distances", default="1,5,20,60")
ap.add_argument("--frames", type=int, default=20)
ap.add_argument("--warmup", type=int, default=3)
ap.add_argument("--repeat", type=int, default=3)
ap.add_argument("--width", type=int, default=1080)
ap.add_argument("--height", type=int, default=720)
ap.add_argument("--json", help="write every result here")
args = ap.parse_args()


cpu_work_ms = benchrun.cpu_work_ms


def med(xs):
    return statistics.median(xs) if xs else float("nan")


configs = [("forward", None, None)]
for dist in [float(x) for x in args.distances.split(",")]:
    for vis in ("all", "seen"):
        configs.append(("osl", dist, vis))


def name(c):
    return "forward" if c[0] == "forward" else "osl %s d=%g" % (c[2], c[1])


bench = benchrun.Run()
bench.start()
d = testlib.Daemon()
results = []
rows = {}
try:
    dev = d.json("GET", "/v1/info")[1]["device"]
    print("device: %s | %s" % (dev["gl_renderer"], dev["gl_version"]))
    print("scene: grid %dx%d, %d timed frames after %d warm-up, %d interleaved rounds, auto tiles"
          % (args.width, args.height, args.frames, args.warmup, args.repeat), flush=True)
    for rep in range(args.repeat):
        for moving in (True, False):
            fwd_ms = None
            for c in configs:
                job = {"technique": c[0], "frames": args.frames, "warmup_frames": args.warmup,
                       "scene": {"preset": "grid", "dynamic": moving, "width": args.width,
                                 "height": args.height}}
                if c[0] == "osl":
                    job["async_distance"] = c[1]
                    job["osl"] = {"resolution": "auto", "visibility": c[2]}
                done = d.run(job)
                if done.get("status") != "done":
                    sys.exit("bench_osl: %s failed: %s" % (name(c), done.get("error")))
                r = done["result"]
                results.append(r)
                ms = r["frame_ms"]["median"]
                if c[0] == "forward":
                    fwd_ms = ms
                row = rows.setdefault((moving, c), {"ms": [], "ratio": [], "cpu": [], "light": [],
                                                     "raster": [], "texels": [], "spread": [],
                                                     "stale": []})
                row["ms"].append(ms)
                row["ratio"].append(ms / fwd_ms)
                row["cpu"].append(cpu_work_ms(r))
                sec = r.get("gpu_sections_ms", {})
                row["light"].append(sec.get("lighting", {}).get("median", 0.0))
                row["raster"].append(sec.get("raster", sec.get("shading", {})).get("median", 0.0))
                row["spread"].append(r["frame_ms"]["p99"] / ms)
                o = r.get("osl", {})
                row["texels"].append(o.get("texels_shaded_per_frame", {}).get("mean", 0.0))
                row["stale"].append(o.get("visibility", {}).get("stale_blocks", 0))
                print("  round %d %s %-18s frame_ms %8.2f (x%.2f of forward)"
                      % (rep + 1, "moving" if moving else "still ", name(c), ms, ms / fwd_ms),
                      flush=True)
finally:
    testlib.stop_and_check(d)

pixels = args.width * args.height
for moving in (True, False):
    print("\n%s lights: median over %d rounds" % ("moving" if moving else "still", args.repeat))
    print("%-18s %9s %8s %9s %9s %9s %12s %9s %8s %6s" % (
        "configuration", "frame_ms", "/fwd", "cpu_work", "lighting", "raster", "texels/frame",
        "texels/px", "p99/med", "stale"))
    for c in configs:
        row = rows[(moving, c)]
        t = med(row["texels"])
        print("%-18s %9.2f %8.2f %9.2f %9.2f %9.2f %12.0f %9.3f %8.2f %6d" % (
            name(c), med(row["ms"]), med(row["ratio"]), med(row["cpu"]), med(row["light"]),
            med(row["raster"]), t, t / pixels, med(row["spread"]), max(row["stale"])))
bench.end(results)
if args.json:
    with open(args.json, "w") as f:
        json.dump(results, f)
