"""The glTF converter (shadebench-asset) over every asset gltf_gen.py makes:
exit codes, the refusals' status and field, the descriptions (meshes,
triangles, textures and their sizes, lights by type, cameras, uv1 from the
file or generated with its waste and why, a TEXCOORD_1 whose charts
overlap caught, each texture's uv set and transform, the vertex
attributes, COLOR_0, ignored features), decoded texels read
back from the cache file, no cache left by a refusal, and the process
limits; issue 34's hostile files (a JPEG or PNG whose header lies about
its size, an unused mesh, node chains of 256 and 257 levels, bad base64, a
data URI longer than byteLength, a million root nodes, 60,000 mesh nodes
under a CPU-time limit). No daemon, no GL."""

import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import gltf_gen  # noqa: E402
import testlib  # noqa: E402
from testlib import check, finish  # noqa: E402

CONVERTER = os.environ.get("SHADEBENCH_ASSET", "./shadebench-asset")
SANITIZERS = bool(os.environ.get("SHADEBENCH_SANITIZERS"))


def read_cache_images(path):
    """The images of a cache file (docs/assets.md's layout): [(w, h, rgba)]."""
    with open(path, "rb") as f:
        data = f.read()
    if data[:8] != b"SBASSET\0":
        return None
    nmesh, nmat, nimg, nlight, ncam, nign = struct.unpack_from("<6I", data, 16)
    off = 64 + nign * 128 + nmat * 352 + nlight * 120 + ncam * 120
    images = []
    for _ in range(nimg):
        w, h = struct.unpack_from("<II", data, off + 64)
        off += 72
        images.append((w, h, data[off:off + w * h * 4]))
        off += w * h * 4
    return images


def flat(v):
    """The numbers of a JSON value, keys sorted."""
    if isinstance(v, dict):
        return [x for k in sorted(v) for x in flat(v[k])]
    if isinstance(v, list):
        return [x for i in v for x in flat(i)]
    return [float(v)]


def texel(images, spec):
    w, h, px = images[spec["image"]]
    o = (spec["y"] * w + spec["x"]) * 4
    return list(px[o:o + 4])


def convert(src, dst, args=()):
    p = subprocess.run([CONVERTER, "convert", src, dst] + list(args), capture_output=True,
                       timeout=120 * (10 if SANITIZERS else 1))
    out = p.stdout.decode(errors="replace").strip()
    try:
        doc = json.loads(out) if out else None
    except ValueError:
        doc = None
    return p.returncode, doc, out, p.stderr.decode(errors="replace")


def check_good(name, entry, doc, cache):
    e = entry["expect"]
    check(doc is not None, "%s: stdout is one JSON object" % name)
    if doc is None:
        return
    for key in ("meshes", "triangles", "vertices"):
        if key in e:
            check(doc.get(key) == e[key], "%s: %s %s, expected %s" % (name, key, doc.get(key), e[key]))
    if "textures" in e:
        got = [[t["width"], t["height"]] for t in doc["textures"]]
        check(got == e["textures"], "%s: texture sizes %s, expected %s" % (name, got, e["textures"]))
    if "lights" in e:
        for kind in ("point", "spot", "directional"):
            want = e["lights"].get(kind, [])
            check(doc["lights"][kind] == want, "%s: %s lights %s, expected %s"
                  % (name, kind, doc["lights"][kind], want))
    if "cameras" in e:
        got = [c["name"] for c in doc["cameras"]]
        check(got == e["cameras"], "%s: cameras %s, expected %s" % (name, got, e["cameras"]))
    if "uv1" in e:
        check(doc["uv1"]["origin"] == e["uv1"], "%s: uv1 %s, expected %s"
              % (name, doc["uv1"]["origin"], e["uv1"]))
        for m in doc["mesh_list"]:
            check(m["uv1"] == e["uv1"], "%s: mesh %s uv1 %s" % (name, m["name"], m["uv1"]))
            check(0 < m["uv1_waste"] < 1, "%s: mesh %s uv1 waste %s in (0, 1)"
                  % (name, m["name"], m["uv1_waste"]))
            if "uv1_reason" in e:
                check(e["uv1_reason"] in m.get("uv1_reason", ""), "%s: mesh %s uv1 generated because %s"
                      % (name, m["name"], m.get("uv1_reason")))
    if "attributes" in e:
        for m in doc["mesh_list"]:
            check(m["attributes"] == e["attributes"], "%s: mesh %s attributes %s, expected %s"
                  % (name, m["name"], m["attributes"], e["attributes"]))
    if "vertex_colors" in e:
        check(doc["vertex_colors"] == e["vertex_colors"], "%s: %s meshes with COLOR_0"
              % (name, doc["vertex_colors"]))
    for key in ("texcoord", "texture_transforms"):
        if key in e:
            got = doc["materials"][0].get(key, {})
            want = json.loads(json.dumps(e[key]))
            close = json.dumps(got, sort_keys=True) == json.dumps(want, sort_keys=True) or all(
                abs(a - b) < 1e-6 for a, b in zip(flat(got), flat(want))) and len(flat(got)) == len(flat(want))
            check(close, "%s: material %s %s, expected %s" % (name, key, got, want))
    if "slots" in e:
        check(doc["materials"][0]["textures"] == e["slots"], "%s: slots %s, expected %s"
              % (name, doc["materials"][0]["textures"], e["slots"]))
    if "alpha_modes" in e:
        got = [m["alpha_mode"] for m in doc["materials"]]
        check(got == e["alpha_modes"], "%s: alpha modes %s" % (name, got))
    if "ignored" in e:
        check(sorted(doc["ignored"]) == sorted(e["ignored"]), "%s: ignored %s, expected %s"
              % (name, doc["ignored"], e["ignored"]))
    check(all(doc["bounds"]["min"][k] <= doc["bounds"]["max"][k] for k in range(3)),
          "%s: bounds ordered" % name)
    images = read_cache_images(cache)
    check(images is not None, "%s: the cache starts with its magic" % name)
    for key in ("texel", "texel_checker"):
        if key in e and images:
            got = texel(images, e[key])
            check(got == e[key]["rgba"], "%s: %s decoded %s, expected %s" % (name, key, got, e[key]["rgba"]))
    if "texel_near" in e and images:
        got = texel(images, e["texel_near"])
        tol = e["texel_near"]["tolerance"]
        check(all(abs(a - b) <= tol for a, b in zip(got, e["texel_near"]["rgba"])),
              "%s: JPEG texel %s near %s" % (name, got, e["texel_near"]["rgba"]))


