"""shadebench-compare on translucent PNGs judges them as perceptualdiff does:
premultiplied by alpha (in float, before the gamma) for PerceptualDiff,
composited over black for SSIM, PSNR and FLIP.

The outside reference is perceptualdiff itself (github.com/myint/perceptualdiff
at 5850a7a, built against Debian 12's libfreeimage-dev; Debian packages no
perceptualdiff). Its counts on the two crops of its own test pairs kept
here (fixtures/perceptualdiff/README.md says which and under what licence)
were measured with that binary and are written below; they are not
computed by this project. perceptualdiff 2.x reads pixels in FreeImage's
byte order, which on little-endian machines swaps red and blue, so each
pair has two reference counts: perceptualdiff on the files (matched by
--swap-red-blue) and perceptualdiff on copies with red and blue swapped
(its count in true channel order, matched by default).

Before alpha was premultiplied, the alpha crop passed here with 0 failing
pixels (perceptualdiff: 358, a failure) and the fish crop counted 2,863
(perceptualdiff: 2,527 in true order). GL-free: no daemon."""

import json
import os
import struct
import subprocess
import tempfile
import zlib

import testlib
from testlib import check

COMPARE = os.environ.get("SHADEBENCH_COMPARE", "./shadebench-compare")
HERE = os.path.dirname(os.path.abspath(__file__))
FIX = os.path.join(HERE, "fixtures", "perceptualdiff")

# perceptualdiff 5850a7a's counts: --fov F A B on the files ("files") and
# on the files with red and blue swapped ("true order").
REFERENCE = [
    # (reference, test, fov, files, true order)
    ("fish2-crop.png", "fish1-crop.png", 45, 2178, 2527),
    ("alpha1-crop.png", "alpha2-crop.png", 9.5, 358, 186),
]


def compare(a, b, *args):
    out = subprocess.run([COMPARE, a, b] + [str(x) for x in args], capture_output=True,
                         text=True)
    return out.returncode, (json.loads(out.stdout) if out.stdout.strip() else {}), out.stderr


def write_png(path, w, h, pixels, alpha):
    """8-bit RGB (alpha False) or RGBA PNG from rows of tuples."""
    ctype, bpp = (6, 4) if alpha else (2, 3)
    raw = b"".join(b"\x00" + bytes(v for p in pixels[y * w:(y + 1) * w] for v in p[:bpp])
                   for y in range(h))

    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(
            ">I", zlib.crc32(kind + body) & 0xffffffff)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, ctype, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


for ref, test, fov, files, true_order in REFERENCE:
    a, b = os.path.join(FIX, ref), os.path.join(FIX, test)
    rc, res, err = compare(a, b, "--fov", fov, "--metrics", "pdiff")
    pd = res.get("pdiff", {})
    check(rc == 1 and pd.get("failing_pixels") == true_order and res.get("alpha") == "premultiplied",
          "%s against %s at %g degrees: %s failing pixels, perceptualdiff's %d (true channel "
          "order), and both fail: rc %d %s" % (test, ref, fov, pd.get("failing_pixels"), true_order,
                                               rc, err))
    rc, res, err = compare(a, b, "--fov", fov, "--metrics", "pdiff", "--swap-red-blue")
    check(rc == 1 and res.get("pdiff", {}).get("failing_pixels") == files,
          "with --swap-red-blue, perceptualdiff's own count on the files: %s against %d"
          % (res.get("pdiff", {}).get("failing_pixels"), files))

tmp = tempfile.mkdtemp(prefix="shadebench-alpha-")
W, H = 48, 32
# A red stroke and a black one, each half transparent, on a transparent
# ground; the second image changes both strokes' alpha only.
def stroke_image(red_alpha, black_alpha):
    px = []
    for y in range(H):
        for x in range(W):
            if 8 <= y < 14:
                px.append((230, 30, 20, red_alpha))
            elif 18 <= y < 24:
                px.append((0, 0, 0, black_alpha))
            else:
                px.append((90, 160, 200, 0))
    return px

base = stroke_image(128, 128)
paths = {}
for name, px in (("base", base), ("black", stroke_image(128, 255)),
                 ("red", stroke_image(255, 128))):
    paths[name] = os.path.join(tmp, name + ".png")
    write_png(paths[name], W, H, px, True)
rc, res, _ = compare(paths["base"], paths["black"])
check(rc == 0 and res["pdiff"]["failing_pixels"] == 0 and res["ssim"] == 1.0 and
      res["psnr"]["identical"] and res["flip"]["mean"] == 0.0,
      "an alpha change where the colour is black shows to no metric (premultiplied): %s" % res)
rc, res, _ = compare(paths["base"], paths["red"], "--threshold-pixels", 10)
check(rc == 1 and res["pdiff"]["failing_pixels"] >= 10 and res["ssim"] < 1.0 and
      res["flip"]["mean"] > 0, "an alpha change on the red stroke shows to every metric: pdiff %s, "
      "SSIM %s, FLIP %s" % (res["pdiff"], res["ssim"], res["flip"]["mean"]))

# SSIM, PSNR and FLIP see the image over black: a translucent image against
# its own composite (colour times alpha, rounded) written as opaque RGB.
over_black = [tuple((c * p[3] + 127) // 255 for c in p[:3]) for p in base]
paths["composite"] = os.path.join(tmp, "composite.png")
write_png(paths["composite"], W, H, over_black, False)
rc, res, _ = compare(paths["base"], paths["composite"], "--metrics", "ssim,psnr,flip")
check(rc == 0 and res["ssim"] == 1.0 and res["psnr"]["identical"] and res["flip"]["mean"] == 0.0,
      "SSIM, PSNR and FLIP compare the premultiplied colours: %s" % res)

# An opaque RGBA file is the RGB file: the same figures, alpha "opaque".
red_rgb = [tuple(p[:3]) for p in stroke_image(255, 255)]
for name, px, alpha in (("opaque_rgba", [p[:3] + (255,) for p in red_rgb], True),
                        ("opaque_rgb", red_rgb, False)):
    paths[name] = os.path.join(tmp, name + ".png")
    write_png(paths[name], W, H, px, alpha)
_, as_rgba, _ = compare(paths["opaque_rgba"], paths["composite"], "--metrics", "ssim,pdiff,psnr,flip")
_, as_rgb, _ = compare(paths["opaque_rgb"], paths["composite"], "--metrics", "ssim,pdiff,psnr,flip")
for res in (as_rgba, as_rgb):
    res.pop("reference", None), res.pop("timing_ms", None)
check(as_rgba == as_rgb and as_rgb.get("alpha") == "opaque",
      "an opaque RGBA PNG scores as its RGB twin: %s / %s" % (as_rgba.get("pdiff"), as_rgb.get("pdiff")))
testlib.finish("e2e_compare_alpha")
