#!/usr/bin/env python3
"""Radiance .hdr (RGBE) and OpenEXR images made from nothing, standard
library only: the environment maps the tests upload (good, truncated,
huge).

    hdr_bytes(width, height, pixel, rle=True)
    exr_bytes(width, height, pixel, compression="zip", pixel_type="half",
              channels="RGB", tile=None)

pixel(x, y) gives linear (r, g, b) floats; row 0 is the image's top. With
rle the scanlines are run-length coded channel by channel (widths 8 to
32767), as most writers do; else flat, 4 bytes a pixel. exr_bytes writes a
single-part scanline OpenEXR file (or tiled, one level, with tile = (w, h))
as the OpenEXR file layout says: uncompressed ("none"), or zlib with
OpenEXR's byte split and delta predictor ("zips": a line a chunk, "zip":
16)."""
import math
import struct
import zlib


def rgbe(r, g, b):
    v = max(r, g, b)
    if v < 1e-32:
        return bytes((0, 0, 0, 0))
    m, e = math.frexp(v)
    scale = m * 256.0 / v
    return bytes((int(r * scale), int(g * scale), int(b * scale), e + 128))


def _rle_channel(values):
    """One channel of a scanline: literal runs only (valid, simple)."""
    out = bytearray()
    i = 0
    while i < len(values):
        # a run of equal bytes (at least 3) as a run, else literals
        j = i
        while j < len(values) and values[j] == values[i] and j - i < 127:
            j += 1
        if j - i >= 3:
            out += bytes((128 + j - i, values[i]))
            i = j
            continue
        k = i
        while k < len(values) and k - i < 128:
            if k + 2 < len(values) and values[k] == values[k + 1] == values[k + 2]:
                break
            k += 1
        out.append(k - i)
        out += bytes(values[i:k])
        i = k
    return bytes(out)


def hdr_bytes(width, height, pixel, rle=True, header_size=None):
    """header_size: (width, height) the header claims, when it should lie."""
    hw, hh = header_size or (width, height)
    out = bytearray(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n")
    out += b"-Y %d +X %d\n" % (hh, hw)
    for y in range(height):
        row = [rgbe(*pixel(x, y)) for x in range(width)]
        if rle and 8 <= width < 32768:
            out += bytes((2, 2, width >> 8, width & 255))
            for c in range(4):
                out += _rle_channel([p[c] for p in row])
        else:
            out += b"".join(row)
    return bytes(out)


def _exr_attr(name, kind, value):
    return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(value)) + value


def _exr_zip(raw):
    """OpenEXR's ZIP(S) coding: the bytes split into even and odd halves,
    each byte stored as its difference from the one before (+128), zlib."""
    t = bytearray(raw[0::2] + raw[1::2])
    prev = t[0] if t else 0
    for i in range(1, len(t)):
        cur = t[i]
        t[i] = (cur - prev + 128 + 256) & 255
        prev = cur
    return zlib.compress(bytes(t))


def exr_bytes(width, height, pixel, compression="zip", pixel_type="half", channels="RGB",
              tile=None, header_size=None):
    """header_size: (width, height) the data window claims, when it should
    lie. channels: "RGB", "RGBA" (alpha 1) or "Y" (the mean of r, g, b)."""
    hw, hh = header_size or (width, height)
    comp = {"none": 0, "zips": 2, "zip": 3}[compression]
    lines = {"none": 1, "zips": 1, "zip": 16}[compression]
    ptype, fmt, size = {"half": (1, "e", 2), "float": (2, "f", 4)}[pixel_type]
    names = sorted(channels)  # OpenEXR lists channels alphabetically
    chlist = b"".join(n.encode() + b"\0" + struct.pack("<iB3xii", ptype, 0, 1, 1) for n in names)
    header = (_exr_attr("channels", "chlist", chlist + b"\0")
              + _exr_attr("compression", "compression", bytes((comp,)))
              + _exr_attr("dataWindow", "box2i", struct.pack("<4i", 0, 0, hw - 1, hh - 1))
              + _exr_attr("displayWindow", "box2i", struct.pack("<4i", 0, 0, hw - 1, hh - 1))
              + _exr_attr("lineOrder", "lineOrder", b"\0")
              + _exr_attr("pixelAspectRatio", "float", struct.pack("<f", 1.0))
              + _exr_attr("screenWindowCenter", "v2f", struct.pack("<2f", 0, 0))
              + _exr_attr("screenWindowWidth", "float", struct.pack("<f", 1.0)))
    if tile:
        header += _exr_attr("tiles", "tiledesc", struct.pack("<IIB", tile[0], tile[1], 0))
    header += b"\0"

    def value(x, y, name):
        r, g, b = pixel(x, y)
        return {"R": r, "G": g, "B": b, "A": 1.0, "Y": (r + g + b) / 3}[name]

    def block(x0, y0, w, h):
        raw = b"".join(struct.pack("<%d%s" % (w, fmt), *[value(x, y, n) for x in range(x0, x0 + w)])
                       for y in range(y0, y0 + h) for n in names)
        if comp:
            z = _exr_zip(raw)
            if len(z) < len(raw):
                return z
        return raw
    chunks = []
    if tile:
        tw, th = tile
        for ty in range((height + th - 1) // th):
            for tx in range((width + tw - 1) // tw):
                w, h = min(tw, width - tx * tw), min(th, height - ty * th)
                data = block(tx * tw, ty * th, w, h)
                chunks.append(struct.pack("<5i", tx, ty, 0, 0, len(data)) + data)
    else:
        for y0 in range(0, height, lines):
            data = block(0, y0, width, min(lines, height - y0))
            chunks.append(struct.pack("<2i", y0, len(data)) + data)
    version = 2 | (0x200 if tile else 0)
    head = b"\x76\x2f\x31\x01" + struct.pack("<i", version) + header
    table, offset = b"", len(head) + 8 * len(chunks)
    for c in chunks:
        table += struct.pack("<Q", offset)
        offset += len(c)
    return head + table + b"".join(chunks)


def sky_pixel(width=64, height=32):
    """sky_and_ground's pixel(x, y)."""
    def pixel(x, y):
        lat = math.pi * (0.5 - (y + 0.5) / height)
        lon = 2 * math.pi * ((x + 0.5) / width - 0.5)
        if lat > 0:
            r, g, b = 0.6 + 0.4 * math.sin(lat), 0.7, 0.9
        else:
            r, g, b = 0.1, 0.08, 0.06
        if abs(lat) < 0.2 and abs(lon) < 0.3:
            r, g, b = 8.0, 7.0, 6.0
        return r, g, b
    return pixel


def sky_and_ground_exr(width=64, height=32, **kw):
    """sky_and_ground as an OpenEXR image (exr_bytes' options)."""
    return exr_bytes(width, height, sky_pixel(width, height), **kw)


def sky_and_ground(width=64, height=32):
    """Bright above the horizon (a warm top), dark below, a hot spot at
    +x: an environment whose shading shows where it comes from."""
    return hdr_bytes(width, height, sky_pixel(width, height))

