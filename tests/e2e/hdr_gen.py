#!/usr/bin/env python3
"""Radiance .hdr (RGBE) images made from nothing, standard library only:
the environment maps the tests upload (good, truncated, huge).

    hdr_bytes(width, height, pixel, rle=True)

pixel(x, y) gives linear (r, g, b) floats; row 0 is the image's top. With
rle the scanlines are run-length coded channel by channel (widths 8 to
32767), as most writers do; else flat, 4 bytes a pixel."""
import math


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


def sky_and_ground(width=64, height=32):
    """Bright above the horizon (a warm top), dark below, a hot spot at
    +x: an environment whose shading shows where it comes from."""
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
    return hdr_bytes(width, height, pixel)
