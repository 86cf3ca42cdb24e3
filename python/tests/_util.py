"""Shared helpers of the package tests: paths, a tiny PNG writer/reader (standard library only),
the gray test card of the former tests/python/test_capi.py."""

import os
import struct
import zlib

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EXAMPLES = os.path.join(ROOT, "assets", "examples")
SKETCH = os.path.join(EXAMPLES, "sketch.png")
SKETCH_JOINTS = os.path.join(EXAMPLES, "sketch_joints.json")
CLI = os.environ.get("SKB_CLI", os.path.join(ROOT, "target", "release", "sketchbody"))


def write_gray_png(path, width, height, pixels):
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    raw = b"".join(b"\x00" + bytes(pixels[y * width:(y + 1) * width]) for y in range(height))
    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(png)


def read_gray_png(path):
    """Reads an 8-bit gray, non-interlaced PNG (what `sketchbody edges` writes)."""
    with open(path, "rb") as f:
        data = f.read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, idat, width = 8, b"", 0
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos:pos + 4])
        kind, body = data[pos + 4:pos + 8], data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, color, _, _, interlace = struct.unpack(">IIBBBBB", body)
            assert (depth, color, interlace) == (8, 0, 0), "expected 8-bit gray, non-interlaced"
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw, out, prev = zlib.decompress(idat), [], [0] * width
    for y in range(height):
        ftype, line = raw[y * (width + 1)], list(raw[y * (width + 1) + 1:(y + 1) * (width + 1)])
        for x in range(width):
            a = line[x - 1] if x else 0
            b, c = prev[x], prev[x - 1] if x else 0
            if ftype == 1:
                line[x] = (line[x] + a) & 255
            elif ftype == 2:
                line[x] = (line[x] + b) & 255
            elif ftype == 3:
                line[x] = (line[x] + (a + b) // 2) & 255
            elif ftype == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        out.extend(line)
        prev = line
    return width, height, out


def test_card(width, height):
    """A gray test card: a filled disc, a diagonal bar and a gradient."""
    px = []
    for y in range(height):
        for x in range(width):
            v = (x * 255) // width // 3
            if (x - width * 0.35) ** 2 + (y - height * 0.5) ** 2 < (height * 0.25) ** 2:
                v = 220
            if abs((x - y) - width * 0.3) < 4:
                v = 20
            px.append(v)
    return px
