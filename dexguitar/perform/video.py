"""Watch a performance: the stage (`world.stage`) rendered headless from its "front" camera (both hands) or its
"closeup" (the fretting hand), strings coloured per frame (`colors.py`), an optional caption (`play.caption`: the
song, the running F1 and the colours' legend), as an MP4 with the synthesized audio, or a PNG contact sheet when no
ffmpeg is around.

Why this way: MuJoCo's own OpenGL renderer needs nothing beyond MuJoCo and an offscreen GL (OSMesa or EGL, through
`motion.render.Offscreen`); only the kinematics are recomputed per frame (the recorded qpos is the whole state of
the weightless hands). The string geoms lose their material so `geom_rgba` shows, and are drawn at least
`STRING_PIXELS` wide (sub-millimetre strings would be a pixel wide in a view of the whole guitar). The close-up
glides along the neck after the fretting wrist, smoothed over `FOLLOW_SECONDS` so that it does not shake with the
hand. MP4 writing uses `imageio-ffmpeg`, which ships its own ffmpeg binary: an optional extra,
`pip install imageio-ffmpeg`.
"""
from __future__ import annotations

import warnings
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import mujoco
import numpy as np

from dexguitar.motion.render import Offscreen, fixed_camera, strip_frames, write_png
from dexguitar.world import scene as S
from dexguitar.world.guitar import N_STRINGS

STRING_PIXELS = 3.0            # the least width of a string on screen
# x264: "veryfast" takes half the encoding time of the default for about the same file size; two threads, as more
# only fight the renderer for the CPU (about 20 % slower in all on 2 cores).
X264 = ["-preset", "veryfast", "-threads", "2"]
FOLLOW_SECONDS = 1.0           # the close-up's moving average of the fretting wrist's place along the neck


class SceneRenderer:
    """Renders (qpos, string colours, caption) frames of a compiled stage (`stage.stage_model`) or visual scene.
    `fast`: no shadows and no multisampling (about 4x faster with software GL)."""

    def __init__(self, model: mujoco.MjModel, width: int = 1280, height: int = 720, camera: str = "front",
                 fast: bool = True):
        m = model
        self.model, self.width, self.height = m, width, height
        self.strings = []
        for i in range(1, N_STRINGS + 1):
            g = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, f"string{i}")
            if g < 0:
                raise ValueError(f"the model has no geom 'string{i}': render the stage (stage.stage_model)")
            self.strings.append(g)
        self.strings = np.asarray(self.strings)
        self.camera = fixed_camera(m, camera)
        self.data = mujoco.MjData(m)
        if m.nkey:
            mujoco.mj_resetDataKeyframe(m, self.data, 0)
        cid = self.camera.fixedcamid
        self._saved = (m.geom_matid[self.strings].copy(), m.geom_rgba[self.strings].copy(),
                       m.geom_size[self.strings].copy(), m.cam_pos[cid].copy(), m.vis.quality.offsamples)
        # Software GL (OSMesa) spends most of a frame on shadow maps and multisampling: off unless asked for.
        if fast:
            m.vis.quality.offsamples = 0
        try:
            self._screen = Offscreen(m, width, height, fast)
        except Exception:
            m.vis.quality.offsamples = self._saved[4]
            raise
        m.geom_matid[self.strings] = -1                     # a material would override geom_rgba
        m.geom_size[self.strings, 0] = np.maximum(m.geom_size[self.strings, 0],
                                                  STRING_PIXELS / 2 * pixel_size(m, self.data, cid, height))

    def frame(self, qpos, colors=None, caption: str | None = None, camera_offset=None) -> np.ndarray:
        """(H, W, 3) uint8 image of the pose `qpos` (nq,) with string colours (6, 4) (None: as they are), a caption
        (None: none) and the camera moved by `camera_offset` (3,) in its body's frame (None: where it is)."""
        self.data.qpos[:] = qpos
        if colors is not None:
            self.model.geom_rgba[self.strings] = np.asarray(colors, np.float32)
        if camera_offset is not None:
            self.model.cam_pos[self.camera.fixedcamid] = self._saved[3] + camera_offset
        return self._screen.render(self.data, self.camera, caption)

    def close(self):
        """Free the GL context and give the model its string materials, colours, sizes and its camera back."""
        if self._screen is not None:
            self._screen.close()
            self._screen = None
            m = self.model
            m.geom_matid[self.strings], m.geom_rgba[self.strings], m.geom_size[self.strings] = self._saved[:3]
            m.cam_pos[self.camera.fixedcamid], m.vis.quality.offsamples = self._saved[3:]

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def pixel_size(model: mujoco.MjModel, data: mujoco.MjData, camera: int, height: int) -> float:
    """Metres per pixel, at the guitar, in a `height`-line frame from a fixed camera."""
    mujoco.mj_kinematics(model, data)
    mujoco.mj_camlight(model, data)
    guitar = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "guitar")
    distance = np.linalg.norm(data.cam_xpos[camera] - data.xpos[guitar])
    return float(2 * distance * np.tan(np.radians(model.cam_fovy[camera]) / 2) / height)


