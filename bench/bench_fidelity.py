#!/usr/bin/env python3
"""shadebench against the Khronos glTF Sample Viewer (issue 32): fidelity
jobs on tests/e2e/gltf_gen.py's generated assets, lit and per look.debug
channel, under two lightings (the asset's punctual lights with the uniform
ambient, and an uploaded HDR environment from tests/e2e/hdr_gen.py), then
the same jobs again to show the reference cache. Prints, per asset and look,
each channel's SSIM, FLIP and pixels off, and what the reference cost
(Chromium's start, the page, the asset's load, the environment's filtering,
each channel's render) against the job it checks (its own wall time). The
fidelity set (--assets set) is also scored per object: each feature's
rectangle cropped from both images of every channel (shadebench-compare,
$SHADEBENCH_COMPARE or beside $SHADEBENCHD).

    SHADEBENCHD=build/shadebenchd bench/bench_fidelity.py [--size 160x120]
        [--assets transforms,texcoord1_outside] [--looks punctual,environment]
        [--images DIR]

--images copies each job's fidelity/ images (both renders and the SSIM and
FLIP maps) to DIR/ASSET-LOOK-*.png."""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tests", "e2e"))
sys.path.insert(0, HERE)
import benchrun  # noqa: E402
import gltf_gen  # noqa: E402
import hdr_gen  # noqa: E402
import testlib  # noqa: E402

ASSETS = {
    "transforms": lambda: gltf_gen.transforms_asset(False),
    "transforms_baked": lambda: gltf_gen.transforms_asset(True),
    "texcoord1_outside": lambda: gltf_gen.texcoord_asset(1, False),
    "colors": lambda: gltf_gen.colors_asset(True),
    "texture_transform": lambda: gltf_gen.texture_transform_asset(True),
    "showcase": gltf_gen.showcase_asset,
    # One object per feature (gltf_gen.FIDELITY_SET_FEATURES), seen by
    # FIDELITY_SET_CAMERA; its table is per object as well (each object's
    # rectangle cropped from both images, as tests/e2e/e2e_fidelity.py).
    "set": gltf_gen.fidelity_set_asset,
    "set_baked": lambda: gltf_gen.fidelity_set_asset(True),
}
LOOKS = {
    # The asset's own lights and shadebench's PBR ambient (a uniform
    # environment of radiance 0.15), Khronos PBR Neutral.
    "punctual": {"tonemap": "pbr_neutral"},
    # An uploaded equirectangular HDR, as look.ibl's environment, and the
    # asset's lights.
    "environment": {"tonemap": "pbr_neutral", "ibl": {"environment": {"asset": "sky.hdr"}}},
}


def crop_ssim(ref, test, rect, tmp, compare):
    """The lower of luma and RGB SSIM of rect in two png_pixels images."""
    paths = []
    for k, image in enumerate((ref, test)):
        paths.append(os.path.join(tmp, "crop%d.png" % k))
        with open(paths[-1], "wb") as f:
            f.write(gltf_gen.crop_png(image, rect))
    r = subprocess.run([compare] + paths + ["--metrics", "ssim"], capture_output=True, text=True)
    o = json.loads(r.stdout)
    return min(o["ssim"], o["ssim_rgb"])


