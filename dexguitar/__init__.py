"""dexguitar: two physically simulated hands learn to play guitar from tabs (JAX + MuJoCo MJX)."""


def mjx():
    """`mujoco.mjx`, imported without the line it prints to stdout when the optional Warp backend is absent (which
    would corrupt `--json` output)."""
    import contextlib
    import io
    with contextlib.redirect_stdout(io.StringIO()):
        from mujoco import mjx as module
    return module
