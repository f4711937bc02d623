"""Time in the frame contract and TAA (issue 37), on small frames:
- frame k is a pure function of k with TAA on: frame 10 is byte-identical
  after 2 or 7 warm-up frames, with a moving camera and a moving object,
  and the reference, which draws frame 10 in a new instance after its
  history frames, draws the same bytes;
- the harness's motion vectors: zero on a still scene; on an orbiting
  camera over the plane preset, their mean equals the mean computed here
  by hand from the camera's path (ray to the ground, back through the
  camera of the frame before); on a moving object, the moving pixels'
  mean equals the motion of its centre;
- TAA on a still scene is nearer the 4x supersampled truth than no
  anti-aliasing, and nearer with a longer history;
- ghosting is counted: in the band behind scene.mover the error against
  the truth is larger without clamping than with variance clipping, and
  flicker is reported beside MSAA 4's;
- every TAA pass is timed, result.time states the rule;
- issue 37's Done-when request (visibility buffer, TAA, the 4x truth, 8
  temporal frames, 256 lights on an orbit) reports its cost, its accuracy
  against the truth and its flicker;
- bad options are answered 400 naming the field."""

import math
import os

import testlib
from testlib import check

testlib.skip_without_egl()

W, H = 64, 48


def done_ok(d, job, what):
    done = d.run(job)
    check(done.get("status") == "done", "%s runs: %s" % (what, done.get("error")))
    return done.get("result", {}), done.get("id")


def fetch(d, result, what, index=-1, kind="url"):
    path = os.path.join(d.tmp, "%s-%d.png" % (what, len(os.listdir(d.tmp))))
    d.download(result["captures"][index][kind], path)
    return path


def same_bytes(a, b):
    with open(a, "rb") as f, open(b, "rb") as g:
        return f.read() == g.read()


# --- The camera by hand (daemon/scene/camera.c's orbit; GL conventions).
def sub(a, b):
    return [a[i] - b[i] for i in range(3)]


def dot(a, b):
    return sum(a[i] * b[i] for i in range(3))


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def unit(v):
    n = math.sqrt(dot(v, v))
    return [x / n for x in v]


def orbit_eye(cam, frame):
    c, d, el = cam["centre"], cam["distance"], math.radians(cam["elevation_deg"])
    e0 = cam["eye_at_frame_0"]
    az = math.atan2(e0[0] - c[0], e0[2] - c[2]) + 2 * math.pi * (frame % cam["period"]) / cam["period"]
    return [c[0] + d * math.cos(el) * math.sin(az), c[1] + d * math.sin(el),
            c[2] + d * math.cos(el) * math.cos(az)]


def basis(eye, target):
    f = unit(sub(target, eye))
    r = unit(cross(f, [0.0, 1.0, 0.0]))
    return f, r, cross(r, f)


def project(eye, target, fovy, point):
    """Window position (pixels, y up) of a world point."""
    f, r, u = basis(eye, target)
    v = sub(point, eye)
    t = math.tan(math.radians(fovy) / 2)
    z = dot(v, f)
    ndc = (dot(v, r) / z / (t * W / H), dot(v, u) / z / t)
    return ((ndc[0] * 0.5 + 0.5) * W, (ndc[1] * 0.5 + 0.5) * H)


def ground_motion(cam, k, half=40.0):
    """Mean motion (pixels, frame k minus k - 1) over every pixel centre of
    what it shows with the orbit's frames k and k - 1: the plane preset's
    ground (y = 0, half a side of `half`), else the far plane, where the
    depth buffer's background lies."""
    now, before = orbit_eye(cam, k), orbit_eye(cam, k - 1)
    target = cam["centre"]
    f, r, u = basis(now, target)
    t = math.tan(math.radians(cam["fovy_deg"]) / 2)
    sx = sy = 0.0
    for j in range(H):
        for i in range(W):
            nx = ((i + 0.5) / W) * 2 - 1
            ny = ((j + 0.5) / H) * 2 - 1
            d = [f[c] + r[c] * nx * t * W / H + u[c] * ny * t for c in range(3)]
            s = -now[1] / d[1] if d[1] < 0 else -1
            p = [now[c] + s * d[c] for c in range(3)]
            if s <= 0 or abs(p[0]) > half or abs(p[2]) > half or s > cam["far"]:
                p = [now[c] + cam["far"] * d[c] for c in range(3)]
            x, y = project(before, target, cam["fovy_deg"], p)
            sx += (i + 0.5) - x
            sy += (j + 0.5) - y
    return sx / (W * H), sy / (W * H)


