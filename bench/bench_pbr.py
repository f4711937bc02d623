#!/usr/bin/env python3
"""Seed 002's renderer measured in one run on one daemon (issue 12):

1. forward against deferred and clustered deferred, physically based, on
   the `teapots` preset at 8, 80 and 800 lights;
2. shadow cost per light: the shadow pass with every light's faces in one
   atlas against one cube map per light (the same face size), at a few
   light counts, and the atlas sized by importance ("auto");
3. image-based lighting's setup time (capture and filtering of the
   environment and three probes) against the probe resolution.

  bench/bench_pbr.py [--frames N] [--warmup N] [--repeat R] [--width W --height H]
                     [--lights 8,80,800] [--shadow-lights 4,8,16]
                     [--resolutions 16,32,64,128,256] [--only techniques,shadows,ibl]
                     [--json FILE] [--from-json FILE]

Every configuration runs once per repeat, all of them in each repeat
(A, B, C, A, B, C, ...), on one daemon; the tables give the medians over the
repeats of each job's median, ratios of those medians, and the range of the
ratios paired within each repeat. The run's commit, command, date and load
(/proc/loadavg and the jobs' result.interference) are printed with them.

frame_ms (present to present) is the figure to read on llvmpipe; gpu_ms and
the per-pass gpu_sections_ms cover rasterization only there (vertex work and
binning run at draw time on the CPU), and both are printed."""

import json
import statistics
import sys
import time

import benchrun
from benchrun import testlib

ap = benchrun.parser()
ap.add_argument("--frames", type=int, default=3)
ap.add_argument("--warmup", type=int, default=1)
ap.add_argument("--repeat", type=int, default=3)
ap.add_argument("--only", default="techniques,shadows,ibl", help="parts to run")
ap.add_argument("--width", type=int, default=320)
ap.add_argument("--height", type=int, default=240)
ap.add_argument("--lights", default="8,80,800")
ap.add_argument("--techniques", default="forward,deferred,clustered_deferred")
ap.add_argument("--shadow-lights", default="4,8,16")
ap.add_argument("--shadow-tile", type=int, default=64)
ap.add_argument("--resolutions", default="16,32,64,128,256")
ap.add_argument("--teapot-segments", type=int, default=8)
ap.add_argument("--json", help="write every result here")
ap.add_argument("--from-json", help="report again on the results a --json run wrote, without running "
                "(give the same --lights, --shadow-lights, --resolutions and --only)")
args = ap.parse_args()

scene = {"preset": "teapots", "width": args.width, "height": args.height,
         "teapot_segments": args.teapot_segments}
timing = {"frames": args.frames, "warmup_frames": args.warmup, "capture_interval": 0}
everything = []


def run(d, job, label, rep):
    t0 = time.time()
    done = d.wait(d.submit(job), timeout=7200)
    if done.get("status") != "done":
        sys.exit("%s failed: %s" % (label, done.get("error")))
    r = done["result"]
    everything.append({"label": label, "repeat": rep, "job": job, "result": r})
    print("  [%d/%d] %-46s frame %9.2f ms  gpu %8.2f ms  (%.0f s)"
          % (rep + 1, args.repeat, label, r["frame_ms"]["median"], r["gpu_ms"]["median"],
             time.time() - t0), flush=True)
    return r


def med(rs, f=lambda r: r["frame_ms"]["median"]):
    """Median over the repeats of f(result)."""
    return statistics.median(f(r) for r in rs)


def paired(a, b, f=lambda r: r["frame_ms"]["median"]):
    """The ratios f(b) / f(a) of each repeat, a and b run side by side."""
    return [f(y) / f(x) for x, y in zip(a, b)]


work_ms = benchrun.cpu_work_ms


def ratio_cell(a, b, f=lambda r: r["frame_ms"]["median"]):
    rs = paired(a, b, f)
    r = med(b, f) / med(a, f)
    return "%.2f (%.2f-%.2f)" % (r, min(rs), max(rs)) if len(rs) > 1 else "%.2f" % r


def section(r, name):
    return r.get("gpu_sections_ms", {}).get(name, {}).get("median", 0.0)


parts = set(args.only.split(","))
techniques = args.techniques.split(",") if "techniques" in parts else []
counts = [int(c) for c in args.lights.split(",")] if techniques else []
shadow_counts = [int(c) for c in args.shadow_lights.split(",")] if "shadows" in parts else []
layouts = [("none", False),
           ("atlas, tile %d" % args.shadow_tile, {"tile": args.shadow_tile}),
           ("cubes, tile %d" % args.shadow_tile, {"layout": "cubes", "tile": args.shadow_tile}),
           ("atlas, auto", {})]
resolutions = [int(c) for c in args.resolutions.split(",")] if "ibl" in parts else []
tech = {(t, n): [] for t in techniques for n in counts}
shadow = {(name, n): [] for name, _ in layouts for n in shadow_counts}
ibl = {res: [] for res in resolutions}

if args.from_json:
    with open(args.from_json) as f:
        everything = json.load(f)
    labels = {}
    for n in counts:
        for t in techniques:
            labels["%s, %d lights" % (t, n)] = tech[(t, n)]
    for n in shadow_counts:
        for name, _ in layouts:
            labels["shadows %s, %d lights" % (name, n)] = shadow[(name, n)]
    for res in resolutions:
        labels["ibl, 3 probes at %d" % res] = ibl[res]
    for e in everything:
        if e["label"] in labels:
            labels[e["label"]].append(e["result"])
    args.repeat = max(len(v) for v in labels.values())
    print("report on %s (%d repeats)" % (args.from_json, args.repeat))
