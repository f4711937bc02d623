#!/usr/bin/env python3
"""The Khronos reference (issue 32; docs/assets.md, "Fidelity against the
Khronos viewer"): POST /v1/assets/NAME/fidelity renders gltf_gen.py's
fidelity set (one asset holding one object per feature the generated
assets state: rotated, scaled, mirrored and nested nodes, maps on
TEXCOORD_1 outside and inside [0, 1], KHR_texture_transform, COLOR_0 as
bytes and floats, a sphere without normals, a double-sided plate from
behind) with the glTF Sample Viewer in headless Chromium and compares
shadebench's lit image and look.debug channels with the viewer's. Each
object's rectangle is cropped from both images of every channel and
compared on its own: SSIM 0.99 or more, or the figure measured for it where
a difference is known and explained (OBJECT_MIN_SSIM, docs/assets.md); the
whole images too. Then: the images downloadable, the reference cached (a
second request renders nothing), another camera another key, a look the
viewer cannot draw refused naming its field, a daemon without Chromium or
without the viewer answering 503 naming what is missing (and saying so in
/v1/info), an uploaded environment oriented as shadebench maps it (a white
ball lit from +x by it in both), and a job cancelled while the viewer
renders. 256x192 (objects of 30 to 50 pixels): 61 s at load average 8 on
the 2-core machine (docs/testing.md)."""
import json
import os
import shutil
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gltf_gen  # noqa: E402
import hdr_gen  # noqa: E402
from testlib import Daemon, check, finish, png_info, png_pixels, stop_and_check  # noqa: E402

COMPARE = os.environ.get("SHADEBENCH_COMPARE", "./shadebench-compare")
W, H = 256, 192
CAMERA = gltf_gen.FIDELITY_SET_CAMERA
CHANNELS = ["lit", "shading_normal", "geometric_normal", "normal_texture", "tangent",
            "bitangent", "base_color", "metallic", "roughness", "occlusion", "emissive",
            "uv0", "uv1", "alpha"]
# The whole images: every channel and the lit image (punctual lights and
# the uniform ambient) at 0.995 or more (measured 0.9966 to 1.0).
WHOLE_MIN_SSIM = 0.995
# Each object's crop, per channel: 0.99 unless listed. The listed figures
# were measured at 256x192 (docs/assets.md, "What still differs"), each
# bound just under its figure, and are the same with the transforms baked
# into the vertices (gltf_gen.fidelity_set_asset(True)):
OBJECT_MIN_SSIM = {
    # Generated tangents: assimp's per-vertex sums, not MikkTSpace as the
    # viewer's; they part near the sphere's pole, which faces the camera
    # (tangent 0.952, bitangent 0.946, shading normal 0.977, lit 0.985).
    ("transforms.rotated0", "tangent"): 0.945,
    ("transforms.rotated0", "bitangent"): 0.94,
    ("transforms.rotated0", "shading_normal"): 0.97,
    ("transforms.rotated0", "lit"): 0.98,
    # The uniform ambient's specular at grazing views: the split sum's
    # environment BRDF (Karis's fit) against the viewer's table with
    # multiple-scattering Fresnel: the cube's side seen edge-on (0.974),
    # the sphere's rim (0.990).
    ("transforms.mirrored_cube0", "lit"): 0.97,
    ("transforms.mirrored0", "lit"): 0.985,
    # Coverage at silhouettes: the viewer's rasteriser snaps vertices to
    # 1/16 pixel, llvmpipe to 1/256, so a few edge pixels of the small
    # objects are covered by one and not the other (uniform channels such
    # as roughness show it alone): the mirrored cube 0.989, the nested box
    # 0.986 to 0.990, the flat ball's tangent 0.988.
    ("transforms.mirrored_cube0", "occlusion"): 0.985,
    ("transforms.mirrored_cube0", "uv1"): 0.985,
    ("transforms.mirrored_cube0", "alpha"): 0.985,
    ("flat_normals.ball", "tangent"): 0.985,
}
for _ch in CHANNELS:
    OBJECT_MIN_SSIM.setdefault(("transforms.nested0", _ch), 0.982)


