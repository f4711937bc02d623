#!/usr/bin/env python3
"""Scenes stated the way users state them, end to end, against pixels
computed by hand (64x64 images, a frame or two each):
- scene.light_rig: a glTF point light of I candela 2 m over the plane
  preset's flat Lambertian ground (albedo 0.7, Phong with specular 0, tone
  map none), seen straight down through an explicit camera: every checked
  pixel is 0.15 x 0.7 + I / pi / d^2 x 0.7 x cos within one 8-bit level, for
  every technique (OSL within 3); with a range the glTF window
  clamp(1 - (d / range)^4, 0, 1) multiplies it; the display curves srgb,
  gamma 2.2 (look.transfer) and pbr_neutral turn the same linear values
  into the bytes their formulas give;
- an uploaded quad seen through an orthographic scene.camera covers exactly
  the pixels its extents say, and the asset's own orthographic camera,
  rolled 90 degrees about its view axis, covers the same quad turned (its
  up vector and projection honoured); the culling techniques under an
  orthographic view agree with forward;
- environment maps: a Radiance .hdr uploaded as an asset is described, a
  truncated one and one whose header claims 100000 x 50000 pixels are
  refused 422 naming the rule, and a PBR look with look.ibl.environment
  {"asset": ...} draws it behind the scene (its hot spot straight ahead
  along +x, its sky above); an environment named as scene.asset (and a
  glTF named as the environment) is refused naming the field; deleted, its
  files go; the same map as OpenEXR (half floats, zlib; float and tiled;
  Y alone) uploads, is described with the Radiance copy the Khronos viewer
  reads, and renders as the .hdr does (every pixel within 2 levels); a cut
  .exr and one whose data window claims 100000 x 50000 pixels are refused
  422 the same way;
- an asset scene's look defaults to tonemap pbr_neutral."""

import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gltf_gen  # noqa: E402
import hdr_gen  # noqa: E402
import testlib  # noqa: E402
from testlib import check  # noqa: E402

testlib.skip_without_egl()

W = H = 64
FOVY = 60.0
EYE_HEIGHT = 10.0
LIGHT_HEIGHT = 2.0
INTENSITY = 12.0
ALBEDO = 0.7   # the plane preset's ground (daemon/scene/presets.c)
AMBIENT = 0.15  # Phong's constant term (shaders/common/lighting.glsl)
BASE = {"frames": 1, "warmup_frames": 1, "capture_interval": 1}
DOWN = {"eye": [0, EYE_HEIGHT, 0], "target": [0, 0, 0], "up": [0, 0, -1], "yfov_deg": FOVY}


def capture(d, done, name):
    path = os.path.join(d.tmp, name + ".png")
    d.download(done["result"]["captures"][-1]["url"], path)
    return testlib.png_pixels(path)[2]


def ground_point(col, row):
    """The ground point seen at pixel (col, row from the top) through DOWN:
    the camera's right is +x, its up -z."""
    t = math.tan(math.radians(FOVY) / 2) * EYE_HEIGHT
    ndc_x = (col + 0.5) / W * 2 - 1
    ndc_y = 1 - (row + 0.5) / H * 2
    return ndc_x * t, -ndc_y * t


def expected(col, row, rng=None):
    x, z = ground_point(col, row)
    d2 = x * x + z * z + LIGHT_HEIGHT ** 2
    d = math.sqrt(d2)
    att = 1.0 / d2
    if rng:
        att *= min(max(1 - (d / rng) ** 4, 0.0), 1.0)
    value = AMBIENT * ALBEDO + INTENSITY / math.pi * att * ALBEDO * (LIGHT_HEIGHT / d)
    return min(value, 1.0) * 255


