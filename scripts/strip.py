#!/usr/bin/env python3
"""Puts 8-bit RGB or gray PNGs side by side (same height), with a 4-pixel white gap, optionally
scaled up by an integer factor (nearest neighbour): python3 scripts/strip.py OUT.png [--scale N] A.png B.png ...
Standard library only, so that the result pictures can be remade on any machine."""
import struct
import sys
import zlib


def read_png(path):
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", f"{path}: not a PNG"
    pos, idat, w = 8, b"", None
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            w, h, depth, color, _, _, interlace = struct.unpack(">IIBBBBB", body)
            assert depth == 8 and color in (0, 2) and interlace == 0, f"{path}: only 8-bit gray/RGB PNGs"
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    bpp = 3 if color == 2 else 1
    raw, stride = zlib.decompress(idat), w * bpp
    rows, prev = [], bytearray(stride)
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b, c = prev[i], prev[i - bpp] if i >= bpp else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(line if bpp == 3 else bytearray(v for g in line for v in (g, g, g)))
        prev = line
    return w, h, rows


def write_png(path, w, h, rows):
    raw = b"".join(b"\x00" + bytes(r) for r in rows)
    chunk = lambda k, b: struct.pack(">I", len(b)) + k + b + struct.pack(">I", zlib.crc32(k + b))
    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
    open(path, "wb").write(png + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def main():
    args = sys.argv[1:]
    out, scale = args.pop(0), 1
    if args and args[0] == "--scale":
        scale = int(args[1])
        args = args[2:]
    images = [read_png(p) for p in args]
    h = images[0][1]
    assert all(i[1] == h for i in images), "images must share a height"
    gap = 4
    rows = []
    for y in range(h):
        row = bytearray()
        for k, (w, _, r) in enumerate(images):
            if k:
                row += b"\xff" * (3 * gap * scale)
            line = r[y]
            row += b"".join(bytes(line[3 * x:3 * x + 3]) * scale for x in range(w))
        rows.extend([row] * scale)
    width = len(rows[0]) // 3
    write_png(out, width, h * scale, rows)


main()
