#!/usr/bin/env python3
"""Writes the data of scenes/textured-serialized.xml (run from anywhere; output next to this script):
  textured.serialized  Mitsuba serialized file, format version 4, two zlib-compressed shapes:
                       0 "floor"  quad [-1,1]^2 at z = 0 facing +z, normals, uv (0,0) at (-1,-1)
                       1 "torus"  major radius 0.5, minor 0.2, around z, normals, uv = (phi, theta) / 2pi
  tiles.png            64x64 8-bit sRGB tiles with a soft gradient (the floor's bitmap)
Layout as in common/scene/serialized_reader.cpp: per shape uint16 0x041C, uint16 4, a zlib stream of
(uint32 flags, name\\0, uint64 vertex count, uint64 triangle count, float positions, normals, uvs, uint32
indices); then uint64 offsets of the shapes and uint32 shape count at the end of the file."""
import math
import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))


def record(name, positions, normals, uvs, indices):
    flags = 0x1000 | 0x0001 | 0x0002  # single precision, normals, uvs
    out = struct.pack('<I', flags) + name.encode() + b'\0'
    out += struct.pack('<QQ', len(positions), len(indices) // 3)
    for arr in (positions, normals, uvs):
        for v in arr:
            out += struct.pack('<%df' % len(v), *v)
    out += struct.pack('<%dI' % len(indices), *indices)
    return out


def floor():
    p = [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)]
    n = [(0, 0, 1)] * 4
    uv = [(0, 0), (1, 0), (1, 1), (0, 1)]
    return record('floor', p, n, uv, [0, 1, 2, 0, 2, 3])


def torus(R=0.5, r=0.2, nu=48, nv=24):
    p, n, uv, idx = [], [], [], []
    for i in range(nu + 1):
        phi = 2 * math.pi * i / nu
        for j in range(nv + 1):
            th = 2 * math.pi * j / nv
            c = (math.cos(phi), math.sin(phi))
            normal = (c[0] * math.cos(th), c[1] * math.cos(th), math.sin(th))
            p.append((c[0] * (R + r * math.cos(th)), c[1] * (R + r * math.cos(th)), r * math.sin(th)))
            n.append(normal)
            uv.append((i / nu, j / nv))
    for i in range(nu):
        for j in range(nv):
            a, b = i * (nv + 1) + j, (i + 1) * (nv + 1) + j
            idx += [a, b, b + 1, a, b + 1, a + 1]  # counter-clockwise seen from outside
    return record('torus', p, n, uv, idx)


def write_serialized(path, records):
    data, offsets = b'', []
    for rec in records:
        offsets.append(len(data))
        data += struct.pack('<HH', 0x041C, 4) + zlib.compress(rec, 9)
    data += b''.join(struct.pack('<Q', o) for o in offsets) + struct.pack('<I', len(records))
    with open(path, 'wb') as f:
        f.write(data)


def write_png(path, w, h, pixel):
    raw = b''.join(b'\0' + bytes(c for x in range(w) for c in pixel(x, y)) for y in range(h))
    chunk = lambda t, d: struct.pack('>I', len(d)) + t + d + struct.pack('>I', zlib.crc32(t + d) & 0xffffffff)
    png = b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, 8, 2, 0, 0, 0))
    png += chunk(b'IDAT', zlib.compress(raw, 9)) + chunk(b'IEND', b'')
    with open(path, 'wb') as f:
        f.write(png)


def tiles(x, y):
    tile = ((x // 16) + (y // 16)) % 2
    g = 0.6 + 0.4 * y / 63
    base = (200, 170, 120) if tile else (90, 110, 150)
    mortar = x % 16 == 0 or y % 16 == 0
    return (40, 40, 40) if mortar else tuple(int(c * g) for c in base)


if __name__ == '__main__':
    write_serialized(os.path.join(HERE, 'textured.serialized'), [floor(), torus()])
    write_png(os.path.join(HERE, 'tiles.png'), 64, 64, tiles)
