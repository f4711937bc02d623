#!/usr/bin/env python3
"""glTF 2.0 test assets, made from nothing (standard library only; PIL for
the one JPEG case, when it is installed).

    python3 tests/e2e/gltf_gen.py --out DIR [--realistic] [--big-maps]

writes the good and bad assets into DIR with manifest.json, which says for
each file what shadebench-asset must answer: the exit code, and for a
refusal the status and field, for a good asset the figures its description
must show. Importable: build_all(out_dir, realistic=False, big_maps=False)
returns the manifest; Gltf is the builder the assets are written with.

Patterns are known: the base colour texture is BASE_TEXEL everywhere but a
2x2 checker in its top-left corner, so a decoded texel can be checked
exactly.
"""
import argparse
import base64
import json
import math
import os
import struct
import zlib

BASE_TEXEL = (200, 100, 50, 255)  # sRGB, the flat region of the base colour map


def png_bytes(width, height, rows):
    """An 8-bit RGBA PNG; rows is a list of height bytes objects of width*4."""
    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)
    raw = b"".join(b"\x00" + r for r in rows)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw, 1)) + chunk(b"IEND", b""))


def png_header_only(width, height):
    """A PNG whose IHDR claims width x height, with no image data: the
    converter must refuse it from the header, before decoding."""
    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0))
            + chunk(b"IEND", b""))


def base_color_png(size=8):
    rows = []
    for y in range(size):
        row = bytearray()
        for x in range(size):
            if x < 2 and y < 2:
                row += bytes((255, 255, 255, 255) if (x + y) % 2 == 0 else (0, 0, 0, 255))
            else:
                row += bytes(BASE_TEXEL)
        rows.append(bytes(row))
    return png_bytes(size, size, rows)


