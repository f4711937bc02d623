#!/usr/bin/env python3
"""Regenerates docs/assets/*.png and the table in docs/assets.md ("Every
technique on a generated asset"): tests/e2e/gltf_gen.py's showcase asset
(a textured court: normal, metallic-roughness and emissive maps, an
alpha-masked fence, a glass pane, a point, a spot and a directional light)
uploaded to a daemon and rendered by every technique with 64 generated
point lights besides the asset's own, scored against forward, interleaved
over --repeat rounds.

    SHADEBENCHD=build/shadebenchd docs/assets/make_captures.py [--repeat 3]

Prints the run's commit, command and load (bench/benchrun.py), then a
markdown table: frame_ms and cpu_work_ms medians, their ratio to forward,
and SSIM and PerceptualDiff against forward."""

import argparse
import os
import shutil
import statistics
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "tests", "e2e"))
sys.path.insert(0, os.path.join(HERE, "..", "..", "bench"))
import benchrun  # noqa: E402
import gltf_gen  # noqa: E402
import testlib  # noqa: E402

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("--repeat", type=int, default=3)
ap.add_argument("--frames", type=int, default=8)
ap.add_argument("--width", type=int, default=480)
ap.add_argument("--height", type=int, default=360)
ap.add_argument("--dynamic", action="store_true", help="the generated lights move (scene.dynamic); "
                "the captures are written only without it")
args = ap.parse_args()

SCENE = {"asset": "court.glb", "lights": 64, "light_intensity": 0.15, "width": args.width,
         "height": args.height, "dynamic": args.dynamic}
bench = benchrun.Run()
d = testlib.Daemon()
results = {}
try:
    info = d.json("GET", "/v1/info")[1]
    dev = info["device"]
    print("device: %s | %s | %s" % (dev["gl_renderer"], dev["gl_version"], dev["egl_device"]))
    techniques = [t["name"] for t in info["techniques"]]
    status, up = d.json("PUT", "/v1/assets/court.glb", gltf_gen.showcase_asset().glb())
    if status not in (200, 201):
        sys.exit("upload: %d %s" % (status, up))
    bench.start()
    every = []
    for rep in range(args.repeat):
        for t in techniques:
            job = {"technique": t, "frames": args.frames, "warmup_frames": 2,
                   "capture_interval": args.frames, "scene": SCENE}
            if t not in ("forward", "unlit"):
                job["reference"] = "forward"
            done = d.wait(d.submit(job), timeout=1800)
            if done.get("status") != "done":
                sys.exit("%s: %s" % (t, done.get("error")))
            results.setdefault(t, []).append(done["result"])
            every.append(done["result"])
            if rep == 0 and not args.dynamic:
                name = "frame-%06d.png" % args.frames
                shutil.copy(os.path.join(d.state, "jobs", done["id"], name),
                            os.path.join(HERE, "court-%s.png" % t))
    bench.end(every)
finally:
    testlib.stop_and_check(d)

fwd = statistics.median(r["frame_ms"]["median"] for r in results["forward"])
fwd_cpu = statistics.median(benchrun.cpu_work_ms(r) for r in results["forward"])
print()
print("| technique | frame_ms | / forward | cpu_work_ms | / forward | SSIM against forward | PerceptualDiff |")
print("|---|---|---|---|---|---|---|")
for t, rs in results.items():
    f = statistics.median(r["frame_ms"]["median"] for r in rs)
    c = statistics.median(benchrun.cpu_work_ms(r) for r in rs)
    q = rs[0].get("quality", {})
    ssim = q.get("worst_ssim", {}).get("value")
    pd = q.get("pdiff_failed_captures")
    print("| %s | %.1f | %.2f | %.1f | %.2f | %s | %s |" % (
        t, f, f / fwd, c, c / fwd_cpu, "%.5f" % ssim if ssim is not None else "-",
        "-" if pd is None else ("passes" if pd == 0 else "fails")))
