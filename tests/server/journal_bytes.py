"""The byte formats of engine/durable/journal_format.h, written by hand for the suites that send
the server records and snapshots no client would: CRC-32C, a journal record, a snapshot file."""

import struct

_TABLE = []
for _n in range(256):
    _c = _n
    for _ in range(8):
        _c = (_c >> 1) ^ (0x82F63B78 if _c & 1 else 0)
    _TABLE.append(_c)


def crc32c(data: bytes) -> int:
    crc = 0xFFFFFFFF
    for byte in data:
        crc = _TABLE[(crc ^ byte) & 0xFF] ^ (crc >> 8)
    return crc ^ 0xFFFFFFFF


def log_entry(payload: bytes, version: int) -> bytes:
    """A well-formed journal record (and Redis log entry) of version `version` around `payload`."""
    v = version.to_bytes(8, "little")
    return (len(payload).to_bytes(4, "little") + crc32c(payload + v).to_bytes(4, "little") + v
            + payload)


def snapshot_file(payload: bytes, version: int) -> bytes:
    """A well-formed snapshot file of `version` around `payload` (an edit batch)."""
    return (b"STRATAS1" + struct.pack("<II", 1, crc32c(payload)) +
            struct.pack("<QQ", version, len(payload)) + payload)


def clears(count: int) -> bytes:
    """An edit batch of `count` one-byte clear edits (kind tag 13)."""
    return count.to_bytes(4, "little") + bytes([13]) * count
