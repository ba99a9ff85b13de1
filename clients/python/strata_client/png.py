"""A minimal PNG decoder (zlib + struct): 8-bit greyscale, grey+alpha, RGB and RGBA, not
interlaced, every filter type. That covers what strata-server encodes (8-bit RGB)."""

import struct
import zlib
from typing import Any, Tuple

_SIGNATURE = b"\x89PNG\r\n\x1a\n"
_CHANNELS = {0: 1, 2: 3, 4: 2, 6: 4}  # PNG colour type -> samples per pixel


def _paeth(a: int, b: int, c: int) -> int:
    p = a + b - c
    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
    if pa <= pb and pa <= pc:
        return a
    return b if pb <= pc else c


def _unfilter_row(kind: int, row: bytearray, prev: bytearray, bpp: int) -> None:
    """Undoes one row's filter in place (PNG specification, section 9)."""
    n = len(row)
    if kind == 0:
        return
    if kind == 1:  # Sub
        for i in range(bpp, n):
            row[i] = (row[i] + row[i - bpp]) & 0xFF
    elif kind == 2:  # Up
        row[:] = bytes((x + y) & 0xFF for x, y in zip(row, prev))
    elif kind == 3:  # Average
        for i in range(n):
            left = row[i - bpp] if i >= bpp else 0
            row[i] = (row[i] + ((left + prev[i]) >> 1)) & 0xFF
    elif kind == 4:  # Paeth
        for i in range(n):
            left = row[i - bpp] if i >= bpp else 0
            upper_left = prev[i - bpp] if i >= bpp else 0
            row[i] = (row[i] + _paeth(left, prev[i], upper_left)) & 0xFF
    else:
        raise ValueError(f"PNG: unknown filter type {kind}")


def decode_png(data: bytes) -> Tuple[int, int, int, bytearray]:
    """Decodes a PNG; returns (width, height, channels, pixels), the pixels row by row with
    `channels` bytes each. Raises ValueError for anything else than the supported subset."""
    if not data.startswith(_SIGNATURE):
        raise ValueError("not a PNG (bad signature)")
    pos = len(_SIGNATURE)
    header = None
    compressed = bytearray()
    while pos + 8 <= len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        chunk = data[pos + 8:pos + 8 + length]
        if len(chunk) != length or pos + 12 + length > len(data):
            raise ValueError("PNG: truncated chunk")
        crc = struct.unpack(">I", data[pos + 8 + length:pos + 12 + length])[0]
        if zlib.crc32(kind + chunk) & 0xFFFFFFFF != crc:
            raise ValueError(f"PNG: bad CRC in {kind.decode('latin-1')} chunk")
        pos += 12 + length
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", chunk)
        elif kind == b"IDAT":
            compressed += chunk
        elif kind == b"IEND":
            break
    if header is None:
        raise ValueError("PNG: no IHDR chunk")
    width, height, depth, colour, _compression, _filter, interlace = header
    if depth != 8 or colour not in _CHANNELS or interlace != 0:
        raise ValueError(f"PNG: unsupported format (bit depth {depth}, colour type {colour}, "
                         f"interlace {interlace}); only 8-bit non-interlaced images are decoded")
    channels = _CHANNELS[colour]
    stride = width * channels
    raw = zlib.decompress(bytes(compressed))
    if len(raw) != height * (stride + 1):
        raise ValueError("PNG: image data has the wrong size")
    pixels = bytearray(height * stride)
    prev = bytearray(stride)
    for y in range(height):
        start = y * (stride + 1)
        row = bytearray(raw[start + 1:start + 1 + stride])
        _unfilter_row(raw[start], row, prev, channels)
        pixels[y * stride:(y + 1) * stride] = row
        prev = row
    return width, height, channels, pixels


def png_to_array(png: bytes) -> Any:
    """A PNG as a numpy uint8 array of shape (height, width, channels); imports numpy, only
    when called (the rest of the client needs the standard library only)."""
    import numpy as np

    width, height, channels, pixels = decode_png(png)
    return np.frombuffer(pixels, dtype=np.uint8).reshape(height, width, channels)