def light_job(technique, rng=None):
    light = {"type": "point", "position": [0, LIGHT_HEIGHT, 0], "intensity": INTENSITY}
    if rng:
        light["range"] = rng
    job = dict(BASE, technique=technique,
               scene={"preset": "plane", "width": W, "height": H, "specular": 0,
                      "camera": DOWN, "light_rig": [light]},
               look={"lighting": "phong", "tonemap": "none"})
    if technique == "osl":
        job["osl"] = {"resolution": 256}
    return job


def srgb(v):
    v = min(max(v, 0.0), 1.0)
    return 12.92 * v if v <= 0.0031308 else 1.055 * v ** (1 / 2.4) - 0.055


def pbr_neutral_grey(v):
    """Khronos PBR Neutral on a grey (its specification's f, p, p_n, g)."""
    f = v - v * v / 0.16 if v <= 0.08 else 0.04
    p = v - f
    if p <= 0.76:
        return p
    pn = 1 - 0.24 ** 2 / (p + 1 - 1.52)
    g = 1 / (0.15 * (p - pn) + 1)
    return p * pn / p * g + pn * (1 - g)


PIXELS = [(32, 32), (31, 31), (20, 40), (5, 10), (60, 58), (0, 0), (45, 12)]


def check_light_rig(d, techniques):
    for t in techniques:
        done = d.run(light_job(t))
        if not check(done.get("status") == "done", "%s renders a light rig: %s"
                     % (t, done.get("error"))):
            continue
        px = capture(d, done, "rig-" + t)
        tol = 3 if t == "osl" else 1
        worst = 0.0
        for col, row in PIXELS:
            want, got = expected(col, row), px[row * W + col]
            worst = max(worst, max(abs(g - want) for g in got))
        check(worst <= tol, "%s: a %g cd point light %g m over the ground gives the pixels "
              "I / pi / d^2 x albedo x cos + ambient: worst off by %.2f levels (bound %d)"
              % (t, INTENSITY, LIGHT_HEIGHT, worst, tol))
        if t == "forward":
            lights = done["result"]["scene"]["gltf_lights"]["lights"]
            check(len(lights) == 1 and lights[0]["intensity"] == INTENSITY
                  and lights[0]["source"] == "light_rig" and lights[0]["range"] is None,
                  "the result lists the rig's light in glTF's terms: %s" % lights)
            cam = done["result"]["scene"]["camera"]
            check(cam["source"] == "scene.camera" and cam["up_at_frame_0"] == [0, 0, -1]
                  and len(cam["projection_matrix"]) == 16,
                  "the result gives the camera as drawn: %s" % {k: cam[k] for k in
                                                               ("source", "up_at_frame_0")})
    # The display curves on the same linear values: srgb (the sRGB encode
    # alone), the Sample Viewer's gamma 2.2, and Khronos PBR Neutral.
    for tonemap, transfer in (("srgb", "srgb"), ("srgb", "gamma_2.2"), ("pbr_neutral", "srgb")):
        job = light_job("forward")
        job["look"] = {"lighting": "phong", "tonemap": tonemap, "transfer": transfer}
        done = d.run(job)
        if not check(done.get("status") == "done", "%s/%s renders: %s"
                     % (tonemap, transfer, done.get("error"))):
            continue
        px = capture(d, done, "rig-%s-%s" % (tonemap, transfer))
        worst = 0.0
        for col, row in PIXELS:
            v = expected(col, row) / 255
            if tonemap == "pbr_neutral":
                v = pbr_neutral_grey(v)
            v = v ** (1 / 2.2) if transfer == "gamma_2.2" else srgb(v)
            worst = max(worst, max(abs(g - v * 255) for g in px[row * W + col]))
        check(worst <= 1, "tonemap %s, transfer %s: the pixels are the curve of the linear "
              "ones: worst off by %.2f levels" % (tonemap, transfer, worst))
    # The range window.
    done = d.run(light_job("forward", rng=3.0))
    px = capture(d, done, "rig-range")
    worst = max(max(abs(g - expected(c, r, 3.0)) for g in px[r * W + c]) for c, r in PIXELS)
    check(worst <= 1, "a range of 3 m multiplies by clamp(1 - (d / 3)^4, 0, 1): worst off by "
          "%.2f levels" % worst)


