#!/usr/bin/env python3
"""Re-frames recorded wire bytes for a new protocol version, every message kept byte for byte.

    scripts/reframe.py OLD NEW FILE...

Each FILE is a .pclog (its header's wire version is rewritten too) or a bare stream of frames
(a fuzz corpus input). Every frame of version OLD (COBS, then 0) gets version NEW and its
CRC-32 rewritten so that it stays as right or as wrong as it was: a frame damaged on purpose
keeps its damage. Anything that is not such a frame (a torn frame, noise) is left as it is.
Use it when a version bump leaves the phone's messages as they were; a message whose layout
changed needs the recording made again (tests/logs/make.sh). The one exception it knows:
version 5 gave the phone's set-up messages (StudentProfile, CoachSelect, Config, SensorLayout)
a sequence number as their first field, so going from below 5 to 5 or later it inserts one
into each, numbering them 0, 1, 2, ... in the order they come in each file.
"""
import itertools
import sys
import zlib

MAGIC = b"PCLOG"
HEADER_LEN = 8
# The set-up messages' variant indices, and the version that gave them a sequence number.
SETUP_VARIANTS = (2, 3, 4, 9)
SETUP_SEQ_VERSION = 5


def varint(n):
    out = bytearray()
    while True:
        byte = n & 0x7F
        n >>= 7
        if n:
            out.append(byte | 0x80)
        else:
            out.append(byte)
            return bytes(out)


def cobs_decode(data):
    out = bytearray()
    i = 0
    while i < len(data):
        code = data[i]
        block = data[i + 1 : i + code]
        if code == 0 or len(block) != code - 1 or 0 in block:
            return None
        out += block
        i += code
        if code < 0xFF and i < len(data):
            out.append(0)
    return bytes(out)


def cobs_encode(data):
    out = bytearray()
    block = bytearray()
    for byte in data:
        if byte == 0:
            out.append(len(block) + 1)
            out += block
            block.clear()
        else:
            block.append(byte)
            if len(block) == 0xFE:
                out.append(0xFF)
                out += block
                block.clear()
    out.append(len(block) + 1)
    out += block
    return bytes(out)


def reframe_frame(chunk, old, new, setups):
    payload = cobs_decode(chunk)
    # Only what this encoder writes back as it was (the device's COBS) is taken for a frame.
    if payload is None or len(payload) < 5 or payload[0] != old or cobs_encode(payload) != chunk:
        return chunk, False
    body, crc = payload[:-4], int.from_bytes(payload[-4:], "little")
    message = body[1:]
    if old < SETUP_SEQ_VERSION <= new and message[:1] and message[0] in SETUP_VARIANTS:
        message = message[:1] + varint(next(setups)) + message[1:]
    fresh = bytes([new]) + message
    # The CRC keeps its error: right stays right, damaged stays damaged by as much.
    crc ^= zlib.crc32(body) ^ zlib.crc32(fresh)
    encoded = cobs_encode(fresh + crc.to_bytes(4, "little"))
    assert cobs_decode(encoded) == fresh + crc.to_bytes(4, "little")
    return encoded, True


def reframe(data, old, new):
    head = b""
    if data.startswith(MAGIC) and len(data) >= HEADER_LEN:
        head = bytearray(data[:HEADER_LEN])
        if head[6] == old:
            head[6] = new
        head, data = bytes(head), data[HEADER_LEN:]
    chunks = data.split(b"\x00")
    count = 0
    setups = itertools.count()
    for i, chunk in enumerate(chunks):
        if chunk:
            chunks[i], done = reframe_frame(chunk, old, new, setups)
            count += done
    return head + b"\x00".join(chunks), count


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    old, new = int(sys.argv[1]), int(sys.argv[2])
    for path in sys.argv[3:]:
        with open(path, "rb") as f:
            data = f.read()
        out, count = reframe(data, old, new)
        if out != data:
            with open(path, "wb") as f:
                f.write(out)
        print(f"{path}: {count} frames")


if __name__ == "__main__":
    main()
