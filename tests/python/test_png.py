"""The client's PNG decoder against images encoded here with every filter type and colour type,
and against what strata-server sends."""

import random
import struct
import unittest
import zlib

from strata_client import decode_png


def _paeth(a, b, c):
    p = a + b - c
    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
    if pa <= pb and pa <= pc:
        return a
    return b if pb <= pc else c


def encode_png(width, height, colour, pixels, filters):
    """A reference encoder: row y uses filter filters[y % len(filters)]."""
    channels = {0: 1, 2: 3, 4: 2, 6: 4}[colour]
    stride = width * channels
    raw = bytearray()
    prev = bytes(stride)
    for y in range(height):
        row = pixels[y * stride:(y + 1) * stride]
        kind = filters[y % len(filters)]
        out = bytearray()
        for i in range(stride):
            left = row[i - channels] if i >= channels else 0
            up = prev[i]
            upper_left = prev[i - channels] if i >= channels else 0
            predictor = [0, left, up, (left + up) >> 1, _paeth(left, up, upper_left)][kind]
            out.append((row[i] - predictor) & 0xFF)
        raw += bytes([kind]) + out
        prev = row

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(
            ">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    # Two IDAT chunks: a decoder must join them.
    compressed = zlib.compress(bytes(raw))
    half = len(compressed) // 2
    return (b"\x89PNG\r\n\x1a\n"
            + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, colour, 0, 0, 0))
            + chunk(b"tEXt", b"Comment\x00ignored")
            + chunk(b"IDAT", compressed[:half]) + chunk(b"IDAT", compressed[half:])
            + chunk(b"IEND", b""))


class DecodePngTest(unittest.TestCase):
    def test_every_filter_and_colour_type_decodes_to_the_pixels(self):
        rng = random.Random(7)
        for colour, channels in ((0, 1), (2, 3), (4, 2), (6, 4)):
            width, height = 13, 11
            pixels = bytes(rng.randrange(256) for _ in range(width * height * channels))
            png = encode_png(width, height, colour, pixels, [0, 1, 2, 3, 4])
            self.assertEqual(decode_png(png), (width, height, channels, bytearray(pixels)),
                             f"colour type {colour}")

    def test_unsupported_or_damaged_images_are_refused(self):
        good = encode_png(2, 2, 2, bytes(12), [1])
        with self.assertRaisesRegex(ValueError, "signature"):
            decode_png(b"GIF89a" + good)
        damaged = bytearray(good)
        damaged[40] ^= 0xFF
        with self.assertRaisesRegex(ValueError, "CRC|size|truncated"):
            decode_png(bytes(damaged))
        for depth, colour, interlace in ((16, 2, 0), (8, 3, 0), (8, 2, 1)):
            header = struct.pack(">IIBBBBB", 2, 2, depth, colour, 0, 0, interlace)
            ihdr = (struct.pack(">I", 13) + b"IHDR" + header
                    + struct.pack(">I", zlib.crc32(b"IHDR" + header) & 0xFFFFFFFF))
            with self.assertRaisesRegex(ValueError, "unsupported format"):
                decode_png(good[:8] + ihdr + good[33:])
        with self.assertRaisesRegex(ValueError, "truncated"):
            decode_png(good[:30])


if __name__ == "__main__":
    unittest.main()