d = testlib.Daemon()
try:
    taa8 = {"taa": {"history": 8}}
    scene = {"preset": "grid", "width": W, "height": H, "camera": {"path": "orbit", "period": 60},
             "mover": {"period": 24}, "dynamic": True}

    # Frame 10, after 2 and after 7 warm-up frames: the same bytes; and the
    # reference (the same technique and look) draws it again after its
    # history frames, in an instance of its own: the same bytes again.
    paths = []
    for warmup in (2, 7):
        job = {"frames": 10, "warmup_frames": warmup, "capture_interval": 10,
               "look": {"post": [taa8]}, "scene": scene, "reference": "forward",
               "reference_look": {"post": [taa8]}}
        result, _ = done_ok(d, job, "TAA after %d warm-up frames" % warmup)
        if result:
            paths.append(fetch(d, result, "w%d" % warmup))
            paths.append(fetch(d, result, "r%d" % warmup, kind="reference_url"))
            t = result.get("time", {})
            check(t.get("history_frames") == 8 and t.get("jitter", {}).get("length") == 8 and
                  t.get("motion_vectors") is True and "pure function" in t.get("rule", ""),
                  "result.time states the history, jitter and rule: %s" % t)
            passes = list(result.get("gpu_sections_ms", {}))
            check("motion_vectors" in passes and "taa.resolve" in passes and
                  passes.index("motion_vectors") < passes.index("taa.resolve"),
                  "motion vectors and TAA are timed passes, in frame order: %s" % passes)
    if check(len(paths) == 4, "four captures"):
        check(same_bytes(paths[0], paths[2]),
              "frame 10 with TAA is the same after 2 and 7 warm-up frames")
        check(same_bytes(paths[0], paths[1]) and same_bytes(paths[2], paths[3]),
              "the reference, drawing frame 10 after its history frames, draws the same bytes")
        # ...and TAA did something: without it frame 10 differs.
        result, _ = done_ok(d, {"frames": 10, "warmup_frames": 2, "capture_interval": 10,
                                "scene": scene}, "no TAA")
        if result:
            check(not same_bytes(paths[0], fetch(d, result, "plain")),
                  "TAA changes frame 10")

    # Motion vectors: none on a still scene; on the orbiting plane, the
    # mean computed by hand; on the moving object, its centre's motion.
    still = {"frames": 17, "warmup_frames": 0, "capture_interval": 17,
             "look": {"post": [{"taa": {"jitter_length": 0}}]}}
    result, _ = done_ok(d, dict(still, scene={"preset": "grid", "width": W, "height": H}),
                        "still scene")
    m = result.get("captures", [{}])[-1].get("motion", {})
    check(m.get("max_px") == 0 and m.get("moving_pixels") == 0,
          "a still scene has no motion: %s" % m)
    result, _ = done_ok(d, dict(still, scene={"preset": "plane", "width": W, "height": H,
                                              "camera": {"path": "orbit", "period": 90}}),
                        "orbiting camera")
    m = result.get("captures", [{}])[-1].get("motion", {})
    cam = result.get("scene", {}).get("camera", {})
    if check("mean_px" in m and "centre" in cam, "motion and the orbit are reported"):
        ex, ey = ground_motion(cam, 17)
        got = m["mean_px"]
        check(m["moving_pixels"] == W * H and math.hypot(ex, ey) > 0.2,
              "the orbit moves every pixel of the ground: %s, by hand %.3f %.3f" % (m, ex, ey))
        check(abs(got[0] - ex) < 0.02 + 0.01 * abs(ex) and abs(got[1] - ey) < 0.02 + 0.01 * abs(ey),
              "mean motion %.4f %.4f px equals the hand-computed %.4f %.4f" % (got[0], got[1], ex, ey))
    result, _ = done_ok(d, dict(still, scene={"preset": "grid", "width": W, "height": H,
                                              "mover": {"period": 30}}), "moving object")
    m = result.get("captures", [{}])[-1].get("motion", {})
    sc = result.get("scene", {})
    if check("mover" in sc and m.get("moving_pixels", 0) > 0, "the mover moves: %s" % m):
        mv, cam = sc["mover"], sc["camera"]

        def centre(frame):
            t = 2.0 * (frame % mv["period"]) / mv["period"]
            t = 2.0 - t if t > 1 else t
            p = [mv["from"][c] + t * (mv["to"][c] - mv["from"][c]) for c in range(3)]
            return project(cam["eye_at_frame_0"], cam["target_at_frame_0"], cam["fovy_deg"], p)
        a, b = centre(17), centre(16)
        ex, ey = a[0] - b[0], a[1] - b[1]
        n = m["moving_pixels"]
        mx, my = m["mean_px"][0] * W * H / n, m["mean_px"][1] * W * H / n
        check(abs(mx - ex) < 0.1 * abs(ex) + 0.05 and abs(my - ey) < 0.1 * abs(ex) + 0.05,
              "the moving pixels' mean motion %.3f %.3f is the centre's %.3f %.3f" % (mx, my, ex, ey))

    # TAA against the 4x supersampled truth on a still scene: nearer than
    # no anti-aliasing, and nearer after a longer history.
    # (Lights dim enough that the frame stays within the display's range:
    # TAA, like the MSAA resolve, averages before the tone curve, the truth
    # after it, and they part where highlights clip.)
    def truth(look, what):
        job = {"frames": 17, "warmup_frames": 0, "capture_interval": 17, "look": look,
               "reference": {"technique": "forward", "supersample": 4},
               "scene": {"preset": "lights", "lights": 32, "light_intensity": 0.3,
                         "width": W, "height": H}}
        q = done_ok(d, job, what)[0].get("quality", {})
        return (q.get("worst_ssim", {}).get("value", 0), q.get("worst_flip", {}).get("mean", 1),
                q.get("worst_psnr", {}).get("value", 0))
    none = truth({}, "no anti-aliasing")
    short = truth({"post": [{"taa": {"history": 2}}]}, "TAA, 2 frames of history")
    full = truth({"post": [{"taa": {"history": 16}}]}, "TAA, 16 frames of history")
    # (FLIP, which weighs the blur TAA trades for stability more at this
    # size, is docs/techniques.md's business: bench/bench_taa.py.)
    check(full[0] > none[0] + 0.005 and full[2] > none[2] + 1.0,
          "TAA is nearer the truth than none: SSIM, FLIP, PSNR %s against %s" % (full, none))
    check(full[0] > short[0] and full[2] > short[2],
          "TAA converges: 16 frames of history %s, 2 frames %s" % (full, short))

    # Ghosting behind the mover, against the truth: larger unclamped.
    def ghost(post, what, msaa=1):
        job = {"frames": 17, "warmup_frames": 0, "capture_interval": 17, "msaa": msaa,
               "look": {"post": post}, "temporal": {"frames": 2},
               "reference": {"technique": "forward", "supersample": 2},
               "scene": {"preset": "grid", "width": W, "height": H, "mover": {"period": 24}}}
        result, _ = done_ok(d, job, what)
        return result.get("captures", [{}])[-1].get("temporal", {})
    loose = ghost([{"taa": {"clamp": "none"}}], "TAA unclamped").get("ghosting") or {}
    tight = ghost([{"taa": {"clamp": "variance"}}], "TAA variance clipping").get("ghosting") or {}
    msaa = ghost([], "MSAA 4", msaa=4)
    check(loose.get("band_pixels", 0) > 20 and loose.get("band_error", 0) > loose.get("rest_error", 1),
          "unclamped TAA ghosts: band error above the rest's: %s" % loose)
    check(tight.get("band_error", 1) < loose.get("band_error", 0),
          "variance clipping ghosts less: %s < %s" % (tight.get("band_error"), loose.get("band_error")))
    check(isinstance(msaa.get("flicker"), float) and isinstance(msaa.get("ghosting"), dict),
          "MSAA 4 reports its flicker and band error beside TAA's: %s" % msaa)

    # Issue 37's request as users send it (the visibility buffer with TAA,
    # the 4x supersampled forward truth, 8 temporal frames, 256 lights on
    # an orbit), at a quarter of this test's size and its length: it reports its cost (the
    # estimate at submit, frame times, each pass's and the targets' bytes),
    # its accuracy against the truth and its flicker.
    issue = {"technique": "visibility_buffer", "look": {"post": ["taa"]},
             "reference": {"technique": "forward", "supersample": 4}, "temporal": {"frames": 8},
             "scene": {"preset": "lights", "lights": 256, "camera": "orbit",
                       "width": W // 2, "height": H // 2},
             "frames": 17, "warmup_frames": 0, "capture_interval": 17}
    code, reply = d.json("POST", "/v1/jobs", issue)
    check(code == 202 and reply.get("cost", {}).get("memory_bytes", 0) > 0 and
          reply.get("cost", {}).get("temporal_bytes", 0) > 0,
          "issue 37's request is accepted with its cost estimated: %d %s" % (code, reply))
    done = d.wait(reply["id"]) if code == 202 else {}
    check(done.get("status") == "done", "issue 37's request runs: %s" % done.get("error"))
    result = done.get("result", {})
    q, cap = result.get("quality", {}), (result.get("captures") or [{}])[-1]
    sections = result.get("gpu_sections_ms", {})
    check(result.get("frame_ms", {}).get("median", 0) > 0 and result.get("targets_bytes", 0) > 0 and
          all(p in sections for p in ("visibility", "shading", "motion_vectors", "taa.resolve")),
          "cost: frame times, targets' bytes and the visibility, shading, motion and TAA "
          "passes timed: %s" % list(sections))
    check(q.get("reference") == "forward" and q.get("reference_supersample") == 4 and
          0 < q.get("worst_ssim", {}).get("value", 0) < 1 and
          q.get("worst_flip", {}).get("mean", -1) > 0 and q.get("worst_psnr", {}).get("value", 0) > 0,
          "accuracy against the 4x supersampled truth: %s" % q)
    temporal = cap.get("temporal", {})
    check(isinstance(temporal.get("flicker"), float) and
          temporal.get("frames", [0, 0])[1] - temporal.get("frames", [0, 0])[0] == 7 and
          isinstance(q.get("worst_flicker", {}).get("value"), float) and
          result.get("temporal", {}).get("frames") == 8,
          "flicker over the 8 temporal frames: %s" % temporal)
    check("taa" in result.get("time", {}).get("reference", {}).get("antialiasing_left_out", ""),
          "the truth leaves TAA out and says so: %s" % result.get("time"))

    # Bad input, named.
    base = {"frames": 40, "warmup_frames": 16, "capture_interval": 40}
    for opt, value in (("blend", 0), ("clamp", "box"), ("jitter_length", 1000),
                       ("history", 0), ("filter", "lanczos"), ("gamma", -1)):
        testlib.rejects(d, dict(base, look={"post": [{"taa": {opt: value}}]}),
                        "look.post[0]." + opt)
    testlib.rejects(d, dict(base, capture_interval=10, look={"post": ["taa"]}), "capture_interval")
    testlib.rejects(d, {"frames": 10, "warmup_frames": 2, "capture_interval": 10,
                        "look": {"post": ["taa"]}}, "warmup_frames")
    testlib.rejects(d, {"scene": {"preset": "textured", "mover": True}}, "scene.mover")
    testlib.rejects(d, {"scene": {"mover": {"period": 0}}}, "scene.mover.period")
finally:
    testlib.stop_and_check(d)
testlib.finish("e2e_taa")
