#!/usr/bin/env python3
"""Upload and load time against asset size: glTF assets from a few MB to
about 100 MB (tests/e2e/gltf_gen.py's realistic asset: 98,304 triangles,
36 textures at 512 or 2048 texels; and the same geometry with incompressible
2K noise maps), each uploaded to one daemon, converted, and rendered by a
short job, --repeat times (the asset deleted between uploads, so every upload
converts again). Prints per asset:

  - bytes of the file and of the cache (decoded textures, flattened meshes);
  - upload: PUT /v1/assets/NAME's wall time as the client sees it: the body
    streamed and hashed, the converter run (checks, assimp, image decoding,
    uv1 charts, the cache written and synced), the record stored;
  - load: the job's result.scene.asset.load_ms: reading the cache, and
    building the scene and its GL objects (textures with mipmaps) up to a
    glFinish, before the warm-up, outside every timed region.

Medians over the repeats, with min and max.

  bench/bench_assets.py [--repeat R] [--no-noise] [--width W --height H]"""

import os
import random
import statistics
import struct
import sys
import tempfile
import time
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tests", "e2e"))
import benchrun  # noqa: E402
import gltf_gen  # noqa: E402
import testlib  # noqa: E402

ap = benchrun.parser()
ap.add_argument("--repeat", type=int, default=3)
ap.add_argument("--no-noise", action="store_true", help="leave out the ~100 MB noise asset")
ap.add_argument("--width", type=int, default=320)
ap.add_argument("--height", type=int, default=240)
args = ap.parse_args()


def noise_png(size, seed):
    """An RGBA PNG of deterministic noise: zlib cannot shrink it, so the file
    is about as large as its pixels (16 MiB at 2048)."""
    rng = random.Random(seed)
    raw = bytearray()
    row = size * 4
    for _ in range(size):
        raw.append(0)
        raw += rng.randbytes(row)
    ihdr = struct.pack(">IIBBBBB", size, size, 8, 6, 0, 0, 0)

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(bytes(raw), 1)) + \
        chunk(b"IEND", b"")


def noise_asset(maps=6):
    """The realistic asset's panels with `maps` 2K noise images spread over
    its materials as base colour and metallic-roughness maps."""
    g = gltf_gen.Gltf()
    images = [g.texture(g.image(noise_png(2048, k))) for k in range(maps)]
    for k in range(12):
        mat = g.material(name="noise%d" % k, pbrMetallicRoughness={
            "baseColorTexture": {"index": images[k % maps]},
            "metallicRoughnessTexture": {"index": images[(k + 1) % maps]}})
        mesh = g.mesh(gltf_gen.grid(64, z=0.0), material=mat, uv1=False, name="panel%d" % k)
        g.node(mesh=mesh, name="panel%d" % k, translation=[(k % 4) * 2.5, (k // 4) * 2.5, 0])
    return g.glb()


assets = [("realistic.glb", gltf_gen.realistic_asset(False).glb()),
          ("realistic_2k.glb", gltf_gen.realistic_asset(True).glb())]
if not args.no_noise:
    assets.append(("noise_2k.glb", noise_asset()))

bench = benchrun.Run()
d = testlib.Daemon()
rows = []
try:
    info = d.json("GET", "/v1/info")[1]["device"]
    print("device: %s | %s | %s" % (info["gl_renderer"], info["gl_version"], info["egl_device"]))
    bench.start()
    print()
    results = []
    for name, data in assets:
        up, read, build, cache = [], [], [], 0
        for rep in range(args.repeat):
            d.json("DELETE", "/v1/assets/" + name)
            t0 = time.time()
            status, body = d.json("PUT", "/v1/assets/" + name, data, timeout=900)
            up.append(time.time() - t0)
            if status not in (200, 201):
                sys.exit("%s: upload answered %d %s" % (name, status, body))
            sha = body["sha256"]
            cache = os.path.getsize(os.path.join(d.state, "assets", sha + ".sbasset"))
            done = d.wait(d.submit({"technique": "forward", "frames": 1, "warmup_frames": 0,
                                    "capture_interval": 0,
                                    "scene": {"asset": name, "lights": 16, "width": args.width,
                                              "height": args.height}}), timeout=900)
            if done.get("status") != "done":
                sys.exit("%s: job %s" % (name, done.get("error")))
            results.append(done["result"])
            lm = done["result"]["scene"]["asset"]["load_ms"]
            read.append(lm["read"] / 1e3)
            build.append(lm["scene_and_upload"] / 1e3)
        desc = body.get("description", {})
        rows.append((name, len(data), cache, desc.get("triangles", 0), len(desc.get("textures", [])),
                     up, read, build))
    bench.end(results)
finally:
    testlib.stop_and_check(d)


def mmm(v):
    return "%.2f (%.2f to %.2f)" % (statistics.median(v), min(v), max(v))


print()
print("| asset | file MB | cache MB | triangles | textures | upload s | cache read s | scene and GL upload s |")
print("|---|---|---|---|---|---|---|---|")
for name, size, cache, tris, texs, up, read, build in rows:
    print("| %s | %.1f | %.1f | %d | %d | %s | %s | %s |" % (name, size / 1e6, cache / 1e6, tris, texs,
                                                           mmm(up), mmm(read), mmm(build)))
