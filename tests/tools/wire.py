"""The link's two checks in Python, one place for the project's scripts (the bad-input
corpus's generators, the minimal client, the TUI round-trip trace): CRC-32C (PROTOCOL.md §2,
Castagnoli, reflected, init and final xor 0xFFFFFFFF), COBS both ways (§2; the 0x00 delimiter
is the caller's) and the LEB128 varint both ways (§5)."""


def crc32c(data):
    crc = 0xFFFFFFFF
    for b in data:
        crc ^= b
        for _ in range(8):
            crc = (crc >> 1) ^ (0x82F63B78 if crc & 1 else 0)
    return crc ^ 0xFFFFFFFF


def cobs(raw):
    """COBS-encodes `raw` (no delimiter)."""
    out, block = bytearray(), bytearray()
    for b in raw:
        if b == 0:
            out.append(len(block) + 1)
            out += block
            block = bytearray()
        else:
            block.append(b)
            if len(block) == 254:
                out.append(255)
                out += block
                block = bytearray()
    out.append(len(block) + 1)
    out += block
    return bytes(out)


def uncobs(enc):
    """COBS-decodes `enc` (no delimiter); None when a 0x00 is inside, which COBS never writes."""
    out, i = bytearray(), 0
    while i < len(enc):
        code = enc[i]
        if code == 0:
            return None
        out += enc[i + 1 : i + code]
        i += code
        if code < 0xFF and i < len(enc):
            out.append(0)
    return bytes(out)


def varint(n):
    """A LEB128 varint, as postcard writes unsigned integers (PROTOCOL.md §5)."""
    out = bytearray()
    while True:
        b = n & 0x7F
        n >>= 7
        if n:
            out.append(b | 0x80)
        else:
            out.append(b)
            return bytes(out)


def read_varint(b, i):
    """Reads a LEB128 varint at `b[i]`: (value, index after it)."""
    n, shift = 0, 0
    while True:
        x = b[i]
        i += 1
        n |= (x & 0x7F) << shift
        if not x & 0x80:
            return n, i
        shift += 7