def main():
    tmp = tempfile.mkdtemp(prefix="e2e_assets.")
    try:
        manifest = gltf_gen.build_all(tmp, hostile_big=True,
                                      cpu_seconds=int(60 * testlib.TIME_SCALE))
        check(len(manifest) >= 20, "generator wrote %d assets" % len(manifest))
        for entry in manifest:
            name = entry["file"]
            src = os.path.join(tmp, name)
            cache = os.path.join(tmp, name + ".sbasset")
            rc, doc, out, err = convert(src, cache, entry.get("args", []))
            if not check(rc == entry["exit"], "%s: exit %d, expected %d (stdout %s, stderr %s)"
                         % (name, rc, entry["exit"], out[:300], err[:300])):
                continue
            if rc == 0:
                check(os.path.exists(cache), "%s: cache written" % name)
                # The daemon reads at most 1 MiB of it (ASSETS_MAX_STDOUT).
                check(len(out) < (1 << 20), "%s: the description is %d bytes, under 1 MiB"
                      % (name, len(out)))
                if doc and doc.get("meshes", 0) > 1024:
                    check(len(doc.get("mesh_list", [])) == 1024 and
                          doc.get("mesh_list_omitted") == doc["meshes"] - 1024,
                          "%s: the mesh list holds 1024 meshes and counts the rest" % name)
                check_good(name, entry, doc, cache)
            else:
                check(doc is not None and set(doc) == {"status", "field", "message"},
                      "%s: refusal is {status, field, message}: %s" % (name, out))
                if doc:
                    check(doc["status"] == entry["status"] and doc["field"] == entry["field"],
                          "%s: %s %s, expected %s %s (%s)" % (name, doc["status"], doc["field"],
                                                              entry["status"], entry["field"],
                                                              doc.get("message")))
                    check(bool(doc["message"]), "%s: a message" % name)
                check(not os.path.exists(cache), "%s: no cache left by a refusal" % name)
        # A relative output path, and the limits applied as rlimits (not
        # under ASan, whose shadow memory RLIMIT_AS would take away).
        src = os.path.join(tmp, "textured.glb")
        args = [] if SANITIZERS else ["--max-memory", str(1 << 30), "--max-cpu-seconds", "30"]
        p = subprocess.run([os.path.abspath(CONVERTER), "convert", src, "rel.sbasset"] + args,
                           cwd=tmp, capture_output=True, timeout=120 * (10 if SANITIZERS else 1))
        check(p.returncode == 0 and os.path.exists(os.path.join(tmp, "rel.sbasset")),
              "relative OUT_CACHE written beside the caller (rc %d, %s)" % (p.returncode, p.stderr[:200]))
        # A memory limit too small to import: a failed load, never exit 0 or 2.
        if not SANITIZERS:
            p = subprocess.run([CONVERTER, "convert", src, os.path.join(tmp, "small.sbasset"),
                                "--max-memory", str(8 << 20)], capture_output=True, timeout=60)
            check(p.returncode not in (0, 2), "8 MiB of address space: the loader fails (rc %d)"
                  % p.returncode)
        rc, _, _, _ = convert(os.path.join(tmp, "no_such_file.glb"), os.path.join(tmp, "x"))
        check(rc == 1, "a missing input is exit 1, not a refusal (rc %d)" % rc)
        p = subprocess.run([CONVERTER, "convert"], capture_output=True)
        check(p.returncode == 1, "usage error is exit 1")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    finish("e2e_assets")


main()
