"""Can this machine render? The offscreen OpenGL (OSMesa or EGL) that the videos use, found by trying a real one.

A library on disk proves nothing (`libEGL.so.1` is only the loader, there may be no driver behind it), so
each backend is tried in a child process that makes a context, draws into it and reads the pixel back. A child,
because PyOpenGL fixes its platform when it is first imported: a failed try in this process would spoil the next
one. OSMesa comes first: on a CPU it draws a frame about twice as fast as Mesa's EGL. `MUJOCO_GL=osmesa|egl`
picks one without trying.

`python -m dexguitar.motion.glcheck [osmesa|egl]` prints the backend that works (exit 0) or what to install
(exit 1); the Makefile's setup runs it.
"""
from __future__ import annotations

import functools
import os
import subprocess
import sys

from dexguitar.errors import UserError

BACKENDS = ("osmesa", "egl")
INSTALL = "apt-get install libosmesa6 (or an EGL driver)"
PROBE_TIMEOUT_S = 120

# Make a context, clear a 4 x 4 offscreen buffer to red with MuJoCo's renderer and read it back.
_PROBE = """
import mujoco, numpy as np
from mujoco.{backend} import GLContext
ctx = GLContext(4, 4)
ctx.make_current()
model = mujoco.MjModel.from_xml_string("<mujoco/>")
con = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_100)
mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, con)
rect = mujoco.MjrRect(0, 0, 4, 4)
mujoco.mjr_rectangle(rect, 1, 0, 0, 1)
rgb = np.zeros((4, 4, 3), np.uint8)
mujoco.mjr_readPixels(rgb, None, rect, con)
assert (rgb[..., 0] > 200).all() and (rgb[..., 1:] < 50).all(), "the pixels read back are not the ones drawn"
con.free()
ctx.free()
"""


class NoGL(UserError):
    """No offscreen OpenGL here; the message says what to install."""


def probe(backend: str) -> str | None:
    """None if `backend` renders in a fresh process, else why not (the child's last line of error)."""
    env = dict(os.environ, PYOPENGL_PLATFORM=backend, MUJOCO_GL=backend)
    try:
        run = subprocess.run([sys.executable, "-c", _PROBE.format(backend=backend)], env=env, capture_output=True,
                             text=True, timeout=PROBE_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        return f"no answer in {PROBE_TIMEOUT_S} s"
    if run.returncode == 0:
        return None
    lines = run.stderr.strip().splitlines()
    return lines[-1] if lines else f"exit status {run.returncode}"


@functools.cache
def backend() -> str:
    """The backend this process renders with: MUJOCO_GL's when it names one (or the one PyOpenGL was already set
    to), else the first of BACKENDS that works. Raises NoGL."""
    for var in ("MUJOCO_GL", "PYOPENGL_PLATFORM"):
        chosen = os.environ.get(var, "").lower()
        if chosen in BACKENDS:
            return chosen
    errors = []
    for name in BACKENDS:
        why = probe(name)
        if why is None:
            return name
        errors.append(f"{name}: {why}")
    raise NoGL(f"no offscreen OpenGL for the videos ({'; '.join(errors)}): {INSTALL}")


def gl_context(width: int, height: int):
    """A current offscreen OpenGL context of at least width x height. Raises NoGL."""
    name = backend()
    try:
        if name == "osmesa":
            from mujoco.osmesa import GLContext
        else:
            from mujoco.egl import GLContext
        ctx = GLContext(width, height)
        ctx.make_current()
    except Exception as e:      # noqa: BLE001 - a missing library surfaces as many error types
        raise NoGL(f"no offscreen OpenGL ({name}: {type(e).__name__}: {e}): {INSTALL}") from e
    return ctx


def main(argv=None) -> int:
    """Print the backend that renders (or check the one named) and exit 0, or print what to install, exit 1."""
    args = sys.argv[1:] if argv is None else argv
    if args and args[0] not in BACKENDS:
        print(f"usage: python -m dexguitar.motion.glcheck [{'|'.join(BACKENDS)}]", file=sys.stderr)
        return 2
    try:
        if args:
            why = probe(args[0])
            if why is not None:
                raise NoGL(f"no offscreen OpenGL ({args[0]}: {why})")
            name = args[0]
        else:
            name = backend()
    except NoGL as e:
        print(e)
        return 1
    print(f"offscreen OpenGL: {name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