def per_object(d, job_id, f, w, h, tmp, compare):
    """{feature: {channel: SSIM}} of the fidelity set's objects."""
    rects = gltf_gen.fidelity_set_rects(w, h)
    out = {name: {} for name in rects}
    for ch, m in f["channels"].items():
        if "error" in m:
            continue
        imgs = []
        for kind in ("khronos", "shadebench"):
            path = os.path.join(tmp, "%s-%s.png" % (ch, kind))
            d.download("/v1/jobs/%s/%s" % (job_id, m["files"][kind]), path)
            imgs.append(testlib.png_pixels(path))
        for name, rect in rects.items():
            out[name][ch] = crop_ssim(imgs[0], imgs[1], rect, tmp, compare)
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--size", default="160x120")
    ap.add_argument("--assets", default="transforms,texcoord1_outside,colors,texture_transform")
    ap.add_argument("--looks", default="punctual,environment")
    ap.add_argument("--images")
    ap.add_argument("--repeat-cached", type=int, default=1,
                    help="runs of each job again afterwards, answered from the cache")
    a = ap.parse_args()
    w, h = (int(v) for v in a.size.split("x"))
    bench = benchrun.Run()
    bench.start()
    d = testlib.Daemon()
    ok = False
    tmp = None
    try:
        d.request("PUT", "/v1/assets/sky.hdr", hdr_gen.sky_and_ground())
        for name in a.assets.split(","):
            st, _, body = d.request("PUT", "/v1/assets/%s.glb" % name, ASSETS[name]().glb())
            assert st == 201, (name, st, body)
        rows = []
        objects = {}
        tmp = tempfile.mkdtemp(prefix="bench_fidelity.")
        compare = os.environ.get("SHADEBENCH_COMPARE") or os.path.join(
            os.path.dirname(os.path.abspath(os.environ.get("SHADEBENCHD", "./shadebenchd"))),
            "shadebench-compare")
        for name in a.assets.split(","):
            for look in a.looks.split(","):
                for attempt in range(1 + a.repeat_cached):
                    t0 = time.time()
                    body = {"width": w, "height": h, "look": LOOKS[look]}
                    if name.startswith("set"):
                        body["camera"] = gltf_gen.FIDELITY_SET_CAMERA
                    st, sub = d.json("POST", "/v1/assets/%s.glb/fidelity" % name, body)
                    assert st == 202, (st, sub)
                    job = d.wait(sub["id"])
                    wall = time.time() - t0
                    if job["status"] != "done":
                        print("%s %s: %s %s" % (name, look, job["status"], job.get("error")))
                        break
                    r = job["result"]
                    f = r["fidelity"]
                    rows.append((name, look, attempt, f, wall, r))
                    if name.startswith("set") and attempt == 0:
                        objects[(name, look)] = per_object(d, sub["id"], f, w, h, tmp, compare)
                    if a.images and attempt == 0:
                        os.makedirs(a.images, exist_ok=True)
                        for ch, m in f["channels"].items():
                            for kind, rel in m.get("files", {}).items():
                                dest = os.path.join(a.images, "%s-%s-%s-%s.png" % (name, look, ch, kind))
                                d.download("/v1/jobs/%s/%s" % (sub["id"], rel), dest)
        print("\n%-18s %-11s %-16s %8s %8s %8s %8s %7s %5s" % (
            "asset", "look", "channel", "ssim", "ssim_rgb", "flip", ">8", ">32", "max"))
        for name, look, attempt, f, wall, r in rows:
            if attempt:
                continue
            for ch, m in f["channels"].items():
                if "error" in m:
                    print("%-18s %-11s %-16s %s" % (name, look, ch, m["error"]))
                    continue
                print("%-18s %-11s %-16s %8.5f %8.5f %8.5f %8d %7d %5d" % (
                    name, look, ch, m["ssim"], m["ssim_rgb"], m["flip"]["mean"], m["pixels_over_8"],
                    m["pixels_over_32"], m["max_difference"]))
        for (name, look), table in objects.items():
            chans = list(next(iter(table.values())))
            print("\n%s, %s, per object (SSIM, the lower of luma and RGB, of its rectangle):" % (
                name, look))
            print("%-26s" % "object" + "".join("%9s" % c[:8] for c in chans))
            for obj, per in table.items():
                print("%-26s" % obj + "".join("%9.5f" % per[c] for c in chans))
        print("\nthe reference's cost (ms) against the job's own wall time (s):")
        print("%-18s %-11s %-5s %9s %7s %7s %9s %9s %8s %8s" % (
            "asset", "look", "cache", "chromium", "page", "load", "environ", "channels",
            "ref_s", "job_s"))
        for name, look, attempt, f, wall, r in rows:
            c = f["cost"]
            chans = sum(c["render_ms"].values())
            print("%-18s %-11s %-5s %9.0f %7.0f %7.0f %9.0f %9.0f %8.1f %8.1f" % (
                name, look, "hit" if f["cache_hit"] else "miss", c["chromium_start_ms"],
                c["page_ms"], c["load_ms"], c["environment_ms"], chans, f["fidelity_s"], wall))
            if attempt == 0:
                print("    per channel render ms: " + ", ".join(
                    "%s %.0f" % kv for kv in sorted(c["render_ms"].items())))
        bench.end([r for _, _, _, _, _, r in rows])
        ok = True
    finally:
        if tmp:
            shutil.rmtree(tmp, ignore_errors=True)
        d.stop()
        if not ok:
            print("the daemon's folder, kept: %s" % d.tmp)
        d.cleanup(keep=not ok)


if __name__ == "__main__":
    main()
