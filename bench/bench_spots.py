#!/usr/bin/env python3
"""Spots against points in the light-culling techniques (issue 21): the
`lights` preset with N lights as points and as spots of the same radius (and
optionally the sun), for each technique, in one run on one daemon,
interleaved (each round runs every technique with both light types, A, B,
A, B, so that load spreads evenly). Prints per technique the median
frame_ms and cpu_work_ms (the CPU time all the daemon's threads took per
timed frame: on llvmpipe, which does all its work on the CPU, the figure
other processes' load moves least) with the spot/point ratios, the light
evaluations per pixel (the heat map's mean at the last frame) and the lights
per non-empty cell, and the load the run ran under.

  bench/bench_spots.py [--lights 256] [--radius 6] [--angle 30] [--sun]
      [--techniques forward_plus,clustered_forward] [--frames N] [--warmup N]
      [--repeat R] [--width W --height H] [--json FILE]

On llvmpipe GL_TIME_ELAPSED covers rasterisation only, so frame_ms (and
cpu_work_ms) compare techniques there; on a GPU gpu_ms does."""

import statistics
import sys

import benchrun
from benchrun import testlib

ap = benchrun.parser()
ap.add_argument("--lights", type=int, default=256)
ap.add_argument("--radius", type=float, default=6.0)
ap.add_argument("--angle", type=float, default=30.0, help="spots' outer half-angle, degrees")
ap.add_argument("--sun", action="store_true", help="add the directional light to both")
ap.add_argument("--techniques", default="forward_plus,clustered_forward")
ap.add_argument("--frames", type=int, default=10)
ap.add_argument("--warmup", type=int, default=2)
ap.add_argument("--repeat", type=int, default=3)
ap.add_argument("--width", type=int, default=480)
ap.add_argument("--height", type=int, default=320)
ap.add_argument("--json", help="write every result here")
args = ap.parse_args()

TYPES = ("point", "spot")


def med(xs):
    return statistics.median(xs) if xs else float("nan")


bench = benchrun.Run()
bench.start()
d = testlib.Daemon()
runs = {}
try:
    techs = args.techniques.split(",")
    for rnd in range(args.repeat):
        for tech in techs:
            for kind in TYPES:
                job = {"technique": tech, "frames": args.frames, "warmup_frames": args.warmup,
                       "capture_interval": args.frames,
                       "scene": {"preset": "lights", "lights": args.lights, "light_type": kind,
                                 "light_radius": args.radius, "spot_angle_deg": args.angle,
                                 "sun": args.sun, "dynamic": True,
                                 "width": args.width, "height": args.height}}
                done = d.wait(d.submit(job), timeout=3600)
                if done.get("status") != "done":
                    sys.exit("%s %s failed: %s" % (tech, kind, done.get("error")))
                runs.setdefault((tech, kind), []).append(done["result"])
                print("  round %d %s %s: frame_ms median %.2f" % (rnd + 1, tech, kind,
                      done["result"]["frame_ms"]["median"]), flush=True)
finally:
    d.stop()
    d.cleanup()

print("\n%d lights of radius %g on the lights preset (moving), %dx%d, %d frames after %d warm-up, "
      "%d rounds%s; spots: %g-degree outer half-angle, pointing down\n"
      % (args.lights, args.radius, args.width, args.height, args.frames, args.warmup, args.repeat,
         ", with the sun" if args.sun else "", args.angle))
print("| technique | lights | frame_ms | cpu_work_ms | evaluations / pixel | lights / cell | spot / point frame_ms | spot / point cpu_work_ms |")
print("|---|---|---|---|---|---|---|---|")
for tech in techs:
    fig = {}
    for kind in TYPES:
        rs = runs[(tech, kind)]
        heat = [r.get("heatmap", {}).get("captures", [{}])[-1].get("mean", float("nan")) for r in rs]
        cells = [r.get(tech, {}).get("lights_per_cell", {}).get("mean", float("nan")) for r in rs]
        fig[kind] = (med([r["frame_ms"]["median"] for r in rs]), med([benchrun.cpu_work_ms(r) for r in rs]),
                     med(heat), med(cells))
    for kind in TYPES:
        f = fig[kind]
        ratio = kind == "spot"
        print("| %s | %s | %.2f | %.2f | %.2f | %.2f | %s | %s |"
              % (tech, kind, f[0], f[1], f[2], f[3],
                 "%.3f" % (f[0] / fig["point"][0]) if ratio else "",
                 "%.3f" % (f[1] / fig["point"][1]) if ratio else ""))
bench.end([r for rs in runs.values() for r in rs])
benchrun.write_json(args.json, {"%s/%s" % k: v for k, v in runs.items()})
