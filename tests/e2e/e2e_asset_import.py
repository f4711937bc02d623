#!/usr/bin/env python3
"""What a glTF file states, imported as it states it (issue 32), end to end:
gltf_gen.py's fidelity pairs uploaded through PUT /v1/assets, converted and
rendered by forward at 128x96; each pair says one thing two ways, and a
correct importer draws both halves alike (SSIM >= PAIR_BOUND, lit and in
look.debug's channels):
- node transforms (a quarter turn about x, rotation with non-uniform scale,
  mirrored nodes, a child under a rotated parent; as matrices and as
  translation/rotation/scale) against the same transforms baked into the
  vertices: normals by the inverse transpose, tangents with their
  handedness turned and the winding reversed where a node mirrors;
- base colour, occlusion and emissive maps reading TEXCOORD_1 against the
  same values as TEXCOORD_0, with TEXCOORD_1 inside [0, 1] and outside it
  (where the converter generates object-space shading's uv1, which no
  material may read);
- COLOR_0 (unsigned-byte VEC4, float VEC3) against the same colours as base
  colour factors;
- KHR_texture_transform (offset, rotation, scale, a texCoord override)
  against the coordinates it produces;
- a mesh without normals (glTF: flat ones) against its triangles unwelded
  with their face normals stated;
- a double-sided, normal-mapped plate seen from behind against the same
  plate rebuilt to face the viewer with normal, tangent and handedness
  reversed (glTF reverses a back face's normal, the normal map's too);
every technique draws the same channel image (the look's debug pass), and
OSL, which bakes the material into its atlas, draws the texCoord, COLOR_0
and transform pairs' halves alike too;
and look.debug's channels are the viewer's encodings at known pixels:
base_color of a COLOR_0 box, the grey checks where a mesh has no
TEXCOORD_1, normals as n * 0.5 + 0.5, alpha 1 for opaque materials; a
cache an older shadebench wrote is converted anew when uploaded again."""

import json
import os
import struct
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gltf_gen  # noqa: E402
import testlib  # noqa: E402
from testlib import check  # noqa: E402

testlib.skip_without_egl()

PAIR_BOUND = 0.999
COMPARE = os.environ.get("SHADEBENCH_COMPARE", "./shadebench-compare")
SCENE = {"width": 128, "height": 96}
JOB = {"frames": 1, "warmup_frames": 0, "capture_interval": 1, "technique": "forward"}


def frame(d, job):
    done = d.run(job)
    if not check(done.get("status") == "done", "%s renders: %s" % (json.dumps(job), done.get("error"))):
        return None
    return os.path.join(d.state, "jobs", done["id"], "frame-000001.png")


def ssim(a, b):
    if not a or not b:
        return 0.0
    out = subprocess.run([COMPARE, a, b, "--metrics", "ssim"], capture_output=True, text=True)
    try:
        return json.loads(out.stdout)["ssim"]
    except (ValueError, KeyError):
        return 0.0


def pixel(path, x, y):
    if not path:
        return None
    w, h, px = testlib.png_pixels(path)
    return px[y * w + x]


