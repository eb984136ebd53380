"""Render worker process: ``python -m synthaug.render._worker`` (see server.py).

Reads length-prefixed pickled requests on stdin and answers on the original
stdout; anything else the GL stack prints goes to stderr.
"""

from __future__ import annotations

import os
import sys
import traceback


def main() -> int:
    out = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)  # stray prints must not corrupt the protocol stream
    sys.stdout = sys.stderr
    from synthaug.render.server import read_frame_fd, write_frame

    fd = sys.stdin.fileno()
    renderer = None
    while True:
        try:
            msg = read_frame_fd(fd)
        except EOFError:
            return 0
        op = msg.get("op")
        try:
            if op == "quit":
                write_frame(out, ("ok", None))
                return 0
            if op == "init":
                from synthaug.render.gl import GLLayerRenderer

                renderer = GLLayerRenderer(msg["vertices"], msg["faces"])
                # create the context now so that a broken platform fails at init
                renderer.render(__import__("numpy").eye(3)[None], None, size=4, scale=0.5, supersample=1)
                write_frame(out, ("ok", renderer.platform))
            elif op == "render":
                if renderer is None:
                    raise RuntimeError("render before init")
                cov, nrm = renderer.render(msg["rotations"], msg["translations"], size=msg["size"],
                                           scale=msg["scale"], supersample=msg["supersample"])
                write_frame(out, ("ok", (cov, nrm)))
            else:
                raise ValueError(f"unknown op {op!r}")
        except Exception as e:  # report, keep serving
            write_frame(out, ("error", f"{type(e).__name__}: {e}\n{traceback.format_exc()}"))


if __name__ == "__main__":
    sys.exit(main())
