"""Small binary asset files generated in tests: a binary STL mesh and a PNG texture."""

import struct
import zlib


def tetrahedron_stl(scale: float = 0.1) -> bytes:
    """A binary STL tetrahedron with edges of length ~`scale`."""
    v = [(0, 0, 0), (scale, 0, 0), (0, scale, 0), (0, 0, scale)]
    faces = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]
    data = bytearray(b"generated tetrahedron".ljust(80, b" "))
    data += struct.pack("<I", len(faces))
    for face in faces:
        data += struct.pack("<3f", 0, 0, 0)
        for index in face:
            data += struct.pack("<3f", *v[index])
        data += struct.pack("<H", 0)
    return bytes(data)


def checker_png(size: int = 8) -> bytes:
    """An RGB PNG checkerboard of `size` x `size` pixels."""
    rows = []
    for y in range(size):
        row = bytearray([0])
        for x in range(size):
            row += bytes((255, 255, 255) if (x + y) % 2 else (20, 40, 200))
        rows.append(bytes(row))

    def chunk(kind: bytes, body: bytes) -> bytes:
        crc = zlib.crc32(kind + body) & 0xFFFFFFFF
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", crc)

    header = struct.pack(">IIBBBBB", size, size, 8, 2, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", zlib.compress(b"".join(rows)))
        + chunk(b"IEND", b"")
    )


def triangle_skin(body: str) -> bytes:
    """A MuJoCo .skn skin: one triangle bound to bone body `body`."""
    vertices = (0, 0, 0, 0.1, 0, 0, 0, 0.1, 0)
    data = struct.pack("<4i", 3, 0, 1, 1)
    data += struct.pack("<9f", *vertices)
    data += struct.pack("<3i", 0, 1, 2)
    data += body.encode().ljust(40, b"\0")
    data += struct.pack("<7f", 0, 0, 0, 1, 0, 0, 0)
    data += struct.pack("<i", 3) + struct.pack("<3i", 0, 1, 2) + struct.pack("<3f", 1, 1, 1)
    return data
