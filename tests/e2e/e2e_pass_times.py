"""Per-pass GPU times that add up (issue #33).

Every technique, plain and with look.shadows, and the deferred and forward
families with image-based lighting and post effects:
- the passes of each timed frame add up to its gpu_ms (timings.csv, to the
  precision it is written with: a pass is the time between timestamps at its
  start and the next pass's, gpu_pass_timing says so);
- no pass is swallowed: the technique's passes that draw (all but the
  compute passes llvmpipe runs on the CPU at the dispatch, outside its GPU
  clock: OSL's lighting, the deferred family's edge classification) read at
  least 10 microseconds with shadows as without (forward's shading read
  0.000 ms with look.shadows, the shadow pass absorbing it);
- unlit, the cost floor, draws no shadow pass under look.shadows.
Counts and sums only: no wall-clock bound."""

import csv
import os

import testlib
from testlib import check

testlib.skip_without_egl()

TECHNIQUES = ["forward", "unlit", "osl", "deferred", "tiled_deferred", "forward_plus",
              "clustered_forward", "clustered_deferred"]
LOOKS = {
    "plain": {},
    "shadows": {"lighting": "pbr", "shadows": {"atlas": 512}},
    "ibl": {"lighting": "pbr", "ibl": {"probes": 1, "resolution": 16, "samples": 8}},
    "post": {"hdr": "rgba16f", "post": ["bloom", "toon", "ssao"]},
}
# Compute passes llvmpipe runs at the dispatch, on the calling thread.
CPU_SIDE = {("osl", "lighting")} | {(t, "edges") for t in ("deferred", "tiled_deferred",
                                                            "clustered_deferred")}


def job(tech, look):
    return {"technique": tech, "frames": 3, "warmup_frames": 1,
            "scene": {"preset": "teapots", "width": 48, "height": 32, "lights": 4},
            "look": look}


def rows(d, done):
    with open(os.path.join(d.state, "jobs", done["id"], "timings.csv")) as f:
        return list(csv.DictReader(f))


d = testlib.Daemon()
try:
    info = d.json("GET", "/v1/info")[1]
    own = {t["name"]: t.get("passes", []) for t in info.get("techniques", [])}
    cases = [(t, "plain") for t in TECHNIQUES] + [(t, "shadows") for t in TECHNIQUES]
    cases += [(t, l) for t in ("forward", "deferred") for l in ("ibl", "post")]
    shading = {}
    for tech, look in cases:
        done = d.run(job(tech, LOOKS[look]))
        what = "%s %s" % (tech, look)
        if not check(done.get("status") == "done", "%s runs: %s" % (what, done.get("error"))):
            continue
        res = done["result"]
        method = (res.get("gpu_pass_timing") or {}).get("method")
        sections = res.get("gpu_sections_ms") or {}
        worst = 0.0
        for r in rows(d, done):
            parts = sum(float(v) for k, v in r.items() if k.startswith("gpu_") and k.endswith("_ms")
                        and k != "gpu_ms")
            worst = max(worst, abs(parts - float(r["gpu_ms"])))
        check(method == "timestamps" and worst <= 1e-5 * max(1, len(sections)),
              "%s: the passes add up to gpu_ms in every frame (worst %.6f ms, %s)"
              % (what, worst, method))
        means = {k: v.get("mean", 0) for k, v in sections.items()}
        check(abs(sum(means.values()) - res.get("gpu_ms", {}).get("mean", -1)) <= 1e-6 * (1 + sum(means.values())),
              "%s: the passes' means add up to gpu_ms's: %s" % (what, means))
        drawn = [p for p in own.get(tech, []) if (tech, p) not in CPU_SIDE]
        empty = [p for p in drawn if means.get(p, 0) < 0.01]
        check(not empty, "%s: every pass of the technique is timed: %s empty in %s"
              % (what, empty, means))
        check(("shadows" in means) == (look == "shadows" and tech != "unlit"),
              "%s: a shadow pass exactly where the look draws one for a technique that reads "
              "light: %s" % (what, sorted(means)))
        if tech == "unlit" and look == "shadows":
            check("look_not_made" in res and res["look_not_made"].get("shadows") is True,
                  "unlit says it made no shadow maps: %s" % res.get("look_not_made"))
        if drawn:
            shading[(tech, look)] = means.get(drawn[-1], 0)
    for tech in TECHNIQUES:
        a, b = shading.get((tech, "plain")), shading.get((tech, "shadows"))
        if a and b is not None:
            print("%-20s last pass: %.3f ms plain, %.3f ms with shadows" % (tech, a, b))
finally:
    testlib.stop_and_check(d)
testlib.finish("e2e_pass_times")