def white_ball():
    """A white rough sphere, nothing else: it shows where light comes from."""
    g = gltf_gen.Gltf()
    mat = g.material(name="white", pbrMetallicRoughness={
        "baseColorFactor": [0.8, 0.8, 0.8, 1], "metallicFactor": 0.0, "roughnessFactor": 1.0})
    g.node(mesh=g.mesh(gltf_gen.sphere()[:5], material=mat, uv1=False, name="ball"), name="ball")
    return g


def crop_ssim(ref, test, rect, tmp):
    """The lower of luma and RGB SSIM of rect in the two images."""
    a, b = os.path.join(tmp, "crop-ref.png"), os.path.join(tmp, "crop-test.png")
    for image, path in ((ref, a), (test, b)):
        with open(path, "wb") as f:
            f.write(gltf_gen.crop_png(image, rect))
    r = subprocess.run([COMPARE, a, b, "--metrics", "ssim"], capture_output=True, text=True)
    o = json.loads(r.stdout) if r.returncode in (0, 1) and r.stdout else {}
    return min(o.get("ssim", 0), o.get("ssim_rgb", 0))


d = Daemon()
try:
    st, info = d.json("GET", "/v1/info")
    ref = info.get("reference", {})
    check(ref.get("available") is True, "/v1/info: the reference is available (%s)" % ref)
    st, _, body = d.request("PUT", "/v1/assets/set.glb", gltf_gen.fidelity_set_asset().glb())
    check(st == 201, "the fidelity set uploads (%d)" % st)

    # Refusals, before anything renders.
    st, e = d.json("POST", "/v1/assets/set.glb/fidelity", {"look": {"lighting": "phong"}})
    check(st == 400 and e.get("error", {}).get("field") == "look.lighting",
          "a Phong look is refused naming look.lighting (%d %s)" % (st, e))
    st, e = d.json("POST", "/v1/assets/set.glb/fidelity", {"channels": ["albedo"]})
    check(st == 400 and e.get("error", {}).get("field") == "fidelity.channels[0]",
          "an unknown channel is refused naming it (%d %s)" % (st, e))
    st, e = d.json("POST", "/v1/assets/nothere.glb/fidelity", {})
    check(st == 400 and e.get("error", {}).get("field") == "scene.asset",
          "an unknown asset is refused naming scene.asset (%d %s)" % (st, e))
    st, e = d.json("GET", "/v1/assets/set.glb/fidelity")
    check(st == 405, "GET on the fidelity route is 405 (%d)" % st)

    # The comparison: every channel of the whole set.
    req = {"width": W, "height": H, "camera": CAMERA}
    st, sub = d.json("POST", "/v1/assets/set.glb/fidelity", req)
    check(st == 202, "POST /v1/assets/set.glb/fidelity is accepted (%d %s)" % (st, sub))
    job = d.wait(sub["id"])
    check(job.get("status") == "done", "the fidelity job is done (%s: %s)" % (
        job.get("status"), job.get("error")))
    f = job.get("result", {}).get("fidelity", {})
    chans = f.get("channels", {})
    check(f.get("cache_hit") is False, "the first request renders the reference")
    cost = f.get("cost", {})
    check(all(cost.get(k, 0) > 0 for k in ("chromium_start_ms", "page_ms", "load_ms")),
          "the reference's cost is reported (%s)" % cost)
    check(sorted(f.get("mirrored_matrices_restated", [])) != [] and
          "mirrored_bitangent" in f.get("viewer_patches", []),
          "the mirrored nodes restated and the viewer's bitangent patched (%s %s)" % (
              f.get("mirrored_matrices_restated"), f.get("viewer_patches")))
    check(sorted(chans) == sorted(CHANNELS), "every channel compared (%s)" % sorted(chans))
    for name in CHANNELS:
        m = chans.get(name, {})
        s = min(m.get("ssim", 0), m.get("ssim_rgb", 0))
        check(s >= WHOLE_MIN_SSIM, "whole %s: SSIM %.5f >= %.3f (%s)" % (
            name, s, WHOLE_MIN_SSIM, m.get("error", "")))
    # Both renders and the difference images are served.
    lit = chans.get("lit", {})
    for kind in ("shadebench", "khronos", "ssim_map", "flip_map"):
        rel = lit.get("files", {}).get(kind)
        path = os.path.join(d.tmp, kind + ".png")
        ok = rel and d.download("/v1/jobs/%s/%s" % (sub["id"], rel), path) == 200
        pi = (png_info(path) or {}) if ok else {}
        # The SSIM map is the valid region: the window's border off.
        check(ok and (kind == "ssim_map" or (pi.get("width"), pi.get("height")) == (W, H)),
              "lit %s image downloads (%s %s)" % (kind, rel, pi))
    st, _, _ = d.request("GET", "/v1/jobs/%s/fidelity/..%%2fjob.json" % sub["id"])
    check(st in (400, 404), "a path outside fidelity/ is refused (%d)" % st)

    # Each feature's object, channel by channel.
    rects = gltf_gen.fidelity_set_rects(W, H, CAMERA)
    worst = {}
    for name in CHANNELS:
        files = chans.get(name, {}).get("files", {})
        paths = {}
        for kind in ("shadebench", "khronos"):
            paths[kind] = os.path.join(d.tmp, "%s-%s.png" % (name, kind))
            if not files.get(kind) or d.download("/v1/jobs/%s/%s" % (sub["id"], files[kind]),
                                                 paths[kind]) != 200:
                paths = None
                break
        if not paths:
            check(False, "%s: both images download" % name)
            continue
        images = {k: png_pixels(p) for k, p in paths.items()}
        low = []
        for obj, rect in rects.items():
            s = crop_ssim(images["khronos"], images["shadebench"], rect, d.tmp)
            bound = OBJECT_MIN_SSIM.get((obj, name), 0.99)
            if s < worst.get(obj, (2, ""))[0]:
                worst[obj] = (s, name)
            if s < bound:
                low.append("%s %.5f < %.3f" % (obj, s, bound))
        check(not low, "%s, per object: each at its bound (%s)" % (name, "; ".join(low) or "all"))
    print("  the lowest channel of each object: " + ", ".join(
        "%s %s %.5f" % (obj, ch, s) for obj, (s, ch) in worst.items()))

    # The cache: the same request again renders nothing and compares the same.
    st, sub2 = d.json("POST", "/v1/assets/set.glb/fidelity", req)
    job2 = d.wait(sub2["id"])
    f2 = job2.get("result", {}).get("fidelity", {})
    check(f2.get("cache_hit") is True, "the second request is a cache hit")
    check(f2.get("cache_key") == f.get("cache_key"), "with the same key")
    check(abs(f2.get("channels", {}).get("lit", {}).get("ssim", 0) - lit.get("ssim", 1)) < 1e-9,
          "and the same lit SSIM")
    # Another camera is another key.
    st, sub3 = d.json("POST", "/v1/assets/set.glb/fidelity",
                      {"width": 96, "height": 72, "channels": ["base_color"],
                       "camera": {"eye": [2, 1.5, 16], "target": [0, 0, 0], "yfov_deg": 40}})
    job3 = d.wait(sub3["id"])
    f3 = job3.get("result", {}).get("fidelity", {})
    check(job3.get("status") == "done" and f3.get("cache_hit") is False and
          f3.get("cache_key") != f.get("cache_key"),
          "an explicit camera renders anew (%s %s)" % (job3.get("status"), job3.get("error")))
    bc = f3.get("channels", {}).get("base_color", {})
    s = min(bc.get("ssim", 0), bc.get("ssim_rgb", 0))
    check(s >= 0.99, "base_color from that camera, 96x72: SSIM %.5f >= 0.99" % s)

    # An uploaded environment, oriented as shadebench maps it: a white ball
    # under hdr_gen.sky_and_ground (its hot spot at +x) is brighter on its
    # right in both images, seen from +z (the viewer's default rotation of
    # 90 degrees put the hot spot at +z: lit SSIM 0.808, left and right
    # alike). Small sampler sizes: the orientation, not the filtering.
    d.request("PUT", "/v1/assets/sky.hdr", hdr_gen.sky_and_ground())
    st, _, _ = d.request("PUT", "/v1/assets/ball.glb", white_ball().glb())
    st, sub5 = d.json("POST", "/v1/assets/ball.glb/fidelity", {
        "width": 48, "height": 48, "channels": ["base_color"], "lights": [],
        "scene": {"asset_lights": False},
        "camera": {"eye": [0, 0, 3], "target": [0, 0, 0], "yfov_deg": 40},
        "look": {"tonemap": "pbr_neutral", "ibl": {"environment": {"asset": "sky.hdr"}}},
        "ibl_sampler": {"texture_size": 32, "ggx_samples": 16, "lambertian_samples": 64}})
    job5 = d.wait(sub5["id"]) if st == 202 else {}
    lit5 = job5.get("result", {}).get("fidelity", {}).get("channels", {}).get("lit", {})
    sides = {}
    for kind in ("shadebench", "khronos"):
        path = os.path.join(d.tmp, "ball-%s.png" % kind)
        if lit5.get("files", {}).get(kind) and d.download(
                "/v1/jobs/%s/%s" % (sub5["id"], lit5["files"][kind]), path) == 200:
            w, h, px = png_pixels(path)
            sides[kind] = (px[(h // 2) * w + w // 2 - 10][0], px[(h // 2) * w + w // 2 + 10][0])
    check(len(sides) == 2 and all(right > left + 8 for left, right in sides.values()),
          "the environment's hot spot (+x) lights the ball's right in both (left, right: %s)" % sides)
    s = min(lit5.get("ssim", 0), lit5.get("ssim_rgb", 0))
    check(s >= 0.92, "the ball under the environment: lit SSIM %.5f >= 0.92 (%s: %s)" % (
        s, job5.get("status"), job5.get("error")))

    # Cancelled while the viewer renders: Chromium is killed with its group
    # and the job ends cancelled.
    st, sub4 = d.json("POST", "/v1/assets/set.glb/fidelity",
                      {"width": 96, "height": 72, "channels": ["base_color"],
                       "camera": {"eye": [-2, 1.5, 16], "target": [0, 0, 0], "yfov_deg": 40}})
    deadline = time.time() + 120
    phase = None
    while time.time() < deadline:
        st, j = d.json("GET", "/v1/jobs/%s" % sub4["id"])
        phase = j.get("phase")
        if phase == "fidelity" or j.get("status") not in ("queued", "running"):
            break
        time.sleep(0.2)
    time.sleep(1.0)  # Chromium is starting
    t0 = time.time()
    st, _ = d.json("DELETE", "/v1/jobs/%s" % sub4["id"])
    job4 = d.wait(sub4["id"])
    check(phase == "fidelity" and job4.get("status") == "cancelled",
          "a fidelity job cancelled in its fidelity phase ends cancelled (%s, %s: %s)" % (
              phase, job4.get("status"), job4.get("error")))
    check(time.time() - t0 < 30, "within 30 s of the DELETE (%.1f s)" % (time.time() - t0))
    stop_and_check(d)  # a clean exit: under the sanitizers, no error and no leak
finally:
    d.stop()
    d.cleanup()

# Without Chromium, and without the viewer: the daemon runs and says so.
for args, what in ((["--chromium", "/nonexistent/chromium"], "Chromium"),
                   (["--reference-viewer", "/nonexistent/viewer"], "Sample Viewer")):
    d = Daemon(*args)
    try:
        st, info = d.json("GET", "/v1/info")
        ref = info.get("reference", {})
        check(ref.get("available") is False and what in ref.get("missing", ""),
              "%s missing: /v1/info says so (%s)" % (what, ref))
        d.request("PUT", "/v1/assets/box.glb", gltf_gen.texcoord_asset(1, False).glb())
        st, e = d.json("POST", "/v1/assets/box.glb/fidelity", {"width": W, "height": H})
        err = e.get("error", {})
        check(st == 503 and err.get("field") == "fidelity" and what in err.get("message", ""),
              "%s missing: 503 naming it (%d %s)" % (what, st, e))
        st, _ = d.json("GET", "/healthz")
        check(st == 200, "%s missing: the daemon still serves (%d)" % (what, st))
        stop_and_check(d)
    finally:
        d.stop()
        d.cleanup()

finish("e2e_fidelity")
