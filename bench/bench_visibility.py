#!/usr/bin/env python3
"""The visibility buffer against the g-buffer (issue 37): visibility_buffer
(every light, and clustered) against deferred and clustered_deferred, with
forward as the anchor, across

- triangle density: the lights preset with its spheres tessellated at
  --segments (scene.sphere_segments), and a dense generated asset
  (gltf_gen's grid panels of --panel-quads quads a side, one textured
  material each), so that triangles shrink to pixels and below;
- light count: --counts on the lights preset at the default tessellation.

On one daemon, every configuration of a sweep point runs once a round, in
turn, for --repeat rounds (interleaved); figures are medians over the
rounds of each job's median. Prints frame_ms and cpu_work_ms (the CPU
time the daemon took a frame: on llvmpipe, where all the work is on the
CPU, the figure other processes' load inflates least), the geometry pass
(visibility against gbuffer) and the shading pass (shading against
lighting) from the per-pass GPU times, the bytes a pixel each keeps beside
the output's colour, and the crossovers: from which triangle count (or
light count) on the visibility buffer beats each g-buffer technique,
interpolated linearly in log-log between measured points.

  bench/bench_visibility.py [--width 480 --height 320] [--frames 10]
      [--repeat 2] [--segments 8,32,128,256] [--panel-quads 16,64,256]
      [--counts 16,256,1024] [--json FILE] [--from-json FILE]"""

import argparse
import json
import math
import os
import statistics
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "e2e"))
import gltf_gen  # noqa: E402
import testlib  # noqa: E402
import benchrun  # noqa: E402

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("--width", type=int, default=480)
ap.add_argument("--height", type=int, default=320)
ap.add_argument("--frames", type=int, default=10)
ap.add_argument("--warmup", type=int, default=2)
ap.add_argument("--repeat", type=int, default=2)
ap.add_argument("--segments", default="8,32,128,256")
ap.add_argument("--panel-quads", default="16,64,256")
ap.add_argument("--counts", default="16,256,1024")
ap.add_argument("--lights", type=int, default=64, help="lights of the density points")
ap.add_argument("--json", help="write every result here")
ap.add_argument("--from-json", help="report on the results a --json run wrote, without running")
args = ap.parse_args()

TECHS = [("forward", "forward", None), ("deferred", "deferred", None),
         ("clustered_deferred", "clustered_deferred", None),
         ("visibility_buffer", "visibility_buffer", {"lights": "all"}),
         ("visibility_buffer_clustered", "visibility_buffer", {"lights": "clustered"})]
GBUFFER = ("deferred", "clustered_deferred")
VIS = ("visibility_buffer", "visibility_buffer_clustered")
segments = [int(s) for s in args.segments.split(",") if s]
quads = [int(q) for q in args.panel_quads.split(",") if q]
counts = [int(c) for c in args.counts.split(",") if c]
POINTS = ([("segments", s) for s in segments] + [("asset", q) for q in quads] +
          [("lights", n) for n in counts])