def follow_fretting_hand(model: mujoco.MjModel, qpos_frames, fps: float) -> np.ndarray:
    """(T, 3) offsets of the close-up in the guitar frame: the fretting wrist's place along the neck (its y slide,
    0 where the close-up is set), a moving average over FOLLOW_SECONDS."""
    y = np.asarray(qpos_frames)[:, S.hand_index(model, "left").qpos[1]]
    n = max(1, int(round(FOLLOW_SECONDS * fps)))
    smooth = np.convolve(np.pad(y, (n // 2, n - 1 - n // 2), mode="edge"), np.ones(n) / n, mode="valid")
    return np.stack([np.zeros_like(smooth), smooth, np.zeros_like(smooth)], axis=1)


def camera_offsets(model: mujoco.MjModel, qpos_frames, fps: float, camera: str):
    """Per-frame camera offsets (T, 3): the close-up follows the fretting hand, other cameras stay (None)."""
    return follow_fretting_hand(model, qpos_frames, fps) if camera == "closeup" else None


def have_ffmpeg() -> bool:
    try:
        import imageio_ffmpeg  # noqa: F401
        return True
    except ImportError:
        return False


def _check(qpos_frames, colors, captions, model):
    qpos_frames = np.asarray(qpos_frames, np.float64)
    if qpos_frames.ndim != 2 or qpos_frames.shape[1] != model.nq:
        raise ValueError(f"qpos_frames: expected (T, {model.nq}), got {qpos_frames.shape}")
    if colors is not None:
        colors = np.asarray(colors, np.float32)
        if colors.shape != (len(qpos_frames), N_STRINGS, 4):
            raise ValueError(f"colors: expected ({len(qpos_frames)}, 6, 4), got {colors.shape}")
    if captions is not None and len(captions) != len(qpos_frames):
        raise ValueError(f"captions: expected {len(qpos_frames)}, got {len(captions)}")
    return qpos_frames, colors


def _pick(items, t):
    return None if items is None else items[t]


def render_video(model: mujoco.MjModel, qpos_frames, colors, out, fps: float = 30.0, audio=None, *,
                 width: int = 1280, height: int = 720, camera: str = "front", captions=None,
                 quality: int = 7) -> Path:
    """Write `out` (.mp4): one video frame per row of qpos_frames (T, nq) with string colours (T, 6, 4) and
    captions (T strings) (either may be None), at `fps`; `audio`: a WAV path muxed in as AAC, cut to the T / fps
    seconds of the picture (a shorter track is not: every frame stays). Needs the optional package imageio-ffmpeg."""
    try:
        import imageio_ffmpeg
    except ImportError:
        raise RuntimeError(f"{out}: writing an .mp4 needs the optional package imageio-ffmpeg "
                           "(pip install imageio-ffmpeg, or pip install -e '.[video]'); "
                           "use render_frames_png for a PNG contact sheet instead") from None
    qpos_frames, colors = _check(qpos_frames, colors, captions, model)
    offsets = camera_offsets(model, qpos_frames, fps, camera)
    out = Path(out)
    extra = {"output_params": list(X264)}
    if audio is not None:
        seconds = len(qpos_frames) / fps                    # the picture's length rules: a longer track is cut
        extra = {"audio_path": str(audio), "audio_codec": "aac", "output_params": X264 + ["-t", f"{seconds:.6f}"]}
    with SceneRenderer(model, width, height, camera) as r:
        writer = imageio_ffmpeg.write_frames(str(out), (width, height), fps=fps, macro_block_size=1,
                                             quality=quality, ffmpeg_log_level="error", **extra)
        with warnings.catch_warnings():    # JAX warns about any fork; ffmpeg is exec'd at once, nothing is shared
            warnings.filterwarnings("ignore", message=r"os\.fork\(\) was called", category=RuntimeWarning)
            writer.send(None)
        # ffmpeg takes a frame through a pipe that blocks until it has read all of it: a thread hands each frame
        # over while the next one renders (the demo's 579 frames: 8.6 -> 7.6 s on 2 cores; the same file)
        try:
            with ThreadPoolExecutor(1) as feeder:
                sent = None
                for t in range(len(qpos_frames)):
                    image = np.ascontiguousarray(r.frame(qpos_frames[t], _pick(colors, t), _pick(captions, t),
                                                         _pick(offsets, t)))
                    if sent is not None:
                        sent.result()                       # raises what ffmpeg's pipe raised
                    sent = feeder.submit(writer.send, image)
                if sent is not None:
                    sent.result()
        finally:
            writer.close()
    return out


def render_frames_png(model: mujoco.MjModel, qpos_frames, colors, out, *, frames: int = 8, columns: int = 4,
                      indices=None, width: int = 480, height: int = 270, camera: str = "front", captions=None,
                      fps: float = 60.0) -> Path:
    """A PNG contact sheet: `frames` evenly spaced frames (or the given `indices`) in rows of `columns`; needs no
    ffmpeg. `fps`: the frame rate of qpos_frames (for the close-up's smoothing). Returns the path."""
    qpos_frames, colors = _check(qpos_frames, colors, captions, model)
    offsets = camera_offsets(model, qpos_frames, fps, camera)
    idx = strip_frames(len(qpos_frames), frames) if indices is None else np.asarray(indices, int)
    with SceneRenderer(model, width, height, camera) as r:
        images = [r.frame(qpos_frames[t], _pick(colors, t), _pick(captions, t), _pick(offsets, t)) for t in idx]
    columns = max(1, min(columns, len(images)))
    rows = -(-len(images) // columns)
    sheet = np.full((rows * height, columns * width, 3), 255, np.uint8)
    for k, img in enumerate(images):
        y, x = divmod(k, columns)
        sheet[y * height:(y + 1) * height, x * width:(x + 1) * width] = img
    return write_png(out, sheet)