def pattern_png(size, rgba_a, rgba_b, cell=8):
    """A checker of two colours; rows repeat, so even 2K maps are quick."""
    a, b = bytes(rgba_a), bytes(rgba_b)
    row0 = b"".join((a if (x // cell) % 2 == 0 else b) for x in range(size))
    row1 = b"".join((b if (x // cell) % 2 == 0 else a) for x in range(size))
    return png_bytes(size, size, [row0 if (y // cell) % 2 == 0 else row1 for y in range(size)])


# A 16x16 baseline JPEG of (30, 160, 90), quality 95, made for this file
# with libjpeg-turbo's jpeg_mem_dest (288 bytes): the JPEG case where PIL is
# not installed (Python has no JPEG encoder of its own).
SOLID16_JPEG = base64.b64decode(
    "/9j/4AAQSkZJRgABAQAAAQABAAD/2wBDAAIBAQEBAQIBAQECAgICAgQDAgICAgUEBAMEBg"
    "UGBgYFBgYGBwkIBgcJBwYGCAsICQoKCgoKBggLDAsKDAkKCgr/2wBDAQICAgICAgUDAwUK"
    "BwYHCgoKCgoKCgoKCgoKCgoKCgoKCgoKCgoKCgoKCgoKCgoKCgoKCgoKCgoKCgoKCgoKCg"
    "r/wAARCAAQABADASIAAhEBAxEB/8QAFQABAQAAAAAAAAAAAAAAAAAAAAb/xAAUEAEAAAAA"
    "AAAAAAAAAAAAAAAA/8QAFQEBAQAAAAAAAAAAAAAAAAAABgj/xAAUEQEAAAAAAAAAAAAAAA"
    "AAAAAA/9oADAMBAAIRAxEAPwCDAC0Jv//Z")


def jpeg_bytes(size=16):
    try:
        from PIL import Image  # only for the JPEG case
    except ImportError:
        return SOLID16_JPEG if size == 16 else None
    import io
    im = Image.new("RGB", (size, size), (30, 160, 90))
    buf = io.BytesIO()
    im.save(buf, format="JPEG", quality=95)
    return buf.getvalue()


class Gltf:
    """A glTF document and its one binary buffer."""

    def __init__(self):
        self.bin = bytearray()
        self.doc = {"asset": {"version": "2.0", "generator": "shadebench gltf_gen.py"},
                    "scene": 0, "scenes": [{"nodes": []}], "nodes": [], "meshes": [],
                    "buffers": [], "bufferViews": [], "accessors": []}

    def _list(self, key):
        return self.doc.setdefault(key, [])

    def view(self, data, stride=None):
        while len(self.bin) % 4:
            self.bin.append(0)
        v = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data)}
        if stride:
            v["byteStride"] = stride
        self.bin += data
        self.doc["bufferViews"].append(v)
        return len(self.doc["bufferViews"]) - 1

    def accessor(self, values, ctype, atype, count):
        fmt = {5126: "f", 5125: "I", 5123: "H", 5121: "B"}[ctype]
        data = struct.pack("<%d%s" % (len(values), fmt), *values)
        acc = {"bufferView": self.view(data), "componentType": ctype, "type": atype, "count": count}
        if atype == "VEC3" and ctype == 5126:
            acc["min"] = [min(values[i::3]) for i in range(3)]
            acc["max"] = [max(values[i::3]) for i in range(3)]
        self.doc["accessors"].append(acc)
        return len(self.doc["accessors"]) - 1

    def mesh(self, geom, material=None, uv1=True, tangents=False, name=None, mode=None,
             colors=None, normals=True):
        """geom: (positions, normals, uv0, uv1, indices[, tangents]); tangents
        True writes the geometry's own (or (1, 0, 0, 1) where it has none);
        colors: (values, componentType, "VEC3" or "VEC4") for COLOR_0."""
        pos, nrm, uv0, uv1v, idx = geom[:5]
        n = len(pos) // 3
        attrs = {"POSITION": self.accessor(pos, 5126, "VEC3", n),
                 "TEXCOORD_0": self.accessor(uv0, 5126, "VEC2", n)}
        if normals:
            attrs["NORMAL"] = self.accessor(nrm, 5126, "VEC3", n)
        if uv1:
            attrs["TEXCOORD_1"] = self.accessor(uv1v, 5126, "VEC2", n)
        if tangents:
            tan = list(geom[5]) if len(geom) > 5 else [1.0, 0.0, 0.0, 1.0] * n
            attrs["TANGENT"] = self.accessor(tan, 5126, "VEC4", n)
        if colors:
            values, ctype, atype = colors
            if ctype != 5126:
                values = list(values) + [0] * (-len(values) % 4)
            attrs["COLOR_0"] = self.accessor(values, ctype, atype, n)
            if ctype != 5126:
                self.doc["accessors"][attrs["COLOR_0"]]["normalized"] = True
        prim = {"attributes": attrs,
                "indices": self.accessor(idx, 5125 if n > 65535 else 5123, "SCALAR", len(idx))}
        if material is not None:
            prim["material"] = material
        if mode is not None:
            prim["mode"] = mode
        m = {"primitives": [prim]}
        if name:
            m["name"] = name
        self.doc["meshes"].append(m)
        return len(self.doc["meshes"]) - 1

    def node(self, root=True, **kw):
        self.doc["nodes"].append(kw)
        i = len(self.doc["nodes"]) - 1
        if root:
            self.doc["scenes"][0]["nodes"].append(i)
        return i

    def image(self, data, mime="image/png", name=None):
        img = {"bufferView": self.view(data), "mimeType": mime}
        if name:
            img["name"] = name
        self._list("images").append(img)
        return len(self.doc["images"]) - 1

    def texture(self, image, sampler=None):
        t = {"source": image}
        if sampler is not None:
            t["sampler"] = sampler
        self._list("textures").append(t)
        return len(self.doc["textures"]) - 1

    def material(self, **kw):
        self._list("materials").append(kw)
        return len(self.doc["materials"]) - 1

    def light(self, **kw):
        self.doc.setdefault("extensions", {}).setdefault("KHR_lights_punctual", {"lights": []})
        lights = self.doc["extensions"]["KHR_lights_punctual"]["lights"]
        lights.append(kw)
        used = self.doc.setdefault("extensionsUsed", [])
        if "KHR_lights_punctual" not in used:
            used.append("KHR_lights_punctual")
        return len(lights) - 1

    def finish_buffer(self):
        while len(self.bin) % 4:
            self.bin.append(0)
        self.doc["buffers"] = [{"byteLength": len(self.bin)}]

    def glb(self):
        self.finish_buffer()
        js = json.dumps(self.doc, separators=(",", ":")).encode()
        js += b" " * (-len(js) % 4)
        out = struct.pack("<I I", len(js), 0x4E4F534A) + js
        out += struct.pack("<I I", len(self.bin), 0x004E4942) + bytes(self.bin)
        return b"glTF" + struct.pack("<I I", 2, 12 + len(out)) + out

    def gltf_data_uri(self):
        """The same document as .gltf JSON, its buffer and images as data URIs."""
        self.finish_buffer()
        doc = json.loads(json.dumps(self.doc))
        for img in doc.get("images", []):
            if "bufferView" not in img:
                continue
            v = doc["bufferViews"][img["bufferView"]]
            data = bytes(self.bin[v["byteOffset"]:v["byteOffset"] + v["byteLength"]])
            del img["bufferView"]
            img["uri"] = "data:%s;base64,%s" % (img.pop("mimeType", "image/png"),
                                                base64.b64encode(data).decode())
        doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + \
            base64.b64encode(bytes(self.bin)).decode()
        return json.dumps(doc, indent=1).encode()


def cube(size=1.0, chart_uv1=True):
    """24 vertices, 12 triangles; uv1 puts the 6 faces in a 3x2 grid."""
    faces = [((1, 0, 0), (0, 0, -1), (0, 1, 0)), ((-1, 0, 0), (0, 0, 1), (0, 1, 0)),
             ((0, 1, 0), (1, 0, 0), (0, 0, -1)), ((0, -1, 0), (1, 0, 0), (0, 0, 1)),
             ((0, 0, 1), (1, 0, 0), (0, 1, 0)), ((0, 0, -1), (-1, 0, 0), (0, 1, 0))]
    pos, nrm, uv0, uv1, idx = [], [], [], [], []
    h = size / 2
    for f, (n, u, v) in enumerate(faces):
        base = len(pos) // 3
        cx, cy = f % 3, f // 3
        for (a, b) in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
            pos += [h * (n[k] + a * u[k] + b * v[k]) for k in range(3)]
            nrm += list(map(float, n))
            uv0 += [(a + 1) / 2, 1 - (b + 1) / 2]
            uv1 += [(cx + 0.05 + 0.9 * (a + 1) / 2) / 3, (cy + 0.05 + 0.9 * (1 - (b + 1) / 2)) / 2]
        idx += [base, base + 1, base + 2, base, base + 2, base + 3]
    return pos, nrm, uv0, uv1, idx


def grid(n, size=2.0, z=0.0):
    """An n x n quad grid in the xy plane facing +z: 2 n^2 triangles."""
    pos, nrm, uv0, uv1, idx = [], [], [], [], []
    for j in range(n + 1):
        for i in range(n + 1):
            pos += [size * (i / n - 0.5), size * (j / n - 0.5), z + 0.05 * math.sin(i * 0.7 + j * 0.3)]
            nrm += [0.0, 0.0, 1.0]
            uv0 += [i / n, 1 - j / n]
            uv1 += [i / n, 1 - j / n]
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            idx += [a, a + 1, a + n + 2, a, a + n + 2, a + n + 1]
    return pos, nrm, uv0, uv1, idx


def textured(normal_map=True, uv1=False):
    g = Gltf()
    smp = g._list("samplers")
    smp.append({"magFilter": 9728, "minFilter": 9728, "wrapS": 33071, "wrapT": 33648})
    base = g.texture(g.image(base_color_png(), name="base"), sampler=0)
    mr = g.texture(g.image(pattern_png(16, (0, 128, 255, 255), (0, 200, 0, 255)), name="mr"))
    mat = {"name": "painted", "pbrMetallicRoughness": {
        "baseColorFactor": [1, 1, 1, 1], "baseColorTexture": {"index": base},
        "metallicRoughnessTexture": {"index": mr}, "metallicFactor": 0.5, "roughnessFactor": 0.75},
        "emissiveFactor": [0.1, 0.2, 0.3]}
    if normal_map:
        nm = g.texture(g.image(pattern_png(32, (128, 128, 255, 255), (160, 128, 230, 255)), name="normal"))
        mat["normalTexture"] = {"index": nm, "scale": 0.8}
    m = g.material(**mat)
    mesh = g.mesh(cube(), material=m, uv1=uv1, name="cube")
    g.node(mesh=mesh, name="cube_a")
    g.node(mesh=mesh, name="cube_b", translation=[3, 0, 0], rotation=[0, 0.3826834, 0, 0.9238795],
           scale=[1, 2, 1])
    g.doc["cameras"] = [{"type": "perspective", "name": "main",
                         "perspective": {"yfov": 0.9, "znear": 0.1, "zfar": 100, "aspectRatio": 1.5}}]
    g.node(camera=0, name="cam_node", translation=[0, 1, 6])
    pl = g.light(type="point", name="bulb", color=[1, 0.9, 0.8], intensity=20, range=10)
    sl = g.light(type="spot", name="torch", intensity=50, spot={"innerConeAngle": 0.2, "outerConeAngle": 0.5})
    dl = g.light(type="directional", name="sun", intensity=3)
    g.node(name="bulb_node", translation=[0, 3, 0], extensions={"KHR_lights_punctual": {"light": pl}})
    g.node(name="torch_node", translation=[2, 2, 2], extensions={"KHR_lights_punctual": {"light": sl}})
    g.node(name="sun_node", rotation=[-0.3826834, 0, 0, 0.9238795],
           extensions={"KHR_lights_punctual": {"light": dl}})
    return g


def alpha_asset():
    g = Gltf()
    mask = g.material(name="leaves", alphaMode="MASK", alphaCutoff=0.3, doubleSided=True,
                      pbrMetallicRoughness={"baseColorFactor": [0.2, 0.8, 0.2, 1]})
    blend = g.material(name="glass", alphaMode="BLEND",
                       pbrMetallicRoughness={"baseColorFactor": [0.8, 0.9, 1.0, 0.3]})
    g.node(mesh=g.mesh(grid(2), material=mask, uv1=False, name="leaf"))
    g.node(mesh=g.mesh(grid(2, z=0.5), material=blend, uv1=False, name="pane"))
    return g


def extras_asset():
    """What the converter ignores (an animation, an unknown extension, a
    points primitive, an orthographic camera) and a texture transform it
    takes."""
    g = Gltf()
    t = g.texture(g.image(base_color_png()))
    m = g.material(name="m", pbrMetallicRoughness={"baseColorTexture": {
        "index": t, "extensions": {"KHR_texture_transform": {"scale": [2, 2]}}}})
    n = g.node(mesh=g.mesh(cube(), material=m, uv1=False), name="box")
    pts = g.mesh(cube(), uv1=False, mode=0, name="points")
    g.node(mesh=pts, name="dots")
    times = g.accessor([0.0, 1.0], 5126, "SCALAR", 2)
    moves = g.accessor([0.0, 0.0, 0.0, 1.0, 0.0, 0.0], 5126, "VEC3", 2)
    g.doc["animations"] = [{"samplers": [{"input": times, "output": moves}],
                            "channels": [{"sampler": 0, "target": {"node": n, "path": "translation"}}]}]
    g.doc["extensionsUsed"] = ["KHR_texture_transform", "KHR_materials_clearcoat"]
    g.doc["cameras"] = [{"type": "orthographic", "name": "plan",
                         "orthographic": {"xmag": 2, "ymag": 2, "znear": 0.1, "zfar": 50}}]
    g.node(camera=0, name="plan_node", translation=[0, 10, 0], rotation=[-0.7071068, 0, 0, 0.7071068])
    return g


def realistic_asset(big_maps=False):
    """Tens of thousands of triangles, a few dozen textures: 12 materials
    with base colour, metallic-roughness and normal maps (512 or 2048
    texels), 12 grid meshes of 64x64 quads (98,304 triangles), no uv1."""
    g = Gltf()
    size = 2048 if big_maps else 512
    for k in range(12):
        bc = g.texture(g.image(pattern_png(size, (40 + 15 * k, 90, 200 - 10 * k, 255), (230, 220, 200, 255), 16)))
        mr = g.texture(g.image(pattern_png(size, (0, 100, 20 * k, 255), (0, 220, 0, 255), 32)))
        nm = g.texture(g.image(pattern_png(size, (128, 128, 255, 255), (150, 110, 240, 255), 8)))
        mat = g.material(name="mat%d" % k, pbrMetallicRoughness={
            "baseColorTexture": {"index": bc}, "metallicRoughnessTexture": {"index": mr}},
            normalTexture={"index": nm})
        mesh = g.mesh(grid(64, z=0.0), material=mat, uv1=False, name="panel%d" % k)
        g.node(mesh=mesh, name="panel%d" % k, translation=[(k % 4) * 2.5, (k // 4) * 2.5, 0])
    return g


def showcase_asset():
    """The docs' captures (docs/assets/make_captures.py): a textured court.
    A ground of 32 x 32 quads (a checker base colour, a bump normal map, a
    metallic-roughness map), four boxes (bricks with a normal map, polished
    metal, an emissive panel, one with a second uv set), an alpha-masked
    fence, a blended glass pane, a point, a spot and a directional light, a
    camera looking over it."""
    g = Gltf()
    flat = [-0.7071068, 0, 0, 0.7071068]  # grid's xy plane laid down, facing +y
    checker = g.texture(g.image(pattern_png(256, (200, 190, 170, 255), (70, 80, 95, 255), 32), name="tiles"))
    bumps = g.texture(g.image(pattern_png(128, (128, 128, 255, 255), (168, 150, 225, 255), 4), name="bumps"))
    rough = g.texture(g.image(pattern_png(64, (0, 60, 0, 255), (0, 220, 0, 255), 16), name="roughness"))
    ground = g.material(name="tiles", pbrMetallicRoughness={
        "baseColorTexture": {"index": checker}, "metallicRoughnessTexture": {"index": rough},
        "metallicFactor": 0.0}, normalTexture={"index": bumps, "scale": 1.0})
    g.node(mesh=g.mesh(grid(32, size=12.0), material=ground, uv1=False, name="ground"),
           name="ground", rotation=flat)
    bricks = g.texture(g.image(pattern_png(128, (150, 60, 40, 255), (120, 110, 100, 255), 16), name="bricks"))
    mortar = g.texture(g.image(pattern_png(128, (128, 128, 255, 255), (128, 200, 200, 255), 16), name="mortar"))
    brick = g.material(name="bricks", pbrMetallicRoughness={"baseColorTexture": {"index": bricks},
                                                            "metallicFactor": 0.0, "roughnessFactor": 0.8},
                       normalTexture={"index": mortar})
    metal = g.material(name="metal", pbrMetallicRoughness={"baseColorFactor": [0.9, 0.8, 0.5, 1],
                                                           "metallicFactor": 1.0, "roughnessFactor": 0.3})
    glow = g.texture(g.image(pattern_png(32, (255, 160, 40, 255), (40, 20, 10, 255), 4), name="glow"))
    panel = g.material(name="panel", emissiveFactor=[1, 1, 1], emissiveTexture={"index": glow},
                       pbrMetallicRoughness={"baseColorFactor": [0.2, 0.2, 0.2, 1]})
    box = g.mesh(cube(1.5), material=brick, uv1=False, name="brick_box")
    g.node(mesh=box, name="bricks_a", translation=[-3.0, 0.75, -1.0])
    g.node(mesh=box, name="bricks_b", translation=[2.5, 0.75, -3.0], rotation=[0, 0.3826834, 0, 0.9238795])
    g.node(mesh=g.mesh(cube(1.2), material=metal, uv1=True, name="metal_box"), name="metal",
           translation=[0.0, 0.6, 1.5])
    g.node(mesh=g.mesh(cube(1.0), material=panel, uv1=False, name="panel_box"), name="panel",
           translation=[3.5, 0.5, 2.0])
    fence_img = g.texture(g.image(pattern_png(64, (60, 140, 60, 255), (0, 0, 0, 0), 8), name="fence"))
    fence = g.material(name="fence", alphaMode="MASK", alphaCutoff=0.5, doubleSided=True,
                       pbrMetallicRoughness={"baseColorTexture": {"index": fence_img}, "metallicFactor": 0.0})
    g.node(mesh=g.mesh(grid(4, size=3.0), material=fence, uv1=False, name="fence"), name="fence",
           translation=[-1.0, 1.5, -4.5])
    glass = g.material(name="glass", alphaMode="BLEND",
                       pbrMetallicRoughness={"baseColorFactor": [0.7, 0.85, 1.0, 0.35], "metallicFactor": 0.0,
                                             "roughnessFactor": 0.1})
    g.node(mesh=g.mesh(grid(2, size=2.0), material=glass, uv1=False, name="pane"), name="pane",
           translation=[1.0, 1.0, 3.5])
    g.doc["cameras"] = [{"type": "perspective", "name": "court",
                         "perspective": {"yfov": 0.8, "znear": 0.1, "zfar": 100, "aspectRatio": 4 / 3}}]
    # Looking down at about 35 degrees towards the court's centre.
    g.node(camera=0, name="camera", translation=[0, 6.5, 10.5], rotation=[-0.2923717, 0, 0, 0.9563048])
    # In glTF's units as a viewer draws them at exposure 1 (candela, lux):
    # each gives the court a radiance of about 0.5 where it falls.
    pl = g.light(type="point", name="lamp", color=[1, 0.85, 0.6], intensity=20, range=8)
    sl = g.light(type="spot", name="spot", color=[0.7, 0.8, 1], intensity=80, range=12,
                 spot={"innerConeAngle": 0.3, "outerConeAngle": 0.5})
    dl = g.light(type="directional", name="sun", color=[1, 0.95, 0.85], intensity=2)
    g.node(name="lamp", translation=[-1.0, 3.0, 3.5], extensions={"KHR_lights_punctual": {"light": pl}})
    g.node(name="spot", translation=[2.5, 5.0, 0.0], rotation=[-0.7071068, 0, 0, 0.7071068],
           extensions={"KHR_lights_punctual": {"light": sl}})
    g.node(name="sun", rotation=[-0.3535534, 0.3535534, 0.1464466, 0.8535534],
           extensions={"KHR_lights_punctual": {"light": dl}})
    return g


def quantized_asset():
    """TEXCOORD_0 as normalized unsigned shorts and TEXCOORD_1 as normalized
    unsigned bytes (core glTF allows both; assimp 5.2 misreads them, so the
    converter decodes them itself)."""
    g = Gltf()
    pos, nrm, uv0, uv1, idx = cube()
    n = len(pos) // 3
    attrs = {"POSITION": g.accessor(pos, 5126, "VEC3", n), "NORMAL": g.accessor(nrm, 5126, "VEC3", n)}
    q0 = [int(round(x * 65535)) for x in uv0]
    q1 = [int(round(x * 255)) for x in uv1]
    attrs["TEXCOORD_0"] = g.accessor(q0, 5123, "VEC2", n)
    attrs["TEXCOORD_1"] = g.accessor(q1 + [0] * (-len(q1) % 4), 5121, "VEC2", n)
    for k in ("TEXCOORD_0", "TEXCOORD_1"):
        g.doc["accessors"][attrs[k]]["normalized"] = True
    prim = {"attributes": attrs, "indices": g.accessor(idx, 5123, "SCALAR", len(idx))}
    g.doc["meshes"].append({"primitives": [prim], "name": "qcube"})
    g.node(mesh=0, name="qcube")
    return g


def skinned_asset():
    """A cube bound to a two-joint skin (JOINTS_0 as bytes): drawn in its
    bind pose, the skin reported as ignored."""
    g = Gltf()
    pos, nrm, uv0, uv1, idx = cube()
    n = len(pos) // 3
    mesh = g.mesh((pos, nrm, uv0, uv1, idx), uv1=False, name="skinned")
    attrs = g.doc["meshes"][mesh]["primitives"][0]["attributes"]
    attrs["JOINTS_0"] = g.accessor([0, 1, 0, 0] * n, 5121, "VEC4", n)
    attrs["WEIGHTS_0"] = g.accessor([0.5, 0.5, 0.0, 0.0] * n, 5126, "VEC4", n)
    ident = [1.0, 0, 0, 0, 0, 1.0, 0, 0, 0, 0, 1.0, 0, 0, 0, 0, 1.0]
    ibm = g.accessor(ident * 2, 5126, "MAT4", 2)
    j0 = g.node(root=False, name="root_joint", children=[])
    j1 = g.node(root=False, name="tip_joint", translation=[0, 1, 0])
    g.doc["nodes"][j0]["children"] = [j1]
    g.doc["skins"] = [{"joints": [j0, j1], "inverseBindMatrices": ibm, "skeleton": j0}]
    body = g.node(mesh=mesh, skin=0, name="body")
    g.doc["scenes"][0]["nodes"].append(j0)
    return g


# ---- import fidelity: pairs a correct importer renders alike ----
#
# Each pair states one thing two ways: a node transform and the same
# transform baked into the vertices, a material's uv set 1 and the same
# values as set 0, COLOR_0 and the same colour as a factor, a texture
# transform and the coordinates it produces. tests/e2e/e2e_asset_import.py
# renders both halves of each pair and compares.

def quat_matrix(q):
    """A unit quaternion (x, y, z, w) as a 3x3 rotation, rows."""
    x, y, z, w = q
    n = math.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / n, y / n, z / n, w / n
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]


def axis_angle(axis, degrees):
    n = math.sqrt(sum(a * a for a in axis))
    h = math.radians(degrees) / 2
    return [axis[0] / n * math.sin(h), axis[1] / n * math.sin(h), axis[2] / n * math.sin(h), math.cos(h)]


def trs(t=(0, 0, 0), r=(0, 0, 0, 1), s=(1, 1, 1)):
    """(3x3 rows, translation) of translation * rotation * scale."""
    rm = quat_matrix(r)
    return [[rm[i][j] * s[j] for j in range(3)] for i in range(3)], list(t)


def compose(a, b):
    """a then applied after b: a * b."""
    (ma, ta), (mb, tb) = a, b
    m = [[sum(ma[i][k] * mb[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    t = [sum(ma[i][k] * tb[k] for k in range(3)) + ta[i] for i in range(3)]
    return m, t


def det3(m):
    return (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]))


def inverse_transpose(m):
    """The cofactor matrix over the determinant: M^-T."""
    d = det3(m)
    c = [[m[(i + 1) % 3][(j + 1) % 3] * m[(i + 2) % 3][(j + 2) % 3]
          - m[(i + 1) % 3][(j + 2) % 3] * m[(i + 2) % 3][(j + 1) % 3] for j in range(3)] for i in range(3)]
    return [[c[i][j] / d for j in range(3)] for i in range(3)]


def normalized(v):
    n = math.sqrt(sum(x * x for x in v))
    return [x / n for x in v]


def bake(geom, xf):
    """geom (positions, normals, uv0, uv1, indices, tangents) with the
    transform xf = (3x3, translation) applied as an importer must: points by
    the matrix, normals by its inverse transpose, tangents by the matrix with
    w turned and the winding reversed where it mirrors."""
    pos, nrm, uv0, uv1, idx, tan = geom
    m, t = xf
    nm = inverse_transpose(m)
    mirror = det3(m) < 0
    p2, n2, t2 = [], [], []
    for v in range(len(pos) // 3):
        p = pos[3 * v:3 * v + 3]
        p2 += [sum(m[i][k] * p[k] for k in range(3)) + t[i] for i in range(3)]
        n = nrm[3 * v:3 * v + 3]
        n2 += normalized([sum(nm[i][k] * n[k] for k in range(3)) for i in range(3)])
        tv = tan[4 * v:4 * v + 4]
        t2 += normalized([sum(m[i][k] * tv[k] for k in range(3)) for i in range(3)])
        t2.append(-tv[3] if mirror else tv[3])
    i2 = list(idx)
    if mirror:
        for k in range(0, len(i2), 3):
            i2[k + 1], i2[k + 2] = i2[k + 2], i2[k + 1]
    return p2, n2, list(uv0), list(uv1), i2, t2


def cube_tangents(size=1.0):
    """cube() with its tangents: each face's u direction, w = 1 (its faces
    are u x v = n, and uv0's v runs down the face)."""
    faces = [((0, 0, -1)), ((0, 0, 1)), ((1, 0, 0)), ((1, 0, 0)), ((1, 0, 0)), ((-1, 0, 0))]
    tan = []
    for u in faces:
        tan += (list(map(float, u)) + [1.0]) * 4
    return cube(size) + (tan,)


def sphere(rings=12, segments=24, radius=0.8):
    """A uv sphere with smooth normals and tangents: uv0 (longitude,
    latitude from the top), uv1 the same squeezed into [0.05, 0.95]^2."""
    pos, nrm, uv0, uv1, idx, tan = [], [], [], [], [], []
    for j in range(rings + 1):
        th = math.pi * j / rings
        for i in range(segments + 1):
            ph = 2 * math.pi * i / segments
            n = [math.sin(th) * math.cos(ph), math.cos(th), -math.sin(th) * math.sin(ph)]
            pos += [radius * x for x in n]
            nrm += n
            u, v = i / segments, j / rings
            uv0 += [u, v]
            uv1 += [0.05 + 0.9 * u, 0.05 + 0.9 * v]
            t = [-math.sin(ph), 0.0, -math.cos(ph)]  # dP/du, along increasing longitude
            dpdv = [math.cos(th) * math.cos(ph), -math.sin(th), -math.cos(th) * math.sin(ph)]
            cr = [n[1] * t[2] - n[2] * t[1], n[2] * t[0] - n[0] * t[2], n[0] * t[1] - n[1] * t[0]]
            w = -1.0 if sum(cr[k] * dpdv[k] for k in range(3)) > 0 else 1.0
            tan += t + [w]
    for j in range(rings):
        for i in range(segments):
            a = j * (segments + 1) + i
            b = a + segments + 1
            idx += [a, b, a + 1, a + 1, b, b + 1]
    return pos, nrm, uv0, uv1, idx, tan


def fidelity_scene(g):
    """The pairs' shared camera and lights (the same in both halves)."""
    g.doc["cameras"] = [{"type": "perspective", "name": "view",
                         "perspective": {"yfov": 0.75, "znear": 0.1, "zfar": 60, "aspectRatio": 4 / 3}}]
    g.node(camera=0, name="view", translation=[0.3, 2.4, 9.5], rotation=axis_angle([1, 0, 0], -6))
    pl = g.light(type="point", name="lamp", color=[1, 0.9, 0.8], intensity=250, range=25)
    dl = g.light(type="directional", name="sun", color=[0.8, 0.85, 1], intensity=4)
    g.node(name="lamp", translation=[2.5, 4, 4], extensions={"KHR_lights_punctual": {"light": pl}})
    g.node(name="sun", rotation=axis_angle([1, 0.4, 0], -50), extensions={"KHR_lights_punctual": {"light": dl}})


# Node transforms: rotated (a quarter turn about x, as a helmet exported
# z-up), non-uniformly scaled and rotated, mirrored (a negative scale) and
# rotated, and a child's scale under its parent's rotation.
NODE_CASES = [
    ("rotated", "sphere", False, [trs((-2.6, 0.9, 0), axis_angle([1, 0, 0], 90))]),
    ("scaled", "cube", True, [trs((-0.8, 0.9, 0), axis_angle([1, 1, 0], 35), (1.0, 2.2, 0.6))]),
    ("mirrored", "sphere", True, [trs((1.2, 0.9, 0), axis_angle([0, 1, 0.3], 40), (-1, 1, 1))]),
    ("mirrored_cube", "cube", False, [trs((3.0, 0.9, 0), axis_angle([0.2, 1, 0], -30), (1, -1.3, 1))]),
    ("nested", "cube", True, [trs((0.5, 2.9, -1), axis_angle([0, 0, 1], 60)),
                              trs((0, 0, 0), axis_angle([1, 0, 0], 20), (0.5, 1.4, 0.8))]),
]


def transforms_asset(baked):
    """NODE_CASES drawn with a normal-mapped material through their nodes'
    transforms (baked False) or with the transforms baked into the vertices
    and identity nodes (baked True). Tangents from the file where the case
    says, else the importer's."""
    g = Gltf()
    bumps = g.texture(g.image(pattern_png(64, (128, 128, 255, 255), (190, 150, 215, 255), 8), name="bumps"))
    tiles = g.texture(g.image(pattern_png(64, (210, 180, 150, 255), (90, 110, 140, 255), 16), name="tiles"))
    mat = g.material(name="bumpy", pbrMetallicRoughness={
        "baseColorTexture": {"index": tiles}, "metallicFactor": 0.1, "roughnessFactor": 0.5},
        normalTexture={"index": bumps, "scale": 1.0})
    shapes = {"sphere": sphere(), "cube": cube_tangents(1.2)}
    for name, shape, file_tangents, chain in NODE_CASES:
        geom = shapes[shape]
        if baked:
            xf = chain[0]
            for inner in chain[1:]:
                xf = compose(xf, inner)
            mesh = g.mesh(bake(geom, xf), material=mat, uv1=False, tangents=file_tangents, name=name)
            g.node(mesh=mesh, name=name)
            continue
        mesh = g.mesh(geom, material=mat, uv1=False, tangents=file_tangents, name=name)
        parent = None
        for depth, (m, t) in enumerate(chain):
            # Column-major, as glTF stores a node's matrix.
            node = {"name": "%s%d" % (name, depth),
                    "matrix": [m[0][0], m[1][0], m[2][0], 0, m[0][1], m[1][1], m[2][1], 0,
                               m[0][2], m[1][2], m[2][2], 0, t[0], t[1], t[2], 1]}
            if depth == len(chain) - 1:
                node["mesh"] = mesh
            i = g.node(root=parent is None, **node)
            if parent is not None:
                g.doc["nodes"][parent].setdefault("children", []).append(i)
            parent = i
    fidelity_scene(g)
    return g


def transforms_trs_asset():
    """The first NODE_CASES as translation, rotation and scale properties
    rather than matrices (the node graph's other spelling), unbaked."""
    g = transforms_asset(False)
    for node in g.doc["nodes"]:
        if node.get("name") == "rotated0":
            del node["matrix"]
            node["translation"] = [-2.6, 0.9, 0]
            node["rotation"] = axis_angle([1, 0, 0], 90)
        if node.get("name") == "mirrored0":
            del node["matrix"]
            node["translation"] = [1.2, 0.9, 0]
            node["rotation"] = axis_angle([0, 1, 0.3], 40)
            node["scale"] = [-1, 1, 1]
    return g


def texcoord_asset(set_index, inside):
    """Base colour, occlusion and emissive maps reading uv set set_index, on
    a cube whose TEXCOORD_0 and TEXCOORD_1 hold the same values: inside
    [0, 1], or spread over [-0.5, 1.5] (repeating)."""
    g = Gltf()
    g._list("samplers").append({"wrapS": 10497, "wrapT": 10497})
    base = g.texture(g.image(pattern_png(32, (230, 200, 90, 255), (60, 90, 160, 255), 4), name="base"), 0)
    occl = g.texture(g.image(pattern_png(32, (255, 255, 255, 255), (40, 40, 40, 255), 8), name="occlusion"), 0)
    glow = g.texture(g.image(pattern_png(32, (0, 0, 0, 255), (90, 40, 10, 255), 16), name="glow"), 0)
    mat = g.material(name="sets", emissiveFactor=[1, 1, 1],
                     emissiveTexture={"index": glow, "texCoord": set_index},
                     occlusionTexture={"index": occl, "texCoord": set_index, "strength": 1.0},
                     pbrMetallicRoughness={"baseColorTexture": {"index": base, "texCoord": set_index},
                                           "metallicFactor": 0.0})
    pos, nrm, uv0, _, idx = cube(1.6)
    if not inside:
        uv0 = [2 * x - 0.5 for x in uv0]
    # Squeezed per face into a sixth of the square so that set 1 inside
    # [0, 1] is a valid unique parametrisation too.
    if inside:
        sq = []
        for v in range(len(uv0) // 2):
            f = v // 4
            sq += [(f % 3 + 0.1 + 0.8 * uv0[2 * v]) / 3, (f // 3 + 0.1 + 0.8 * uv0[2 * v + 1]) / 2]
        uv0 = sq
    mesh = g.mesh((pos, nrm, uv0, list(uv0), idx), material=mat, uv1=True, name="sets")
    g.node(mesh=mesh, name="box", translation=[0, 0.9, 0], rotation=axis_angle([0, 1, 0], 30))
    fidelity_scene(g)
    return g


def overlap_asset(overlap):
    """Two halves of a plane whose TEXCOORD_1 stays inside [0, 1]: mirrored
    onto the same texels (overlap True: the converter must not take it as
    uv1) or side by side."""
    g = Gltf()
    pos, nrm, uv0, uv1, idx = [], [], [], [], []
    for half in (0, 1):
        base = len(pos) // 3
        for j in range(5):
            for i in range(5):
                x = (i / 4 - (1.0 if half == 0 else 0.0)) * 1.5
                pos += [x, j / 4 * 1.5, 0.0]
                nrm += [0.0, 0.0, 1.0]
                uv0 += [i / 4, 1 - j / 4]
                u = i / 4 if half == 0 else 1 - i / 4  # the right half mirrors the left
                if overlap:
                    uv1 += [0.1 + 0.8 * u, 0.1 + 0.8 * (1 - j / 4)]
                else:
                    uv1 += [0.05 + 0.4 * (i / 4) + 0.5 * half, 0.1 + 0.8 * (1 - j / 4)]
        for j in range(4):
            for i in range(4):
                a = base + j * 5 + i
                idx += [a, a + 1, a + 6, a, a + 6, a + 5]
    g.node(mesh=g.mesh((pos, nrm, uv0, uv1, idx), uv1=True, name="halves"), name="halves")
    return g


def colors_asset(as_attribute):
    """Two boxes, one coloured by an unsigned-byte VEC4 COLOR_0 and one by a
    float VEC3 COLOR_0 (as_attribute), or by the same colours as base colour
    factors."""
    g = Gltf()
    tex = g.texture(g.image(pattern_png(16, (255, 255, 255, 255), (160, 160, 160, 255), 4), name="grey"))
    rgba8 = (200, 120, 60, 255)
    rgbf = (0.2, 0.5, 0.9)
    for k, (name, color) in enumerate((("bytes", [c / 255 for c in rgba8]), ("floats", list(rgbf) + [1.0]))):
        pbr = {"baseColorTexture": {"index": tex}, "metallicFactor": 0.0}
        if not as_attribute:
            pbr["baseColorFactor"] = color
        mat = g.material(name=name, pbrMetallicRoughness=pbr)
        geom = cube(1.3)
        n = len(geom[0]) // 3
        cols = None
        if as_attribute:
            cols = (list(rgba8) * n, 5121, "VEC4") if k == 0 else (list(rgbf) * n, 5126, "VEC3")
        # At y 0.95 the boxes' horizontal edges fall 0.08 px or more from
        # the pixel centres' rows at 160x120 (at 0.9 their lower edges lay
        # 0.013 px above row 80's: the viewer's rasteriser, which snaps
        # vertices to 1/16 px, covered that row and llvmpipe did not).
        g.node(mesh=g.mesh(geom, material=mat, uv1=False, colors=cols, name=name), name=name,
               translation=[-1.2 + 2.4 * k, 0.95, 0])
    fidelity_scene(g)
    return g


# KHR_texture_transform's matrix as the sample viewer applies it.
TEX_TRANSFORM = {"offset": [0.2, -0.1], "rotation": 0.6, "scale": [1.5, 0.7]}


def tex_transform_uv(u, v, t=TEX_TRANSFORM):
    c, s = math.cos(t["rotation"]), math.sin(t["rotation"])
    su, sv = u * t["scale"][0], v * t["scale"][1]
    return c * su + s * sv + t["offset"][0], -s * su + c * sv + t["offset"][1]


def texture_transform_asset(transformed):
    """A base colour map through KHR_texture_transform (offset, rotation,
    scale, and a texCoord override naming set 1, TEXCOORD_0 holding other
    coordinates) when transformed, or plain over TEXCOORD_0 holding the
    coordinates the transform produces."""
    g = Gltf()
    g._list("samplers").append({"wrapS": 10497, "wrapT": 10497})
    base = g.texture(g.image(pattern_png(32, (230, 200, 90, 255), (60, 90, 160, 255), 4), name="base"), 0)
    pos, nrm, uv0, _, idx = cube(1.6)
    if transformed:
        info = {"index": base, "texCoord": 0, "extensions": {"KHR_texture_transform": dict(TEX_TRANSFORM, texCoord=1)}}
        geom = (pos, nrm, [0.5 * x for x in uv0], list(uv0), idx)
        g.doc["extensionsUsed"] = ["KHR_texture_transform"]
    else:
        info = {"index": base}
        moved = []
        for k in range(0, len(uv0), 2):
            moved += list(tex_transform_uv(uv0[k], uv0[k + 1]))
        geom = (pos, nrm, moved, list(uv0), idx)
    mat = g.material(name="moved", pbrMetallicRoughness={"baseColorTexture": info, "metallicFactor": 0.0})
    g.node(mesh=g.mesh(geom, material=mat, uv1=True, name="moved"), name="box",
           translation=[0, 0.9, 0], rotation=axis_angle([0, 1, 0], 30))
    fidelity_scene(g)
    return g


def flat_asset(file_normals):
    """A sphere whose file gives no normals (glTF: flat ones, a vertex per
    triangle corner) against the same triangles unwelded with their face
    normals stated."""
    g = Gltf()
    pos, nrm, uv0, uv1, idx, tan = sphere(rings=8, segments=12, radius=1.2)

    def area2(k):
        a, b, c = (pos[3 * i:3 * i + 3] for i in idx[k:k + 3])
        e1 = [b[q] - a[q] for q in range(3)]
        e2 = [c[q] - a[q] for q in range(3)]
        return sum(x * x for x in (e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                                   e1[0] * e2[1] - e1[1] * e2[0]))
    # The poles' degenerate triangles left out (no face normal to state).
    idx = [i for k in range(0, len(idx), 3) if area2(k) > 1e-12 for i in idx[k:k + 3]]
    if file_normals:
        p2, n2, u2, idx2 = [], [], [], []
        for k in range(0, len(idx), 3):
            a, b, c = (pos[3 * i:3 * i + 3] for i in idx[k:k + 3])
            e1 = [b[q] - a[q] for q in range(3)]
            e2 = [c[q] - a[q] for q in range(3)]
            fn = normalized([e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                             e1[0] * e2[1] - e1[1] * e2[0]])
            for i in idx[k:k + 3]:
                idx2.append(len(p2) // 3)
                p2 += pos[3 * i:3 * i + 3]
                n2 += fn
                u2 += uv0[2 * i:2 * i + 2]
        geom = (p2, n2, u2, list(u2), idx2)
    else:
        geom = (pos, nrm, uv0, uv1, idx)
    mat = g.material(name="matte", pbrMetallicRoughness={"baseColorFactor": [0.8, 0.7, 0.5, 1],
                                                         "metallicFactor": 0.0, "roughnessFactor": 0.6})
    g.node(mesh=g.mesh(geom, material=mat, uv1=False, normals=file_normals, name="ball"), name="ball",
           translation=[0, 1.2, 0])
    fidelity_scene(g)
    return g


def back_face_asset(double_sided):
    """A normal-mapped plate seen from behind: double-sided (its back lit as
    glTF says, the normal reversed, normal map and all), against the same
    plate rebuilt to face the viewer with its normal, tangent and
    handedness reversed and its winding turned."""
    g = Gltf()
    bumps = g.texture(g.image(pattern_png(64, (128, 128, 255, 255), (200, 140, 210, 255), 8), name="bumps"))
    mat = g.material(name="plate", doubleSided=True, normalTexture={"index": bumps},
                     pbrMetallicRoughness={"baseColorFactor": [0.7, 0.75, 0.8, 1], "metallicFactor": 0.0,
                                           "roughnessFactor": 0.5})
    pos, nrm, uv0, uv1, idx = grid(6, size=3.0)
    n = len(pos) // 3
    geom = (pos, [0.0, 0.0, 1.0] * n, uv0, uv1, idx, [1.0, 0.0, 0.0, 1.0] * n)
    turn = trs((0, 1.5, 0), axis_angle([0, 1, 0], 180))
    if double_sided:
        mesh = g.mesh(geom, material=mat, uv1=False, tangents=True, name="plate")
        g.node(mesh=mesh, name="plate", translation=[0, 1.5, 0], rotation=axis_angle([0, 1, 0], 180))
    else:
        p2, n2, u0, u1, i2, t2 = bake(geom, turn)
        n2 = [-x for x in n2]
        t2 = [-x for x in t2]
        for k in range(0, len(i2), 3):
            i2[k + 1], i2[k + 2] = i2[k + 2], i2[k + 1]
        mesh = g.mesh((p2, n2, u0, u1, i2, t2), material=mat, uv1=False, tangents=True, name="plate")
        g.node(mesh=mesh, name="plate")
    fidelity_scene(g)
    return g


def fidelity_pairs():
    """{name: (asset, its equivalent)}: what e2e_asset_import renders."""
    return {
        "transforms": (transforms_asset(False), transforms_asset(True)),
        "transforms_trs": (transforms_trs_asset(), transforms_asset(True)),
        "texcoord1_outside": (texcoord_asset(1, False), texcoord_asset(0, False)),
        "texcoord1_inside": (texcoord_asset(1, True), texcoord_asset(0, True)),
        "colors": (colors_asset(True), colors_asset(False)),
        "texture_transform": (texture_transform_asset(True), texture_transform_asset(False)),
        "flat_normals": (flat_asset(False), flat_asset(True)),
        "back_face": (back_face_asset(True), back_face_asset(False)),
    }


# ---- bad assets ----

# ---- the fidelity set: every feature above in one asset ----
#
# One asset holding one object per feature the pairs state (the node
# transforms, the texCoord sets inside and outside [0, 1], COLOR_0, a
# texture transform, a sphere without normals, a double-sided plate from
# behind), each in a cell of its own, so that one Khronos reference render
# (tests/e2e/e2e_fidelity.py, bench/bench_fidelity.py) holds every feature
# to the viewer: the test crops each object's rectangle from both images.

FIDELITY_SET_CELL = 3.0   # a cell's edge (units): the largest object fits
FIDELITY_SET_COLUMNS = 4
# An explicit scene.camera pose framing the 4 x 3 cells (the asset's own
# camera is the same pose).
FIDELITY_SET_CAMERA = {"eye": [0.0, 0.0, 21.0], "target": [0.0, 0.0, 0.0], "up": [0, 1, 0],
                       "yfov_deg": 30.0}


def _node_matrix(node):
    """A node's local transform as (3x3 rows, translation)."""
    m = node.get("matrix")
    if m:
        return [[m[0], m[4], m[8]], [m[1], m[5], m[9]], [m[2], m[6], m[10]]], [m[12], m[13], m[14]]
    return trs(node.get("translation", (0, 0, 0)), node.get("rotation", (0, 0, 0, 1)),
               node.get("scale", (1, 1, 1)))


def world_boxes(g):
    """{root node name: (min xyz, max xyz)}: each root subtree's world
    bounds, from its meshes' POSITION bounds through the node transforms."""
    doc = g.doc
    out = {}

    def walk(i, xf, box):
        node = doc["nodes"][i]
        xf = compose(xf, _node_matrix(node))
        if "mesh" in node:
            for prim in doc["meshes"][node["mesh"]]["primitives"]:
                acc = doc["accessors"][prim["attributes"]["POSITION"]]
                lo, hi = acc["min"], acc["max"]
                for k in range(8):
                    c = [hi[a] if k >> a & 1 else lo[a] for a in range(3)]
                    w = [sum(xf[0][r][q] * c[q] for q in range(3)) + xf[1][r] for r in range(3)]
                    for a in range(3):
                        box[0][a] = min(box[0][a], w[a])
                        box[1][a] = max(box[1][a], w[a])
        for child in node.get("children", []):
            walk(child, xf, box)
    identity = ([[1, 0, 0], [0, 1, 0], [0, 0, 1]], [0, 0, 0])
    for i in doc["scenes"][0]["nodes"]:
        box = [[1e30] * 3, [-1e30] * 3]
        walk(i, identity, box)
        if box[0][0] <= box[1][0]:
            out[doc["nodes"][i].get("name", str(i))] = box
    return out


def _cell_centre(k, rows):
    cols = FIDELITY_SET_COLUMNS
    return [FIDELITY_SET_CELL * (k % cols - (cols - 1) / 2),
            FIDELITY_SET_CELL * ((rows - 1) / 2 - k // cols), 0.0]


def merge_into(g, src, place, prefix):
    """Copies src's buffers, images, textures, samplers, materials, meshes
    and nodes into g (cameras and lights left out), each root node that
    draws something named prefix + its name and moved by place(node)."""
    d, sd = g.doc, src.doc
    src.finish_buffer()
    while len(g.bin) % 4:
        g.bin.append(0)
    base = len(g.bin)
    g.bin += src.bin
    off = {k: len(d.get(k, [])) for k in ("bufferViews", "accessors", "images", "textures",
                                          "samplers", "materials", "meshes", "nodes")}
    for v in sd.get("bufferViews", []):
        d["bufferViews"].append(dict(v, byteOffset=v.get("byteOffset", 0) + base))
    for a in sd.get("accessors", []):
        d["accessors"].append(dict(a, bufferView=a["bufferView"] + off["bufferViews"]))
    for im in sd.get("images", []):
        g._list("images").append(dict(im, bufferView=im["bufferView"] + off["bufferViews"]))
    for sm in sd.get("samplers", []):
        g._list("samplers").append(dict(sm))
    for t in sd.get("textures", []):
        t2 = dict(t, source=t["source"] + off["images"])
        if "sampler" in t:
            t2["sampler"] = t["sampler"] + off["samplers"]
        g._list("textures").append(t2)

    def retex(v):
        if isinstance(v, dict):
            v = {k: retex(x) for k, x in v.items()}
            if "index" in v and isinstance(v["index"], int):
                v["index"] += off["textures"]
        return v
    for m in sd.get("materials", []):
        m2 = {k: retex(v) if k.endswith("Texture") else v for k, v in m.items()}
        if "pbrMetallicRoughness" in m:
            m2["pbrMetallicRoughness"] = {k: retex(v) if k.endswith("Texture") else v
                                          for k, v in m["pbrMetallicRoughness"].items()}
        g._list("materials").append(m2)
    for mesh in sd.get("meshes", []):
        prims = []
        for prim in mesh["primitives"]:
            p2 = dict(prim, attributes={k: a + off["accessors"] for k, a in prim["attributes"].items()})
            if "indices" in prim:
                p2["indices"] = prim["indices"] + off["accessors"]
            if "material" in prim:
                p2["material"] = prim["material"] + off["materials"]
            prims.append(p2)
        d["meshes"].append(dict(mesh, primitives=prims))
    for node in sd["nodes"]:
        n2 = {k: v for k, v in node.items() if k not in ("camera", "extensions")}
        if "mesh" in node:
            n2["mesh"] = node["mesh"] + off["meshes"]
        if "children" in node:
            n2["children"] = [c + off["nodes"] for c in node["children"]]
        d["nodes"].append(n2)
    for i in sd["scenes"][0]["nodes"]:
        node = d["nodes"][i + off["nodes"]]
        if "mesh" in node or "children" in node:
            node["name"] = prefix + node.get("name", "")
            place(node)
            d["scenes"][0]["nodes"].append(i + off["nodes"])
    used = [e for e in sd.get("extensionsUsed", []) if e != "KHR_lights_punctual"]
    for e in used:
        if e not in g._list("extensionsUsed"):
            d["extensionsUsed"].append(e)


# The objects in cell order, by the root node names fidelity_set_asset
# gives them, and what each states.
FIDELITY_SET_FEATURES = [
    ("transforms.rotated0", "a quarter turn about x (node matrix; generated tangents)"),
    ("transforms.scaled0", "rotation with scale (1, 2.2, 0.6) (file tangents)"),
    ("transforms.mirrored0", "a mirrored sphere, scale -1 in x (file tangents)"),
    ("transforms.mirrored_cube0", "a mirrored cube, -1.3 in y (generated tangents)"),
    ("transforms.nested0", "a child's scale under a rotated parent"),
    ("texcoord1_outside.box", "base colour, occlusion, emissive on TEXCOORD_1 outside [0, 1]"),
    ("texcoord1_inside.box", "the same on TEXCOORD_1 inside [0, 1]"),
    ("texture_transform.box", "KHR_texture_transform with a texCoord override"),
    ("colors.bytes", "COLOR_0, unsigned-byte VEC4"),
    ("colors.floats", "COLOR_0, float VEC3"),
    ("flat_normals.ball", "a sphere without NORMAL (flat normals)"),
    ("back_face.plate", "a double-sided normal-mapped plate from behind"),
]


def project_box(box, width, height, camera=FIDELITY_SET_CAMERA, pad=1):
    """The pixel rectangle (x0, y0, x1, y1), top row 0, exclusive ends,
    covering a world box seen by camera (a scene.camera pose with
    yfov_deg) in a width x height image, padded by pad pixels and clipped."""
    eye, target = camera["eye"], camera["target"]
    f = normalized([t - e for t, e in zip(target, eye)])
    up = camera.get("up", [0, 1, 0])
    r = normalized([f[1] * up[2] - f[2] * up[1], f[2] * up[0] - f[0] * up[2], f[0] * up[1] - f[1] * up[0]])
    u = [r[1] * f[2] - r[2] * f[1], r[2] * f[0] - r[0] * f[2], r[0] * f[1] - r[1] * f[0]]
    t = math.tan(math.radians(camera["yfov_deg"]) / 2)
    xs, ys = [], []
    for k in range(8):
        c = [box[1][a] if k >> a & 1 else box[0][a] for a in range(3)]
        v = [c[a] - eye[a] for a in range(3)]
        z = sum(v[a] * f[a] for a in range(3))
        x = sum(v[a] * r[a] for a in range(3)) / (z * t * width / height)
        y = sum(v[a] * u[a] for a in range(3)) / (z * t)
        xs.append((x * 0.5 + 0.5) * width)
        ys.append((0.5 - y * 0.5) * height)
    return (max(0, int(math.floor(min(xs))) - pad), max(0, int(math.floor(min(ys))) - pad),
            min(width, int(math.ceil(max(xs))) + pad), min(height, int(math.ceil(max(ys))) + pad))


def crop_png(image, rect):
    """An opaque PNG of rect (x0, y0, x1, y1, exclusive ends) of image, a
    (width, height, pixels) as testlib.png_pixels reads one."""
    w, _, px = image
    x0, y0, x1, y1 = rect
    rows = [bytes(c for x in range(x0, x1) for c in (*px[y * w + x][:3], 255))
            for y in range(y0, y1)]
    return png_bytes(x1 - x0, y1 - y0, rows)


def fidelity_set_rects(width, height, camera=FIDELITY_SET_CAMERA):
    """{feature name: pixel rectangle} of fidelity_set_asset's objects."""
    boxes = world_boxes(fidelity_set_asset())
    return {name: project_box(boxes[name], width, height, camera) for name, _ in FIDELITY_SET_FEATURES}


def fidelity_set_asset(baked=False):
    """FIDELITY_SET_FEATURES' objects in a 4 x 3 grid of cells facing +z
    (each object's node moved to its cell's centre, rotation and scale
    kept), seen by FIDELITY_SET_CAMERA, lit by a point light and a sun in
    glTF's units. baked: the transforms' half with its nodes baked into the
    vertices (transforms_asset(True)); the rest is the same either way."""
    g = Gltf()
    names = [n for n, _ in FIDELITY_SET_FEATURES]
    rows = (len(names) + FIDELITY_SET_COLUMNS - 1) // FIDELITY_SET_COLUMNS

    def place(node):
        name = node["name"]
        case = name.split(".", 1)[1]
        if name.startswith("transforms.") and baked:
            # Identity nodes over vertices the chain moved: the node moves
            # them on by the cell's offset from where the chain put them.
            chain = next(c for n, _, _, c in NODE_CASES if n == case)
            xf = chain[0]
            for inner in chain[1:]:
                xf = compose(xf, inner)
            k = names.index(name + "0")
            node["translation"] = [a - b for a, b in zip(_cell_centre(k, rows), xf[1])]
            return
        c = _cell_centre(names.index(name), rows)
        if "matrix" in node:
            m = list(node["matrix"])
            m[12:15] = c
            node["matrix"] = m
        else:
            node["translation"] = c
    parts = [("transforms.", transforms_asset(baked)),
             ("texcoord1_outside.", texcoord_asset(1, False)),
             ("texcoord1_inside.", texcoord_asset(1, True)),
             ("texture_transform.", texture_transform_asset(True)),
             ("colors.", colors_asset(True)),
             ("flat_normals.", flat_asset(False)),
             ("back_face.", back_face_asset(True))]
    for prefix, src in parts:
        merge_into(g, src, place, prefix)
    cam = FIDELITY_SET_CAMERA
    g.doc["cameras"] = [{"type": "perspective", "name": "set",
                         "perspective": {"yfov": math.radians(cam["yfov_deg"]), "znear": 0.5,
                                         "zfar": 100, "aspectRatio": 4 / 3}}]
    g.node(camera=0, name="view", translation=list(cam["eye"]))
    pl = g.light(type="point", name="lamp", color=[1, 0.9, 0.8], intensity=900, range=60)
    dl = g.light(type="directional", name="sun", color=[0.8, 0.85, 1], intensity=4)
    g.node(name="lamp", translation=[3.0, 5.0, 12.0], extensions={"KHR_lights_punctual": {"light": pl}})
    g.node(name="sun", rotation=axis_angle([1, 0.4, 0], -50), extensions={"KHR_lights_punctual": {"light": dl}})
    return g


def bad_accessor_oob():
    g = textured(normal_map=False)
    g.doc["accessors"][0]["count"] += 10  # POSITION runs past its bufferView
    return g.glb(), "accessors[0]"


def bad_view_oob():
    g = textured(normal_map=False)
    data = g.glb()
    doc = json.loads(json.dumps(g.doc))
    doc["bufferViews"][1]["byteLength"] = len(g.bin) * 2
    return rebuild_glb(doc, g.bin), "bufferViews[1]"


def rebuild_glb(doc, binary):
    js = json.dumps(doc, separators=(",", ":")).encode()
    js += b" " * (-len(js) % 4)
    out = struct.pack("<I I", len(js), 0x4E4F534A) + js
    out += struct.pack("<I I", len(binary), 0x004E4942) + bytes(binary)
    return b"glTF" + struct.pack("<I I", 2, 12 + len(out)) + out


def bad_index_oob():
    g = Gltf()
    pos, nrm, uv0, uv1, idx = cube()
    idx[5] = 99
    g.node(mesh=g.mesh((pos, nrm, uv0, uv1, idx), uv1=False))
    return g.glb(), "meshes[0].primitives[0].indices"


def bad_huge_count():
    g = Gltf()
    g.node(mesh=g.mesh(cube(), uv1=False))
    g.doc["accessors"][0]["count"] = 2 ** 31
    return g.glb(), "accessors[0]"


def bad_not_image():
    g = Gltf()
    t = g.texture(g.image(b"this is not an image at all, just some text"))
    m = g.material(pbrMetallicRoughness={"baseColorTexture": {"index": t}})
    g.node(mesh=g.mesh(cube(), material=m, uv1=False))
    return g.glb(), "images[0]"


def bad_uri(where, uri):
    g = Gltf()
    g.node(mesh=g.mesh(cube(), uv1=False))
    if where == "images":
        g.doc["images"] = [{"uri": uri}]
        g.doc["textures"] = [{"source": 0}]
        g.doc["materials"] = [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]
        g.doc["meshes"][0]["primitives"][0]["material"] = 0
        return g.gltf_data_uri(), "images[0].uri"
    text = json.loads(g.gltf_data_uri())
    text["buffers"][0]["uri"] = uri
    return json.dumps(text).encode(), "buffers[0].uri"


def bad_big_texture():
    g = Gltf()
    t = g.texture(g.image(png_header_only(9000, 4)))
    m = g.material(pbrMetallicRoughness={"baseColorTexture": {"index": t}})
    g.node(mesh=g.mesh(cube(), material=m, uv1=False))
    return g.glb(), "limits.max_texture_edge"


def bad_mode(mode):
    g = Gltf()
    g.node(mesh=g.mesh(cube(), uv1=False, mode=mode))
    return g.glb()


# ---- hostile assets (issue 34): what a red team sent ----

def lying_jpeg(edge=8192):
    """The 16x16 JPEG whose frame header declares edge x edge: libjpeg pads
    the missing scans, so a 2 KB file would decode to edge^2 x 4 bytes."""
    jpg = bytearray(SOLID16_JPEG)
    sof = jpg.index(b"\xff\xc0")
    jpg[sof + 5:sof + 9] = struct.pack(">HH", edge, edge)
    return bytes(jpg)


def lying_png(edge=8192):
    """A PNG whose IHDR declares edge x edge over one row of data."""
    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", edge, edge, 8, 6, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(b"\0" * (edge * 4 + 1), 9)) + chunk(b"IEND", b""))


def image_asset(images, mime):
    """A cube whose material names each of images (bytes) as a texture."""
    g = Gltf()
    slots = ["baseColorTexture", "metallicRoughnessTexture"]
    pbr = {}
    extra = {}
    for k, data in enumerate(images):
        t = g.texture(g.image(data, mime=mime))
        if k < 2:
            pbr[slots[k]] = {"index": t}
        elif k == 2:
            extra["emissiveTexture"] = {"index": t}
        else:
            extra["occlusionTexture"] = {"index": t}
    m = g.material(pbrMetallicRoughness=pbr, **extra)
    g.node(mesh=g.mesh(cube(), material=m, uv1=False))
    return g


def unused_mesh_asset():
    """A valid glTF with a mesh no node uses (glTF allows it)."""
    g = Gltf()
    g.node(mesh=g.mesh(cube(), uv1=False, name="used"))
    g.mesh(grid(2), uv1=False, name="spare")
    return g


def node_chain_asset(levels):
    """A mesh at the bottom of a chain of levels nodes (the root is level 1)."""
    g = Gltf()
    mesh = g.mesh(cube(), uv1=False)
    g.node(root=True)
    for i in range(1, levels):
        g.node(root=False)
        g.doc["nodes"][i - 1]["children"] = [i]
    g.doc["nodes"][levels - 1]["mesh"] = mesh
    return g


def data_uri_asset(mutate):
    """The textured-less cube as .gltf with its buffer as a data URI; mutate
    (doc) changes it."""
    g = Gltf()
    g.node(mesh=g.mesh(cube(), uv1=False))
    doc = json.loads(g.gltf_data_uri())
    mutate(doc)
    return json.dumps(doc).encode()


def bad_base64_unpadded(doc):
    uri = doc["buffers"][0]["uri"]
    doc["buffers"][0]["uri"] = uri.rstrip("=") + "A"  # a length no base64 text has


def bad_base64_inner_pad(doc):
    head, data = doc["buffers"][0]["uri"].split(",", 1)
    doc["buffers"][0]["uri"] = head + "," + data[:8] + "=" + data[9:]


def data_longer_than_bytelength(doc):
    head, data = doc["buffers"][0]["uri"].split(",", 1)
    doc["buffers"][0]["uri"] = head + "," + base64.b64encode(base64.b64decode(data) +
                                                             b"\0" * 16).decode()


def many_nodes_asset(roots, mesh_nodes=1):
    """mesh_nodes root nodes instancing one triangle, then empty root nodes
    up to roots in all; the JSON written directly (a million nodes)."""
    tri = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)
    doc = {"asset": {"version": "2.0"}, "scene": 0,
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
           "buffers": [{"byteLength": len(tri)}],
           "bufferViews": [{"buffer": 0, "byteLength": len(tri)}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                          "min": [0, 0, 0], "max": [1, 1, 0]}]}
    head = json.dumps(doc, separators=(",", ":"))[:-1]
    nodes = ",".join(['{"mesh":0,"translation":[%d,0,0]}' % i for i in range(mesh_nodes)] +
                     ["{}"] * (roots - mesh_nodes))
    scene = ",".join(str(i) for i in range(roots))
    js = ('%s,"nodes":[%s],"scenes":[{"nodes":[%s]}]}' % (head, nodes, scene)).encode()
    return rebuild_glb_json(js, tri)


def rebuild_glb_json(js, binary):
    js += b" " * (-len(js) % 4)
    binary = bytes(binary) + b"\0" * (-len(binary) % 4)
    out = struct.pack("<I I", len(js), 0x4E4F534A) + js
    out += struct.pack("<I I", len(binary), 0x004E4942) + binary
    return b"glTF" + struct.pack("<I I", 2, 12 + len(out)) + out


def hostile_all(write):
    """The hostile files of issue 34 that are small enough for every run;
    write(name, data, **expect) as build_all's."""
    write("lying_jpeg.glb", image_asset([lying_jpeg()], "image/jpeg").glb(), exit=2, status=400,
          field="images[0]")
    write("lying_jpeg4.glb", image_asset([lying_jpeg()] * 4, "image/jpeg").glb(), exit=2,
          status=400, field="images[0]")
    write("lying_png.glb", image_asset([lying_png()], "image/png").glb(), exit=2, status=400,
          field="images[0]")
    write("unused_mesh.glb", unused_mesh_asset().glb(), exit=0,
          expect={"meshes": 1, "triangles": 12})
    write("chain_256.glb", node_chain_asset(256).glb(), exit=0, expect={"meshes": 1})
    write("chain_257.glb", node_chain_asset(257).glb(), exit=2, status=422, field="nodes[256]")
    write("base64_unpadded.gltf", data_uri_asset(bad_base64_unpadded), exit=2, status=400,
          field="buffers[0].uri")
    write("base64_inner_pad.gltf", data_uri_asset(bad_base64_inner_pad), exit=2, status=400,
          field="buffers[0].uri")
    write("data_longer.gltf", data_uri_asset(data_longer_than_bytelength), exit=2, status=400,
          field="buffers[0].byteLength")


def build_all(out, realistic=False, big_maps=False, hostile_big=False, cpu_seconds=60):
    os.makedirs(out, exist_ok=True)
    manifest = []

    def write(name, data, **expect):
        with open(os.path.join(out, name), "wb") as f:
            f.write(data)
        entry = {"file": name}
        entry.update(expect)
        manifest.append(entry)

    # 2 nodes x 12 triangles, generated uv1: one chart per face, 24 vertices each.
    tex = {"meshes": 2, "triangles": 24, "vertices": 48, "textures": [[8, 8], [16, 16], [32, 32]],
           "lights": {"point": ["bulb"], "spot": ["torch"], "directional": ["sun"]},
           "cameras": ["main"], "uv1": "generated", "slots": ["base_color", "metallic_roughness", "normal"],
           "texel": {"image": 0, "x": 5, "y": 5, "rgba": list(BASE_TEXEL)},
           "texel_checker": {"image": 0, "x": 1, "y": 0, "rgba": [0, 0, 0, 255]}}
    write("textured.glb", textured().glb(), exit=0, expect=tex)
    nn = dict(tex, textures=[[8, 8], [16, 16]], slots=["base_color", "metallic_roughness"])
    write("no_normal_map.glb", textured(normal_map=False).glb(), exit=0, expect=nn)
    write("uv1_file.glb", textured(uv1=True).glb(), exit=0,
          expect=dict(tex, uv1="file"))
    write("datauri.gltf", textured().gltf_data_uri(), exit=0, expect=tex)
    write("alpha.glb", alpha_asset().glb(), exit=0,
          expect={"meshes": 2, "triangles": 16, "vertices": 18, "alpha_modes": ["mask", "blend"], "lights": {},
                  "cameras": [], "uv1": "generated"})
    write("extras.glb", extras_asset().glb(), exit=0,
          expect={"meshes": 1, "triangles": 12, "cameras": ["plan"], "uv1": "generated",
                  "ignored": ["animations", "extension KHR_materials_clearcoat",
                              "points and lines primitives"],
                  "texture_transforms": {"base_color": {"offset": [0, 0], "rotation": 0, "scale": [2, 2]}}})
    write("quantized.glb", quantized_asset().glb(), exit=0,
          expect={"meshes": 1, "triangles": 12, "vertices": 24, "uv1": "file"})
    write("skinned.glb", skinned_asset().glb(), exit=0,
          expect={"meshes": 1, "triangles": 12, "uv1": "generated", "ignored": ["skins"]})
    jpg = jpeg_bytes()
    if jpg:
        g = Gltf()
        t = g.texture(g.image(jpg, mime="image/jpeg", name="photo"))
        m = g.material(pbrMetallicRoughness={"baseColorTexture": {"index": t}})
        g.node(mesh=g.mesh(cube(), material=m, uv1=False))
        write("jpeg.glb", g.glb(), exit=0,
              expect={"meshes": 1, "triangles": 12, "textures": [[16, 16]], "uv1": "generated",
                      "texel_near": {"image": 0, "x": 8, "y": 8, "rgba": [30, 160, 90, 255], "tolerance": 4}})
        # The same with the frame's sample precision 7: libjpeg's error exit.
        sof = jpg.index(b"\xff\xc0")
        bad = bytearray(jpg)
        bad[sof + 4] = 7
        g = Gltf()
        t = g.texture(g.image(bytes(bad), mime="image/jpeg"))
        m = g.material(pbrMetallicRoughness={"baseColorTexture": {"index": t}})
        g.node(mesh=g.mesh(cube(), material=m, uv1=False))
        write("bad_jpeg.glb", g.glb(), exit=2, status=400, field="images[0]")
    # The import-fidelity pairs (e2e_asset_import renders them) and what
    # the converter says of them.
    pairs = fidelity_pairs()
    for name, (a, b) in pairs.items():
        write("fid_%s_a.glb" % name, a.glb(), exit=0, expect={})
        write("fid_%s_b.glb" % name, b.glb(), exit=0, expect={})
    write("uv1_overlap.glb", overlap_asset(True).glb(), exit=0,
          expect={"uv1": "generated", "uv1_reason": "overlap", "triangles": 64})
    write("uv1_apart.glb", overlap_asset(False).glb(), exit=0,
          expect={"uv1": "file", "triangles": 64})
    write("texcoord1_outside.glb", texcoord_asset(1, False).glb(), exit=0,
          expect={"uv1": "generated", "uv1_reason": "leaves",
                  "texcoord": {"base_color": 1, "occlusion": 1, "emissive": 1},
                  "attributes": ["POSITION", "TEXCOORD_0", "TEXCOORD_1"]})
    write("vertex_colors.glb", colors_asset(True).glb(), exit=0,
          expect={"vertex_colors": 2, "attributes": ["POSITION", "TEXCOORD_0", "COLOR_0"]})
    write("texture_transform.glb", texture_transform_asset(True).glb(), exit=0,
          expect={"texcoord": {"base_color": 1}, "ignored": [],
                  "texture_transforms": {"base_color": TEX_TRANSFORM}})
    if realistic:
        data = realistic_asset(big_maps).glb()
        write("realistic_2k.glb" if big_maps else "realistic.glb", data, exit=0,
              expect={"meshes": 12, "triangles": 98304, "uv1": "generated"})

    good = textured(normal_map=False).glb()
    write("truncated.glb", good[:len(good) // 2], exit=2, status=400, field="file")
    write("wrong_magic.glb", b"glTX" + good[4:], exit=2, status=400, field="file")
    write("bad_json.gltf", b'{"asset": {"version": "2.0"}, "nodes": [', exit=2, status=400, field="file")
    write("glb_version1.glb", good[:4] + struct.pack("<I", 1) + good[8:], exit=2, status=422, field="file")
    data, field = bad_accessor_oob()
    write("accessor_oob.glb", data, exit=2, status=400, field=field)
    data, field = bad_view_oob()
    write("view_oob.glb", data, exit=2, status=400, field=field)
    data, field = bad_index_oob()
    write("index_oob.glb", data, exit=2, status=400, field=field)
    data, field = bad_huge_count()
    write("huge_count.glb", data, exit=2, status=422, field=field)
    data, field = bad_not_image()
    write("not_image.glb", data, exit=2, status=400, field=field)
    data, field = bad_uri("buffers", "../../etc/passwd")
    write("uri_passwd.gltf", data, exit=2, status=400, field=field)
    data, field = bad_uri("images", "file:///etc/passwd")
    write("uri_file.gltf", data, exit=2, status=400, field=field)
    data, field = bad_big_texture()
    write("big_texture.glb", data, exit=2, status=422, field=field)
    write("points_only.glb", bad_mode(0), exit=2, status=422, field="meshes")
    write("bad_mode.glb", bad_mode(9), exit=2, status=422, field="meshes[0].primitives[0]")
    write("over_vertices.glb", good, exit=2, status=422, field="limits.max_vertices",
          args=["--max-vertices", "10"])
    write("over_file_bytes.glb", good, exit=2, status=422, field="limits.max_file_bytes",
          args=["--max-file-bytes", "100"])
    hostile_all(write)
    if hostile_big:
        # Checked in time linear in the nodes (issue 34: each took the old
        # converter minutes, quadratic in nodes times roots), under a CPU
        # limit that minutes would run past.
        cpu = ["--max-cpu-seconds", str(cpu_seconds)]
        write("roots_1m.glb", many_nodes_asset(1000000), exit=2, status=422,
              field="limits.max_nodes", args=cpu)
        write("mesh_nodes_60k.glb", many_nodes_asset(60000, 60000), exit=0,
              expect={"meshes": 60000, "triangles": 60000}, args=cpu)
    with open(os.path.join(out, "manifest.json"), "w") as f:
        json.dump(manifest, f, indent=1)
    return manifest


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--realistic", action="store_true", help="also the benchmark-size asset")
    ap.add_argument("--big-maps", action="store_true", help="2048-texel maps in the realistic asset")
    a = ap.parse_args()
    m = build_all(a.out, a.realistic or a.big_maps, a.big_maps)
    print("gltf_gen: %d files in %s" % (len(m), a.out))


if __name__ == "__main__":
    main()