def main():
    out = tempfile.mkdtemp(prefix="shadebench-import-")
    pairs = gltf_gen.fidelity_pairs()
    d = testlib.Daemon()
    try:
        for name, (a, b) in pairs.items():
            for half, g in (("a", a), ("b", b)):
                status, body = d.json("PUT", "/v1/assets/%s_%s.glb" % (name, half), g.glb())
                check(status == 201, "upload %s_%s: %d %s" % (name, half, status, body.get("error")))

        looks = {"phong": {}, "pbr": {"lighting": "pbr"}}
        for name in pairs:
            for look_name, look in looks.items():
                if look_name == "pbr" and name != "transforms":
                    continue
                shots = [frame(d, dict(JOB, look=look, scene=dict(SCENE, asset="%s_%s.glb" % (name, h))))
                         for h in ("a", "b")]
                s = ssim(shots[1], shots[0])
                print("%s (%s): SSIM %.5f" % (name, look_name, s), flush=True)
                check(s >= PAIR_BOUND, "%s, %s: the two halves render alike: SSIM %.5f >= %s"
                      % (name, look_name, s, PAIR_BOUND))

        # The channels behind them, pair by pair.
        channels = {"transforms": ["shading_normal", "geometric_normal", "tangent"],
                    "texcoord1_outside": ["occlusion", "base_color", "emissive"],
                    "colors": ["base_color"], "texture_transform": ["base_color"],
                    "flat_normals": ["geometric_normal"], "back_face": ["shading_normal"]}
        for name, chans in channels.items():
            for ch in chans:
                shots = [frame(d, dict(JOB, look={"debug": ch},
                                       scene=dict(SCENE, asset="%s_%s.glb" % (name, h)))) for h in ("a", "b")]
                s = ssim(shots[1], shots[0])
                print("%s, look.debug %s: SSIM %.5f" % (name, ch, s), flush=True)
                check(s >= PAIR_BOUND, "%s, look.debug %s: the two halves alike: SSIM %.5f" % (name, ch, s))

        # Object-space shading bakes the material into its atlas and applies
        # base colour per pixel: it reads the same texCoord sets, COLOR_0 and
        # texture transforms, so it too draws both halves alike (before its
        # shaders read them, 0.988, 0.998 and 0.986).
        for name in ("texcoord1_outside", "colors", "texture_transform"):
            shots = [frame(d, dict(JOB, technique="osl",
                                   scene=dict(SCENE, asset="%s_%s.glb" % (name, h)))) for h in ("a", "b")]
            s = ssim(shots[1], shots[0])
            print("%s (osl): SSIM %.5f" % (name, s), flush=True)
            check(s >= PAIR_BOUND, "%s, osl: the two halves render alike: SSIM %.5f >= %s"
                  % (name, s, PAIR_BOUND))

        # The channels are the shared surface's: every technique draws the
        # same image of one.
        techniques = [t["name"] for t in d.json("GET", "/v1/info")[1]["techniques"]]
        scene = dict(SCENE, asset="back_face_a.glb")
        ref = frame(d, dict(JOB, look={"debug": "shading_normal"}, scene=scene))
        for t in techniques:
            if t == "forward":
                continue
            shot = frame(d, dict(JOB, technique=t, look={"debug": "shading_normal"}, scene=scene))
            diff = testlib.png_diff(ref, shot) if ref and shot else None
            check(diff is not None and diff["differing_pixels"] == 0,
                  "%s's shading_normal channel is forward's: %s" % (t, diff))

        # The encodings at known pixels. The colours pair's left box is
        # COLOR_0 (200, 120, 60) / 255 over a white and grey checker: its
        # base colour channel is the linear colour to the power 1 / 2.2.
        scene = dict(SCENE, asset="colors_a.glb")
        base = frame(d, dict(JOB, look={"debug": "base_color"}, scene=scene))
        uv1 = frame(d, dict(JOB, look={"debug": "uv1"}, scene=scene))
        normal = frame(d, dict(JOB, look={"debug": "geometric_normal"}, scene=scene))
        alpha = frame(d, dict(JOB, look={"debug": "alpha"}, scene=scene))
        if base and uv1 and normal and alpha:
            w, h, px = testlib.png_pixels(base)
            want = [round(255 * (c / 255) ** (1 / 2.2)) for c in (200, 120, 60)]
            hits = sum(1 for p in px if all(abs(p[k] - want[k]) <= 1 for k in range(3)))
            check(hits > 50, "base_color: %d pixels of the COLOR_0 box's %s (factor, white texel, "
                  "gamma 2.2)" % (hits, want))
            # No TEXCOORD_1 on these boxes: the viewer's grey checks, 0.9 or
            # 1.0, where the boxes are.
            _, _, upx = testlib.png_pixels(uv1)
            _, _, npx = testlib.png_pixels(normal)
            drawn = [i for i, p in enumerate(npx) if p != (0, 0, 0)]
            greys = sum(1 for i in drawn if upx[i] in ((229, 229, 229), (230, 230, 230), (255, 255, 255)))
            check(drawn and greys == len(drawn),
                  "uv1 without TEXCOORD_1: the grey checks on all %d drawn pixels (%d)" % (len(drawn), greys))
            # Normals n * 0.5 + 0.5: unit length once decoded.
            lengths = [sum(((c / 255) * 2 - 1) ** 2 for c in npx[i]) ** 0.5 for i in drawn]
            check(lengths and all(abs(L - 1) < 0.03 for L in lengths),
                  "geometric_normal decodes to unit vectors: %.3f to %.3f"
                  % (min(lengths or [0]), max(lengths or [0])))
            _, _, apx = testlib.png_pixels(alpha)
            check(all(apx[i] == (255, 255, 255) for i in drawn), "alpha of opaque materials is 1")

        # A cache an older shadebench wrote (version 1): a job says to upload
        # again, and the upload converts anew.
        status, body = d.json("GET", "/v1/assets/colors_a.glb")
        cache = os.path.join(d.state, "assets", "%s.sbasset" % body.get("sha256", "none"))
        if check(os.path.exists(cache), "the cache of colors_a.glb is %s" % cache):
            with open(cache, "r+b") as f:
                f.seek(8)
                f.write(struct.pack("<I", 1))
            done = d.run(dict(JOB, scene=dict(SCENE, asset="colors_a.glb")))
            check(done.get("status") == "failed" and "upload the asset again" in str(done.get("error")),
                  "a job on a version 1 cache fails saying what to do: %s" % done.get("error"))
            status, _ = d.json("PUT", "/v1/assets/colors_a.glb", pairs["colors"][0].glb())
            done = d.run(dict(JOB, scene=dict(SCENE, asset="colors_a.glb")))
            check(status in (200, 201) and done.get("status") == "done",
                  "uploaded again, it converts anew and renders: %d %s" % (status, done.get("error")))

        # A debug channel refuses post effects, naming the field.
        testlib.rejects(d, dict(JOB, scene=dict(SCENE, asset="colors_a.glb"),
                                look={"debug": "uv0", "post": ["bloom"]}), "look.post")
        testlib.rejects(d, dict(JOB, scene=dict(SCENE, asset="colors_a.glb"),
                                look={"debug": "normals"}), "look.debug")
    finally:
        testlib.stop_and_check(d)
    testlib.finish("e2e_asset_import")


main()
