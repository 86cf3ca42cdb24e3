"""Loads the sketchbody shared library with ctypes (standard library only), calls skb_version and
skb_canny, and compares the edge map with the Rust result produced by `sketchbody edges` on the
same image. Run: python3 tests/python/test_capi.py (after `cargo build --release`).
Environment: SKB_LIB (shared library path), SKB_CLI (CLI path); default target/release/."""

import ctypes
import os
import struct
import subprocess
import tempfile
import tomllib
import unittest
import zlib

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
LIB = os.environ.get("SKB_LIB", os.path.join(ROOT, "target", "release", "libsketchbody.so"))
CLI = os.environ.get("SKB_CLI", os.path.join(ROOT, "target", "release", "sketchbody"))


class SkbImage(ctypes.Structure):
    _fields_ = [("data", ctypes.POINTER(ctypes.c_uint8)), ("width", ctypes.c_uint32),
                ("height", ctypes.c_uint32), ("stride", ctypes.c_uint32), ("channels", ctypes.c_uint32)]


def load_library():
    lib = ctypes.CDLL(LIB)
    lib.skb_version.restype = ctypes.c_char_p
    lib.skb_last_error_message.restype = ctypes.c_char_p
    lib.skb_status_str.restype = ctypes.c_char_p
    lib.skb_status_str.argtypes = [ctypes.c_uint32]
    lib.skb_canny.restype = ctypes.c_uint32
    lib.skb_canny.argtypes = [ctypes.POINTER(SkbImage), ctypes.c_double, ctypes.c_double, ctypes.c_int32,
                              ctypes.c_bool, ctypes.POINTER(ctypes.c_uint8), ctypes.c_size_t, ctypes.c_size_t]
    return lib


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


def test_image(width, height):
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


class CApiTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.lib = load_library()

    def test_version_matches_cargo_toml(self):
        with open(os.path.join(ROOT, "Cargo.toml"), "rb") as f:
            version = tomllib.load(f)["package"]["version"]
        self.assertEqual(self.lib.skb_version().decode(), version)

    def test_canny_matches_rust_cli(self):
        w, h = 97, 64
        pixels = test_image(w, h)
        buf = (ctypes.c_uint8 * (w * h))(*pixels)
        img = SkbImage(ctypes.cast(buf, ctypes.POINTER(ctypes.c_uint8)), w, h, w, 1)
        out = (ctypes.c_uint8 * (w * h))()
        status = self.lib.skb_canny(ctypes.byref(img), 30.0, 90.0, 3, False, out, w, w * h)
        self.assertEqual(status, 0, self.lib.skb_last_error_message())
        ours = list(out)
        self.assertTrue(any(ours), "the test card must have edges")
        self.assertTrue(set(ours) <= {0, 255})
        with tempfile.TemporaryDirectory() as tmp:
            src, dst = os.path.join(tmp, "in.png"), os.path.join(tmp, "edges.png")
            write_gray_png(src, w, h, pixels)
            subprocess.run([CLI, "edges", src, dst, "--low", "30", "--high", "90"], check=True)
            rw, rh, rust = read_gray_png(dst)
        self.assertEqual((rw, rh), (w, h))
        diff = [i for i in range(w * h) if rust[i] != ours[i]]
        self.assertEqual(diff, [], f"{len(diff)} pixels differ, first at index {diff[:1]}")

    def test_error_path_sets_status_and_message(self):
        out = (ctypes.c_uint8 * 4)(*([7] * 4))
        status = self.lib.skb_canny(None, 1.0, 2.0, 3, False, out, 2, 4)
        self.assertEqual(status, 1)
        self.assertIn(b"NULL", self.lib.skb_last_error_message())
        self.assertEqual(list(out), [7] * 4)
        self.assertEqual(self.lib.skb_status_str(status), b"a required pointer argument was NULL")


if __name__ == "__main__":
    unittest.main(verbosity=2)
