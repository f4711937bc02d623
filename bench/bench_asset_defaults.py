#!/usr/bin/env python3
"""How much of an asset scene clips at the defaults: generated assets
(tests/e2e/gltf_gen.py's showcase court, 12 m across, with its own lights
left out so that the daemon's generated lights light it; the realistic
asset; and two helmet-sized ones, gltf_gen's two textured cubes 3 m apart
and a 2 m box of light grey, each with its own lights left out) rendered by forward
at the job defaults (no look given), then with look.tonemap "none" (the
lights alone), and the share of pixels with a channel at 255, over the
whole image and over the pixels the asset covers (not the cleared
background), and the covered pixels' mean luma (0 to 255: how lit the
asset is; generated lights inside a closed mesh light only its inside).
Run against two daemons to compare defaults before and after
a change:

  bench/bench_asset_defaults.py [--daemon PATH ...] [--width W --height H]

Each --daemon (default: build/shadebenchd) runs in turn on the same files."""

import argparse
import os
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tests", "e2e"))
import benchrun  # noqa: E402
import gltf_gen  # noqa: E402
import testlib  # noqa: E402

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("--daemon", action="append")
ap.add_argument("--width", type=int, default=320)
ap.add_argument("--height", type=int, default=240)
args = ap.parse_args()
daemons = args.daemon or [os.path.join(HERE, "..", "build", "shadebenchd")]



def small_box():
    g = gltf_gen.Gltf()
    grey = g.material(pbrMetallicRoughness={"baseColorFactor": [0.8, 0.8, 0.8, 1],
                                            "metallicFactor": 0.0, "roughnessFactor": 0.5})
    g.node(mesh=g.mesh(gltf_gen.cube(2.0), material=grey, uv1=False))
    return g


ASSETS = {"showcase.glb": (gltf_gen.showcase_asset, {"asset_lights": False}),
          "realistic.glb": (gltf_gen.realistic_asset, {}),
          "two_cubes.glb": (gltf_gen.textured, {"asset_lights": False}),
          "box2m.glb": (small_box, {})}
LOOKS = [None, {"tonemap": "none"}]

run = benchrun.Run()
run.start()
results = []
tmp = tempfile.mkdtemp(prefix="shadebench-clip-")
files = {}
for name, (make, _) in ASSETS.items():
    files[name] = os.path.join(tmp, name)
    with open(files[name], "wb") as f:
        f.write(make().glb())
print("\n%-32s %-14s %-12s %6s %8s %16s %10s" % ("daemon", "asset", "tonemap", "lights",
                                                 "clipped", "clipped (asset)", "mean luma"))
for path in daemons:
    testlib.SHADEBENCHD = path
    d = testlib.Daemon()
    try:
        for name, (_, extra) in ASSETS.items():
            with open(files[name], "rb") as f:
                status, body = d.json("PUT", "/v1/assets/" + name, f.read())
            if status not in (200, 201):
                print("%s: upload refused: %s %s" % (name, status, body))
                continue
            scene = dict({"asset": name, "width": args.width, "height": args.height}, **extra)
            for look in LOOKS:
                job = {"technique": "forward", "frames": 2, "warmup_frames": 1,
                       "capture_interval": 2, "scene": scene}
                if look:
                    job["look"] = look
                done = d.run(job)
                if done.get("status") != "done":
                    print("%s: %s" % (name, done.get("error")))
                    continue
                results.append(done["result"])
                png = os.path.join(tmp, "%s-%d.png" % (name, len(results)))
                d.download(done["result"]["captures"][-1]["url"], png)
                px = testlib.png_pixels(png)[2]
                clipped = sum(1 for p in px if max(p) == 255)
                covered = [p for p in px if max(p) > 0]
                clipped_cov = sum(1 for p in covered if max(p) == 255)
                luma = sum(0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2] for p in covered)
                print("%-32s %-14s %-12s %6d %7.1f%% %15.1f%% %10.1f"
                      % (os.path.relpath(path)[-32:], name, done["spec"]["look"]["tonemap"],
                         done["result"]["scene"]["lights"]["count"], 100.0 * clipped / len(px),
                         100.0 * clipped_cov / max(len(covered), 1),
                         luma / max(len(covered), 1)))
    finally:
        d.stop()
        d.cleanup()
run.end(results)