def dense_asset(n):
    """Nine panels of n x n quads (2 n^2 triangles each), one textured
    material each, side by side facing the camera."""
    g = gltf_gen.Gltf()
    for k in range(9):
        bc = g.texture(g.image(gltf_gen.pattern_png(64, (60 + 20 * k, 90, 200 - 15 * k, 255),
                                                    (230, 220, 200, 255), 8)))
        mat = g.material(name="m%d" % k, pbrMetallicRoughness={"baseColorTexture": {"index": bc},
                                                                "roughnessFactor": 0.5})
        mesh = g.mesh(gltf_gen.grid(n), material=mat, uv1=False, name="p%d" % k)
        g.node(mesh=mesh, name="p%d" % k, translation=[(k % 3) * 2.1, (k // 3) * 2.1, 0])
    return g.glb()


def job(name, point):
    tech, opts = next((t, o) for n, t, o in TECHS if n == name)
    kind, v = point
    scene = {"width": args.width, "height": args.height}
    if kind == "segments":
        scene.update(preset="lights", lights=args.lights, sphere_segments=v)
    elif kind == "asset":
        scene.update(asset="dense%d.glb" % v, lights=args.lights, light_intensity=0.5)
    else:
        scene.update(preset="lights", lights=v)
    j = {"technique": tech, "frames": args.frames, "warmup_frames": args.warmup,
         "capture_interval": 0, "scene": scene}
    if opts:
        j[tech] = opts
    return j


def key(name, point):
    return "%s/%s/%d" % (name, point[0], point[1])


results = {key(n, p): [] for n, _, _ in TECHS for p in POINTS}
if args.from_json:
    with open(args.from_json) as f:
        results.update(json.load(f))
bench = benchrun.Run()
d = None if args.from_json else testlib.Daemon()
try:
    if d:
        info = d.json("GET", "/v1/info")[1]["device"]
        print("device: %s | %s | %s" % (info["gl_renderer"], info["gl_version"], info["egl_device"]))
        for q in quads:
            status, up = d.json("PUT", "/v1/assets/dense%d.glb" % q, dense_asset(q), timeout=600)
            if status not in (200, 201):
                sys.exit("uploading dense%d.glb: %d %s" % (q, status, up))
        print("scenes: lights preset (%d lights) at sphere_segments %s; dense asset (9 panels of "
              "n x n quads, %d generated lights) at n = %s; lights preset at %s lights; %dx%d, "
              "%d timed frames after %d warm-up, %d interleaved rounds"
              % (args.lights, args.segments, args.lights, args.panel_quads, args.counts,
                 args.width, args.height, args.frames, args.warmup, args.repeat))
        bench.start()
        print()
        for rep in range(args.repeat):
            for p in POINTS:
                for n, _, _ in TECHS:
                    t0 = time.time()
                    done = d.wait(d.submit(job(n, p)), timeout=7200)
                    if done.get("status") != "done":
                        sys.exit("%s at %s failed: %s" % (n, p, done.get("error")))
                    r = done["result"]
                    results[key(n, p)].append(r)
                    print("  [%d/%d] %-28s %-8s %6d  frame %9.2f ms  (%.0f s)"
                          % (rep + 1, args.repeat, n, p[0], p[1], r["frame_ms"]["median"],
                             time.time() - t0), flush=True)
finally:
    if d:
        d.stop()
        d.cleanup()
if d:
    bench.end([r for rs in results.values() for r in rs])
if args.json and not args.from_json:
    with open(args.json, "w") as f:
        json.dump(results, f)


def med(name, p, what="frame"):
    rs = results[key(name, p)]
    if what == "frame":
        return statistics.median(r["frame_ms"]["median"] for r in rs)
    if what == "work":
        return statistics.median(benchrun.cpu_work_ms(r) for r in rs)
    return statistics.median(r["gpu_sections_ms"].get(what, {}).get("median", 0.0) for r in rs)


def triangles(p):
    return results[key("forward", p)][0]["triangles_per_frame"]


def bytes_pp(name, p):
    r = results[key(name, p)][0]
    tech = r["technique"]
    if tech == "visibility_buffer":
        return r[tech]["bytes_per_pixel"]
    if tech in GBUFFER:
        return (r[tech].get("gbuffer") or r[tech])["bytes_per_pixel"]
    return 4.0  # forward: the depth alone


GEOMETRY = {"deferred": "gbuffer", "clustered_deferred": "gbuffer"}
SHADING = {"deferred": "lighting", "clustered_deferred": "lighting"}


def geometry_ms(name, p):
    return med(name, p, "visibility") if name in VIS else med(name, p, GEOMETRY.get(name, "shading"))


def shading_ms(name, p):
    return med(name, p, "shading") if name in VIS else med(name, p, SHADING.get(name, "shading"))


for series, label in (("frame", "frame_ms"), ("work", "cpu_work_ms")):
    print("\n== %s ==" % label)
    print("| point | triangles a frame | " + " | ".join(n for n, _, _ in TECHS) + " |")
    print("|---|---|" + "---|" * len(TECHS))
    for p in POINTS:
        print("| %s %d | %d | %s |" % (p[0], p[1], triangles(p), " | ".join(
            "%.2f" % med(n, p, series) for n, _, _ in TECHS)))

print("\n== passes (GPU ms, medians): geometry (visibility / gbuffer), shading (shading / lighting) ==")
print("| point | " + " | ".join("%s geometry | %s shading" % (n, n) for n in ("deferred", "clustered_deferred", "visibility_buffer", "visibility_buffer_clustered")) + " |")
print("|---|" + "---|" * 8)
for p in POINTS:
    print("| %s %d | %s |" % (p[0], p[1], " | ".join(
        "%.2f | %.2f" % (geometry_ms(n, p), shading_ms(n, p))
        for n in ("deferred", "clustered_deferred", "visibility_buffer", "visibility_buffer_clustered"))))

print("\n== bytes a pixel beside the output's colour ==")
for n, _, _ in TECHS:
    p = POINTS[0]
    pa = next((q for q in POINTS if q[0] == "asset"), None)
    print("  %-28s %s%s" % (n, bytes_pp(n, p), " (asset scenes: %s)" % bytes_pp(n, pa) if pa else ""))


def crossover(a, b, kind, xs, xof):
    """The x (triangles or lights) from which a is faster than b, by linear
    interpolation in log-log between the measured points of kind."""
    pts = [(xof((kind, v)), med(a, (kind, v)), med(b, (kind, v))) for v in xs]
    for (x0, a0, b0), (x1, a1, b1) in zip(pts, pts[1:]):
        d0, d1 = math.log(a0 / b0), math.log(a1 / b1)
        if d0 >= 0 > d1:
            t = d0 / (d0 - d1)
            return "from about %.3g on" % math.exp(math.log(x0) + t * (math.log(x1) - math.log(x0)))
        if d0 < 0 <= d1:
            t = d0 / (d0 - d1)
            return "up to about %.3g" % math.exp(math.log(x0) + t * (math.log(x1) - math.log(x0)))
    return "everywhere measured" if pts and all(p[1] < p[2] for p in pts) else \
        "nowhere measured" if pts and all(p[1] >= p[2] for p in pts) else "mixed"


print("\n== crossovers (frame_ms) ==")
for v, g in (("visibility_buffer", "deferred"), ("visibility_buffer_clustered", "clustered_deferred"),
             ("visibility_buffer", "clustered_deferred")):
    print("  %s beats %s: triangles (lights preset) %s; triangles (dense asset) %s; lights %s"
          % (v, g, crossover(v, g, "segments", segments, triangles),
             crossover(v, g, "asset", quads, triangles),
             crossover(v, g, "lights", counts, lambda p: p[1])))
