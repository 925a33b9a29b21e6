"""Screenshots docs pages in headless Chromium; prints the path of each PNG it writes.

Usage: python -m tools.docs.screenshots SITE_DIR OUT_DIR [PAGE ...] [--height PIXELS]

SITE_DIR is `mkdocs build`'s output (default pages: home, a concept page, the gallery).
The site is served from `python -m http.server` on 127.0.0.1 so that pages load as they
would from a web server.
"""

import argparse
import contextlib
import pathlib
import re
import socket
import subprocess
import sys
import tempfile
import time

DEFAULT_PAGES = ("", "concepts/observables/", "generated/gallery/")
_CHROMIUM_FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--hide-scrollbars",
    # Let the page finish loading (fonts, lazily loaded images, a jump to an #anchor).
    "--virtual-time-budget=5000",
)


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


@contextlib.contextmanager
def _serve(directory: pathlib.Path):
    """Serves `directory` over HTTP on 127.0.0.1 and yields the base URL."""
    port = _free_port()
    server = subprocess.Popen(
        [sys.executable, "-m", "http.server", str(port), "--bind", "127.0.0.1"],
        cwd=directory,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        for _ in range(50):
            with contextlib.suppress(OSError), socket.create_connection(("127.0.0.1", port)):
                break
            time.sleep(0.1)
        yield f"http://127.0.0.1:{port}/"
    finally:
        server.terminate()
        server.wait()


def screenshot(url: str, output: pathlib.Path, *, width: int = 1280, height: int = 1600) -> None:
    """Saves a `width` x `height` PNG of `url` as rendered by headless Chromium."""
    with tempfile.TemporaryDirectory() as profile:
        subprocess.run(
            [
                "chromium",
                *_CHROMIUM_FLAGS,
                f"--user-data-dir={profile}",
                f"--screenshot={output}",
                f"--window-size={width},{height}",
                url,
            ],
            check=True,
            capture_output=True,
            timeout=120,
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("site", type=pathlib.Path, help="the built site (mkdocs build output)")
    parser.add_argument("out", type=pathlib.Path, help="folder for the PNG files")
    parser.add_argument("pages", nargs="*", default=DEFAULT_PAGES, help="paths below the site")
    parser.add_argument("--height", type=int, default=1600)
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    with _serve(args.site) as base:
        for page in args.pages:
            name = re.sub(r"[^A-Za-z0-9]+", "_", page.removesuffix(".svg")).strip("_") or "home"
            output = args.out / f"{name}.png"
            screenshot(base + page, output, height=args.height)
            print(output)


if __name__ == "__main__":
    main()
