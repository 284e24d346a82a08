"""Watch a performance: the scene's "front" camera rendered headless, strings coloured per frame (`colors.py`), as an
MP4 with the synthesized audio, or a PNG contact sheet when no ffmpeg is around.

Why this way: MuJoCo's own OpenGL renderer on the visual scene needs nothing beyond MuJoCo and an offscreen GL
(OSMesa or EGL, through `motion.render.Offscreen`); only the kinematics are recomputed per frame (the recorded
qpos is the whole state of the weightless hands). The string geoms lose their material so `geom_rgba` shows, and
are drawn thicker than the real ones (`string_radius`: sub-millimetre strings are a pixel wide in a 640 x 360
frame). MP4 writing
uses `imageio-ffmpeg`, which ships its own ffmpeg binary: an optional extra, `pip install imageio-ffmpeg`.
"""
from __future__ import annotations

import warnings
from pathlib import Path

import mujoco
import numpy as np

from dexguitar.motion.render import Offscreen, fixed_camera, strip_frames, write_png

N_STRINGS = 6


class SceneRenderer:
    """Renders (qpos, string colours) frames of a compiled visual scene (`scene.build_spec(..., visual=True)`).
    `fast`: no shadows and no multisampling (about 4x faster with software GL)."""

    def __init__(self, model: mujoco.MjModel, width: int = 640, height: int = 360, camera: str = "front",
                 string_radius: float = 0.0015, fast: bool = True):
        m = model
        self.model, self.width, self.height = m, width, height
        self.strings = []
        for i in range(1, N_STRINGS + 1):
            g = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, f"string{i}")
            if g < 0:
                raise ValueError(f"the model has no geom 'string{i}': build it with visual=True")
            self.strings.append(g)
        self.strings = np.asarray(self.strings)
        self._saved = (m.geom_matid[self.strings].copy(), m.geom_rgba[self.strings].copy(),
                       m.geom_size[self.strings].copy())
        m.geom_matid[self.strings] = -1                     # a material would override geom_rgba
        m.geom_size[self.strings, 0] = np.maximum(m.geom_size[self.strings, 0], string_radius)
        self.data = mujoco.MjData(m)
        if m.nkey:
            mujoco.mj_resetDataKeyframe(m, self.data, 0)
        self.camera = fixed_camera(m, camera)
        # Software GL (OSMesa) spends most of a frame on shadow maps and multisampling: off unless asked for.
        self._saved_quality = (m.vis.quality.offsamples, m.vis.quality.shadowsize)
        if fast:
            m.vis.quality.offsamples = 0
        self._screen = Offscreen(m, width, height, fast)

    def frame(self, qpos, colors=None) -> np.ndarray:
        """(H, W, 3) uint8 image of the pose `qpos` (nq,) with string colours (6, 4) (None: as they are)."""
        self.data.qpos[:] = qpos
        if colors is not None:
            self.model.geom_rgba[self.strings] = np.asarray(colors, np.float32)
        return self._screen.render(self.data, self.camera)

    def close(self):
        """Free the GL context and give the model its string materials, colours and sizes back."""
        if self._screen is not None:
            self._screen.close()
            self._screen = None
            m = self.model
            m.geom_matid[self.strings], m.geom_rgba[self.strings], m.geom_size[self.strings] = self._saved
            m.vis.quality.offsamples = self._saved_quality[0]

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def have_ffmpeg() -> bool:
    try:
        import imageio_ffmpeg  # noqa: F401
        return True
    except ImportError:
        return False


def _check(qpos_frames, colors, model):
    qpos_frames = np.asarray(qpos_frames, np.float64)
    if qpos_frames.ndim != 2 or qpos_frames.shape[1] != model.nq:
        raise ValueError(f"qpos_frames: expected (T, {model.nq}), got {qpos_frames.shape}")
    if colors is not None:
        colors = np.asarray(colors, np.float32)
        if colors.shape != (len(qpos_frames), N_STRINGS, 4):
            raise ValueError(f"colors: expected ({len(qpos_frames)}, 6, 4), got {colors.shape}")
    return qpos_frames, colors


def render_video(model: mujoco.MjModel, qpos_frames, colors, out, fps: float = 60.0, audio=None, *,
                 width: int = 640, height: int = 360, camera: str = "front", quality: int = 7) -> Path:
    """Write `out` (.mp4): one video frame per row of qpos_frames (T, nq) with string colours (T, 6, 4) (or None),
    at `fps`; `audio`: a WAV path muxed in as AAC (the track should last T / fps seconds). Needs the optional
    package imageio-ffmpeg."""
    try:
        import imageio_ffmpeg
    except ImportError:
        raise RuntimeError(f"{out}: writing an .mp4 needs the optional package imageio-ffmpeg "
                           "(pip install imageio-ffmpeg, or pip install -e '.[video]'); "
                           "use render_frames_png for a PNG contact sheet instead") from None
    qpos_frames, colors = _check(qpos_frames, colors, model)
    out = Path(out)
    extra = {}
    if audio is not None:
        extra = {"audio_path": str(audio), "audio_codec": "aac", "output_params": ["-shortest"]}
    with SceneRenderer(model, width, height, camera) as r:
        writer = imageio_ffmpeg.write_frames(str(out), (width, height), fps=fps, macro_block_size=1,
                                             quality=quality, ffmpeg_log_level="error", **extra)
        with warnings.catch_warnings():    # JAX warns about any fork; ffmpeg is exec'd at once, nothing is shared
            warnings.filterwarnings("ignore", message=r"os\.fork\(\) was called", category=RuntimeWarning)
            writer.send(None)
        try:
            for t in range(len(qpos_frames)):
                writer.send(np.ascontiguousarray(r.frame(qpos_frames[t], None if colors is None else colors[t])))
        finally:
            writer.close()
    return out


def render_frames_png(model: mujoco.MjModel, qpos_frames, colors, out, *, frames: int = 8, columns: int = 4,
                      indices=None, width: int = 480, height: int = 270, camera: str = "front") -> Path:
    """A PNG contact sheet: `frames` evenly spaced frames (or the given `indices`) in rows of `columns`; needs no
    ffmpeg. Returns the path."""
    qpos_frames, colors = _check(qpos_frames, colors, model)
    idx = strip_frames(len(qpos_frames), frames) if indices is None else np.asarray(indices, int)
    with SceneRenderer(model, width, height, camera) as r:
        images = [r.frame(qpos_frames[t], None if colors is None else colors[t]) for t in idx]
    columns = max(1, min(columns, len(images)))
    rows = -(-len(images) // columns)
    sheet = np.full((rows * height, columns * width, 3), 255, np.uint8)
    for k, img in enumerate(images):
        y, x = divmod(k, columns)
        sheet[y * height:(y + 1) * height, x * width:(x + 1) * width] = img
    return write_png(out, sheet)
