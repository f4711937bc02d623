"""Our SSIM against an independent implementation: scikit-image's
structural_similarity (gaussian_weights=True, sigma=1.5,
use_sample_covariance=False, data_range=255), within 1e-4, on generated
pairs: noise, shifted blocks, blur, colour shift, identical, and a real
render pair. Also checks the images-smaller-than-the-window error."""

import json
import os
import subprocess
import sys
import tempfile

try:
    import numpy as np
    from PIL import Image
    from skimage.metrics import structural_similarity
except ImportError:
    # Debian's python3-skimage lives under /usr/bin/python3; another python3
    # first on PATH (pyenv, venv) may not see it.
    if sys.executable != "/usr/bin/python3" and os.path.exists("/usr/bin/python3"):
        os.execv("/usr/bin/python3", ["/usr/bin/python3"] + sys.argv)
    print("FAIL: scikit-image, numpy and PIL are needed (Debian: python3-skimage python3-pil)")
    sys.exit(1)

COMPARE = os.environ.get("SHADEBENCH_COMPARE", "./shadebench-compare")
TOL = 1e-4
failures = 0


def check(cond, what):
    global failures
    if not cond:
        failures += 1
        print("FAIL:", what, flush=True)


def ours(a_path, b_path):
    out = subprocess.run([COMPARE, a_path, b_path, "--metrics", "ssim"], capture_output=True,
                         text=True)
    return out.returncode, (json.loads(out.stdout) if out.stdout.strip() else None), out.stderr


def luma(img):
    img = img.astype(np.float64)
    return 0.299 * img[..., 0] + 0.587 * img[..., 1] + 0.114 * img[..., 2]


def reference(a, b):
    kw = dict(gaussian_weights=True, sigma=1.5, use_sample_covariance=False, data_range=255)
    y = structural_similarity(luma(a), luma(b), **kw)
    rgb = structural_similarity(a.astype(np.float64), b.astype(np.float64), channel_axis=2, **kw)
    return y, rgb


rng = np.random.default_rng(2004)
H, W = 96, 128
base = rng.integers(0, 256, (H, W, 3), dtype=np.uint8)
smooth = np.zeros((H, W, 3), np.uint8)
yy, xx = np.mgrid[0:H, 0:W]
smooth[..., 0] = (xx * 2) % 256
smooth[..., 1] = (yy * 2) % 256
smooth[..., 2] = ((xx + yy) * 3) % 256


def blur(img):
    f = img.astype(np.float64)
    k = np.array([1, 4, 6, 4, 1], np.float64) / 16
    for axis in (0, 1):
        f = np.apply_along_axis(lambda v: np.convolve(np.pad(v, 2, mode="edge"), k, "valid"), axis, f)
    return np.clip(np.rint(f), 0, 255).astype(np.uint8)


shifted = smooth.copy()
shifted[20:60, 30:90] = np.roll(smooth[20:60, 30:90], 7, axis=1)
pairs = {
    "noise": (smooth, np.clip(smooth + rng.normal(0, 12, smooth.shape), 0, 255).astype(np.uint8)),
    "random vs noise": (base, np.clip(base.astype(int) + rng.integers(-30, 31, base.shape), 0, 255).astype(np.uint8)),
    "shifted block": (smooth, shifted),
    "blurred": (smooth, blur(smooth)),
    "colour shift": (smooth, np.clip(smooth.astype(int) + [25, -10, 5], 0, 255).astype(np.uint8)),
    "identical": (smooth, smooth.copy()),
    "flat vs flat": (np.full((H, W, 3), 200, np.uint8), np.full((H, W, 3), 190, np.uint8)),
    "minimum size": (base[:11, :11], blur(base)[:11, :11]),
}
render_a = os.environ.get("SSIM_RENDER_A")
render_b = os.environ.get("SSIM_RENDER_B")
if render_a and render_b:
    pairs["render"] = (np.asarray(Image.open(render_a).convert("RGB")),
                       np.asarray(Image.open(render_b).convert("RGB")))

with tempfile.TemporaryDirectory() as tmp:
    for name, (a, b) in pairs.items():
        pa, pb = os.path.join(tmp, "a.png"), os.path.join(tmp, "b.png")
        Image.fromarray(a).save(pa)
        Image.fromarray(b).save(pb)
        rc, res, err = ours(pa, pb)
        check(rc == 0 and res is not None, "%s: shadebench-compare ran (%s)" % (name, err))
        if not res:
            continue
        y, rgb = reference(a, b)
        print("%-16s ours %.8f / %.8f   skimage %.8f / %.8f" % (name, res["ssim"], res["ssim_rgb"], y, rgb))
        check(abs(res["ssim"] - y) <= TOL, "%s: luma SSIM %.8f vs skimage %.8f" % (name, res["ssim"], y))
        check(abs(res["ssim_rgb"] - rgb) <= TOL, "%s: RGB SSIM %.8f vs skimage %.8f" % (name, res["ssim_rgb"], rgb))
        if name == "identical":
            check(res["ssim"] == 1.0 and res["ssim_min"]["value"] == 1.0, "identical images give SSIM 1")

    # Smaller than the window: a clear error, exit 2.
    small = os.path.join(tmp, "small.png")
    Image.fromarray(base[:10, :40]).save(small)
    rc, res, err = ours(small, small)
    check(rc == 2 and "smaller than the 11x11 window" in err, "10-pixel-high images are refused: %d %s" % (rc, err))

print("ssim_skimage: %d failed" % failures)
sys.exit(1 if failures else 0)