else:
    bench = benchrun.Run()
    d = testlib.Daemon()
    try:
        info = d.json("GET", "/v1/info")[1]["device"]
        print("device: %s | %s | %s" % (info["gl_renderer"], info["gl_version"], info["egl_device"]))
        print("teapots %dx%d, %d segments a patch edge, %d timed frames after %d warm-up, %d repeats"
              % (args.width, args.height, args.teapot_segments, args.frames, args.warmup, args.repeat))
        bench.start()
        print()
        for rep in range(args.repeat):
            # 1. Techniques against light count, physically based.
            for n in counts:
                for t in techniques:
                    tech[(t, n)].append(run(d, dict(timing, technique=t, look={"lighting": "pbr"},
                                                    scene=dict(scene, lights=n)),
                                            "%s, %d lights" % (t, n), rep))
            # 2. Shadow cost per light: atlas against one cube map per light.
            for n in shadow_counts:
                for name, opts in layouts:
                    look = {"lighting": "pbr", "shadows": False}
                    if isinstance(opts, dict):
                        look["shadows"] = dict(opts, atlas=4096)
                    shadow[(name, n)].append(run(d, dict(timing, technique="forward", look=look,
                                                         scene=dict(scene, lights=n)),
                                                 "shadows %s, %d lights" % (name, n), rep))
            # 3. Image-based lighting's setup against probe resolution.
            for res in resolutions:
                ibl[res].append(run(d, dict(timing, frames=1, warmup_frames=0, technique="forward",
                                            look={"lighting": "pbr", "ibl": {"probes": 3, "resolution": res}},
                                            scene=dict(scene, lights=8)),
                                    "ibl, 3 probes at %d" % res, rep))
    finally:
        d.stop()
        d.cleanup()
    bench.end([e["result"] for e in everything])

if counts:
    print("\n1. Physically based shading on teapots (frame_ms, median over %d repeats of the job "
          "medians; gpu_ms in brackets; ratios of the medians, with the range of the ratios paired "
          "in each repeat)\n" % args.repeat)
    print("| lights | " + " | ".join(techniques) + " | " +
          " | ".join("%s / %s" % (t, techniques[0]) for t in techniques[1:]) + " |")
    print("|---|" + "---|" * (2 * len(techniques) - 1))
    for n in counts:
        cells = ["%.1f [%.1f]" % (med(tech[(t, n)]), med(tech[(t, n)], lambda r: r["gpu_ms"]["median"]))
                 for t in techniques]
        ratios = [ratio_cell(tech[(techniques[0], n)], tech[(t, n)]) for t in techniques[1:]]
        print("| %d | %s | %s |" % (n, " | ".join(cells), " | ".join(ratios)))
    print("\nThe same on cpu_work_ms (the CPU time all the daemon's threads took per timed frame, "
          "from result.interference; medians over repeats)\n")
    print("| lights | " + " | ".join(techniques) + " | " +
          " | ".join("%s / %s" % (t, techniques[0]) for t in techniques[1:]) + " |")
    print("|---|" + "---|" * (2 * len(techniques) - 1))
    for n in counts:
        cells = ["%.1f" % med(tech[(t, n)], work_ms) for t in techniques]
        ratios = [ratio_cell(tech[(techniques[0], n)], tech[(t, n)], work_ms) for t in techniques[1:]]
        print("| %d | %s | %s |" % (n, " | ".join(cells), " | ".join(ratios)))

if shadow_counts:
    print("\n2. Shadow cost per light (forward, PBR): frame_ms and cpu_work_ms (medians over repeats), "
          "the shadows pass's gpu_ms, (frame - no shadows) / lights mapped on each, and each layout "
          "against the atlas with tile %d (ratio of the medians, range paired in each repeat)\n"
          % args.shadow_tile)
    print("| lights | layout | frame_ms | cpu_work_ms | shadows pass gpu_ms | lights mapped | faces "
          "| ms per light (frame) | ms per light (cpu_work) | atlas texels used | frame / atlas "
          "| cpu_work / atlas |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for n in shadow_counts:
        base, wbase = med(shadow[("none", n)]), med(shadow[("none", n)], work_ms)
        atlas = shadow[(layouts[1][0], n)]
        for name, _ in layouts:
            rs = shadow[(name, n)]
            sh = rs[0].get("shadows", {})
            mapped = sh.get("lights_mapped", {}).get("mean", 0)
            per = "%.2f" % ((med(rs) - base) / mapped) if mapped else "-"
            wper = "%.2f" % ((med(rs, work_ms) - wbase) / mapped) if mapped else "-"
            print("| %d | %s | %.1f | %.1f | %.1f | %.1f | %.0f | %s | %s | %s | %s | %s |"
                  % (n, name, med(rs), med(rs, work_ms), med(rs, lambda r: section(r, "shadows")), mapped,
                     sh.get("faces_per_frame", 0), per, wper,
                     "%.0f" % sh.get("atlas_use", {}).get("texels_mean", 0) if sh else "-",
                     ratio_cell(atlas, rs) if name != "none" else "-",
                     ratio_cell(atlas, rs, work_ms) if name != "none" else "-"))

if resolutions:
    print("\n3. Image-based lighting setup (3 probes + the environment), wall ms, medians over "
          "repeats\n")
    print("| resolution | levels | capture | filter | BRDF table | total | maps (bytes) |")
    print("|---|---|---|---|---|---|---|")
    for res in resolutions:
        rs = ibl[res]
        i = rs[0]["ibl"]

        def setup(k):
            return med(rs, lambda r: r["ibl"]["setup_ms"][k])
        print("| %d | %d | %.0f | %.0f | %.0f | %.0f | %.0f |"
              % (res, i["prefiltered_levels"], setup("capture"), setup("filter"), setup("brdf_table"),
                 setup("total"), i["bytes"]))

if args.json and not args.from_json:
    with open(args.json, "w") as f:
        json.dump(everything, f, indent=1)