def quad_asset():
    """A 1 x 0.5 quad in the xy plane facing +z, a perspective camera and
    an orthographic one (xmag 1, ymag 1) 5 m in front of it, rolled 90
    degrees about the view axis (its up is -x)."""
    g = gltf_gen.Gltf()
    pos = [-0.5, -0.25, 0, 0.5, -0.25, 0, 0.5, 0.25, 0, -0.5, 0.25, 0]
    mesh = g.mesh((pos, [0, 0, 1] * 4, [0, 1, 1, 1, 1, 0, 0, 0], [0, 1, 1, 1, 1, 0, 0, 0],
                   [0, 1, 2, 0, 2, 3]),
                  material=g.material(pbrMetallicRoughness={"baseColorFactor": [1, 1, 1, 1],
                                                            "metallicFactor": 0}),
                  uv1=False)
    g.node(mesh=mesh)
    g.doc["cameras"] = [{"type": "orthographic", "name": "plan",
                         "orthographic": {"xmag": 1, "ymag": 1, "znear": 0.1, "zfar": 20}}]
    s = math.sqrt(0.5)
    g.node(camera=0, translation=[0, 0, 5], rotation=[0, 0, s, s])
    return g.glb()


def covered(px, threshold=8):
    """The box (x0, y0, x1, y1) of the pixels brighter than threshold, and
    their count."""
    xs, ys, n = [], [], 0
    for i, p in enumerate(px):
        if max(p) > threshold:
            xs.append(i % W)
            ys.append(i // W)
            n += 1
    return (min(xs), min(ys), max(xs), max(ys)) if n else None, n


def check_orthographic(d):
    status, body = d.json("PUT", "/v1/assets/quad.glb", quad_asset())
    check(status == 201 and body["description"]["cameras"][0].get("xmag") == 1,
          "the quad uploads, its orthographic camera described with xmag and ymag: %s %s"
          % (status, body.get("description", {}).get("cameras")))
    # Through scene.camera: xmag 1, ymag 1 on 64x64 is 32 pixels a unit, so
    # the quad covers x 16..47 and y 24..39 exactly.
    cam = {"eye": [0, 0, 5], "target": [0, 0, 0], "orthographic": {"xmag": 1, "ymag": 1}}
    done = d.run(dict(BASE, technique="forward",
                      scene={"asset": "quad.glb", "width": W, "height": H, "camera": cam}))
    check(done.get("status") == "done", "an orthographic scene.camera renders: %s"
          % done.get("error"))
    box, n = covered(capture(d, done, "ortho"))
    check(box == (16, 24, 47, 39) and n == 32 * 16,
          "the quad covers x 16..47, y 24..39 (%s, %d pixels)" % (box, n))
    # The asset's camera, rolled: the quad's long side now runs up the image.
    done = d.run(dict(BASE, technique="forward",
                      scene={"asset": "quad.glb", "width": W, "height": H}))
    check(done.get("status") == "done" and
          done["result"]["scene"]["camera"]["projection"] == "orthographic",
          "the asset's orthographic camera is drawn orthographic: %s"
          % done.get("result", {}).get("scene", {}).get("camera", {}).get("projection"))
    box, n = covered(capture(d, done, "ortho-asset"))
    check(box == (24, 16, 39, 47) and n == 16 * 32,
          "rolled 90 degrees, the asset camera sees the quad upright: x 24..39, y 16..47 "
          "(%s, %d pixels)" % (box, n))
    # An asset scene's look is display-referred by default.
    check(done["spec"]["look"]["tonemap"] == "pbr_neutral",
          "an asset scene's tone map defaults to pbr_neutral: %s" % done["spec"]["look"]["tonemap"])
    # The culling techniques under an orthographic view (their cells are
    # perspective frusta: every light is binned everywhere) draw what
    # forward draws: the teapots from above, 80 lights.
    top = {"eye": [0, 30, 0], "target": [0, 0, 0], "up": [0, 0, -1],
           "orthographic": {"ymag": 12}}
    for t in ("tiled_deferred", "clustered_forward"):
        done = d.run(dict(BASE, technique=t, reference="forward",
                          scene={"preset": "teapots", "width": 96, "height": 64, "camera": top}))
        q = done.get("result", {}).get("quality", {})
        ssim = q.get("worst_ssim", {}).get("value", 0)
        check(done.get("status") == "done" and ssim >= 0.999 and q.get("pdiff_failed_captures") == 0,
              "%s under an orthographic camera agrees with forward: SSIM %.5f, PerceptualDiff "
              "failures %s (%s)" % (t, ssim, q.get("pdiff_failed_captures"), done.get("error")))


def check_environment(d):
    good = hdr_gen.sky_and_ground()
    status, body = d.json("PUT", "/v1/assets/sky.hdr", good)
    desc = body.get("description", {})
    check(status == 201 and desc.get("kind") == "environment" and desc.get("width") == 64
          and desc.get("height") == 32 and body.get("format") == "hdr",
          "a Radiance .hdr uploads as an environment: %s %s" % (status, body))
    status, body = d.json("PUT", "/v1/assets/cut.hdr", good[:len(good) * 2 // 3])
    err = body.get("error", {})
    check(status == 422 and err.get("field") == "body" and "truncated" in err.get("message", ""),
          "a truncated .hdr is refused 422 naming where it ends: %s %s" % (status, err))
    huge = hdr_gen.hdr_bytes(8, 2, lambda x, y: (1, 1, 1), header_size=(100000, 50000))
    status, body = d.json("PUT", "/v1/assets/huge.hdr", huge)
    err = body.get("error", {})
    check(status == 422 and err.get("field") == "limits.max_environment_edge",
          "an .hdr claiming 100000 x 50000 pixels is refused 422 from its header: %s %s"
          % (status, err))
    # Looking along +x from 3 m up: the hot spot straight ahead, sky above.
    look = {"lighting": "pbr", "tonemap": "none",
            "ibl": {"environment": {"asset": "sky.hdr"}, "probes": 0, "resolution": 16,
                    "samples": 8}}
    cam = {"eye": [0, 3, 0], "target": [10, 3, 0], "yfov_deg": 60}
    done = d.run(dict(BASE, technique="forward", look=look,
                      scene={"preset": "sphere", "width": W, "height": H, "camera": cam}))
    if check(done.get("status") == "done", "a look with an uploaded environment renders: %s"
             % done.get("error")):
        px = capture(d, done, "env")
        centre, top = px[32 * W + 32], px[2 * W + 32]
        check(min(centre) >= 250, "the environment's hot spot (+x) is straight ahead: %s"
              % (centre,))
        check(top[2] > top[0] > 150, "its sky (blue over red) is above: %s" % (top,))
        env = done["spec"]["look"]["ibl"]["environment"]
        check(env.get("asset") == "sky.hdr" and len(env.get("asset_sha256", "")) == 64,
              "the spec pins the environment's hash: %s" % env)
    testlib.rejects(d, dict(BASE, technique="forward", scene={"asset": "sky.hdr"}),
                    "scene.asset")
    check_openexr(d, look, cam, px if done.get("status") == "done" else None)
    # Deleted, its files go: the upload, the cache and the description.
    status, body = d.json("GET", "/v1/assets/sky.hdr")
    sha = body.get("sha256", "")
    status, _ = d.json("DELETE", "/v1/assets/sky.hdr")
    left = [f for f in os.listdir(os.path.join(d.state, "assets")) if f.startswith(sha)]
    check(status == 200 and sha and not left,
          "a deleted environment leaves none of its files: %s %s" % (status, left))
    testlib.rejects(d, dict(BASE, technique="forward",
                            look={"lighting": "pbr",
                                  "ibl": {"environment": {"asset": "quad.glb"}}}),
                    "look.ibl.environment.asset")


def check_openexr(d, look, cam, hdr_pixels):
    """The same sky as OpenEXR: described, its Radiance copy written,
    rendered as the .hdr is; a truncated and a huge one refused."""
    variants = (("sky.exr", {}), ("sky_float.exr", {"compression": "none", "pixel_type": "float"}),
                ("sky_tiled.exr", {"compression": "zips", "tile": (16, 8)}),
                ("sky_grey.exr", {"channels": "Y"}))
    for name, kw in variants:
        status, body = d.json("PUT", "/v1/assets/" + name, hdr_gen.sky_and_ground_exr(**kw))
        desc = body.get("description", {})
        check(status == 201 and desc.get("kind") == "environment" and body.get("format") == "exr"
              and desc.get("format") == "openexr" and desc.get("viewer_copy") == "radiance_hdr"
              and (desc.get("width"), desc.get("height")) == (64, 32),
              "an OpenEXR image (%s) uploads as an environment with a Radiance copy for the "
              "viewer: %s %s" % (kw or "half, zip", status, body))
        sha = body.get("sha256", "")
        copy = os.path.join(d.state, "assets", sha + ".hdr")
        check(os.path.exists(copy) and open(copy, "rb").read(2) == b"#?",
              "%s: its Radiance copy is in the store (%s)" % (name, copy))
    if hdr_pixels is not None:
        for name in ("sky.exr", "sky_tiled.exr"):
            exr_look = dict(look, ibl=dict(look["ibl"], environment={"asset": name}))
            done = d.run(dict(BASE, technique="forward", look=exr_look,
                              scene={"preset": "sphere", "width": W, "height": H, "camera": cam}))
            if check(done.get("status") == "done", "a look with %s renders: %s"
                     % (name, done.get("error"))):
                px = capture(d, done, name)
                worst = max(max(abs(a - b) for a, b in zip(p, q)) for p, q in zip(px, hdr_pixels))
                check(worst <= 2, "%s renders as the same .hdr does: largest difference %d levels"
                      % (name, worst))
    good = hdr_gen.sky_and_ground_exr()
    status, body = d.json("PUT", "/v1/assets/cut.exr", good[:len(good) * 2 // 3])
    err = body.get("error", {})
    check(status == 422 and err.get("field") == "body" and "truncated" in err.get("message", ""),
          "a truncated .exr is refused 422 saying so: %s %s" % (status, err))
    huge = hdr_gen.exr_bytes(8, 2, lambda x, y: (1, 1, 1), header_size=(100000, 50000))
    status, body = d.json("PUT", "/v1/assets/huge.exr", huge)
    err = body.get("error", {})
    check(status == 422 and err.get("field") == "limits.max_environment_edge",
          "an .exr whose data window claims 100000 x 50000 pixels is refused 422 from its "
          "header: %s %s" % (status, err))
    status, body = d.json("GET", "/v1/assets/sky.exr")
    sha = body.get("sha256", "")
    status, _ = d.json("DELETE", "/v1/assets/sky.exr")
    left = [f for f in os.listdir(os.path.join(d.state, "assets")) if f.startswith(sha)]
    check(status == 200 and sha and not left,
          "a deleted OpenEXR environment leaves none of its files (the copy too): %s %s"
          % (status, left))


def main():
    d = testlib.Daemon()
    try:
        status, info = d.json("GET", "/v1/info")
        techniques = [t["name"] for t in info["techniques"] if t["name"] != "unlit"]
        check_light_rig(d, techniques)
        check_orthographic(d)
        check_environment(d)
        check(d.alive(), "the daemon serves on")
    finally:
        if d.stop() != 0:
            d.dump_log()
        d.cleanup(keep=testlib.failures > 0)
    testlib.finish("e2e_scene_view")


if __name__ == "__main__":
    main()
