"""A supersampled reference and temporal stability (issue 22): the
reference rendered at N x N and box-filtered is served at the job's size
and scores forward below forward's own image; bad values name
reference.supersample; flicker is 0 for forward against itself and grows
with OSL's async distance; sweeps vary reference.supersample, judge
"ssim >= X" and bisect "flicker_max <= X"."""

import os

import testlib
from testlib import check

testlib.skip_without_egl()
SCENE = {"width": 128, "height": 96, "lights": 6, "dynamic": True, "light_speed": 4,
         "sphere_segments": 8}
JOB = {"frames": 8, "warmup_frames": 0, "capture_interval": 4, "scene": SCENE}

d = testlib.Daemon()
try:
    # forward against forward: exact, and the spec keeps the shorthand.
    plain = d.run(dict(JOB, technique="forward", reference="forward"))
    check(plain["status"] == "done", "forward vs forward done: %s" % plain.get("error"))
    check(plain["spec"]["reference"] == "forward", "the shorthand stays a string")
    check(plain["result"]["quality"]["worst_ssim"]["value"] == 1.0, "forward vs forward is exact")
    check(plain["result"]["quality"].get("reference_supersample") == 1, "factor 1 recorded")

    # forward against forward supersampled 4x4: the reference is the job's
    # size, not identical, and scores lower.
    ss = d.run(dict(JOB, technique="forward", reference={"technique": "forward", "supersample": 4}))
    check(ss["status"] == "done", "forward vs forward x4 done: %s" % ss.get("error"))
    check(ss["spec"]["reference"] == {"technique": "forward", "supersample": 4},
          "the spec records the reference and its factor: %s" % ss["spec"].get("reference"))
    q = ss["result"]["quality"]
    check(q["reference"] == "forward" and q["reference_supersample"] == 4,
          "the result records technique and factor: %s" % q)
    caps = ss["result"]["captures"]
    check(len(caps) == 2, "two captures")
    for c in caps:
        path = os.path.join(d.tmp, "ref-%d.png" % c["frame"])
        check(d.download(c["reference_url"], path) == 200, "reference %d downloads" % c["frame"])
        info = testlib.png_info(path)
        check(info and (info["width"], info["height"]) == (128, 96),
              "the supersampled reference is the job's size: %s" % info)
        m = c["metrics"]
        check(m["psnr"]["identical"] is False, "not identical to forward's own frame")
        check(m["ssim"] < 0.995, "aliasing shows against the true image: SSIM %s" % m["ssim"])
    check(q["worst_ssim"]["value"] < plain["result"]["quality"]["worst_ssim"]["value"],
          "forward scores lower against x4 than against itself")
    # 2x2 too is not forward's own image (SSIM need not be monotone in N:
    # the sample positions differ, measured 0.936 at 2x2 against 0.941 at 4x4).
    ss2 = d.run(dict(JOB, technique="forward", reference={"technique": "forward", "supersample": 2}))
    check(ss2["status"] == "done", "x2 done")
    check(ss2["result"]["quality"]["worst_ssim"]["value"] < 0.995,
          "SSIM against x2: %s" % ss2["result"]["quality"]["worst_ssim"]["value"])

    # Bad values: 400 naming the field.
    for bad in (0, 5, 2.5, "4", None):
        testlib.rejects(d, dict(JOB, reference={"technique": "forward", "supersample": bad}),
                        "reference.supersample")
    testlib.rejects(d, dict(JOB, reference={"technique": "nope"}), "reference.technique")
    testlib.rejects(d, dict(JOB, reference={"technique": "forward", "factor": 2}), "reference.factor")
    testlib.rejects(d, dict(JOB, reference="forward", temporal={"frames": 1}), "temporal.frames")
    testlib.rejects(d, dict(JOB, reference="forward", temporal={"frames": 17}), "temporal.frames")
    testlib.rejects(d, dict(JOB, temporal={"frames": 4}), "temporal")

    # Flicker: forward against itself is 0 at every capture.
    ff = d.run(dict(JOB, technique="forward", reference="forward", temporal={"frames": 6}))
    check(ff["status"] == "done", "forward temporal done: %s" % ff.get("error"))
    for c in ff["result"]["captures"]:
        t = c.get("temporal", {})
        check(t.get("flicker") == 0.0 and t.get("frames") == [c["frame"], c["frame"] + 5],
              "forward vs forward flicker 0 over 6 frames: %s" % t)
    check(ff["result"]["quality"]["worst_flicker"]["value"] == 0.0, "worst flicker 0")
    check(ff["result"]["temporal"]["frames"] == 6 and "tLP" in ff["result"]["temporal"]["measure"],
          "result.temporal states the measure")

    # OSL: async shading at d = 8 holds objects' shading for several frames
    # and pops; d = 0 reshades every frame. Its flicker grows.
    flicker = {}
    for dist in (0, 8):
        j = d.run(dict(JOB, technique="osl", osl={"async_distance": dist, "resolution": 32},
                       reference="forward", temporal={"frames": 6}))
        check(j["status"] == "done", "osl d=%d temporal done: %s" % (dist, j.get("error")))
        flicker[dist] = j["result"]["quality"]["worst_flicker"]["value"]
    check(flicker[8] > 3 * flicker[0] and flicker[8] > 1e-4,
          "OSL's flicker grows with async distance: %s" % flicker)

    # SSAO with few samples shimmers as the camera moves: against 64 samples,
    # 4 flicker more than 32 (0.00049 and 0.00029 when written).
    ssao = {}
    for n in (4, 32):
        j = d.run({"technique": "forward", "frames": 4, "warmup_frames": 0, "capture_interval": 4,
                   "reference": "forward", "temporal": {"frames": 6}, "metrics": ["ssim"],
                   "look": {"post": [{"ssao": {"samples": n}}]},
                   "reference_look": {"post": [{"ssao": {"samples": 64}}]},
                   "scene": {"preset": "grid", "width": 160, "height": 120, "camera": "orbit"}})
        ssao[n] = (j.get("result", {}).get("quality", {}).get("worst_flicker") or {}).get("value")
    print("SSAO flicker against 64 samples: %s" % ssao)
    check(ssao[4] is not None and ssao[32] is not None and ssao[4] > 1.2 * ssao[32],
          "SSAO at 4 samples flickers more than at 32: %s" % ssao)

    # Sweeps: reference.supersample as an axis (each factor its own
    # workload: forward is exact only against x1) ...
    code, reply = d.json("POST", "/v1/sweeps", {
        "base": dict(JOB, technique="forward", reference="forward"),
        "vary": {"reference.supersample": [1, 2]}, "time_reference": False})
    check(code == 202, "sweep over reference.supersample accepted: %s" % reply)
    sw = d.wait_sweep(reply["id"])
    rows = sw.get("points", [])
    check(sw["status"] == "done" and len(rows) == 2, "two points: %s" % sw.get("error"))
    by = {r["values"]["reference.supersample"]: r for r in rows}
    check(by[1]["worst_ssim"] == 1.0 and by[2]["worst_ssim"] < 1.0,
          "x1 exact, x2 not: %s" % {k: v.get("worst_ssim") for k, v in by.items()})
    # ... and a find on flicker_max over the light speed: OSL at d = 8
    # holds below a bound while the lights are still and fails once they move fast.
    code, reply = d.json("POST", "/v1/sweeps", {
        "base": dict(JOB, technique="osl", osl={"async_distance": 8, "resolution": 32},
                     reference="forward", temporal={"frames": 4}),
        "find": {"param": "scene.light_speed", "from": 0, "to": 8,
                 "while": "flicker_max <= 0.0003", "steps": 3}})
    check(code == 202, "find on flicker_max accepted: %s" % reply)
    sw = d.wait_sweep(reply["id"])
    bp = sw.get("result", {}).get("breaking_point", {})
    check(sw["status"] == "done" and bp.get("outcome") == "boundary" and 0 <= bp.get("value", -1) < 8,
          "flicker_max finds a boundary: %s" % bp)
    check(all("worst_flicker" in r for r in sw["points"]), "rows carry worst_flicker")
    # ... and a find on the mean SSIM (the thesis's measure): where OSL at
    # d = 8 drops below 0.999 as its lights speed up (0.99997 still, 0.9988
    # at speed 1, 0.963 at 8).
    code, reply = d.json("POST", "/v1/sweeps", {
        "base": dict(JOB, technique="osl", osl={"async_distance": 8, "resolution": 32},
                     reference="forward", metrics=["ssim"]),
        "find": {"param": "scene.light_speed", "from": 0, "to": 8,
                 "while": "ssim >= 0.999", "steps": 6}})
    check(code == 202, "find on the mean SSIM accepted: %s" % reply)
    sw = d.wait_sweep(reply["id"])
    bp = sw.get("result", {}).get("breaking_point", {})
    check(sw["status"] == "done" and bp.get("outcome") == "boundary" and
          0 <= bp.get("value", -1) < 1 and bp.get("value", 9) < bp.get("first_failing", -1) <= 1,
          "ssim >= 0.999 brackets a boundary below light speed 1: %s" % bp)
    code, reply = d.json("POST", "/v1/sweeps", {
        "base": dict(JOB, technique="osl"), "find": {"param": "scene.light_speed", "from": 0, "to": 8,
                                                      "while": "flicker_max <= 0.01"}})
    check(code == 400 and reply["error"]["field"] == "find.while" and "temporal" in reply["error"]["message"],
          "flicker_max without base.temporal is refused: %s" % reply)
    code, reply = d.json("POST", "/v1/sweeps", {
        "base": dict(JOB, technique="forward"), "find": {"param": "scene.light_speed", "from": 0, "to": 8,
                                                          "while": "ssim >= 2"}})
    check(code == 400 and reply["error"]["field"] == "find.while", "ssim >= 2 refused: %s" % reply)
finally:
    testlib.stop_and_check(d)
testlib.finish("e2e_reference_temporal")
