"""Renders a manipulation scene from the vision tasks' camera and from a wide view, as a PNG.

The left panel is what the vision tasks observe (`front_close`, drawn larger than the
agent's 84x84 pixels); the right panel is a wide view of the whole table from `front_far`.

Usage: python examples/render_arenas.py OUTPUT.png [--environment NAME] [--seed N]
"""

import argparse
import os
import struct
import zlib

import numpy as np

os.environ.setdefault("MUJOCO_GL", "egl")

import manipulation  # noqa: E402  (the GL backend is chosen when mujoco is imported)

_CLOSE_SIZE = (480, 480)
_WIDE_SIZE = (480, 640)


def write_png(path: str, image: np.ndarray) -> None:
    """Writes an (height, width, 3) uint8 RGB image as a PNG file."""
    height, width, _ = image.shape
    # Every scanline starts with filter type 0 (none).
    raw = np.concatenate([np.zeros((height, 1), np.uint8), image.reshape(height, -1)], axis=1)

    def chunk(kind: bytes, payload: bytes) -> bytes:
        body = kind + payload
        return struct.pack(">I", len(payload)) + body + struct.pack(">I", zlib.crc32(body))

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    with open(path, "wb") as file:
        file.write(b"\x89PNG\r\n\x1a\n")
        file.write(chunk(b"IHDR", header))
        file.write(chunk(b"IDAT", zlib.compress(raw.tobytes(), 9)))
        file.write(chunk(b"IEND", b""))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("output", help="path of the PNG file to write")
    parser.add_argument(
        "--environment", default="place_brick_features", help="a name from manipulation.ALL"
    )
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()

    env = manipulation.load(args.environment, seed=args.seed)
    env.reset()
    close = env.physics.render(*_CLOSE_SIZE, camera_id="front_close")
    wide = env.physics.render(*_WIDE_SIZE, camera_id="front_far")
    gap = np.full((_WIDE_SIZE[0], 8, 3), 255, np.uint8)
    write_png(args.output, np.concatenate([close, gap, wide], axis=1))
    print(f"wrote {args.output}: {args.environment} (seed {args.seed}), front_close | front_far")


if __name__ == "__main__":
    main()
