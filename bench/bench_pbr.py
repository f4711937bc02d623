#!/usr/bin/env python3
"""Seed 002's renderer measured in one run on one daemon (issue 12):

1. forward against deferred and clustered deferred, physically based, on
   the `teapots` preset at 8, 80 and 800 lights;
2. shadow cost per light: the shadow pass with every light's faces in one
   atlas against one cube map per light (the same face size), at a few
   light counts, and the atlas sized by importance ("auto");
3. image-based lighting's setup time (capture and filtering of the
   environment and three probes) against the probe resolution.

  bench/bench_pbr.py [--frames N] [--warmup N] [--width W --height H]
                     [--lights 8,80,800] [--shadow-lights 4,8,16]
                     [--resolutions 16,32,64,128,256] [--json FILE]

frame_ms (present to present) is the figure to read on llvmpipe; gpu_ms and
the per-pass gpu_sections_ms cover rasterization only there (vertex work and
binning run at draw time on the CPU), and both are printed."""

import argparse
import json
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "e2e"))
import testlib  # noqa: E402

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("--frames", type=int, default=3)
ap.add_argument("--warmup", type=int, default=1)
ap.add_argument("--width", type=int, default=320)
ap.add_argument("--height", type=int, default=240)
ap.add_argument("--lights", default="8,80,800")
ap.add_argument("--techniques", default="forward,deferred,clustered_deferred")
ap.add_argument("--shadow-lights", default="4,8,16")
ap.add_argument("--shadow-tile", type=int, default=64)
ap.add_argument("--resolutions", default="16,32,64,128,256")
ap.add_argument("--teapot-segments", type=int, default=8)
ap.add_argument("--json", help="write every result here")
args = ap.parse_args()

scene = {"preset": "teapots", "width": args.width, "height": args.height,
         "teapot_segments": args.teapot_segments}
timing = {"frames": args.frames, "warmup_frames": args.warmup, "capture_interval": 0}
everything = []


def run(d, job, label):
    t0 = time.time()
    done = d.wait(d.submit(job), timeout=7200)
    if done.get("status") != "done":
        sys.exit("%s failed: %s" % (label, done.get("error")))
    r = done["result"]
    everything.append({"label": label, "job": job, "result": r})
    print("  %-46s frame %9.2f ms  gpu %8.2f ms  (%.0f s)"
          % (label, r["frame_ms"]["median"], r["gpu_ms"]["median"], time.time() - t0), flush=True)
    return r


def section(r, name):
    return r.get("gpu_sections_ms", {}).get(name, {}).get("median", 0.0)


d = testlib.Daemon()
try:
    info = d.json("GET", "/v1/info")[1]["device"]
    print("device: %s | %s | %s" % (info["gl_renderer"], info["gl_version"], info["egl_device"]))
    print("teapots %dx%d, %d segments a patch edge, %d timed frames after %d warm-up\n"
          % (args.width, args.height, args.teapot_segments, args.frames, args.warmup))

    # 1. Techniques against light count, physically based.
    techniques = args.techniques.split(",")
    counts = [int(c) for c in args.lights.split(",")]
    tech = {}
    for n in counts:
        for t in techniques:
            tech[(t, n)] = run(d, dict(timing, technique=t, look={"lighting": "pbr"},
                                       scene=dict(scene, lights=n)),
                               "%s, %d lights" % (t, n))

    # 2. Shadow cost per light: atlas against one cube map per light.
    shadow_counts = [int(c) for c in args.shadow_lights.split(",")]
    layouts = [("none", False),
               ("atlas, tile %d" % args.shadow_tile, {"tile": args.shadow_tile}),
               ("cubes, tile %d" % args.shadow_tile, {"layout": "cubes", "tile": args.shadow_tile}),
               ("atlas, auto", {})]
    shadow = {}
    for n in shadow_counts:
        for name, opts in layouts:
            look = {"lighting": "pbr", "shadows": opts if opts is not False else False}
            if isinstance(opts, dict):
                look["shadows"] = dict(opts, atlas=4096)
            shadow[(name, n)] = run(d, dict(timing, technique="forward", look=look,
                                            scene=dict(scene, lights=n)),
                                    "shadows %s, %d lights" % (name, n))

    # 3. Image-based lighting's setup against probe resolution.
    resolutions = [int(c) for c in args.resolutions.split(",")]
    ibl = {}
    for res in resolutions:
        ibl[res] = run(d, dict(timing, frames=1, warmup_frames=0, technique="forward",
                               look={"lighting": "pbr", "ibl": {"probes": 3, "resolution": res}},
                               scene=dict(scene, lights=8)),
                       "ibl, 3 probes at %d" % res)
finally:
    d.stop()
    d.cleanup()

print("\n1. Physically based shading on teapots (frame_ms median; gpu_ms in brackets)\n")
print("| lights | " + " | ".join(techniques) + " | " +
      " | ".join("%s / forward" % t for t in techniques[1:]) + " |")
print("|---|" + "---|" * (2 * len(techniques) - 1))
for n in counts:
    f = tech[("forward", n)]["frame_ms"]["median"] if "forward" in techniques else None
    cells = ["%.1f [%.1f]" % (tech[(t, n)]["frame_ms"]["median"], tech[(t, n)]["gpu_ms"]["median"])
             for t in techniques]
    ratios = ["%.2f" % (tech[(t, n)]["frame_ms"]["median"] / f) if f else "-" for t in techniques[1:]]
    print("| %d | %s | %s |" % (n, " | ".join(cells), " | ".join(ratios)))

print("\n2. Shadow cost per light (forward, PBR): frame_ms median, the shadows pass's gpu_ms, "
      "and (frame - no shadows) / lights mapped\n")
print("| lights | layout | frame_ms | shadows pass gpu_ms | lights mapped | faces | ms per light | atlas texels used |")
print("|---|---|---|---|---|---|---|---|")
for n in shadow_counts:
    base = shadow[("none", n)]["frame_ms"]["median"]
    for name, _ in layouts:
        r = shadow[(name, n)]
        sh = r.get("shadows", {})
        mapped = sh.get("lights_mapped", {}).get("mean", 0)
        per = (r["frame_ms"]["median"] - base) / mapped if mapped else 0.0
        print("| %d | %s | %.1f | %.1f | %.1f | %.0f | %s | %s |"
              % (n, name, r["frame_ms"]["median"], section(r, "shadows"), mapped,
                 sh.get("faces_per_frame", 0), "%.2f" % per if mapped else "-",
                 "%.0f" % sh.get("atlas_use", {}).get("texels_mean", 0) if sh else "-"))

print("\n3. Image-based lighting setup (3 probes + the environment), wall ms\n")
print("| resolution | levels | capture | filter | BRDF table | total | maps (bytes) |")
print("|---|---|---|---|---|---|---|")
for res in resolutions:
    i = ibl[res]["ibl"]
    s = i["setup_ms"]
    print("| %d | %d | %.0f | %.0f | %.0f | %.0f | %.0f |"
          % (res, i["prefiltered_levels"], s["capture"], s["filter"], s["brdf_table"], s["total"],
             i["bytes"]))

if args.json:
    with open(args.json, "w") as f:
        json.dump(everything, f, indent=1)
